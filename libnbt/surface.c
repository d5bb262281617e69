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
#include "gslice_j.h"
#ifdef __SSE2__
#include <emmintrin.h>
#endif

#define SEG_MAX_INTERVALS 2000

/* ---- the azimuthal kernel K_n(theta, g) ---- */

static double ipow_d(double x, int n)
{
    double r = 1;
    for (; n > 0; n >>= 1, x *= x)
        if (n & 1)
            r *= x;
    return r;
}

static size_t kernel_nodes(int n)
{
    size_t m = 48 + (size_t)n;
    return m > 600 ? 600 : m;
}

/* K_n from cos/sin of theta and g (both in [0, pi]). With a = cos theta
 * cos g, b = sin theta sin g: a + b = cos(theta - g), a - b = cos(theta + g),
 * so |a| + b <= 1 and every sum below loses at most ~n DBL_EPSILON absolute,
 * which is all J's weights need (rule = NULL). Relative accuracy where the
 * horizon cuts the lobe and a < 0 (K tiny next to those sums) takes a
 * Gauss-Legendre rule of kernel_nodes(n) nodes: the point evaluations. */
static double kernel_cs(const nbt_gl_rule *rule, int n, double ct, double st, double cg, double sg)
{
    double a = ct * cg, b = fabs(st * sg);
    if (a >= b) {
        /* the whole cone is above the horizon: 2 pi sum_{j even} C(n,j) a^{n-j} b^j (j-1)!!/j!!
         * = 2 pi a^n sum_j ... (b/a)^j */
        if (a == 0)
            return 0.0;
        double x = b / a, x2 = x * x, s = 1, binom = 1, dfr = 1, xp = 1;
        for (int j = 2; j <= n; j += 2) {
            binom *= (double)(n - j + 2) * (double)(n - j + 1) / ((double)(j - 1) * (double)j);
            dfr *= (double)(j - 1) / j;
            xp *= x2;
            s += binom * xp * dfr;
        }
        return 2.0 * NBT_PI * (n <= 16 ? ipow_d(a, n) : pow(a, n)) * s;
    }
    if (a <= -b)
        return 0.0;
    /* cut by the horizon: 2 I_n, I_m = int_0^{phi0} (a + b cos phi)^m dphi,
     * cos phi0 = -a/b. The reduction formula's boundary term
     * b sin phi (a + b cos phi)^{m-1} vanishes at 0 and phi0 for m >= 2:
     * m I_m = (2m - 1) a I_{m-1} - (m - 1)(a^2 - b^2) I_{m-2}. Its two
     * solutions grow like (a + b)^m and (a - b)^m, both <= 1 in size. */
    double c0 = -a / b, phi0 = acos(c0), s0 = sqrt(fmax(0.0, 1.0 - c0 * c0));
    if (rule && a < 0 && n > 1) {
        double s = 0;
        for (size_t i = 0; i < rule->n; i++) {
            double v = a + b * cos(0.5 * phi0 * (1.0 + rule->x[i]));
            s += rule->w[i] * (v > 0 ? ipow_d(v, n) : 0.0);
        }
        return phi0 * s;
    }
    double I0 = phi0, I1 = a * phi0 + b * s0, d = a * a - b * b;
    for (int m = 2; m <= n; m++) {
        double I2 = ((2.0 * m - 1.0) * a * I1 - (m - 1.0) * d * I0) / m;
        I0 = I1;
        I1 = I2;
    }
    return 2.0 * (n == 0 ? I0 : I1);
}

static double kernel_eval(const nbt_gl_rule *rule, int n, double theta, double g)
{
    return kernel_cs(rule, n, cos(theta), sin(theta), cos(g), sin(g));
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
    nbt__weights w = {kmax, NULL, NULL, NULL, 0, NULL};
    return j_eval(&w, n, T, theta, tol, J, abserr);
}

nbt_status nbt_j_phase(const nbt_phase *p, int n, double T, double theta, double tol,
                       double *J, double *abserr)
{
    nbt__weights w = {0, p, NULL, NULL, 0, NULL};
    return j_eval(&w, n, T, theta, tol, J, abserr);
}

/* ---- surface radiance ---- */

nbt_status nbt_surface_check(const nbt_surface_geom *g)
{
    if (!(g->kappa_s >= 0.0) || !isfinite(g->kappa_s))
        return nbt__failv(NBT_EDOM, "surface: kappa_s = %g is not accepted: finite and >= 0", g->kappa_s);
    if (!(g->kappa_t >= g->kappa_s) || !isfinite(g->kappa_t))
        return nbt__failv(NBT_EDOM, "surface: kappa_t = %g is not accepted: finite and >= kappa_s = %g", g->kappa_t,
                          g->kappa_s);
    if (!(g->I0 >= 0.0) || !isfinite(g->I0))
        return nbt__failv(NBT_EDOM, "surface: I0 = %g is not accepted: finite and >= 0", g->I0);
    if (!(g->dsp > 0.0) || !isfinite(g->dsp))
        return nbt__failv(NBT_EDOM, "surface: dsp = %g is not accepted: finite and > 0", g->dsp);
    if (!(g->theta_s >= 0 && g->theta_s <= NBT_PI))
        return nbt__failv(NBT_EDOM, "surface: theta_s = %g is not accepted: in [0, pi]", g->theta_s);
    if (!(g->theta_r >= 0 && g->theta_r <= NBT_PI))
        return nbt__failv(NBT_EDOM, "surface: theta_r = %g is not accepted: in [0, pi]", g->theta_r);
    if (!(g->kd >= 0) || !isfinite(g->kd))
        return nbt__failv(NBT_EDOM, "surface: kd = %g is not accepted: finite and >= 0", g->kd);
    if (!(g->ks >= 0) || !isfinite(g->ks))
        return nbt__failv(NBT_EDOM, "surface: ks = %g is not accepted: finite and >= 0", g->ks);
    if (g->n < 1)
        return nbt__failv(NBT_EDOM, "surface: the Phong exponent n = %d is not accepted: >= 1", g->n);
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
    double rel; /* the inner integrals' largest relative error estimate (lobe + airlight) */
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
    /* a missed inner tolerance (NBT_ETOL) still gives a value and its error */
    if ((st == NBT_OK || st == NBT_ETOL) && lob > 0) {
        c->ray.gamma = g;
        st = nbt__status_join(st, nbt__airlight_ray(c->p, NULL, 0, &c->ray, 0.1 * c->tol, &La, &Le));
        if (La > 0)
            c->rel = fmax(c->rel, le / lob + Le / La);
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
    sdir_ctx c = {p, {g->kappa_s, g->kappa_t, g->I0, g->dsp, 0.0, INFINITY}, n, theta, tol, NULL, NBT_OK, 0.0};
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
        /* the integrand is >= 0 with a relative error of at most c.rel at every node */
        *err += c.rel * fabs(*val);
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
    /* a missed tolerance in the diffuse lobe must not drop the specular one */
    if ((st == NBT_OK || st == NBT_ETOL) && g->ks > 0)
        st = nbt__status_join(st, lobe_direct(p, g, g->n, g->theta_r, tol, &vs, &es));
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
    nbt__weights w = {nterms - 1, NULL, b, NULL, 0, NULL};
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
 * G is smooth in g on (0, pi], so it is sampled once on Gauss-Legendre nodes
 * of fixed panels (graded towards g = 0, where G varies on a scale
 * ~ 1/sqrt(T)). At g = 0 it is not smooth: u = T sin g, and H(u, pi/2) has
 * u^j log u terms, so G ~ smooth + T g log g. A polynomial in g on the first
 * panel [0, h0] leaves ~T e^-T h0 / m^2 (3.5e-9 at T = 5, 1.5e-7 on T in
 * [0, 1]); there the nodes and the basis live in y with
 * g = h0 ((1 + y)/2)^J_FIRST_POW, where g log g becomes y^P log y and the
 * interpolation error falls like m^-2P. M(theta, q) = int K_n(theta, g)
 * l_q(y(g)) dg, l_q the Lagrange basis of the panel's nodes in y, is
 * integrated per theta in y between the kernel's own kinks, with a
 * smoothstep change of variable that makes the (g - g_kink)^{n+1/2}
 * endpoint behaviour analytic.
 *
 * The error of the product (interpolation of G, the rule for M) is measured:
 * on the first 3, every J_CHECK_STRIDE-th and the last T row it is rebuilt
 * with every panel halved, and twice the largest difference over all theta
 * is added to the G quadrature error. */

#define J_PANEL_NODES 16
/* HG slices: 10 nodes per panel. J^1, J^20 65^2 x 33 over g in [-0.95,
 * 0.95]: recorded quadrature error (relative, log_et) 2.4e-6 / 4.1e-5 with
 * 16, 4.0e-6 / 4.2e-5 with 10, 9.2e-5 / 1.3e-4 with 8; build 1.6x faster
 * with 10 than with 16 */
#define J_PANEL_NODES_HG 10
#define J_FIRST_POW 4
#define J_CHECK_STRIDE 8

typedef struct {
    size_t npanel, Q;
    double *pb; /* panel boundaries, npanel + 1, pb[0] = 0 */
    double *gq; /* nodes in g, Q = npanel * J_PANEL_NODES */
} jpanels;

typedef struct {
    size_t nch;
    const int *kmap;
    int n;
    nbt__weights w;
    unsigned fdim, nt;
    double tol;
    const jpanels *P;           /* the panels of the current pass */
    jpanels coarse, fine;       /* the table's, and each halved (the check) */
    const nbt_gl_rule *rp;      /* the panel rule, nodes y in [-1, 1] */
    double lam[J_PANEL_NODES];  /* its barycentric weights (rp->n <= J_PANEL_NODES of them) */
    const double *xs, *ys;
    size_t nx, ny;
    double *G, *M, *F;
    size_t *mq;                 /* per theta row of M: its non-zero q in [mq[2j], mq[2j + 1]) */
    double *Mk, *yk;            /* the coarse panels' M, mq and theta nodes of the last pass (the */
    size_t *mqk, nyk;           /* measured rows' pass has the node rows' thetas: M once), or NULL */
    double *rowerr;
    nbt_quad_ws **ws;
    double **buf;
    nbt_gl_rule *rm;            /* integration rule for M */
    int checked;                /* the check ran (on the node rows, once per build) */
    nbt__segfix *sf;            /* fixed rules for G (Legendre channels), or NULL */
    double check_err;           /* its result, added to later passes */
    nbt__jcache *gc;            /* G rows shared with other builds (Legendre channels), or NULL */
    size_t ngeo, nhi;           /* the panel layout (the rows' key) */
    unsigned char *have;        /* rows of the current pass taken from gc */
    int logform;                /* values as ln(e^T J) (NBT_FORM_LOG_ET), errors relative */
} jfill_ctx;

/* g(y) on panel p, dg/dy, and the inverse */
static double panel_g(const jpanels *P, size_t p, double y)
{
    double a = P->pb[p], b = P->pb[p + 1], r = 0.5 * (1.0 + y);
    return p == 0 ? b * pow(r, J_FIRST_POW) : a + (b - a) * r;
}

static double panel_dg(const jpanels *P, size_t p, double y)
{
    double a = P->pb[p], b = P->pb[p + 1], r = 0.5 * (1.0 + y);
    return p == 0 ? 0.5 * J_FIRST_POW * b * pow(r, J_FIRST_POW - 1) : 0.5 * (b - a);
}

static double panel_y(const jpanels *P, size_t p, double g)
{
    double a = P->pb[p], b = P->pb[p + 1];
    return p == 0 ? 2.0 * pow(g / b, 1.0 / J_FIRST_POW) - 1.0 : (2.0 * g - a - b) / (b - a);
}

static void jpanels_free(jpanels *P)
{
    free(P->pb);
    free(P->gq);
}

/* geometric below pi/8 (ngeo panels), 8 uniform above, the last of them
 * geometric towards pi (nhi more panels); split: each halved */
static nbt_status jpanels_init(jpanels *P, size_t ngeo, size_t nhi, int split, const nbt_gl_rule *rp)
{
    size_t nb = ngeo + 8 + nhi, f = split ? 2 : 1, m = rp->n;
    P->npanel = nb * f;
    P->Q = P->npanel * m;
    P->pb = malloc((P->npanel + 1) * sizeof(double));
    P->gq = malloc(P->Q * sizeof(double));
    if (!P->pb || !P->gq)
        return NBT_ENOMEM;
    double base[64];
    size_t p = 0;
    base[p++] = 0.0;
    for (size_t j = ngeo; j >= 1; j--)
        base[p++] = NBT_PI / 8 * ldexp(1.0, -(int)j);
    for (int j = 1; j <= 7; j++)
        base[p++] = NBT_PI / 8 * j;
    for (size_t j = 1; j <= nhi; j++)
        base[p++] = NBT_PI - NBT_PI / 8 * ldexp(1.0, -(int)j);
    base[p++] = NBT_PI;
    for (size_t q = 0; q < nb; q++)
        for (size_t s = 0; s < f; s++)
            P->pb[q * f + s] = base[q] + (base[q + 1] - base[q]) * (double)s / (double)f;
    P->pb[P->npanel] = NBT_PI;
    for (size_t q = 0; q < P->npanel; q++)
        for (size_t r = 0; r < m; r++)
            P->gq[q * m + r] = panel_g(P, q, rp->x[r]);
    return NBT_OK;
}

static nbt_status j_grow(size_t i, unsigned thread, void *vp)
{
    jfill_ctx *c = vp;
    double *err = c->buf[thread], *re = c->rowerr + i * c->fdim;
    if (c->have && c->have[i])
        return NBT_OK; /* the row and its errors came from the plan's cache */
    for (unsigned k = 0; k < c->fdim; k++)
        re[k] = 0.0;
    for (size_t q = 0; q < c->P->Q; q++) {
        double *G = c->G + (i * c->P->Q + q) * c->fdim;
        if (c->sf) {
            /* Legendre channels: fixed rules, one a-priori bound for all orders */
            double T = c->xs[i], g = c->P->gq[q], b = 0, ex = exp(-T);
            nbt__segfix_eval(c->sf, &c->w, T * sin(g), g - NBT_PI_2, NBT_PI_2, 1, G, err, &b);
            for (unsigned k = 0; k < c->fdim; k++) {
                G[k] *= ex;
                re[k] = fmax(re[k], b * ex);
            }
            continue;
        }
        nbt_status st = g_eval(c->ws[thread], &c->w, c->xs[i], c->P->gq[q], c->tol, G, err);
        if (st != NBT_OK)
            return st;
        for (unsigned k = 0; k < c->fdim; k++)
            re[k] = fmax(re[k], err[k]);
    }
    return NBT_OK;
}

static nbt_status j_mrow(size_t j, unsigned thread, void *vp)
{
    (void)thread;
    jfill_ctx *c = vp;
    const jpanels *P = c->P;
    double theta = c->ys[j], kinks[4], lo, hi, ct = cos(theta), st = sin(theta);
    size_t nk = kernel_kinks(theta, kinks, &lo, &hi);
    double *M = c->M + j * P->Q;
    for (size_t q = 0; q < P->Q; q++)
        M[q] = 0;
    size_t m = c->rp->n;
    const double *x = c->rp->x, *lam = c->lam;
    for (size_t p = 0; p < P->npanel; p++) {
        double a = fmax(P->pb[p], lo), b = fmin(P->pb[p + 1], hi);
        if (!(b > a))
            continue;
        /* the pieces between kinks, in the panel's variable y */
        double cuts[6];
        size_t nc = 0;
        cuts[nc++] = panel_y(P, p, a);
        for (size_t k = 0; k < nk; k++)
            if (kinks[k] > a && kinks[k] < b)
                cuts[nc++] = panel_y(P, p, kinks[k]);
        cuts[nc++] = panel_y(P, p, b);
        for (size_t s = 0; s + 1 < nc; s++) {
            double c0 = cuts[s], w0 = cuts[s + 1] - cuts[s];
            for (size_t r = 0; r < c->rm->n; r++) {
                double z = 0.5 * (1.0 + c->rm->x[r]);
                double y = c0 + w0 * z * z * (3.0 - 2.0 * z);
                double wt = 0.5 * c->rm->w[r] * w0 * 6.0 * z * (1.0 - z) * panel_dg(P, p, y);
                double g = panel_g(P, p, y);
                double Kw = wt * kernel_cs(NULL, c->n, ct, st, cos(g), sin(g));
                if (Kw == 0)
                    continue;
                /* barycentric Lagrange basis at y */
                double den = 0;
                size_t hit = m;
                for (size_t q = 0; q < m; q++) {
                    if (y == x[q]) {
                        hit = q;
                        break;
                    }
                    den += lam[q] / (y - x[q]);
                }
                if (hit < m) {
                    M[p * m + hit] += Kw;
                    continue;
                }
                for (size_t q = 0; q < m; q++)
                    M[p * m + q] += Kw * lam[q] / (y - x[q]) / den;
            }
        }
    }
    size_t qa = 0, qb = P->Q;
    while (qa < qb && M[qa] == 0)
        qa++;
    while (qb > qa && M[qb - 1] == 0)
        qb--;
    c->mq[2 * j] = qa;
    c->mq[2 * j + 1] = qb;
    return NBT_OK;
}

/* a0[k] = sum_q G[q fd + k] M0[q], a1 the same with M1, q from qa to
 * qb - 1 in order. Where SSE2 is there, eight and then two orders at a
 * time; each sum's additions are a scalar loop's, in its order (the same
 * values to the bit). */
static void j_dot2(const double *G, size_t fd, const double *M0, const double *M1, size_t qa, size_t qb,
                   double *a0, double *a1)
{
    size_t k = 0;
#ifdef __SSE2__
    for (; k + 8 <= fd; k += 8) {
        __m128d x0 = _mm_setzero_pd(), x1 = x0, x2 = x0, x3 = x0, y0 = x0, y1 = x0, y2 = x0, y3 = x0;
        for (size_t q = qa; q < qb; q++) {
            const double *g = G + q * fd + k;
            __m128d m0 = _mm_set1_pd(M0[q]), m1 = _mm_set1_pd(M1[q]);
            __m128d g0 = _mm_loadu_pd(g), g1 = _mm_loadu_pd(g + 2), g2 = _mm_loadu_pd(g + 4), g3 = _mm_loadu_pd(g + 6);
            x0 = _mm_add_pd(x0, _mm_mul_pd(g0, m0));
            x1 = _mm_add_pd(x1, _mm_mul_pd(g1, m0));
            x2 = _mm_add_pd(x2, _mm_mul_pd(g2, m0));
            x3 = _mm_add_pd(x3, _mm_mul_pd(g3, m0));
            y0 = _mm_add_pd(y0, _mm_mul_pd(g0, m1));
            y1 = _mm_add_pd(y1, _mm_mul_pd(g1, m1));
            y2 = _mm_add_pd(y2, _mm_mul_pd(g2, m1));
            y3 = _mm_add_pd(y3, _mm_mul_pd(g3, m1));
        }
        _mm_storeu_pd(a0 + k, x0);
        _mm_storeu_pd(a0 + k + 2, x1);
        _mm_storeu_pd(a0 + k + 4, x2);
        _mm_storeu_pd(a0 + k + 6, x3);
        _mm_storeu_pd(a1 + k, y0);
        _mm_storeu_pd(a1 + k + 2, y1);
        _mm_storeu_pd(a1 + k + 4, y2);
        _mm_storeu_pd(a1 + k + 6, y3);
    }
    for (; k + 2 <= fd; k += 2) {
        __m128d x0 = _mm_setzero_pd(), y0 = x0;
        for (size_t q = qa; q < qb; q++) {
            __m128d g0 = _mm_loadu_pd(G + q * fd + k);
            x0 = _mm_add_pd(x0, _mm_mul_pd(g0, _mm_set1_pd(M0[q])));
            y0 = _mm_add_pd(y0, _mm_mul_pd(g0, _mm_set1_pd(M1[q])));
        }
        _mm_storeu_pd(a0 + k, x0);
        _mm_storeu_pd(a1 + k, y0);
    }
#endif
    for (; k < fd; k++) {
        double x = 0, y = 0;
        for (size_t q = qa; q < qb; q++) {
            x += G[q * fd + k] * M0[q];
            y += G[q * fd + k] * M1[q];
        }
        a0[k] = x;
        a1[k] = y;
    }
}

/* row i of F = G_i M^T, two theta rows at a time, over the q where either
 * of their kernel rows is non-zero (K_n vanishes beyond theta +- pi/2: the
 * terms left out are zeros, and adding G * 0 changes no sum) */
static nbt_status j_product(size_t i, unsigned thread, void *vp)
{
    jfill_ctx *c = vp;
    size_t nch = c->nch, Q = c->P->Q, fd = c->fdim, ny = c->ny;
    double *acc = c->buf[thread];
    const double *G = c->G + i * Q * fd;
    for (size_t j0 = 0; j0 < ny; j0 += 2) {
        size_t nr = j0 + 1 < ny ? 2 : 1, j1 = j0 + nr - 1;
        size_t qa = c->mq[2 * j0], qb = c->mq[2 * j0 + 1];
        qa = c->mq[2 * j1] < qa ? c->mq[2 * j1] : qa;
        qb = c->mq[2 * j1 + 1] > qb ? c->mq[2 * j1 + 1] : qb;
        j_dot2(G, fd, c->M + j0 * Q, c->M + j1 * Q, qa, qb, acc, acc + fd);
        for (size_t jj = 0; jj < nr; jj++)
            for (size_t ch = 0; ch < nch; ch++)
                c->F[(i * ny + j0 + jj) * nch + ch] = acc[jj * fd + (c->w.phase ? 0u : (unsigned)c->kmap[ch])];
    }
    return NBT_OK;
}

/* J at (xs[i], ys[j]) on the panels P; *gerr: G's quadrature error times
 * int K dg <= 2 pi */
static nbt_status j_compute(jfill_ctx *c, const jpanels *P, const double *xs, size_t nx, const double *ys,
                            size_t ny, double *F, double *gerr)
{
    c->P = P;
    c->xs = xs;
    c->ys = ys;
    c->nx = nx;
    c->ny = ny;
    c->F = F;
    c->G = malloc(nx * P->Q * c->fdim * sizeof(double));
    /* M depends on the panels and theta only: the coarse one is kept */
    int keep = P == &c->coarse, reuse = keep && c->Mk && ny == c->nyk && !memcmp(ys, c->yk, ny * sizeof *ys);
    c->M = reuse ? c->Mk : malloc(ny * P->Q * sizeof(double));
    c->mq = reuse ? c->mqk : malloc(2 * ny * sizeof(size_t));
    c->rowerr = calloc(nx * c->fdim, sizeof(double));
    int share = c->gc && (c->sf || c->w.hg);
    c->have = share ? calloc(nx, 1) : NULL;
    nbt_status st = NBT_ENOMEM;
    double e = 0;
    if (c->G && c->M && c->mq && c->rowerr && (!share || c->have)) {
        /* rows another build of the plan computed are copied, the others
         * computed and offered to the later builds (fixed rules: one
         * a-priori bound for every component of a row; HG slices: each
         * component's adaptive bound) */
        size_t len = P->Q * c->fdim;
        nbt__jkey key = {0, c->tol, len, c->ngeo, c->nhi, c->fdim, P == &c->fine, c->w.hg};
        for (size_t i = 0; share && i < nx; i++) {
            key.T = xs[i];
            double re = 0, *rei = c->rowerr + i * c->fdim;
            c->have[i] = (unsigned char)nbt__jcache_get(c->gc, &key, c->G + i * len, c->w.hg ? rei : &re);
            for (unsigned k = 0; c->have[i] && !c->w.hg && k < c->fdim; k++)
                rei[k] = re;
        }
        st = nbt__parallel_for(nx, c->nt, j_grow, c);
        for (size_t i = 0; share && st == NBT_OK && i < nx; i++)
            if (!c->have[i]) {
                double re = 0;
                for (unsigned k = 0; k < c->fdim; k++)
                    re = fmax(re, c->rowerr[i * c->fdim + k]);
                key.T = xs[i];
                nbt__jcache_put(c->gc, &key, c->G + i * len, c->w.hg ? c->rowerr + i * c->fdim : &re);
            }
        if (st == NBT_OK && !reuse)
            st = nbt__parallel_for(ny, c->nt, j_mrow, c);
        if (st == NBT_OK)
            st = nbt__parallel_for(nx, c->nt, j_product, c);
        /* G's error per row and component; in the log form F -> T + ln F,
         * and that error over the smallest J of its channel in the row
         * becomes a bound in ln (relative) */
        for (size_t i = 0; i < nx && st == NBT_OK; i++)
            for (size_t ch = 0; ch < c->nch; ch++) {
                double *Fi = F + i * ny * c->nch + ch, jmin = INFINITY;
                double re = c->rowerr[i * c->fdim + (c->w.phase ? 0u : (unsigned)c->kmap[ch])];
                if (c->logform) {
                    for (size_t j = 0; j < ny; j++) {
                        jmin = fmin(jmin, Fi[j * c->nch]);
                        Fi[j * c->nch] = xs[i] + log(Fi[j * c->nch]);
                    }
                    if (!(jmin > 0))
                        st = nbt__fail(NBT_EDOM, "J table: form log_et needs J > 0 at every node");
                    re /= jmin;
                }
                e = fmax(e, re);
            }
    }
    free(c->have);
    c->have = NULL;
    *gerr = 2.0 * NBT_PI * e;
    free(c->G);
    double *yk = keep && !reuse && st == NBT_OK ? malloc(ny * sizeof *yk) : NULL;
    if (yk) { /* the new coarse M replaces the kept one */
        free(c->Mk);
        free(c->mqk);
        free(c->yk);
        c->Mk = c->M;
        c->mqk = c->mq;
        c->yk = memcpy(yk, ys, ny * sizeof *ys);
        c->nyk = ny;
    } else if (!reuse) {
        free(c->M);
        free(c->mq);
    }
    c->M = NULL;
    c->mq = NULL;
    free(c->rowerr);
    return st;
}

static int j_check_row(size_t i, size_t nx)
{
    return i < 3 || i % J_CHECK_STRIDE == 0 || i + 1 == nx;
}

static nbt_status j_fill(void *vp, const double *xs, size_t nx, const double *ys, size_t ny,
                         double *F, double *quad_err)
{
    jfill_ctx *c = vp;
    double qerr = 0;
    nbt_status st = j_compute(c, &c->coarse, xs, nx, ys, ny, F, &qerr);
    if (st == NBT_OK && !c->checked) {
        c->checked = 1;
        size_t ns = 0;
        for (size_t i = 0; i < nx; i++)
            ns += (size_t)j_check_row(i, nx);
        double *xc = malloc(ns * sizeof(double)), *Fc = malloc(ns * ny * c->nch * sizeof(double));
        size_t *ic = malloc(ns * sizeof(size_t));
        double qf = 0, d = 0;
        st = NBT_ENOMEM;
        if (xc && Fc && ic) {
            ns = 0;
            for (size_t i = 0; i < nx; i++)
                if (j_check_row(i, nx)) {
                    ic[ns] = i;
                    xc[ns++] = xs[i];
                }
            st = j_compute(c, &c->fine, xc, ns, ys, ny, Fc, &qf);
            for (size_t s = 0; s < ns && st == NBT_OK; s++)
                for (size_t j = 0; j < ny * c->nch; j++)
                    d = fmax(d, fabs(F[ic[s] * ny * c->nch + j] - Fc[s * ny * c->nch + j]));
        }
        free(xc);
        free(Fc);
        free(ic);
        /* twice: the rows between the checked ones, and the halved panels' own error */
        c->check_err = 2.0 * d + qf;
    }
    *quad_err = qerr + c->check_err;
    return st;
}

/* a fixed phase, HG at hg[0..ntab-1] (one one-channel table each, filled
 * in one pass), or (both NULL) Legendre channels; gc: G rows shared with other builds of a plan, or NULL */
static nbt_status j_build(nbt_table *const *ts, size_t ntab, const nbt_phase *fixed, const double *hg,
                          const nbt_build_opts *o, nbt__jcache *gc)
{
    int *kmap;
    jfill_ctx c = {.tol = o->quad_tol, .gc = gc};
    c.w.phase = fixed;
    nbt_phase *any = hg ? nbt_phase_hg(hg[0]) : NULL; /* set_prepare: channels are fixed-phase ones */
    nbt_status st = hg && !any ? NBT_ENOMEM : nbt__table_set_prepare(ts, ntab, hg ? any : fixed, &kmap, &c.nch,
                                                                        &c.w.kmax);
    nbt_phase_free(any);
    if (st != NBT_OK)
        return st;
    for (size_t i = 0; hg && i < ntab; i++) {
        if (ts[i]->nch != 1)
            st = nbt__fail(NBT_EINVAL, "J table: HG slices are one-channel tables");
        kmap[i] = (int)i; /* slice i is component i */
    }
    double *hgk = hg ? malloc(3 * ntab * sizeof *hgk) : NULL;
    if (hg) {
        c.w.hg = hg;
        c.w.nhg = ntab;
        c.w.kmax = 0;
        if (hgk) /* the HG constants once per build, not per node */
            nbt__hg_consts(hg, ntab, hgk);
        else
            st = NBT_ENOMEM;
        c.w.hgk = hgk;
    }
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
    for (size_t i = 0; i < ntab && st == NBT_OK; i++)
        if (ts[i]->form != t->form || (t->form != NBT_FORM_PLAIN && (t->form != NBT_FORM_SUB || hg) &&
                                       (t->form != NBT_FORM_LOG_ET || !(fixed || hg))))
            st = nbt__fail(NBT_EINVAL, "J table: forms plain, sub (not for HG slices), or log_et for a fixed "
                                       "phase, the same for the set");
    c.logform = t->form == NBT_FORM_LOG_ET;
    if (st != NBT_OK) {
        free(kmap);
        free(hgk);
        return st == NBT_ENOMEM ? nbt__fail(st, "J table: out of memory") : st;
    }
    c.fdim = nbt__fdim(&c.w);
    for (size_t i = 0; i < ntab; i++)
        ts[i]->quad_tol = o->quad_tol;
    /* panels: geometric below pi/8 down to ~0.2/sqrt(1 + T_max), uniform above */
    size_t ngeo = 0;
    /* a peaked fixed phase p(cos g) puts a feature of width ~1 - |mean
     * cosine| where the segment's lower end t = g - pi/2 crosses its peak:
     * at g = 0 (forward), g = pi (backward): panels graded to it */
    double hmin = 0.2 / sqrt(1.0 + t->axis[0].hi), mc = fixed ? nbt_phase_mean_cosine(fixed) : 0;
    double mfw = mc > 0 ? mc : 0, mbw = mc < 0 ? -mc : 0; /* the most forward and backward peaks */
    for (size_t i = 0; hg && i < ntab; i++) {
        mfw = fmax(mfw, hg[i]);
        mbw = fmax(mbw, -hg[i]);
    }
    if (mfw > 0)
        hmin = fmin(hmin, 0.5 * (1.0 - mfw));
    while (ngeo < 20 && NBT_PI / 8 * ldexp(1.0, -(int)ngeo) > hmin)
        ngeo++;
    size_t nhi = 0;
    while (mbw > 0 && nhi < 20 && NBT_PI / 8 * ldexp(1.0, -(int)nhi) > 0.5 * (1.0 - mbw))
        nhi++;
    c.ngeo = ngeo;
    c.nhi = nhi;
    /* HG slices (for 1e-3 tables ~1e-5 relative is plenty) take fewer
     * nodes per panel; the halved-panel check records what that costs */
    size_t m = hg ? J_PANEL_NODES_HG : J_PANEL_NODES;
    nbt_gl_rule *rp = nbt_gl_rule_alloc(m);
    c.rm = nbt_gl_rule_alloc(2 * m + 8);
    c.nt = nbt__nthreads(o->nthreads, 2 * t->axis[0].n);
    nbt_quad_ws *ws[64] = {0};
    double *buf[64] = {0};
    for (unsigned i = 0; i < c.nt; i++) {
        ws[i] = nbt_quad_ws_alloc(c.fdim, SEG_MAX_INTERVALS);
        buf[i] = malloc(2 * c.fdim * sizeof(double)); /* j_product: two rows */
        if (!ws[i] || !buf[i])
            st = NBT_ENOMEM;
    }
    if (!rp || !c.rm)
        st = NBT_ENOMEM;
    if (st == NBT_OK) {
        c.rp = rp;
        for (size_t r = 0; r < m; r++)
            c.lam[r] = ((r % 2) ? -1.0 : 1.0) * sqrt((1.0 - rp->x[r] * rp->x[r]) * rp->w[r]);
        st = jpanels_init(&c.coarse, ngeo, nhi, 0, rp);
        if (st == NBT_OK)
            st = jpanels_init(&c.fine, ngeo, nhi, 1, rp);
    }
    if (st == NBT_OK) {
        c.ws = ws;
        c.buf = buf;
        c.tol = 0.1 * o->quad_tol;
        if (!fixed && !hg && !(c.sf = nbt__segfix_alloc(c.tol)))
            st = NBT_ENOMEM;
        if (st == NBT_OK)
            st = nbt__table_fill(ts, ntab, o->measure_error ? NBT__MEASURE_SPARSE : 0, j_fill, &c);
        nbt__segfix_free(c.sf);
    }
    for (unsigned i = 0; i < c.nt; i++) {
        nbt_quad_ws_free(ws[i]);
        free(buf[i]);
    }
    jpanels_free(&c.coarse);
    jpanels_free(&c.fine);
    free(c.Mk);
    free(c.mqk);
    free(c.yk);
    nbt_gl_rule_free(rp);
    nbt_gl_rule_free(c.rm);
    free(kmap);
    free(hgk);
    if (st == NBT_ENOMEM)
        NBT_FAIL(st, "J table: out of memory");
    return st;
}

nbt_status nbt_j_table_build_set(nbt_table *const *ts, size_t ntab, const nbt_phase *fixed, const nbt_build_opts *o)
{
    return j_build(ts, ntab, fixed, NULL, o, NULL);
}

nbt_status nbt__j_table_build_set_gc(nbt_table *const *ts, size_t ntab, const nbt_phase *fixed,
                                     const nbt_build_opts *o, nbt__jcache *gc)
{
    return j_build(ts, ntab, fixed, NULL, o, gc);
}

nbt_status nbt__j_table_build_hg(nbt_table *const *ts, size_t m, const double *g, const nbt_build_opts *o,
                                 nbt__jcache *gc)
{
    return j_build(ts, m, NULL, g, o, gc);
}

nbt_status nbt_j_table_build(nbt_table *t, const nbt_phase *fixed, const nbt_build_opts *o)
{
    return nbt_j_table_build_set(&t, 1, fixed, o);
}
