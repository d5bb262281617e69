/* libnbt/internal.h: helpers shared by libnbt's sources; not installed. */
#ifndef NBT_INTERNAL_H
#define NBT_INTERNAL_H

#include <errno.h>
#include <math.h>
#include <stddef.h>
#include <nbt/error.h>
#include <nbt/phase.h>
#include <nbt/quad.h>
#include <nbt/table.h>
#include <nbt/airlight.h>

#define NBT_PI 3.14159265358979323846
#define NBT_PI_2 1.57079632679489661923

/* The status of a failed fopen, read or write whose errno is e: NBT_ENOMEM
 * when the C library ran out of memory (fopen's FILE, a stream's buffer),
 * else NBT_EIO. */
static inline nbt_status nbt__io_status(int e)
{
    return e == ENOMEM ? NBT_ENOMEM : NBT_EIO;
}

/* The status of a result made of two parts, each with a value: a hard
 * error (neither NBT_OK nor NBT_ETOL) of either, else NBT_ETOL if either
 * part missed its tolerance, else NBT_OK. */
static inline nbt_status nbt__status_join(nbt_status a, nbt_status b)
{
    if (a != NBT_OK && a != NBT_ETOL)
        return a;
    if (b != NBT_OK && b != NBT_ETOL)
        return b;
    return a == NBT_ETOL || b == NBT_ETOL ? NBT_ETOL : NBT_OK;
}

/* Report a failure to the error handler (if any) and return the status. */
nbt_status nbt__fail(nbt_status s, const char *reason);
#define NBT_FAIL(s, reason) return nbt__fail((s), (reason))
/* The same with a formatted reason (naming the bad value). */
nbt_status nbt__failv(nbt_status s, const char *fmt, ...) __attribute__((format(printf, 2, 3)));

/* Format a one-line reason into err (if given) and return st; no handler
 * (the planners' errors go to the caller's buffer). Defined in plan.c. */
/* Wall-clock seconds (monotonic) and the process's CPU seconds, all threads
 * (the work, whatever else runs on the machine); defined in plan.c. */
double nbt__now_s(void);
double nbt__cpu_s(void);

nbt_status nbt__failf(char *err, size_t errlen, nbt_status st, const char *fmt, ...)
    __attribute__((format(printf, 4, 5)));

/* 4 pi HG(g, mu): the Henyey-Greenstein phase function times 4 pi */
static inline double nbt__hg_4pi(double g, double mu)
{
    double d = 1.0 + g * g - 2.0 * g * mu;
    return (1.0 - g * g) / (d * sqrt(d));
}

/* A 3-D table's quadratic interpolation in its slice coordinate
 * (interp2 = 2): the weights of slices mc - 1, mc, mc + 1 at p = mc + t. */
static inline void nbt__quad_weights(double t, double w[3])
{
    w[0] = 0.5 * t * (t - 1.0);
    w[1] = 1.0 - t * t;
    w[2] = 0.5 * t * (t + 1.0);
}

/* Cubic (Lagrange) interpolation in the slice coordinate (interp2 = 3):
 * the weights of slices m0 .. m0 + 3 at p = m0 + x, x in [0, 3]. */
static inline void nbt__cubic_weights(double x, double w[4])
{
    w[0] = -(x - 1.0) * (x - 2.0) * (x - 3.0) / 6.0;
    w[1] = x * (x - 2.0) * (x - 3.0) / 2.0;
    w[2] = -x * (x - 1.0) * (x - 3.0) / 2.0;
    w[3] = x * (x - 1.0) * (x - 2.0) / 6.0;
}

/* First slice of the cubic stencil for p = s (n - 1): the cell's own four
 * slices m - 1 .. m + 2 (m = floor p), moved inwards in the first and last
 * cells; needs n >= 4. */
static inline size_t nbt__cubic_first(double p, size_t n)
{
    double m0 = fmin(fmax(floor(p) - 1.0, 0.0), (double)(n - 4));
    return (size_t)m0;
}

/* Sum of |weights| of one lookup: bilinear 1, quadratic in g (interp2 = 2)
 * at most 1.25 (at t = +-1/2), cubic (interp2 = 3) 1.25 in inner cells and
 * at most 1.6312 in the first and last (the one-sided stencil, at 0.451 of
 * the cell): a change of at most d at every node moves a lookup by at most
 * this times d. */
static inline double nbt__lookup_weight_sum(const nbt_table *t)
{
    return t->interp2 == 3 && t->axis[2].n >= 4 ? 1.6312 : t->interp2 == 2 && t->axis[2].n >= 3 ? 1.25 : 1.0;
}

/* nbt_table_round_half, returning the largest change of channel c. */
double nbt__table_round_half_change(nbt_table *t, size_t c);

/* The error per row from the error per (band, row): rows[k] = max over
 * b < nb of bands[b * nk + k], k < nk (the layout of theta_err within a g
 * cell, whose rows are row_err's). */
void nbt__band_max(const double *bands, size_t nb, size_t nk, double *rows);

/* Texel position p = s (n - 1) of x on axis a, split into the cell i0
 * (clamped to [0, n - 2]) and the weight f = p - i0, as a sampler does. */
void nbt__axis_cell(const nbt_axis *a, double x, size_t *i0, double *f);

/* Weights of the airlight integrand: Legendre orders 0..kmax, or one
 * channel: 4 pi p(mu) when phase != NULL, or the truncated series
 * sum_k (2k+1) b_k P_k(mu) when b != NULL (orders 0..kmax); or, when
 * nhg > 0, 4 pi HG(hg[i], mu) for nhg asymmetries at once (g-sliced
 * tables: one quadrature for all slices). hgk, when set: the slices'
 * constants 1 + g^2, 2 g and 1 - g^2 (nhg each, nbt__hg_consts), which the
 * integrands then use in a vector loop (the same values to the bit). */
typedef struct {
    size_t kmax;
    const nbt_phase *phase;
    const double *b;
    const double *hg;
    size_t nhg;
    const double *hgk;
} nbt__weights;

/* hgk[0..3n-1] for nbt__weights from g[0..n-1] */
void nbt__hg_consts(const double *g, size_t n, double *hgk);

static inline unsigned nbt__fdim(const nbt__weights *w)
{
    return w->nhg ? (unsigned)w->nhg : (w->phase || w->b) ? 1u : (unsigned)(w->kmax + 1);
}

/* p at mu = cos(theta) with sn = sin(theta) >= 0 given accurately (the
 * Gaussian kinds need the angle itself: acos(mu) loses all but the top bits
 * of pi - theta near mu = -1, where 1 + mu rounds in steps of 1.1e-16). */
double nbt__phase_eval_cs(const nbt_phase *p, double mu, double sn);

/* A cosine of the scattering angle distributed as p, from uniforms in [0, 1). */
double nbt__phase_sample_mu(const nbt_phase *p, double (*uniform)(void *), void *rs);

/* The one parameter of a phase function whose sampler a caller may inline
 * (same arithmetic and uniforms as nbt__phase_sample_mu): g for HG, B for a
 * single Gaussian lobe (GAUSS, or SOG with one term); returns 0 for every
 * other phase function. */
int nbt__phase_sample_param(const nbt_phase *p, nbt_phase_kind *kind, double *param);

/* sum_{k=0}^{kmax} (2k+1) b_k P_k(x) by Clenshaw's recurrence. */
double nbt__legendre_series(const double *b, size_t kmax, double x);

/* s(t) = tan(pi/4 + t/2), written without cancellation on either side. */
double nbt__s_of_t(double t);

/* The airlight segment integral
 *   S(u; v1, v2) = int_{v1}^{v2} exp(-u (s(t) - s0)) w(-sin t) dt,
 * s0 = s(v1) when shifted, else 0 (so shifted values carry exp(-u s(v1))
 * outside). -pi/2 <= v1 <= v2 <= pi/2, u >= 0. out/err hold fdim values. */
nbt_status nbt__airlight_segment(nbt_quad_ws *ws, const nbt__weights *w, double u,
                                 double v1, double v2, int shifted, double tol,
                                 double *out, double *err);

/* The same segment by fixed Gauss-Legendre rules (libnbt/airlight.c):
 * all components at once, *err an a-priori bound (all components);
 * scratch holds fdim doubles. One workspace per tolerance, shareable. */
typedef struct nbt__segfix nbt__segfix;
nbt__segfix *nbt__segfix_alloc(double tol);
void nbt__segfix_free(nbt__segfix *F);
void nbt__segfix_eval(const nbt__segfix *F, const nbt__weights *w, double u, double v1, double v2, int shifted,
                      double *out, double *scratch, double *err);

/* Airlight by Nishita's integral in distance along the ray, with phase p or
 * (p == NULL) the Legendre series b[0..nterms-1]; geometry not checked. */
nbt_status nbt__airlight_ray(const nbt_phase *p, const double *b, size_t nterms,
                             const void *geom, double tol, double *La, double *err);

/* The first size on a ladder (increasing, n entries) above x; 0 past its end. */
/* Turns the unit direction u by the polar cosine mu (st = sin) and azimuth
 * (cp, sp) = (cos, sin): u' = mu u + st (cp e1 + sp e2) with e1, e2 the
 * orthonormal basis around u of Duff et al. ("Building an orthonormal basis,
 * revisited", 2017), which has no pole: the usual formula's special case for
 * |uz| near 1 sets u' about the z axis and forgets the tilt u had. */
static inline void nbt__turn(double u[3], double mu, double st, double cp, double sp)
{
    double sgn = copysign(1.0, u[2]), a = -1.0 / (sgn + u[2]), b = u[0] * u[1] * a;
    double e1[3] = {1.0 + sgn * u[0] * u[0] * a, sgn * b, -sgn * u[0]};
    double e2[3] = {b, sgn + u[1] * u[1] * a, -u[1]};
    double n[3], nn = 0.0;
    for (int i = 0; i < 3; i++) {
        n[i] = mu * u[i] + st * (cp * e1[i] + sp * e2[i]);
        nn += n[i] * n[i];
    }
    nn = 1.5 - 0.5 * nn; /* |n|^2 = 1 + e, e ~ 1e-16: 1/sqrt(1 + e) = 1 - e/2 + O(e^2) */
    for (int i = 0; i < 3; i++)
        u[i] = n[i] * nn;
}

static inline size_t nbt__ladder_next(const size_t *ladder, size_t n, size_t x)
{
    for (size_t i = 0; i < n; i++)
        if (ladder[i] > x)
            return ladder[i];
    return 0;
}

/* The airlight table routes (Legendre packs, fixed phase, g-sliced): where
 * the lookup's recorded-error bound exceeds NBT__TABLE_RAY_FRAC of its value
 * they integrate along the ray instead (see nbt/airlight.h). */
#define NBT__TABLE_RAY_FRAC 0.1
/* L_a from the tables' difference s = sum_k w_k [H_k(u, theta_d) - H_k(u, theta_0)]
 * and w, the bound of s's error (h = d_sv sin gamma > 0, t = d_sv cos gamma):
 * the prefactor kappa_s I0 e^{-kappa_t t}/(4 pi h) combined in logs. */
void nbt__airlight_from_diff(const void *geom, double h, double t, double s, double w, double *La, double *abserr);
/* The ray integral with phase p (or the series b) where the lookup (Lt, Et)
 * was not good enough; keeps the lookup where the ray quadrature did not
 * converge to better than Et. outside: the lookup clamped u (NBT_ETOL). */
nbt_status nbt__airlight_ray_or_lookup(const nbt_phase *p, const double *b, size_t nterms, const void *geom,
                                       double h, double Lt, double Et, int outside, double *La, double *abserr);

/* Sum over the tables' channels of (2k+1) b_k [T(x0, y1) - T(x0, y0)]
 * (fixed-phase channels weight 1; y0 = NAN: no subtraction). Returns 1 if x0
 * lies outside a table's first axis. */
#include <nbt/table.h>
int nbt__table_series_diff(const nbt_table *const *tables, size_t ntables, const double *b,
                           size_t nterms, double x0, double y0, double y1, double *sum);

/* Read a text file of rows "x y" ('#' comments, blank lines skipped). check
 * (may be NULL) writes why row i (previous x: prev) is rejected, naming the
 * bad value and what is accepted, into why[whylen] and returns nonzero, or
 * returns 0. Errors name the file, the line and `names` (e.g. "z rho"); on
 * success *x and *y are malloc'd and *n >= 1. */
typedef int (*nbt__row_check)(size_t i, double x, double y, double prev, char *why, size_t whylen);
nbt_status nbt__read_columns(const char *path, const char *what, const char *names, nbt__row_check check,
                             double **x, double **y, size_t *n, char *err, size_t errlen);

/* Run fn(i, thread, ctx) for i in [0, n) on up to nthreads threads (0: all
 * online CPUs). Stops early and returns the first non-OK status. */
typedef nbt_status (*nbt__task)(size_t i, unsigned thread, void *ctx);
nbt_status nbt__parallel_for(size_t n, unsigned nthreads, nbt__task fn, void *ctx);
/* The same; the calling thread, once no item is left to start, calls watch(wctx) every period
 * seconds until the other threads have finished theirs (progress reports while the last items
 * run elsewhere). */
nbt_status nbt__parallel_for_watch(size_t n, unsigned nthreads, nbt__task fn, void *ctx, void (*watch)(void *),
                                   void *wctx, double period);
unsigned nbt__nthreads(unsigned requested, size_t n);

/* G rows of J builds, shared between builds (libnbt/jcache.c): a row is
 * G_k(T, g_q) for k < fdim at all Q panel nodes, which depend on T, the
 * panel layout (ngeo, nhi, split; len = Q fdim values), the quadrature
 * tolerance and the components (Legendre orders, or HG at hg[0..fdim-1]),
 * not on n or theta. get copies a stored row into row and its error bounds
 * into err (1) or returns 0; put stores a copy until max_bytes are held.
 * Both are thread-safe. Errors: one for Legendre rows (hg NULL), one per
 * component for HG rows. */
typedef struct {
    double T, tol;
    size_t len, ngeo, nhi, fdim;
    int split;
    const double *hg; /* HG components' g (fdim values), or NULL: Legendre */
} nbt__jkey;
typedef struct nbt__jcache nbt__jcache;
nbt__jcache *nbt__jcache_alloc(size_t max_bytes);
void nbt__jcache_free(nbt__jcache *c);
int nbt__jcache_get(nbt__jcache *c, const nbt__jkey *k, double *row, double *err);
void nbt__jcache_put(nbt__jcache *c, const nbt__jkey *k, const double *row, const double *err);
/* nbt_j_table_build_set with G rows taken from and added to gc (may be NULL) */
nbt_status nbt__j_table_build_set_gc(nbt_table *const *ts, size_t ntab, const nbt_phase *fixed,
                                     const nbt_build_opts *o, nbt__jcache *gc);

/* An EXR header can claim any data window. Before allocating for it, the
 * pixels' raw size must be one the file could hold: ZIP (deflate) compresses
 * by at most 1032:1 and the other codecs by less on real data, so raw bytes
 * above 1e4 x the file's size, plus 16 MiB below which any claim is harmless,
 * mean a corrupt or hostile header (found by fuzzing: a 1 kB file asked for
 * 13 GB). Nonzero when plausible. */
int nbt__exr_raw_plausible(const char *path, double raw_bytes);

/* OpenEXR contexts allocate through libnbt (image_exr.c): nbt__exr_init sets
 * init's alloc_fn and free_fn and clears this thread's out-of-memory flag;
 * nbt__exr_nomem is nonzero when an OpenEXR allocation has failed since. */
#ifdef OPENEXR_CONTEXT_H
void nbt__exr_init(exr_context_initializer_t *init);
#endif
int nbt__exr_nomem(void);


/* Non-negative least squares: x >= 0 minimising |A x - b| (A m x n,
 * row-major; Lawson-Hanson); *resid (may be NULL) gets the final |A x - b|. */
nbt_status nbt__nnls(const double *A, size_t m, size_t n, const double *b, double *x, double *resid);

#endif
