/* nbt/gl_scatter.h: screen-space multiple scattering on the GPU (GLSL 4.3
 * compute shaders), the fast counterparts of libnbt's CPU references
 * (nbt/screen.h, operators A and B; SCREENSPACE.md). Needs a current
 * OpenGL >= 4.3 context for every call that takes an nbt_gls or runs.
 *
 * Input per image: linear RGB c and, per pixel, the kernel libnbt computes
 * (nbt_screen_kernel_eval): M0 (the scattered mass; for Elek the mass to
 * blur e^{-sigma_a D}(1 - e^{-sigma_s D}), the same number), beta_px (the
 * erfc kernel's beta in pixels, beta / (D dtheta)), optionally sigma_px
 * (a Gaussian's deviation in pixels, W / (D dtheta)), and the distance D
 * (>= 0; D >= NBT_SCREEN_SKY or +inf is sky) for the nearer-pixel rule.
 * Output: the scattered part S only; the caller adds T c.
 *
 * Methods:
 *   NBT_GLS_SHINYA          operator A (nearer pixel's kernel, lateral
 *       distance at the nearer depth, ties once, own pixel integrated) by a
 *       windowed gather: near offsets (max(|dx|,|dy|) <= 2) from a table of
 *       nbt_screen_atom_pixel over log2 beta_px (NBT_GLS_LUT_*), farther
 *       ones the far-field value plus its pixel-average (laplacian/24)
 *       term, inside |x - y| <= cut * beta_px of the nearer kernel. Errors
 *       against operator A: the window's lost mass (1e-3 at cut = 3, 1e-6
 *       at 5), the table's linear interpolation (at most 6.2e-5 of the mass
 *       over the 25 near pixels), the far field (< 8e-5), float rounding
 *       (~1e-6); measured relative L1 7e-4 .. 9.4e-4 at cut = 3 on the
 *       test's scenes. beta_px = 0 with M0 > 0 is a kernel without spread
 *       (M0 on the own pixel).
 *   NBT_GLS_SHINYA_LITERAL  Shinya et al. Alg. 1-4 as printed (errors 1-6 of
 *       SCREENSPACE.md's table reproduced; see nbt_scatter_literal.glsl).
 *       Its S is not even dimensionally a radiance; for measurements only.
 *       cut is ignored (the printed cut_off = 1).
 *   NBT_GLS_NAIVE           one Gaussian pyramid of M0 c, one bilinear read
 *       per receiver at the level of its own width (linear between levels);
 *       leaks across depth edges (no masks).
 *   NBT_GLS_ELEK            Elek et al. eq. 3-12 (eq. 4 corrected): masked
 *       pyramid with smoothstep width eps, luminance-weighted W, level from
 *       the blurred W map, linear-bicubic reads.
 *   NBT_GLS_NBT             our approximation of operator A (nbt_scatter_nbt*.glsl):
 *       the erfc kernel is fitted, per beta, as non-negative weights over
 *       NBT_GLS_NBT_NB pyramid kernels U^l [B] D^l, l = 1..K (D: the 4-tap
 *       decimation, U: one bilinear octave up-step, B: an optional 3x3 blur
 *       [b, 1-2b, b]^2 at level l, b = NBT_GLS_NBT_BLUR, which puts a kernel
 *       half-way between two octaves) and NBT_GLS_NBT_NW wide kernels (three
 *       Gaussian blurs at level K, nbt_scatter_nbtwide.glsl: they reach
 *       about 1300 px, the pyramid's own about 150), plus exact 3x3 centre taps (the
 *       kernel's pixel integrals minus the pyramid's phase-averaged spill
 *       there). Depth slabs (NBT_GLS_NBT_SLABS, log-spaced over the finite
 *       depths; sky is one more): a receiver in slab i takes the centre taps
 *       by the exact nearer-pixel rule, the pyramid scatter of the sources
 *       in slabs <= i with their own kernels, and the pyramid gather, with
 *       its own kernel, of slabs > i (sky included). Kernel weights per slab
 *       are taken at the slab's middle log2 beta with a first-order
 *       correction in each pixel's log2 beta (source side: an extra
 *       pyramid of delta M0 c; receiver side: an extra collapse). Pairs
 *       within one slab go through the source's kernel; the receiver
 *       subtracts an estimate of what that adds over the nearer pixel's
 *       kernel (a march along its depth profile, nbt_scatter_nbt.glsl:
 *       first order in the kernel's change, strips whole across the line,
 *       so a kernel wider than the screen's sides is over-corrected). The
 *       approximation: that estimate, the fitted kernel shapes (misplaced mass 4-9% of the kernel's own for
 *       beta = 1 .. 30 px, tests/test_gl_scatter.c; total mass within
 *       +0.01 .. +1.0% of the kernel's for beta = 1 .. 200 px) and the second order in
 *       delta log2 beta. Weights are fitted (NNLS) for beta_px in
 *       [2^NBT_GLS_NBT_LO, 2^NBT_GLS_NBT_HI], held below and scaled by
 *       1/beta above (light a kernel sends beyond the pyramid's reach, as
 *       beyond the screen, is lost, as in operator A).
 * The pyramid methods use sigma_px when given, otherwise the Gaussian of the
 * same second moment as the erfc kernel, sigma = beta_px / sqrt 3. Pyramids
 * have NBT_GLS_K + 1 levels over the image padded with zeros to a multiple
 * of 2^NBT_GLS_K; every method drops light that leaves the screen, none
 * renormalises.
 *
 * Bilinear fetches (naive, Elek) use the texture unit: Mesa's llvmpipe
 * weights in float; many GPUs quantise the weights to 8 bits, which moves S
 * by up to ~1/256 of a texel step. */
#ifndef NBT_GL_SCATTER_H
#define NBT_GL_SCATTER_H

#include <stddef.h>
#include <nbt/error.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef enum {
    NBT_GLS_SHINYA,
    NBT_GLS_SHINYA_LITERAL,
    NBT_GLS_NAIVE,
    NBT_GLS_ELEK,
    NBT_GLS_NBT
} nbt_gls_method;
#define NBT_GLS_NMETHODS 5

typedef struct {
    size_t w, h;
    const float *rgb;      /* c: rgb[(y*w + x)*3 + ch], finite */
    const float *D;        /* distance along the ray, >= 0; sky: >= 1e10 or +inf */
    const float *M0;       /* scattered mass, >= 0 (0 for sky and D = 0) */
    const float *beta_px;  /* erfc kernel beta in pixels, >= 0 */
    const float *sigma_px; /* Gaussian deviation in pixels (naive, Elek), >= 0; NULL: beta_px/sqrt 3 */
    double dtheta;         /* pixel pitch in radians (literal only: the 3-D distance), > 0 */
    double cut;            /* shinya: window radius in beta, > 0 (NBT_GLS_CUT) */
    double eps;            /* Elek: smoothstep width over the threshold, >= 0 (0: a step; NBT_GLS_EPS) */
} nbt_gls_input;

#define NBT_GLS_CUT 3.0  /* drops 1e-3 of each kernel's mass; 5.0: 1e-6 */
#define NBT_GLS_EPS 0.1  /* Elek et al. leave it open; > 0.1 loses light (the mask rises above T) */
#define NBT_GLS_K 6      /* pyramid levels above the image (Elek et al.: K = 6) */
#define NBT_GLS_ELEK_C 0.8        /* Elek et al. eq. 10 (B-spline reads: sigma_k -> 0.768 2^k) */
#define NBT_GLS_NAIVE_C 0.6506407 /* bilinear reads: sigma_k -> sqrt(0.77/3 + 1/6) 2^k */

/* The near-field table: entry i at beta_px = 2^(LO + i/PER), 8 floats
 * (a00, a10, a11, a20, a21, a22, 0, 0), a(dx, dy) the weight a unit erfc
 * atom gives to the pixel at that offset (nbt_screen_atom_pixel). */
#define NBT_GLS_LUT_LO (-5)
#define NBT_GLS_LUT_PER 32
#define NBT_GLS_LUT_N (18 * NBT_GLS_LUT_PER + 1) /* up to beta = 8192 px; scaled by 1/beta beyond */

/* Fills lut[NBT_GLS_LUT_N * 8]. */
void nbt_gls_near_table(float *lut);

/* NBT_GLS_NBT: the fit. Basis kernel b < K is level b + 1, K <= b < 2K
 * level b - K + 1 with the blur, b = 2K + m level K with the wide blur m
 * (nbt_gls_nbt_wide_taps): the pyramid's own kernels stop at about 150
 * px, where an erfc kernel of beta = 100 px still has 7% of its mass, so
 * without them wide kernels lost light on screen (-0.9% on 320x240 scenes).
 * Weights tabulated at log2 beta_px = LO + i / PER, i < N, linear in between. */
#define NBT_GLS_NBT_NW 3
#define NBT_GLS_NBT_NB (2 * NBT_GLS_K + NBT_GLS_NBT_NW)
#define NBT_GLS_NBT_WT 18
#define NBT_GLS_NBT_BLUR 0.16
#define NBT_GLS_NBT_LO (-1)
#define NBT_GLS_NBT_HI 14 /* 16384 px: the fit window (r <= 1344 px) is in the 1/r regime (G 6.5% below G(0) at its edge) */
#define NBT_GLS_NBT_PER 4
#define NBT_GLS_NBT_N ((NBT_GLS_NBT_HI - NBT_GLS_NBT_LO) * NBT_GLS_NBT_PER + 1)
#define NBT_GLS_NBT_SLABS 4    /* default depth slabs */
#define NBT_GLS_NBT_MAXSLABS 6

/* The fitted weights (NNLS, computed once per process on first use, about
 * 0.4 s; thread-safe): tab[i * NB + b]. */
const double *nbt_gls_nbt_table(void);
/* Weights a[NB] at log2 beta_px = lb (linear between table entries, held
 * below the table, scaled by 2^(HI - lb) above it: a kernel far wider than
 * the pyramid's reach is G(0)/(sqrt(2 pi) beta r) there, so it only scales)
 * and their slope da[NB] in lb (the segment's; 0 below, -ln 2 a above). */
void nbt_gls_nbt_weights(double lb, double *a, double *da);
/* The 1-D phase-averaged level kernel of basis b at offset d (|d| < 2048),
 * the 2-D one being the product of two. */
double nbt_gls_nbt_kbar(int b, long d);
/* The wide blur m < NBT_GLS_NBT_NW: 1-D taps t[|d|], d = -WT .. WT, a
 * Gaussian of 1.5 (m = 0) or 3 (m = 1) texels cut at 9, or of 6 texels
 * (m = 2) cut at 18, normalised to sum 1 (0 beyond the cut). */
void nbt_gls_nbt_wide_taps(int m, double t[NBT_GLS_NBT_WT + 1]);
/* The centre-tap table of NBT_GLS_NBT, laid out as nbt_gls_near_table
 * (entries a00, a10, a11 used; the others 0): the atom's pixel integral
 * minus the pyramid's phase-averaged spill. */
void nbt_gls_nbt_near_table(float *lut);

/* NBT_GLS_NBT's in-slab excess (nbt_scatter_nbt.glsl): the unit erfc
 * atom's mass beyond distance v beta_px along a line, all across it,
 * tail(v) = ∫_0^1 G(v/s) ds (the atom is a uniform mixture of Gaussians of
 * deviation s beta, s < 1; tail(0) = 1/2), at v = k / NBT_GLS_TAIL_PER for
 * k < NBT_GLS_TAIL_N (beyond: 0). */
#define NBT_GLS_TAIL_PER 128
#define NBT_GLS_TAIL_N (8 * NBT_GLS_TAIL_PER + 1)
void nbt_gls_nbt_tail_table(float *t);

/* The slab plan for an input: n finite slabs, slab of a finite D > 0 =
 * the number of bound[k] <= D (float compare), mid log2 beta_px lb[j] of
 * each (the middle of its pixels' range with M0 > 0; 0 when empty). */
typedef struct {
    unsigned n;
    float bound[NBT_GLS_NBT_MAXSLABS];
    float lb[NBT_GLS_NBT_MAXSLABS];
} nbt_gls_nbt_plan;
void nbt_gls_nbt_plan_of(const nbt_gls_input *in, unsigned slabs, nbt_gls_nbt_plan *p);

/* A context for images of w x h: textures and compiled programs, reused by
 * every run. NULL (reason through libnbt's error handler) without a GL 4.3
 * context, on a bad size or when a shader does not compile. */
typedef struct nbt_gls nbt_gls;
nbt_gls *nbt_gls_alloc(size_t w, size_t h);
void nbt_gls_free(nbt_gls *g);

/* Uploads the input (in->w, in->h must be the context's), runs method m,
 * reads S back (w*h*3 floats). gpu_ms (may be NULL): the GPU time of the
 * method's passes (GL_TIMESTAMP queries around them: llvmpipe
 * reports 1 ns for GL_TIME_ELAPSED of compute work; upload and read-back
 * excluded: the upload is of the input, c with D and the kernel per
 * pixel, and for nbt D once more alone).
 * NBT_EDOM for an input outside the documented ranges, NBT_EINVAL for a
 * size mismatch or an unknown method, NBT_EIO on a GL error. */
nbt_status nbt_gls_exec(nbt_gls *g, nbt_gls_method m, const nbt_gls_input *in, float *S, double *gpu_ms);

/* The GPU time of each group of passes of the last exec, in order (a
 * GL_TIMESTAMP after each; their sum is exec's gpu_ms): names[k], ms[k]
 * and cpu_ms[k] for k < min(count, max), any of them may be NULL; returns
 * the count (0 before the first exec and after one that refused its
 * input). cpu_ms: the process's CPU time
 * (all threads) over the same span: on a software GL that finishes a
 * dispatch before returning (Mesa's llvmpipe) the pass's work, which
 * other jobs on a shared machine do not inflate; on a GPU only the
 * driver's. Groups: shinya "near", "shinya"; shinya-literal "literal";
 * naive and elek "pyr0", "down" (all K levels), "naive" or "elek"; nbt
 * "nbt0" (source level 1), "nbtdown" (levels 2 .. K), "nbtup" (the
 * collapse), "near", "nbt" (the receivers). */
#define NBT_GLS_MAXPASSES 8
unsigned nbt_gls_pass_times(const nbt_gls *g, const char **names, double *ms, double *cpu_ms, unsigned max);

/* NBT_GLS_NBT writes its pyramid levels through a staging buffer, a band
 * of rows at a time (as many as one shader storage block holds: all of a
 * level unless the image is large, e.g. above ~1080p at 6 slabs on
 * llvmpipe's 128 MiB). This caps the rows per band (0: no cap) so that
 * tests can take the banded path on small images; the output does not
 * depend on it. */
nbt_status nbt_gls_set_band_rows(nbt_gls *g, unsigned rows);

/* NBT_GLS_NBT's slab count for later runs (1 .. NBT_GLS_NBT_MAXSLABS;
 * NBT_GLS_NBT_SLABS at alloc); NBT_EDOM outside. */
nbt_status nbt_gls_set_slabs(nbt_gls *g, unsigned slabs);

/* GL state left behind by exec: program 0; 2-D textures on units 0-9, images
 * on units 0-3 and the active texture unit are the context's. */

/* One-shot: alloc, exec, free. */
nbt_status nbt_gls_run(nbt_gls_method m, const nbt_gls_input *in, float *S, double *gpu_ms);

/* The window bound in pixels a method uses for this input (shinya,
 * literal; 0 for the pyramid methods), capped at max(w, h). */
long nbt_gls_window(nbt_gls_method m, const nbt_gls_input *in);

/* "shinya", "shinya-literal", "naive", "elek", "nbt"; parse: NBT_EINVAL for others. */
const char *nbt_gls_method_name(nbt_gls_method m);
nbt_status nbt_gls_method_parse(const char *name, nbt_gls_method *m);

/* The compute programs as compiled (for validation or other pipelines):
 * pass i < nbt_gls_npasses(); malloc'd source, NULL past the end. */
unsigned nbt_gls_npasses(void);
const char *nbt_gls_pass_name(unsigned i);
char *nbt_gls_pass_source(unsigned i);

#ifdef __cplusplus
}
#endif
#endif
