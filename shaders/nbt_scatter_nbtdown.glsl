// shaders/nbt_scatter_nbtdown.glsl: method nbt, one decimation of every
// layer of the source pyramid, level l - 1 to l >= 2: the 4-tap {0.13,
// 0.37, 0.37, 0.13} filter at 2p - 1 .. 2p + 2 (as nbt_scatter_down), in
// logical texels (physical = logical + 1, see nbt_scatter_nbt0), zero
// outside the stored margins.

layout(local_size_x = 8, local_size_y = 8) in;
layout(rgba32f, binding = 0) uniform readonly image2DArray nbt_sc_src;
uniform ivec2 nbt_sc_srcsize, nbt_sc_dstsize; // physical extents n_l + 2; stored through nbt_sc_put

const float NBT_SC_F4[4] = float[4](0.13, 0.37, 0.37, 0.13);

void main()
{
    ivec3 p = ivec3(gl_GlobalInvocationID) + ivec3(0, nbt_sc_rows.x, 0);
    if (!nbt_sc_inside(p.xy, nbt_sc_dstsize) || !nbt_sc_in_band(p.xy))
        return;
    vec3 I = vec3(0.0);
    for (int b = 0; b < 4; b++) {
        int qy = 2 * p.y - 2 + b; // physical: 2 (p - 1) - 1 + b + 1
        if (qy < 0 || qy >= nbt_sc_srcsize.y)
            continue;
        vec3 row = vec3(0.0);
        for (int a = 0; a < 4; a++) {
            int qx = 2 * p.x - 2 + a;
            if (qx >= 0 && qx < nbt_sc_srcsize.x)
                row += NBT_SC_F4[a] * imageLoad(nbt_sc_src, ivec3(qx, qy, p.z)).rgb;
        }
        I += NBT_SC_F4[b] * row;
    }
    nbt_sc_put(p.xy, p.z, I);
}
