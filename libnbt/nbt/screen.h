/* nbt/screen.h: screen-space multiple scattering references. A rendered
 * image c(x) (linear RGB) with the distance D(x) along each pixel's view ray
 * becomes the image seen through a homogeneous medium,
 *     J(x) = T(x) c(x) + S(x),   T = exp(-sigma_t D),
 * where S, the scattered part, is one of two operators (doc/screenspace.md):
 *
 *   NBT_SCREEN_NEAR   (operator A, Shinya et al. eq. 37-39): every ordered
 *       pair of pixels (x receives from y, y = x included) exchanges light
 *       through the kernel of the nearer of the two, evaluated at the nearer
 *       depth, at lateral distance D_near * dtheta * |x - y|, integrated over
 *       pixel y's footprint;
 *   NBT_SCREEN_SOURCE (operator B, Elek et al.): every source pixel spreads
 *       its own kernel, whatever the receiver's depth.
 *
 * Conventions: pixels are squares of constant angle dtheta = 2 tan(fov_y/2)/H;
 * a kernel at depth D seen from the camera spans D*dtheta per pixel. Sky
 * pixels (D infinite, or >= NBT_SCREEN_SKY) lie behind infinite medium:
 * T = 0 and they send nothing (their kernel's mass is spread over an infinite
 * area), but they receive from nearer pixels. D = 0 gives T = 1, S = 0.
 *
 * Kernels are radially symmetric and written as a few "atoms": the
 * narrow-beam shape alpha/r G(r/beta) (G(x) = erfc(x/sqrt 2)/2) and unit
 * Gaussians. Since (1/r) G(r/beta) = sqrt(2 pi) int_0^beta N(r; s) ds, with N
 * a unit-mass 2-D Gaussian of deviation s, both integrate over a square
 * pixel in closed form per deviation (products of erf differences), and the
 * erfc atom by Gauss-Legendre quadrature in s on octave panels. */
#ifndef NBT_SCREEN_H
#define NBT_SCREEN_H

#include <stddef.h>
#include <nbt/beam.h>
#include <nbt/error.h>
#include <nbt/phase.h>

#ifdef __cplusplus
extern "C" {
#endif

/* Depths at or beyond this (Blender writes 1e10 for the background) are sky. */
#define NBT_SCREEN_SKY 1e10

#define NBT_SCREEN_MAX_ATOMS 128

typedef enum {
    NBT_ATOM_ERFC,  /* mass * (1/(sqrt(2 pi) scale r)) G(r/scale): the kernel alpha/r G(r/beta), scale = beta */
    NBT_ATOM_GAUSS  /* mass * exp(-r^2 / 2 scale^2) / (2 pi scale^2) */
} nbt_atom_shape;

/* A kernel at one depth, lengths in world units. mass is the fraction of a
 * source's radiance that arrives scattered (int Psi dA); T the direct part. */
typedef struct {
    double T;
    size_t n;
    nbt_atom_shape shape[NBT_SCREEN_MAX_ATOMS];
    double mass[NBT_SCREEN_MAX_ATOMS], scale[NBT_SCREEN_MAX_ATOMS];
} nbt_screen_kern;

typedef enum {
    NBT_SKERNEL_MOMENT,     /* alpha/r G(r/beta) from eq. 25/26 moments (nbt_beam_moments, ISHIMARU) */
    NBT_SKERNEL_SMALLANGLE, /* the same shape from the small-angle random walk's moments */
    NBT_SKERNEL_CORRECTED,  /* the moment kernel with an nbt-fit correction (nbt_kernel_corrected) */
    NBT_SKERNEL_SINGLE,     /* single scattering Psi_1 (one erfc atom per lobe) */
    NBT_SKERNEL_LINEINT,    /* the eq. 16 line integral: Gaussians at Gauss-Legendre nodes in depth */
    NBT_SKERNEL_ELEK,       /* Elek et al.: one Gaussian of deviation W(D), mass M0 (g = the lobes' mean cosine) */
    NBT_SKERNEL_FITTED,     /* for a phase (nbt_screen_kernel_phase): the first order exactly plus a fitted
                             * model's higher orders (nbt_screen_model) */
    NBT_SKERNEL_FIRST       /* for a phase: the first order exactly, nothing more */
} nbt_skernel_kind;

/* A built-in kernel family over depth, or a caller's. */
typedef struct nbt_screen_kernel nbt_screen_kernel;
typedef nbt_status (*nbt_screen_kernel_fn)(double D, nbt_screen_kern *out, void *ctx);

/* medium: homogeneous (nlayers = 0, no rho_fn); corr: only for CORRECTED
 * (copied). NULL on a bad medium (reason through the error handler) or no
 * memory. */
nbt_screen_kernel *nbt_screen_kernel_alloc(nbt_skernel_kind kind, const nbt_beam_medium *medium,
                                           const nbt_kernel_correction *corr);
/* fn(D, out, ctx) for 0 < D < infinity fills T and the atoms. */
nbt_screen_kernel *nbt_screen_kernel_custom(nbt_screen_kernel_fn fn, void *ctx);
void nbt_screen_kernel_free(nbt_screen_kernel *k);
/* The kernel at distance D (>= 0, INFINITY or >= NBT_SCREEN_SKY for sky). */
nbt_status nbt_screen_kernel_eval(const nbt_screen_kernel *k, double D, nbt_screen_kern *out);
/* "moment", "smallangle", "corrected", "single", "lineint", "elek", "fitted", "first"; parse: NBT_EINVAL for others. */
const char *nbt_skernel_name(nbt_skernel_kind kind);
nbt_status nbt_skernel_parse(const char *name, nbt_skernel_kind *kind);

/* ---- kernels built for a phase function ----
 *
 * The camera sees a wall at distance D through a homogeneous medium
 * (sigma_t, albedo, any phase p). A kernel is then a radial function on the
 * wall: the fraction of the wall's radiance at lateral distance r that
 * reaches the pixel scattered, per unit area. Geometry:
 *   NBT_SCREEN_INSIDE    the camera is inside the medium (fog around it; light
 *                        may scatter behind the camera and come back),
 *   NBT_SCREEN_ENTERING  the medium begins at the camera (vacuum behind it).
 * Only the first time a light path meets the wall counts (the wall absorbs).
 *
 * The first scattering order is exact for any phase (a line integral over
 * depth at the true scattering angle, with the longer oblique path's
 * attenuation; no small-angle step): its cumulative radial mass is one
 * integral over the scattering angle, fitted as a non-negative mixture of
 * atoms on the slot grid below (relative L1 error of its radial masses
 * ~1e-5) at optical depths 2^(i/4) and interpolated in log depth between
 * them, with its total mass exact at every depth (to ~1e-7 relative;
 * tested at optical depths 0.003 to 11.3). Higher orders come from a
 * model fitted to photon counts (nbt_mc_kernel_run) for the phase's family,
 * interpolated over its parameter, the albedo and the optical depth.
 *
 * Shapes: masses of atoms whose scales are s_m = 2^(m/2) times a reference
 * length (the depth D), m = NBT_SCREEN_SLOT_LO..NBT_SCREEN_SLOT_HI, one
 * ERFC and one GAUSS atom per slot. */
#define NBT_SCREEN_SLOT_LO (-34)
#define NBT_SCREEN_SLOT_HI 22
#define NBT_SCREEN_NSLOTS (NBT_SCREEN_SLOT_HI - NBT_SCREEN_SLOT_LO + 1)

typedef enum { NBT_SCREEN_INSIDE = 0, NBT_SCREEN_ENTERING = 1 } nbt_screen_geometry;

typedef struct {
    double erfc[NBT_SCREEN_NSLOTS], gauss[NBT_SCREEN_NSLOTS]; /* index m - NBT_SCREEN_SLOT_LO */
} nbt_screen_shape;

/* s_m = 2^(m/2). */
double nbt_screen_slot_scale(int m);

/* Fits a shape to radial masses (NNLS; every atom non-negative): mass[b] is
 * the mass in the annulus [e_{b-1}, e_b) of radii in units of the reference
 * length (bin 0 from 0, bin nedges to infinity), se[b] its standard error
 * (NULL: exact data, fitted to relative accuracy per bin). slot_step 1 uses
 * every slot, 2 the whole octaves only. The total mass is kept (to ~1e-6).
 * *misfit (may be NULL): sum |fit - mass| / sum mass over the bins. */
nbt_status nbt_screen_shape_fit(size_t nedges, const double *edges, const double *mass, const double *se,
                                int slot_step, nbt_screen_shape *out, double *misfit);

/* Mass of a unit atom in the annulus a0 <= r/scale < a1 (a1 may be inf). */
double nbt_screen_atom_mass(nbt_atom_shape shape, double a0, double a1);
/* Mass of a shape in the annulus lo <= r < hi (units of its reference length; hi may be inf). */
double nbt_screen_shape_mass(const nbt_screen_shape *s, double lo, double hi);

/* A fitted model of the higher scattering orders (2, 3, ...) for a family of
 * phase functions: shapes on a grid of (family parameter, albedo, optical
 * depth), both geometries, from photon counts (nbt-fit screenmodel). The
 * family is "hg" (parameter g) or one fixed phase (no parameter; a phase is
 * recognised by its values). Immutable: safe to share between threads. */
typedef struct nbt_screen_model nbt_screen_model;
/* The model libnbt ships: HG, g in [0, 0.95], both geometries (doc/screenspace.md
 * gives its range and measured error). */
const nbt_screen_model *nbt_screen_model_default(void);
/* Reads the text form nbt-fit screenmodel writes; err gets one line naming the file and line. */
nbt_status nbt_screen_model_read(const char *path, nbt_screen_model **out, char *err, size_t errlen);
void nbt_screen_model_free(nbt_screen_model *m);
/* NBT_OK when m covers phase p in geometry geo; else NBT_EDOM with a one-line
 * reason in err naming what the model holds (its family and range). */
nbt_status nbt_screen_model_covers(const nbt_screen_model *m, const nbt_phase *p, nbt_screen_geometry geo, char *err,
                                   size_t errlen);
/* The higher orders at optical depth tau > 0 for phase p and albedo a:
 * atom masses (fractions of the source's radiance) on the slots, reference
 * length = the depth. Outside the fitted range of tau and albedo the model
 * holds its edge shapes and scales the mass (doc/screenspace.md);
 * *extrapolated (may be NULL) says when it did. */
nbt_status nbt_screen_model_eval(const nbt_screen_model *m, const nbt_phase *p, nbt_screen_geometry geo, double albedo,
                                 double tau, nbt_screen_shape *out, int *extrapolated);

/* Building a model (nbt-fit screenmodel): a grid over the family parameter
 * (g for the HG family; fixed != NULL: that phase alone, param ignored),
 * the albedo (in (0, 1)) and the optical depth (two or more), all
 * increasing; then each node's higher-order masses (absolute: the shape's
 * sum is the node's mass), geometry by geometry. Interpolation: linear in
 * -ln(1 - g), -ln(1 - albedo) and ln(tau) of the normalised shapes and of
 * the log masses. write: the text form, via a temporary file. */
nbt_screen_model *nbt_screen_model_alloc(const nbt_phase *fixed, size_t np, const double *param, size_t na,
                                         const double *albedo, size_t nt, const double *tau);
nbt_status nbt_screen_model_set(nbt_screen_model *m, nbt_screen_geometry geo, size_t ip, size_t ia, size_t it,
                                const nbt_screen_shape *masses);
nbt_status nbt_screen_model_write(const nbt_screen_model *m, const char *path, const char *comment, char *err,
                                  size_t errlen);

/* The kernel family for a phase: kind NBT_SKERNEL_FITTED (first order +
 * model; model NULL: nbt_screen_model_default()), NBT_SKERNEL_FIRST (the
 * first order only; model ignored) or NBT_SKERNEL_ELEK (Elek et al.'s
 * Gaussian width with g = the phase's mean cosine, carrying the FITTED
 * kernel's whole mass). p must outlive the kernel. NULL with a
 * reason through the error handler on bad arguments or when the model does
 * not cover p. */
nbt_screen_kernel *nbt_screen_kernel_phase(nbt_skernel_kind kind, double sigma_t, double albedo, const nbt_phase *p,
                                           nbt_screen_geometry geo, const nbt_screen_model *model);

/* ---- colour: a kernel per channel ---- */

/* One kernel per channel (RGB media: sigma_t, albedo or phase per channel).
 * Takes ownership of r, g, b (freed with the result, also on failure). */
nbt_screen_kernel *nbt_screen_kernel_rgb(nbt_screen_kernel *r, nbt_screen_kernel *g, nbt_screen_kernel *b);
/* 1 for a kernel that is the same in every channel, 3 for an RGB kernel. */
unsigned nbt_screen_kernel_channels(const nbt_screen_kernel *k);
/* The kernel of channel ch (0, 1, 2) at distance D; for a grey kernel every
 * channel is the same. nbt_screen_kernel_eval is channel 0. */
nbt_status nbt_screen_kernel_eval_ch(const nbt_screen_kernel *k, unsigned ch, double D, nbt_screen_kern *out);

/* The weight a kernel of total mass 1 and one atom (shape, scale in pixels)
 * gives to the pixel at integer offset (dx, dy): its integral over that
 * pixel's unit square. The building block of every operator; exported for
 * tests and for fitting GPU approximations. */
double nbt_screen_atom_pixel(nbt_atom_shape shape, double scale_px, long dx, long dy);

/* Radius in pixels (integer, >= 0) beyond which a unit-mass atom of this
 * shape and scale leaves less than tail outside (0 < tail < 1). */
long nbt_screen_atom_radius(nbt_atom_shape shape, double scale_px, double tail);

typedef enum { NBT_SCREEN_NEAR, NBT_SCREEN_SOURCE } nbt_screen_rule;

/* A moment kernel of one pixel (heterogeneous media): transmittance,
 * scattered mass and beta in pixels. */
typedef struct {
    double T, M0, beta_px;
} nbt_screen_pixkern;

typedef struct {
    size_t w, h;
    const float *rgb;     /* c: rgb[(y*w + x)*3 + ch] */
    const float *D;       /* distance along the ray, >= 0 (sky: see above); orders the pixels */
    double dtheta;        /* pixel angle in radians, > 0 */
    const nbt_screen_pixkern *pix; /* NULL: kernels from the family over D; else one per pixel
                                      (nbt_screen_medium_kernels), and the family may be NULL */
} nbt_screen_input;

/* Checks sizes, dtheta and every depth (finite >= 0, or sky); NBT_EDOM with
 * the first bad pixel named through the error handler. */
nbt_status nbt_screen_check(const nbt_screen_input *in);

/* Brute force, any depth map: S (w*h*3 doubles) and, if T != NULL, the
 * transmittance per pixel. Each kernel is truncated where less than tail
 * (e.g. 1e-7) of its mass lies outside. O(N R^2): small images. Threads:
 * 0 = all cores; the result depends on the thread count only in round-off. */
nbt_status nbt_screen_brute(const nbt_screen_input *in, const nbt_screen_kernel *k, nbt_screen_rule rule,
                            double tail, unsigned nthreads, double *S, double *T);

/* The same operator by FFT convolution, exact for layered depth: the depth
 * map may take at most max_layers distinct values (sky counts as one). Same
 * truncation as nbt_screen_brute, so the two agree to round-off.
 * NBT_EDOM if the depth map has more layers. */
nbt_status nbt_screen_layered(const nbt_screen_input *in, const nbt_screen_kernel *k, nbt_screen_rule rule,
                              double tail, size_t max_layers, unsigned nthreads, double *S, double *T);

/* An approximation for continuous depth: out[i] = D[i] snapped to one of L
 * layers (L >= 2) log-spaced between the nearest and the farthest finite
 * non-zero distance (0 and sky unchanged), so that nbt_screen_layered with
 * max_layers = L + 2 applies. The error falls as 1/L (doc/screenspace.md).
 * L < 2 (no snapping possible), or a map with one finite non-zero depth:
 * out = D unchanged. */
void nbt_screen_quantize(const float *D, size_t n, size_t L, float *out);

/* Scores of a scattered part S against a reference (both w*h*3). */
typedef struct {
    double rel_l1;   /* sum |S - R| / sum |R| */
    double rel_rms;  /* sqrt(sum (S - R)^2 / sum R^2) */
    double edge;     /* rel_rms over the band around depth discontinuities (0 if none) */
    double bias;     /* sum S / sum R - 1 */
    double max;      /* max |S - R| / max |R| */
    size_t edge_pixels;
} nbt_screen_metrics;

/* The band: pixels within 2 kernel radii (the larger beta or sigma, in
 * pixels, of the two sides) of an edge between 4-neighbours whose depths
 * differ by more than 5% of the nearer one (either side sky counts). */
nbt_status nbt_screen_compare(const nbt_screen_input *in, const nbt_screen_kernel *k, const double *S,
                              const double *ref, nbt_screen_metrics *m);

/* ---- heterogeneous media (Shinya et al. eq. 28/29) ---- */

/* Density at a world point (>= 0; multiplies sigma_t and sigma_s). */
typedef double (*nbt_density_fn)(const double p[3], void *ctx);

/* A pinhole camera: position, view direction, up (need not be unit or
 * orthogonal to fwd). Row 0 of the image is at the top (towards up). */
typedef struct {
    double pos[3], fwd[3], up[3];
} nbt_camera;

/* The moment kernel of every pixel through the density: each view ray is
 * a beam from its surface (distance D) to the camera, zeta(z') = int rho
 * along it (trapezoid rule, steps of at most `step` world units), M0 by
 * eq. 28, M2 by eq. 29 (trapezoid), then beta^2 = 1.5 M2/M0 and
 * T = exp(-sigma_t zeta(D)). m gives sigma_t, albedo and the lobes (its
 * layers are ignored). A sky pixel i is a beam from sky_D[i], where the
 * medium ends along its ray (e.g. nbt_grid_exit); sky_D NULL: sky pixels
 * lie behind infinite medium (T = 0, nothing sent). *max_err (may be NULL)
 * gets the largest relative change of M0 or M2 between step and 2 step,
 * over pixels (an estimate of the discretisation error). */
nbt_status nbt_screen_medium_kernels(const nbt_screen_input *in, const nbt_beam_medium *m, nbt_density_fn rho,
                                     void *ctx, const nbt_camera *cam, double step, const float *sky_D,
                                     unsigned nthreads, nbt_screen_pixkern *pix, double *max_err);

/* The unit direction of pixel (x, y)'s view ray. */
void nbt_camera_ray(const nbt_camera *cam, size_t w, size_t h, double dtheta, size_t x, size_t y, double dir[3]);

/* Distance along the ray from planar depth Z (along the view axis) for a
 * pinhole camera with pixel pitch dtheta on the unit-distance image plane,
 * centred: D = Z sqrt(1 + u^2 + v^2). Sky stays sky. */
double nbt_screen_ray_distance(double Z, size_t w, size_t h, double dtheta, size_t x, size_t y);

#ifdef __cplusplus
}
#endif
#endif
