// shaders/nbt_scatter_elek.glsl: Elek et al. Step 3 (eq. 10-12) on the masked
// pyramid (nbt_scatter_down with masks): per receiver
//   l0 = l(W)            W = sigma_px, l(W) = clamp(log2(W/c), 0, K), c = NBT_SC_ELEK_C
//   Wt = Wb^[l0](x)      the isotropic blur of W read at level l0 (eq. 11:
//                        blurred in spread space; Wb / v, v the validity)
//   S  = I^[l(Wt)](x)    eq. 12 without I' (the caller adds T c)
// A sky receiver (no width of its own) takes l0 = K: Wt is then the
// validity-weighted width of the sources around it.
// Every read is "linear-bicubic" (Sec. 3.5): the two levels around l, each
// by the cubic B-spline as 4 bilinear fetches (Sigg and Hadwiger), mixed
// linearly.

layout(local_size_x = 8, local_size_y = 8) in;
layout(binding = 2) uniform sampler2D nbt_sc_pyr; // mipmapped, LINEAR_MIPMAP_NEAREST, zero border
layout(binding = 3) uniform sampler2D nbt_sc_wbt; // the same for (W v, v)
layout(rgba32f, binding = 0) uniform writeonly image2D nbt_sc_out;
uniform ivec2 nbt_sc_psize;
uniform int nbt_sc_K;

float nbt_sc_level(float W)
{
    return W > 0.0 ? clamp(log2(W / NBT_SC_ELEK_C), 0.0, float(nbt_sc_K)) : 0.0;
}

// cubic B-spline at pixel x of level k: 4 bilinear fetches
vec4 nbt_sc_bspline(sampler2D t, ivec2 x, int k)
{
    float n = exp2(float(k));
    vec2 size = vec2(nbt_sc_psize) / n;
    vec2 c = (vec2(x) + 0.5) / n - 0.5; // in texel-centre units
    vec2 i = floor(c), f = c - i, g = 1.0 - f;
    vec2 w0 = g * g * g / 6.0, w3 = f * f * f / 6.0;
    vec2 w1 = (4.0 - 6.0 * f * f + 3.0 * f * f * f) / 6.0, w2 = 1.0 - w0 - w1 - w3;
    vec2 g0 = w0 + w1, g1 = w2 + w3;
    vec2 h0 = (i - 1.0 + w1 / g0 + 0.5) / size, h1 = (i + 1.0 + w3 / g1 + 0.5) / size;
    float lod = float(k);
    return g0.y * (g0.x * textureLod(t, vec2(h0.x, h0.y), lod) + g1.x * textureLod(t, vec2(h1.x, h0.y), lod)) +
           g1.y * (g0.x * textureLod(t, vec2(h0.x, h1.y), lod) + g1.x * textureLod(t, vec2(h1.x, h1.y), lod));
}

vec4 nbt_sc_read(sampler2D t, ivec2 x, float l)
{
    int k0 = int(floor(l)), k1 = min(k0 + 1, nbt_sc_K);
    return mix(nbt_sc_bspline(t, x, k0), nbt_sc_bspline(t, x, k1), l - float(k0));
}

void main()
{
    ivec2 x = ivec2(gl_GlobalInvocationID.xy);
    if (!nbt_sc_inside(x, nbt_sc_size))
        return;
    float W = texelFetch(nbt_sc_p, x, 0).z;
    // a sky receiver's own width is infinite (its beam never ends): it looks
    // up the blurred width at the coarsest level, so it gathers at the width
    // of the sources around it instead of staying black
    bool sky = texelFetch(nbt_sc_c, x, 0).w >= NBT_SC_SKY;
    vec2 wb = nbt_sc_read(nbt_sc_wbt, x, sky ? float(nbt_sc_K) : nbt_sc_level(W)).xy;
    float Wt = wb.y > 0.0 ? wb.x / wb.y : W;
    vec3 s = nbt_sc_read(nbt_sc_pyr, x, nbt_sc_level(Wt)).rgb;
    imageStore(nbt_sc_out, x, vec4(s, 1.0));
}
