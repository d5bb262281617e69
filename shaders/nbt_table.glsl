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

// NBT_FORM_SUB (libnbt's nbt_table_sub, doc/tables.md "33^2 at 1e-3"): the texels hold f - S,
// S(x0, x1) = d(x0 - lo0) sum_q c_q b_q(x1), both coordinates clamped to the axes as the lookup
// clamps them; b = 1, y, cos y, sin y, cos 2y, sin 2y, cos 3y, sin 3y, cos 4y, 1/sqrt(y^2 + w^2)
// (0 when w = 0); c_q holds term q of all four channels. sub: 0 a plain table (S = 0), 1 form sub
// with d(x) = 1/(1 + x), 2 with d(x) = e^-x. One sin/cos pair, the rest by angle addition.
// The coefficients come as ten vec4 (NBT_SUB_C(c) spells out a uniform array c[10]): no array
// parameter to copy per call.
vec4 nbt_sub(int sub, float w, vec4 c0, vec4 c1, vec4 c2, vec4 c3, vec4 c4, vec4 c5, vec4 c6, vec4 c7, vec4 c8,
             vec4 c9, vec4 a0, vec4 a1, float x0, float x1)
{
    if (sub == 0)
        return vec4(0.0);
    float x = clamp(x0, a0.x, a0.y) - a0.x, y = clamp(x1, a1.x, a1.y);
    float cs1 = cos(y), sn1 = sin(y);
    float cs2 = cs1 * cs1 - sn1 * sn1, sn2 = 2.0 * sn1 * cs1;
    float cs3 = cs2 * cs1 - sn2 * sn1, sn3 = sn2 * cs1 + cs2 * sn1;
    float cs4 = cs3 * cs1 - sn3 * sn1;
    vec4 s = c0 + y * c1 + cs1 * c2 + sn1 * c3 + cs2 * c4 + sn2 * c5 + cs3 * c6 + sn3 * c7 + cs4 * c8;
    if (w > 0.0)
        s += inversesqrt(y * y + w * w) * c9;
    return (sub == 2 ? exp(-x) : 1.0 / (1.0 + x)) * s;
}
#define NBT_SUB_C(c) c[0], c[1], c[2], c[3], c[4], c[5], c[6], c[7], c[8], c[9]

// a 2-D table's value whatever its form: nbt_lookup plus the closed form (nbt_table_lookup);
// sub, w, c: the pack's uniforms (c its vec4[10] array); one line: GLSL 3.30 has no line continuation
#define nbt_lookup_sub(t, a0, m0, a1, m1, sub, w, c, x0, x1) (nbt_lookup(t, a0, m0, a1, m1, x0, x1) + nbt_sub(sub, w, NBT_SUB_C(c), a0, a1, x0, x1))
