/* libnbt/gslice_tail.c: the tail form of g-sliced H tables (NBT_FORM_TAIL,
 * doc/tables.md): fill with its relative error map (per node) and per g cell, and the airlight
 * from it (lookup, physical exponentials, a Gauss rule on short segments).
 *
 * HG in the angle phi = 2 atan(s/k), k = (1 - g)/(1 + g), s = tan(pi/4 + t/2)
 * (Moebius map of the circle; with alpha = t + pi/2 the scattering angle,
 * tan(alpha/2) = s = k tan(phi/2)):
 *   4 pi p_g(-sin t) dt = sqrt(1 + g^2 + 2 g cos phi)/(1 - g^2) dphi,
 * smooth in phi for every |g| < 1: HG's peak, of width ~1 - |g| in t, is
 * spread over O(1) in phi. Both the table's cells and the short segments are
 * integrated in phi. */
#include <config.h>
#include <math.h>
#include <pthread.h>
#include <stdlib.h>
#include <string.h>
#include <nbt/gslice.h>
#include "internal.h"
#include "gslice_tail.h"

/* exponents above this (relative to the start) are dropped: e^-60 < 1e-26 */
#define TAIL_YCAP 60.0


double nbt__tail_phi(double s, double g)
{
    return isinf(s) ? NBT_PI : 2.0 * atan(s * (1.0 + g) / (1.0 - g));
}

/* W = 1 + s/2 + u s^2/2 at s = s(v) */
static double weight_s(double u, double s)
{
    return 1.0 + 0.5 * s + 0.5 * u * s * s;
}

double nbt__tail_weight(double u, double v)
{
    double s = nbt__s_of_t(v);
    return isinf(s) ? INFINITY : weight_s(u, s);
}

/* int_{pa}^{pb} exp(y0 - u k tan(phi/2)) f(phi) dphi in pieces of at most
 * wmax in phi and `step` in the exponent, m-node Gauss-Legendre each;
 * stops where the exponent falls TAIL_YCAP below y0 - u s(pa) */
static double tail_seg(const nbt_gl_rule *R, double g, double u, double y0, double pa, double pb, double step,
                       double wmax)
{
    double k = (1.0 - g) / (1.0 + g), acc = 0.0, a = pa;
    double ystart = u > 0 ? u * k * tan(0.5 * pa) : 0.0;
    while (a < pb) {
        double sa = k * tan(0.5 * a);
        if (u > 0 && u * sa - ystart > TAIL_YCAP)
            break;
        double b = fmin(pb, a + wmax);
        if (u > 0) /* the exponent's step, and ratio <= 2 in pi - phi (s ~ 1/(pi - phi)) */
            b = fmin(fmin(b, 2.0 * atan((sa + step / u) / k)), a + 0.5 * (NBT_PI - a));
        double c = 0.5 * (a + b), h = 0.5 * (b - a), sum = 0.0;
        for (size_t i = 0; i < R->n; i++) {
            /* one tan per node: cos phi = (1 - tan^2(phi/2))/(1 + tan^2(phi/2)) */
            double tq = tan(0.5 * (c + h * R->x[i])), cph = tq > 1e150 ? -1.0 : (1.0 - tq * tq) / (1.0 + tq * tq);
            double e = u > 0 ? exp(y0 - u * k * tq) : exp(y0);
            sum += R->w[i] * e * sqrt(fmax(1.0 + g * g + 2.0 * g * cph, 0.0));
        }
        acc += h * sum / (1.0 - g * g);
        a = b;
    }
    return acc;
}

/* ---- fill ---- */

typedef struct {
    const double *gs, *us, *vs;
    size_t ng, nu, nv;
    double *out;          /* out[(m nv + j) nu + i]: R = C W */
    double *qerr;         /* per task: relative quadrature error (check rows) */
    nbt_gl_rule *R, *Rfine;
} tail_ctx;

/* C(u, v_j) for all j of one u row by the tail recursion
 * C_j = exp(-u (s_{j+1} - s_j)) C_{j+1} + int_{v_j}^{v_{j+1}}, from C = 0 at pi/2 */
static void tail_row(const nbt_gl_rule *R, double g, double u, const double *vs, size_t nv, double step,
                     double wmax, double *row)
{
    double cnext = 0.0, snext = INFINITY;
    for (size_t jj = nv; jj-- > 0;) {
        double v = vs[jj], s = nbt__s_of_t(v);
        if (isinf(s)) {
            cnext = 0.0;
            snext = s;
            row[jj] = (1.0 - g * g) / ((1.0 + g) * (1.0 + g) * (1.0 + g)); /* R at pi/2: 4 pi p(-1) */
            continue;
        }
        double decay = u > 0 ? (isinf(snext) ? 0.0 : exp(-u * (snext - s))) : 1.0;
        double seg = tail_seg(R, g, u, u * s, nbt__tail_phi(s, g), nbt__tail_phi(snext, g), step, wmax);
        double c = decay * cnext + seg;
        row[jj] = c * weight_s(u, s);
        cnext = c;
        snext = s;
    }
}

static nbt_status tail_task(size_t task, unsigned thread, void *vp)
{
    (void)thread;
    tail_ctx *c = vp;
    size_t m = task / c->nu, i = task % c->nu;
    double *row = malloc(c->nv * sizeof *row), *fine = malloc(c->nv * sizeof *fine);
    if (!row || !fine) {
        free(row);
        free(fine);
        return NBT_ENOMEM;
    }
    tail_row(c->R, c->gs[m], c->us[i], c->vs, c->nv, 1.0, 0.1, row);
    double e = 0;
    if (i < 2 || i % 32 == 0 || i + 1 == c->nu) {
        /* a rerun with pieces half as long (in phi and in the exponent) and twice the nodes */
        tail_row(c->Rfine, c->gs[m], c->us[i], c->vs, c->nv, 0.5, 0.05, fine);
        for (size_t j = 0; j < c->nv; j++)
            e = fmax(e, 2.0 * fabs(fine[j] - row[j]) / fabs(fine[j]));
    }
    for (size_t j = 0; j < c->nv; j++)
        c->out[(m * c->nv + j) * c->nu + i] = row[j];
    c->qerr[task] = e;
    free(row);
    free(fine);
    return NBT_OK;
}

/* R on the grid us x vs for every g in gs; *qerr: largest relative quadrature error */
static nbt_status tail_grid(const double *gs, size_t ng, const double *us, size_t nu, const double *vs, size_t nv,
                            unsigned nthreads, double *out, double *qerr)
{
    tail_ctx c = {gs, us, vs, ng, nu, nv, out, calloc(ng * nu, sizeof(double)), nbt_gl_rule_alloc(4),
                  nbt_gl_rule_alloc(8)};
    nbt_status st = NBT_ENOMEM;
    if (c.qerr && c.R && c.Rfine)
        st = nbt__parallel_for(ng * nu, nbt__nthreads(nthreads, ng * nu), tail_task, &c);
    *qerr = 0;
    for (size_t i = 0; st == NBT_OK && i < ng * nu; i++)
        *qerr = fmax(*qerr, c.qerr[i]);
    free(c.qerr);
    nbt_gl_rule_free(c.R);
    nbt_gl_rule_free(c.Rfine);
    return st;
}

/* the error map's value at a node: relative error bound of the cells
 * around it (channel 1) */
double nbt__tail_err_at(const nbt_table *t, double u, double v, double g)
{
    if (t->nch < 2)
        return nbt_table_err_at(t, 0, g);
    size_t i, j, m;
    double f;
    nbt__axis_cell(&t->axis[0], u, &i, &f);
    nbt__axis_cell(&t->axis[1], v, &j, &f);
    nbt__axis_cell(&t->axis[2], g, &m, &f);
    size_t nu = t->axis[0].n, nv = t->axis[1].n;
    double e = 0;
    for (size_t dm = 0; dm < 2; dm++)
        for (size_t dj = 0; dj < 2; dj++)
            for (size_t di = 0; di < 2; di++)
                e = fmax(e, t->data[(((m + dm) * nv + j + dj) * nu + i + di) * 2 + 1]);
    return e;
}

typedef struct {
    const nbt_table *t;
    const double *ex, *us, *vs2, *gs;
    size_t nu, nv, nv2, ng, ns;
    double *ce;
} meas_ctx;

/* the error of g cell m's (u, v) cells, from the exact rows at g_m, the
 * midpoint and g_{m+1} */
static nbt_status meas_task(size_t m, unsigned thread, void *vp)
{
    (void)thread;
    const meas_ctx *c = vp;
    const nbt_table *t = c->t;
    const nbt_axis *ag = &t->axis[2];
    const double *ex = c->ex, *us = c->us, *vs2 = c->vs2, *gs = c->gs;
    size_t nu = c->nu, nv = c->nv, nv2 = c->nv2, ng = c->ng, ns = c->ns;
    double *ce = c->ce, dg = 1e-9 / (double)(ng - 1);
    double gl = nbt_axis_from_unit(ag, ((double)m + 0.5) / (double)(ng - 1) - dg);
    double gh = nbt_axis_from_unit(ag, ((double)m + 0.5) / (double)(ng - 1) + dg);
    const double *rows[3] = {ex + m * ns, ex + (ng + m) * ns, ex + (m + 1) * ns};
    /* cubic in g: the midpoint is the worst point of an inner cell's error
     * polynomial (x+1)x(x-1)(x-2), 9/16 at x = 1/2; in the first and last
     * cells the one-sided stencil's x(x-1)(x-2)(x-3) peaks at 1 (x = 0.382)
     * against 15/16 at the midpoint, so there the measurement is scaled by
     * 16/15 */
    double fmid = t->interp2 == 3 && (m == 0 || m + 2 == ng) ? 16.0 / 15.0 : 1.0;
    for (size_t j2 = 0; j2 < nv2; j2++)
        for (size_t i = 0; i < nu; i++) {
            double e = 0, eu = 0;
            for (int q = 0; q < 3; q++) {
                double x = rows[q][j2 * nu + i], a[2], b[2];
                if (q == 1) {
                    nbt_table_lookup3(t, us[i], vs2[j2], gl, a);
                    nbt_table_lookup3(t, us[i], vs2[j2], gh, b);
                    e = fmax(e, fmid * fmax(fabs(expm1(a[0] - log(x))), fabs(expm1(b[0] - log(x)))));
                } else if (j2 % 2) {
                    nbt_table_lookup3(t, us[i], vs2[j2], q ? gs[m + 1] : gs[m], a);
                    e = fmax(e, fabs(expm1(a[0] - log(x))));
                }
                if (i > 0 && i + 1 < nu)
                    eu = fmax(eu, fabs(log(rows[q][j2 * nu + i - 1]) - 2.0 * log(x) +
                                       log(rows[q][j2 * nu + i + 1])) / 8.0);
            }
            /* the point's cells: u cells i-1, i; v cells around j2 */
            size_t jlo = j2 / 2 > 0 && j2 % 2 == 0 ? j2 / 2 - 1 : j2 / 2, jhi = j2 / 2;
            if (jhi > nv - 2)
                jhi = nv - 2;
            for (size_t j = jlo; j <= jhi; j++)
                for (size_t ii = i > 0 ? i - 1 : 0; ii <= i && ii + 1 < nu; ii++) {
                    double *pc = &ce[(m * (nv - 1) + j) * (nu - 1) + ii];
                    *pc = fmax(*pc, e + eu);
                }
        }
    return NBT_OK;
}

nbt_status nbt__tail_fill(nbt_table *t, const nbt_build_opts *o)
{
    if (!(t->axis[1].lo == -NBT_PI_2 && t->axis[1].hi == NBT_PI_2) || t->axis[0].lo != 0.0)
        NBT_FAIL(NBT_EDOM, "g-sliced H table (tail form): axes must be u in [0, hi], v in [-pi/2, pi/2]");
    if (t->axis[2].n < 3)
        NBT_FAIL(NBT_EINVAL, "g-sliced H table (tail form): the g axis needs at least 3 nodes (quadratic in g)");
    const nbt_axis *ag = &t->axis[2];
    int meas = o->measure_error;
    /* measuring: v refined (node rows are the even ones) */
    size_t nu = t->axis[0].n, nv = t->axis[1].n, ng = ag->n, vstep = meas ? 2 : 1, nv2 = vstep * (nv - 1) + 1;
    size_t ns = nu * nv2;
    /* two channels: log R and, when measured, the error map */
    float *d2 = realloc(t->data, nu * nv * ng * 2 * sizeof(float));
    if (d2)
        t->data = d2;
    double *c2 = d2 ? realloc(t->cell_err, (ng - 1) * 2 * sizeof(double)) : NULL;
    if (c2)
        t->cell_err = c2;
    double *us = malloc(nu * sizeof *us), *vs2 = malloc(nv2 * sizeof *vs2), *gs = malloc(2 * ng * sizeof *gs);
    /* exact R on the grid refined in v (node rows are the even ones) at
     * the g nodes, then (measuring) at the g midpoints */
    double *ex = malloc((meas ? 2 * ng - 1 : ng) * ns * sizeof *ex), qerr = 0;
    nbt_status st = d2 && c2 && us && vs2 && gs && ex ? NBT_OK : NBT_ENOMEM;
    if (st == NBT_OK) {
        t->nch = 2;
        t->k[1] = -1;
        for (size_t i = 0; i < nu; i++)
            us[i] = nbt_axis_node(&t->axis[0], i);
        for (size_t j = 0; j < nv2; j++)
            vs2[j] = j % vstep == 0 ? nbt_axis_node(&t->axis[1], j / vstep)
                                : nbt_axis_from_unit(&t->axis[1], (double)j / (double)(nv2 - 1));
        for (size_t m = 0; m < ng; m++)
            gs[m] = nbt_axis_node(ag, m);
        for (size_t m = 0; m + 1 < ng; m++)
            gs[ng + m] = nbt_axis_from_unit(ag, ((double)m + 0.5) / (double)(ng - 1));
        st = tail_grid(gs, meas ? 2 * ng - 1 : ng, us, nu, vs2, nv2, o->nthreads, ex, &qerr);
    }
    double amax = 0;
    for (size_t m = 0; st == NBT_OK && m < ng; m++)
        for (size_t j = 0; j < nv; j++)
            for (size_t i = 0; i < nu; i++) {
                double r = ex[m * ns + vstep * j * nu + i];
                t->data[((m * nv + j) * nu + i) * 2] = (float)log(r);
                t->data[((m * nv + j) * nu + i) * 2 + 1] = NAN;
                amax = fmax(amax, r);
            }
    t->form = NBT_FORM_TAIL;
    /* cubic in g where there are 4 slices: the g error ~h^4, 4.7 times
     * below quadratic's at 33 slices on [-0.95, 0.95] (doc/tables.md) */
    t->interp2 = ng >= 4 ? 3 : 2;
    for (size_t m = 0; c2 && m + 1 < ng; m++)
        t->cell_err[2 * m] = t->cell_err[2 * m + 1] = NAN;
    double *ce = NULL;
    if (st == NBT_OK && meas && !(ce = calloc((nu - 1) * (nv - 1) * (ng - 1), sizeof *ce)))
        st = NBT_ENOMEM;
    if (st == NBT_OK && meas) {
        /* per (u, v, g) cell: the largest relative error |lookup/exact - 1|
         * at its points (u node) x (v node, v midpoint) x (g nodes, g
         * midpoint with both quadratic stencils), plus the bilinear u error
         * at its u midpoints estimated from second differences of log R in
         * u (|d2|/8) on the same rows, plus the quadrature error */
        meas_ctx mc = {t, ex, us, vs2, gs, nu, nv, nv2, ng, ns, ce};
        st = nbt__parallel_for(ng - 1, nbt__nthreads(o->nthreads, ng - 1), meas_task, &mc);
        /* node values: the largest of the cells around the node */
        for (size_t m = 0; m < ng; m++)
            for (size_t j = 0; j < nv; j++)
                for (size_t i = 0; i < nu; i++) {
                    double e = 0;
                    for (size_t mm = m > 0 ? m - 1 : 0; mm <= m && mm + 1 < ng; mm++)
                        for (size_t jj = j > 0 ? j - 1 : 0; jj <= j && jj + 1 < nv; jj++)
                            for (size_t ii = i > 0 ? i - 1 : 0; ii <= i && ii + 1 < nu; ii++)
                                e = fmax(e, ce[(mm * (nv - 1) + jj) * (nu - 1) + ii]);
                    /* rounded up to float */
                    float f = (float)(e + qerr);
                    if ((double)f < e + qerr)
                        f = nextafterf(f, INFINITY);
                    t->data[((m * nv + j) * nu + i) * 2 + 1] = f;
                }
        for (size_t m = 0; m + 1 < ng; m++) {
            double e = 0;
            for (size_t k = 0; k < (nu - 1) * (nv - 1); k++)
                e = fmax(e, ce[m * (nv - 1) * (nu - 1) + k]);
            t->cell_err[2 * m] = e + qerr;
        }
    }
    free(ce);
    free(ex);
    free(us);
    free(vs2);
    free(gs);
    if (st != NBT_OK)
        NBT_FAIL(st, "g-sliced H table (tail form): out of memory");
    double emax = 0;
    for (size_t m = 0; meas && m + 1 < ng; m++)
        emax = fmax(emax, t->cell_err[2 * m]);
    t->quad_tol = 1e-10;
    t->quad_err = qerr;
    t->max_abs[0] = amax;
    t->max_err[0] = meas ? emax : NAN;
    t->max_err[1] = t->max_abs[1] = NAN;
    return NBT_OK;
}

/* ---- airlight ---- */

nbt_status nbt__airlight_tail(const nbt_table *t, double g, const void *geom, double *La, double *abserr,
                              int *used_gauss)
{
    const nbt_airlight_geom *geo = geom;
    double h = geo->dsv * sin(geo->gamma), tf = geo->dsv * cos(geo->gamma), kt = geo->kappa_t;
    double u = kt * h, th0 = geo->gamma - NBT_PI_2;
    double thd = isinf(geo->dvp) ? NBT_PI_2 : atan2(geo->dvp - tf, h);
    double pref = geo->kappa_s * geo->I0 / (4.0 * NBT_PI * h);
    double r0[NBT_TABLE_MAX_CH], rd[NBT_TABLE_MAX_CH] = {0}, w0 = nbt__tail_weight(u, th0), wd = nbt__tail_weight(u, thd);
    nbt_table_lookup3(t, u, th0, g, r0);
    if (!isinf(wd))
        nbt_table_lookup3(t, u, thd, g, rd);
    double c0 = isinf(w0) ? 0.0 : exp(r0[0]) / w0, cd = isinf(wd) ? 0.0 : exp(rd[0]) / wd;
    double A = exp(-kt * geo->dsv);
    double dsp = hypot(geo->dvp - tf, h), B = isinf(geo->dvp) ? 0.0 : exp(-kt * (dsp + geo->dvp));
    /* theta_0 = pi/2 (gamma = pi in double): C = 0 times an infinite
     * prefactor, no bound */
    double e0 = isinf(w0) ? INFINITY : nbt__tail_err_at(t, u, th0, g);
    double ed = isinf(wd) ? 0.0 : nbt__tail_err_at(t, u, thd, g);
    *used_gauss = 0;
    if (B * cd > NBT_TAIL_SHORT * A * c0) {
        /* the two terms nearly cancel: the segment by a fixed Gauss rule in
         * phi (the shader's), its error from the rule with twice the nodes */
        *used_gauss = 1;
        /* s(theta_d) - s(theta_0) = (d_sp + d_vp - d_sv)/h, the path's excess
         * d_vp (d_sv - t_f + d_sp + d_vp - t_f)/(d_sp + d_sv) without cancellation */
        double q = geo->dvp - tf, sh = sin(0.5 * geo->gamma);
        double ex = geo->dvp * (2.0 * geo->dsv * sh * sh + (q >= 0 ? dsp + q : h * h / (dsp - q))) / (dsp + geo->dsv);
        double s0 = tan(0.5 * geo->gamma), ds = ex / h; /* s(theta_0) = tan(gamma/2) */
        double s1 = nbt__tail_gauss(g, u, kt * geo->dsv, s0, ds, 0);
        double s2 = nbt__tail_gauss(g, u, kt * geo->dsv, s0, ds, 1);
        *La = pref * s1;
        *abserr = pref * (2.0 * fabs(s2 - s1) + 1e-12 * fabs(s2)); /* + rounding */
        return NBT_OK;
    }
    *La = pref * (A * c0 - B * cd);
    /* |lookup/exact - 1| <= e, so |exact - lookup| <= e |lookup|/(1 - e) */
    *abserr = e0 >= 1.0 || ed >= 1.0 ? INFINITY
                                     : pref * (A * c0 * e0 / (1.0 - e0) + B * cd * ed / (1.0 - ed));
    return NBT_OK;
}

/* the short-segment rules (NBT_TAIL_GAUSS_N nodes and twice that), computed
 * once: computing them per call was ~30 us of a ~33 us evaluation */
static nbt_gl_rule *gauss_rule[2];
static pthread_once_t gauss_once = PTHREAD_ONCE_INIT;

static void gauss_init(void)
{
    gauss_rule[0] = nbt_gl_rule_alloc(NBT_TAIL_GAUSS_N);
    gauss_rule[1] = nbt_gl_rule_alloc(2 * NBT_TAIL_GAUSS_N);
}

double nbt__tail_gauss(double g, double u, double e0, double s0, double ds, int fine)
{
    pthread_once(&gauss_once, gauss_init);
    const nbt_gl_rule *R = gauss_rule[fine ? 1 : 0];
    if (!R)
        return NAN;
    int n = (int)R->n;
    /* a = tan(phi_0/2), b = tan(phi_d/2); dphi by the atan difference */
    double k = (1.0 - g) / (1.0 + g), a = s0 / k, b = a + ds / k;
    double c0 = 1.0 / sqrt(1.0 + a * a), n0 = a * c0, dphi = 2.0 * atan((ds / k) / (1.0 + a * b)), sum = 0.0;
    for (int i = 0; i < n; i++) {
        double hd = 0.25 * dphi * (1.0 + R->x[i]), sd = sin(hd), ci = c0 * cos(hd) - n0 * sd;
        /* u (s - s0) = u k (tan(phi/2) - a) = u k sin(delta/2)/(cos(phi/2) cos(phi_0/2)) */
        double y = e0 + u * k * sd / (ci * c0), cphi = 2.0 * ci * ci - 1.0;
        sum += R->w[i] * exp(-y) * sqrt(fmax(1.0 + g * g + 2.0 * g * cphi, 0.0));
    }
    return 0.5 * dphi * sum / (1.0 - g * g);
}

nbt_status nbt__tail_round_half(nbt_table *t)
{
    size_t n = nbt_table_size(t) / t->nch;
    /* the log values move by at most d, a lookup by the weights' sum times d */
    double er = expm1(nbt__lookup_weight_sum(t) * nbt__table_round_half_change(t, 0));
    /* the map before rounding is not kept: add the rounding, then a margin of
     * a half-precision step (2^-10 relative) so that the rounded map is not
     * below it */
    for (size_t i = 0; i < n; i++)
        t->data[i * t->nch + 1] = (float)(((double)t->data[i * t->nch + 1] * (1.0 + 0x1p-10) + er) * (1.0 + 0x1p-10));
    nbt_table_round_half(t);
    for (size_t m = 0; m + 1 < t->axis[2].n; m++)
        t->cell_err[m * t->nch] += er;
    t->max_err[0] += er;
    return NBT_OK;
}
