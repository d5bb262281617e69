/* nbt/screen_path.h: a path-traced reference for screen-space multiple
 * scattering, independent of the narrow-beam theory.
 *
 * The world is what an image with planar depth describes. A pinhole camera
 * sits at the origin looking along +z; +x is to the right, +y up (image row
 * 0 at the top). Pixel (x, y) of the w x h world covers the unit-distance
 * image-plane square
 *     u in [(x - cx) dtheta, (x + 1 - cx) dtheta],
 *     v in [(cy - y - 1) dtheta, (cy - y) dtheta],
 * and a pixel of finite planar depth Z (Z < NBT_SCREEN_SKY) is the
 * fronto-parallel square {Z (u, v, 1)} over that footprint: opaque, black
 * on both sides, emitting Lambertian radiance rgb from its face towards the
 * camera side (-z). Gaps between neighbours at different depths stay open;
 * sky pixels hold nothing. A homogeneous medium (per channel sigma_t and
 * albedo, one phase function) fills the ball of the given radius around the
 * camera (INFINITY: all space); a ray leaving it sees the first patch along
 * it without attenuation beyond the ball, else the sky radiance.
 *
 * nbt_screen_path estimates per pixel of the display rectangle the
 * SCATTERED radiance S (light that scattered at least once; the direct,
 * unscattered part is excluded), averaged over the pixel's footprint (box
 * filter), with its standard error. Volumetric path tracing: distances
 * sampled before the first surface (forced collision, one density for all
 * channels: the balance mixture of the channels' exponentials), next-event
 * estimation to the patches (a uniform point on a patch chosen by power or,
 * for the few brightest, by power x solid angle x phase at the vertex)
 * combined with phase sampling by the power heuristic, Russian roulette by
 * the path weight from the second order on. Ray casting walks the pixels that a ray's projection
 * crosses and tests each patch exactly (see libnbt/screen_path.c).
 *
 * Deterministic: pixel i of pass k draws from its own generator, seeded by
 * (seed, k * ow * oh + i), so the result depends on the seed, spp, the number
 * of passes and the inputs, never on the thread count. */
#ifndef NBT_SCREEN_PATH_H
#define NBT_SCREEN_PATH_H

#include <stddef.h>
#include <stdint.h>
#include <nbt/error.h>
#include <nbt/phase.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef struct {
    size_t w, h;           /* the world (e.g. an EXR data window) */
    const float *rgb;      /* emitted radiance, rgb[(y*w + x)*3 + c], finite */
    const float *Z;        /* planar depth per pixel, > 0; >= NBT_SCREEN_SKY or inf: sky */
    double dtheta, cx, cy; /* pixel pitch on the unit image plane (> 0); optical axis in pixel coordinates */
    size_t x0, y0, ow, oh; /* the rendered rectangle (display window) inside the world */
} nbt_screen_world;

typedef struct {
    double sigma_t[3], albedo[3]; /* per channel: sigma_t >= 0, albedo in [0, 1] */
    const nbt_phase *phase;       /* any phase function, the same in every channel */
    double radius;                /* medium radius around the camera, > 0 (INFINITY: everywhere) */
    double sky[3];                /* radiance beyond the medium where no patch is hit */
} nbt_screen_path_medium;

typedef struct {
    unsigned long spp;     /* samples per pixel per pass, >= 2 */
    double target_noise;   /* > 0: add passes until nbt_screen_binned_noise <= target (or max_spp); 0: one pass */
    unsigned long max_spp; /* cap on the total with a target (0: 64 spp) */
    unsigned bin;          /* bin size of the binned noise (0: 4) */
    uint64_t seed;
    unsigned nthreads;     /* 0: all cores */
    unsigned max_order;    /* highest scattering order counted; 0: no cap */
    int progress;          /* nonzero: a progress line per pass on stderr */
    int no_nee;            /* nonzero: phase sampling only (no next-event estimation); for tests */
} nbt_screen_path_opts;

/* S and se (may be NULL): ow*oh*3 doubles, row-major over the display
 * rectangle; *spp_done (may be NULL): samples per pixel taken. Bad
 * arguments: NBT_EINVAL or NBT_EDOM with one line through the error handler
 * naming the bad value and what is accepted; S is then untouched. */
nbt_status nbt_screen_path(const nbt_screen_world *world, const nbt_screen_path_medium *m,
                           const nbt_screen_path_opts *o, double *S, double *se, unsigned long *spp_done);

/* The expected bin x bin binned relative L1 of S that its own noise gives:
 * sum over bins and channels of sqrt(2/pi) SE_bin / sum over bins and
 * channels of |S_bin| (S_bin the sum of the bin's pixels, SE_bin from the
 * pixels' standard errors as independent). Partial bins at the right and
 * bottom edges count. 0 when S sums to 0 and every SE is 0; INFINITY when
 * only S does. bin 0 counts as 1. */
double nbt_screen_binned_noise(size_t w, size_t h, const double *S, const double *se, unsigned bin);

/* The binned relative L1 between two w x h x 3 images: sum over bins and
 * channels of |A_b - B_b| / sum of |B_b| (same bins as above). */
double nbt_screen_binned_rel_l1(size_t w, size_t h, const double *A, const double *B, unsigned bin);

#ifdef __cplusplus
}
#endif
#endif
