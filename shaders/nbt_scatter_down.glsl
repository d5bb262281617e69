// shaders/nbt_scatter_down.glsl: level k from level k-1 (Elek et al. eq. 6-9):
// coarse texel p takes the 4 x 4 fine texels q = 2p - 1 + (a, b), a, b < 4
// (zero outside the level), with the separable filter G' = {0.13, 0.37,
// 0.37, 0.13} per axis:
//   I^k  = sum G'_a G'_b M(W_q) I_q      M = 1 (nbt_sc_masked = 0: the naive
//          pyramid) or the smoothstep mask of eq. 7 on W^{k-1}, threshold
//          T = c 2^{k-1}, width eps T (eps = 0: a step, W >= T)
//   W^k  = sum Y_q W_q / sum Y_q          eq. 8, Y = luminance of I^{k-1}
//          (unmasked, eq. 9, its absolute value), box U over the same 16 texels; where all Y = 0
//          the validity-weighted box mean sum v_q W_q / sum v_q (0 if none)
//   Wb^k = sum G'_a G'_b Wb_q            the isotropic pyramid of (W v, v)

layout(local_size_x = 8, local_size_y = 8) in;
layout(rgba32f, binding = 0) uniform readonly image2D nbt_sc_src;
layout(rgba32f, binding = 1) uniform writeonly image2D nbt_sc_dst;
layout(rg32f, binding = 2) uniform readonly image2D nbt_sc_wsrc;
layout(rg32f, binding = 3) uniform writeonly image2D nbt_sc_wdst;
uniform ivec2 nbt_sc_srcsize, nbt_sc_dstsize;
uniform int nbt_sc_masked;
uniform float nbt_sc_T, nbt_sc_eps;

const float NBT_SC_F[4] = float[4](0.13, 0.37, 0.37, 0.13);

float nbt_sc_mask(float W)
{
    if (nbt_sc_eps <= 0.0)
        return W >= nbt_sc_T ? 1.0 : 0.0;
    float t = clamp((W - nbt_sc_T) / (nbt_sc_eps * nbt_sc_T), 0.0, 1.0);
    return t * t * (3.0 - 2.0 * t);
}

void main()
{
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (!nbt_sc_inside(p, nbt_sc_dstsize))
        return;
    vec3 I = vec3(0.0);
    vec2 wb = vec2(0.0);
    float yw = 0.0, ys = 0.0, vw = 0.0, vs = 0.0;
    for (int b = 0; b < 4; b++)
        for (int a = 0; a < 4; a++) {
            ivec2 q = 2 * p - 1 + ivec2(a, b);
            if (!nbt_sc_inside(q, nbt_sc_srcsize))
                continue;
            vec4 s = imageLoad(nbt_sc_src, q);
            vec2 w = imageLoad(nbt_sc_wsrc, q).xy;
            float f = NBT_SC_F[a] * NBT_SC_F[b], Y = abs(nbt_sc_lum(s.rgb));
            I += (f * (nbt_sc_masked != 0 ? nbt_sc_mask(s.a) : 1.0)) * s.rgb;
            wb += f * w;
            yw += Y * s.a;
            ys += Y;
            vw += w.y * s.a;
            vs += w.y;
        }
    float W = ys > 0.0 ? yw / ys : (vs > 0.0 ? vw / vs : 0.0);
    imageStore(nbt_sc_dst, p, vec4(I, W));
    imageStore(nbt_sc_wdst, p, vec4(wb, 0.0, 0.0));
}
