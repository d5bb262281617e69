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
    NBT_GLS_ELEK
} nbt_gls_method;
#define NBT_GLS_NMETHODS 4

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
#define NBT_GLS_LUT_N (15 * NBT_GLS_LUT_PER + 1) /* up to beta = 1024 px */

/* Fills lut[NBT_GLS_LUT_N * 8]. */
void nbt_gls_near_table(float *lut);

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
 * excluded).
 * NBT_EDOM for an input outside the documented ranges, NBT_EINVAL for a
 * size mismatch or an unknown method, NBT_EIO on a GL error. */
nbt_status nbt_gls_exec(nbt_gls *g, nbt_gls_method m, const nbt_gls_input *in, float *S, double *gpu_ms);

/* GL state left behind by exec: program 0; textures on units 0-4, images on
 * units 0-3 and the active texture unit are the context's. */

/* One-shot: alloc, exec, free. */
nbt_status nbt_gls_run(nbt_gls_method m, const nbt_gls_input *in, float *S, double *gpu_ms);

/* The window bound in pixels a method uses for this input (shinya,
 * literal; 0 for the pyramid methods), capped at max(w, h). */
long nbt_gls_window(nbt_gls_method m, const nbt_gls_input *in);

/* "shinya", "shinya-literal", "naive", "elek"; parse: NBT_EINVAL for others. */
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
