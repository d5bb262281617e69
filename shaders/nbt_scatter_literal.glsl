// shaders/nbt_scatter_literal.glsl: Shinya et al. Alg. 1-4 as printed, for
// measuring what the corrections change (SCREENSPACE.md's table). Receiver
// x, every y in the window, kernel of the nearer pixel n at its own depth:
//   D_y > D_x: Alg. 2 (gather, x's kernel);  D_y < D_x: Alg. 3 (distribute,
//   y's kernel);  D_y == D_x, the own pixel included: nothing (error 3,
//   strict '>' in both).
// Reproduced errors:
//   1, 2: Alg. 1 stores beta[] = 3 M2/M0 (which is beta^2) and alpha[] =
//       2 M0/beta[]; Alg. 2/3 then use beta[] as beta: r / beta[]. With the
//       erfc kernel's M2 = (2/3) M0 beta^2 (beta in world units: beta_px D
//       dtheta) this is beta[] = 2 beta^2, alpha[] = M0 / beta^2;
//   4: cut_off = 1: a square window (Alg. 3 draws a rectangle) of half-size
//       beta[] / (D_n dtheta) pixels, nbt_sc_cut ignored;
//   5: no pixel area: weight = alpha[]/d G(d / beta[]) itself;
//   6: d = the 3-D distance between the two surface points D ray(pixel),
//       ray through the pixel centre of a pinhole camera with constant pitch
//       dtheta (a sky pixel is infinitely far: weight 0).
// Not reproduced: 8 (r' = WorldCoord(p) would make d = 0: the printed
// Alg. 2 divides by zero), 9 (M0 and beta come from libnbt's eq. 25/26),
// 7 (T is not part of S).

layout(local_size_x = 8, local_size_y = 8) in;
layout(rgba32f, binding = 0) uniform writeonly image2D nbt_sc_out;
uniform int nbt_sc_R;         // window bound in pixels
uniform float nbt_sc_dtheta;  // pixel pitch (radians)

vec3 nbt_sc_point(ivec2 p, float D)
{
    vec2 uv = (vec2(p) + 0.5 - 0.5 * vec2(nbt_sc_size)) * nbt_sc_dtheta;
    return D * vec3(uv, 1.0) / sqrt(1.0 + dot(uv, uv));
}

void main()
{
    ivec2 x = ivec2(gl_GlobalInvocationID.xy);
    if (!nbt_sc_inside(x, nbt_sc_size))
        return;
    float Dx = texelFetch(nbt_sc_c, x, 0).a;
    vec2 px = texelFetch(nbt_sc_p, x, 0).xy;
    vec3 Px = nbt_sc_point(x, Dx), s = vec3(0.0);
    for (int dy = -nbt_sc_R; dy <= nbt_sc_R; dy++) {
        int yy = x.y + dy;
        if (yy < 0 || yy >= nbt_sc_size.y)
            continue;
        for (int dx = -nbt_sc_R; dx <= nbt_sc_R; dx++) {
            ivec2 y = ivec2(x.x + dx, yy);
            if (y.x < 0 || y.x >= nbt_sc_size.x)
                continue;
            vec4 cy = texelFetch(nbt_sc_c, y, 0);
            if (cy.a == Dx)
                continue;
            bool mine = cy.a > Dx;
            float Dn = mine ? Dx : cy.a, Df = mine ? cy.a : Dx;
            vec2 mb = mine ? px : texelFetch(nbt_sc_p, y, 0).xy;
            if (!(mb.x > 0.0) || Df >= NBT_SC_SKY)
                continue;
            float pitch = Dn * nbt_sc_dtheta, bw = mb.y * pitch;
            float bl = 2.0 * bw * bw; // beta[] = 3 M2/M0 = 2 beta^2
            if (float(max(abs(dx), abs(dy))) * pitch > bl)
                continue;
            float d = length(nbt_sc_point(y, cy.a) - Px);
            s += (mb.x / (bw * bw)) / d * nbt_G(d / bl) * cy.rgb; // alpha[] = 2 M0 / beta[]
        }
    }
    imageStore(nbt_sc_out, x, vec4(s, 1.0));
}
