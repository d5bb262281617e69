// shaders/nbt_scatter_nbt0.glsl: method nbt (nbt/gl_scatter.h), level 1 of
// the source pyramid straight from the image (level 0 is never stored):
// one layer per slab and kind (n finite slabs, slab n = sky),
//   layer j        A_j = M0 c          pixels of finite slab j (j < n)
//   layer n + j    E_j = delta M0 c    delta = lb(beta_px) - nbt_sc_lb[j]
//   layer 2n + j   C_j = c             pixels of slab j (j <= n, sky included)
// each decimated by the 4-tap {0.13, 0.37, 0.37, 0.13} filter at 2p - 1 ..
// 2p + 2 (zero outside the image). D = 0 pixels are in no slab (they send
// and receive nothing).
// Margins: level l >= 1 holds logical texels -1 .. n_l (n_l = padded size
// >> l), all the texels an image on [0, n_0) reaches, at physical texel
// logical + 1 of texture level l - 1, so no light is lost by the pyramid
// itself at the image's border (the infinite zero-extended pyramid).
// The loops run to the largest slab count with constant indices (llvmpipe
// keeps such arrays in registers; an index that varies per pixel costs a
// memory round trip per access).

layout(local_size_x = 8, local_size_y = 8) in;
uniform ivec2 nbt_sc_lsize; // physical extent of level 1: n_1 + 2 (stored through nbt_sc_put)

const float NBT_SC_F4[4] = float[4](0.13, 0.37, 0.37, 0.13);

void main()
{
    ivec2 P = ivec2(gl_GlobalInvocationID.xy) + ivec2(0, nbt_sc_rows.x);
    if (!nbt_sc_inside(P, nbt_sc_lsize) || !nbt_sc_in_band(P))
        return;
    ivec2 p = P - 1; // logical
    int n = nbt_sc_nslab;
    vec3 A[NBT_SC_NBT_MAXSLABS], E[NBT_SC_NBT_MAXSLABS], C[NBT_SC_NBT_MAXSLABS + 1];
    for (int j = 0; j < NBT_SC_NBT_MAXSLABS; j++)
        A[j] = E[j] = C[j] = vec3(0.0);
    C[NBT_SC_NBT_MAXSLABS] = vec3(0.0);
    for (int b = 0; b < 4; b++)
        for (int a = 0; a < 4; a++) {
            ivec2 q = 2 * p - 1 + ivec2(a, b);
            if (!nbt_sc_inside(q, nbt_sc_size))
                continue;
            vec4 cq = texelFetch(nbt_sc_c, q, 0);
            int s = nbt_sc_slab(cq.a);
            if (s < 0)
                continue;
            float f = NBT_SC_F4[a] * NBT_SC_F4[b];
            vec3 fc = f * cq.rgb, m = vec3(0.0), e = vec3(0.0);
            if (s < n) {
                vec2 pq = texelFetch(nbt_sc_p, q, 0).xy;
                m = pq.x * fc;
                float lbs = 0.0;
                for (int j = 0; j < NBT_SC_NBT_MAXSLABS; j++)
                    lbs = s == j ? nbt_sc_lb[j] : lbs;
                e = (nbt_sc_lbeta(pq.y) - lbs) * m;
            }
            for (int j = 0; j < NBT_SC_NBT_MAXSLABS; j++) {
                bool here = s == j;
                A[j] += here ? m : vec3(0.0);
                E[j] += here ? e : vec3(0.0);
                C[j] += here ? fc : vec3(0.0);
            }
            C[NBT_SC_NBT_MAXSLABS] += s == n ? fc : vec3(0.0);
        }
    for (int j = 0; j < NBT_SC_NBT_MAXSLABS; j++)
        if (j < n) {
            nbt_sc_put(P, j, A[j]);
            nbt_sc_put(P, n + j, E[j]);
            nbt_sc_put(P, 2 * n + j, C[j]);
        }
    nbt_sc_put(P, 3 * n, C[NBT_SC_NBT_MAXSLABS]);
}
