/* nbt/gl_mc.h: the GLSL compute photon counter (shaders/nbt_mc.glsl), the
 * GPU counterpart of nbt_mc_run. Needs a current OpenGL >= 4.3 context.
 *
 * It runs the analog estimator of nbt/mc.h in single precision with its own
 * random numbers (Philox4x32-10 keyed by the seed, one counter per photon
 * index): a different sample of the same expectations as nbt_mc_run, with
 * the same tallies, batches (64, by photon index) and standard errors,
 * finished by nbt_mc_finish. Tallies are 64-bit integers (M2: r^2 in units
 * of 2^-20, rounded per crossing), so the result is bit-identical for any
 * work-group size wg and any split of a batch into dispatches of at most
 * max_dispatch photons (0: 2^20). Supported: a slab or a homogeneous
 * half-space (infinite or not) with tally planes, order_max, HG/isotropic
 * or single-Gaussian phase functions, the analog estimator; anything else
 * (layers, a density callback, other phase functions, weighted) returns
 * NBT_EINVAL with the reason. wg: 1..1024 (0: 64). */
#ifndef NBT_GL_MC_H
#define NBT_GL_MC_H

#include <stdint.h>
#include <nbt/mc.h>

#ifdef __cplusplus
extern "C" {
#endif

nbt_status nbt_gl_mc_run(const nbt_mc_config *cfg, unsigned wg, uint64_t max_dispatch, nbt_mc_result **out);

#ifdef __cplusplus
}
#endif
#endif
