/* libnbt/surface.c: J_k^n in source-centred coordinates, surface radiance
 * three ways, and J tables as a matrix product. */
#include <config.h>
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <nbt/surface.h>
#include "internal.h"
#include "tablefill.h"

#define SEG_MAX_INTERVALS 2000

/* ---- the azimuthal kernel K_n(theta, g) ---- */

static size_t kernel_nodes(int n)
{
    size_t m = 48 + (size_t)n;
    return m > 600 ? 600 : m;
}

/* rule: Gauss-Legendre with kernel_nodes(n) nodes. */
static double kernel_eval(const nbt_gl_rule *rule, int n, double theta, double g)
{
    double a = cos(theta) * cos(g), b = fabs(sin(theta) * sin(g));
    if (a >= b) {
        /* the whole cone is above the horizon: 2 pi sum_{j even} C(n,j) a^{n-j} b^j (j-1)!!/j!! */
        double s = 0, binom = 1, dfr = 1;
        for (int j = 0; j <= n; j++) {
            if (j > 0)
                binom *= (double)(n - j + 1) / j;
            if (j % 2 == 0) {
                if (j > 0)
                    dfr *= (double)(j - 1) / j;
                s += binom * pow(a, n - j) * pow(b, j) * dfr;
            }
        }
        return 2.0 * NBT_PI * s;
    }
    if (a <= -b)
        return 0.0;
    /* cut by the horizon: 2 int_0^{phi0} (a + b cos phi)^n dphi, analytic on [0, phi0] */
    double phi0 = acos(-a / b), s = 0;
    for (size_t i = 0; i < rule->n; i++) {
        double phi = 0.5 * phi0 * (1.0 + rule->x[i]);
        double v = a + b * cos(phi);
        s += rule->w[i] * (v > 0 ? pow(v, n) : 0.0);
    }
    return phi0 * s;
}

double nbt_surface_kernel(int n, double theta, double g)
{
    if (n < 1)
        return NAN;
    nbt_gl_rule *r = nbt_gl_rule_alloc(kernel_nodes(n));
    if (!r)
        return NAN;
    double v = kernel_eval(r, n, theta, g);
    nbt_gl_rule_free(r);
    return v;
}

/* Kinks of K_n(theta, .) in (0, pi): where cos(theta +- g) = 0. Also the
 * support [lo, hi] outside which K_n vanishes. Returns the number of kinks. */
static size_t kernel_kinks(double theta, double *pts, double *lo, double *hi)
{
    double c[4] = {NBT_PI_2 - theta, 1.5 * NBT_PI - theta, theta - NBT_PI_2, theta + NBT_PI_2};
    *lo = fmax(0.0, theta - NBT_PI_2);
    *hi = fmin(NBT_PI, theta + NBT_PI_2);
    size_t n = 0;
    for (int i = 0; i < 4; i++)
        if (c[i] > *lo && c[i] < *hi) {
            int dup = 0;
            for (size_t j = 0; j < n; j++)
                dup |= fabs(pts[j] - c[i]) < 1e-15;
            if (!dup)
                pts[n++] = c[i];
        }
    for (size_t i = 1; i < n; i++) /* sort (n <= 4) */
        for (size_t j = i; j > 0 && pts[j] < pts[j - 1]; j--) {
            double t = pts[j];
            pts[j] = pts[j - 1];
            pts[j - 1] = t;
        }
    return n;
}

/* ---- G_k(T, g) = e^{-T} S(T sin g; g - pi/2, pi/2), shifted segment ---- */

static nbt_status g_eval(nbt_quad_ws *ws, const nbt__weights *w, double T, double g, double tol,
                         double *G, double *err)
{
    unsigned fdim = nbt__fdim(w);
    if (g >= NBT_PI) {
        for (unsigned k = 0; k < fdim; k++)
            G[k] = err[k] = 0.0;
        return NBT_OK;
    }
    nbt_status st = nbt__airlight_segment(ws, w, T * sin(g), g - NBT_PI_2, NBT_PI_2, 1, tol, G, err);
    double e = exp(-T);
    for (unsigned k = 0; k < fdim; k++) {
        G[k] *= e;
        err[k] *= e;
    }
    return st;
}

/* ---- pointwise J by nested adaptive quadrature ---- */

typedef struct {
    nbt__weights w;
    int n;
    double T, theta, tol;
    nbt_quad_ws *inner;
    nbt_gl_rule *rule;
    double *err;
    nbt_status st;
} j_ctx;

static int j_integrand(double g, void *vp, unsigned fdim, double *f)
{
    j_ctx *c = vp;
    nbt_status st = g_eval(c->inner, &c->w, c->T, g, c->tol, f, c->err);
    if (st != NBT_OK && c->st == NBT_OK)
        c->st = st;
    double K = kernel_eval(c->rule, c->n, c->theta, g);
    for (unsigned k = 0; k < fdim; k++)
        f[k] *= K;
    return 0;
}

static nbt_status j_eval(const nbt__weights *w, int n, double T, double theta, double tol,
                         double *J, double *abserr)
{
    if (n < 1)
        NBT_FAIL(NBT_EDOM, "J: the cosine exponent n must be >= 1");
    if (!(T >= 0) || isinf(T))
        NBT_FAIL(NBT_EDOM, "J: T must be finite and >= 0");
    if (!(theta >= 0 && theta <= NBT_PI))
        NBT_FAIL(NBT_EDOM, "J: theta must lie in [0, pi]");
    if (!(tol > 0 && tol < 1))
        NBT_FAIL(NBT_EDOM, "J: tol must lie in (0, 1)");
    unsigned fdim = nbt__fdim(w);
    j_ctx c = {*w, n, T, theta, 0.1 * tol, NULL, NULL, NULL, NBT_OK};
    c.inner = nbt_quad_ws_alloc(fdim, SEG_MAX_INTERVALS);
    c.rule = nbt_gl_rule_alloc(kernel_nodes(n));
    c.err = malloc(fdim * sizeof(double));
    nbt_quad_ws *outer = nbt_quad_ws_alloc(fdim, 1000);
    nbt_status st = NBT_ENOMEM;
    if (c.inner && c.rule && c.err && outer) {
        double pts[4], lo, hi;
        size_t np = kernel_kinks(theta, pts, &lo, &hi);
        st = nbt_quad_gk_pts(outer, j_integrand, &c, fdim, lo, hi, pts, np, 0.0, tol, J, abserr);
        if (st == NBT_OK)
            st = c.st;
    }
    nbt_quad_ws_free(c.inner);
    nbt_quad_ws_free(outer);
    nbt_gl_rule_free(c.rule);
    free(c.err);
    if (st == NBT_ENOMEM)
        NBT_FAIL(st, "J: out of memory");
    return st;
}

nbt_status nbt_jk(size_t kmax, int n, double T, double theta, double tol, double *J, double *abserr)
{
    nbt__weights w = {kmax, NULL, NULL};
    return j_eval(&w, n, T, theta, tol, J, abserr);
}

nbt_status nbt_j_phase(const nbt_phase *p, int n, double T, double theta, double tol,
                       double *J, double *abserr)
{
    nbt__weights w = {0, p, NULL};
    return j_eval(&w, n, T, theta, tol, J, abserr);
}

/* ---- surface radiance ---- */

nbt_status nbt_surface_check(const nbt_surface_geom *g)
{
    if (!(g->kappa_s >= 0.0) || !isfinite(g->kappa_s))
        NBT_FAIL(NBT_EDOM, "surface: kappa_s must be finite and >= 0");
    if (!(g->kappa_t >= g->kappa_s) || !isfinite(g->kappa_t))
        NBT_FAIL(NBT_EDOM, "surface: kappa_t must be finite and >= kappa_s");
    if (!(g->I0 >= 0.0) || !isfinite(g->I0))
        NBT_FAIL(NBT_EDOM, "surface: I0 must be finite and >= 0");
    if (!(g->dsp > 0.0) || !isfinite(g->dsp))
        NBT_FAIL(NBT_EDOM, "surface: dsp must be finite and > 0");
    if (!(g->theta_s >= 0 && g->theta_s <= NBT_PI) || !(g->theta_r >= 0 && g->theta_r <= NBT_PI))
        NBT_FAIL(NBT_EDOM, "surface: theta_s and theta_r must lie in [0, pi]");
    if (!(g->kd >= 0) || !(g->ks >= 0) || !isfinite(g->kd) || !isfinite(g->ks))
        NBT_FAIL(NBT_EDOM, "surface: kd and ks must be finite and >= 0");
    if (g->n < 1)
        NBT_FAIL(NBT_EDOM, "surface: the Phong exponent n must be >= 1");
    return NBT_OK;
}

static double direct_term(const nbt_surface_geom *g)
{
    double cs = fmax(0.0, cos(g->theta_s)), cr = fmax(0.0, cos(g->theta_r));
    return g->I0 * exp(-g->kappa_t * g->dsp) / (g->dsp * g->dsp) * (g->kd * cs + g->ks * pow(cr, g->n));
}

/* Reference: int dg sin g L_a(g) int dphi max(0, cos theta_i)^n, with L_a by
 * Nishita's integral in distance and the azimuth integrated pointwise. */
typedef struct {
    const nbt_phase *p;
    nbt_airlight_geom ray;
    int n;
    double theta, tol;
    nbt_quad_ws *ws_phi;
    nbt_status st;
} sdir_ctx;

typedef struct {
    double a, b;
    int n;
} lobe_ctx;

static int lobe_f(double phi, void *vp, unsigned fdim, double *f)
{
    (void)fdim;
    const lobe_ctx *c = vp;
    double v = c->a + c->b * cos(phi);
    f[0] = v > 0 ? pow(v, c->n) : 0.0;
    return 0;
}

static int sdir_f(double g, void *vp, unsigned fdim, double *f)
{
    (void)fdim;
    sdir_ctx *c = vp;
    lobe_ctx l = {cos(c->theta) * cos(g), sin(c->theta) * sin(g), c->n};
    double phi0 = (l.b > 0 && fabs(l.a) < l.b) ? acos(-l.a / l.b) : NBT_PI;
    double lob, le, La, Le;
    nbt_status st = nbt_quad_gk_pts(c->ws_phi, lobe_f, &l, 1, 0.0, NBT_PI, &phi0, phi0 < NBT_PI,
                                    0.0, 0.1 * c->tol, &lob, &le);
    if (st == NBT_OK && lob > 0) {
        c->ray.gamma = g;
        st = nbt__airlight_ray(c->p, NULL, 0, &c->ray, 0.1 * c->tol, &La, &Le);
    } else
        La = 0;
    if (st != NBT_OK && c->st == NBT_OK)
        c->st = st;
    f[0] = 2.0 * lob * sin(g) * La;
    return 0;
}

static nbt_status lobe_direct(const nbt_phase *p, const nbt_surface_geom *g, int n, double theta,
                              double tol, double *val, double *err)
{
    sdir_ctx c = {p, {g->kappa_s, g->kappa_t, g->I0, g->dsp, 0.0, INFINITY}, n, theta, tol, NULL, NBT_OK};
    c.ws_phi = nbt_quad_ws_alloc(1, 500);
    nbt_quad_ws *ws = nbt_quad_ws_alloc(1, 1000);
    nbt_status st = NBT_ENOMEM;
    if (c.ws_phi && ws) {
        double pts[4], lo, hi;
        size_t np = kernel_kinks(theta, pts, &lo, &hi);
        (void)lo;
        (void)hi; /* integrate all of [0, pi]: the reference does not rely on the support */
        st = nbt_quad_gk_pts(ws, sdir_f, &c, 1, 0.0, NBT_PI, pts, np, 0.0, tol, val, err);
        if (st == NBT_OK)
            st = c.st;
    }
    nbt_quad_ws_free(c.ws_phi);
    nbt_quad_ws_free(ws);
    return st;
}

nbt_status nbt_surface_direct(const nbt_phase *p, const nbt_surface_geom *g, double tol,
                              double *Lp, double *abserr)
{
    nbt_status st = nbt_surface_check(g);
    if (st != NBT_OK)
        return st;
    double vd = 0, ed = 0, vs = 0, es = 0;
    if (g->kd > 0)
        st = lobe_direct(p, g, 1, g->theta_s, tol, &vd, &ed);
    if (st == NBT_OK && g->ks > 0)
        st = lobe_direct(p, g, g->n, g->theta_r, tol, &vs, &es);
    *Lp = direct_term(g) + g->kd * vd + g->ks * vs;
    *abserr = g->kd * ed + g->ks * es;
    return st;
}

nbt_status nbt_surface_series(const double *b, size_t nterms, const nbt_surface_geom *g,
                              double tol, double *Lp, double *abserr)
{
    nbt_status st = nbt_surface_check(g);
    if (st != NBT_OK)
        return st;
    if (nterms == 0)
        NBT_FAIL(NBT_EINVAL, "surface: need at least one Legendre term");
    /* one channel: J of the truncated series sum_k (2k+1) b_k P_k */
    nbt__weights w = {nterms - 1, NULL, b};
    double T = g->kappa_t * g->dsp, s = 0, e = 0;
    for (int lobe = 0; lobe < 2 && st == NBT_OK; lobe++) {
        double coef = lobe == 0 ? g->kd : g->ks, J, Je;
        if (coef == 0)
            continue;
        st = j_eval(&w, lobe == 0 ? 1 : g->n, T, lobe == 0 ? g->theta_s : g->theta_r, tol, &J, &Je);
        s += coef * J;
        e += coef * Je;
    }
    double pre = g->kappa_s * g->I0 / (4.0 * NBT_PI * g->dsp);
    *Lp = direct_term(g) + pre * s;
    *abserr = pre * e;
    return st;
}

nbt_status nbt_surface_table(const nbt_table *const *diffuse, size_t ndiffuse,
                             const nbt_table *const *specular, size_t nspecular,
                             const double *b, size_t nterms, const nbt_surface_geom *g, double *Lp)
{
    nbt_status st = nbt_surface_check(g);
    if (st != NBT_OK)
        return st;
    if ((g->kd > 0 && ndiffuse == 0) || (g->ks > 0 && nspecular == 0))
        NBT_FAIL(NBT_EINVAL, "surface: a lobe with a non-zero coefficient has no table");
    for (size_t i = 0; i < ndiffuse; i++)
        if (diffuse[i]->kind != NBT_TABLE_J || diffuse[i]->n != 1)
            NBT_FAIL(NBT_EINVAL, "surface: diffuse tables must be J tables with n = 1");
    for (size_t i = 0; i < nspecular; i++)
        if (specular[i]->kind != NBT_TABLE_J || specular[i]->n != g->n)
            NBT_FAIL(NBT_EINVAL, "surface: specular tables must be J tables with the geometry's n");
    double T = g->kappa_t * g->dsp, sd = 0, ss = 0;
    int out = 0;
    if (g->kd > 0)
        out |= nbt__table_series_diff(diffuse, ndiffuse, b, nterms, T, NAN, g->theta_s, &sd);
    if (g->ks > 0)
        out |= nbt__table_series_diff(specular, nspecular, b, nterms, T, NAN, g->theta_r, &ss);
    *Lp = direct_term(g) + g->kappa_s * g->I0 / (4.0 * NBT_PI * g->dsp) * (g->kd * sd + g->ks * ss);
    return out ? NBT_ETOL : NBT_OK;
}

/* ---- J tables: J(T_i, theta_j) = sum_q G(T_i, g_q) M(theta_j, q) ----
 *
 * G is smooth in g, so it is sampled once on Gauss-Legendre nodes of fixed
 * panels (graded towards g = 0, where G varies on a scale ~ 1/sqrt(T)).
 * M(theta, q) = int K_n(theta, g) l_q(g) dg, l_q the Lagrange basis of the
 * panel's nodes, integrated per theta between the kernel's own kinks with a
 * smoothstep change of variable that makes the (g - g_kink)^{n+1/2} endpoint
 * behaviour analytic. */

#define J_PANEL_NODES 16

typedef struct {
    size_t nch;
    const int *kmap;
    int n;
    nbt__weights w;
    unsigned fdim, nt;
    double tol;
    size_t npanel, Q;
    double *pb;                 /* panel boundaries, npanel + 1 */
    double *gq;                 /* nodes, Q */
    double *lam;                /* barycentric weights per node within its panel */
    const double *xs, *ys;
    size_t nx, ny;
    double *G, *M, *F;
    double *rowerr;
    nbt_quad_ws **ws;
    double **buf;
    nbt_gl_rule *rk, *rm;       /* kernel rule; integration rule for M */
    int checked;                /* the adaptive check below ran (once per build) */
} jfill_ctx;

static nbt_status j_grow(size_t i, unsigned thread, void *vp)
{
    jfill_ctx *c = vp;
    double e = 0, *err = c->buf[thread];
    for (size_t q = 0; q < c->Q; q++) {
        double *G = c->G + (i * c->Q + q) * c->fdim;
        nbt_status st = g_eval(c->ws[thread], &c->w, c->xs[i], c->gq[q], c->tol, G, err);
        if (st != NBT_OK)
            return st;
        for (unsigned k = 0; k < c->fdim; k++)
            e = fmax(e, err[k]);
    }
    c->rowerr[i] = e;
    return NBT_OK;
}

static nbt_status j_mrow(size_t j, unsigned thread, void *vp)
{
    (void)thread;
    jfill_ctx *c = vp;
    double theta = c->ys[j], kinks[4], lo, hi;
    size_t nk = kernel_kinks(theta, kinks, &lo, &hi);
    double *M = c->M + j * c->Q;
    for (size_t q = 0; q < c->Q; q++)
        M[q] = 0;
    size_t m = J_PANEL_NODES;
    for (size_t p = 0; p < c->npanel; p++) {
        double a = fmax(c->pb[p], lo), b = fmin(c->pb[p + 1], hi);
        if (!(b > a))
            continue;
        const double *x = c->gq + p * m, *lam = c->lam + p * m;
        double cuts[6];
        size_t nc = 0;
        cuts[nc++] = a;
        for (size_t k = 0; k < nk; k++)
            if (kinks[k] > a && kinks[k] < b)
                cuts[nc++] = kinks[k];
        cuts[nc++] = b;
        for (size_t s = 0; s + 1 < nc; s++) {
            double c0 = cuts[s], w0 = cuts[s + 1] - cuts[s];
            for (size_t r = 0; r < c->rm->n; r++) {
                double y = 0.5 * (1.0 + c->rm->x[r]);
                double g = c0 + w0 * y * y * (3.0 - 2.0 * y);
                double wt = 0.5 * c->rm->w[r] * w0 * 6.0 * y * (1.0 - y);
                double Kw = wt * kernel_eval(c->rk, c->n, theta, g);
                if (Kw == 0)
                    continue;
                /* barycentric Lagrange basis at g */
                double den = 0;
                size_t hit = m;
                for (size_t q = 0; q < m; q++) {
                    if (g == x[q]) {
                        hit = q;
                        break;
                    }
                    den += lam[q] / (g - x[q]);
                }
                if (hit < m) {
                    M[p * m + hit] += Kw;
                    continue;
                }
                for (size_t q = 0; q < m; q++)
                    M[p * m + q] += Kw * lam[q] / (g - x[q]) / den;
            }
        }
    }
    return NBT_OK;
}

static nbt_status j_product(size_t i, unsigned thread, void *vp)
{
    (void)thread;
    jfill_ctx *c = vp;
    size_t nch = c->nch;
    for (size_t j = 0; j < c->ny; j++) {
        const double *M = c->M + j * c->Q;
        for (size_t ch = 0; ch < nch; ch++) {
            unsigned k = c->w.phase ? 0u : (unsigned)c->kmap[ch];
            const double *G = c->G + i * c->Q * c->fdim + k;
            double s = 0;
            for (size_t q = 0; q < c->Q; q++)
                s += G[q * c->fdim] * M[q];
            c->F[(i * c->ny + j) * nch + ch] = s;
        }
    }
    return NBT_OK;
}

static nbt_status j_fill(void *vp, const double *xs, size_t nx, const double *ys, size_t ny,
                         double *F, double *quad_err)
{
    jfill_ctx *c = vp;
    c->xs = xs;
    c->ys = ys;
    c->nx = nx;
    c->ny = ny;
    c->F = F;
    c->G = malloc(nx * c->Q * c->fdim * sizeof(double));
    c->M = malloc(ny * c->Q * sizeof(double));
    c->rowerr = calloc(nx, sizeof(double));
    nbt_status st = NBT_ENOMEM;
    if (c->G && c->M && c->rowerr) {
        st = nbt__parallel_for(nx, c->nt, j_grow, c);
        if (st == NBT_OK)
            st = nbt__parallel_for(ny, c->nt, j_mrow, c);
        if (st == NBT_OK)
            st = nbt__parallel_for(nx, c->nt, j_product, c);
    }
    /* error of the g quadrature: check against adaptive J at the corners
     * and the centre (to 1e-8: this bounds an error far below any table's) */
    double qerr = 0;
    for (size_t i = 0; i < nx; i++)
        qerr = fmax(qerr, c->rowerr[i]) ; /* G's own error, times int K <= 2 pi */
    qerr *= 2.0 * NBT_PI;
    if (st == NBT_OK && !c->checked) {
        c->checked = 1;
        size_t si[5] = {0, nx - 1, 0, nx - 1, nx / 2}, sj[5] = {0, 0, ny - 1, ny - 1, ny / 2};
        double J[256], E[256];
        for (int a = 0; a < 5 && st == NBT_OK; a++) {
            size_t i = si[a], j = sj[a];
            unsigned fd = c->fdim;
            double *Jv = fd <= 256 ? J : malloc(2 * fd * sizeof(double)), *Ev = fd <= 256 ? E : Jv + fd;
            if (!Jv) {
                st = NBT_ENOMEM;
                break;
            }
            st = j_eval(&c->w, c->n, xs[i], ys[j], fmax(c->tol, 1e-8), Jv, Ev);
            for (size_t ch = 0; ch < c->nch && st == NBT_OK; ch++) {
                unsigned k = c->w.phase ? 0u : (unsigned)c->kmap[ch];
                qerr = fmax(qerr, fabs(F[(i * ny + j) * c->nch + ch] - Jv[k]) + Ev[k]);
            }
            if (Jv != J)
                free(Jv);
        }
    }
    *quad_err = qerr;
    free(c->G);
    free(c->M);
    free(c->rowerr);
    return st;
}

nbt_status nbt_j_table_build_set(nbt_table *const *ts, size_t ntab, const nbt_phase *fixed, const nbt_build_opts *o)
{
    int *kmap;
    jfill_ctx c = {.tol = o->quad_tol};
    c.w.phase = fixed;
    nbt_status st = nbt__table_set_prepare(ts, ntab, fixed, &kmap, &c.nch, &c.w.kmax);
    if (st != NBT_OK)
        return st;
    c.kmap = kmap;
    nbt_table *t = ts[0];
    c.n = t->n;
    if (t->kind != NBT_TABLE_J)
        st = nbt__fail(NBT_EINVAL, "J table: the table is not of kind J");
    else if (t->n < 1)
        st = nbt__fail(NBT_EDOM, "J table: the cosine exponent n must be >= 1");
    else if (t->axis[0].lo < 0 || t->axis[1].lo < 0 || t->axis[1].hi > NBT_PI)
        st = nbt__fail(NBT_EDOM, "J table: axes must lie in T >= 0, theta in [0, pi]");
    else if (!(o->quad_tol > 0 && o->quad_tol < 1))
        st = nbt__fail(NBT_EDOM, "J table: quad_tol must lie in (0, 1)");
    if (st != NBT_OK) {
        free(kmap);
        return st;
    }
    c.fdim = nbt__fdim(&c.w);
    for (size_t i = 0; i < ntab; i++)
        ts[i]->quad_tol = o->quad_tol;
    /* panels: geometric below pi/8 down to ~0.2/sqrt(1 + T_max), uniform above */
    size_t ngeo = 0;
    while (ngeo < 20 && NBT_PI / 8 * ldexp(1.0, -(int)ngeo) > 0.2 / sqrt(1.0 + t->axis[0].hi))
        ngeo++;
    c.npanel = ngeo + 8;
    size_t m = J_PANEL_NODES;
    c.Q = c.npanel * m;
    c.pb = malloc((c.npanel + 1) * sizeof(double));
    c.gq = malloc(c.Q * sizeof(double));
    c.lam = malloc(c.Q * sizeof(double));
    nbt_gl_rule *rp = nbt_gl_rule_alloc(m);
    c.rk = nbt_gl_rule_alloc(kernel_nodes(c.n));
    c.rm = nbt_gl_rule_alloc(2 * m + 8);
    c.nt = nbt__nthreads(o->nthreads, 2 * t->axis[0].n);
    nbt_quad_ws *ws[64] = {0};
    double *buf[64] = {0};
    for (unsigned i = 0; i < c.nt; i++) {
        ws[i] = nbt_quad_ws_alloc(c.fdim, SEG_MAX_INTERVALS);
        buf[i] = malloc(c.fdim * sizeof(double));
        if (!ws[i] || !buf[i])
            st = NBT_ENOMEM;
    }
    if (!c.pb || !c.gq || !c.lam || !rp || !c.rk || !c.rm)
        st = NBT_ENOMEM;
    if (st == NBT_OK) {
        size_t p = 0;
        c.pb[p++] = 0.0;
        for (size_t j = ngeo; j >= 1; j--)
            c.pb[p++] = NBT_PI / 8 * ldexp(1.0, -(int)j);
        for (int j = 1; j <= 8; j++)
            c.pb[p++] = NBT_PI / 8 * j;
        c.pb[c.npanel] = NBT_PI;
        for (size_t q = 0; q < c.npanel; q++)
            for (size_t r = 0; r < m; r++) {
                double a = c.pb[q], b = c.pb[q + 1];
                c.gq[q * m + r] = 0.5 * (a + b) + 0.5 * (b - a) * rp->x[r];
                c.lam[q * m + r] = ((r % 2) ? -1.0 : 1.0) * sqrt((1.0 - rp->x[r] * rp->x[r]) * rp->w[r]);
            }
        c.ws = ws;
        c.buf = buf;
        c.tol = 0.1 * o->quad_tol;
        st = nbt__table_fill(ts, ntab, o->measure_error ? NBT__MEASURE_SPARSE : 0, j_fill, &c);
    }
    for (unsigned i = 0; i < c.nt; i++) {
        nbt_quad_ws_free(ws[i]);
        free(buf[i]);
    }
    free(c.pb);
    free(c.gq);
    free(c.lam);
    nbt_gl_rule_free(rp);
    nbt_gl_rule_free(c.rk);
    nbt_gl_rule_free(c.rm);
    free(kmap);
    if (st == NBT_ENOMEM)
        NBT_FAIL(st, "J table: out of memory");
    return st;
}

nbt_status nbt_j_table_build(nbt_table *t, const nbt_phase *fixed, const nbt_build_opts *o)
{
    return nbt_j_table_build_set(&t, 1, fixed, o);
}
