// shaders/nbt_scatter_nbt.glsl: method nbt, the receivers. Pixel x in
// finite slab i (sky: i = n, D = 0: S = 0):
//   S = U col(i') + M0_x (U col(n + i) + delta_x U col(2n + i)) + centre
// i' = min(i, n - 1); the gather terms only for i < n; U the bilinear read
// of level 1 at x; delta_x = lb(beta_x) - nbt_sc_lb[i]; centre = the 3x3
// taps by the exact nearer-pixel rule of operator A (the source is
// farther: x's weights, else the source's; ties: the source's) from the
// per-pixel weights M0 (a00, a10, a11) of the centre table
// (nbt_gls_nbt_near_table, through nbt_scatter_near); a nearer pixel at
// D = 0 gives nothing.

layout(local_size_x = 8, local_size_y = 8) in;
layout(binding = 3) uniform sampler2DArray nbt_sc_colt;
layout(binding = 4) uniform sampler2D nbt_sc_n0;
layout(rgba32f, binding = 0) uniform writeonly image2D nbt_sc_out;
uniform ivec2 nbt_sc_usize; // texture size of level 1 (texture level 0)

void main()
{
    ivec2 x = ivec2(gl_GlobalInvocationID.xy);
    if (!nbt_sc_inside(x, nbt_sc_size))
        return;
    float Dx = texelFetch(nbt_sc_c, x, 0).a;
    int i = nbt_sc_slab(Dx), n = nbt_sc_nslab;
    vec3 s = vec3(0.0);
    if (i >= 0) {
        vec2 uv = (0.5 * (vec2(x) + 0.5) + 1.0) / vec2(nbt_sc_usize); // logical (x + 0.5)/2 - 0.5, physical + 1
        s = textureLod(nbt_sc_colt, vec3(uv, float(min(i, n - 1))), 0.0).rgb;
        vec2 p = texelFetch(nbt_sc_p, x, 0).xy;
        if (i < n && p.x > 0.0) {
            float d = nbt_sc_lbeta(p.y) - nbt_sc_lb[i];
            s += p.x * (textureLod(nbt_sc_colt, vec3(uv, float(n + i)), 0.0).rgb +
                        d * textureLod(nbt_sc_colt, vec3(uv, float(2 * n + i)), 0.0).rgb);
        }
        vec4 nx = texelFetch(nbt_sc_n0, x, 0);
        for (int dy = -1; dy <= 1; dy++)
            for (int dx = -1; dx <= 1; dx++) {
                ivec2 y = x + ivec2(dx, dy);
                if (!nbt_sc_inside(y, nbt_sc_size))
                    continue;
                vec4 cy = texelFetch(nbt_sc_c, y, 0);
                bool mine = cy.a > Dx;
                if (!mine && !(cy.a > 0.0))
                    continue;
                s += (mine ? nx : texelFetch(nbt_sc_n0, y, 0))[abs(dx) + abs(dy)] * cy.rgb;
            }
    }
    imageStore(nbt_sc_out, x, vec4(s, 1.0));
}
