// shaders/nbt_scatter_nbtmix.glsl: method nbt at pyramid level l >= 1: the
// level's part of each collapse (used by nbt_scatter_nbtup, which adds the
// coarser levels), from the source layers of nbt_scatter_nbt0 at texel p:
//   z = i          scatter into slab i: sum_{j <= i} w_l(j) A_j + w'_l(j) E_j
//   z = n + i      gather of slab i: w_l(i) sum_{j > i} C_j
//   z = 2n + i     its slope in log2 beta: w'_l(i) sum_{j > i} C_j
// each the sharp kernel's weight times the layer plus the blurred kernel's
// weight times the layer's 3x3 blur [b, 1 - 2b, b]^2, b = NBT_SC_NBT_BLUR,
// zero outside the level's stored texels. w_l(j) = the fitted weight of
// level l at slab j's mid log2 beta, w' its slope (uniforms: sharp wa, wda;
// blurred wb, wdb). Part z is returned in q[k * NBT_SC_NBT_MAXSLABS + i]
// for z = k n + i; the loops run to the largest slab count (constant
// indices: registers on llvmpipe).

layout(rgba32f, binding = 0) uniform readonly image2DArray nbt_sc_src;
uniform ivec2 nbt_sc_lsize; // physical extent n_l + 2
uniform float nbt_sc_wa[NBT_SC_NBT_MAXSLABS], nbt_sc_wda[NBT_SC_NBT_MAXSLABS];
uniform float nbt_sc_wb[NBT_SC_NBT_MAXSLABS], nbt_sc_wdb[NBT_SC_NBT_MAXSLABS];

// layer z at p (returned) and its 3x3 blur (bl)
vec3 nbt_sc_src_blur(ivec2 p, int z, out vec3 bl)
{
    const float b = NBT_SC_NBT_BLUR;
    const float wt[3] = float[3](b, 1.0 - 2.0 * b, b);
    vec3 v = vec3(0.0);
    bl = vec3(0.0);
    for (int dy = -1; dy <= 1; dy++) {
        int y = p.y + dy;
        if (y < 0 || y >= nbt_sc_lsize.y)
            continue;
        vec3 row = vec3(0.0);
        for (int dx = -1; dx <= 1; dx++) {
            int x = p.x + dx;
            if (x < 0 || x >= nbt_sc_lsize.x)
                continue;
            vec3 t = imageLoad(nbt_sc_src, ivec3(x, y, z)).rgb;
            row += wt[dx + 1] * t;
            if (dx == 0 && dy == 0)
                v = t;
        }
        bl += wt[dy + 1] * row;
    }
    return v;
}

void nbt_sc_mix(ivec2 p, out vec3 q[3 * NBT_SC_NBT_MAXSLABS])
{
    const int M = NBT_SC_NBT_MAXSLABS;
    int n = nbt_sc_nslab;
    for (int j = 0; j < 3 * M; j++)
        q[j] = vec3(0.0);
    vec3 acc = vec3(0.0), bA, bE;
    for (int j = 0; j < M; j++)
        if (j < n) {
            vec3 A = nbt_sc_src_blur(p, j, bA), E = nbt_sc_src_blur(p, n + j, bE);
            acc += nbt_sc_wa[j] * A + nbt_sc_wda[j] * E + nbt_sc_wb[j] * bA + nbt_sc_wdb[j] * bE;
            q[j] = acc;
        }
    vec3 bs, bc, s = nbt_sc_src_blur(p, 3 * n, bs); // sky
    for (int i = M - 1; i >= 0; i--)
        if (i < n) {
            q[M + i] = nbt_sc_wa[i] * s + nbt_sc_wb[i] * bs;
            q[2 * M + i] = nbt_sc_wda[i] * s + nbt_sc_wdb[i] * bs;
            s += nbt_sc_src_blur(p, 2 * n + i, bc);
            bs += bc;
        }
}
