// shaders/nbt_scatter_pyr0.glsl: level 0 of the pyramids the naive and Elek
// methods read, over the padded size (a multiple of 2^K, so that every level
// halves exactly; the padding is zero: light off screen is gone):
//   nbt_sc_pyr  level 0 = (M0 c, W)   M0 c the light to blur (Elek eq. 4
//       corrected: e^{-sigma_a D}(1 - e^{-sigma_s D}) = M0), W = sigma_px
//       (Elek eq. 5, in pixels)
//   nbt_sc_wb   level 0 = (W v, v)    v = 1 on the image, 0 in the padding:
//       the isotropic pyramid of W (Elek eq. 11's blurred distance map, in
//       spread space), normalised by v when read.

layout(local_size_x = 8, local_size_y = 8) in;
layout(rgba32f, binding = 0) uniform writeonly image2D nbt_sc_pyr;
layout(rg32f, binding = 1) uniform writeonly image2D nbt_sc_wb;
uniform ivec2 nbt_sc_psize; // padded size

void main()
{
    ivec2 x = ivec2(gl_GlobalInvocationID.xy);
    if (!nbt_sc_inside(x, nbt_sc_psize))
        return;
    vec4 I = vec4(0.0);
    vec2 wb = vec2(0.0);
    if (nbt_sc_inside(x, nbt_sc_size)) {
        vec4 p = texelFetch(nbt_sc_p, x, 0);
        I = vec4(p.x * texelFetch(nbt_sc_c, x, 0).rgb, p.z);
        wb = vec2(p.z, 1.0);
    }
    imageStore(nbt_sc_pyr, x, I);
    imageStore(nbt_sc_wb, x, vec4(wb, 0.0, 0.0));
}
