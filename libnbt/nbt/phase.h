/* nbt/phase.h: phase functions of the scattering angle.
 *
 * Every phase function is normalised over the sphere, int_{4pi} p dw = 1,
 * and is a function of mu = cos(scattering angle). Legendre form:
 *   p(mu) = (1/4pi) sum_k (2k+1) b_k P_k(mu),   b_k = 2pi int_{-1}^{1} p P_k dmu,
 * so b_0 = 1 and b_1 = g, the mean cosine. */
#ifndef NBT_PHASE_H
#define NBT_PHASE_H

#include <stddef.h>
#include <nbt/error.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef enum {
    NBT_PHASE_ISO,       /* 1/4pi */
    NBT_PHASE_HG,        /* Henyey-Greenstein, g in (-1, 1) */
    NBT_PHASE_RAYLEIGH,  /* 3/(16pi) (1 + mu^2) */
    NBT_PHASE_GAUSS,     /* Shinya eq. 13 on the sphere, spread B > 0 (see below) */
    NBT_PHASE_SOG,       /* sum of Gaussians, weights w_i >= 0 summing to 1 */
    NBT_PHASE_TABLE,     /* piecewise linear in mu, normalised on creation */
    NBT_PHASE_HG2        /* two-term HG: w HG(g1) + (1 - w) HG(g2) */
} nbt_phase_kind;

/* Opaque, immutable once created: safe to share between threads. */
typedef struct nbt_phase nbt_phase;

nbt_phase *nbt_phase_iso(void);
nbt_phase *nbt_phase_rayleigh(void);
/* NULL unless -1 < g < 1. */
nbt_phase *nbt_phase_hg(double g);
/* Two-term Henyey-Greenstein, w HG(g1) + (1 - w) HG(g2) (e.g. a forward
 * lobe and a weak backward one); NULL unless -1 < g1, g2 < 1, 0 <= w <= 1. */
nbt_phase *nbt_phase_hg2(double g1, double g2, double w);
/* Gaussian phase function of Shinya et al. eq. 13, p(s) = exp(-|s|^2/4B)/(4 pi B)
 * for the 2-D deflection s, mapped onto the sphere by polar angle theta = |s|
 * (theta >= pi rejected, i.e. renormalised by 1 - exp(-pi^2/4B)):
 *   p(theta) = theta exp(-theta^2/4B) / (4 pi B sin(theta) (1 - exp(-pi^2/4B))).
 * This is exactly what the photon counter samples. The spread is dtheta^2 = 4B.
 * NULL unless 0 < B <= NBT_PHASE_GAUSS_BMAX: at B = 1000 the phase is
 * isotropic to 2.5e-3 and sampling it already rejects 400 draws per photon;
 * beyond, 4B overflows near 1e308 (a fuzzed SPEC gauss:B=1e308 gave NaN). */
#define NBT_PHASE_GAUSS_BMAX 1e3
nbt_phase *nbt_phase_gauss(double B);
/* Sum of n Gaussians: weights w (>= 0, renormalised to sum 1), spreads B (0 < B <= NBT_PHASE_GAUSS_BMAX). */
nbt_phase *nbt_phase_sog(size_t n, const double *w, const double *B);
/* Tabulated p at n >= 2 strictly increasing mu from -1 to 1 (first and last
 * exactly -1 and 1), values >= 0, piecewise linear in mu, renormalised to 1. */
nbt_phase *nbt_phase_tabulated(size_t n, const double *mu, const double *p);

/* Parse a SPEC: "iso", "rayleigh", "hg:g=0.8", "hg2:g1=0.9,g2=-0.3,w=0.8", "gauss:B=0.0685",
 * "table:FILE" (FILE: lines "mu p"), "sog:FILE" (lines "w B": a sum of
 * Gaussians, as nbt-fit phase writes it). In both files a data line is
 * exactly two finite numbers, '#' starts a comment and blank lines are
 * skipped; any other line is an error naming FILE:LINE. On failure returns a
 * status and writes a one-line reason naming the bad value and the accepted
 * range into err (of size errlen). */
nbt_status nbt_phase_parse(const char *spec, nbt_phase **out, char *err, size_t errlen);

void nbt_phase_free(nbt_phase *p);

nbt_phase_kind nbt_phase_get_kind(const nbt_phase *p);
/* A canonical SPEC-like description, e.g. "hg:g=0.8" (tables: "table:N points"). */
const char *nbt_phase_name(const nbt_phase *p);

/* p(mu) per steradian, mu in [-1, 1] (clamped). */
double nbt_phase_eval(const nbt_phase *p, double mu);

/* Legendre moments b_0..b_kmax (closed forms where they exist, otherwise
 * adaptive quadrature to ~1e-13 absolute). */
nbt_status nbt_phase_moments(const nbt_phase *p, size_t kmax, double *b);

/* Mean cosine g = b_1. */
double nbt_phase_mean_cosine(const nbt_phase *p);

/* Legendre polynomials P_0..P_kmax at x, by the three-term recurrence. */
void nbt_legendre_p(size_t kmax, double x, double *P);

/* Truncation error of the HG series kept to orders 0..N, relative, in closed form:
 *   NBT_NORM_MAX: max_mu |p - p_N| / max_mu p   (attained at mu = 1 for g >= 0)
 *   NBT_NORM_L2:  ||p - p_N|| / ||p||           (L2 over the sphere)
 * g in (-1, 1). */
typedef enum { NBT_NORM_MAX, NBT_NORM_L2 } nbt_norm;
double nbt_phase_hg_trunc_error(double g, size_t N, nbt_norm norm);
/* Smallest N with nbt_phase_hg_trunc_error(g, N, norm) <= tol (capped at nmax;
 * returns nmax + 1 when even nmax does not meet tol). */
size_t nbt_phase_hg_terms(double g, double tol, nbt_norm norm, size_t nmax);

#ifdef __cplusplus
}
#endif
#endif
