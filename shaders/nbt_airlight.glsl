// shaders/nbt_airlight.glsl: airlight of an isotropic point source along a
// view ray from H tables (Hong, eq. 4.18 with albedo and 1/4pi explicit):
//   L_a = kappa_s I0 e^{-kappa_t t}/(4 pi h) sum_k w_k [H_k(kappa_t h, theta_d) - H_k(kappa_t h, theta_0)]
// Defines: NBT_H_PACKS (1..4 RGBA textures holding orders 4p..4p+3) with
// weights nbt_hw[p] (nbt_weights.glsl), or, with NBT_FIXED_PHASE, one
// fixed-phase table (channel R, weight (1, 0, 0, 0)), or, with NBT_G_SLICED,
// one g-sliced table H_p(u, v; g) of the HG phase (a sampler3D, channel R,
// axis 2 = g): nbt_airlight_g(..., g) reads it at any g, nbt_airlight at the
// uniform nbt_g (g clamps to the table's g range, as libnbt's lookup does).
// Singular places: gamma is clamped to [NBT_GAMMA_EPS, pi - NBT_GAMMA_EPS]
// (a ray through the source has infinite airlight; the clamp gives that of a
// ray passing at angle NBT_GAMMA_EPS); u beyond the table reads its edge.
#ifndef NBT_GAMMA_EPS
#define NBT_GAMMA_EPS 1e-3
#endif
#ifdef NBT_G_SLICED
NBT_SAMPLER3D(nbt_H0, 3)
#else
NBT_SAMPLER(nbt_H0, 3)
#endif
#if NBT_H_PACKS > 1
NBT_SAMPLER(nbt_H1, 4)
#endif
#if NBT_H_PACKS > 2
NBT_SAMPLER(nbt_H2, 5)
#endif
#if NBT_H_PACKS > 3
NBT_SAMPLER(nbt_H3, 6)
#endif
NBT_BLOCK_BEGIN(nbt_H_block, 1)
NBT_U vec4 nbt_H_ax0, nbt_H_ax1; // u axis, v axis: vec4(lo, hi, c, n)
NBT_U int nbt_H_map0, nbt_H_map1;
#ifdef NBT_G_SLICED
NBT_U vec4 nbt_H_ax2; // g axis
NBT_U int nbt_H_map2;
#endif
NBT_BLOCK_END

#ifdef NBT_G_SLICED
// H_p(u, v1; g) - H_p(u, v0; g)
float nbt_h_diff_g(float u, float v0, float v1, float g)
{
    return nbt_lookup3(nbt_H0, nbt_H_ax0, nbt_H_map0, nbt_H_ax1, nbt_H_map1, nbt_H_ax2, nbt_H_map2, u, v1, g).r -
           nbt_lookup3(nbt_H0, nbt_H_ax0, nbt_H_map0, nbt_H_ax1, nbt_H_map1, nbt_H_ax2, nbt_H_map2, u, v0, g).r;
}
#define NBT_H_DIFF(u, v0, v1, g) nbt_h_diff_g(u, v0, v1, g)
#else

// sum_k w_k [H_k(u, v1) - H_k(u, v0)]
float nbt_h_diff(float u, float v0, float v1)
{
    float s = dot(nbt_hw[0], nbt_lookup(nbt_H0, nbt_H_ax0, nbt_H_map0, nbt_H_ax1, nbt_H_map1, u, v1) -
                             nbt_lookup(nbt_H0, nbt_H_ax0, nbt_H_map0, nbt_H_ax1, nbt_H_map1, u, v0));
#if NBT_H_PACKS > 1
    s += dot(nbt_hw[1], nbt_lookup(nbt_H1, nbt_H_ax0, nbt_H_map0, nbt_H_ax1, nbt_H_map1, u, v1) -
                        nbt_lookup(nbt_H1, nbt_H_ax0, nbt_H_map0, nbt_H_ax1, nbt_H_map1, u, v0));
#endif
#if NBT_H_PACKS > 2
    s += dot(nbt_hw[2], nbt_lookup(nbt_H2, nbt_H_ax0, nbt_H_map0, nbt_H_ax1, nbt_H_map1, u, v1) -
                        nbt_lookup(nbt_H2, nbt_H_ax0, nbt_H_map0, nbt_H_ax1, nbt_H_map1, u, v0));
#endif
#if NBT_H_PACKS > 3
    s += dot(nbt_hw[3], nbt_lookup(nbt_H3, nbt_H_ax0, nbt_H_map0, nbt_H_ax1, nbt_H_map1, u, v1) -
                        nbt_lookup(nbt_H3, nbt_H_ax0, nbt_H_map0, nbt_H_ax1, nbt_H_map1, u, v0));
#endif
    return s;
}
#define NBT_H_DIFF(u, v0, v1, g) nbt_h_diff(u, v0, v1)
#endif

// kappa_s, kappa_t [1/length], I0, dsv = viewer-source distance, gamma = angle
// between the view ray and the source direction, dvp = distance to the
// surface along the ray (use a huge value, e.g. 1e30, for none); gph: the
// HG g of a g-sliced table (unused otherwise)
float nbt_airlight_core(float kappa_s, float kappa_t, float I0, float dsv, float gamma, float dvp, float gph)
{
    float g = clamp(gamma, NBT_GAMMA_EPS, NBT_PI - NBT_GAMMA_EPS);
    float h = dsv * sin(g), t = dsv * cos(g);
    float th0 = g - 0.5 * NBT_PI;
    float thd = atan(dvp - t, h);
    float d = NBT_H_DIFF(kappa_t * h, th0, thd, gph);
    // e^{-kappa_t t} can overflow where t < 0 while d is tiny: combine in logs
    return d == 0.0 ? 0.0 : sign(d) * exp(-kappa_t * t + log(abs(d) * kappa_s * I0 / (4.0 * NBT_PI * h)));
}

#ifdef NBT_G_SLICED
float nbt_airlight_g(float kappa_s, float kappa_t, float I0, float dsv, float gamma, float dvp, float g)
{
    return nbt_airlight_core(kappa_s, kappa_t, I0, dsv, gamma, dvp, g);
}

float nbt_airlight(float kappa_s, float kappa_t, float I0, float dsv, float gamma, float dvp)
{
    return nbt_airlight_core(kappa_s, kappa_t, I0, dsv, gamma, dvp, nbt_g);
}
#else
float nbt_airlight(float kappa_s, float kappa_t, float I0, float dsv, float gamma, float dvp)
{
    return nbt_airlight_core(kappa_s, kappa_t, I0, dsv, gamma, dvp, 0.0);
}
#endif
