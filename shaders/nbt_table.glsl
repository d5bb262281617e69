// shaders/nbt_table.glsl: node-aligned table lookup, exactly as libnbt writes
// tables. An axis is vec4(lo, hi, c, n) plus a mapping code: 0 linear,
// 1 sqrt, 2 log1p (c > 0 clusters at lo, -1 < c < 0 at hi), 3 cos,
// 4 log1p_cbrt (the cube root of log1p's coordinate, c > 0), 5 atanh
// (uniform in atanh x, -1 < lo < hi < 1), 6 asinh (nodes clustered at the
// middle of the range, c > 0), 7 ends (log1p from both ends: c/2 at lo, c at
// hi, the halves' slopes matched at the middle; c > 0).
// Outside [lo, hi] the unit coordinate clamps (CLAMP_TO_EDGE values).
// nbt_lookup3 reads a 3-D (g-sliced) table, axis 2 the slices (e.g. the HG
// g), with the same convention on all three axes: libnbt's nbt_table_lookup3;
// nbt_lookup3q is its quadratic-in-g variant (interp2 = 2): three bilinear
// fetches at the centres of the slices nearest to x2; nbt_lookup3c the cubic
// one (interp2 = 3, Lagrange): four fetches, the cell's two slices and one
// on either side (moved inwards in the first and last cells).
const float NBT_PI = 3.14159265358979;
#ifdef NBT_VULKAN
// HLSL has no atanh, so SPIRV-Cross cannot translate it: the Vulkan variant
// (the source of the generated HLSL and MSL) uses its log form
float nbt_atanh(float x) { return 0.5 * log((1.0 + x) / (1.0 - x)); }
#else
#define nbt_atanh atanh
#endif

float nbt_axis_unit(float x, vec4 a, int map)
{
    if (map == 5)
        return clamp((nbt_atanh(clamp(x, a.x, a.y)) - nbt_atanh(a.x)) / (nbt_atanh(a.y) - nbt_atanh(a.x)), 0.0, 1.0);
    float r = clamp((x - a.x) / (a.y - a.x), 0.0, 1.0);
    if (map == 1)
        return sqrt(r);
    if (map == 2)
        return log(1.0 + a.z * r) / log(1.0 + a.z);
    if (map == 3) // acos(1 - 2r)/pi, as 2 atan(sqrt r, sqrt(1 - r))/pi: llvmpipe's acos is off by
                  // up to 5e-5 in s (its atan 2e-6), and 1 - 2r loses r's low bits near r = 0
        return 2.0 * atan(sqrt(r), sqrt(1.0 - r)) / NBT_PI;
    if (map == 4)
        return pow(log(1.0 + a.z * r) / log(1.0 + a.z), 1.0 / 3.0);
    if (map == 6) { // asinh by its odd log form: no cancellation for z < 0
        float z = a.z * abs(2.0 * r - 1.0);
        return 0.5 + 0.5 * sign(r - 0.5) * log(z + sqrt(z * z + 1.0)) / log(a.z + sqrt(a.z * a.z + 1.0));
    }
    if (map == 7) { // ends
        float l1 = log(1.0 + 0.5 * a.z), l2 = log(1.0 + a.z);
        float k1 = l1 * (1.0 + 0.5 * a.z) / (0.5 * a.z), k2 = l2 * (1.0 + a.z) / a.z, f = k1 / (k1 + k2);
        if (r <= 0.5)
            return f * log(1.0 + a.z * r) / l1;
        return 1.0 - (1.0 - f) * log(1.0 + 2.0 * a.z * (1.0 - r)) / l2;
    }
    return r;
}

// the texel-centre convention: node i of n sits at (i + 0.5)/n
float nbt_texcoord(float s, float n)
{
    return (s * (n - 1.0) + 0.5) / n;
}

vec4 nbt_lookup(sampler2D t, vec4 a0, int m0, vec4 a1, int m1, float x0, float x1)
{
    return texture(t, vec2(nbt_texcoord(nbt_axis_unit(x0, a0, m0), a0.w),
                           nbt_texcoord(nbt_axis_unit(x1, a1, m1), a1.w)));
}

vec4 nbt_lookup3(sampler3D t, vec4 a0, int m0, vec4 a1, int m1, vec4 a2, int m2, float x0, float x1, float x2)
{
    return texture(t, vec3(nbt_texcoord(nbt_axis_unit(x0, a0, m0), a0.w),
                           nbt_texcoord(nbt_axis_unit(x1, a1, m1), a1.w),
                           nbt_texcoord(nbt_axis_unit(x2, a2, m2), a2.w)));
}

vec4 nbt_lookup3q(sampler3D t, vec4 a0, int m0, vec4 a1, int m1, vec4 a2, int m2, float x0, float x1, float x2)
{
    vec2 st = vec2(nbt_texcoord(nbt_axis_unit(x0, a0, m0), a0.w), nbt_texcoord(nbt_axis_unit(x1, a1, m1), a1.w));
    float p = nbt_axis_unit(x2, a2, m2) * (a2.w - 1.0);
    float mc = clamp(floor(p + 0.5), 1.0, a2.w - 2.0), q = p - mc;
    return 0.5 * q * (q - 1.0) * texture(t, vec3(st, (mc - 0.5) / a2.w))
         + (1.0 - q * q) * texture(t, vec3(st, (mc + 0.5) / a2.w))
         + 0.5 * q * (q + 1.0) * texture(t, vec3(st, (mc + 1.5) / a2.w));
}

vec4 nbt_lookup3c(sampler3D t, vec4 a0, int m0, vec4 a1, int m1, vec4 a2, int m2, float x0, float x1, float x2)
{
    vec2 st = vec2(nbt_texcoord(nbt_axis_unit(x0, a0, m0), a0.w), nbt_texcoord(nbt_axis_unit(x1, a1, m1), a1.w));
    float p = nbt_axis_unit(x2, a2, m2) * (a2.w - 1.0);
    float f = clamp(floor(p) - 1.0, 0.0, a2.w - 4.0), x = p - f;
    float x1m = x - 1.0, x2m = x - 2.0, x3m = x - 3.0;
    return (-x1m * x2m * x3m / 6.0) * texture(t, vec3(st, (f + 0.5) / a2.w))
         + (x * x2m * x3m / 2.0) * texture(t, vec3(st, (f + 1.5) / a2.w))
         + (-x * x1m * x3m / 2.0) * texture(t, vec3(st, (f + 2.5) / a2.w))
         + (x * x1m * x2m / 6.0) * texture(t, vec3(st, (f + 3.5) / a2.w));
}

// a g-sliced table's lookup by its interp2: 3 cubic, 2 quadratic, else trilinear
vec4 nbt_lookup3i(sampler3D t, vec4 a0, int m0, vec4 a1, int m1, vec4 a2, int m2, int interp, float x0, float x1,
                  float x2)
{
    if (interp == 3)
        return nbt_lookup3c(t, a0, m0, a1, m1, a2, m2, x0, x1, x2);
    if (interp == 2)
        return nbt_lookup3q(t, a0, m0, a1, m1, a2, m2, x0, x1, x2);
    return nbt_lookup3(t, a0, m0, a1, m1, a2, m2, x0, x1, x2);
}
