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
