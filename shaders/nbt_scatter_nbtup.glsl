// shaders/nbt_scatter_nbtup.glsl: method nbt, one step of the collapse, at
// level l from K down to 1, every layer z < Z = 3n of a texel in one
// invocation:
//   col_l(z) = part_l(z) + U col_{l+1}(z)
// part_l from nbt_sc_mix (nbt_scatter_nbtmix: sharp + blurred level
// kernels of the source layers), U the bilinear read of level l + 1 at the
// texel centre (weights 0.75 / 0.25 per axis, zero border); col_{K+1} = 0.
// The parts are never stored (llvmpipe pays far more per store than per
// load); col goes through nbt_sc_put.

layout(local_size_x = 8, local_size_y = 8) in;
layout(binding = 3) uniform sampler2DArray nbt_sc_colt; // mipmapped, zero border
uniform ivec2 nbt_sc_usize; // texture size of level l + 1
uniform int nbt_sc_level, nbt_sc_K;

void main()
{
    ivec2 p = ivec2(gl_GlobalInvocationID.xy) + ivec2(0, nbt_sc_rows.x);
    if (!nbt_sc_inside(p, nbt_sc_lsize) || !nbt_sc_in_band(p))
        return;
    const int M = NBT_SC_NBT_MAXSLABS;
    int n = nbt_sc_nslab;
    vec3 q[3 * M];
    nbt_sc_mix(p, q);
    vec2 uv = (0.5 * (vec2(p) - 1.0 + 0.5) + 1.0) / vec2(nbt_sc_usize);
    for (int k = 0; k < 3; k++)
        for (int j = 0; j < M; j++)
            if (j < n) {
                int z = k * n + j;
                vec3 v = q[k * M + j];
                if (nbt_sc_level < nbt_sc_K)
                    v += textureLod(nbt_sc_colt, vec3(uv, float(z)), float(nbt_sc_level)).rgb;
                nbt_sc_put(p, z, v);
            }
}
