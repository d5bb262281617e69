// shaders/nbt_scatter_near.glsl: per pixel, the weights its own kernel
// (mass M0, erfc atom of beta_px) gives to the near offsets, integrated
// over the receiving pixel's square:
//   out0 = M0 * (a(0,0), a(1,0), a(1,1), a(2,0)),  out1 = M0 * (a(2,1), a(2,2), 0, 0)
// a(dx, dy) from the table nbt_sc_lut that libnbt-gl fills with
// nbt_screen_atom_pixel: row 0 (a00, a10, a11, a20), row 1 (a21, a22, 0, 0)
// at beta = 2^(NBT_SC_LUT_LO + i / NBT_SC_LUT_PER), i < NBT_SC_LUT_N, linear
// in log2 beta; below the table the first entry, above it the last times
// beta_top / beta (the weights tend to const/beta). Defines come from C.
// Error of the interpolation (32 entries per octave): at most 6.2e-5 of the
// kernel's mass misplaced over the 25 near pixels (worst at beta ~ 1 px);
// per offset up to 1.8% where those weights are tiny (beta < 0.5 px).

layout(local_size_x = 8, local_size_y = 8) in;
layout(binding = 2) uniform sampler2D nbt_sc_lut;
layout(rgba32f, binding = 0) uniform writeonly image2D nbt_sc_out0;
layout(rgba32f, binding = 1) uniform writeonly image2D nbt_sc_out1;
uniform int nbt_sc_only0; // 1: out0 alone (method nbt reads a00, a10, a11)

void main()
{
    ivec2 x = ivec2(gl_GlobalInvocationID.xy);
    if (!nbt_sc_inside(x, nbt_sc_size))
        return;
    vec4 p = texelFetch(nbt_sc_p, x, 0);
    vec4 a = vec4(0.0), b = vec4(0.0);
    if (p.x > 0.0) { // beta_px = 0: no spread, the first entry (all but ~0 on the own pixel)
        int i;
        float f, scale;
        nbt_sc_lut_at(p.y, i, f, scale);
        a = mix(texelFetch(nbt_sc_lut, ivec2(i, 0), 0), texelFetch(nbt_sc_lut, ivec2(i + 1, 0), 0), f);
        b = mix(texelFetch(nbt_sc_lut, ivec2(i, 1), 0), texelFetch(nbt_sc_lut, ivec2(i + 1, 1), 0), f);
        a *= p.x * scale;
        b *= p.x * scale;
    }
    imageStore(nbt_sc_out0, x, a);
    if (nbt_sc_only0 == 0)
        imageStore(nbt_sc_out1, x, b);
}
