/* libnbt/airlight.c: H_k, fixed-phase H, airlight three ways, H tables. */
#include <config.h>
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <nbt/airlight.h>
#include "internal.h"
#ifdef __SSE2__
#include <emmintrin.h>
#endif

#define SEG_MAX_INTERVALS 2000
/* exp(-y) beyond this y is below 1e-34 of the segment's leading value */
#define Y_TAIL 80.0
/* components kept on the stack when a segment is split */
#define NBT__SEG_MAXDIM 64

/* s = tan(pi/4 + t/2) = (1 + sin t)/cos t = cos t/(1 - sin t) from sin t, cos t */
static double s_of_sc(double t, double st, double ct)
{
    if (t >= NBT_PI_2)
        return INFINITY;
    if (t <= -NBT_PI_2)
        return 0.0; /* cos of the double nearest -pi/2 is 6e-17, not 0 */
    return t < 0 ? ct / (1.0 - st) : (1.0 + st) / ct;
}

double nbt__s_of_t(double t)
{
    return s_of_sc(t, sin(t), cos(t));
}

void nbt__hg_consts(const double *g, size_t n, double *hgk)
{
    for (size_t i = 0; i < n; i++) {
        hgk[i] = 1.0 + g[i] * g[i];
        hgk[n + i] = 2.0 * g[i];
        hgk[2 * n + i] = 1.0 - g[i] * g[i];
    }
}

/* f[i] = e 4 pi HG(g_i, mu) from hgk: nbt__hg_4pi's operations in its
 * order, (1 + g^2) - (2 g) mu, (1 - g^2) / (d sqrt d), two slices at a time
 * where SSE2 is there (the packed sqrt and division round as the scalar
 * ones do: the same values to the bit). The HG slices of a g-sliced J
 * table spend ~40% of their build here. */
static void hg_scaled(const double *hgk, size_t n, double mu, double e, double *f)
{
    const double *A = hgk, *B = hgk + n, *C = hgk + 2 * n;
    size_t i = 0;
#ifdef __SSE2__
    __m128d m2 = _mm_set1_pd(mu), e2 = _mm_set1_pd(e);
    for (; i + 2 <= n; i += 2) {
        __m128d d = _mm_sub_pd(_mm_loadu_pd(A + i), _mm_mul_pd(_mm_loadu_pd(B + i), m2));
        __m128d h = _mm_div_pd(_mm_loadu_pd(C + i), _mm_mul_pd(d, _mm_sqrt_pd(d)));
        _mm_storeu_pd(f + i, _mm_mul_pd(h, e2));
    }
#endif
    for (; i < n; i++) {
        double d = A[i] - B[i] * mu;
        f[i] = C[i] / (d * sqrt(d)) * e;
    }
}

/* Legendre orders or 4 pi p at mu = c, sn = sqrt(1 - c^2) computed without
 * cancellation by the caller. */
static void weights_at(const nbt__weights *w, double c, double sn, double *f)
{
    if (w->nhg)
        for (size_t i = 0; i < w->nhg; i++)
            f[i] = nbt__hg_4pi(w->hg[i], c);
    else if (w->phase)
        f[0] = 4.0 * NBT_PI * nbt__phase_eval_cs(w->phase, c, sn);
    else if (w->b)
        f[0] = nbt__legendre_series(w->b, w->kmax, c);
    else
        nbt_legendre_p(w->kmax, c, f);
}

/* weights_at times e */
static void weights_scaled(const nbt__weights *w, double c, double sn, double e, unsigned fdim, double *f)
{
    if (w->hgk) {
        hg_scaled(w->hgk, w->nhg, c, e, f);
        return;
    }
    weights_at(w, c, sn, f);
    for (unsigned k = 0; k < fdim; k++)
        f[k] *= e;
}

typedef struct {
    const nbt__weights *w;
    double u, base;
} seg_ctx;

/* In t: exp(-u (s(t) - base)) w(-sin t). Used for u < 1. */
static int seg_t(double t, void *vp, unsigned fdim, double *f)
{
    const seg_ctx *c = vp;
    double e = 1.0, st = sin(t), ct = cos(t);
    if (c->u > 0) {
        double s = s_of_sc(t, st, ct);
        e = isinf(s) ? 0.0 : exp(-c->u * (s - c->base));
    }
    weights_scaled(c->w, -st, fabs(ct), e, fdim, f);
    return 0;
}

/* In y = u (s - base): exp(-y) w(c(s)) 2/(1+s^2) / u. Used for u >= 1,
 * where the exponential, not the angle, sets the scale. */
static int seg_y(double y, void *vp, unsigned fdim, double *f)
{
    const seg_ctx *c = vp;
    double s = c->base + y / c->u;
    double mu, sn, jac;
    if (s <= 1.0) {
        double s2 = s * s;
        mu = (1.0 - s2) / (1.0 + s2);
        sn = 2.0 * s / (1.0 + s2);
        jac = 2.0 / (1.0 + s2);
    } else {
        double r = 1.0 / s, r2 = r * r;
        mu = (r2 - 1.0) / (r2 + 1.0);
        sn = 2.0 * r / (1.0 + r2);
        jac = 2.0 * r2 / (1.0 + r2);
    }
    weights_scaled(c->w, mu, sn, exp(-y) * jac / c->u, fdim, f);
    return 0;
}

/* In z = log(w), w = 1/s = cot(pi/4 + t/2) = cos t/(1 + sin t), for t in
 * [0, pi/2): exp(-u (1/w - base)) w(mu) 2w/(1+w^2), mu = (w^2-1)/(w^2+1),
 * sin(theta) = cos t = 2w/(1+w^2). Used for 0 < u < 1 on t > 0, where the
 * exponential falls from 1 to 0 over w ~ u near t = pi/2: a boundary layer
 * of width ~u in t that in z is smooth and O(1) wide. */
static int seg_z(double z, void *vp, unsigned fdim, double *f)
{
    const seg_ctx *c = vp;
    double w = exp(z), w2 = w * w;
    double sn = 2.0 * w / (1.0 + w2);
    weights_scaled(c->w, (w2 - 1.0) / (w2 + 1.0), sn, exp(-c->u * (1.0 / w - c->base)) * sn, fdim, f);
    return 0;
}

static double w_of_t(double t)
{
    return t >= NBT_PI_2 ? 0.0 : cos(t) / (1.0 + sin(t));
}

nbt_status nbt__airlight_segment(nbt_quad_ws *ws, const nbt__weights *w, double u,
                                 double v1, double v2, int shifted, double tol,
                                 double *out, double *err)
{
    unsigned fdim = nbt__fdim(w);
    double s1 = nbt__s_of_t(v1);
    seg_ctx c = {w, u, shifted ? s1 : 0.0};
    if (u < 1.0 && (u == 0.0 || v2 <= 0.0 || v1 >= v2))
        return nbt_quad_gk(ws, seg_t, &c, fdim, v1, v2, 0.0, tol, out, err);
    if (u < 1.0) {
        /* t in [v1, 0] as it is, t in [max(v1, 0), v2] in z = log w; below
         * w_c the exponential is under e^-Y_TAIL of its value at the start */
        double a[NBT__SEG_MAXDIM], ae[NBT__SEG_MAXDIM];
        double *r0 = fdim <= NBT__SEG_MAXDIM ? a : NULL, *e0 = fdim <= NBT__SEG_MAXDIM ? ae : NULL;
        nbt_status st = NBT_OK;
        double t0 = v1;
        if (v1 < 0.0) {
            if (!r0) {
                r0 = malloc(2 * fdim * sizeof(double));
                if (!r0)
                    NBT_FAIL(NBT_ENOMEM, "H: out of memory");
                e0 = r0 + fdim;
            }
            st = nbt_quad_gk(ws, seg_t, &c, fdim, v1, 0.0, 0.0, tol, r0, e0);
            t0 = 0.0;
        }
        double wa = w_of_t(t0), wb = w_of_t(v2);
        double wc = 1.0 / (fmax(c.base, 1.0 / wa) + Y_TAIL / u);
        nbt_status s2 = NBT_OK;
        if (wb < wc)
            wb = wc;
        if (wb < wa)
            s2 = nbt_quad_gk(ws, seg_z, &c, fdim, log(wb), log(wa), 0.0, tol, out, err);
        else
            for (unsigned k = 0; k < fdim; k++)
                out[k] = err[k] = 0.0;
        if (v1 < 0.0) {
            for (unsigned k = 0; k < fdim; k++) {
                out[k] += r0[k];
                err[k] += e0[k];
            }
            if (r0 != a)
                free(r0);
        }
        return st != NBT_OK ? st : s2;
    }
    double y1 = u * (s1 - c.base);
    double y2 = v2 >= NBT_PI_2 ? INFINITY : u * (nbt__s_of_t(v2) - c.base);
    double cap = fmax(y1, 0.0) + Y_TAIL;
    if (y2 > cap)
        y2 = cap;
    if (y1 > 700.0) { /* exp(-y) underflows: the segment is 0 in double */
        for (unsigned k = 0; k < fdim; k++)
            out[k] = err[k] = 0.0;
        return NBT_OK;
    }
    return nbt_quad_gk(ws, seg_y, &c, fdim, y1, y2, 0.0, tol, out, err);
}

static nbt_status check_uv(double u, double v, double tol)
{
    if (!(u >= 0.0) || isinf(u))
        NBT_FAIL(NBT_EDOM, "H: u must be finite and >= 0");
    if (!(v >= -NBT_PI_2 && v <= NBT_PI_2))
        NBT_FAIL(NBT_EDOM, "H: v must lie in [-pi/2, pi/2]");
    if (!(tol > 0.0 && tol < 1.0))
        NBT_FAIL(NBT_EDOM, "H: tol must lie in (0, 1)");
    return NBT_OK;
}

static nbt_status h_eval(const nbt__weights *w, double u, double v, double tol, double *H, double *err)
{
    nbt_status st = check_uv(u, v, tol);
    if (st != NBT_OK)
        return st;
    nbt_quad_ws *ws = nbt_quad_ws_alloc(nbt__fdim(w), SEG_MAX_INTERVALS);
    if (!ws)
        NBT_FAIL(NBT_ENOMEM, "H: out of memory");
    st = nbt__airlight_segment(ws, w, u, -NBT_PI_2, v, 0, tol, H, err);
    nbt_quad_ws_free(ws);
    return st;
}

nbt_status nbt_hk(size_t kmax, double u, double v, double tol, double *H, double *abserr)
{
    nbt__weights w = {kmax, NULL, NULL, NULL, 0, NULL};
    return h_eval(&w, u, v, tol, H, abserr);
}

nbt_status nbt_h_phase(const nbt_phase *p, double u, double v, double tol, double *H, double *abserr)
{
    nbt__weights w = {0, p, NULL, NULL, 0, NULL};
    return h_eval(&w, u, v, tol, H, abserr);
}

/* ---- airlight along a ray ---- */

nbt_status nbt_airlight_check(const nbt_airlight_geom *g)
{
    if (!(g->kappa_s >= 0.0) || !isfinite(g->kappa_s))
        return nbt__failv(NBT_EDOM, "airlight: kappa_s = %g is not accepted: finite and >= 0", g->kappa_s);
    if (!(g->kappa_t >= g->kappa_s) || !isfinite(g->kappa_t))
        return nbt__failv(NBT_EDOM, "airlight: kappa_t = %g is not accepted: finite and >= kappa_s = %g", g->kappa_t,
                          g->kappa_s);
    if (!(g->I0 >= 0.0) || !isfinite(g->I0))
        return nbt__failv(NBT_EDOM, "airlight: I0 = %g is not accepted: finite and >= 0", g->I0);
    if (!(g->dsv > 0.0) || !isfinite(g->dsv))
        return nbt__failv(NBT_EDOM, "airlight: dsv = %g is not accepted: finite and > 0", g->dsv);
    if (!(g->gamma >= 0.0 && g->gamma <= NBT_PI))
        return nbt__failv(NBT_EDOM, "airlight: gamma = %g is not accepted: in [0, pi]", g->gamma);
    if (!(g->dvp > 0.0))
        return nbt__failv(NBT_EDOM, "airlight: dvp = %g is not accepted: > 0 (INFINITY allowed)", g->dvp);
    if (g->gamma == 0.0 && g->dvp >= g->dsv)
        return nbt__failv(NBT_EDOM, "airlight: the ray runs through the source (gamma = 0, dvp = %g >= dsv = %g): "
                          "infinite", g->dvp, g->dsv);
    return NBT_OK;
}

/* Nishita's integrand in the distance x along the ray, with exp(-kappa_t dsv)
 * taken out (x + d(x) >= dsv, so the rest never overflows). */
typedef struct {
    const nbt_phase *p;        /* phase, or NULL: Legendre series b[0..nterms-1] */
    const double *b;
    size_t nterms;
    double kt, t, h, dsv;
    double x0, L;              /* tail map x = x0 + L y/(1-y) when L > 0 */
} ray_ctx;

static double ray_phase(const ray_ctx *c, double mu)
{
    if (c->p)
        return nbt_phase_eval(c->p, mu);
    return nbt__legendre_series(c->b, c->nterms - 1, mu) / (4.0 * NBT_PI);
}

static double ray_value(const ray_ctx *c, double x)
{
    double dx = x - c->t, d = hypot(dx, c->h);
    double mu = d > 0 ? -dx / d : 1.0;
    double ex = c->kt > 0 ? exp(-c->kt * (x + d - c->dsv)) : 1.0;
    return ray_phase(c, mu) * ex / (d * d);
}

static int ray_f(double x, void *vp, unsigned fdim, double *f)
{
    (void)fdim;
    f[0] = ray_value(vp, x);
    return 0;
}

static int ray_tail_f(double y, void *vp, unsigned fdim, double *f)
{
    (void)fdim;
    const ray_ctx *c = vp;
    double om = 1.0 - y;
    f[0] = ray_value(c, c->x0 + c->L * y / om) * c->L / (om * om);
    return 0;
}

/* int_0^dvp of the ray integrand (without kappa_s I0 exp(-kt dsv)). */
static nbt_status ray_integral(ray_ctx *c, double dvp, double tol, double *val, double *err)
{
    nbt_quad_ws *ws = nbt_quad_ws_alloc(1, 4000);
    if (!ws)
        NBT_FAIL(NBT_ENOMEM, "airlight: out of memory");
    double end = isinf(dvp) ? fmax(c->t, 0.0) + c->dsv : dvp;
    double pts[1];
    size_t np = 0;
    if (c->t > 0 && c->t < end)
        pts[np++] = c->t;
    nbt_status st = nbt_quad_gk_pts(ws, ray_f, c, 1, 0.0, end, pts, np, 0.0, tol, val, err);
    /* the tail beyond `end` also when the first part missed tol (NBT_ETOL):
     * without it the value lacked the tail and its error said nothing of it */
    if ((st == NBT_OK || st == NBT_ETOL) && isinf(dvp)) {
        double v2, e2;
        c->x0 = end;
        c->L = c->dsv;
        st = nbt__status_join(st, nbt_quad_gk(ws, ray_tail_f, c, 1, 0.0, 1.0, 0.0, tol, &v2, &e2));
        *val += v2;
        *err += e2;
    }
    nbt_quad_ws_free(ws);
    return st;
}

nbt_status nbt__airlight_ray(const nbt_phase *p, const double *b, size_t nterms,
                             const void *geom, double tol, double *La, double *err)
{
    const nbt_airlight_geom *g = geom;
    ray_ctx c = {p, b, nterms, g->kappa_t, g->dsv * cos(g->gamma), g->dsv * sin(g->gamma),
                 g->dsv, 0.0, 0.0};
    double v = 0, e = 0;
    nbt_status st = ray_integral(&c, g->dvp, tol, &v, &e);
    double pre = g->kappa_s * g->I0 * exp(-g->kappa_t * g->dsv);
    *La = pre * v;
    *err = pre * e;
    return st;
}

nbt_status nbt_airlight_direct(const nbt_phase *p, const nbt_airlight_geom *g, double tol,
                               double *La, double *abserr)
{
    nbt_status st = nbt_airlight_check(g);
    if (st != NBT_OK)
        return st;
    return nbt__airlight_ray(p, NULL, 0, g, tol, La, abserr);
}

nbt_status nbt_airlight_series(const double *b, size_t nterms, const nbt_airlight_geom *g,
                               double tol, double *La, double *abserr)
{
    nbt_status st = nbt_airlight_check(g);
    if (st != NBT_OK)
        return st;
    if (nterms == 0)
        NBT_FAIL(NBT_EINVAL, "airlight: need at least one Legendre term");
    double h = g->dsv * sin(g->gamma), t = g->dsv * cos(g->gamma);
    /* Nearly on the source axis theta_0 and theta_d are too close to -pi/2 or
     * pi/2 to be resolved in angle: the same series in distance is exact. */
    if (sin(g->gamma) < 1e-4)
        return nbt__airlight_ray(NULL, b, nterms, g, tol, La, abserr);
    nbt__weights w = {nterms - 1, NULL, b, NULL, 0, NULL};
    nbt_quad_ws *ws = nbt_quad_ws_alloc(1, SEG_MAX_INTERVALS);
    if (!ws)
        NBT_FAIL(NBT_ENOMEM, "airlight: out of memory");
    double th0 = g->gamma - NBT_PI_2;
    double thd = isinf(g->dvp) ? NBT_PI_2 : atan2(g->dvp - t, h);
    double D, De;
    /* one channel: the weighted sum of the H_k differences, never a difference of H values */
    st = nbt__airlight_segment(ws, &w, g->kappa_t * h, th0, thd, 1, tol, &D, &De);
    double pre = g->kappa_s * g->I0 * exp(-g->kappa_t * g->dsv) / (4.0 * NBT_PI * h);
    *La = pre * D;
    *abserr = pre * De;
    nbt_quad_ws_free(ws);
    return st;
}

int nbt__table_series_diff(const nbt_table *const *tables, size_t ntables, const double *b,
                           size_t nterms, double x0, double y0, double y1, double *sum)
{
    int outside = 0;
    *sum = 0;
    for (size_t i = 0; i < ntables; i++) {
        const nbt_table *T = tables[i];
        double a[NBT_TABLE_MAX_CH], c[NBT_TABLE_MAX_CH] = {0};
        if (x0 < T->axis[0].lo || x0 > T->axis[0].hi)
            outside = 1;
        nbt_table_lookup(T, x0, y1, a);
        if (!isnan(y0))
            nbt_table_lookup(T, x0, y0, c);
        for (size_t ch = 0; ch < T->nch; ch++) {
            int k = T->k[ch];
            double wk = k < 0 ? 1.0 : ((size_t)k < nterms ? (2.0 * k + 1.0) * b[k] : 0.0);
            *sum += wk * (a[ch] - c[ch]);
        }
    }
    return outside;
}

void nbt__airlight_from_diff(const void *geom, double h, double t, double s, double w, double *La, double *abserr)
{
    const nbt_airlight_geom *g = geom;
    /* e^{-kt t} may overflow where t < 0 while s is tiny: combine in logs */
    double lp = -g->kappa_t * t + log(g->kappa_s * g->I0 / (4.0 * NBT_PI * h));
    int zero = g->kappa_s == 0.0 || g->I0 == 0.0;
    *La = s == 0.0 || zero ? 0.0 : copysign(exp(lp + log(fabs(s))), s);
    *abserr = zero ? 0.0 : (w > 0 ? exp(lp + log(w)) : (w == 0 ? 0.0 : NAN));
}

nbt_status nbt__airlight_ray_or_lookup(const nbt_phase *p, const double *b, size_t nterms, const void *geom,
                                       double h, double Lt, double Et, int outside, double *La, double *abserr)
{
    double Lr, Er;
    nbt_status st = nbt__airlight_ray(p, b, nterms, geom, 1e-10, &Lr, &Er);
    if (st != NBT_OK && st != NBT_ETOL)
        return st;
    if (st == NBT_ETOL && h > 0.0 && !(Er < Et)) {
        *La = Lt;
        *abserr = Et;
        return outside ? NBT_ETOL : NBT_OK;
    }
    *La = Lr;
    *abserr = Er;
    return st;
}

nbt_status nbt_airlight_table_e(const nbt_table *const *tables, size_t ntables, const double *b,
                                size_t nterms, const nbt_phase *fixed, const nbt_airlight_geom *g,
                                double *La, double *abserr)
{
    nbt_status st = nbt_airlight_check(g);
    if (st != NBT_OK)
        return st;
    if (ntables == 0)
        NBT_FAIL(NBT_EINVAL, "airlight: no tables given");
    int isfixed = 0;
    size_t K = 0;
    for (size_t i = 0; i < ntables; i++) {
        if (tables[i]->kind != NBT_TABLE_H)
            NBT_FAIL(NBT_EINVAL, "airlight: table is not an H table");
        for (size_t c = 0; c < tables[i]->nch; c++) {
            int k = tables[i]->k[c];
            if (k < 0)
                isfixed = 1;
            else if ((size_t)k < nterms && (size_t)k > K)
                K = (size_t)k;
        }
    }
    if (!isfixed && (!b || nterms == 0))
        NBT_FAIL(NBT_EINVAL, "airlight: Legendre tables need the moments b");
    double h = g->dsv * sin(g->gamma), t = g->dsv * cos(g->gamma);
    double Lt = NAN, Et = INFINITY;
    int outside = 0;
    if (h > 0.0) {
        double th0 = g->gamma - NBT_PI_2;
        double thd = isinf(g->dvp) ? NBT_PI_2 : atan2(g->dvp - t, h);
        double s, w = 0;
        outside = nbt__table_series_diff(tables, ntables, b, nterms, g->kappa_t * h, th0, thd, &s);
        for (size_t i = 0; i < ntables; i++)
            for (size_t c = 0; c < tables[i]->nch; c++) {
                int k = tables[i]->k[c];
                double wk = k < 0 ? 1.0 : ((size_t)k < nterms ? (2.0 * k + 1.0) * b[k] : 0.0);
                w += 2.0 * fabs(wk) * tables[i]->max_err[c]; /* two lookups per channel */
            }
        nbt__airlight_from_diff(g, h, t, s, w, &Lt, &Et);
        /* max_err not measured (NaN): the lookup is all there is */
        if (isnan(Et) || Et <= NBT__TABLE_RAY_FRAC * fabs(Lt)) {
            *La = Lt;
            *abserr = Et;
            return outside ? NBT_ETOL : NBT_OK;
        }
    }
    /* Near the source axis (gamma -> 0 or pi, h -> 0) the airlight is the
     * small difference of two lookups divided by h: the bound above grows as
     * 1/h while the airlight stays finite. There (and wherever the bound
     * exceeds NBT__TABLE_RAY_FRAC of the value) integrate along the ray with the
     * phase the tables hold: the channels' truncated series, or the fixed
     * phase (given, or parsed from the table's name). */
    nbt_phase *own = NULL;
    const nbt_phase *ph = NULL;
    double *bk = NULL;
    if (isfixed) {
        ph = fixed;
        if (!ph) {
            char err[128];
            if (nbt_phase_parse(tables[0]->phase, &own, err, sizeof err) == NBT_OK)
                ph = own;
        }
        if (!ph) {
            if (!(h > 0.0))
                NBT_FAIL(NBT_EDOM, "airlight: on the source axis a fixed-phase table needs its phase function");
            *La = Lt;
            *abserr = Et;
            return outside ? NBT_ETOL : NBT_OK;
        }
    } else {
        bk = calloc(K + 1, sizeof(double));
        if (!bk)
            NBT_FAIL(NBT_ENOMEM, "airlight: out of memory");
        for (size_t i = 0; i < ntables; i++)
            for (size_t c = 0; c < tables[i]->nch; c++) {
                int k = tables[i]->k[c];
                if (k >= 0 && (size_t)k <= K && (size_t)k < nterms)
                    bk[k] = b[k];
            }
    }
    st = nbt__airlight_ray_or_lookup(ph, bk, bk ? K + 1 : 0, g, h, Lt, Et, outside, La, abserr);
    free(bk);
    nbt_phase_free(own);
    return st;
}

nbt_status nbt_airlight_table(const nbt_table *const *tables, size_t ntables, const double *b,
                              size_t nterms, const nbt_airlight_geom *g, double *La)
{
    double e;
    return nbt_airlight_table_e(tables, ntables, b, nterms, NULL, g, La, &e);
}

/* ---- H tables: cumulative quadrature in v, one u column per task ---- */

#include "tablefill.h"

/* Legendre channels use fixed Gauss-Legendre rules on each cell of the v
 * grid, prefix-summed along v: one exponential and one Legendre recurrence
 * per node. The variable is s = tan(pi/4 + t/2) for t <= 0 and w = 1/s for
 * t >= 0, where the integrand is
 *   exp(-u s) 2/(1+s^2) P_k((1-s^2)/(1+s^2)) ds,  exp(-u/w) 2/(1+w^2) P_k((w^2-1)/(w^2+1)) dw:
 * exp(-u s) is entire in s, the rest is rational with poles at s = +-i (distance
 * >= 1 from [0, 1]), and the only other singularity is exp(-u/w)'s at w = 0
 * (the boundary layer at v -> pi/2 for small u), which pieces of ratio <= 2
 * in w resolve. A cell's rule (pieces, nodes) follows from the analytic
 * structure (the rule per row, not adaptivity per texel): with a the
 * piece's exponent range a = u h_s plus its half-width over the distance to
 * the poles (times the order), the Gauss-Legendre error of e^{a x} on
 * [-1, 1], c_m a^{2m} e^a, must stay below the target. The error estimate of
 * a build also reruns some rows with a 1e4 times tighter target. */

#define HF_MMAX 8

typedef struct {
    nbt_gl_rule *gl[HF_MMAX + 1];
    double cm[HF_MMAX + 1];
} hrules;

static void hrules_free(hrules *R)
{
    for (int m = 0; m <= HF_MMAX; m++)
        nbt_gl_rule_free(R->gl[m]);
}

static int hrules_alloc(hrules *R)
{
    memset(R, 0, sizeof *R);
    for (int m = 2; m <= HF_MMAX; m++) {
        if (!(R->gl[m] = nbt_gl_rule_alloc((size_t)m))) {
            hrules_free(R);
            memset(R, 0, sizeof *R);
            return -1;
        }
        /* error of the m-point rule for e^{ax} on [-1, 1]: c_m a^{2m} e^{xi a} */
        R->cm[m] = exp((2.0 * m + 1.0) * log(2.0) + 4.0 * lgamma(m + 1.0) - log(2.0 * m + 1.0) -
                       3.0 * lgamma(2.0 * m + 1.0));
    }
    return 0;
}

/* am[m]: the largest a with c_m a^{2m} e^a <= target/2 */
static void hrules_limits(const hrules *R, double target, double *am)
{
    for (int m = 2; m <= HF_MMAX; m++) {
        double lo = 0.0, hi = 20.0;
        for (int it = 0; it < 60; it++) {
            double mid = 0.5 * (lo + hi);
            if (R->cm[m] * pow(mid, 2 * m) * exp(mid) <= 0.5 * target)
                lo = mid;
            else
                hi = mid;
        }
        am[m] = lo;
    }
}

static double ipow(double x, int n)
{
    double r = 1.0;
    while (n-- > 0)
        r *= x;
    return r;
}

/* Smallest pieces n (then nodes m) with the regular part (a per piece <=
 * am[m]) and a pole-like part of relative strength eps (as) both within
 * target/2. */
static void hrule_choose(const double *am, double a, double as, double eps, int *n, int *m)
{
    if (eps > 1.0)
        eps = 1.0;
    if (as <= a)
        eps = 0.0; /* then the pole-like part passes wherever the regular part does */
    double top = eps > 0 ? fmax(a, as) : a;
    int n0 = top > 0.5 ? (int)ceil(top / 0.5) : 1;
    for (int nn = n0;; nn++) {
        double an = a / nn, asn = as / nn;
        for (int mm = 2; mm <= HF_MMAX; mm++)
            if ((an <= am[mm] && (eps == 0 || eps * ipow(asn / am[mm], 2 * mm) <= 1.0)) ||
                (mm == HF_MMAX && nn >= 4 * n0 + 8)) {
                *n = nn;
                *m = mm;
                return;
            }
    }
}

/* One cell's part in s (wvar = 0) or w (wvar = 1), with its one-piece rules
 * for m = 2..HF_MMAX precomputed: per node y (= s, or 1/w, so that the
 * exponential is exp(-u y)) and the fdim weights g_q 2/(1+x^2) w_k(mu) h. */
typedef struct {
    double lo, hi;
    int wvar;
    double *tab;
    size_t off[HF_MMAX + 1];
} hpiece;

typedef struct {
    const hrules *R;
    const nbt__weights *w;
    unsigned fdim;
    double u, kfac, bound;
    const double *am;     /* hrules_limits of target */
    double target;
    double *f;            /* fdim scratch */
} hrow_ctx;

/* add int over [lo, hi] in s (wvar = 0) or w (wvar = 1) of
 * exp(-u (s - base)) 2/(1+x^2) w(mu) dx, n equal pieces of rule g; f: fdim
 * scratch. Shared by the H cells and J's G segments. */
static void gl_pieces(const nbt_gl_rule *g, const nbt__weights *w, unsigned fdim, double u, double base, int wvar,
                      double lo, double hi, int n, double *f, double *acc)
{
    double step = (hi - lo) / n;
    for (int p = 0; p < n; p++) {
        double a = lo + p * step, b = p + 1 == n ? hi : a + step;
        double mid = 0.5 * (a + b), hw = 0.5 * (b - a);
        for (size_t q = 0; q < g->n; q++) {
            double x = mid + hw * g->x[q], x2 = x * x, r = 1.0 / (1.0 + x2);
            double e = u > 0 ? exp(-u * ((wvar ? 1.0 / x : x) - base)) : 1.0;
            weights_at(w, wvar ? (x2 - 1.0) * r : (1.0 - x2) * r, 2.0 * x * r, f);
            double wt = hw * g->w[q] * 2.0 * r * e;
            for (unsigned k = 0; k < fdim; k++)
                acc[k] += wt * f[k];
        }
    }
}

/* add int over [lo, hi] in s (wvar = 0) or w (wvar = 1), n pieces of m nodes */
static void h_pieces(hrow_ctx *c, int wvar, double lo, double hi, int n, int m, double *acc)
{
    gl_pieces(c->R->gl[m], c->w, c->fdim, c->u, 0.0, wvar, lo, hi, n, c->f, acc);
    c->bound += 2.0 * (hi - lo) * c->target;
}

/* the precomputed one-piece rule of m nodes */
static void h_tab(hrow_ctx *c, const hpiece *P, int m, double *acc)
{
    const double *t = P->tab + P->off[m];
    unsigned fd = c->fdim;
    double u = c->u;
    for (int q = 0; q < m; q++, t += fd + 1) {
        double e = u > 0 ? exp(-u * t[0]) : 1.0;
        for (unsigned k = 0; k < fd; k++)
            acc[k] += e * t[1 + k];
    }
    c->bound += 2.0 * (P->hi - P->lo) * c->target;
}

/* add int_{lo}^{hi} dw, 0 < lo < hi <= 1, u > 0: pieces of ratio <= 2 */
static void h_wsplit(hrow_ctx *c, double lo, double hi, double *acc)
{
    double u = c->u;
    while (hi > 2.0 * lo) {
        h_wsplit(c, 0.5 * hi, hi, acc);
        hi *= 0.5;
    }
    int n, m;
    hrule_choose(c->am, 0.5 * u * (1.0 / lo - 1.0 / hi) + (hi - lo) * c->kfac, 1.5 * (hi - lo) / lo, u / lo, &n, &m);
    h_pieces(c, 1, lo, hi, n, m, acc);
}

static void h_piece(hrow_ctx *c, const hpiece *P, double *acc)
{
    double u = c->u, lo = P->lo, hi = P->hi;
    int n, m;
    if (!P->wvar) {
        if (u > 0 && u * lo > Y_TAIL)
            return; /* below e^-80 of the integrand at v = -pi/2 */
        if (u > 0 && u * hi > Y_TAIL)
            hi = Y_TAIL / u;
        hrule_choose(c->am, (hi - lo) * (0.5 * u + c->kfac), 0.0, 0.0, &n, &m);
        if (n == 1 && hi == P->hi)
            h_tab(c, P, m, acc);
        else
            h_pieces(c, 0, lo, hi, n, m, acc);
        return;
    }
    if (u > 0) {
        lo = fmax(lo, u / Y_TAIL);
        if (!(hi > lo))
            return;
        if (lo != P->lo || hi > 2.0 * lo) {
            h_wsplit(c, lo, hi, acc);
            return;
        }
        hrule_choose(c->am, 0.5 * u * (1.0 / lo - 1.0 / hi) + (hi - lo) * c->kfac, 1.5 * (hi - lo) / lo, u / lo, &n, &m);
    } else
        hrule_choose(c->am, (hi - lo) * c->kfac, 0.0, 0.0, &n, &m);
    if (n == 1)
        h_tab(c, P, m, acc);
    else
        h_pieces(c, 1, lo, hi, n, m, acc);
}

/* H at u for every node: cell j's pieces are P[pj[j]] .. P[pj[j+1]-1];
 * out[j*stride + k] */
static void h_row_fixed(hrow_ctx *c, const hpiece *P, const size_t *pj, size_t ny, double *acc, double *out,
                        size_t stride)
{
    for (unsigned k = 0; k < c->fdim; k++)
        acc[k] = 0.0;
    for (size_t j = 0; j < ny; j++) {
        for (size_t p = pj[j]; p < pj[j + 1]; p++)
            h_piece(c, &P[p], acc);
        for (unsigned k = 0; k < c->fdim; k++)
            out[j * stride + k] = acc[k];
    }
}

/* Split the cells [-pi/2, ys[0]], [ys[0], ys[1]], ... at t = 0 into pieces
 * in s and w and precompute their rules; *P and *pj malloc'd. */
static int h_pieces_make(const hrules *R, const nbt__weights *w, const double *ys, size_t ny, hpiece **Pout,
                         size_t **pjout)
{
    unsigned fd = nbt__fdim(w);
    hpiece *P = calloc(2 * ny, sizeof *P);
    size_t *pj = malloc((ny + 1) * sizeof *pj), np = 0, per = 0;
    double *f = malloc(fd * sizeof(double));
    for (int m = 2; m <= HF_MMAX; m++)
        per += (size_t)m * (fd + 1);
    int bad = !P || !pj || !f;
    double prev = -NBT_PI_2;
    for (size_t j = 0; j < ny && !bad; j++) {
        double ta = prev, tb = ys[j];
        pj[j] = np;
        if (ta < 0.0 && tb > ta)
            P[np++] = (hpiece){nbt__s_of_t(ta), tb >= 0.0 ? 1.0 : nbt__s_of_t(tb), 0, NULL, {0}};
        if (tb > 0.0 && tb > ta)
            P[np++] = (hpiece){w_of_t(tb), ta <= 0.0 ? 1.0 : w_of_t(ta), 1, NULL, {0}};
        prev = tb > prev ? tb : prev;
    }
    if (!bad)
        pj[ny] = np;
    for (size_t p = 0; p < np && !bad; p++) {
        hpiece *Q = &P[p];
        if (!(Q->tab = malloc(per * sizeof(double)))) {
            bad = 1;
            break;
        }
        double mid = 0.5 * (Q->lo + Q->hi), hw = 0.5 * (Q->hi - Q->lo), *t = Q->tab;
        for (int m = 2; m <= HF_MMAX; m++) {
            Q->off[m] = (size_t)(t - Q->tab);
            const nbt_gl_rule *g = R->gl[m];
            for (int q = 0; q < m; q++, t += fd + 1) {
                double x = mid + hw * g->x[q], x2 = x * x, r = 1.0 / (1.0 + x2);
                weights_at(w, Q->wvar ? (x2 - 1.0) * r : (1.0 - x2) * r, 2.0 * x * r, f);
                t[0] = Q->wvar ? 1.0 / x : x;
                for (unsigned k = 0; k < fd; k++)
                    t[1 + k] = hw * g->w[q] * 2.0 * r * f[k];
            }
        }
    }
    free(f);
    if (bad) {
        for (size_t p = 0; P && p < np; p++)
            free(P[p].tab);
        free(P);
        free(pj);
        return -1;
    }
    *Pout = P;
    *pjout = pj;
    return 0;
}

/* ---- one shifted segment by fixed rules (J's G rows) ----
 * As the H cells, over a wide interval: pieces in s and w, ratio <= 2 in w
 * towards w = 0; the exponential sets a = u h as for H, and the rational
 * part (a pole of order K + 1 at +-i, distance >= 1) the Gauss-Legendre
 * error pi (h/2)^{2m} (2m)^{K+1}, which for wide pieces asks for more
 * nodes, not more pieces. */

#define SF_MMAX 20

struct nbt__segfix {
    nbt_gl_rule *gl[SF_MMAX + 1];
    double am[SF_MMAX + 1];
    double target, logt;
};

void nbt__segfix_free(nbt__segfix *F)
{
    if (!F)
        return;
    for (int m = 0; m <= SF_MMAX; m++)
        nbt_gl_rule_free(F->gl[m]);
    free(F);
}

nbt__segfix *nbt__segfix_alloc(double tol)
{
    nbt__segfix *F = calloc(1, sizeof *F);
    if (!F)
        return NULL;
    F->target = fmax(0.1 * tol, 1e-15);
    F->logt = log(0.5 * F->target / NBT_PI);
    for (int m = 2; m <= SF_MMAX; m++) {
        if (!(F->gl[m] = nbt_gl_rule_alloc((size_t)m))) {
            nbt__segfix_free(F);
            return NULL;
        }
        double cm = exp((2.0 * m + 1.0) * log(2.0) + 4.0 * lgamma(m + 1.0) - log(2.0 * m + 1.0) -
                        3.0 * lgamma(2.0 * m + 1.0));
        double lo = 0.0, hi = 40.0;
        for (int it = 0; it < 60; it++) {
            double mid = 0.5 * (lo + hi);
            if (cm * pow(mid, 2 * m) * exp(mid) <= 0.25 * F->target)
                lo = mid;
            else
                hi = mid;
        }
        F->am[m] = lo;
    }
    return F;
}

typedef struct {
    const nbt__segfix *F;
    const nbt__weights *w;
    unsigned fdim;
    double u, base, len;
    double *f;
} sf_ctx;

/* n pieces, m nodes: the exponential's range a, half-width hw, the pole-like
 * part at w = 0 (as, strength eps) */
static void sf_choose(const sf_ctx *c, double a, double hw, double as, double eps, int *n, int *m)
{
    double K1 = (double)c->w->kmax + 1.0;
    if (eps > 1.0)
        eps = 1.0;
    if (as <= a)
        eps = 0.0;
    double top = eps > 0 ? fmax(a, as) : a;
    int n0 = top > 2.0 ? (int)ceil(top / 2.0) : 1;
    if (hw > 0.25 && (int)ceil(hw / 0.25) > n0)
        n0 = (int)ceil(hw / 0.25);
    for (int nn = n0;; nn++) {
        double an = a / nn, asn = as / nn, lh = log(0.5 * hw / nn);
        for (int mm = 2; mm <= SF_MMAX; mm++)
            if ((an <= c->F->am[mm] && (eps == 0 || eps * ipow(asn / c->F->am[mm], 2 * mm) <= 1.0) &&
                 2.0 * mm * lh + K1 * log(2.0 * mm) <= c->F->logt) ||
                (mm == SF_MMAX && nn >= 4 * n0 + 8)) {
                *n = nn;
                *m = mm;
                return;
            }
    }
}

static void sf_pieces(sf_ctx *c, int wvar, double lo, double hi, int n, int m, double *acc)
{
    gl_pieces(c->F->gl[m], c->w, c->fdim, c->u, c->base, wvar, lo, hi, n, c->f, acc);
    c->len += hi - lo;
}

static void sf_wsplit(sf_ctx *c, double lo, double hi, double *acc)
{
    double u = c->u;
    while (hi > 2.0 * lo) {
        sf_wsplit(c, 0.5 * hi, hi, acc);
        hi *= 0.5;
    }
    int n, m;
    sf_choose(c, 0.5 * u * (1.0 / lo - 1.0 / hi), 0.5 * (hi - lo), 1.5 * (hi - lo) / lo, u / lo, &n, &m);
    sf_pieces(c, 1, lo, hi, n, m, acc);
}

void nbt__segfix_eval(const nbt__segfix *F, const nbt__weights *w, double u, double v1, double v2, int shifted,
                      double *out, double *scratch, double *err)
{
    unsigned fdim = nbt__fdim(w);
    sf_ctx c = {F, w, fdim, u, shifted ? nbt__s_of_t(v1) : 0.0, 0.0, scratch};
    for (unsigned k = 0; k < fdim; k++)
        out[k] = 0.0;
    int n, m;
    if (v1 < 0.0 && v2 > v1) {
        double lo = nbt__s_of_t(v1), hi = v2 >= 0.0 ? 1.0 : nbt__s_of_t(v2);
        if (u > 0 && u * (hi - c.base) > Y_TAIL)
            hi = c.base + Y_TAIL / u;
        if (hi > lo && !(u > 0 && u * (lo - c.base) > Y_TAIL)) {
            sf_choose(&c, 0.5 * u * (hi - lo), 0.5 * (hi - lo), 0.0, 0.0, &n, &m);
            sf_pieces(&c, 0, lo, hi, n, m, out);
        }
    }
    if (v2 > 0.0 && v2 > v1) {
        double lo = w_of_t(v2), hi = v1 <= 0.0 ? 1.0 : w_of_t(v1);
        if (u > 0) {
            lo = fmax(lo, 1.0 / (c.base + Y_TAIL / u));
            if (hi > lo)
                sf_wsplit(&c, lo, hi, out);
        } else if (hi > lo) {
            sf_choose(&c, 0.0, 0.5 * (hi - lo), 0.0, 0.0, &n, &m);
            sf_pieces(&c, 1, lo, hi, n, m, out);
        }
    }
    *err = 2.0 * c.len * F->target;
}

/* ---- H tables: cumulative quadrature in v, one u row per task ---- */

#include "tablefill.h"

typedef struct {
    size_t nch;
    const int *kmap;      /* Legendre order (or -1: fixed phase) per channel */
    nbt__weights w;
    double tol;
    const double *xs, *ys;
    size_t nx, ny;
    double *F;
    double *colerr;       /* per column: largest accumulated error over channels */
    nbt_quad_ws **ws;     /* one per thread */
    double **buf;         /* one per thread: 4 fdim doubles */
    unsigned nt;
    hrules R;             /* fixed rules (Legendre channels) */
    double **rowbuf;      /* one per thread: ny * fdim doubles */
    hpiece *P;            /* the cells' pieces and their rules */
    size_t *pj;
    double am[HF_MMAX + 1], amfine[HF_MMAX + 1], target;
} hfill_ctx;

/* rows rerun with a tighter rule to check the a-priori bound */
static int h_check_row(size_t i, size_t nx)
{
    return i < 3 || i + 1 == nx || i % 16 == 0;
}

static nbt_status h_column_fixed(size_t i, unsigned thread, void *vp)
{
    hfill_ctx *c = vp;
    unsigned fdim = nbt__fdim(&c->w);
    double *acc = c->buf[thread], *f = acc + fdim;
    hrow_ctx r = {&c->R, &c->w, fdim, c->xs[i], 1.5 * ((double)c->w.kmax + 2.0), 0.0, c->am, c->target, f};
    double *row = c->rowbuf[thread];
    h_row_fixed(&r, c->P, c->pj, c->ny, acc, row, fdim);
    size_t nc = c->nch;
    for (size_t j = 0; j < c->ny; j++)
        for (size_t ch = 0; ch < nc; ch++)
            c->F[(i * c->ny + j) * nc + ch] = row[j * fdim + (size_t)c->kmap[ch]];
    double e = r.bound;
    if (h_check_row(i, c->nx)) {
        hrow_ctx fine = r;
        fine.am = c->amfine;
        fine.target = 1e-4 * c->target;
        h_row_fixed(&fine, c->P, c->pj, c->ny, acc, row, fdim);
        double d = 0;
        for (size_t j = 0; j < c->ny; j++)
            for (size_t ch = 0; ch < nc; ch++)
                d = fmax(d, fabs(row[j * fdim + (size_t)c->kmap[ch]] - c->F[(i * c->ny + j) * nc + ch]));
        e = fmax(e, 2.0 * d);
    }
    c->colerr[i] = e;
    return NBT_OK;
}

static nbt_status h_column(size_t i, unsigned thread, void *vp)
{
    hfill_ctx *c = vp;
    unsigned fdim = nbt__fdim(&c->w);
    double *acc = c->buf[thread], *aerr = acc + fdim, *seg = aerr + fdim, *serr = seg + fdim;
    for (unsigned k = 0; k < fdim; k++)
        acc[k] = aerr[k] = 0.0;
    double u = c->xs[i], prev = -NBT_PI_2;
    size_t nc = c->nch;
    for (size_t j = 0; j < c->ny; j++) {
        nbt_status st = nbt__airlight_segment(c->ws[thread], &c->w, u, prev, c->ys[j], 0, c->tol, seg, serr);
        if (st != NBT_OK)
            return st;
        for (unsigned k = 0; k < fdim; k++) {
            acc[k] += seg[k];
            aerr[k] += serr[k];
        }
        prev = c->ys[j];
        for (size_t ch = 0; ch < nc; ch++) {
            size_t k = c->w.phase ? 0 : (size_t)c->kmap[ch];
            c->F[(i * c->ny + j) * nc + ch] = acc[k];
        }
    }
    double e = 0;
    for (size_t ch = 0; ch < nc; ch++)
        e = fmax(e, aerr[c->w.phase ? 0 : (size_t)c->kmap[ch]]);
    c->colerr[i] = e;
    return NBT_OK;
}

static nbt_status h_fill(void *vp, const double *xs, size_t nx, const double *ys, size_t ny,
                         double *F, double *quad_err)
{
    hfill_ctx *c = vp;
    c->xs = xs;
    c->ys = ys;
    c->nx = nx;
    c->ny = ny;
    c->F = F;
    c->colerr = calloc(nx, sizeof(double));
    if (!c->colerr)
        NBT_FAIL(NBT_ENOMEM, "H table: out of memory");
    c->rowbuf = NULL;
    nbt_status st = NBT_OK;
    if (!c->w.phase) {
        double *rb[64] = {0};
        for (unsigned t = 0; t < c->nt; t++)
            if (!(rb[t] = malloc(ny * nbt__fdim(&c->w) * sizeof(double))))
                st = NBT_ENOMEM;
        c->rowbuf = rb;
        c->target = fmax(0.1 * c->tol, 1e-15);
        hrules_limits(&c->R, c->target, c->am);
        hrules_limits(&c->R, 1e-4 * c->target, c->amfine);
        if (st == NBT_OK && h_pieces_make(&c->R, &c->w, ys, ny, &c->P, &c->pj))
            st = NBT_ENOMEM;
        if (st == NBT_OK) {
            st = nbt__parallel_for(nx, c->nt, h_column_fixed, c);
            for (size_t p = 0; p < c->pj[ny]; p++)
                free(c->P[p].tab);
            free(c->P);
            free(c->pj);
        }
        for (unsigned t = 0; t < c->nt; t++)
            free(rb[t]);
        c->rowbuf = NULL;
    } else
        st = nbt__parallel_for(nx, c->nt, h_column, c);
    *quad_err = 0;
    for (size_t i = 0; i < nx; i++)
        *quad_err = fmax(*quad_err, c->colerr[i]);
    free(c->colerr);
    return st;
}

nbt_status nbt_h_table_build_set(nbt_table *const *ts, size_t nt, const nbt_phase *fixed, const nbt_build_opts *o)
{
    int *kmap;
    hfill_ctx c = {.tol = o->quad_tol};
    c.w.phase = fixed;
    nbt_status st = nbt__table_set_prepare(ts, nt, fixed, &kmap, &c.nch, &c.w.kmax);
    if (st != NBT_OK)
        return st;
    c.kmap = kmap;
    nbt_table *t = ts[0];
    if (t->kind != NBT_TABLE_H)
        st = nbt__fail(NBT_EINVAL, "H table: the table is not of kind H");
    else if (t->axis[0].lo < 0 || t->axis[1].lo < -NBT_PI_2 || t->axis[1].hi > NBT_PI_2)
        st = nbt__fail(NBT_EDOM, "H table: axes must lie in u >= 0, v in [-pi/2, pi/2]");
    else if (!(o->quad_tol > 0 && o->quad_tol < 1))
        st = nbt__fail(NBT_EDOM, "H table: quad_tol must lie in (0, 1)");
    if (st != NBT_OK) {
        free(kmap);
        return st;
    }
    for (size_t i = 0; i < nt; i++) {
        ts[i]->n = 0;
        ts[i]->quad_tol = o->quad_tol;
    }
    unsigned nthr = nbt__nthreads(o->nthreads, 2 * t->axis[0].n);
    nbt_quad_ws *ws[64] = {0};
    double *buf[64] = {0};
    for (unsigned i = 0; i < nthr; i++) {
        ws[i] = nbt_quad_ws_alloc(nbt__fdim(&c.w), SEG_MAX_INTERVALS);
        buf[i] = malloc(4 * nbt__fdim(&c.w) * sizeof(double));
        if (!ws[i] || !buf[i])
            st = NBT_ENOMEM;
    }
    c.ws = ws;
    c.buf = buf;
    c.nt = nthr;
    if (st == NBT_OK && hrules_alloc(&c.R))
        st = NBT_ENOMEM;
    if (st == NBT_OK)
        st = nbt__table_fill(ts, nt, o->measure_error ? NBT__MEASURE_SPARSE : 0, h_fill, &c);
    hrules_free(&c.R);
    for (unsigned i = 0; i < nthr; i++) {
        nbt_quad_ws_free(ws[i]);
        free(buf[i]);
    }
    free(kmap);
    if (st == NBT_ENOMEM)
        NBT_FAIL(st, "H table: out of memory");
    return st;
}

nbt_status nbt_h_table_build(nbt_table *t, const nbt_phase *fixed, const nbt_build_opts *o)
{
    return nbt_h_table_build_set(&t, 1, fixed, o);
}
