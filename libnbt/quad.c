/* libnbt/quad.c: Gauss-Legendre rules and adaptive vector Gauss-Kronrod. */
#include <config.h>
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <nbt/quad.h>
#include "internal.h"
#ifdef __SSE2__
#include <emmintrin.h>
#endif

nbt_gl_rule *nbt_gl_rule_alloc(size_t n)
{
    if (n == 0)
        return NULL;
    nbt_gl_rule *r = malloc(sizeof *r);
    if (!r)
        return NULL;
    r->n = n;
    r->x = malloc(n * sizeof(double));
    r->w = malloc(n * sizeof(double));
    if (!r->x || !r->w) {
        nbt_gl_rule_free(r);
        return NULL;
    }
    /* Newton on P_n from Tricomi's initial guess; nodes ascending. */
    for (size_t i = 0; i < (n + 1) / 2; i++) {
        double x = cos(NBT_PI * ((double)i + 0.75) / ((double)n + 0.5));
        double dp = 1.0;
        for (int it = 0; it < 100; it++) {
            double p0 = 1.0, p1 = x;
            for (size_t k = 1; k < n; k++) {
                double p2 = ((2.0 * (double)k + 1.0) * x * p1 - (double)k * p0) / ((double)k + 1.0);
                p0 = p1;
                p1 = p2;
            }
            if (n == 1) {
                p1 = x;
                p0 = 1.0;
            }
            dp = (double)n * (x * p1 - p0) / (x * x - 1.0);
            double dx = p1 / dp;
            x -= dx;
            if (fabs(dx) <= 1e-16 * fabs(x) + 1e-300)
                break;
        }
        if (n == 1) {
            x = 0.0;
            dp = 1.0;
        }
        double w = 2.0 / ((1.0 - x * x) * dp * dp);
        r->x[i] = -x;
        r->w[i] = w;
        r->x[n - 1 - i] = x;
        r->w[n - 1 - i] = w;
    }
    if (n % 2 == 1)
        r->x[n / 2] = 0.0;
    return r;
}

void nbt_gl_rule_free(nbt_gl_rule *r)
{
    if (!r)
        return;
    free(r->x);
    free(r->w);
    free(r);
}

/* Kronrod 15 / Gauss 7 abscissae and weights (standard values). */
static const double xgk[8] = {
    0.991455371120812639206854697526329, 0.949107912342758524526189684047851,
    0.864864423359769072789712788640926, 0.741531185599394439863864773280788,
    0.586087235467691130294144845693013, 0.405845151377397166906606412076961,
    0.207784955007898467600689403773245, 0.000000000000000000000000000000000};
static const double wgk[8] = {
    0.022935322010529224963732008058970, 0.063092092629978553290700663189204,
    0.104790010322250183839876322541518, 0.140653259715525918745189590510238,
    0.169004726639267902826583426598550, 0.190350578064785409913256402421014,
    0.204432940075298892414161999234649, 0.209482141084727828012999174891714};
static const double wg[4] = {
    0.129484966168869693270611432679082, 0.279705391489276667901467771423780,
    0.381830050505118944950369775488975, 0.417959183673469387755102040816327};

struct nbt_quad_ws {
    unsigned fdim;
    size_t max;
    size_t n;
    double *a, *b;     /* interval ends */
    double *r, *e, *l; /* per interval x fdim: integral, error, integral of |f| */
    double *fv;        /* 15 x fdim integrand values */
    double *acc;       /* 4 x fdim: sums per component */
};

nbt_quad_ws *nbt_quad_ws_alloc(unsigned fdim, size_t max_intervals)
{
    if (fdim == 0 || max_intervals < 2)
        return NULL;
    nbt_quad_ws *w = calloc(1, sizeof *w);
    if (!w)
        return NULL;
    w->fdim = fdim;
    w->max = max_intervals;
    w->a = malloc(max_intervals * sizeof(double));
    w->b = malloc(max_intervals * sizeof(double));
    w->r = malloc(max_intervals * fdim * sizeof(double));
    w->e = malloc(max_intervals * fdim * sizeof(double));
    w->l = malloc(max_intervals * fdim * sizeof(double));
    w->fv = malloc(15 * (size_t)fdim * sizeof(double));
    w->acc = malloc(4 * (size_t)fdim * sizeof(double));
    if (!w->a || !w->b || !w->r || !w->e || !w->l || !w->fv || !w->acc) {
        nbt_quad_ws_free(w);
        return NULL;
    }
    return w;
}

void nbt_quad_ws_free(nbt_quad_ws *w)
{
    if (!w)
        return;
    free(w->a);
    free(w->b);
    free(w->r);
    free(w->e);
    free(w->l);
    free(w->fv);
    free(w->acc);
    free(w);
}

/* The vector integrands' sums over their components (g-sliced J: 33 HG
 * slices): two components at a time where SSE2 is there. Each component
 * sees the same operations in the same order as a scalar loop (no fused
 * multiply-add), so the results are the same to the bit. */

/* K += w (fa + fb), L += w (|fa| + |fb|) */
static void kl_add(double *K, double *L, double w, const double *fa, const double *fb, unsigned n)
{
    unsigned d = 0;
#ifdef __SSE2__
    __m128d w2 = _mm_set1_pd(w), sgn = _mm_set1_pd(-0.0);
    for (; d + 2 <= n; d += 2) {
        __m128d a = _mm_loadu_pd(fa + d), b = _mm_loadu_pd(fb + d);
        _mm_storeu_pd(K + d, _mm_add_pd(_mm_loadu_pd(K + d), _mm_mul_pd(w2, _mm_add_pd(a, b))));
        __m128d s = _mm_add_pd(_mm_andnot_pd(sgn, a), _mm_andnot_pd(sgn, b));
        _mm_storeu_pd(L + d, _mm_add_pd(_mm_loadu_pd(L + d), _mm_mul_pd(w2, s)));
    }
#endif
    for (; d < n; d++) {
        K[d] += w * (fa[d] + fb[d]);
        L[d] += w * (fabs(fa[d]) + fabs(fb[d]));
    }
}

/* G += w (fa + fb) */
static void g_add(double *G, double w, const double *fa, const double *fb, unsigned n)
{
    unsigned d = 0;
#ifdef __SSE2__
    __m128d w2 = _mm_set1_pd(w);
    for (; d + 2 <= n; d += 2) {
        __m128d a = _mm_loadu_pd(fa + d), b = _mm_loadu_pd(fb + d);
        _mm_storeu_pd(G + d, _mm_add_pd(_mm_loadu_pd(G + d), _mm_mul_pd(w2, _mm_add_pd(a, b))));
    }
#endif
    for (; d < n; d++)
        G[d] += w * (fa[d] + fb[d]);
}

/* whether all of f[0..n-1] are finite */
static int all_finite(const double *f, unsigned n)
{
    unsigned d = 0;
    int ok = 1;
#ifdef __SSE2__
    /* x * 0 is NaN exactly for infinite and NaN x */
    __m128d z = _mm_setzero_pd(), acc = _mm_setzero_pd();
    for (; d + 2 <= n; d += 2)
        acc = _mm_add_pd(acc, _mm_mul_pd(_mm_loadu_pd(f + d), z));
    ok = _mm_movemask_pd(_mm_cmpunord_pd(acc, acc)) == 0;
#endif
    for (; d < n; d++)
        ok &= isfinite(f[d]) != 0;
    return ok;
}

/* Apply G7K15 on interval j = [a, b]; store into slot j. */
static int gk15(nbt_quad_ws *w, nbt_integrand f, void *params, unsigned fdim,
                double a, double b, size_t j)
{
    double c = 0.5 * (a + b), h = 0.5 * (b - a);
    double *fv = w->fv;
    for (int i = 0; i < 15; i++) {
        /* node order: i < 7 left of centre, 7 centre, > 7 right */
        double x = i < 7 ? c - h * xgk[i] : (i == 7 ? c : c + h * xgk[14 - i]);
        if (f(x, params, fdim, fv + (size_t)i * fdim) || !all_finite(fv + (size_t)i * fdim, fdim))
            return 1;
    }
    double ah = fabs(h);
    /* the sums of every component at once (the inner loops run over the
     * components, contiguous); each component's additions in the same
     * order as one at a time, so the same values to the bit */
    double *K = w->acc, *G = K + fdim, *L = G + fdim;
    const double *f7 = fv + 7 * (size_t)fdim;
    for (unsigned d = 0; d < fdim; d++) {
        K[d] = wgk[7] * f7[d];
        G[d] = wg[3] * f7[d];
        L[d] = wgk[7] * fabs(f7[d]);
    }
    for (int i = 0; i < 7; i++) {
        const double *fa = fv + (size_t)i * fdim, *fb = fv + (size_t)(14 - i) * fdim;
        kl_add(K, L, wgk[i], fa, fb, fdim);
        if (i % 2 == 1)
            g_add(G, wg[i / 2], fa, fb, fdim);
    }
    double *r = w->r + j * fdim, *l = w->l + j * fdim, *e = w->e + j * fdim;
    unsigned d0 = 0;
#ifdef __SSE2__
    __m128d h2 = _mm_set1_pd(h), ah2 = _mm_set1_pd(ah), fl2 = _mm_set1_pd(50.0 * DBL_EPSILON);
    __m128d sgn = _mm_set1_pd(-0.0);
    for (; d0 + 2 <= fdim; d0 += 2) {
        __m128d k = _mm_loadu_pd(K + d0), g = _mm_loadu_pd(G + d0), ll = _mm_loadu_pd(L + d0);
        _mm_storeu_pd(r + d0, _mm_mul_pd(k, h2));
        _mm_storeu_pd(l + d0, _mm_mul_pd(ll, ah2));
        __m128d ed = _mm_andnot_pd(sgn, _mm_mul_pd(_mm_sub_pd(k, g), h2));
        __m128d fl = _mm_mul_pd(_mm_mul_pd(fl2, ll), ah2);
        _mm_storeu_pd(e + d0, _mm_max_pd(ed, fl)); /* ed > fl ? ed : fl */
    }
#endif
    for (unsigned d = d0; d < fdim; d++) {
        r[d] = K[d] * h;
        l[d] = L[d] * ah;
        /* |K - G|, floored at the rounding level of the sum */
        double ed = fabs((K[d] - G[d]) * h);
        double floor_ = 50.0 * DBL_EPSILON * L[d] * ah;
        e[d] = ed > floor_ ? ed : floor_;
    }
    return 0;
}

nbt_status nbt_quad_gk_pts(nbt_quad_ws *w, nbt_integrand f, void *params, unsigned fdim,
                           double a, double b, const double *pts, size_t npts,
                           double epsabs, double epsrel, double *result, double *abserr)
{
    if (!w || fdim > w->fdim)
        NBT_FAIL(NBT_EINVAL, "nbt_quad_gk: fdim exceeds the workspace");
    if (!isfinite(a) || !isfinite(b))
        NBT_FAIL(NBT_EDOM, "nbt_quad_gk: integration limits must be finite");
    if (npts + 1 > w->max)
        NBT_FAIL(NBT_EINVAL, "nbt_quad_gk: more breakpoints than intervals");
    for (unsigned d = 0; d < fdim; d++)
        result[d] = abserr[d] = 0.0;
    if (a == b)
        return NBT_OK;
    double sign = 1.0;
    if (a > b) {
        double t = a;
        a = b;
        b = t;
        sign = -1.0;
    }
    w->n = 0;
    double lo = a;
    for (size_t i = 0; i <= npts; i++) {
        double hi = i < npts ? pts[i] : b;
        if (hi <= lo || hi > b)
            continue;
        w->a[w->n] = lo;
        w->b[w->n] = hi;
        if (gk15(w, f, params, fdim, lo, hi, w->n))
            NBT_FAIL(NBT_EDOM, "nbt_quad_gk: integrand failed or returned a non-finite value");
        w->n++;
        lo = hi;
    }
    nbt_status st = NBT_OK;
    for (;;) {
        /* totals and the worst interval, errors scaled by each tolerance */
        int done = 1;
        /* per component, the intervals summed in order (loops over the
         * components inside, as in gk15) */
        double *R = w->acc, *E = R + fdim, *L = E + fdim;
        for (unsigned d = 0; d < fdim; d++)
            R[d] = E[d] = L[d] = 0;
        for (size_t j = 0; j < w->n; j++) {
            const double *rj = w->r + j * fdim, *ej = w->e + j * fdim, *lj = w->l + j * fdim;
            unsigned d = 0;
#ifdef __SSE2__
            for (; d + 2 <= fdim; d += 2) {
                _mm_storeu_pd(R + d, _mm_add_pd(_mm_loadu_pd(R + d), _mm_loadu_pd(rj + d)));
                _mm_storeu_pd(E + d, _mm_add_pd(_mm_loadu_pd(E + d), _mm_loadu_pd(ej + d)));
                _mm_storeu_pd(L + d, _mm_add_pd(_mm_loadu_pd(L + d), _mm_loadu_pd(lj + d)));
            }
#endif
            for (; d < fdim; d++) {
                R[d] += rj[d];
                E[d] += ej[d];
                L[d] += lj[d];
            }
        }
        for (unsigned d = 0; d < fdim; d++) {
            result[d] = sign * R[d];
            abserr[d] = E[d];
            double tol = fmax(epsabs, epsrel * L[d]);
            w->fv[d] = tol > 0 ? tol : DBL_MIN; /* scratch: scale of component d */
            if (E[d] > tol)
                done = 0;
        }
        if (done)
            break;
        if (w->n + 1 > w->max) {
            st = NBT_ETOL;
            break;
        }
        size_t worst = 0;
        double wv = -1.0;
        for (size_t j = 0; j < w->n; j++) {
            /* errors and scales are finite and >= 0: a comparison, not fmax */
            double v = 0;
            const double *ej = w->e + j * fdim;
            unsigned d = 0;
#ifdef __SSE2__
            __m128d v2 = _mm_setzero_pd();
            for (; d + 2 <= fdim; d += 2)
                v2 = _mm_max_pd(_mm_div_pd(_mm_loadu_pd(ej + d), _mm_loadu_pd(w->fv + d)), v2);
            double vl[2];
            _mm_storeu_pd(vl, v2);
            v = vl[0] > vl[1] ? vl[0] : vl[1];
#endif
            for (; d < fdim; d++) {
                double x = ej[d] / w->fv[d];
                v = x > v ? x : v;
            }
            if (v > wv) {
                wv = v;
                worst = j;
            }
        }
        double ja = w->a[worst], jb = w->b[worst], m = 0.5 * (ja + jb);
        if (!(m > ja && m < jb)) { /* interval at machine resolution */
            st = NBT_ETOL;
            break;
        }
        size_t nj = w->n++;
        w->a[nj] = m;
        w->b[nj] = jb;
        w->b[worst] = m;
        if (gk15(w, f, params, fdim, ja, m, worst) || gk15(w, f, params, fdim, m, jb, nj))
            NBT_FAIL(NBT_EDOM, "nbt_quad_gk: integrand failed or returned a non-finite value");
    }
    return st;
}

nbt_status nbt_quad_gk(nbt_quad_ws *w, nbt_integrand f, void *params, unsigned fdim,
                       double a, double b, double epsabs, double epsrel,
                       double *result, double *abserr)
{
    return nbt_quad_gk_pts(w, f, params, fdim, a, b, NULL, 0, epsabs, epsrel, result, abserr);
}
