/* tests/test_beam.c: narrow-beam moments (closed form vs line integral vs
 * independent integrals), kernels reproduce their moments, edges, bad input. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include <nbt/nbt.h>
#include "testutil.h"

typedef struct {
    const nbt_beam_medium *m;
    nbt_psi_model model;
    double z, alpha, beta;
    int power;
} rint_ctx;

/* 2 pi r^(1+power) Psi(r), r = t/(1-t) on t in [0, 1) */
static int rint_f(double t, void *vp, unsigned fdim, double *f)
{
    (void)fdim;
    const rint_ctx *c = vp;
    double r = t / (1 - t), jac = 1 / ((1 - t) * (1 - t)), psi;
    if (c->beta > 0)
        psi = nbt_beam_kernel(c->alpha, c->beta, r);
    else
        nbt_beam_psi(c->m, c->model, c->z, r, &psi, NULL);
    f[0] = 2 * M_PI * pow(r, 1 + c->power) * psi * jac;
    return 0;
}

static double rho_smooth(double z, void *d)
{
    (void)d;
    return 1.0 + 0.5 * sin(z);
}
static double rho_one(double z, void *d)
{
    (void)d;
    (void)z;
    return 1.0;
}

static double rmoment(nbt_quad_ws *ws, rint_ctx *c, int power)
{
    double r, e;
    c->power = power;
    nbt_quad_gk(ws, rint_f, c, 1, 0.0, 1.0, 1e-300, 1e-10, &r, &e);
    return r;
}

/* zeta(z) through three layers of unequal density (0.5, 2, 0.25 from z = 0,
 * 1.2, 2), by hand: inside the first, the middle and the last (unbounded)
 * layer, and 0 above the surface */
static void test_zeta_layers(void)
{
    const double z[3] = {0, 1.2, 2.0}, rho[3] = {0.5, 2.0, 0.25};
    nbt_beam_medium m = nbt_beam_homogeneous(1.7, 0.7, 0.05);
    m.nlayers = 3, m.z = z, m.rho = rho;
    t_rel(nbt_beam_zeta(&m, 0.7), 0.5 * 0.7, 1e-15, "zeta in the first layer");
    t_rel(nbt_beam_zeta(&m, 1.6), 0.5 * 1.2 + 2.0 * 0.4, 1e-15, "zeta in the middle layer");
    t_rel(nbt_beam_zeta(&m, 3.1), 0.5 * 1.2 + 2.0 * 0.8 + 0.25 * 1.1, 1e-15, "zeta in the last layer");
    t_true(nbt_beam_zeta(&m, -1) == 0, "zeta above the surface = 0");
}

/* The corrected kernel (nbt_kernel_corrected, nbt-gen kernel --correction and
 * the CORRECTED screen kernel): alpha and beta are the moment kernel's times
 * exp(sum alpha_i t_i) and exp(sum beta_i t_i), t = (1, x, x^2, a, a x, b, b x)
 * with x = ln(sigma_t zeta(z)), a the albedo, b = ln B_mix, all written here.
 * sigma_t = 1.7 (a tau without sigma_t shows), two lobes (B_mix = 0.05),
 * two layers (zeta = 0.5 1.2 + 2 1.5 = 3.6), and different coefficients in
 * alpha and beta and per term (a swap or a wrong monomial shows). Only the
 * exponentials' rounding separates the two sides: 1e-13. */
static void test_kernel_corrected(void)
{
    nbt_beam_medium m = nbt_beam_homogeneous(1.7, 0.7, 0.02);
    m.nlobes = 2, m.w[0] = 0.25, m.B[0] = 0.02, m.w[1] = 0.75, m.B[1] = 0.06;
    const double z[2] = {0, 1.2}, rho[2] = {0.5, 2.0};
    m.nlayers = 2, m.z = z, m.rho = rho;
    const double tau = 1.7 * 3.6, a = 0.7, x = log(tau), b = log(0.05);
    const double want_t[7] = {1, x, x * x, a, a * x, b, b * x};
    double t[NBT_KERNEL_CORR_TERMS];
    nbt_kernel_correction_terms(tau, a, 0.05, t);
    double worst = 0;
    for (int i = 0; i < 7; i++)
        worst = fmax(worst, fabs(t[i] - want_t[i]));
    t_true(worst < 1e-14, "correction terms at tau 6.12, albedo 0.7, B 0.05 = (1, x, x^2, a, a x, b, b x): worst %.2g", worst);
    nbt_kernel_correction c = {{0.1, -0.05, 0.02, 0.3, -0.07, 0.04, 0.011}, {-0.2, 0.06, -0.01, 0.15, 0.03, -0.05, 0.02}};
    double la = 0, lb = 0;
    for (int i = 0; i < 7; i++) {
        la += c.alpha[i] * want_t[i];
        lb += c.beta[i] * want_t[i];
    }
    double a0, b0, a1, b1, M0, M2, am, bm;
    nbt_status s0 = nbt_kernel_corrected(NULL, &m, 2.7, &a0, &b0);
    nbt_status s1 = nbt_kernel_corrected(&c, &m, 2.7, &a1, &b1);
    nbt_beam_moments(&m, NBT_BEAM_ISHIMARU, 2.7, &M0, &M2, NULL);
    nbt_beam_kernel_params(M0, M2, &am, &bm);
    t_true(s0 == NBT_OK && s1 == NBT_OK && a0 == am && b0 == bm, "no correction: the moment kernel (eq. 28/29)");
    t_rel(a1 / a0, exp(la), 1e-13, "corrected alpha / moment alpha = exp(sum alpha_i t_i) = %.15g", exp(la));
    t_rel(b1 / b0, exp(lb), 1e-13, "corrected beta / moment beta = exp(sum beta_i t_i) = %.15g", exp(lb));
}

/* Eq. 26 written here (doc/beam.md, A = sigma_s B):
 *   M2 = 4 e^{-sa z} [e^{-az}(A z^2/a - 2B/a^2) + 2B/a^2 - 2Bz/a + (B - A/a) z^2 + A z^3], a = sigma_s,
 * at sigma_t = 1.7, albedo 0.6, two lobes (B = B_mix = 0.05): the loop above
 * has sigma_t = 1, where sigma_s = albedo hides a sigma_t left out. Both
 * branches: z = 2.385 (a z = 2.4, the closed form) and z = 0.2 (a z = 0.2,
 * the library's series; here the closed form loses about 3 digits to
 * cancellation, so 1e-10). */
/* text into a fresh temporary file; path gets its name */
static void put_text(char *path, const char *text)
{
    strcpy(path, "/tmp/nbt-test-beam.XXXXXX");
    int fd = mkstemp(path);
    FILE *f = fd >= 0 ? fdopen(fd, "w") : NULL;
    t_true(f != NULL, "temporary file %s", path);
    if (f) {
        fputs(text, f);
        fclose(f);
    }
}

/* the two readers of text files against the numbers written in them: density profiles (three layers of
 * unequal thickness, a comment, a blank line, CRLF, an exponent) and kernel corrections (7 different
 * numbers per line, alpha before beta); the documented refusals name the file's line */
static void test_readers(void)
{
    char path[64], err[512];
    double *z = NULL, *rho = NULL;
    size_t n = 0;
    put_text(path, "# z rho\n\n0 1.5   # top\n0.75 0\r\n  2.25 3e-1\n");
    nbt_status st = nbt_density_read(path, &z, &rho, &n, err, sizeof err);
    t_true(st == NBT_OK && n == 3 && z[0] == 0 && z[1] == 0.75 && z[2] == 2.25 && rho[0] == 1.5 && rho[1] == 0 &&
               rho[2] == 0.3,
           "density file: 3 layers (0, 1.5) (0.75, 0) (2.25, 0.3): status %d, n %zu", st, n);
    if (st == NBT_OK) {
        free(z);
        free(rho);
    }
    unlink(path);
    /* each message names the bad value (and for z the previous one) and what is accepted */
    static const char *const bad[][2] = {{"0.1 1\n1 2\n", ":1: .*first z = 0.10000000000000001 is not accepted: the first z must be 0"},
                                         {"0 1\n1 2\n1 3\n", ":3: .*z = 1 is not accepted: z must increase (the previous z is 1)"},
                                         {"0 1\n2 1\n1.5 3\n", ":3: .*z = 1.5 is not accepted: z must increase (the previous z is 2)"},
                                         {"0 1\n1 -0.5\n", ":2: .*rho = -0.5 is not accepted: rho must be >= 0"},
                                         {"0 1\n1 2 3\n", ":2: .*two finite numbers"}};
    for (int i = 0; i < 5; i++) {
        put_text(path, bad[i][0]);
        z = rho = NULL;
        st = nbt_density_read(path, &z, &rho, &n, err, sizeof err);
        /* the line number right after the file's name */
        char want[96];
        snprintf(want, sizeof want, "%s%.3s", path, bad[i][1]);
        const char *why = strstr(bad[i][1], ".*") + 2;
        t_true(st == NBT_EFORMAT && !strncmp(err, want, strlen(want)) && strstr(err, why) != NULL,
               "density file %d refused at its line (%s): status %d, '%s'", i, bad[i][1], st, err);
        unlink(path);
    }
    nbt_kernel_correction c;
    memset(&c, 0, sizeof c);
    put_text(path, "# a correction\nalpha -0.5 0.25 -0.125 1e-3 2.5 -3 0.0625\nbeta 0.1 -0.2 0.3 -0.4 0.5 -0.6 0.7\n");
    st = nbt_kernel_correction_read(path, &c, err, sizeof err);
    const double wa[7] = {-0.5, 0.25, -0.125, 1e-3, 2.5, -3, 0.0625}, wb[7] = {0.1, -0.2, 0.3, -0.4, 0.5, -0.6, 0.7};
    int same = st == NBT_OK;
    for (int i = 0; i < 7; i++)
        same = same && c.alpha[i] == wa[i] && c.beta[i] == wb[i];
    t_true(same, "kernel correction: alpha and beta lines read term by term: status %d", st);
    unlink(path);
    /* a missing line, a short line, an eighth number, text after the numbers, a mistyped key and a repeated
     * key are each refused at their line (before: the last four were read silently, the typo's line skipped) */
    static const char *const badc[][2] = {
        {"beta 0.1 -0.2 0.3 -0.4 0.5 -0.6 0.7\n", "needs a 'beta' and an 'alpha' line"},
        {"alpha 1 2 3 4 5 6 7\n", "needs a 'beta' and an 'alpha' line"},
        {"beta 0.1 -0.2 0.3 -0.4 0.5 -0.6 0.7\nalpha 1 2 3 4 5 6\n", "line 2: expected 7 finite numbers after 'alpha'"},
        {"beta 0.1 -0.2 0.3 -0.4 0.5 -0.6 0.7 0.8\nalpha 1 2 3 4 5 6 7\n", "line 1: expected 7 finite numbers after 'beta'"},
        {"beta 0.1 -0.2 0.3 -0.4 0.5 -0.6 0.7\n\nalpha 1 2 3 4 5 6 7 x\n", "line 3: 'x' after the 7 numbers"},
        {"beta 0.1 -0.2 0.3 -0.4 0.5 -0.6 0.7\nalpah 1 2 3 4 5 6 7\nalpha 1 2 3 4 5 6 7\n",
         "line 2: 'alpah 1 2 3 4 5 6 7' is not accepted: expected a 'beta' or 'alpha' line"},
        {"alpha 1 2 3 4 5 6 7\nbeta 0.1 -0.2 0.3 -0.4 0.5 -0.6 0.7\n# again\nalpha 1 2 3 4 5 6 8\n",
         "line 4: 'alpha 1 2 3 4 5 6 8' is not accepted: a second line of the same key"}};
    for (size_t i = 0; i < sizeof badc / sizeof badc[0]; i++) {
        put_text(path, badc[i][0]);
        st = nbt_kernel_correction_read(path, &c, err, sizeof err);
        t_true(st == NBT_EFORMAT && strstr(err, path) != NULL && strstr(err, badc[i][1]) != NULL,
               "kernel correction %zu refused (%s): status %d, '%s'", i, badc[i][1], st, err);
        unlink(path);
    }
    /* comments after the numbers and CR LF line ends are fine */
    put_text(path, "beta 0.1 -0.2 0.3 -0.4 0.5 -0.6 0.7 # fitted\r\nalpha -0.5 0.25 -0.125 1e-3 2.5 -3 0.0625\r\n");
    st = nbt_kernel_correction_read(path, &c, err, sizeof err);
    same = st == NBT_OK;
    for (int i = 0; i < 7; i++)
        same = same && c.alpha[i] == wa[i] && c.beta[i] == wb[i];
    t_true(same, "kernel correction with a trailing comment and CR LF: status %d '%s'", st, st ? err : "");
    unlink(path);
}

static void test_eq26(void)
{
    nbt_beam_medium m = nbt_beam_homogeneous(1.7, 0.6, 0.02);
    m.nlobes = 2, m.w[0] = 0.25, m.B[0] = 0.02, m.w[1] = 0.75, m.B[1] = 0.06;
    const double a = 0.6 * 1.7, sa = 1.7 - a, B = 0.05, A = a * B, zs[2] = {2.385, 0.2};
    for (int i = 0; i < 2; i++) {
        double z = zs[i], M0, M2;
        double want = 4 * exp(-sa * z) *
                      (exp(-a * z) * (A * z * z / a - 2 * B / (a * a)) + 2 * B / (a * a) - 2 * B * z / a +
                       (B - A / a) * z * z + A * z * z * z);
        nbt_beam_moments(&m, NBT_BEAM_ISHIMARU, z, &M0, &M2, NULL);
        t_rel(M2, want, 1e-10, "eq. 26 at sigma_t 1.7, albedo 0.6, B_mix 0.05, z %g: M2 = %.15g", z, want);
        t_rel(M0, exp(-sa * z) * (1 - exp(-a * z)), 1e-14, "eq. 25 at sigma_t 1.7, z %g", z);
    }
}

int main(void)
{
    double M0, M2, e, a, b;
    nbt_quad_ws *ws = nbt_quad_ws_alloc(1, 4000);
    double albedos[] = {0.1, 0.5, 0.9, 0.99, 1.0}, Bs[] = {0.0685, 0.274};
    for (int ia = 0; ia < 5; ia++)
        for (int ib = 0; ib < 2; ib++) {
            nbt_beam_medium h = nbt_beam_homogeneous(1.0, albedos[ia], Bs[ib]);
            double zl[3] = {0, 0.7, 2.385}, rl[3] = {1, 1, 1};
            nbt_beam_medium L = h;
            L.nlayers = 3;
            L.z = zl;
            L.rho = rl;
            for (double z = 0.02; z <= 10; z *= 2.2) {
                double M0l, M2l;
                nbt_beam_moments(&h, NBT_BEAM_ISHIMARU, z, &M0, &M2, NULL);
                nbt_beam_moments(&L, NBT_BEAM_ISHIMARU, z, &M0l, &M2l, &e);
                t_rel(M2l, M2, 1e-10, "albedo %g B %g z %g: eq. 26 = eq. 29 with equal layers", albedos[ia], Bs[ib], z);
                t_rel(M0, exp(-(1 - albedos[ia]) * z) * (1 - exp(-albedos[ia] * z)), 1e-14, "M0 eq. 25");
                nbt_beam_moments(&L, NBT_BEAM_SMALLANGLE, z, &M0l, &M2l, &e);
                t_rel(M2l, exp(-(1 - albedos[ia]) * z) * 4.0 / 3.0 * albedos[ia] * Bs[ib] * z * z * z, 1e-10,
                      "random walk, layered = (4/3) sigma_s B z^3");
            }
            /* kernel reproduces the moments; the line-integral Psi has them too */
            for (double z = 0.3; z <= 10; z *= 3) {
                nbt_beam_moments(&h, NBT_BEAM_ISHIMARU, z, &M0, &M2, NULL);
                nbt_beam_kernel_params(M0, M2, &a, &b);
                rint_ctx c = {&h, NBT_PSI_ISHIMARU, z, a, b, 0};
                t_rel(rmoment(ws, &c, 0), M0, 1e-9, "int Psi dA = M0 (albedo %g, z %g)", albedos[ia], z);
                t_rel(rmoment(ws, &c, 2), M2, 1e-9, "int r^2 Psi dA = M2 (albedo %g, z %g)", albedos[ia], z);
                if (ib == 0 && (ia == 1 || ia == 3)) {
                    rint_ctx l = {&h, NBT_PSI_LINEINT, z, 0, 0, 0};
                    t_rel(rmoment(ws, &l, 0), M0, 1e-6, "line-integral Psi: M0 (albedo %g, z %g)", albedos[ia], z);
                    t_rel(rmoment(ws, &l, 2), M2, 1e-6, "line-integral Psi: M2 (albedo %g, z %g)", albedos[ia], z);
                    rint_ctx s = {&h, NBT_PSI_SINGLE, z, 0, 0, 0};
                    double ss = albedos[ia];
                    t_rel(rmoment(ws, &s, 0), ss * z * exp(-z), 1e-7, "int Psi_1 dA = sigma_s z e^-tau");
                    t_rel(rmoment(ws, &s, 2), 4.0 / 3.0 * Bs[ib] * ss * z * z * z * exp(-z), 1e-7,
                          "int r^2 Psi_1 dA = (4/3) B sigma_s z^3 e^-tau");
                    rint_ctx el = {&h, NBT_PSI_ELEK, z, 0, 0, 0};
                    t_rel(rmoment(ws, &el, 0), M0, 1e-8, "Elek kernel normalised to M0");
                }
            }
        }
    /* the small-z series of eq. 26 joins the closed form */
    nbt_beam_medium h = nbt_beam_homogeneous(2.0, 0.8, 0.1);
    double zs = 0.5 / 1.6, M0a, M2a, M2b;
    nbt_beam_moments(&h, NBT_BEAM_ISHIMARU, zs * (1 - 1e-9), &M0a, &M2a, NULL);
    nbt_beam_moments(&h, NBT_BEAM_ISHIMARU, zs * (1 + 1e-9), &M0a, &M2b, NULL);
    t_rel(M2a, M2b, 1e-8, "eq. 26 series and closed form agree where they meet");
    nbt_beam_moments(&h, NBT_BEAM_ISHIMARU, 1e-6, &M0a, &M2a, NULL);
    t_rel(M2a, 4.0 / 3.0 * 1.6 * 0.1 * 1e-18, 1e-5, "M2 -> (4/3) sigma_s B z^3 as z -> 0 (no cancellation)");
    /* layers: density 2 = doubled sigma_t; a vacuum gap */
    double z2[1] = {0}, r2[1] = {2.0};
    nbt_beam_medium d2 = nbt_beam_homogeneous(0.5, 0.9, 0.0685), hh = nbt_beam_homogeneous(1.0, 0.9, 0.0685);
    d2.nlayers = 1;
    d2.z = z2;
    d2.rho = r2;
    nbt_beam_moments(&d2, NBT_BEAM_ISHIMARU, 2.385, &M0, &M2, NULL);
    nbt_beam_moments(&hh, NBT_BEAM_ISHIMARU, 2.385, &M0a, &M2a, NULL);
    t_rel(M2, M2a, 1e-10, "density 2 x sigma_t 0.5 = sigma_t 1");
    double zg[3] = {0, 1, 2}, rg[3] = {1, 0, 1};
    nbt_beam_medium gap = hh;
    gap.nlayers = 3;
    gap.z = zg;
    gap.rho = rg;
    nbt_beam_moments(&gap, NBT_BEAM_SMALLANGLE, 3, &M0, &M2, NULL);
    t_rel(M2, exp(-0.1 * 2) * 4 * 0.0685 * 0.9 * 20.0 / 3.0, 1e-10, "random walk across a vacuum gap: int (3-y)^2 = 20/3");
    t_rel(M0, exp(-0.1 * 2) * (1 - exp(-0.9 * 2)), 1e-14, "M0 across a gap depends on zeta only");
    double psl, psh;
    nbt_beam_medium lay = hh;
    double zl1[2] = {0, 1.5}, rl1[2] = {1, 1};
    lay.nlayers = 2;
    lay.z = zl1;
    lay.rho = rl1;
    nbt_beam_psi(&lay, NBT_PSI_SINGLE, 2.385, 0.3, &psl, NULL);
    nbt_beam_psi(&hh, NBT_PSI_SINGLE, 2.385, 0.3, &psh, NULL);
    t_rel(psl, psh, 1e-8, "single scattering: layered quadrature = closed form");
    /* the quadrature's error estimate is scaled like Psi itself (the prefactor sigma_s e^-zeta times the
     * integral's error): asked for 1e-10 relative, it lies in [0, 1e-8 Psi] and covers the true error
     * against the closed form up to 1e-12 Psi of rounding */
    double pse = -1;
    nbt_beam_psi(&lay, NBT_PSI_SINGLE, 2.385, 0.3, &psl, &pse);
    t_true(pse >= 0 && pse <= 1e-8 * psl && fabs(psl - psh) <= pse + 1e-12 * psh,
           "layered single scattering: error estimate %.3g in [0, 1e-8 Psi] covers |Psi - closed form| = %.3g", pse,
           fabs(psl - psh));
    /* a density callback: constant 1 = homogeneous; a smooth profile against
     * the random walk's integral done here independently */
    nbt_beam_medium cb = hh;
    cb.rho_fn = rho_one;
    nbt_beam_moments(&cb, NBT_BEAM_ISHIMARU, 2.385, &M0, &M2, NULL);
    nbt_beam_moments(&hh, NBT_BEAM_ISHIMARU, 2.385, &M0a, &M2a, NULL);
    t_rel(M2, M2a, 1e-10, "callback rho = 1: eq. 29 = eq. 26");
    t_rel(M0, M0a, 1e-12, "callback rho = 1: M0");
    cb.rho_fn = rho_smooth;
    nbt_beam_moments(&cb, NBT_BEAM_SMALLANGLE, 3.0, &M0, &M2, NULL);
    /* zeta(3) = 3 + 0.5 (1 - cos 3); int_0^3 (1 + 0.5 sin y)(3 - y)^2 dy = 9 + 0.5 (9 - 2 + 2 cos 3 ... ) by parts:
     * int_0^3 sin(y) (3-y)^2 dy = 9 - 2 + 2 cos 3 = 7 + 2 cos 3 */
    double zeta3 = 3 + 0.5 * (1 - cos(3.0)), I = 9 + 0.5 * (7 + 2 * cos(3.0));
    t_rel(M2, exp(-0.1 * zeta3) * 4 * 0.0685 * 0.9 * I, 1e-10, "callback rho = 1 + sin(z)/2: random walk closed form");
    t_rel(M0, exp(-0.1 * zeta3) * (1 - exp(-0.9 * zeta3)), 1e-11, "callback: M0 from zeta");
    /* edges */
    nbt_beam_medium z0 = nbt_beam_homogeneous(1.0, 0.0, 0.0685);
    nbt_beam_moments(&z0, NBT_BEAM_ISHIMARU, 2, &M0, &M2, NULL);
    nbt_beam_kernel_params(M0, M2, &a, &b);
    t_true(M0 == 0 && M2 == 0 && a == 0 && b == 0 && nbt_beam_kernel(a, b, 1) == 0, "albedo 0: no scattered light, kernel 0");
    nbt_beam_moments(&hh, NBT_BEAM_ISHIMARU, 1e4, &M0, &M2, NULL);
    t_true(isfinite(M0) && isfinite(M2) && M0 >= 0 && M2 >= 0, "tau = 1e4: finite (M0 %g, M2 %g)", M0, M2);
    nbt_beam_medium tiny = nbt_beam_homogeneous(1.0, 0.9, 1e-12);
    double p1;
    t_true(nbt_beam_psi(&tiny, NBT_PSI_LINEINT, 2, 1e-7, &p1, NULL) == NBT_OK && isfinite(p1) && p1 >= 0, "B = 1e-12: finite");
    t_true(nbt_beam_psi(&hh, NBT_PSI_ISHIMARU, 1e-12, 1e-13, &p1, NULL) == NBT_OK && isfinite(p1), "z = 1e-12: finite");
    /* bad input */
    nbt_beam_medium bad = nbt_beam_homogeneous(1.0, 1.2, 0.1);
    t_true(nbt_beam_moments(&bad, NBT_BEAM_ISHIMARU, 1, &M0, &M2, NULL) == NBT_EDOM, "albedo > 1 rejected");
    bad = nbt_beam_homogeneous(-1.0, 0.5, 0.1);
    t_true(nbt_beam_moments(&bad, NBT_BEAM_ISHIMARU, 1, &M0, &M2, NULL) == NBT_EDOM, "sigma_t < 0 rejected");
    bad = nbt_beam_homogeneous(1.0, 0.5, 0);
    t_true(nbt_beam_moments(&bad, NBT_BEAM_ISHIMARU, 1, &M0, &M2, NULL) == NBT_EDOM, "B = 0 rejected");
    t_true(nbt_beam_moments(&hh, NBT_BEAM_ISHIMARU, NAN, &M0, &M2, NULL) == NBT_EDOM, "z = NaN rejected");
    /* Psi is defined at r > 0 and z > 0 (the kernel's alpha/r): r = 0, r < 0 and z = 0 are refused by every model */
    for (int md = NBT_PSI_ISHIMARU; md <= NBT_PSI_ELEK; md++) {
        double q = -1;
        int refused = nbt_beam_psi(&hh, (nbt_psi_model)md, 1.5, 0.0, &q, NULL) == NBT_EDOM &&
                      nbt_beam_psi(&hh, (nbt_psi_model)md, 1.5, -0.25, &q, NULL) == NBT_EDOM &&
                      nbt_beam_psi(&hh, (nbt_psi_model)md, 0.0, 0.25, &q, NULL) == NBT_EDOM;
        int runs = nbt_beam_psi(&hh, (nbt_psi_model)md, 1.5, 0.25, &q, NULL) == NBT_OK && q > 0;
        t_true(refused && runs, "Psi model %d: r = 0, r < 0 and z = 0 refused, (1.5, 0.25) gives %g > 0", md, q);
    }
    double zb[2] = {0, 0}, rb[2] = {1, 1};
    bad = hh;
    bad.nlayers = 2;
    bad.z = zb;
    bad.rho = rb;
    t_true(nbt_beam_moments(&bad, NBT_BEAM_ISHIMARU, 1, &M0, &M2, NULL) == NBT_EDOM, "non-increasing layers rejected");
    /* a negative, NaN or infinite density in any layer, the last one too, is refused; the same layers with rho >= 0 run */
    double z3[3] = {0, 1, 2.5};
    bad.nlayers = 3;
    bad.z = z3;
    for (int i = 0; i < 3; i++) {
        double r3[3] = {1, 0.5, 2};
        bad.rho = r3;
        t_true(nbt_beam_moments(&bad, NBT_BEAM_ISHIMARU, 3, &M0, &M2, NULL) == NBT_OK, "layers 1, 0.5, 2 accepted");
        r3[i] = -0.25;
        t_true(nbt_beam_moments(&bad, NBT_BEAM_ISHIMARU, 3, &M0, &M2, NULL) == NBT_EDOM, "negative layer %d rejected", i);
        r3[i] = NAN;
        t_true(nbt_beam_moments(&bad, NBT_BEAM_ISHIMARU, 3, &M0, &M2, NULL) == NBT_EDOM, "NaN layer %d rejected", i);
        r3[i] = INFINITY; /* >= 0 but not finite (nbt/beam.h: finite): the check itself refuses it */
        t_true(nbt_beam_check(&bad) == NBT_EDOM, "infinite layer %d rejected by nbt_beam_check", i);
    }
    test_zeta_layers();
    test_eq26();
    test_kernel_corrected();
    test_readers();
    nbt_quad_ws_free(ws);
    return t_done();
}
