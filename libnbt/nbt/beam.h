/* nbt/beam.h: narrow beam theory (Ishimaru; Shinya et al. sec. 2-3) for a
 * pencil beam entering a layered medium at the origin along +z.
 *
 * Conventions (doc/beam.md derives each): density rho(z) >= 0 multiplies
 * sigma_t and sigma_s = albedo sigma_t; zeta(z) = int_0^z rho; the phase
 * function is a sum of small-angle Gaussians p(s) = sum_i w_i
 * exp(-|s|^2/4B_i)/(4 pi B_i) (dtheta^2 = 4B_i); the diffusion coefficient
 * is A = rho sigma_s <theta^2>/4 = rho sigma_s B_mix, B_mix = sum w_i B_i
 * (eq. 10; eq. 17's sigma_t is a typo, see beam.md's Conventions). G(x) = erfc(x/sqrt2)/2. */
#ifndef NBT_BEAM_H
#define NBT_BEAM_H

#include <stddef.h>
#include <stdio.h>
#include <nbt/error.h>

#ifdef __cplusplus
extern "C" {
#endif

#define NBT_BEAM_MAX_LOBES 16

typedef struct {
    double sigma_t;          /* extinction at unit density, > 0 */
    double albedo;           /* sigma_s / sigma_t, [0, 1] */
    size_t nlobes;           /* Gaussian lobes, 1..NBT_BEAM_MAX_LOBES */
    double w[NBT_BEAM_MAX_LOBES], B[NBT_BEAM_MAX_LOBES]; /* weights (sum 1), spreads > 0 */
    size_t nlayers;          /* 0: homogeneous, rho = 1 */
    const double *z;         /* layer i is [z[i], z[i+1]) (the last unbounded); z[0] = 0, increasing */
    const double *rho;       /* density per layer, >= 0, finite */
    /* or a continuous density (overrides the layers when set): rho_fn(z) >= 0,
     * integrated by adaptive quadrature (smooth or with few kinks) */
    double (*rho_fn)(double z, void *data);
    void *rho_data;
} nbt_beam_medium;

/* A homogeneous medium with one Gaussian lobe. */
nbt_beam_medium nbt_beam_homogeneous(double sigma_t, double albedo, double B);
/* Checks every field; NBT_EDOM with a reason through the error handler. */
nbt_status nbt_beam_check(const nbt_beam_medium *m);

/* zeta(z) = int_0^z rho. */
double nbt_beam_zeta(const nbt_beam_medium *m, double z);

typedef enum {
    NBT_BEAM_ISHIMARU,   /* eq. 25/26 (homogeneous), eq. 28/29 (layered) */
    NBT_BEAM_SMALLANGLE  /* small-angle random walk: M2 = e^{-sa zeta} int 4 B sigma_s rho(y) (z-y)^2 dy */
} nbt_beam_model;

/* Moments of the scattered light on the plane z >= 0: M0 = int int I_d ds dr,
 * M2 = int int |r|^2 I_d ds dr. Closed forms for homogeneous media, a line
 * integral (adaptive, error in *err, may be NULL) for layers. */
nbt_status nbt_beam_moments(const nbt_beam_medium *m, nbt_beam_model model, double z, double *M0,
                            double *M2, double *err);

/* Heuristic kernel Psi(z, r) = alpha/r G(r/beta) reproducing M0 and M2:
 * beta^2 = (3/2) M2/M0, alpha = M0/(sqrt(2 pi) beta)  (M0 = 0: alpha = beta = 0). */
void nbt_beam_kernel_params(double M0, double M2, double *alpha, double *beta);
double nbt_beam_kernel(double alpha, double beta, double r);

/* Psi by model at (z, r > 0), per unit area:
 *   KERNEL_*  the heuristic kernel from that model's moments
 *   LINEINT   int I_d ds of eq. 16, done analytically in s, leaving a line integral in z'
 *   SINGLE    single scattering Psi_1 (homogeneous: eq. 32 corrected,
 *             sigma_s e^{-tau}/(2 sqrt(pi B)) (1/r) G(r/(z sqrt(2B))) per lobe)
 *   ELEK      Elek et al. eq. 2: M0 exp(-r^2/2W^2)/(2 pi W^2),
 *             W(s)^2 = 1/2 (2 sigma_a/(3s) + 4/(s^3 sigma_s (1-g)))^-1, s = z, g the mean cosine
 * err (may be NULL) gets the quadrature error of LINEINT / layered SINGLE. */
typedef enum {
    NBT_PSI_ISHIMARU,
    NBT_PSI_SMALLANGLE,
    NBT_PSI_LINEINT,
    NBT_PSI_SINGLE,
    NBT_PSI_ELEK
} nbt_psi_model;

nbt_status nbt_beam_psi(const nbt_beam_medium *m, nbt_psi_model model, double z, double r, double *psi,
                        double *err);

/* A smooth correction of the moment kernel (fitted by nbt-fit kernel
 * --correction): log(beta/beta_m) = sum beta[i] t_i, log(alpha/alpha_m) =
 * sum alpha[i] t_i, t = (1, x, x^2, a, a x, b, b x), x = ln(sigma_t z) the
 * optical depth's log, a the albedo, b = ln B (B_mix for several lobes). */
#define NBT_KERNEL_CORR_TERMS 7
typedef struct {
    double beta[NBT_KERNEL_CORR_TERMS], alpha[NBT_KERNEL_CORR_TERMS];
} nbt_kernel_correction;

void nbt_kernel_correction_terms(double tau, double albedo, double B, double *t);
/* Corrected alpha, beta of a homogeneous medium at depth z (c == NULL: the moment kernel). */
nbt_status nbt_kernel_corrected(const nbt_kernel_correction *c, const nbt_beam_medium *m, double z, double *alpha,
                                double *beta);
/* Read the file nbt-fit writes: one 'beta' and one 'alpha' line of exactly 7
 * finite numbers; '#' comments and blank lines skipped; any other line is an
 * error naming the file and the line. */
nbt_status nbt_kernel_correction_read(const char *path, nbt_kernel_correction *c, char *err, size_t errlen);

/* The fitted kernel model (doc/fit.md, "A kernel model over the parameter
 * space"): a core plus a diffuse part, in sigma_t = 1 units (tau = sigma_t z,
 * rh = sigma_t r; Psi = sigma_t^2 Psi_hat(tau, rh)):
 *   Psi_hat = a/rh G(rh/b) + M e^{-(q - h)/s} / (2 pi s (h + s)),  q = sqrt(rh^2 + h^2),
 *   sqrt(2 pi) a b = T e^{P0},  b = L e^{P1},  M = T e^{P2},  s = L e^{P3},  h = s e^{P4},
 * T = e^{-(1-albedo) tau}(1 - e^{-albedo tau}) (eq. 25's M0), L = tau sqrt(2B)
 * (single scattering's width), B = B_mix. The core carries sqrt(2 pi) a b and
 * the diffuse part M; the diffuse part is exponential in rh for h << s and
 * Gaussian (variance h s) for h >> s. Each P_i = sum_k c[i][k] t_k over the
 * monomials t of nbt_beam_fit_terms. One coefficient set per geometry: 0 a
 * beam entering a half-space from vacuum, 1 a source inside an infinite
 * medium (nbt-fit mc --infinite). Fitted by nbt-fit model to photon counts;
 * the compiled-in default's range and measured error are in doc/fit.md. */
#define NBT_BEAM_FIT_PARTS 5
#define NBT_BEAM_FIT_TERMS 16
typedef struct {
    double c[2][NBT_BEAM_FIT_PARTS][NBT_BEAM_FIT_TERMS]; /* [geometry][P0..P4][term] */
    int have[2];                         /* the geometries this model holds */
    /* the fitted data's range of tau, albedo and B: the monomials clamp their
     * arguments to it, so that outside it the P_i stay at their edge values
     * (a cubic would run away) while T and L keep their exact scaling;
     * lo >= hi: no clamp */
    double range[3][2];
} nbt_beam_fit;

/* The monomials: with x = ln tau - 1.15, w = albedo - 0.5, v = ln(B/0.05)
 * (tau, albedo, B clamped to f's range; f may be NULL: no clamp):
 * 1, x, w, v, x^2, xw, xv, w^2, wv, v^2, x^3, x^2w, x^2v, xw^2, xwv, xv^2. */
void nbt_beam_fit_terms(const nbt_beam_fit *f, double tau, double albedo, double B, double *t);
/* The model shipped with libnbt (fitted by kernelmodel.sh, installed in PREFIX/share/nbt/scripts). */
const nbt_beam_fit *nbt_beam_fit_default(void);
/* p = (a, b, M, s, h) of Psi_hat at tau > 0, albedo in [0, 1], B > 0
 * (NBT_EDOM outside, or for a geometry the model does not hold). */
nbt_status nbt_beam_fit_params(const nbt_beam_fit *f, int infinite, double tau, double albedo, double B, double *p);
/* The same from the log-parameters P0..P4 (e.g. read from nbt-gen kernel --model fitted's tables). */
void nbt_beam_fit_from_P(const double *P, double tau, double albedo, double B, double *p);
/* Psi_hat(rh) from p (rh > 0; 0 at rh <= 0, where the core is infinite). */
double nbt_beam_fit_eval(const double *p, double rh);
/* Psi(z, r) of medium m (one or more lobes: B = B_mix). Layered or continuous
 * density: the homogeneous model at the equivalent depth zeta(z) (which has
 * eq. 28's M0), its widths scaled by lambda (nbt_beam_fit_equivalent):
 * Psi(z, r) = Psi_hom(zeta, r/lambda)/lambda^2; 0 where zeta(z) = 0. Fitted
 * to homogeneous runs only: see doc/fit.md for its measured error in layers
 * (2-11% on three profiles). */
nbt_status nbt_beam_fit_psi(const nbt_beam_fit *f, int infinite, const nbt_beam_medium *m, double z, double r,
                            double *psi);
/* zeta(z) and lambda = sqrt(M2(z) / M2_hom(zeta)) of m, M2 the small-angle
 * random walk's (NBT_BEAM_SMALLANGLE; closer to layered photon counts than
 * eq. 29 / 26 here); homogeneous: z and 1; exact for a constant density rho,
 * where lambda = 1/rho. */
nbt_status nbt_beam_fit_equivalent(const nbt_beam_medium *m, double z, double *zeta, double *lambda);
/* Read / write the text form nbt-fit model writes: lines 'half P0 c_0 .. c_15'
 * (P0..P4, and 'infinite P0 ..'), 'range tau|albedo|B LO HI', '#' comments. Read: err gets one line. */
nbt_status nbt_beam_fit_read(const char *path, nbt_beam_fit *f, char *err, size_t errlen);
nbt_status nbt_beam_fit_fprint(FILE *fp, const nbt_beam_fit *f, const char *comment);

/* Read a layered density profile: lines "z rho" (exactly two finite
 * numbers; '#' starts a comment, blank lines are skipped, any other line is
 * an error), z increasing from exactly 0, rho >= 0; layer i is
 * [z_i, z_{i+1}), the last unbounded. On success *z and *rho are malloc'd (free both) and *n >= 1;
 * on failure err holds one line naming the file, the line and what is
 * accepted. */
nbt_status nbt_density_read(const char *path, double **z, double **rho, size_t *n, char *err, size_t errlen);

/* The unscattered (direct) part on plane z: a delta at r = 0 of weight exp(-tau(z)). */
double nbt_beam_direct(const nbt_beam_medium *m, double z);

#ifdef __cplusplus
}
#endif
#endif
