// shaders/nbt_scatter_nbtup.glsl: method nbt, one step of the collapse, at
// level l from K down to 1, every layer z < Z = 3n:
//   col_l = q_l(z) + B q_l(Z + z) + U col_{l+1}
// B the 3x3 blur [b, 1 - 2b, b]^2, b = NBT_SC_NBT_BLUR, zero outside the
// level; U the bilinear read of level l + 1 at the texel centre (weights
// 0.75 / 0.25 per axis, zero border); col_{K+1} = 0.

layout(local_size_x = 8, local_size_y = 8) in;
layout(rgba32f, binding = 0) uniform readonly image2DArray nbt_sc_q;
layout(rgba32f, binding = 1) uniform writeonly image2DArray nbt_sc_col;
layout(binding = 3) uniform sampler2DArray nbt_sc_colt; // mipmapped, zero border
uniform ivec2 nbt_sc_lsize, nbt_sc_usize; // physical extent n_l + 2; texture size of level l + 1
uniform int nbt_sc_level, nbt_sc_K;

void main()
{
    ivec3 p = ivec3(gl_GlobalInvocationID);
    if (!nbt_sc_inside(p.xy, nbt_sc_lsize))
        return;
    int Z = 3 * nbt_sc_nslab;
    const float b = NBT_SC_NBT_BLUR;
    const float wt[3] = float[3](b, 1.0 - 2.0 * b, b);
    vec3 v = imageLoad(nbt_sc_q, p).rgb;
    for (int dy = -1; dy <= 1; dy++) {
        int y = p.y + dy;
        if (y < 0 || y >= nbt_sc_lsize.y)
            continue;
        vec3 row = vec3(0.0);
        for (int dx = -1; dx <= 1; dx++) {
            int x = p.x + dx;
            if (x >= 0 && x < nbt_sc_lsize.x)
                row += wt[dx + 1] * imageLoad(nbt_sc_q, ivec3(x, y, Z + p.z)).rgb;
        }
        v += wt[dy + 1] * row;
    }
    if (nbt_sc_level < nbt_sc_K)
        v += textureLod(nbt_sc_colt, vec3((0.5 * (vec2(p.xy) - 1.0 + 0.5) + 1.0) / vec2(nbt_sc_usize), float(p.z)),
                        float(nbt_sc_level)).rgb;
    imageStore(nbt_sc_col, p, vec4(v, 0.0));
}
