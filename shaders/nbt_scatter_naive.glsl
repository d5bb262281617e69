// shaders/nbt_scatter_naive.glsl: the naive Gaussian pyramid (Elek et al.
// Sec. 3.3, "naive approximation"): one fetch per receiver at the level
// whose Gaussian matches the receiver's own kernel, l = clamp(log2(W/c), 0,
// K), W = sigma_px; bilinear within a level, linear between the two levels
// around l. c = NBT_SC_NAIVE_C: with 4-tap decimation and bilinear
// reconstruction level k is a Gaussian of variance 0.77 (4^k - 1)/3 + 4^k/6
// px^2 (averaged over the sub-texel phase), sigma -> 0.651 2^k.

layout(local_size_x = 8, local_size_y = 8) in;
layout(binding = 2) uniform sampler2D nbt_sc_pyr; // mipmapped, LINEAR_MIPMAP_NEAREST, zero border
layout(rgba32f, binding = 0) uniform writeonly image2D nbt_sc_out;
uniform ivec2 nbt_sc_psize;
uniform int nbt_sc_K;

void main()
{
    ivec2 x = ivec2(gl_GlobalInvocationID.xy);
    if (!nbt_sc_inside(x, nbt_sc_size))
        return;
    float W = texelFetch(nbt_sc_p, x, 0).z;
    float l = W > 0.0 ? clamp(log2(W / NBT_SC_NAIVE_C), 0.0, float(nbt_sc_K)) : 0.0;
    int k0 = int(floor(l)), k1 = min(k0 + 1, nbt_sc_K);
    vec2 uv = (vec2(x) + 0.5) / vec2(nbt_sc_psize);
    vec3 s = mix(textureLod(nbt_sc_pyr, uv, float(k0)).rgb, textureLod(nbt_sc_pyr, uv, float(k1)).rgb, l - float(k0));
    imageStore(nbt_sc_out, x, vec4(s, 1.0));
}
