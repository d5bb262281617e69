// shaders/nbt_beam.glsl: the narrow-beam kernel of a homogeneous medium with
// a Gaussian phase function (Shinya et al.): Psi(z, r) = alpha/r G(r/beta),
// alpha and beta from the moments M0, M2 (eq. 25/26, A = sigma_s B) so that
// Psi reproduces them: beta^2 = 1.5 M2/M0, alpha = M0/(sqrt(2 pi) beta).
// G(x) = erfc(x/sqrt 2)/2 by Abramowitz & Stegun 7.1.26 (|error| <= 7.5e-8);
// in float the kernel carries ~1e-6 relative rounding besides.

// G(x) for x >= 0
float nbt_G(float x)
{
    float y = x * 0.70710678118654752;
    float t = 1.0 / (1.0 + 0.3275911 * y);
    float p = t * (0.254829592 + t * (-0.284496736 + t * (1.421413741 + t * (-1.453152027 + t * 1.061405429))));
    return 0.5 * p * exp(-y * y);
}

// M0, M2 at depth z
vec2 nbt_beam_moments(float sigma_t, float albedo, float B, float z)
{
    float ss = albedo * sigma_t, sa = sigma_t - ss, A = ss * B, a = ss, e = exp(-sa * z);
    float M0 = e * (1.0 - exp(-ss * z));
    float x = a * z, br;
    if (x < 0.5) { // the n = 0..2 terms cancel analytically (see doc/beam.md)
        float c = A * z * z / a - 2.0 * B / (a * a), t = x * x * x / 6.0;
        br = A * a * z * z * z * z / 2.0;
        for (int n = 3; n < 16; n++) {
            br += ((n % 2) == 1 ? -t : t) * c;
            t *= x / float(n + 1);
        }
    } else {
        br = exp(-x) * (A * z * z / a - 2.0 * B / (a * a)) + 2.0 * B / (a * a) - 2.0 * B * z / a + (B - A / a) * z * z +
             A * z * z * z;
    }
    return vec2(M0, a > 0.0 ? 4.0 * e * br : 0.0);
}

// (alpha, beta) of the kernel at depth z
vec2 nbt_beam_kernel_params(float sigma_t, float albedo, float B, float z)
{
    vec2 m = nbt_beam_moments(sigma_t, albedo, B, z);
    if (!(m.x > 0.0) || !(m.y > 0.0))
        return vec2(0.0);
    float beta = sqrt(1.5 * m.y / m.x);
    return vec2(m.x / (2.50662827463100050 * beta), beta);
}

float nbt_beam_psi(vec2 ab, float r)
{
    return (ab.y > 0.0 && r > 0.0) ? ab.x / r * nbt_G(r / ab.y) : 0.0;
}

// ---- the fitted kernel model (nbt/beam.h nbt_beam_fit; doc/fit.md) ----
// Psi = sigma_t^2 [a/rh G(rh/b) + M e^{-(q-h)/s}/(2 pi s (h+s))], rh = sigma_t r,
// q = sqrt(rh^2 + h^2), with (a, b, M, s, h) from the log-parameters P0..P4,
// polynomials in ln tau, albedo, ln B (tau = sigma_t z). Uniforms (set them
// with nbt_gl_set_beam_fit): the 5 x 16 coefficients of one geometry and the
// fitted range the monomials' arguments are clamped to (lo >= hi: none).
// The coefficients are 20 vec4s, not float[80]: std140 (Vulkan) would pad each
// float of an array to 16 bytes.
// Without libnbt-gl's target header (the screen-space passes include this
// module on its own): loose uniforms, as for OpenGL.
#ifndef NBT_BLOCK_END
#define NBT_U uniform
#define NBT_BLOCK_BEGIN(name, b)
#define NBT_BLOCK_END
#endif
NBT_BLOCK_BEGIN(nbt_beam_fit_block, 15)
NBT_U vec4 nbt_beam_fit_c[20];
NBT_U vec3 nbt_beam_fit_lo, nbt_beam_fit_hi; // (tau, albedo, B)
NBT_BLOCK_END

// erfc(x) for x >= 0 with relative error < 1.2e-7 everywhere (a Chebyshev
// fit; Numerical Recipes' erfcc): unlike nbt_G's A&S 7.1.26, also in the tail
float nbt_erfc(float x)
{
    float t = 1.0 / (1.0 + 0.5 * x);
    return t * exp(-x * x - 1.26551223 + t * (1.00002368 + t * (0.37409196 + t * (0.09678418 +
           t * (-0.18628806 + t * (0.27886807 + t * (-1.13520398 + t * (1.48851587 +
           t * (-0.82215223 + t * 0.17087277)))))))));
}

float nbt_beam_fit_clamp(float v, float lo, float hi)
{
    return lo < hi ? clamp(v, lo, hi) : v;
}

// P0..P4 at (tau, albedo, B)
void nbt_beam_fit_P(float tau, float albedo, float B, out float P[5])
{
    float x = log(nbt_beam_fit_clamp(tau, nbt_beam_fit_lo.x, nbt_beam_fit_hi.x)) - 1.15;
    float w = nbt_beam_fit_clamp(albedo, nbt_beam_fit_lo.y, nbt_beam_fit_hi.y) - 0.5;
    float v = log(nbt_beam_fit_clamp(B, nbt_beam_fit_lo.z, nbt_beam_fit_hi.z) / 0.05);
    float t[16] = float[16](1.0, x, w, v, x * x, x * w, x * v, w * w, w * v, v * v,
                            x * x * x, x * x * w, x * x * v, x * w * w, x * w * v, x * v * v);
    for (int i = 0; i < 5; i++) {
        float s = 0.0;
        for (int k = 0; k < 16; k++)
            s += nbt_beam_fit_c[4 * i + k / 4][k % 4] * t[k];
        P[i] = s;
    }
}

// (a, b, M, s, h) in sigma_t = 1 units from P0..P4 (or from nbt-gen kernel
// --model fitted's tables, which hold P0..P3 and P4 over (tau, albedo))
void nbt_beam_fit_from_P(float P[5], float tau, float albedo, float B, out float p[5])
{
    float y = albedo * tau;
    float om = y < 0.01 ? y * (1.0 - y * (0.5 - y / 6.0)) : 1.0 - exp(-y); // 1 - e^{-y} without cancellation
    float T = exp(-(1.0 - albedo) * tau) * om, L = tau * sqrt(2.0 * B);
    p[1] = L * exp(P[1]);
    p[0] = T * exp(P[0]) / (2.50662827463100050 * p[1]);
    p[2] = T * exp(P[2]);
    p[3] = L * exp(P[3]);
    p[4] = p[3] * exp(P[4]);
}

// Psi_hat at rh > 0 (0 at rh <= 0, where the core is infinite)
float nbt_beam_fit_eval(float p[5], float rh)
{
    if (!(rh > 0.0))
        return 0.0;
    float core = p[1] > 0.0 ? p[0] / rh * 0.5 * nbt_erfc(rh / (1.41421356237309505 * p[1])) : 0.0;
    float s = p[3], h = p[4], q = sqrt(rh * rh + h * h);
    return core + p[2] * exp(-rh * rh / ((q + h) * s)) / (6.28318530717958648 * s * (h + s));
}

// Psi(z, r) of a homogeneous medium (phase spread B = B_mix)
float nbt_beam_fit_psi(float sigma_t, float albedo, float B, float z, float r)
{
    float tau = sigma_t * z, P[5], p[5];
    nbt_beam_fit_P(tau, albedo, B, P);
    nbt_beam_fit_from_P(P, tau, albedo, B, p);
    return sigma_t * sigma_t * nbt_beam_fit_eval(p, sigma_t * r);
}
