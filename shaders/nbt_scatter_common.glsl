// shaders/nbt_scatter_common.glsl: what the screen-space scattering passes
// (nbt_scatter_*.glsl, assembled by shaders/nbt_gl_scatter.c) share. Needs
// nbt_G from nbt_beam.glsl (G(x) = erfc(x/sqrt 2)/2, Abramowitz & Stegun
// 7.1.26, |error| <= 7.5e-8 absolute).
//
// Textures every pass may read (texelFetch, level 0, w x h):
//   nbt_sc_c: (r, g, b, depth key)   depth key = D, sky (D >= 1e10) = 1e30
//   nbt_sc_p: (M0, beta_px, sigma_px, 0)   sigma_px: the Gaussian width the
//             pyramid methods match (the caller's, or beta_px/sqrt 3)

const float NBT_SC_SQRT2PI = 2.50662827463100050;
const float NBT_SC_SKY = 1e10;

layout(binding = 0) uniform sampler2D nbt_sc_c;
layout(binding = 1) uniform sampler2D nbt_sc_p;
uniform ivec2 nbt_sc_size; // image w, h

// The weight a unit-mass erfc atom G(r/b)/(sqrt(2 pi) b r) gives to a whole
// pixel at distance r >= 3 px from the source (never used nearer, where the
// near table takes over): the value at the centre plus the second-order
// term of the pixel average, laplacian/24. The laplacian of the radial
// f = G(u)/(k r), u = r/b, k = sqrt(2 pi) b, is
// (u phi(u)/(b^2 r) + phi(u)/(b r^2) + G(u)/r^3)/k, phi the unit normal
// density. Against the exact pixel integral the mass it misplaces over all
// far pixels is below 1e-4 of the kernel's (doc: below 8e-5 for any beta;
// the plain centre value misplaces up to 5e-3).
float nbt_sc_far(float b, float r)
{
    float u = r / b, phi = exp(-0.5 * u * u) / NBT_SC_SQRT2PI, G = nbt_G(u);
    float lap = (u * phi / (b * b * r) + phi / (b * r * r) + G / (r * r * r));
    return (G / r + lap / 24.0) / (NBT_SC_SQRT2PI * b);
}

// Rec. 709 luminance (Elek et al. eq. 9 "absolute RGB luminance")
float nbt_sc_lum(vec3 c)
{
    return dot(c, vec3(0.2126, 0.7152, 0.0722));
}

bool nbt_sc_inside(ivec2 p, ivec2 size)
{
    return p.x >= 0 && p.y >= 0 && p.x < size.x && p.y < size.y;
}

// Where beta_px falls in the per-beta tables (entry i at beta = 2^(LO + i /
// PER)): entries i and i + 1 at fraction f, linear; past the last entry the
// last one, times scale = beta_last / beta (the tables scale as 1 / beta)
void nbt_sc_lut_at(float beta, out int i, out float f, out float scale)
{
    float u = beta > 0.0 ? (log2(beta) - float(NBT_SC_LUT_LO)) * float(NBT_SC_LUT_PER) : -1.0;
    scale = 1.0;
    if (u <= 0.0) {
        i = 0;
        f = 0.0;
    } else if (u >= float(NBT_SC_LUT_N - 1)) {
        i = NBT_SC_LUT_N - 2;
        f = 1.0;
        scale = exp2(float(NBT_SC_LUT_LO) + float(NBT_SC_LUT_N - 1) / float(NBT_SC_LUT_PER)) / beta;
    } else {
        i = int(floor(u));
        f = u - float(i);
    }
}
