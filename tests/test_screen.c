/* tests/test_screen.c: screen-space references (nbt/screen.h) against
 * independent quadrature, closed forms, invariants, and each other. */
#include <config.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include <nbt/nbt.h>
#include "testutil.h"

static double G(double x)
{
    return 0.5 * erfc(x / sqrt(2.0));
}

/* ---- independent reference for the pixel-integrated erfc kernel ----
 * k(r) = G(r/b)/(sqrt(2 pi) b r) has unit mass. Own pixel in polar
 * coordinates, the radial integral in closed form:
 * int_0^a G(r/b) dr = b (1/sqrt(2 pi) - phi(a/b) + (a/b) G(a/b)). */
static int own_f(double ph, void *vp, unsigned fdim, double *f)
{
    (void)fdim;
    double b = *(double *)vp, q = 0.5 / (b * cos(ph));
    double phi = exp(-0.5 * q * q) / sqrt(2.0 * M_PI);
    f[0] = 8.0 / sqrt(2.0 * M_PI) * (1.0 / sqrt(2.0 * M_PI) - phi + q * G(q));
    return 0;
}

typedef struct {
    double b, x, y0, y1;
    nbt_quad_ws *ws;
} cell_ctx;

static int cell_inner(double y, void *vp, unsigned fdim, double *f)
{
    (void)fdim;
    cell_ctx *c = vp;
    double r = hypot(c->x, y);
    f[0] = G(r / c->b) / (sqrt(2.0 * M_PI) * c->b * r);
    return 0;
}

static int cell_outer(double x, void *vp, unsigned fdim, double *f)
{
    (void)fdim;
    cell_ctx *c = vp;
    c->x = x;
    double v, e;
    nbt_quad_gk(c->ws, cell_inner, c, 1, c->y0, c->y1, 0, 1e-13, &v, &e);
    f[0] = v;
    return 0;
}

static double ref_pixel(double b, long dx, long dy)
{
    double v, e;
    nbt_quad_ws *ws = nbt_quad_ws_alloc(1, 500), *ws2 = nbt_quad_ws_alloc(1, 500);
    if (dx == 0 && dy == 0) {
        nbt_quad_gk(ws, own_f, &b, 1, 0, M_PI / 4, 0, 1e-13, &v, &e);
    } else {
        cell_ctx c = {b, 0, dy - 0.5, dy + 0.5, ws2};
        nbt_quad_gk(ws, cell_outer, &c, 1, dx - 0.5, dx + 0.5, 0, 1e-12, &v, &e);
    }
    nbt_quad_ws_free(ws);
    nbt_quad_ws_free(ws2);
    return v;
}

static void test_pixel_integrals(void)
{
    /* SCREENSPACE.md: own pixel 0.303 of M0 at beta = 2.07 px */
    t_abs(nbt_screen_atom_pixel(NBT_ATOM_ERFC, 2.07, 0, 0), 0.303, 5e-4, "own pixel at beta 2.07 px ~ 0.303");
    const double betas[] = {0.137, 0.61, 2.07, 7.385, 41.3};
    const long off[][2] = {{0, 0}, {1, 0}, {1, 1}, {2, 1}, {3, 0}, {5, 4}};
    for (size_t i = 0; i < sizeof betas / sizeof betas[0]; i++)
        for (size_t j = 0; j < sizeof off / sizeof off[0]; j++) {
            double want = ref_pixel(betas[i], off[j][0], off[j][1]);
            double got = nbt_screen_atom_pixel(NBT_ATOM_ERFC, betas[i], off[j][0], off[j][1]);
            if (want > 1e-12)
                t_rel(got, want, 1e-7, "erfc atom, beta %g px, offset (%ld,%ld) vs 2-D quadrature", betas[i],
                      off[j][0], off[j][1]);
            else
                t_abs(got, want, 1e-12, "erfc atom, beta %g px, far offset (%ld,%ld)", betas[i], off[j][0], off[j][1]);
        }
    /* symmetric in the offset */
    t_rel(nbt_screen_atom_pixel(NBT_ATOM_ERFC, 3.3, -2, 1), nbt_screen_atom_pixel(NBT_ATOM_ERFC, 3.3, 1, 2), 1e-14,
          "erfc atom symmetric");
    /* wide kernels: own pixel -> 2 ln(1 + sqrt2)/(sqrt(2 pi) beta) */
    double b = 400.0;
    t_rel(nbt_screen_atom_pixel(NBT_ATOM_ERFC, b, 0, 0) * b, 2.0 * log(1 + sqrt(2.0)) / sqrt(2.0 * M_PI), 2e-3,
          "own pixel of a wide kernel ~ 0.703/beta");
    /* Gaussian atom: product of erf differences */
    double s = 1.37, gx = 0.5 * (erf(1.5 / (sqrt(2.0) * s)) - erf(0.5 / (sqrt(2.0) * s)));
    double gy = 0.5 * (erf(2.5 / (sqrt(2.0) * s)) - erf(1.5 / (sqrt(2.0) * s)));
    t_rel(nbt_screen_atom_pixel(NBT_ATOM_GAUSS, s, 1, -2), gx * gy, 1e-14, "Gaussian atom at (1,-2)");
    /* truncation: the mass inside the square of radius R is >= 1 - tail,
     * and the closed-form tail is tight (a radius one smaller leaves more) */
    const double tails[] = {1e-3, 1e-6};
    for (int sh = 0; sh < 2; sh++)
        for (size_t i = 1; i < 4; i++)
            for (int t = 0; t < 2; t++) {
                nbt_atom_shape shape = sh ? NBT_ATOM_GAUSS : NBT_ATOM_ERFC;
                long R = nbt_screen_atom_radius(shape, betas[i], tails[t]);
                double in = 0;
                for (long y = -R; y <= R; y++)
                    for (long x = -R; x <= R; x++)
                        in += nbt_screen_atom_pixel(shape, betas[i], x, y);
                t_true(in >= 1 - tails[t] - 1e-9 && in <= 1 + 1e-9,
                       "%s atom %g px: mass %.12f inside R = %ld (tail %g)", sh ? "gauss" : "erfc", betas[i], in, R,
                       tails[t]);
            }
}

/* ---- radial masses of the atoms ----
 * ERFC atom of unit scale: 2 pi r k(r) = sqrt(2 pi) G(r), so its mass in
 * a0 <= r < a1 is sqrt(2 pi) int_a0^a1 G, done here by quadrature; GAUSS:
 * exp(-a0^2/2) - exp(-a1^2/2). Annuli on both sides of a = 1, where the
 * library switches from the inside form to the tail form. */
static int G_f(double u, void *vp, unsigned fdim, double *f)
{
    (void)vp;
    (void)fdim;
    f[0] = sqrt(2.0 * M_PI) * G(u);
    return 0;
}

static void test_atom_mass(void)
{
    nbt_quad_ws *ws = nbt_quad_ws_alloc(1, 500);
    const double a[][2] = {{0.0, 0.4}, {0.3, 0.999}, {1.0, 1.7}, {1.7, 3.2}, {2.5, INFINITY}, {0.5, INFINITY}};
    for (size_t i = 0; i < sizeof a / sizeof a[0]; i++) {
        double want, e, hi = isinf(a[i][1]) ? 40.0 : a[i][1]; /* G(40) ~ 1e-350: nothing beyond */
        nbt_quad_gk(ws, G_f, NULL, 1, a[i][0], hi, 0, 1e-13, &want, &e);
        /* 1e-10: the quadrature is good to ~1e-13; a wrong constant in a form is O(1) */
        t_rel(nbt_screen_atom_mass(NBT_ATOM_ERFC, a[i][0], a[i][1]), want, 1e-10,
              "erfc atom mass in [%g, %g) vs quadrature %.12g", a[i][0], a[i][1], want);
        double wg = exp(-0.5 * a[i][0] * a[i][0]) - exp(-0.5 * hi * hi);
        t_rel(nbt_screen_atom_mass(NBT_ATOM_GAUSS, a[i][0], a[i][1]), wg, 1e-12, "gauss atom mass in [%g, %g)",
              a[i][0], a[i][1]);
    }
    /* the truncation radius of a scale-3.1 px atom: the circle of radius R + 1/2
     * leaves at most the tail outside, R - 1/2 more than it */
    for (int sh = 0; sh < 2; sh++) {
        nbt_atom_shape shape = sh ? NBT_ATOM_GAUSS : NBT_ATOM_ERFC;
        double s = 3.1, tail = 1e-4, out_hi, out_lo, e;
        long R = nbt_screen_atom_radius(shape, s, tail);
        if (sh) {
            out_hi = exp(-0.5 * pow((R + 0.5) / s, 2));
            out_lo = exp(-0.5 * pow((R - 0.5) / s, 2));
        } else {
            nbt_quad_gk(ws, G_f, NULL, 1, (R + 0.5) / s, 40, 0, 1e-13, &out_hi, &e);
            nbt_quad_gk(ws, G_f, NULL, 1, (R - 0.5) / s, 40, 0, 1e-13, &out_lo, &e);
        }
        t_true(out_hi <= tail && out_lo > tail, "%s atom %g px, tail %g: R = %ld leaves %.3g beyond R + 1/2, %.3g beyond R - 1/2",
               sh ? "gauss" : "erfc", s, tail, R, out_hi, out_lo);
    }
    nbt_quad_ws_free(ws);
}

static void test_kernels(void)
{
    nbt_beam_medium m = nbt_beam_homogeneous(0.7385, 0.9, 0.0685);
    double D = 3.31, M0, M2, alpha, beta;
    nbt_beam_moments(&m, NBT_BEAM_ISHIMARU, D, &M0, &M2, NULL);
    nbt_beam_kernel_params(M0, M2, &alpha, &beta);
    nbt_screen_kern kn;
    nbt_screen_kernel *k = nbt_screen_kernel_alloc(NBT_SKERNEL_MOMENT, &m, NULL);
    nbt_screen_kernel_eval(k, D, &kn);
    t_true(kn.n == 1 && kn.shape[0] == NBT_ATOM_ERFC, "moment kernel: one erfc atom");
    t_rel(kn.mass[0], M0, 1e-14, "moment kernel mass = M0");
    t_rel(kn.scale[0], beta, 1e-14, "moment kernel scale = beta");
    t_rel(kn.T, exp(-m.sigma_t * D), 1e-14, "T = exp(-sigma_t D)");
    /* the atom's value at r equals nbt_beam_kernel */
    double r = 0.37 * beta;
    t_rel(kn.mass[0] * G(r / kn.scale[0]) / (sqrt(2 * M_PI) * kn.scale[0] * r), nbt_beam_kernel(alpha, beta, r), 1e-13,
          "erfc atom value = alpha/r G(r/beta)");
    nbt_screen_kernel_free(k);

    k = nbt_screen_kernel_alloc(NBT_SKERNEL_SINGLE, &m, NULL);
    nbt_screen_kernel_eval(k, D, &kn);
    double ss = m.albedo * m.sigma_t, psi;
    t_rel(kn.mass[0], ss * D * exp(-m.sigma_t * D), 1e-14, "single scattering mass = sigma_s D e^{-tau}");
    nbt_beam_psi(&m, NBT_PSI_SINGLE, D, r, &psi, NULL);
    t_rel(kn.mass[0] * G(r / kn.scale[0]) / (sqrt(2 * M_PI) * kn.scale[0] * r), psi, 1e-13,
          "single-scattering atom = nbt_beam_psi SINGLE");
    nbt_screen_kernel_free(k);

    k = nbt_screen_kernel_alloc(NBT_SKERNEL_LINEINT, &m, NULL);
    nbt_screen_kernel_eval(k, D, &kn);
    double mass = 0, m2 = 0, val = 0;
    for (size_t i = 0; i < kn.n; i++) {
        mass += kn.mass[i];
        m2 += kn.mass[i] * 2 * kn.scale[i] * kn.scale[i];
        val += kn.mass[i] * exp(-r * r / (2 * kn.scale[i] * kn.scale[i])) / (2 * M_PI * kn.scale[i] * kn.scale[i]);
    }
    t_rel(mass, M0, 1e-12, "line-integral kernel mass = M0");
    t_rel(m2, M2, 1e-10, "line-integral kernel second moment = M2 (eq. 26)");
    nbt_beam_psi(&m, NBT_PSI_LINEINT, D, r, &psi, NULL);
    t_rel(val, psi, 1e-6, "line-integral atoms at r = nbt_beam_psi LINEINT");
    nbt_screen_kernel_free(k);

    k = nbt_screen_kernel_alloc(NBT_SKERNEL_ELEK, &m, NULL);
    nbt_screen_kernel_eval(k, D, &kn);
    nbt_beam_psi(&m, NBT_PSI_ELEK, D, r, &psi, NULL);
    t_rel(kn.mass[0] * exp(-r * r / (2 * kn.scale[0] * kn.scale[0])) / (2 * M_PI * kn.scale[0] * kn.scale[0]), psi,
          1e-12, "Elek atom = nbt_beam_psi ELEK");
    /* edges of the domain */
    nbt_screen_kernel_eval(k, 0, &kn);
    t_true(kn.n == 0 && kn.T == 1, "D = 0: T = 1, no scattering");
    nbt_screen_kernel_eval(k, INFINITY, &kn);
    t_true(kn.n == 0 && kn.T == 0, "sky (inf): T = 0, sends nothing");
    nbt_screen_kernel_eval(k, 1e10, &kn);
    t_true(kn.n == 0 && kn.T == 0, "sky (1e10): T = 0, sends nothing");
    t_true(nbt_screen_kernel_eval(k, -1, &kn) == NBT_EDOM, "negative depth rejected");
    t_true(nbt_screen_kernel_eval(k, NAN, &kn) == NBT_EDOM, "NaN depth rejected");
    nbt_screen_kernel_free(k);
    nbt_beam_medium m0 = nbt_beam_homogeneous(0.7, 0.0, 0.0685);
    k = nbt_screen_kernel_alloc(NBT_SKERNEL_MOMENT, &m0, NULL);
    nbt_screen_kernel_eval(k, 2.0, &kn);
    t_true(kn.n == 0, "albedo 0: no scattered mass");
    nbt_screen_kernel_free(k);
    nbt_skernel_kind kk;
    t_true(nbt_skernel_parse("lineint", &kk) == NBT_OK && kk == NBT_SKERNEL_LINEINT &&
               nbt_skernel_parse("bogus", &kk) == NBT_EINVAL,
           "kernel names parse");
    /* every kind's documented name (nbt/screen.h), and parse inverts name */
    static const char *const kn_names[8] = {"moment", "smallangle", "corrected", "single",
                                            "lineint", "elek", "fitted", "first"};
    int names_ok = 1;
    for (int i = 0; i < 8; i++) {
        nbt_skernel_kind ki = (nbt_skernel_kind)-1;
        names_ok &= !strcmp(nbt_skernel_name((nbt_skernel_kind)i), kn_names[i]) &&
                    nbt_skernel_parse(kn_names[i], &ki) == NBT_OK && ki == (nbt_skernel_kind)i;
    }
    t_true(names_ok, "kernel kinds named moment .. first in enum order; parse inverts name");
}

/* ---- operators ---- */

typedef struct {
    size_t w, h;
    float *rgb, *D;
} scene;

static scene scene_new(size_t w, size_t h)
{
    scene s = {w, h, calloc(w * h * 3, sizeof(float)), calloc(w * h, sizeof(float))};
    return s;
}

static void scene_free(scene *s)
{
    free(s->rgb);
    free(s->D);
}

static nbt_screen_input as_input(const scene *s, double dtheta)
{
    nbt_screen_input in = {s->w, s->h, s->rgb, s->D, dtheta, NULL};
    return in;
}

static void test_operators(void)
{
    nbt_beam_medium m = nbt_beam_homogeneous(0.2385, 0.93, 0.0085); /* dtheta = 10.6 deg */
    nbt_screen_kernel *k = nbt_screen_kernel_alloc(NBT_SKERNEL_MOMENT, &m, NULL);
    const double dth = 0.08, tail = 1e-9;
    const size_t W = 64, H = 56, N = W * H;
    double *S = malloc(N * 3 * sizeof *S), *S2 = malloc(N * 3 * sizeof *S2), *T = malloc(N * sizeof *T);
    nbt_screen_kern kn;

    /* constant image at constant depth: interior receives M0 c, J = (T + M0) c */
    scene s = scene_new(W, H);
    double Dw = 7.3;
    for (size_t i = 0; i < N; i++) {
        s.D[i] = (float)Dw;
        s.rgb[3 * i] = 1.25f, s.rgb[3 * i + 1] = 0.5f, s.rgb[3 * i + 2] = 2.0f;
    }
    nbt_screen_kernel_eval(k, (float)Dw, &kn);
    nbt_screen_input in = as_input(&s, dth);
    long R = nbt_screen_atom_radius(NBT_ATOM_ERFC, kn.scale[0] / ((float)Dw * dth), tail);
    t_true(nbt_screen_brute(&in, k, NBT_SCREEN_NEAR, tail, 2, S, T) == NBT_OK, "brute force runs");
    size_t c = (H / 2) * W + W / 2;
    t_true(R < (long)H / 2, "wall kernel fits on screen (R = %ld px)", R);
    t_rel(S[3 * c] / 1.25, kn.mass[0], 1e-8, "constant wall: interior S = M0 c (red)");
    t_rel(S[3 * c + 2] / 2.0, kn.mass[0], 1e-8, "constant wall: interior S = M0 c (blue)");
    t_rel(T[c], kn.T, 1e-7, "constant wall: T");
    t_true(S[0] < 0.5 * kn.mass[0] * 1.25 && S[0] > 0.2 * kn.mass[0] * 1.25,
           "corner pixel keeps only what lands on screen (%.3f of M0)", S[0] / (kn.mass[0] * 1.25));

    /* impulse response integrates to M0; same for both rules at constant depth */
    memset(s.rgb, 0, N * 3 * sizeof(float));
    s.rgb[3 * c + 1] = 3.0f;
    nbt_screen_brute(&in, k, NBT_SCREEN_NEAR, tail, 1, S, NULL);
    double sum = 0;
    for (size_t i = 0; i < N; i++)
        sum += S[3 * i + 1];
    t_rel(sum / 3.0, kn.mass[0], 1e-8, "impulse response integrates to M0");
    t_rel(S[3 * c + 1] / 3.0, kn.mass[0] * nbt_screen_atom_pixel(NBT_ATOM_ERFC, kn.scale[0] / ((float)Dw * dth), 0, 0),
          1e-12, "impulse: own pixel weight");
    t_abs(S[3 * c], 0, 0, "impulse: other channels untouched");

    /* two layers: a near square over a far wall; check the pair rule */
    double Dn = 2.9, Df = 11.7;
    for (size_t y = 0; y < H; y++)
        for (size_t x = 0; x < W; x++)
            s.D[y * W + x] = (float)(x >= 10 && x < 30 && y >= 8 && y < 28 ? Dn : Df);
    nbt_screen_kern kf;
    nbt_screen_kernel_eval(k, (float)Dn, &kn);
    nbt_screen_kernel_eval(k, (float)Df, &kf);
    double bn = kn.scale[0] / ((float)Dn * dth), bf = kf.scale[0] / ((float)Df * dth);
    memset(s.rgb, 0, N * 3 * sizeof(float));
    size_t src = 18 * W + 34, rcv = 18 * W + 28; /* far source, near receiver 6 px left */
    s.rgb[3 * src] = 1.0f;
    nbt_screen_brute(&in, k, NBT_SCREEN_NEAR, tail, 2, S, NULL);
    t_rel(S[3 * rcv], kn.mass[0] * nbt_screen_atom_pixel(NBT_ATOM_ERFC, bn, 6, 0), 1e-12,
          "A: far source -> near receiver uses the near (receiver's) kernel");
    t_rel(S[3 * (18 * W + 40)], kf.mass[0] * nbt_screen_atom_pixel(NBT_ATOM_ERFC, bf, 6, 0), 1e-12,
          "A: far source -> far receiver uses the far kernel");
    nbt_screen_brute(&in, k, NBT_SCREEN_SOURCE, tail, 2, S, NULL);
    t_rel(S[3 * rcv], kf.mass[0] * nbt_screen_atom_pixel(NBT_ATOM_ERFC, bf, 6, 0), 1e-12,
          "B: far source -> near receiver uses the source's kernel");
    memset(s.rgb, 0, N * 3 * sizeof(float));
    s.rgb[3 * rcv + 2] = 1.0f; /* near source, far receiver 6 px right */
    nbt_screen_brute(&in, k, NBT_SCREEN_NEAR, tail, 2, S, NULL);
    t_rel(S[3 * src + 2], kn.mass[0] * nbt_screen_atom_pixel(NBT_ATOM_ERFC, bn, 6, 0), 1e-12,
          "A: near source -> far receiver uses the near (source's) kernel");

    /* linearity, and brute force = layered FFT on a layered scene with sky */
    for (size_t y = 0; y < H; y++)
        for (size_t x = 0; x < W; x++) {
            size_t i = y * W + x;
            s.D[i] = (float)(y < 6 ? 1e10 : x < 16 ? 3.7 : x < 33 ? 9.1 : 5.2);
            /* multiples of 1/1024, so that 2 c + 3 c' below is exact in float */
            s.rgb[3 * i] = (float)(floor(t_uniform() * 2048) / 1024);
            s.rgb[3 * i + 1] = (float)(floor(t_uniform() * 1024) / 1024 * (x == 20 && y == 20 ? 400 : 1)); /* an HDR lamp */
            s.rgb[3 * i + 2] = (float)(floor(t_uniform() * 1024) / 1024);
        }
    /* at dtheta = 0.005 the kernels (beta ~ 30 px) are wider than the image: both clip them alike.
     * The two differ by round-off: the FFT's is about u log2(n) of the data's 2-norm (u = 1.1e-16,
     * n ~ 2^14 padded points, 2-norm <= sqrt(64 x 56) = 60 max S): ~1e-13 of max S; limit 1e-12
     * (measured 1.6e-15) */
    for (int rule = 0; rule < 4; rule++) {
        in.dtheta = rule < 2 ? dth : 0.005;
        nbt_screen_brute(&in, k, (nbt_screen_rule)(rule % 2), tail, 2, S, NULL);
        nbt_status st = nbt_screen_layered(&in, k, (nbt_screen_rule)(rule % 2), tail, 8, 2, S2, T);
        double d = 0;
        for (size_t i = 0; i < N * 3; i++)
            d = fmax(d, fabs(S[i] - S2[i]));
        t_true(st == NBT_OK && d <= 1e-12 * t_maxabs(S, N * 3),
               "%s, dtheta %g: brute force = layered FFT (max diff %.2g of max S)", rule % 2 ? "B" : "A", in.dtheta,
               d / t_maxabs(S, N * 3));
    }
    in.dtheta = dth;
    t_true(nbt_screen_layered(&in, k, NBT_SCREEN_NEAR, tail, 3, 2, S2, T) == NBT_EDOM,
           "layered: more depths than layers is refused");
    t_abs(T[0], 0, 0, "sky pixel: T = 0");
    /* linearity */
    double *S3 = malloc(N * 3 * sizeof *S3);
    nbt_screen_brute(&in, k, NBT_SCREEN_NEAR, tail, 2, S, NULL);
    float *orig = malloc(N * 3 * sizeof *orig);
    memcpy(orig, s.rgb, N * 3 * sizeof *orig);
    for (size_t i = 0; i < N * 3; i++)
        s.rgb[i] = (float)(i % 7 == 0);
    nbt_screen_brute(&in, k, NBT_SCREEN_NEAR, tail, 2, S2, NULL);
    for (size_t i = 0; i < N * 3; i++)
        s.rgb[i] = 2.0f * orig[i] + 3.0f * (float)(i % 7 == 0);
    nbt_screen_brute(&in, k, NBT_SCREEN_NEAR, tail, 2, S3, NULL);
    double d = 0;
    for (size_t i = 0; i < N * 3; i++)
        d = fmax(d, fabs(S3[i] - 2 * S[i] - 3 * S2[i]));
    t_true(d <= 1e-12 * t_maxabs(S3, N * 3), "operator A is linear in the image (%.2g)", d / t_maxabs(S3, N * 3));

    /* continuous depth (a slanted floor): quantised layers converge to brute force as 1/L */
    {
        float *Dc = malloc(N * sizeof *Dc), *Dq = malloc(N * sizeof *Dq);
        for (size_t y = 0; y < H; y++)
            for (size_t x = 0; x < W; x++)
                Dc[y * W + x] = (float)(y < 8 ? 1e10 : 2.0 + 30.0 / (double)(y - 7));
        nbt_screen_input ic = in;
        ic.D = Dc;
        nbt_screen_brute(&ic, k, NBT_SCREEN_NEAR, tail, 2, S, NULL);
        double l1[2];
        const size_t Ls[2] = {16, 64};
        for (int q = 0; q < 2; q++) {
            nbt_screen_quantize(Dc, N, Ls[q], Dq);
            ic.D = Dq;
            nbt_screen_layered(&ic, k, NBT_SCREEN_NEAR, tail, Ls[q] + 2, 2, S2, NULL);
            nbt_screen_metrics mq;
            nbt_screen_compare(&ic, k, S2, S, &mq);
            l1[q] = mq.rel_l1;
        }
        t_true(l1[1] < 0.01 && l1[1] < 0.5 * l1[0], "quantised depth: rel L1 %.2g (16 layers), %.2g (64 layers)", l1[0],
               l1[1]);
        double lo = 2.0 + 30.0 / (double)(H - 8), hi = 32.0, r = pow(hi / lo, 1.0 / 15.0), worst = 0;
        nbt_screen_quantize(Dc, N, 16, Dq);
        for (size_t i = 8 * W; i < N; i++)
            worst = fmax(worst, fabs(log(Dq[i] / Dc[i])));
        t_true(worst <= 0.5 * log(r) * (1 + 1e-6) && Dq[0] == Dc[0], "quantise: within half a layer in log, sky kept");
        /* L = 2: every depth snaps to the nearest or the farthest, whichever is nearer in log; L < 2: unchanged */
        nbt_screen_quantize(Dc, N, 2, Dq);
        int two = 1, one = 1;
        for (size_t i = 8 * W; i < N; i++)
            two &= Dq[i] == (float)(fabs(log(Dc[i] / lo)) <= fabs(log(hi / Dc[i])) ? lo : hi) ||
                   fabs(log(Dc[i] * Dc[i] / (lo * hi))) < 1e-6; /* a tie may go either way */
        nbt_screen_quantize(Dc, N, 1, Dq);
        for (size_t i = 0; i < N; i++)
            one &= Dq[i] == Dc[i];
        t_true(two && one, "quantise: 2 layers are the two ends (%d), 1 layer leaves D unchanged (%d)", two, one);
        free(Dc);
        free(Dq);
    }

    /* metrics on a known perturbation */
    nbt_screen_metrics mt;
    for (size_t i = 0; i < N * 3; i++)
        S2[i] = 1.01 * S[i];
    nbt_screen_compare(&in, k, S2, S, &mt);
    t_rel(mt.rel_l1, 0.01, 1e-9, "metrics: rel L1 of a 1%% scale");
    t_rel(mt.rel_rms, 0.01, 1e-9, "metrics: rel RMS of a 1%% scale");
    t_rel(mt.bias, 0.01, 1e-9, "metrics: bias of a 1%% scale");
    t_rel(mt.max, 0.01, 1e-9, "metrics: max of a 1%% scale");
    t_rel(mt.edge, 0.01, 1e-9, "metrics: edge band of a 1%% scale");
    t_true(mt.edge_pixels > 0 && mt.edge_pixels < N, "metrics: a band around the depth edges (%zu px)", mt.edge_pixels);
    memcpy(S2, S, N * 3 * sizeof *S);
    S2[3 * (20 * W + 31)] += 0.5 * t_maxabs(S, N * 3); /* next to the 9.1 | 5.2 edge */
    nbt_screen_compare(&in, k, S2, S, &mt);
    t_rel(mt.max, 0.5, 1e-12, "metrics: max error");
    t_true(mt.edge > mt.rel_rms, "metrics: an error at an edge weighs more in the band");

    /* bad input */
    s.D[5] = -1.0f;
    t_true(nbt_screen_brute(&in, k, NBT_SCREEN_NEAR, tail, 2, S, NULL) == NBT_EDOM, "negative depth refused");
    s.D[5] = NAN;
    t_true(nbt_screen_layered(&in, k, NBT_SCREEN_NEAR, tail, 8, 2, S, NULL) == NBT_EDOM, "NaN depth refused");
    s.D[5] = 3.0f;
    in.dtheta = 0;
    t_true(nbt_screen_brute(&in, k, NBT_SCREEN_NEAR, tail, 2, S, NULL) == NBT_EDOM, "dtheta 0 refused");
    /* depth 0 and albedo 0 */
    in.dtheta = dth;
    for (size_t i = 0; i < N; i++)
        s.D[i] = 0.0f;
    nbt_screen_brute(&in, k, NBT_SCREEN_NEAR, tail, 2, S, T);
    t_true(t_maxabs(S, N * 3) == 0 && T[7] == 1, "D = 0 everywhere: S = 0, T = 1");
    t_rel(nbt_screen_ray_distance(2.0, 100, 80, 0.01, 0, 0), 2.0 * sqrt(1 + 0.495 * 0.495 + 0.395 * 0.395), 1e-14,
          "planar depth to ray distance at a corner pixel");
    free(orig);
    free(S3);
    scene_free(&s);
    free(S);
    free(S2);
    free(T);
    nbt_screen_kernel_free(k);
}


/* ---- heterogeneous media ---- */

static double dens_const(const double p[3], void *ctx)
{
    (void)p;
    return *(double *)ctx;
}

/* world density along the camera's z axis: 1 + 0.6 sin(0.9 t) at distance t */
static double dens_wave(const double p[3], void *ctx)
{
    (void)ctx;
    return 1.0 + 0.6 * sin(0.9 * -p[2]);
}

/* the same seen from a beam starting at the surface (distance D): z' = D - t */
static double beam_wave(double z, void *ctx)
{
    double D = *(double *)ctx;
    return 1.0 + 0.6 * sin(0.9 * (D - z));
}

static void test_medium(void)
{
    nbt_beam_medium m = nbt_beam_homogeneous(0.31, 0.87, 0.0123);
    const size_t W = 5, H = 5;
    float rgb[5 * 5 * 3] = {0}, D[5 * 5];
    for (size_t i = 0; i < W * H; i++)
        D[i] = (float)(4.0 + 0.5 * (double)i);
    D[3] = 1e10f; /* sky */
    nbt_screen_input in = {W, H, rgb, D, 0.02, NULL};
    nbt_camera cam = {{0, 0, 0}, {0, 0, -1}, {0, 1, 0}};
    nbt_screen_pixkern pix[25];
    float skyD[25];
    for (size_t i = 0; i < 25; i++)
        skyD[i] = 20.0f;
    double err, rho = 1.0;
    nbt_status st = nbt_screen_medium_kernels(&in, &m, dens_const, &rho, &cam, 0.002, skyD, 2, pix, &err);
    t_true(st == NBT_OK, "medium kernels: constant density");
    double worst = 0;
    for (size_t i = 0; i < W * H; i++) {
        double Dm = i == 3 ? 20.0 : D[i], M0, M2, alpha, beta;
        nbt_beam_moments(&m, NBT_BEAM_ISHIMARU, Dm, &M0, &M2, NULL);
        nbt_beam_kernel_params(M0, M2, &alpha, &beta);
        worst = fmax(worst, fabs(pix[i].beta_px - beta / (Dm * 0.02)) / (beta / (Dm * 0.02)));
        t_rel(pix[i].M0, M0, 1e-11, "medium, constant density: M0 = eq. 25 (pixel %zu)", i);
        t_rel(pix[i].T, exp(-m.sigma_t * Dm), 1e-11, "medium, constant density: T (pixel %zu)", i);
    }
    t_true(worst < 1e-6, "medium, constant density: beta = eq. 26 (worst rel %.2g)", worst);
    t_true(worst <= err && err < 1e-5, "medium: the step estimate (%.2g) bounds the true error (%.2g)", err, worst);
    /* a smooth density along the central ray against nbt_beam_moments' adaptive quadrature */
    st = nbt_screen_medium_kernels(&in, &m, dens_wave, NULL, &cam, 0.004, skyD, 1, pix, &err);
    t_true(st == NBT_OK, "medium kernels: a smooth density");
    size_t c = 2 * W + 2;
    double Dc = D[c], M0, M2, alpha, beta;
    nbt_beam_medium mb = m;
    mb.rho_fn = beam_wave;
    mb.rho_data = &Dc;
    nbt_beam_moments(&mb, NBT_BEAM_ISHIMARU, Dc, &M0, &M2, NULL);
    nbt_beam_kernel_params(M0, M2, &alpha, &beta);
    t_rel(pix[c].M0, M0, 1e-5, "medium, smooth density: M0 vs adaptive eq. 28");
    t_rel(pix[c].beta_px, beta / (Dc * 0.02), 3 * err + 1e-9, "medium, smooth density: beta vs adaptive eq. 29 (3 x estimate %.2g)", err);
    t_rel(pix[c].T, exp(-m.sigma_t * nbt_beam_zeta(&mb, Dc)), 1e-5, "medium, smooth density: T");
    nbt_screen_medium_kernels(&in, &m, dens_wave, NULL, &cam, 0.004, NULL, 1, pix, &err);
    t_true(pix[3].T == 0 && pix[3].M0 == 0, "medium without sky_D: sky behind infinite medium");
    /* the operators take per-pixel kernels: equal ones reproduce the family */
    nbt_screen_kernel *k = nbt_screen_kernel_alloc(NBT_SKERNEL_MOMENT, &m, NULL);
    for (size_t i = 0; i < W * H; i++) {
        nbt_screen_kern kn;
        nbt_screen_kernel_eval(k, D[i], &kn);
        pix[i].T = kn.T;
        pix[i].M0 = kn.n ? kn.mass[0] : 0;
        pix[i].beta_px = kn.n ? kn.scale[0] / (D[i] * 0.02) : 0;
        rgb[3 * i] = (float)(i % 4), rgb[3 * i + 1] = 1, rgb[3 * i + 2] = (float)(i % 3);
    }
    double S1[75], S2[75];
    nbt_screen_brute(&in, k, NBT_SCREEN_NEAR, 1e-9, 1, S1, NULL);
    in.pix = pix;
    nbt_screen_brute(&in, NULL, NBT_SCREEN_NEAR, 1e-9, 1, S2, NULL);
    double d = 0;
    for (int i = 0; i < 75; i++)
        d = fmax(d, fabs(S1[i] - S2[i]) / fabs(S1[i] + 1e-300));
    t_true(d < 1e-12, "per-pixel kernels = the family's (max rel %.2g)", d);
    t_true(nbt_screen_layered(&in, NULL, NBT_SCREEN_NEAR, 1e-9, 8, 1, S2, NULL) == NBT_EINVAL,
           "layered FFT refuses per-pixel kernels");
    nbt_screen_kernel_free(k);

    /* grids: trilinear at centres and between them, zero outside, raw round trip */
    double o[3] = {-1.0, 0.5, 2.0};
    nbt_grid *g = nbt_grid_alloc(4, 3, 2, o, 0.5);
    for (size_t i = 0; i < 24; i++)
        g->data[i] = (float)(0.25 * (double)i);
    double p[3] = {-1.0 + 0.5, 0.5 + 0.5, 2.0 + 0.5};
    t_rel(nbt_grid_density(p, g), g->data[(1 * 3 + 1) * 4 + 1], 1e-15, "grid: value at a voxel centre");
    double q[3] = {-1.0 + 0.75, 0.5 + 0.25, 2.0 + 0.25}; /* halfway in x, y, z from voxel (1,0,0) */
    double want = 0;
    for (int cz = 0; cz < 2; cz++)
        for (int cy = 0; cy < 2; cy++)
            for (int cx = 0; cx < 2; cx++)
                want += 0.125 * g->data[(cz * 3 + cy) * 4 + 1 + cx];
    t_rel(nbt_grid_density(q, g), want, 1e-14, "grid: trilinear midpoint");
    double out[3] = {-1.3, 0.5, 2.0};
    t_abs(nbt_grid_density(out, g), 0, 0, "grid: zero outside the box");
    double o2[3] = {0.3, 1.0, -5.0}, dz[3] = {0, 0, 1};
    t_rel(nbt_grid_exit(g, o2, dz), 5.0 + 2.0 + 0.75, 1e-14, "grid: exit distance along z");
    /* oblique rays with negative components (the box is (-1.25, 0.25, 1.75) .. (0.75, 1.75, 2.75)):
     * from inside along the unit (-0.6, -0.64, 0.48), out through y = 0.25 at (0.25 - 0.6)/-0.64;
     * from outside along -x, in at x = 0.75 and out at x = -1.25, t = 3.25; a ray past the box: 0 */
    double o3[3] = {0.5, 0.6, 1.9}, d3[3] = {-0.6, -0.64, 0.48}, o4[3] = {2.0, 1.0, 2.2}, d4[3] = {-1, 0, 0},
           d5[3] = {0, 1, 0};
    t_rel(nbt_grid_exit(g, o3, d3), 0.35 / 0.64, 1e-14, "grid: exit of an oblique ray through the -y face");
    t_rel(nbt_grid_exit(g, o4, d4), 3.25, 1e-14, "grid: a ray along -x from outside leaves at x = -1.25");
    t_true(nbt_grid_exit(g, o4, d5) == 0, "grid: a ray that misses the box: 0");
    char err2[256], path[64];
    snprintf(path, sizeof path, "/tmp/nbt-test-grid-%ld.raw", (long)getpid());
    nbt_grid *g2 = NULL;
    t_true(nbt_grid_write_raw(g, path, err2, sizeof err2) == NBT_OK &&
               nbt_grid_read_raw(path, &g2, err2, sizeof err2) == NBT_OK && g2->nx == 4 && g2->nz == 2 &&
               g2->voxel == 0.5 && g2->origin[0] == -1.0 && !memcmp(g2->data, g->data, 24 * sizeof(float)),
           "grid: raw round trip");
    nbt_grid_free(g2);
    g->data[7] = -1.0f;
    nbt_grid_write_raw(g, path, err2, sizeof err2);
    t_true(nbt_grid_read_raw(path, &g2, err2, sizeof err2) == NBT_EFORMAT && strstr(err2, "(3, 1, 0)") && !g2,
           "grid: a negative voxel is refused and named: %s", err2);
    /* a header with a zero size: a format error naming the size (it was NBT_ENOMEM, "cannot be allocated") */
    FILE *fz = fopen(path, "wb");
    fprintf(fz, "NBTGRID 1 3 0 2 0 0 0 1\n");
    fclose(fz);
    t_true(nbt_grid_read_raw(path, &g2, err2, sizeof err2) == NBT_EFORMAT && strstr(err2, "3x0x2") && !g2,
           "grid: a zero size in the header is a format error: %s", err2);
    unlink(path);
    t_true(nbt_grid_read_raw(path, &g2, err2, sizeof err2) == NBT_EIO, "grid: missing file");
    /* nbt/grid.h: the origin must be finite, each of its three coordinates (a raw header's
     * "nan" or "inf" parses as a number) */
    g->data[7] = 1.0f;
    err2[0] = '\0';
    t_true(nbt_grid_check(g, err2, sizeof err2) == NBT_OK, "grid: the check passes a good grid: %s", err2);
    for (int ax = 0; ax < 3; ax++) {
        const double bad[2] = {NAN, INFINITY};
        for (int b = 0; b < 2; b++) {
            g->origin[ax] = bad[b];
            t_true(nbt_grid_check(g, err2, sizeof err2) == NBT_EDOM && strstr(err2, "origin"),
                   "grid: origin[%d] = %g refused: %s", ax, bad[b], err2);
        }
        g->origin[ax] = o[ax];
    }
    nbt_grid_free(g);
}

/* ---- a density that varies with height and across: the camera's ray directions ----
 * rho = 1 + 0.5 y + 0.15 x (world y up, x right), linear along every ray, so
 * zeta(D) = int_0^D rho(pos + t dir) dt = D rho(pos) + (D^2/2)(0.5 dir_y + 0.15 dir_x)
 * in closed form and the trapezoid rule is exact (up to rounding). The
 * pinhole's direction is written here from the header's convention (row 0 at
 * the top, towards up; column 0 at the left): dir = (u, v, -1)/sqrt(1 + u^2 + v^2)
 * for a camera looking along -z with up +y, u = (x + 1/2 - W/2) dtheta,
 * v = (H/2 - y - 1/2) dtheta. A flipped vertical (top row looking down)
 * moves zeta of the top and bottom rows by D^2 0.5 |v| / sqrt(1 + u^2 + v^2)
 * (0.6 to 2.2 here: T by a factor 0.8 to 0.43, against 1e-12); a flipped
 * horizontal, of the outer columns, by D^2 0.15 |u| / sqrt(...) (0.35 to 1.3). */
static double dens_slope(const double p[3], void *ctx)
{
    (void)ctx;
    return 1.0 + 0.5 * p[1] + 0.15 * p[0];
}

/* the closed-form optical depth zeta of pixel (x, y) of a W x H image
 * (ray distance Dp) from a camera at cpos looking down -z through
 * dens_slope; roll = 0: up +y (image right = +x, up = +y), roll = 1: up +x
 * (right = fwd x up = -y, up = +x) */
static double zeta_slope_roll(size_t x, size_t y, size_t W, size_t H, double dth, double Dp, const double cpos[3],
                              int roll)
{
    double u = ((double)x + 0.5 - 0.5 * (double)W) * dth, v = (0.5 * (double)H - (double)y - 0.5) * dth;
    double n = sqrt(1 + u * u + v * v), dx = roll ? v / n : u / n, dy = roll ? -u / n : v / n;
    return Dp * dens_slope(cpos, NULL) + 0.5 * Dp * Dp * (0.5 * dy + 0.15 * dx);
}

static double zeta_slope(size_t x, size_t y, size_t W, size_t H, double dth, double Dp, const double cpos[3])
{
    return zeta_slope_roll(x, y, W, H, dth, Dp, cpos, 0);
}

static void test_medium_height(void)
{
    const size_t W = 7, H = 4; /* non-square: a pitch from the width would show too */
    const double dth = 0.09, cpos[3] = {0.3, -0.2, 1.1};
    nbt_beam_medium m = nbt_beam_homogeneous(0.37, 0.8, 0.011);
    float rgb[7 * 4 * 3] = {0}, D[7 * 4];
    for (size_t i = 0; i < W * H; i++)
        D[i] = (float)(3.0 + 0.1 * (double)((i * 5) % 29)); /* 3 .. 5.8, no two rows alike */
    nbt_screen_input in = {W, H, rgb, D, dth, NULL};
    /* up neither unit nor orthogonal to the view direction; fwd not unit */
    nbt_camera cam = {{cpos[0], cpos[1], cpos[2]}, {0, 0, -2.0}, {0, 1.5, 0.4}};
    nbt_screen_pixkern pix[7 * 4];
    double err, sa = m.sigma_t * (1 - m.albedo), ss = m.sigma_t * m.albedo;
    nbt_status st = nbt_screen_medium_kernels(&in, &m, dens_slope, NULL, &cam, 0.01, NULL, 1, pix, &err);
    t_true(st == NBT_OK, "medium kernels: a density linear in height");
    double worst = 0, worstM = 0;
    for (size_t y = 0; y < H; y++)
        for (size_t x = 0; x < W; x++) {
            size_t i = y * W + x;
            double zeta = zeta_slope(x, y, W, H, dth, D[i], cpos);
            double T = exp(-m.sigma_t * zeta), M0 = exp(-sa * zeta) * -expm1(-ss * zeta);
            worst = fmax(worst, fabs(pix[i].T - T) / T);
            worstM = fmax(worstM, fabs(pix[i].M0 - M0) / M0);
        }
    t_true(worst < 1e-12 && worstM < 1e-12,
           "medium, density linear in height: T and M0 of all 7x4 pixels = the closed form (worst rel %.2g, %.2g)",
           worst, worstM);
    /* the camera rolled by 90 degrees (up along +x: its right vector fwd x up has no x part) */
    nbt_camera rolled = {{cpos[0], cpos[1], cpos[2]}, {0, 0, -2.0}, {1.5, 0, 0.4}};
    st = nbt_screen_medium_kernels(&in, &m, dens_slope, NULL, &rolled, 0.01, NULL, 1, pix, &err);
    worst = 0;
    for (size_t y = 0; st == NBT_OK && y < H; y++)
        for (size_t x = 0; x < W; x++) {
            double T = exp(-m.sigma_t * zeta_slope_roll(x, y, W, H, dth, D[y * W + x], cpos, 1));
            worst = fmax(worst, fabs(pix[y * W + x].T - T) / T);
        }
    t_true(st == NBT_OK && worst < 1e-12, "medium, camera rolled 90 degrees: T of all 7x4 pixels = the closed form "
           "(status %d, worst rel %.2g)", st, worst);

    /* the same field as a dense grid (trilinear: exact for a linear field between
     * voxel centres, float values: 1e-7 relative): T through nbt_grid_density */
    double o[3] = {-1.75, -1.5, -5.5};
    nbt_grid *g = nbt_grid_alloc(17, 11, 29, o, 0.25);
    t_true(g != NULL, "grid 17x11x29");
    if (!g)
        return;
    for (size_t k = 0; k < 29; k++)
        for (size_t j = 0; j < 11; j++)
            for (size_t i = 0; i < 17; i++) {
                double p[3] = {o[0] + 0.25 * (double)i, o[1] + 0.25 * (double)j, o[2] + 0.25 * (double)k};
                g->data[(k * 11 + j) * 17 + i] = (float)dens_slope(p, NULL);
            }
    st = nbt_screen_medium_kernels(&in, &m, nbt_grid_density, g, &cam, 0.05, NULL, 2, pix, &err);
    worst = 0;
    for (size_t y = 0; y < H; y++)
        for (size_t x = 0; x < W; x++) {
            size_t i = y * W + x;
            double zeta = zeta_slope(x, y, W, H, dth, D[i], cpos);
            worst = fmax(worst, fabs(pix[i].T - exp(-m.sigma_t * zeta)) / exp(-m.sigma_t * zeta));
        }
    t_true(st == NBT_OK && worst < 1e-6, "medium through a grid of the linear field: T = the closed form (worst rel %.2g)",
           worst);
    nbt_grid_free(g);
}

/* trilinear interpolation is exact for a linear field: probe one with distinct
 * slopes per axis at unequal fractions (0.1, 0.35, 0.8 in turn on each axis),
 * where weights swapped between axes show; centre values are multiples of 1/4
 * (exact in float). The half voxel at the border is constant (clamped). */
static void test_grid_linear(void)
{
    const double o[3] = {-1.0, 0.5, 2.0}, vox = 0.5;
    nbt_grid *g = nbt_grid_alloc(4, 3, 5, o, vox);
    t_true(g != NULL, "grid 4x3x5");
    if (!g)
        return;
    for (size_t k = 0; k < 5; k++)
        for (size_t j = 0; j < 3; j++)
            for (size_t i = 0; i < 4; i++)
                g->data[(k * 3 + j) * 4 + i] = (float)(4.0 + 0.25 * (double)i + 2.0 * (double)j - 0.75 * (double)k);
    /* voxel-centre coordinates (i, j, k) of the probes */
    const double c[6][3] = {{1.1, 0.35, 2.8}, {2.8, 1.1, 0.35}, {0.35, 1.8, 3.1},
                            {2.35, 0.8, 3.1}, {-0.3, 1.35, 4.3}, {3.2, 2.45, -0.45}};
    const double cl[6][3] = {{1.1, 0.35, 2.8}, {2.8, 1.1, 0.35}, {0.35, 1.8, 3.1},
                             {2.35, 0.8, 3.1}, {0.0, 1.35, 4.0}, {3.0, 2.0, 0.0}}; /* clamped to the centres */
    double worst = 0;
    for (int p = 0; p < 6; p++) {
        double q[3];
        for (int a = 0; a < 3; a++)
            q[a] = o[a] + vox * c[p][a];
        double want = 4.0 + 0.25 * cl[p][0] + 2.0 * cl[p][1] - 0.75 * cl[p][2];
        worst = fmax(worst, fabs(nbt_grid_density(q, g) - want) / want);
    }
    t_true(worst < 1e-14, "grid: a linear field a + b i + c j + d k at unequal fractions, in the border half voxels too "
           "(worst rel %.2g)", worst);
    nbt_grid_free(g);
}

/* the edge band of nbt_screen_compare by hand: per-pixel kernels of 1.05 px
 * (near side, D = 4) and 1.85 px (far side, D = 9) meet at a straight
 * vertical edge between columns 13 and 14 of a 40x9 image; the band is every
 * pixel within 2 x 1.85 = 3.7 px of the edge's midpoints, i.e. the columns
 * 10..17 (|x - 13.5| <= 3.7) on every row: 72 pixels. (The smaller radius,
 * or one radius instead of two, gives columns 12..15.) Depths 9 and 9.3 differ
 * by 3.3% < 5%: no edge there. An error at column 17 counts in the band, one
 * at column 18 does not. */
static void test_edge_band(void)
{
    const size_t W = 40, H = 9, N = W * H;
    float rgb[40 * 9 * 3] = {0}, D[40 * 9];
    nbt_screen_pixkern pix[40 * 9];
    double S[40 * 9 * 3], R[40 * 9 * 3];
    for (size_t y = 0; y < H; y++)
        for (size_t x = 0; x < W; x++) {
            size_t i = y * W + x;
            D[i] = x < 14 ? 4.0f : x < 28 ? 9.0f : 9.3f;
            pix[i].T = 0.5, pix[i].M0 = 0.2, pix[i].beta_px = x < 14 ? 1.05 : 1.85;
            for (int c = 0; c < 3; c++)
                R[3 * i + c] = S[3 * i + c] = 1.0 + 0.01 * (double)i + 0.1 * c;
        }
    nbt_screen_input in = {W, H, rgb, D, 0.01, pix};
    size_t a = 4 * W + 17, b = 2 * W + 18; /* inside the band (3.5 px from the edge), outside (4.5 px) */
    S[3 * a] += 0.3;
    S[3 * b + 1] += 0.5;
    nbt_screen_metrics mt;
    t_true(nbt_screen_compare(&in, NULL, S, R, &mt) == NBT_OK, "compare with per-pixel kernels");
    double band2 = 0, all2 = 0;
    for (size_t i = 0; i < N; i++)
        for (int c = 0; c < 3; c++) {
            size_t x = i % W;
            all2 += R[3 * i + c] * R[3 * i + c];
            if (x >= 10 && x <= 17)
                band2 += R[3 * i + c] * R[3 * i + c];
        }
    t_true(mt.edge_pixels == 8 * H, "edge band: columns 10..17 on all 9 rows = 72 pixels (got %zu)", mt.edge_pixels);
    t_rel(mt.edge, sqrt(0.3 * 0.3 / band2), 1e-12, "edge metric: the band's error, by hand");
    t_rel(mt.rel_rms, sqrt((0.3 * 0.3 + 0.5 * 0.5) / all2), 1e-12, "rel RMS by hand");
}

/* ---- a caller's kernels per channel (nbt_screen_kernel_custom, _rgb,
 * _channels, _eval_ch) and the slot scales ----
 * Channel c's kernel is written here: T = e^{-k_c D}, one erfc atom of mass
 * k_c D and scale 0.1 k_c D, with k = (0.3, 0.7, 1.9): each channel must
 * come back with its own numbers (a channel read from another, or the grey
 * path taken, shows), exactly (the same arithmetic on both sides). */
static nbt_status chan_fn(double D, nbt_screen_kern *o, void *ctx)
{
    double k = *(const double *)ctx;
    o->T = exp(-k * D);
    o->n = 1;
    o->shape[0] = NBT_ATOM_ERFC;
    o->mass[0] = k * D;
    o->scale[0] = 0.1 * k * D;
    return NBT_OK;
}

static void test_custom_rgb(void)
{
    static double kc[3] = {0.3, 0.7, 1.9};
    nbt_screen_kernel *k = nbt_screen_kernel_rgb(nbt_screen_kernel_custom(chan_fn, &kc[0]),
                                                 nbt_screen_kernel_custom(chan_fn, &kc[1]),
                                                 nbt_screen_kernel_custom(chan_fn, &kc[2]));
    t_true(k && nbt_screen_kernel_channels(k) == 3, "RGB of three custom kernels: 3 channels");
    if (!k)
        return;
    int ok = 1;
    for (unsigned c = 0; c < 3; c++) {
        nbt_screen_kern o;
        nbt_status st = nbt_screen_kernel_eval_ch(k, c, 2.5, &o);
        ok &= st == NBT_OK && o.n == 1 && o.shape[0] == NBT_ATOM_ERFC && o.T == exp(-kc[c] * 2.5) &&
              o.mass[0] == kc[c] * 2.5 && o.scale[0] == 0.1 * kc[c] * 2.5;
        nbt_screen_kern sky;
        ok &= nbt_screen_kernel_eval_ch(k, c, NBT_SCREEN_SKY, &sky) == NBT_OK && sky.T == 0 && sky.n == 0;
    }
    t_true(ok, "eval_ch: each channel at D = 2.5 is its own kernel's T, mass and scale; sky: T = 0, no atoms");
    nbt_screen_kern o;
    t_true(nbt_screen_kernel_eval(k, 2.5, &o) == NBT_OK && o.mass[0] == kc[0] * 2.5, "eval = channel 0");
    t_true(nbt_screen_kernel_eval_ch(k, 3, 2.5, &o) == NBT_EINVAL, "channel 3 refused");
    nbt_screen_kernel *g = nbt_screen_kernel_custom(chan_fn, &kc[1]);
    t_true(g && nbt_screen_kernel_channels(g) == 1 && nbt_screen_kernel_eval_ch(g, 2, 2.5, &o) == NBT_OK &&
               o.mass[0] == kc[1] * 2.5,
           "a grey custom kernel: 1 channel, the same in channel 2");
    nbt_screen_kernel_free(g);
    nbt_screen_kernel_free(k);
    /* s_m = 2^(m/2): odd m of both signs, the ends of the slot grid */
    const int ms[4] = {-3, 5, NBT_SCREEN_SLOT_LO, NBT_SCREEN_SLOT_HI};
    double worst = 0;
    for (int i = 0; i < 4; i++)
        worst = fmax(worst, fabs(nbt_screen_slot_scale(ms[i]) / pow(sqrt(2.0), ms[i]) - 1));
    t_true(worst < 1e-14, "slot scales 2^(m/2) at m = -3, 5, -34, 22 (worst rel %.2g)", worst);
}

/* ---- truncation of a kernel of two shapes (nbt_screen_brute's tail) ----
 * A caller's kernel at D = 1, dtheta = 0.01: a Gaussian atom of mass 0.5 and
 * scale 6 px, then an erfc atom of mass 0.25 and scale 1 px. The kernel is
 * truncated where less than tail of its mass lies outside, so an impulse's
 * response (unit colour, in the middle of a 48 x 40 image that holds the
 * square of radius R) sums to at least (1 - tail) 0.75. At tail 1e-2 the
 * Gaussian needs R = 18 (0.4% outside the square); cut at the erfc shape's
 * radius for 6 px (R = 14) it leaves 3.1% of its mass outside, and the sum
 * falls to 0.734 < 0.7425. */
static nbt_status two_shapes_fn(double D, nbt_screen_kern *o, void *ctx)
{
    (void)ctx;
    o->T = 0.25;
    o->n = 2;
    o->shape[0] = NBT_ATOM_GAUSS;
    o->mass[0] = 0.5;
    o->scale[0] = 0.06 * D;
    o->shape[1] = NBT_ATOM_ERFC;
    o->mass[1] = 0.25;
    o->scale[1] = 0.01 * D;
    return NBT_OK;
}

static void test_two_shape_tail(void)
{
    const size_t W = 48, H = 40, N = W * H, c = 20 * W + 24;
    const double tail = 1e-2;
    nbt_screen_kernel *k = nbt_screen_kernel_custom(two_shapes_fn, NULL);
    scene s = scene_new(W, H);
    double *S = malloc(N * 3 * sizeof *S);
    for (size_t i = 0; i < N; i++)
        s.D[i] = 1.0f;
    s.rgb[3 * c] = s.rgb[3 * c + 1] = s.rgb[3 * c + 2] = 1.0f;
    nbt_screen_input in = as_input(&s, 0.01);
    long Rg = nbt_screen_atom_radius(NBT_ATOM_GAUSS, 6.0, tail);
    int ran = k && S && nbt_screen_brute(&in, k, NBT_SCREEN_NEAR, tail, 1, S, NULL) == NBT_OK;
    double sum = 0;
    for (size_t i = 0; ran && i < N; i++)
        sum += S[3 * i + 1];
    t_true(ran && Rg < 20 && sum >= (1 - tail) * 0.75 && sum <= 0.75 * (1 + 1e-12),
           "two-shape kernel, tail %g: impulse response %.6f in [(1 - tail) 0.75, 0.75] (Gaussian R = %ld)", tail, sum,
           Rg);
    free(S);
    scene_free(&s);
    nbt_screen_kernel_free(k);
}

/* ---- fitting a shape to radial masses (nbt_screen_shape_fit) ----
 * Exact data from 1.7 erfc atom of scale 2 (slot 2) and 0.4 Gaussian atom of
 * scale 2^-1.5 (slot -3), binned on 31 geometric edges 0.02 .. 60, the atoms'
 * masses written here: Gaussian e^{-a^2/2} outside a, erfc e^{-a^2/2} -
 * sqrt(2 pi) a G(a). The grid holds more atoms than bins, so the atoms need
 * not come back; what must is the data: the fitted shape's bin masses,
 * recomputed here with the documented slot scales 2^(m/2): the data are
 * exact and the grid holds the true atoms, so the fit reproduces them to
 * rounding (1.6e-13 seen); 1e-6 relative to (mass + 1e-4 total, the fit's
 * per-bin weight floor), and the total to 1e-6 (its documented accuracy). */
static double tail_erfc(double a)
{
    return isinf(a) ? 0 : exp(-0.5 * a * a) - sqrt(2 * M_PI) * a * G(a);
}
static double tail_gauss(double a)
{
    return isinf(a) ? 0 : exp(-0.5 * a * a);
}
static double shape_bin(const double *er, const double *ga, double lo, double hi)
{
    double m = 0;
    for (int k = 0; k < NBT_SCREEN_NSLOTS; k++) {
        double sc = pow(2.0, 0.5 * (k + NBT_SCREEN_SLOT_LO));
        m += er[k] * (tail_erfc(lo / sc) - tail_erfc(hi / sc)) + ga[k] * (tail_gauss(lo / sc) - tail_gauss(hi / sc));
    }
    return m;
}

static void test_shape_fit(void)
{
    enum { NE = 31 };
    double e[NE], mass[NE + 1];
    for (int i = 0; i < NE; i++)
        e[i] = 0.02 * pow(3000.0, i / (NE - 1.0));
    /* every slot (step 1): erfc at slot 2, Gaussian at slot -3; whole octaves
     * (step 2, even slots only): erfc at slot 2, Gaussian at slot -4 */
    for (int step = 1; step <= 2; step++) {
        double er[NBT_SCREEN_NSLOTS] = {0}, ga[NBT_SCREEN_NSLOTS] = {0};
        er[2 - NBT_SCREEN_SLOT_LO] = 1.7;
        ga[(step == 1 ? -3 : -4) - NBT_SCREEN_SLOT_LO] = 0.4;
        for (int b = 0; b <= NE; b++)
            mass[b] = shape_bin(er, ga, b ? e[b - 1] : 0, b < NE ? e[b] : INFINITY);
        nbt_screen_shape sh;
        double mis = -1;
        t_true(nbt_screen_shape_fit(NE, e, mass, NULL, step, &sh, &mis) == NBT_OK, "shape fit to exact masses, slot step %d",
               step);
        double worst = 0, tot = shape_bin(sh.erfc, sh.gauss, 0, INFINITY);
        for (int b = 0; b <= NE; b++) {
            double f = shape_bin(sh.erfc, sh.gauss, b ? e[b - 1] : 0, b < NE ? e[b] : INFINITY);
            worst = fmax(worst, fabs(f - mass[b]) / (mass[b] + 1e-4 * 2.1));
        }
        t_true(worst < 1e-6, "shape fit, slot step %d: every bin's mass back within 1e-6 of (mass + 1e-4 total): worst %.2g",
               step, worst);
        t_rel(tot, 2.1, 1e-6, "shape fit, slot step %d, keeps the total 2.1", step);
        t_true(mis >= 0 && mis < 1e-6, "shape fit, slot step %d: misfit %.2g", step, mis);
    }
    /* no mass at all: the empty shape, and a misfit of 0 (sum |fit - mass| / sum mass taken as 0) */
    for (int b = 0; b <= NE; b++)
        mass[b] = 0;
    nbt_screen_shape sh;
    double mis = -1;
    nbt_status st = nbt_screen_shape_fit(NE, e, mass, NULL, 1, &sh, &mis);
    t_true(st == NBT_OK && mis == 0 && shape_bin(sh.erfc, sh.gauss, 0, INFINITY) == 0,
           "shape fit of zero masses: the empty shape, misfit 0 (%g)", mis);
}

int main(void)
{
    test_pixel_integrals();
    test_atom_mass();
    test_kernels();
    test_operators();
    test_medium();
    test_medium_height();
    test_grid_linear();
    test_edge_band();
    test_custom_rgb();
    test_two_shape_tail();
    test_shape_fit();
    return t_done();
}
