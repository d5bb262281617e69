/* nbt/gl.h: libnbt-gl, the small C helper for nbt's GLSL modules: assemble a
 * fragment shader with the #defines a scene needs, and load tables into GL
 * textures. Needs a current OpenGL >= 3.3 context for the texture calls.
 *
 * Uniforms the modules declare (set them with glUniform*):
 *   nbt_hw[NBT_W_PACKS] (vec4)        Legendre weights w_k = (2k+1) b_k, see nbt_gl_weights
 *   nbt_H0..nbt_H3 (sampler2D)        H packs;  nbt_H_ax0, nbt_H_ax1 (vec4), nbt_H_map0, nbt_H_map1 (int)
 *   nbt_J1_0..3, nbt_Jn_0..3          J^1 and J^n packs; nbt_J_ax0, nbt_J_ax1, nbt_J_map0, nbt_J_map1
 *   X_sub (int), X_sub_w (float), X_sub_c[10] (vec4) for each 2-D pack X above: form sub's closed
 *                                     form (nbt_gl_set_table_sub; 0: plain, the GL default)
 * g-sliced (config g_sliced): nbt_H0, nbt_J1_0, nbt_Jn_0 are sampler3D (channel R, axis 2 = HG g),
 *   nbt_H_ax2, nbt_H_map2, nbt_J_ax2, nbt_J_map2 their g axes, float nbt_g the run-time g
 *   (clamped to the g axis' range by the lookup); nbt_J_form (int, 1: log_et, the texels hold
 *   T + ln J) and nbt_J_interp2 (int, 3: cubic in g, 2: quadratic) for the J tables, nbt_H_interp2
 *   (int, 3: cubic in g, else quadratic) for H; nbt_hw is unused.
 * Functions: nbt_airlight(kappa_s, kappa_t, I0, dsv, gamma, dvp),
 *   nbt_surface(kappa_s, kappa_t, I0, dsp, theta_s, theta_r, kd, ks, n),
 *   g-sliced: nbt_airlight_g(..., dvp, g), nbt_surface_g(..., n, g) at any g (the plain ones read nbt_g),
 *   nbt_lookup3(sampler3D, ax0, map0, ax1, map1, ax2, map2, x0, x1, x2) (nbt_table_lookup3),
 *   nbt_beam_kernel_params(sigma_t, albedo, B, z) -> (alpha, beta), nbt_beam_psi(ab, r),
 *   nbt_beam_fit_psi(sigma_t, albedo, B, z, r) (the fitted model; uniforms vec4 nbt_beam_fit_c[20],
 *   nbt_beam_fit_lo, nbt_beam_fit_hi set by nbt_gl_set_beam_fit). */
#ifndef NBT_GL_H
#define NBT_GL_H

#include <stddef.h>
#include <nbt/beam.h>
#include <nbt/table.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef struct {
    int h_packs;      /* 0: no airlight; 1..4 H textures (orders 4p..4p+3) */
    int j1_packs;     /* 0: no surface radiance; 1..4 J^1 textures */
    int jn_packs;     /* 0..4 J^n (Phong) textures; 0: no specular term */
    int fixed_phase;  /* 1: one fixed-phase table per kind (packs must be 0 or 1) */
    int beam;         /* 1: include the narrow-beam kernel */
    double gamma_eps; /* airlight: gamma clamped to [eps, pi - eps]; 0: 1e-3 */
    int g_sliced;     /* 1: one g-sliced (3-D, HG g on axis 2) table per kind, read at the
                         uniform nbt_g (packs must be 0 or 1) */
} nbt_gl_config;

/* Targets. GL330: "#version 330 core", loose uniforms (the default).
 * ES300: "#version 300 es" (WebGL 2, OpenGL ES 3), highp default precisions,
 * loose uniforms. VULKAN: "#version 450" for glslangValidator -V (SPIR-V);
 * uniforms in std140 blocks and samplers at descriptor set 0, bindings:
 *   0 nbt_weights_block { nbt_hw[, nbt_g] }, 1 nbt_H_block { nbt_H_ax0, nbt_H_ax1, nbt_H_map0, nbt_H_map1
 *   [, nbt_H_ax2, nbt_H_map2, nbt_H_interp2] }, 2 nbt_J_block { nbt_J_ax0, nbt_J_ax1, nbt_J_map0, nbt_J_map1
 *   [, nbt_J_ax2, nbt_J_map2, nbt_J_form, nbt_J_interp2] } (the bracketed members with g_sliced;
 *   without it the packs' X_sub_c, X_sub, X_sub_w follow instead, in pack order: nbt_H0..H3 in
 *   block 1, nbt_J1_0..3 then nbt_Jn_0..3 in block 2, as many as the configuration declares;
 *   the samplers at 3, 7, 11 are
 *   then sampler3D),
 *   3..6 nbt_H0..nbt_H3, 7..10 nbt_J1_0..nbt_J1_3, 11..14 nbt_Jn_0..nbt_Jn_3,
 *   15 nbt_beam_fit_block { nbt_beam_fit_c[20] (vec4), nbt_beam_fit_lo, nbt_beam_fit_hi }.
 * The user's code declares its own outputs (layout(location = 0) out vec4 ...
 * works for all three). */
enum { NBT_GL_TARGET_GL330 = 0, NBT_GL_TARGET_ES300 = 1, NBT_GL_TARGET_VULKAN = 2 };

/* "#version 330 core", the #defines, the modules the configuration needs, then
 * user_src (the shader's own code, may be NULL). malloc'd; NULL on a bad
 * configuration (pack counts out of range) or no memory. */
char *nbt_gl_shader_source(const nbt_gl_config *c, const char *user_src);
/* The same for a target (NBT_GL_TARGET_*): its version line and uniform
 * declarations; NULL also for an unknown target. */
char *nbt_gl_shader_source_target(const nbt_gl_config *c, int target, const char *user_src);

/* Weights for packs x 4 channels: w[k] = (2k+1) b[k] for k < nterms, 0 beyond. */
void nbt_gl_weights(const double *b, size_t nterms, int packs, float *w);

/* One axis' uniforms: vec4(lo, hi, c, n) and its mapping code, the
 * nbt_axis_map value (0 linear, 1 sqrt, 2 log1p, 3 cos, 4 log1p_cbrt,
 * 5 atanh, 6 asinh). */
void nbt_gl_axis(const nbt_axis *a, float v[4], int *map);
/* The table's axis uniforms: vec4(lo, hi, c, n) and mapping codes (axes 0, 1;
 * a g-sliced table's axis 2 by nbt_gl_axis(&t->axis[2], ...)). */
void nbt_gl_table_axes(const nbt_table *t, float ax0[4], float ax1[4], int *map0, int *map1);

/* Set PREFIX_ax0, PREFIX_ax1, PREFIX_map0, PREFIX_map1 of the program in use
 * (e.g. prefix "nbt_H" or "nbt_J") from the table's axes; for a 3-D table
 * (axis[2].n > 1) also PREFIX_ax2, PREFIX_map2, PREFIX_form (1: log_et,
 * else 0) and PREFIX_interp2 (the table's g interpolation). */
void nbt_gl_set_table_axes(unsigned program, const char *prefix, const nbt_table *t);

/* GL_TEXTURE_2D for a 2-D table, GL_TEXTURE_3D for a 3-D (g-sliced) one: the
 * target nbt_gl_upload_table binds it to. */
unsigned nbt_gl_table_target(const nbt_table *t);

/* Upload with LINEAR filtering and CLAMP_TO_EDGE on every axis; binds it on
 * the active texture unit. A 2-D table: a GL_RGBA32F 2-D texture (channels
 * beyond nch are 0). A 3-D table: a 3-D texture of axis[0].n x axis[1].n x
 * axis[2].n texels (slice m = depth m), GL_R32F for one channel, else
 * GL_RGBA32F (channels beyond nch 0); GL_R16F / GL_RGBA16F when t->half
 * (the values are already half, so nothing is rounded again). Returns the
 * texture name, 0 on failure (glGetError set). A table of form sub uploads
 * its remainder f - S: the shaders add S back from the uniforms
 * nbt_gl_set_table_sub sets. */
unsigned nbt_gl_upload_table(const nbt_table *t);

/* Set the form-sub uniforms of the pack read through `sampler` (e.g.
 * "nbt_H0", "nbt_J1_2", "nbt_Jn_0") in the program in use: SAMPLER_sub (int:
 * 0 plain, 1 form sub with d(x) = 1/(1 + x), 2 with e^-x), SAMPLER_sub_w
 * (float, the peak term's width) and SAMPLER_sub_c (vec4[10]: term q of the
 * four channels in element q, as floats); zeros for a plain or 3-D table, so
 * a pack's lookup reads exactly nbt_table_lookup's value either way. Absent
 * uniforms (g-sliced programs) are ignored. */
void nbt_gl_set_table_sub(unsigned program, const char *sampler, const nbt_table *t);

/* Upload t on texture unit `unit` (nbt_gl_upload_table, which leaves it
 * bound there and that unit active), point the program's sampler
 * `sampler` (e.g. "nbt_H0") at it and set its form-sub uniforms
 * (nbt_gl_set_table_sub); the program must be in use. Returns the
 * texture name, 0 on failure. */
unsigned nbt_gl_bind_table(unsigned program, const char *sampler, const nbt_table *t, unsigned unit);

/* Set the fitted kernel model's uniforms (nbt_beam_fit_c, _lo, _hi) of the
 * program in use to f's coefficients for one geometry (infinite: a source
 * inside the medium; 0: a beam entering from vacuum), as floats. Returns 1
 * when f is NULL or does not hold that geometry, else 0. */
int nbt_gl_set_beam_fit(unsigned program, const nbt_beam_fit *f, int infinite);

#ifdef __cplusplus
}
#endif
#endif
