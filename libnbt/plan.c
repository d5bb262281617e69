/* libnbt/plan.c: the table planner (nbt/plan.h): Legendre budget, axis
 * mappings from a small proxy, size from the proxies' convergence rate,
 * and execution that grows a set until it meets its target. */
#include <config.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <nbt/airlight.h>
#include <nbt/plan.h>
#include <nbt/surface.h>
#include "internal.h"

struct nbt_plan {
    nbt_plan_set *sets;
    size_t count;
    nbt_table **cache;    /* per set: the npacks tables built at 33^2 and 65^2 while planning (reused by execute) */
    nbt_plan_legendre leg;
    unsigned nthreads;
    nbt__jcache *gc;      /* G rows shared by the plan's J builds (proxies and sets) */
};

/* Memory for shared G rows: a 49^2 J build of 4 orders holds ~3 MB of them,
 * the default scene's builds ~10 MB; past the cap rows are recomputed. */
#define JCACHE_BYTES ((size_t)64 << 20)

double nbt__now_s(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

double nbt__cpu_s(void)
{
    struct timespec t;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

#define failf nbt__failf
nbt_status nbt__failf(char *err, size_t errlen, nbt_status st, const char *fmt, ...)
{
    if (err && errlen) {
        va_list ap;
        va_start(ap, fmt);
        vsnprintf(err, errlen, fmt, ap);
        va_end(ap);
    }
    return st;
}

/* ---- scenes ---- */

void nbt_scene_init(nbt_scene *s)
{
    memset(s, 0, sizeof *s);
    s->kappa_s[0] = s->kappa_s[1] = -1;
    s->airlight = s->diffuse = 1;
    s->tol = 1e-3;
    s->orders_max = NBT_PLAN_GL_ORDERS;
}

static int range_ok(const double r[2], double lo, double hi)
{
    return r[0] >= lo && r[1] >= r[0] && r[1] <= hi;
}

nbt_status nbt_scene_check(const nbt_scene *s, char *err, size_t errlen)
{
    if (!range_ok(s->kappa_t, 0, 1e3) || !(s->kappa_t[1] > 0))
        return failf(err, errlen, NBT_EDOM, "kappa_t = %g:%g is not accepted: 0 <= lo <= hi <= 1000, hi > 0 "
                     "(kappa_t and distance are required)", s->kappa_t[0], s->kappa_t[1]);
    if (!(s->distance[1] > 0) || !(s->distance[0] >= 0 && s->distance[0] <= s->distance[1]) || !(s->distance[1] <= 1e9))
        return failf(err, errlen, NBT_EDOM, "distance = %g:%g is not accepted: 0 <= lo <= hi <= 1e9, hi > 0 "
                     "(kappa_t and distance are required)", s->distance[0], s->distance[1]);
    if (!!s->have_g == !!s->phase)
        return failf(err, errlen, NBT_EINVAL, "give exactly one of g (a value or range: Legendre tables) and "
                     "phase (fixed phase)");
    if (s->basis < 0 || s->basis > 2)
        return failf(err, errlen, NBT_EINVAL, "basis = %d is not accepted: auto, legendre or slices", s->basis);
    if (s->basis != 0 && !s->have_g)
        return failf(err, errlen, NBT_EINVAL, "basis applies to a g range only (a fixed phase needs one table per kind)");
    if (s->basis == 2 && !(s->g[0] < s->g[1]))
        return failf(err, errlen, NBT_EINVAL, "basis = slices needs a g range lo < hi (g = %g is one value: phase = "
                     "hg:g=%g is exact for it)", s->g[0], s->g[0]);
    if (s->sub != 0 && s->sub != 1)
        return failf(err, errlen, NBT_EINVAL, "form: sub = %d is not accepted: 0 (plain) or 1 (sub)", s->sub);
    if (s->sub && s->have_g && s->g[0] < s->g[1] && s->basis != 1)
        return failf(err, errlen, NBT_EINVAL, "form = sub is for 2-D tables: with a g range it needs basis = legendre "
                     "(g slices have no form sub)");
    if (s->have_g && !range_ok(s->g, -0.99, 0.99))
        return failf(err, errlen, NBT_EDOM, "g = %g:%g is not accepted: -0.99 <= lo <= hi <= 0.99", s->g[0], s->g[1]);
    if (s->kappa_s[1] >= 0 && s->kappa_s[1] > s->kappa_t[1])
        return failf(err, errlen, NBT_EDOM, "kappa_s (%g) must not exceed kappa_t (%g)", s->kappa_s[1], s->kappa_t[1]);
    if (!s->airlight && !s->diffuse && s->nphong == 0)
        return failf(err, errlen, NBT_EINVAL, "the scene needs no tables (airlight = no, diffuse = no, no phong)");
    if (s->nphong > NBT_SCENE_MAX_PHONG)
        return failf(err, errlen, NBT_EDOM, "at most %d Phong exponents", NBT_SCENE_MAX_PHONG);
    for (size_t i = 0; i < s->nphong; i++)
        if (s->phong[i] < 2 || s->phong[i] > 10000)
            return failf(err, errlen, NBT_EDOM, "phong = %d is not accepted: 2 .. 10000", s->phong[i]);
    if (!(s->tol >= 1e-7 && s->tol <= 0.5))
        return failf(err, errlen, NBT_EDOM, "tol = %g is not accepted: 1e-7 .. 0.5", s->tol);
    if (s->orders_max < 1 || s->orders_max > 512)
        return failf(err, errlen, NBT_EDOM, "orders_max = %zu is not accepted: 1 .. 512", s->orders_max);
    double xmax = s->kappa_t[1] * s->distance[1];
    if (xmax > 1e6)
        return failf(err, errlen, NBT_EDOM, "kappa_t * distance = %g exceeds 1e6 (the medium is opaque long before)",
                     xmax);
    return NBT_OK;
}

/* ---- Legendre budget ---- */

/* Smallest N such that the airlight series truncated to N terms differs from
 * the converged one by at most tol relative, for HG with |g| <= gmax, over
 * sample rays (u up to umax, gamma from 0.05 to 2.5 rad, unobstructed).
 * Each ray's H_k differences are integrated directly (one shifted segment
 * from gamma - pi/2 to pi/2), never formed by subtracting H values: for
 * large u and backward rays the difference is ~e^-40 of the H values. */
static nbt_status choose_terms(double gmax, double umax, double tol, size_t *N, double *achieved)
{
    /* orders beyond K: (2k+1) g^k below 1e-3 tol, negligible for the tail */
    size_t K = 8;
    while (K < 512 && (2.0 * K + 1.0) * pow(gmax, (double)K) > 1e-3 * tol)
        K *= 2;
    static const double gam[] = {0.05, 0.2, 0.5, 1.0, 1.5, 2.5};
    double *d = malloc(2 * (K + 1) * sizeof(double));
    double *worst = calloc(K + 2, sizeof(double));
    nbt_quad_ws *ws = nbt_quad_ws_alloc((unsigned)(K + 1), 2000);
    nbt__weights w = {K, NULL, NULL, NULL, 0, NULL};
    nbt_status st = NBT_OK;
    int too_many = 0;
    if (!d || !worst || !ws)
        st = NBT_ENOMEM;
    for (int iu = 0; iu < 6 && st == NBT_OK; iu++) {
        double u = umax * pow(10.0, -iu * 0.6);
        for (size_t ig = 0; ig < sizeof gam / sizeof gam[0] && st == NBT_OK; ig++) {
            st = nbt__airlight_segment(ws, &w, u, gam[ig] - NBT_PI_2, NBT_PI_2, 1, 1e-10, d, d + K + 1);
            if (st != NBT_OK)
                break;
            /* both signs of g: a backward lobe looking towards the source
             * needs more terms than any forward one (gmax 0.8, u 30) */
            for (int sg = 1; sg >= -1; sg -= 2) {
                double g = sg * gmax, total = 0, tail = 0, gk = 1;
                for (size_t k = 0; k <= K; k++, gk *= g)
                    total += (2.0 * k + 1.0) * gk * d[k];
                /* tail after N terms, from the top down */
                gk = pow(g, (double)K);
                for (size_t k = K + 1; k-- > 0; gk = g != 0 ? gk / g : (k == 1 ? 1 : 0)) {
                    tail += (2.0 * k + 1.0) * gk * d[k];
                    worst[k] = fmax(worst[k], fabs(tail / total));
                }
            }
            /* one geometry already needs more than the 512 orders anyone takes:
             * the other 35 cannot lower that (6 s at gmax 0.99 before) */
            if (K == 512 && worst[512] > tol) {
                too_many = 1;
                iu = 6;
                break;
            }
        }
    }
    if (st == NBT_OK && too_many) {
        *N = 513; /* more than 512 */
        *achieved = worst[512];
    } else if (st == NBT_OK) {
        size_t n = 1;
        while (n <= K && worst[n] > tol)
            n++;
        *N = n;
        *achieved = n <= K ? worst[n] : worst[K];
    }
    nbt_quad_ws_free(ws);
    free(d);
    free(worst);
    return st;
}

nbt_status nbt_plan_legendre_terms(double gmax, double xmax, double tol, size_t nmax, nbt_plan_legendre *out)
{
    memset(out, 0, sizeof *out);
    if (!(gmax >= 0 && gmax <= 0.99) || !(xmax > 0 && xmax <= 1e6) || !(tol > 0 && tol < 1) || nmax < 1 || nmax > 512)
        NBT_FAIL(NBT_EDOM, "plan: Legendre budget needs 0 <= gmax <= 0.99, 0 < xmax <= 1e6, 0 < tol < 1, "
                           "1 <= nmax <= 512");
    nbt_status st = choose_terms(gmax, xmax, 0.5 * tol, &out->nterms, &out->trunc_err);
    if (st != NBT_OK)
        return st;
    if (out->nterms > 512)
        out->nterms = 513;
    /* Interpolation gets the other half of tol. In the series each order's
     * error is weighted by (2k+1)|g|^k, so each table must be that much
     * better than tol/2 (relative to H_0/J_0). */
    size_t n = out->nterms < 512 ? out->nterms : 512;
    for (size_t k = 0; k < n; k++)
        out->amp += (2.0 * k + 1.0) * pow(gmax, (double)k);
    out->table_tol = 0.5 * tol / out->amp;
    return out->nterms > nmax ? NBT_ETOL : NBT_OK;
}

/* ---- building one set ---- */

static size_t npacks_of(const nbt_plan_request *r)
{
    return r->phase ? 1 : (r->nterms + 3) / 4;
}

/* Packs [0, count) of r on the given axes, in one pass (every order
 * integrated once), error measured. */
static nbt_status build_packs(const nbt_plan_request *r, size_t count, const nbt_axis *a0, const nbt_axis *a1,
                              double qtol, unsigned nthreads, nbt__jcache *gc, nbt_table **out)
{
    for (size_t i = 0; i < count; i++) {
        size_t nch = 1;
        if (!r->phase) {
            nch = r->nterms - 4 * i;
            if (nch > 4)
                nch = 4;
        }
        nbt_table *t = out[i] = nbt_table_alloc(r->kind, a0, a1, nch);
        if (!t) {
            for (size_t j = 0; j < i; j++) {
                nbt_table_free(out[j]);
                out[j] = NULL;
            }
            NBT_FAIL(NBT_ENOMEM, "plan: out of memory");
        }
        for (size_t c = 0; c < nch; c++)
            t->k[c] = r->phase ? -1 : (int)(4 * i + c);
        t->n = r->kind == NBT_TABLE_J ? r->n : 0;
        t->half = r->half;
        t->form = r->sub ? NBT_FORM_SUB : NBT_FORM_PLAIN;
        if (r->phase)
            snprintf(t->phase, sizeof t->phase, "%s", nbt_phase_name(r->phase));
    }
    nbt_build_opts o = {qtol, 1, nthreads};
    nbt_status st = r->kind == NBT_TABLE_H ? nbt_h_table_build_set(out, count, r->phase, &o)
                                           : nbt__j_table_build_set_gc(out, count, r->phase, &o, gc);
    if (st != NBT_OK)
        for (size_t i = 0; i < count; i++) {
            nbt_table_free(out[i]);
            out[i] = NULL;
        }
    return st;
}

static double rel_error(const nbt_table *t, double scale)
{
    double e = nbt_table_max_err(t);
    return scale > 0 ? e / scale : e;
}

/* worst relative error over packs, relative to the first pack's scale */
static double set_error(nbt_table *const *t, size_t count)
{
    double s = nbt_table_max_abs(t[0]), e = 0;
    for (size_t i = 0; i < count; i++)
        e = fmax(e, rel_error(t[i], s));
    return e;
}

static void free_packs(nbt_table **t, size_t count)
{
    for (size_t i = 0; i < count; i++) {
        nbt_table_free(t[i]);
        t[i] = NULL;
    }
}

/* ---- mappings and sizes ---- */

/* Quadrature tolerance of the tables built (proxies included: they are
 * reused as tables). */
#define QUAD_TOL 1e-10

/* Sizes of the ladder a set grows on, by ~1.5. */
static const size_t SIZES[] = {33, 49, 65, 97, 129, 193, 257, 385, 513, 769, 1025, 1537, 2049};
#define NSIZES (sizeof SIZES / sizeof SIZES[0])


/* Axes by rule (measured by exhaustive builds, doc/tables.md). u/T:
 * log1p_cbrt with c = max(xmax, 10): u ~ s^3 near 0 makes the u log u
 * behaviour of H and J C^2 in s, so bilinear error falls as N^-2; the
 * strength c ~ xmax was the best or within 3% for H over xmax = 1 .. 1000
 * and for J^1, J^20 at xmax = 10. v/theta: cos for H (narrow features
 * at both ends); log1p with c = min(n, 300) for Phong lobes: J^n's feature
 * is the lobe (width ~ n^-1/2) about theta = 0 where the source is, and
 * clustering there alone beat cos 3.4-3.7x for n = 20 (33^2: 1.60e-3 vs
 * 5.83e-3; 49^2: 7.1e-4 vs 2.6e-3), 2.4-11x for n = 2 .. 1000 (best c
 * ~ n up to 100, 300 at n = 1000); asinh with c = 1 for J^1: its Lambert
 * horizon at theta = pi/2 behaves like (theta - pi/2)^2 log|theta - pi/2|,
 * which on linear nodes converged as N^-2 log N (65 -> 129: 3.39); nodes
 * 1.13x denser there and 1.25x sparser at the ends gave 3.97, smaller
 * errors from 65^2 on and 10-25% larger ones at 33^2-49^2. */
static nbt_axis make_axis(const nbt_plan_request *r, int which, size_t n)
{
    nbt_axis a = {0, 0, NBT_AXIS_LINEAR, 0, n};
    if (which == 0) {
        a.hi = r->xmax;
        a.map = NBT_AXIS_LOG1P_CBRT;
        a.c = fmax(r->xmax, 10.0);
    } else {
        a.lo = r->kind == NBT_TABLE_H ? -NBT_PI_2 : 0;
        a.hi = r->kind == NBT_TABLE_H ? NBT_PI_2 : NBT_PI;
        a.map = r->kind == NBT_TABLE_H ? NBT_AXIS_COS : r->n == 1 ? NBT_AXIS_ASINH : NBT_AXIS_LOG1P;
        a.c = a.map == NBT_AXIS_ASINH ? 1.0 : a.map == NBT_AXIS_LOG1P ? fmin((double)r->n, 300.0) : 0.0;
    }
    return a;
}

static nbt_status check_request(const nbt_plan_request *r, char *err, size_t errlen)
{
    if (r->kind != NBT_TABLE_H && r->kind != NBT_TABLE_J)
        return failf(err, errlen, NBT_EINVAL, "plan: a set is of kind H or J");
    if (r->kind == NBT_TABLE_J && (r->n < 1 || r->n > 10000))
        return failf(err, errlen, NBT_EDOM, "plan: n = %d is not accepted: 1 .. 10000", r->n);
    if (!r->phase && (r->nterms < 1 || r->nterms > 4 * NBT_PLAN_MAX_PACKS))
        return failf(err, errlen, NBT_EDOM, "plan: %zu Legendre orders: 1 .. %d accepted", r->nterms,
                     4 * NBT_PLAN_MAX_PACKS);
    if (!(r->xmax > 0 && r->xmax <= 1e6))
        return failf(err, errlen, NBT_EDOM, "plan: xmax = %g is not accepted: 0 < xmax <= 1e6", r->xmax);
    if (!(r->tol >= 0 && r->tol < 1))
        return failf(err, errlen, NBT_EDOM, "plan: tol = %g is not accepted: 0 (fixed size) or in (0, 1)", r->tol);
    if (r->tol == 0 && (r->size[0] < 2 || r->size[1] < 2 || r->size[0] > 4096 || r->size[1] > 4096))
        return failf(err, errlen, NBT_EDOM, "plan: size %zux%zu is not accepted: 2 .. 4096 per axis", r->size[0],
                     r->size[1]);
    if (r->sub != 0 && r->sub != 1)
        return failf(err, errlen, NBT_EDOM, "plan: sub = %d is not accepted: 0 (plain tables) or 1 (form sub)", r->sub);
    return NBT_OK;
}

/* Convergence rate and cost exponent assumed without a 65^2 proxy: the
 * measured rates on the rule's mappings are 1.7 (J^1, its theta) .. 2; H's
 * cost grows with the node count, J's mostly with the rows (G and M). */
#define P_CONSERVATIVE 1.75
/* a predicted error this many times tol at the largest size is a planning-time
 * refusal: the rate from two proxies is not better known than that */
#define TOL_MISS_MARGIN 4.0
static double cost_exponent(const nbt_plan_request *r)
{
    return r->kind == NBT_TABLE_H ? 2.0 : 1.1;
}

/* Bilinear error of the 17^2 table on the same mappings (its nodes are the
 * even nodes of the 33^2 grid, its edge and cell midpoints the others, whose
 * exact values the 33^2 build holds): the second point of the convergence
 * fit for free. Relative to the first pack's largest value, as set_error. */
static double sub_error(nbt_table *const *t, size_t count)
{
    double e = 0;
    for (size_t p = 0; p < count; p++) {
        const nbt_table *a = t[p];
        size_t nx = a->axis[0].n, ny = a->axis[1].n, nc = a->nch;
        for (size_t j = 0; j < ny; j++)
            for (size_t i = 0; i < nx; i++) {
                if (i % 2 == 0 && j % 2 == 0)
                    continue;
                size_t i0 = i - i % 2, i1 = i + i % 2, j0 = j - j % 2, j1 = j + j % 2;
                for (size_t c = 0; c < nc; c++) {
                    double b = 0.25 * ((double)a->data[(j0 * nx + i0) * nc + c] + a->data[(j0 * nx + i1) * nc + c] +
                                       a->data[(j1 * nx + i0) * nc + c] + a->data[(j1 * nx + i1) * nc + c]);
                    e = fmax(e, fabs(b - a->data[(j * nx + i) * nc + c]));
                }
            }
    }
    double s = nbt_table_max_abs(t[0]);
    return s > 0 ? e / s : e;
}

/* The first ladder size where e33 (32/(N-1))^p <= tol (the last if none). */
static size_t ladder_size(double e33, double p, double tol)
{
    for (size_t i = 0; i < NSIZES; i++)
        if (e33 * pow(32.0 / (double)(SIZES[i] - 1), p) <= tol)
            return SIZES[i];
    return SIZES[NSIZES - 1];
}

/* Plan one set: mappings by rule; all packs at 33^2 (the final quadrature
 * tolerance, error measured) give e33; a second build gives the convergence
 * rate and the cost where the set may be 65^2 or larger (then the proxy is
 * the set, or cheap next to it), else the conservative rate is taken. The
 * second build is 65^2, or 129^2 for a set of 257 or more nodes on an axis:
 * builds of 33^2 and 65^2 took about the same time (fixed costs, 10-40 ms on
 * 2 shared cores, were most of it), so a cost exponent fitted to them came
 * out at its floor 1 and a 4096^2 H set was predicted 25-40x too fast; the
 * 129^2 build costs a quarter of a 257^2 set or less. Both builds are kept
 * for execution at those sizes (cache: 2 x NBT_PLAN_MAX_PACKS slots). */
static nbt_status plan_set(const nbt_plan_request *r, unsigned nthreads, nbt__jcache *gc, nbt_plan_set *ps,
                           nbt_table **cache, double *need_n)
{
    memset(ps, 0, sizeof *ps);
    ps->req = *r;
    ps->npacks = npacks_of(r);
    double e[2] = {0, 0}, secs[2] = {0, 0}, cpu[2] = {0, 0};
    size_t N0 = r->size[0], N1 = r->size[1];
    const size_t pn[2] = {33, r->tol == 0 && (N0 >= 257 || N1 >= 257) ? 129 : 65};
    double p = P_CONSERVATIVE, a = cost_exponent(r);
    for (int q = 0; q < 2; q++) {
        /* for a tolerance the rate comes from the 17^2 sub-grid of the 33^2
         * proxy (float data; not from half), at most the conservative one:
         * on the rule's mappings 17 -> 33 gave H 1.80 (33 -> 65: 1.95),
         * J^20 1.87 (2.00), J^1 1.99 (1.65: its theta horizon). Else the
         * 65^2 proxy only where the set may be that large (then it is the
         * set, or cheap next to it): below, the conservative rate */
        if (q == 1 && r->tol > 0 && !r->half) {
            double e17 = sub_error(cache, ps->npacks);
            if (e17 > 0 && e[0] > 0)
                p = fmin(fmax(log(e17 / e[0]) / log(2.0), 1.0), P_CONSERVATIVE);
            break;
        }
        if (q == 1 && (r->tol > 0 ? ladder_size(e[0], P_CONSERVATIVE, r->tol) < 65 : (N0 < 129 && N1 < 129)))
            break;
        nbt_table **t = cache + q * NBT_PLAN_MAX_PACKS;
        nbt_axis a0 = make_axis(r, 0, pn[q]), a1 = make_axis(r, 1, pn[q]);
        double t0 = nbt__now_s(), c0 = nbt__cpu_s();
        nbt_status st = build_packs(r, ps->npacks, &a0, &a1, QUAD_TOL, nthreads, gc, t);
        secs[q] = nbt__now_s() - t0;
        cpu[q] = nbt__cpu_s() - c0;
        if (st != NBT_OK)
            return st;
        e[q] = set_error(t, ps->npacks);
        if (q == 1) {
            /* err(N) = e33 (32/(N-1))^p, p in [1, 2]: at least the log
             * singularity's first order, at most bilinear's second */
            double step = log((double)(pn[1] - 1) / (double)(pn[0] - 1));
            if (e[1] > 0 && e[0] > 0)
                p = fmin(fmax(log(e[0] / e[1]) / step, 1.0), 2.0);
            if (secs[0] > 0 && secs[1] > 0)
                a = fmin(fmax(log(secs[1] / secs[0]) / step, 1.0), 2.0);
        }
    }
    if (r->tol > 0) {
        /* refused now rather than after growing through the ladder (minutes):
         * the largest size misses tol by more than the rate's uncertainty
         * (a factor TOL_MISS_MARGIN) */
        double e_last = e[0] * pow(32.0 / (double)(SIZES[NSIZES - 1] - 1), p);
        if (e_last > TOL_MISS_MARGIN * r->tol) {
            ps->pred_err = e_last;
            *need_n = 1.0 + 32.0 * pow(e[0] / r->tol, 1.0 / p);
            return NBT_ETOL;
        }
        N0 = N1 = ladder_size(e[0], p, r->tol);
    }
    ps->axis[0] = make_axis(r, 0, N0);
    ps->axis[1] = make_axis(r, 1, N1);
    double Nm = sqrt((double)(N0 - 1) * (double)(N1 - 1));
    ps->pred_err = e[0] * pow(32.0 / Nm, p);
    double nodes = (double)N0 * (double)N1, n0 = (double)(pn[0] * pn[0]), n1 = (double)(pn[1] * pn[1]);
    if (r->kind == NBT_TABLE_H && cpu[1] > 0 && secs[1] > 0 && nodes > n1) {
        /* H: every node is its own set of integrals (all orders at once), so the work is the CPU time
         * per node of the larger build times the nodes (measured 0.86-1.03 us per node with 16 orders
         * from 129^2 to 2049^2, while wall times of the same builds varied 2x on 2 shared cores), and
         * the wall time that work takes here and now is its CPU time times the wall/CPU ratio of both
         * builds (the threads' speed-up and the machine's other load) */
        double c = (cpu[1] - cpu[0]) / (n1 - n0), f = cpu[1] - c * n1;
        if (!(c > 0 && f >= 0)) /* no fixed part to be seen: all per node */
            c = cpu[1] / n1, f = 0;
        ps->pred_seconds = (f + c * nodes) * (secs[0] + secs[1]) / (cpu[0] + cpu[1]);
    } else /* cost ~ N^a from the 33^2 build */
        ps->pred_seconds = secs[0] * pow(nodes / n0, 0.5 * a);
    return NBT_OK;
}

static nbt_status plan_alloc(size_t n, unsigned nthreads, nbt_plan **out)
{
    nbt_plan *p = calloc(1, sizeof *p);
    if (!p)
        NBT_FAIL(NBT_ENOMEM, "plan: out of memory");
    p->sets = calloc(n, sizeof *p->sets);
    p->cache = calloc(2 * n * NBT_PLAN_MAX_PACKS, sizeof *p->cache);
    p->gc = nbt__jcache_alloc(JCACHE_BYTES);
    if (!p->sets || !p->cache || !p->gc) {
        nbt_plan_free(p);
        NBT_FAIL(NBT_ENOMEM, "plan: out of memory");
    }
    p->nthreads = nthreads;
    *out = p;
    return NBT_OK;
}

nbt_status nbt_plan_tables(const nbt_plan_request *req, size_t nreq, unsigned nthreads, nbt_plan **out, char *err,
                           size_t errlen)
{
    *out = NULL;
    if (nreq < 1)
        return failf(err, errlen, NBT_EINVAL, "plan: no table sets requested");
    for (size_t i = 0; i < nreq; i++) {
        nbt_status st = check_request(&req[i], err, errlen);
        if (st != NBT_OK)
            return st;
    }
    nbt_plan *p = NULL;
    nbt_status st = plan_alloc(nreq, nthreads, &p);
    if (st != NBT_OK)
        return failf(err, errlen, st, "plan: out of memory");
    size_t i = 0;
    double need_n = 0;
    for (; i < nreq && st == NBT_OK; i++, p->count++)
        st = plan_set(&req[i], nthreads, p->gc, &p->sets[i], p->cache + 2 * i * NBT_PLAN_MAX_PACKS, &need_n);
    if (st == NBT_ETOL) {
        const nbt_plan_request *r = &req[i - 1];
        double e_last = p->sets[i - 1].pred_err;
        char what[64];
        if (r->phase)
            snprintf(what, sizeof what, "a fixed phase");
        else
            snprintf(what, sizeof what, "%zu Legendre orders", r->nterms);
        nbt_plan_free(p);
        return failf(err, errlen, st, "tol %g is out of reach for the %s table with %s: its 33x33 proxy predicts "
                     "about %.3gx%.3g nodes, and an error of %.2g at the largest size, %zux%zu: ask for a larger "
                     "tolerance, fewer orders or a smaller range", r->tol, r->kind == NBT_TABLE_H ? "H" : "J", what,
                     need_n, need_n, e_last, SIZES[NSIZES - 1], SIZES[NSIZES - 1]);
    }
    if (st != NBT_OK) {
        nbt_plan_free(p);
        return failf(err, errlen, st, "plan: the proxy builds failed: %s", nbt_strerror(st));
    }
    *out = p;
    return NBT_OK;
}

nbt_status nbt_plan_scene(const nbt_scene *s, unsigned nthreads, nbt_plan **out, size_t *needed, char *err,
                          size_t errlen)
{
    *out = NULL;
    if (needed)
        *needed = 0;
    nbt_status st = nbt_scene_check(s, err, errlen);
    if (st != NBT_OK)
        return st;
    double xmax = s->kappa_t[1] * s->distance[1];
    nbt_plan_legendre leg = {1, 0, 1, s->tol};
    if (s->have_g) {
        double gmax = fmax(fabs(s->g[0]), fabs(s->g[1]));
        st = nbt_plan_legendre_terms(gmax, xmax, s->tol, s->orders_max, &leg);
        if (needed)
            *needed = leg.nterms;
        if (st == NBT_ETOL && leg.nterms > 512)
            return failf(err, errlen, st, "|g| up to %g needs more than 512 Legendre orders at tol %g: use a fixed "
                         "phase (phase = hg:g=...) or a larger tol", gmax, s->tol);
        if (st == NBT_ETOL)
            return failf(err, errlen, st, "|g| up to %g needs %zu Legendre orders at tol %g, more than orders_max = "
                         "%zu%s: use a fixed phase (phase = hg:g=...), a larger tol or a smaller |g|%s", gmax,
                         leg.nterms, s->tol, s->orders_max,
                         s->orders_max == NBT_PLAN_GL_ORDERS ? " (libnbt-gl's shaders take at most 16: 4 packs of 4)" : "",
                         s->orders_max == NBT_PLAN_GL_ORDERS ? ", or raise orders_max (up to 512) for tables used off the GPU" : "");
        if (st != NBT_OK)
            return failf(err, errlen, st, "the Legendre budget failed: %s", nbt_strerror(st));
    }
    nbt_plan_request rq[2 + NBT_SCENE_MAX_PHONG];
    size_t n = 0;
    nbt_plan_request base = {NBT_TABLE_H, 0, s->have_g ? leg.nterms : 0, s->have_g ? NULL : s->phase, xmax,
                             s->have_g ? leg.table_tol : s->tol, {0, 0}, s->half, s->sub};
    if (s->airlight)
        rq[n++] = base;
    base.kind = NBT_TABLE_J;
    if (s->diffuse) {
        base.n = 1;
        rq[n++] = base;
    }
    for (size_t i = 0; i < s->nphong; i++) {
        base.n = s->phong[i];
        rq[n++] = base;
    }
    st = nbt_plan_tables(rq, n, nthreads, out, err, errlen);
    if (st == NBT_OK)
        (*out)->leg = s->have_g ? leg : (nbt_plan_legendre){0, 0, 0, 0};
    return st;
}

void nbt_plan_free(nbt_plan *p)
{
    if (!p)
        return;
    if (p->cache)
        for (size_t i = 0; i < p->count; i++)
            for (int q = 0; q < 2; q++)
                free_packs(p->cache + (2 * i + (size_t)q) * NBT_PLAN_MAX_PACKS, p->sets[i].npacks);
    free(p->cache);
    free(p->sets);
    nbt__jcache_free(p->gc);
    free(p);
}

size_t nbt_plan_count(const nbt_plan *p)
{
    return p->count;
}

const nbt_plan_set *nbt_plan_get(const nbt_plan *p, size_t i)
{
    return i < p->count ? &p->sets[i] : NULL;
}

nbt_plan_legendre nbt_plan_legendre_budget(const nbt_plan *p)
{
    return p->leg;
}

/* ---- execution ---- */

/* field by field: the struct has padding */
static int same_axis(const nbt_axis *a, const nbt_axis *b)
{
    return a->lo == b->lo && a->hi == b->hi && a->map == b->map && a->c == b->c && a->n == b->n;
}

void nbt_tableset_free(nbt_tableset *ts)
{
    free_packs(ts->t, ts->count);
    ts->count = 0;
}

nbt_status nbt_plan_execute(const nbt_plan *p, size_t i, nbt_tableset *out, char *err, size_t errlen)
{
    memset(out, 0, sizeof *out);
    if (i >= p->count)
        return failf(err, errlen, NBT_EINVAL, "plan: set %zu of %zu", i, p->count);
    const nbt_plan_set *ps = &p->sets[i];
    const nbt_plan_request *r = &ps->req;
    nbt_axis a0 = ps->axis[0], a1 = ps->axis[1];
    double t0 = nbt__now_s(), prev_err = 0;
    size_t prev_n = 0;
    for (;;) {
        nbt_status st = NBT_OK;
        nbt_table *const *cache = NULL;
        for (int q = 0; q < 2; q++) {
            nbt_table *const *c = p->cache + (2 * i + (size_t)q) * NBT_PLAN_MAX_PACKS;
            if (c[0] && same_axis(&c[0]->axis[0], &a0) && same_axis(&c[0]->axis[1], &a1))
                cache = c;
        }
        if (cache) {
            /* a proxy is this very build: copy it */
            for (size_t q = 0; q < ps->npacks && st == NBT_OK; q++)
                if (!(out->t[q] = nbt_table_dup(cache[q])))
                    st = NBT_ENOMEM;
            if (st != NBT_OK)
                free_packs(out->t, ps->npacks);
        } else
            st = build_packs(r, ps->npacks, &a0, &a1, QUAD_TOL, p->nthreads, p->gc, out->t);
        if (st != NBT_OK)
            return failf(err, errlen, st, "building the %s table failed: %s", r->kind == NBT_TABLE_H ? "H" : "J",
                         nbt_strerror(st));
        out->count = ps->npacks;
        out->scale = nbt_table_max_abs(out->t[0]);
        out->rel_err = set_error(out->t, out->count);
        if (r->tol <= 0 || out->rel_err <= r->tol)
            break;
        size_t n = a0.n > a1.n ? a0.n : a1.n, next = nbt__ladder_next(SIZES, NSIZES, n);
        if (prev_n > 0 && next != 0) {
            /* two sizes missed: the measured rate says how large the set
             * must grow; stop now where that is beyond the ladder, rather
             * than after building every size up to it */
            double rate = log(prev_err / out->rel_err) / log((double)(n - 1) / (double)(prev_n - 1));
            double need = rate > 0.1 ? 1.0 + (double)(n - 1) * pow(out->rel_err / r->tol, 1.0 / rate) : INFINITY;
            if (need > TOL_MISS_MARGIN * (double)SIZES[NSIZES - 1]) {
                double worst = out->rel_err;
                nbt_tableset_free(out);
                return failf(err, errlen, NBT_ETOL, "tol %g is out of reach for this %s table: its error fell from %.2g "
                             "at %zux%zu to %.2g at %zux%zu (rate %.2f), which needs about %.3g nodes per axis, more "
                             "than the largest size, 2049: ask for a larger tolerance, fewer orders or a smaller "
                             "range", r->tol, r->kind == NBT_TABLE_H ? "H" : "J", prev_err, prev_n, prev_n, worst, n, n,
                             rate, need);
            }
        }
        prev_n = n;
        prev_err = out->rel_err;
        if (next == 0) {
            double worst = out->rel_err;
            nbt_tableset_free(out);
            return failf(err, errlen, NBT_ETOL, "tol %g is not reached by every order with up to 2049x2049 nodes "
                         "(worst %.2g): ask for a larger tolerance, fewer orders or a smaller range", r->tol, worst);
        }
        nbt_tableset_free(out);
        a0.n = a1.n = next;
    }
    out->seconds = nbt__now_s() - t0;
    return NBT_OK;
}

nbt_status nbt_plan_execute_all(const nbt_plan *p, nbt_tableset *out, char *err, size_t errlen)
{
    for (size_t i = 0; i < p->count; i++) {
        nbt_status st = nbt_plan_execute(p, i, &out[i], err, errlen);
        if (st != NBT_OK) {
            for (size_t j = 0; j < i; j++)
                nbt_tableset_free(&out[j]);
            return st;
        }
    }
    return NBT_OK;
}

void nbt_plan_stem(const nbt_plan_request *r, char *buf, size_t n)
{
    char kind[16];
    if (r->kind == NBT_TABLE_H)
        snprintf(kind, sizeof kind, "H");
    else
        snprintf(kind, sizeof kind, "J%d", r->n);
    if (r->phase)
        snprintf(buf, n, "%s_%s", kind, nbt_phase_name(r->phase));
    else
        snprintf(buf, n, "%s", kind);
    for (char *q = buf; *q; q++) /* keep file names portable */
        if (*q == ':' || *q == '=' || *q == ' ' || *q == '/')
            *q = '_';
}
