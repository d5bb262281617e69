// shaders/nbt_scatter_shinya.glsl: Shinya et al. Alg. 2 + 3 corrected
// (SCREENSPACE.md, errors 1-6 and 8), as one gather: receiver x takes from
// every y with |dx|, |dy| <= nbt_sc_R the weight of the NEARER pixel's
// kernel at lateral distance |x - y| pixels (at the nearer depth, eq. 38/39):
//   D_y >  D_x: x's kernel (Alg. 2);   D_y <= D_x: y's kernel (Alg. 3).
// Ties therefore count once, with the (equal) source kernel, the own pixel
// included; nothing is renormalised (light that leaves the screen is gone).
// The weight is the kernel integrated over the receiving pixel: offsets
// max(|dx|,|dy|) <= 2 from nbt_scatter_near's per-pixel table weights
// (always taken), farther ones the far-field value nbt_sc_far inside the
// window |x - y| <= cut * beta_px of the nearer kernel (and <= nbt_sc_R,
// which is ceil(cut * max beta_px) unless capped at the image size).

layout(local_size_x = 8, local_size_y = 8) in;
layout(binding = 3) uniform sampler2D nbt_sc_n0;
layout(binding = 4) uniform sampler2D nbt_sc_n1;
layout(rgba32f, binding = 0) uniform writeonly image2D nbt_sc_out;
uniform int nbt_sc_R;      // window bound, >= 2
uniform float nbt_sc_cut;  // window radius in beta

void main()
{
    ivec2 x = ivec2(gl_GlobalInvocationID.xy);
    if (!nbt_sc_inside(x, nbt_sc_size))
        return;
    float Dx = texelFetch(nbt_sc_c, x, 0).a;
    vec2 px = texelFetch(nbt_sc_p, x, 0).xy;
    vec4 n0x = texelFetch(nbt_sc_n0, x, 0), n1x = texelFetch(nbt_sc_n1, x, 0);
    vec3 s = vec3(0.0);
    for (int dy = -nbt_sc_R; dy <= nbt_sc_R; dy++) {
        int yy = x.y + dy;
        if (yy < 0 || yy >= nbt_sc_size.y)
            continue;
        int hw = nbt_sc_R; // the disc's half-width in this row, the near taps kept
        while (hw > 0 && hw * hw + dy * dy > nbt_sc_R * nbt_sc_R)
            hw--;
        if (abs(dy) <= 2)
            hw = max(hw, 2);
        for (int dx = -hw; dx <= hw; dx++) {
            ivec2 y = ivec2(x.x + dx, yy);
            int r2i = dx * dx + dy * dy, hi = max(abs(dx), abs(dy)), lo = min(abs(dx), abs(dy));
            if (y.x < 0 || y.x >= nbt_sc_size.x || (hi > 2 && r2i > nbt_sc_R * nbt_sc_R))
                continue;
            vec4 cy = texelFetch(nbt_sc_c, y, 0);
            bool mine = cy.a > Dx; // the source is farther: the receiver's kernel
            float w;
            if (hi <= 2) {
                int k = hi * (hi + 1) / 2 + lo; // (0,0) (1,0) (1,1) (2,0) (2,1) (2,2)
                if (k < 4)
                    w = (mine ? n0x : texelFetch(nbt_sc_n0, y, 0))[k];
                else
                    w = (mine ? n1x : texelFetch(nbt_sc_n1, y, 0))[k - 4];
            } else {
                vec2 mb = mine ? px : texelFetch(nbt_sc_p, y, 0).xy;
                float r2 = float(r2i), cb = nbt_sc_cut * mb.y;
                w = (mb.x > 0.0 && r2 <= cb * cb) ? mb.x * nbt_sc_far(mb.y, sqrt(r2)) : 0.0;
            }
            s += w * cy.rgb;
        }
    }
    imageStore(nbt_sc_out, x, vec4(s, 1.0));
}
