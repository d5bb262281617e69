// shaders/nbt_scatter_nbtmix.glsl: method nbt at pyramid level l >= 1: the
// level's part of each collapse, from the source layers (nbt_scatter_nbt0),
// sharp (layer z) and to be blurred (layer Z + z), Z = 3n:
//   z = i          scatter into slab i: sum_{j <= i} w_l(j) A_j + w'_l(j) E_j
//   z = n + i      gather of slab i: w_l(i) sum_{j > i} C_j
//   z = 2n + i     its slope in log2 beta: w'_l(i) sum_{j > i} C_j
// w_l(j) = the fitted weight of level l at slab j's mid log2 beta, w' its
// slope (uniforms: sharp wa, wda; blurred wb, wdb).

layout(local_size_x = 8, local_size_y = 8) in;
layout(rgba32f, binding = 0) uniform readonly image2DArray nbt_sc_src;
layout(rgba32f, binding = 1) uniform writeonly image2DArray nbt_sc_q;
uniform ivec2 nbt_sc_lsize; // physical extent n_l + 2
uniform float nbt_sc_wa[NBT_SC_NBT_MAXSLABS], nbt_sc_wda[NBT_SC_NBT_MAXSLABS];
uniform float nbt_sc_wb[NBT_SC_NBT_MAXSLABS], nbt_sc_wdb[NBT_SC_NBT_MAXSLABS];

void main()
{
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (!nbt_sc_inside(p, nbt_sc_lsize))
        return;
    int n = nbt_sc_nslab, Z = 3 * n;
    vec3 a = vec3(0.0), b = vec3(0.0);
    for (int j = 0; j < n; j++) {
        vec3 A = imageLoad(nbt_sc_src, ivec3(p, j)).rgb, E = imageLoad(nbt_sc_src, ivec3(p, n + j)).rgb;
        a += nbt_sc_wa[j] * A + nbt_sc_wda[j] * E;
        b += nbt_sc_wb[j] * A + nbt_sc_wdb[j] * E;
        imageStore(nbt_sc_q, ivec3(p, j), vec4(a, 0.0));
        imageStore(nbt_sc_q, ivec3(p, Z + j), vec4(b, 0.0));
    }
    vec3 suf = imageLoad(nbt_sc_src, ivec3(p, 3 * n)).rgb; // sky
    for (int i = n - 1; i >= 0; i--) {
        imageStore(nbt_sc_q, ivec3(p, n + i), vec4(nbt_sc_wa[i] * suf, 0.0));
        imageStore(nbt_sc_q, ivec3(p, Z + n + i), vec4(nbt_sc_wb[i] * suf, 0.0));
        imageStore(nbt_sc_q, ivec3(p, 2 * n + i), vec4(nbt_sc_wda[i] * suf, 0.0));
        imageStore(nbt_sc_q, ivec3(p, Z + 2 * n + i), vec4(nbt_sc_wdb[i] * suf, 0.0));
        suf += imageLoad(nbt_sc_src, ivec3(p, 2 * n + i)).rgb;
    }
}
