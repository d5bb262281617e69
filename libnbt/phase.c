/* libnbt/phase.c: phase functions, their Legendre moments and HG truncation errors. */
#include <config.h>
#include <errno.h>
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <nbt/phase.h>
#include <nbt/quad.h>
#include "internal.h"

struct nbt_phase {
    nbt_phase_kind kind;
    double g;          /* HG; HG2: the first lobe's */
    double g2, wmix;   /* HG2: the second lobe's g and the first lobe's weight */
    size_t n;          /* SOG components or table points */
    double *w, *B;     /* SOG (a single Gaussian is n = 1) */
    double *Z;         /* SOG: 1/(4 pi B (1 - exp(-pi^2/4B))) per component */
    double *mu, *p;    /* table */
    double *cdf;       /* table: 2 pi int_{-1}^{mu_i} p, cdf[n-1] = 1 */
    char name[112];
};

/* The shortest %g form that reads back as the same double. */
static void fmt_double(char *buf, size_t n, double v)
{
    for (int prec = 6; prec <= 17; prec++) {
        snprintf(buf, n, "%.*g", prec, v);
        if (strtod(buf, NULL) == v)
            return;
    }
}

static nbt_phase *phase_new(nbt_phase_kind kind)
{
    nbt_phase *p = calloc(1, sizeof *p);
    if (p)
        p->kind = kind;
    return p;
}

nbt_phase *nbt_phase_iso(void)
{
    nbt_phase *p = phase_new(NBT_PHASE_ISO);
    if (p)
        snprintf(p->name, sizeof p->name, "iso");
    return p;
}

nbt_phase *nbt_phase_rayleigh(void)
{
    nbt_phase *p = phase_new(NBT_PHASE_RAYLEIGH);
    if (p)
        snprintf(p->name, sizeof p->name, "rayleigh");
    return p;
}

nbt_phase *nbt_phase_hg(double g)
{
    if (!(g > -1.0 && g < 1.0))
        return NULL;
    nbt_phase *p = phase_new(NBT_PHASE_HG);
    if (p) {
        p->g = g;
        char num[32];
        fmt_double(num, sizeof num, g);
        snprintf(p->name, sizeof p->name, "hg:g=%s", num);
    }
    return p;
}

nbt_phase *nbt_phase_hg2(double g1, double g2, double w)
{
    if (!(g1 > -1.0 && g1 < 1.0) || !(g2 > -1.0 && g2 < 1.0) || !(w >= 0.0 && w <= 1.0))
        return NULL;
    nbt_phase *p = phase_new(NBT_PHASE_HG2);
    if (p) {
        p->g = g1;
        p->g2 = g2;
        p->wmix = w;
        char a[32], b[32], c[32];
        fmt_double(a, sizeof a, g1);
        fmt_double(b, sizeof b, g2);
        fmt_double(c, sizeof c, w);
        snprintf(p->name, sizeof p->name, "hg2:g1=%s,g2=%s,w=%s", a, b, c);
    }
    return p;
}

nbt_phase *nbt_phase_sog(size_t n, const double *w, const double *B)
{
    if (n == 0 || !w || !B)
        return NULL;
    double sw = 0;
    for (size_t i = 0; i < n; i++) {
        if (!(w[i] >= 0 && isfinite(w[i])) || !(B[i] > 0 && B[i] <= NBT_PHASE_GAUSS_BMAX))
            return NULL;
        sw += w[i];
    }
    if (!(sw > 0))
        return NULL;
    nbt_phase *p = phase_new(n == 1 ? NBT_PHASE_GAUSS : NBT_PHASE_SOG);
    if (!p)
        return NULL;
    p->n = n;
    p->w = malloc(n * sizeof(double));
    p->B = malloc(n * sizeof(double));
    p->Z = malloc(n * sizeof(double));
    if (!p->w || !p->B || !p->Z) {
        nbt_phase_free(p);
        return NULL;
    }
    for (size_t i = 0; i < n; i++) {
        p->w[i] = w[i] / sw;
        p->B[i] = B[i];
        /* -expm1 keeps the normalisation exact for large B as well */
        p->Z[i] = 1.0 / (4.0 * NBT_PI * B[i] * -expm1(-NBT_PI * NBT_PI / (4.0 * B[i])));
    }
    char num[32];
    fmt_double(num, sizeof num, B[0]);
    if (n == 1)
        snprintf(p->name, sizeof p->name, "gauss:B=%s", num);
    else
        snprintf(p->name, sizeof p->name, "sog:%zu terms", n);
    return p;
}

nbt_phase *nbt_phase_gauss(double B)
{
    double w = 1.0;
    return nbt_phase_sog(1, &w, &B);
}

nbt_phase *nbt_phase_tabulated(size_t n, const double *mu, const double *pv)
{
    if (n < 2 || !mu || !pv || mu[0] != -1.0 || mu[n - 1] != 1.0)
        return NULL;
    double area = 0;
    for (size_t i = 0; i < n; i++) {
        if (!(pv[i] >= 0 && isfinite(pv[i])))
            return NULL;
        if (i > 0) {
            if (!(mu[i] > mu[i - 1]))
                return NULL;
            area += 0.5 * (pv[i] + pv[i - 1]) * (mu[i] - mu[i - 1]);
        }
    }
    if (!(area > 0))
        return NULL;
    nbt_phase *p = phase_new(NBT_PHASE_TABLE);
    if (!p)
        return NULL;
    p->n = n;
    p->mu = malloc(n * sizeof(double));
    p->p = malloc(n * sizeof(double));
    p->cdf = malloc(n * sizeof(double));
    if (!p->mu || !p->p || !p->cdf) {
        nbt_phase_free(p);
        return NULL;
    }
    for (size_t i = 0; i < n; i++) {
        p->mu[i] = mu[i];
        p->p[i] = pv[i] / (2.0 * NBT_PI * area);
        p->cdf[i] = i == 0 ? 0.0 : p->cdf[i - 1] + NBT_PI * (p->p[i] + p->p[i - 1]) * (mu[i] - mu[i - 1]);
    }
    snprintf(p->name, sizeof p->name, "table:%zu points", n);
    return p;
}

void nbt_phase_free(nbt_phase *p)
{
    if (!p)
        return;
    free(p->w);
    free(p->B);
    free(p->Z);
    free(p->mu);
    free(p->p);
    free(p->cdf);
    free(p);
}

nbt_phase_kind nbt_phase_get_kind(const nbt_phase *p) { return p->kind; }
const char *nbt_phase_name(const nbt_phase *p) { return p->name; }

/* theta/sin(theta) exp(-theta^2/4B) * Z for one Gaussian at mu = cos(theta),
 * st = sin(theta). */
static double gauss_eval(double B, double Z, double mu, double st)
{
    double th = atan2(st, mu);
    double ratio;
    if (th < 1e-4)
        ratio = 1.0 + th * th / 6.0;
    else
        ratio = th / fmax(st, 1e-8); /* integrable singularity at mu = -1 cut at sin = 1e-8 */
    return Z * ratio * exp(-th * th / (4.0 * B));
}

/* The segment [x[lo], x[lo+1]] of an increasing x[0..n-1] that holds v
 * (the first or last segment outside the range). */
static size_t segment(const double *x, size_t n, double v)
{
    size_t lo = 0, hi = n - 1;
    while (hi - lo > 1) {
        size_t m = (lo + hi) / 2;
        if (x[m] <= v)
            lo = m;
        else
            hi = m;
    }
    return lo;
}

double nbt_phase_eval(const nbt_phase *p, double mu)
{
    if (mu > 1.0)
        mu = 1.0;
    if (mu < -1.0)
        mu = -1.0;
    return nbt__phase_eval_cs(p, mu, sqrt((1.0 - mu) * (1.0 + mu)));
}

double nbt__phase_eval_cs(const nbt_phase *p, double mu, double sn)
{
    if (mu > 1.0)
        mu = 1.0;
    if (mu < -1.0)
        mu = -1.0;
    if (!(sn >= 0.0))
        sn = 0.0;
    switch (p->kind) {
    case NBT_PHASE_ISO:
        return 1.0 / (4.0 * NBT_PI);
    case NBT_PHASE_RAYLEIGH:
        return 3.0 / (16.0 * NBT_PI) * (1.0 + mu * mu);
    case NBT_PHASE_HG:
        return nbt__hg_4pi(p->g, mu) / (4.0 * NBT_PI);
    case NBT_PHASE_HG2:
        return (p->wmix * nbt__hg_4pi(p->g, mu) + (1.0 - p->wmix) * nbt__hg_4pi(p->g2, mu)) / (4.0 * NBT_PI);
    case NBT_PHASE_GAUSS:
    case NBT_PHASE_SOG: {
        double s = 0;
        for (size_t i = 0; i < p->n; i++)
            s += p->w[i] * gauss_eval(p->B[i], p->Z[i], mu, sn);
        return s;
    }
    case NBT_PHASE_TABLE: {
        size_t lo = segment(p->mu, p->n, mu), hi = lo + 1;
        double f = (mu - p->mu[lo]) / (p->mu[hi] - p->mu[lo]);
        return p->p[lo] + f * (p->p[hi] - p->p[lo]);
    }
    }
    return NAN;
}

/* 1/(k+1) for the first orders (constants folded at compile time): the
 * recurrence's divide sat in its dependency chain, and with the fixed rules
 * of the G rows (J tables) P_0..P_K per node is most of the work */
#define INV4(k) 1.0 / ((k) + 1.0), 1.0 / ((k) + 2.0), 1.0 / ((k) + 3.0), 1.0 / ((k) + 4.0)
#define INV16(k) INV4(k), INV4((k) + 4), INV4((k) + 8), INV4((k) + 12)
static const double inv_k1[64] = {INV16(0), INV16(16), INV16(32), INV16(48)};

void nbt_legendre_p(size_t kmax, double x, double *P)
{
    P[0] = 1.0;
    if (kmax == 0)
        return;
    P[1] = x;
    size_t k = 1;
    for (; k < kmax && k < 63; k++)
        P[k + 1] = ((2.0 * (double)k + 1.0) * x * P[k] - (double)k * P[k - 1]) * inv_k1[k];
    for (; k < kmax; k++)
        P[k + 1] = ((2.0 * (double)k + 1.0) * x * P[k] - (double)k * P[k - 1]) / ((double)k + 1.0);
}

double nbt__legendre_series(const double *b, size_t kmax, double x)
{
    /* P_{k+1} = a_k P_k + c_k P_{k-1}, a_k = (2k+1)x/(k+1), c_k = -k/(k+1) */
    double y1 = 0, y2 = 0;
    for (size_t k = kmax + 1; k-- > 0;) {
        double kk = (double)k;
        double a = (2 * kk + 1) * x / (kk + 1), c = -(kk + 1) / (kk + 2);
        double y = (2 * kk + 1) * b[k] + a * y1 + c * y2;
        y2 = y1;
        y1 = y;
    }
    return y1;
}

/* b_k of one Gaussian: int_0^pi P_k(cos th) th exp(-th^2/4B) dth / (2B (1 - e^{-pi^2/4B})),
 * integrated in theta, where the integrand is smooth. */
typedef struct {
    double B;
    size_t kmax;
} gauss_mom_ctx;

static int gauss_mom_f(double th, void *vp, unsigned fdim, double *f)
{
    const gauss_mom_ctx *c = vp;
    nbt_legendre_p(c->kmax, cos(th), f);
    double dens = th * exp(-th * th / (4.0 * c->B)) / (2.0 * c->B * -expm1(-NBT_PI * NBT_PI / (4.0 * c->B)));
    for (unsigned k = 0; k < fdim; k++)
        f[k] *= dens;
    return 0;
}

typedef struct {
    const nbt_phase *p;
    size_t kmax;
} table_mom_ctx;

static int table_mom_f(double mu, void *vp, unsigned fdim, double *f)
{
    const table_mom_ctx *c = vp;
    nbt_legendre_p(c->kmax, mu, f);
    double v = 2.0 * NBT_PI * nbt_phase_eval(c->p, mu);
    for (unsigned k = 0; k < fdim; k++)
        f[k] *= v;
    return 0;
}

nbt_status nbt_phase_moments(const nbt_phase *p, size_t kmax, double *b)
{
    for (size_t k = 0; k <= kmax; k++)
        b[k] = 0.0;
    b[0] = 1.0;
    switch (p->kind) {
    case NBT_PHASE_ISO:
        return NBT_OK;
    case NBT_PHASE_RAYLEIGH:
        if (kmax >= 2)
            b[2] = 0.1;
        return NBT_OK;
    case NBT_PHASE_HG:
        for (size_t k = 1; k <= kmax; k++)
            b[k] = b[k - 1] * p->g;
        return NBT_OK;
    case NBT_PHASE_HG2: {
        double a = 1, c = 1;
        for (size_t k = 1; k <= kmax; k++) {
            a *= p->g;
            c *= p->g2;
            b[k] = p->wmix * a + (1.0 - p->wmix) * c;
        }
        return NBT_OK;
    }
    default:
        break;
    }
    unsigned fdim = (unsigned)(kmax + 1);
    double *r = malloc(2 * fdim * sizeof(double));
    nbt_quad_ws *ws = nbt_quad_ws_alloc(fdim, 4000);
    if (!r || !ws) {
        free(r);
        nbt_quad_ws_free(ws);
        NBT_FAIL(NBT_ENOMEM, "nbt_phase_moments: out of memory");
    }
    nbt_status st = NBT_OK;
    if (p->kind == NBT_PHASE_TABLE) {
        table_mom_ctx c = {p, kmax};
        /* the table's nodes are kinks of the integrand */
        st = nbt_quad_gk_pts(ws, table_mom_f, &c, fdim, -1.0, 1.0, p->mu + 1, p->n - 2,
                             1e-14, 1e-13, b, r + fdim);
    } else {
        for (size_t i = 0; i < p->n && st == NBT_OK; i++) {
            gauss_mom_ctx c = {p->B[i], kmax};
            /* past theta = 40 sqrt(B) the density is below e^-400: a narrow
             * lobe integrated over [0, pi] was missed entirely (B = 1e-6 gave
             * b_0 = 7e-18; found by fuzzing) */
            double top = fmin(NBT_PI, 40.0 * sqrt(p->B[i]));
            st = nbt_quad_gk(ws, gauss_mom_f, &c, fdim, 0.0, top, 1e-15, 1e-13, r, r + fdim);
            for (size_t k = 0; k <= kmax; k++)
                b[k] = (i == 0 ? 0.0 : b[k]) + p->w[i] * r[k];
        }
    }
    free(r);
    nbt_quad_ws_free(ws);
    return st;
}

double nbt_phase_mean_cosine(const nbt_phase *p)
{
    double b[2];
    if (nbt_phase_moments(p, 1, b) != NBT_OK)
        return NAN;
    return b[1];
}

/* sum_{k > N} (2k+1) x^k = x^{N+1} ((2N+3) - (2N+1) x) / (1-x)^2 */
double nbt_phase_hg_trunc_error(double g, size_t N, nbt_norm norm)
{
    double a = fabs(g), n = (double)N;
    if (!(a < 1.0))
        return NAN;
    if (norm == NBT_NORM_MAX)
        return pow(a, n + 1) * ((2 * n + 3) - (2 * n + 1) * a) / (1.0 + a);
    double x = a * a;
    return sqrt(pow(x, n + 1) * ((2 * n + 3) - (2 * n + 1) * x) / (1.0 + x));
}

size_t nbt_phase_hg_terms(double g, double tol, nbt_norm norm, size_t nmax)
{
    for (size_t N = 0; N <= nmax; N++)
        if (nbt_phase_hg_trunc_error(g, N, norm) <= tol)
            return N;
    return nmax + 1;
}

/* ---- sampling ---- */

double nbt__phase_sample_mu(const nbt_phase *p, double (*uniform)(void *), void *rs)
{
    switch (p->kind) {
    case NBT_PHASE_ISO:
        return 2.0 * uniform(rs) - 1.0;
    case NBT_PHASE_RAYLEIGH: {
        /* CDF (mu^3 + 3 mu + 4)/8: solve the depressed cubic by Cardano */
        double q = 8.0 * uniform(rs) - 4.0, d = sqrt(q * q / 4.0 + 1.0);
        return cbrt(q / 2.0 + d) + cbrt(q / 2.0 - d);
    }
    case NBT_PHASE_HG:
    case NBT_PHASE_HG2: {
        /* HG2: the lobe by its weight, then that lobe's inverse CDF */
        double g = p->kind == NBT_PHASE_HG2 && !(uniform(rs) < p->wmix) ? p->g2 : p->g, u = uniform(rs);
        if (fabs(g) < 1e-6)
            return 2.0 * u - 1.0;
        double f = (1.0 - g * g) / (1.0 - g + 2.0 * g * u);
        double mu = (1.0 + g * g - f * f) / (2.0 * g);
        return mu > 1.0 ? 1.0 : (mu < -1.0 ? -1.0 : mu);
    }
    case NBT_PHASE_GAUSS:
    case NBT_PHASE_SOG: {
        size_t i = 0;
        if (p->n > 1) {
            double u = uniform(rs), c = p->w[0];
            while (i + 1 < p->n && u >= c)
                c += p->w[++i];
        }
        /* theta = |s|, s 2-D Gaussian with per-component variance 2B, given
         * theta < pi: theta^2 is exponential with mean 4B truncated at pi^2,
         * sampled by its inverse CDF (rejecting theta >= pi instead took
         * ~400 draws per sample at B = 1000) */
        double a = -expm1(-NBT_PI * NBT_PI / (4.0 * p->B[i]));
        double th = sqrt(-4.0 * p->B[i] * log1p(-a * uniform(rs)));
        return cos(fmin(th, NBT_PI));
    }
    case NBT_PHASE_TABLE: {
        double u = uniform(rs);
        size_t lo = segment(p->cdf, p->n, u), hi = lo + 1;
        /* within the segment: 2 pi (p0 d + s d^2/2) = u - cdf0, s the slope */
        double p0 = p->p[lo], sl = (p->p[hi] - p->p[lo]) / (p->mu[hi] - p->mu[lo]);
        double c = (u - p->cdf[lo]) / (2.0 * NBT_PI), disc = p0 * p0 + 2.0 * sl * c;
        double d = c > 0 ? 2.0 * c / (p0 + sqrt(disc > 0 ? disc : 0.0)) : 0.0;
        double mu = p->mu[lo] + d;
        return mu > p->mu[hi] ? p->mu[hi] : mu;
    }
    }
    return 1.0;
}

int nbt__phase_sample_param(const nbt_phase *p, nbt_phase_kind *kind, double *param)
{
    if (p->kind == NBT_PHASE_HG) {
        *kind = NBT_PHASE_HG;
        *param = p->g;
        return 1;
    }
    if ((p->kind == NBT_PHASE_GAUSS || p->kind == NBT_PHASE_SOG) && p->n == 1) {
        *kind = NBT_PHASE_GAUSS;
        *param = p->B[0];
        return 1;
    }
    return 0;
}

/* ---- SPEC parsing ---- */

static int parse_double(const char *s, double *out)
{
    char *end;
    errno = 0;
    double v = strtod(s, &end);
    if (end == s || *end != '\0' || errno == ERANGE || !isfinite(v))
        return 0;
    *out = v;
    return 1;
}

static nbt_status read_table_file(const char *path, nbt_phase **out, char *err, size_t errlen)
{
    double *mu, *p;
    size_t n;
    nbt_status st = nbt__read_columns(path, "phase table", "mu p", NULL, &mu, &p, &n, err, errlen);
    if (st != NBT_OK)
        return st;
    errno = 0; /* the constructor returns NULL for bad rows and for no memory (malloc sets ENOMEM) */
    *out = nbt_phase_tabulated(n, mu, p);
    if (!*out && errno == ENOMEM) {
        snprintf(err, errlen, "phase table '%s': out of memory", path);
        st = NBT_ENOMEM;
    } else if (!*out) {
        snprintf(err, errlen,
                 "phase table '%s': need >= 2 rows 'mu p' with mu strictly increasing from -1 to 1 "
                 "and p >= 0, not all zero (got %zu rows)", path, n);
        st = NBT_EFORMAT;
    }
    free(mu);
    free(p);
    return st;
}

nbt_status nbt_phase_parse(const char *spec, nbt_phase **out, char *err, size_t errlen)
{
    *out = NULL;
    double v;
    if (!strcmp(spec, "iso"))
        *out = nbt_phase_iso();
    else if (!strcmp(spec, "rayleigh"))
        *out = nbt_phase_rayleigh();
    else if (!strncmp(spec, "hg:g=", 5)) {
        if (!parse_double(spec + 5, &v) || !(v > -1.0 && v < 1.0)) {
            snprintf(err, errlen, "phase '%s': g must be a number in (-1, 1)", spec);
            return NBT_EDOM;
        }
        *out = nbt_phase_hg(v);
    } else if (!strncmp(spec, "hg2:", 4)) {
        /* hg2:g1=G1,g2=G2,w=W: W HG(G1) + (1 - W) HG(G2) */
        char buf[3][64];
        double g1, g2, w;
        const char *q = spec + 4;
        int ok = 1;
        for (int i = 0; i < 3 && ok; i++) {
            size_t n = strcspn(q, ",");
            ok = n < sizeof buf[i] && (i == 2 ? q[n] == '\0' : q[n] == ',');
            if (ok) {
                memcpy(buf[i], q, n);
                buf[i][n] = '\0';
                q += n + 1;
            }
        }
        ok = ok && !strncmp(buf[0], "g1=", 3) && !strncmp(buf[1], "g2=", 3) && !strncmp(buf[2], "w=", 2) &&
             parse_double(buf[0] + 3, &g1) && parse_double(buf[1] + 3, &g2) && parse_double(buf[2] + 2, &w);
        if (!ok || !(g1 > -1.0 && g1 < 1.0) || !(g2 > -1.0 && g2 < 1.0) || !(w >= 0.0 && w <= 1.0)) {
            snprintf(err, errlen, "phase '%s': expected hg2:g1=G1,g2=G2,w=W with -1 < G1, G2 < 1 and 0 <= W <= 1",
                     spec);
            return NBT_EDOM;
        }
        *out = nbt_phase_hg2(g1, g2, w);
    } else if (!strncmp(spec, "gauss:B=", 8)) {
        if (!parse_double(spec + 8, &v) || !(v > 0.0 && v <= NBT_PHASE_GAUSS_BMAX)) {
            snprintf(err, errlen, "phase '%s': B must be a number in (0, %g]", spec, NBT_PHASE_GAUSS_BMAX);
            return NBT_EDOM;
        }
        *out = nbt_phase_gauss(v);
    } else if (!strncmp(spec, "sog:", 4)) {
        double *w, *B;
        size_t n;
        nbt_status st = nbt__read_columns(spec + 4, "sum-of-Gaussians file", "w B", NULL, &w, &B, &n, err, errlen);
        if (st != NBT_OK)
            return st;
        errno = 0; /* NULL for bad rows and for no memory (malloc sets ENOMEM) */
        *out = nbt_phase_sog(n, w, B);
        int nomem = errno == ENOMEM;
        free(w);
        free(B);
        if (!*out && nomem) {
            snprintf(err, errlen, "phase '%s': out of memory", spec);
            return NBT_ENOMEM;
        }
        if (!*out) {
            snprintf(err, errlen, "phase '%s': need rows 'w B' with w >= 0 (not all 0) and 0 < B <= %g", spec,
                     NBT_PHASE_GAUSS_BMAX);
            return NBT_EFORMAT;
        }
        return NBT_OK;
    } else if (!strncmp(spec, "table:", 6)) {
        if (!spec[6]) {
            snprintf(err, errlen, "phase '%s': expected table:FILE", spec);
            return NBT_EFORMAT;
        }
        return read_table_file(spec + 6, out, err, errlen);
    } else {
        snprintf(err, errlen,
                 "unknown phase '%s': accepted are iso, rayleigh, hg:g=G (-1<G<1), hg2:g1=G1,g2=G2,w=W, gauss:B=B (0<B<=1000), "
                 "table:FILE, sog:FILE",
                 spec);
        return NBT_EFORMAT;
    }
    if (!*out) {
        snprintf(err, errlen, "out of memory");
        return NBT_ENOMEM;
    }
    return NBT_OK;
}
