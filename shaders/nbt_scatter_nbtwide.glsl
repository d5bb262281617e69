// shaders/nbt_scatter_nbtwide.glsl: method nbt, the wide kernels: after the
// collapse's step at level K (nbt_scatter_nbtup), each part of level K
// gets the wide kernels' share, the same sums as nbt_scatter_nbtmix with
// the wide blurs of the source layers in place of the level's own:
//   z = i          += sum_m sum_{j <= i} wc_m(j) W_m A_j + wdc_m(j) W_m E_j
//   z = n + i      += sum_m wc_m(i) W_m sum_{j > i} C_j
//   z = 2n + i     += sum_m wdc_m(i) W_m sum_{j > i} C_j
// W_m the separable blur of taps nbt_sc_wg[m][|d|], |d| <= NBT_SC_NBT_WT,
// zero outside the level's stored texels (they hold all the light: the
// blur of the stored texels is exact there, and texels it would write
// beyond them reach only pixels off the screen). The pyramid's own kernels
// stop at about 150 px; these reach about 600 px. Run only when some wide
// weight is not 0 (a pass of its own, so the other levels pay nothing).

layout(local_size_x = 8, local_size_y = 8) in;
layout(rgba32f, binding = 0) uniform readonly image2DArray nbt_sc_src; // level K of the source pyramid
layout(rgba32f, binding = 1) uniform image2DArray nbt_sc_col;          // level K of the collapse
uniform ivec2 nbt_sc_lsize; // physical extent n_K + 2
uniform float nbt_sc_wg[NBT_SC_NBT_NW * (NBT_SC_NBT_WT + 1)]; // 0 beyond each kernel's cut
uniform int nbt_sc_wt; // the widest cut among the kernels with a weight: an unused wide one costs nothing
uniform float nbt_sc_wc[NBT_SC_NBT_NW * NBT_SC_NBT_MAXSLABS], nbt_sc_wdc[NBT_SC_NBT_NW * NBT_SC_NBT_MAXSLABS];

// layer z's wide blurs at p, all kernels in one pass over the window
void nbt_sc_wblur(ivec2 p, int z, out vec3 bl[NBT_SC_NBT_NW])
{
    const int T = nbt_sc_wt, S = NBT_SC_NBT_WT + 1; // the walk, the taps' stride
    for (int m = 0; m < NBT_SC_NBT_NW; m++)
        bl[m] = vec3(0.0);
    for (int dy = -T; dy <= T; dy++) {
        int y = p.y + dy;
        if (y < 0 || y >= nbt_sc_lsize.y)
            continue;
        vec3 row[NBT_SC_NBT_NW];
        for (int m = 0; m < NBT_SC_NBT_NW; m++)
            row[m] = vec3(0.0);
        for (int dx = -T; dx <= T; dx++) {
            int x = p.x + dx;
            if (x < 0 || x >= nbt_sc_lsize.x)
                continue;
            vec3 t = imageLoad(nbt_sc_src, ivec3(x, y, z)).rgb;
            for (int m = 0; m < NBT_SC_NBT_NW; m++)
                row[m] += nbt_sc_wg[m * S + abs(dx)] * t;
        }
        for (int m = 0; m < NBT_SC_NBT_NW; m++)
            bl[m] += nbt_sc_wg[m * S + abs(dy)] * row[m];
    }
}

void nbt_sc_add(ivec2 p, int z, vec3 v)
{
    imageStore(nbt_sc_col, ivec3(p, z), imageLoad(nbt_sc_col, ivec3(p, z)) + vec4(v, 0.0));
}

void main()
{
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (!nbt_sc_inside(p, nbt_sc_lsize))
        return;
    const int M = NBT_SC_NBT_MAXSLABS, NW = NBT_SC_NBT_NW;
    int n = nbt_sc_nslab;
    vec3 acc = vec3(0.0), a[NW], e[NW], s[NW];
    for (int j = 0; j < M; j++)
        if (j < n) {
            nbt_sc_wblur(p, j, a);
            nbt_sc_wblur(p, n + j, e);
            for (int m = 0; m < NW; m++)
                acc += nbt_sc_wc[m * M + j] * a[m] + nbt_sc_wdc[m * M + j] * e[m];
            nbt_sc_add(p, j, acc);
        }
    nbt_sc_wblur(p, 3 * n, s); // sky
    for (int i = M - 1; i >= 0; i--)
        if (i < n) {
            vec3 g = vec3(0.0), dg = vec3(0.0);
            for (int m = 0; m < NW; m++) {
                g += nbt_sc_wc[m * M + i] * s[m];
                dg += nbt_sc_wdc[m * M + i] * s[m];
            }
            nbt_sc_add(p, n + i, g);
            nbt_sc_add(p, 2 * n + i, dg);
            nbt_sc_wblur(p, 2 * n + i, a);
            for (int m = 0; m < NW; m++)
                s[m] += a[m];
        }
}
