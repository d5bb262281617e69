/* tests/test_beamfit.c: the fitted kernel model (nbt_beam_fit): each part
 * carries the light its parameters say (quadrature), sigma_t scaling, the
 * clamp outside the fitted range, the file round trip and bad files, bad
 * input, and the shipped model against fresh photon counts (a seed and
 * runs it was not fitted to) within the 5% goal. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include <nbt/nbt.h>
#include "testutil.h"

typedef struct {
    const double *p;
    double lo, span; /* r = lo + span t/(1-t) when span < 0 means a finite [lo, lo - span] */
} rctx;

/* 2 pi r Psi_hat(r) on r = t/(1-t), t in [0, 1) */
static int mass_f(double t, void *vp, unsigned fdim, double *f)
{
    (void)fdim;
    const rctx *c = vp;
    double r = t / (1 - t), jac = 1 / ((1 - t) * (1 - t));
    f[0] = 2 * M_PI * r * nbt_beam_fit_eval(c->p, r) * jac;
    return 0;
}

/* 2 pi r Psi(r) of a medium (sigma_t scaling applied by nbt_beam_fit_psi) */
typedef struct {
    const nbt_beam_fit *f;
    int inf;
    const nbt_beam_medium *m;
    double z;
} actx;
static int ann_f(double r, void *vp, unsigned fdim, double *f)
{
    (void)fdim;
    const actx *c = vp;
    double psi;
    if (nbt_beam_fit_psi(c->f, c->inf, c->m, c->z, r, &psi) != NBT_OK)
        return 1;
    f[0] = 2 * M_PI * r * psi;
    return 0;
}

/* relative RMS of 2 pi r Psi against photon counts (z = 1..10, r in [0, z), 20 annuli), as doc/fit.md
 * defines it, and the counts' own noise on the same scale */
static double rms_vs_mc(const nbt_beam_fit *f, int inf, double albedo, double B, nbt_quad_ws *ws, double *noise)
{
    double zp[10];
    for (int j = 0; j < 10; j++)
        zp[j] = j + 1;
    nbt_phase *ph = nbt_phase_gauss(B);
    nbt_mc_config c;
    memset(&c, 0, sizeof c);
    c.sigma_t = 1;
    c.albedo = albedo;
    c.phase = ph;
    c.nplanes = 10;
    c.z_planes = zp;
    c.r_bins = 20;
    c.r_max_scale = 1;
    c.photons = 200000;
    c.seed = 9173; /* the model was fitted with seed 1 */
    c.threads = 2;
    c.infinite = inf;
    nbt_mc_result *res;
    if (nbt_mc_run(&c, &res) != NBT_OK)
        return NAN;
    nbt_beam_medium m = nbt_beam_homogeneous(1.0, albedo, B);
    double num = 0, den = 0, se2 = 0;
    for (int j = 0; j < 10; j++)
        for (int k = 0; k < 20; k++) {
            double lo = zp[j] * k / 20, hi = zp[j] * (k + 1) / 20, v, e, w = M_PI * (lo + hi);
            actx a = {f, inf, &m, zp[j]};
            nbt_quad_gk(ws, ann_f, &a, 1, lo, hi, 0, 1e-9, &v, &e);
            v /= M_PI * (hi * hi - lo * lo); /* the annulus mean, as counted */
            double mc = res->psi[j * 20 + k], se = res->psi_se[j * 20 + k];
            num += w * w * (v - mc) * (v - mc);
            den += w * w * mc * mc;
            se2 += w * w * se * se;
        }
    nbt_mc_result_free(res);
    nbt_phase_free(ph);
    *noise = sqrt(se2 / den);
    return sqrt(num / den);
}

/* The equivalent depth and width scale of a layered medium
 * (nbt_beam_fit_equivalent, used by nbt_beam_fit_psi, nbt-fit model and
 * nbt-gen eval): two layers of unequal density 0.5 and 2 (interface 1.2),
 * at z = 2.7: zeta = 0.5 1.2 + 2 1.5 = 3.6, and lambda^2 = M2(z) / M2_hom(zeta)
 * of the small-angle random walk, whose e^{-sigma_a zeta} and 4 B sigma_s
 * cancel: lambda^2 = int_0^z rho(y) (z - y)^2 dy / (zeta^3 / 3)
 *                  = [0.5 (2.7^3 - 1.5^3) + 2 1.5^3] / 3.6^3
 * (eq. 29's M2 would give another value; the constant density the test above
 * uses cannot tell them apart). Both sides are closed forms: 1e-12. Then the
 * layered Psi is the homogeneous model at (zeta, r/lambda) over lambda^2. */
static void test_fit_equivalent(const nbt_beam_fit *f)
{
    nbt_beam_medium m = nbt_beam_homogeneous(1.7, 0.8, 0.05);
    double zeta, lam, want = sqrt((0.5 * (pow(2.7, 3) - pow(1.5, 3)) + 2 * pow(1.5, 3)) / pow(3.6, 3));
    t_true(nbt_beam_fit_equivalent(&m, 2.7, &zeta, &lam) == NBT_OK && zeta == 2.7 && lam == 1,
           "homogeneous: zeta = z, lambda = 1");
    const double z[2] = {0, 1.2}, rho[2] = {0.5, 2.0};
    m.nlayers = 2, m.z = z, m.rho = rho;
    t_true(nbt_beam_fit_equivalent(&m, 2.7, &zeta, &lam) == NBT_OK, "two layers: equivalent depth");
    t_rel(zeta, 3.6, 1e-14, "two layers: zeta = 3.6");
    t_rel(lam, want, 1e-12, "two layers: lambda = %.15g (random walk second moments)", want);
    nbt_beam_medium h = nbt_beam_homogeneous(1.7, 0.8, 0.05);
    double pl, ph;
    nbt_beam_fit_psi(f, 0, &m, 2.7, 0.61, &pl);
    nbt_beam_fit_psi(f, 0, &h, 3.6, 0.61 / want, &ph);
    t_rel(pl, ph / (want * want), 1e-12, "two layers: Psi(z, r) = Psi_hom(zeta, r/lambda)/lambda^2");
    t_true(nbt_beam_fit_equivalent(&m, 0, &zeta, &lam) == NBT_EDOM, "z = 0 refused");
}

/* nbt_beam_fit_from_P against the header's definitions written out here, at distinct log-parameters
 * (both signs) and tau 2.385, albedo 0.7, B 0.05: b = L e^P1, sqrt(2 pi) a b = T e^P0, M = T e^P2,
 * s = L e^P3, h = s e^P4 with T = e^{-(1-albedo) tau}(1 - e^{-albedo tau}), L = tau sqrt(2B) */
static void test_from_P(void)
{
    const double P[5] = {0.3, -0.2, 0.1, 0.4, -0.5}, tau = 2.385, alb = 0.7, B = 0.05;
    double p[5];
    nbt_beam_fit_from_P(P, tau, alb, B, p);
    double T = exp(-0.3 * tau) * (1 - exp(-alb * tau)), L = tau * sqrt(0.1), b = L * exp(-0.2), s = L * exp(0.4);
    const double want[5] = {T * exp(0.3) / (sqrt(2 * M_PI) * b), b, T * exp(0.1), s, s * exp(-0.5)};
    static const char *const name[5] = {"a", "b", "M", "s", "h"};
    for (int i = 0; i < 5; i++)
        t_rel(p[i], want[i], 1e-13, "from_P: %s = %.15g (want %.15g)", name[i], p[i], want[i]);
}

int main(void)
{
    const nbt_beam_fit *f = nbt_beam_fit_default();
    nbt_quad_ws *ws = nbt_quad_ws_alloc(1, 4000);
    t_true(f->have[0] && f->have[1], "the shipped model holds both geometries");
    t_true(f->range[0][0] > 0 && f->range[0][0] < f->range[0][1] && f->range[1][0] < f->range[1][1] &&
               f->range[2][0] > 0 && f->range[2][0] < f->range[2][1],
           "its fitted range is recorded (tau [%g, %g], albedo [%g, %g], B [%g, %g])", f->range[0][0], f->range[0][1],
           f->range[1][0], f->range[1][1], f->range[2][0], f->range[2][1]);

    /* each part carries what its parameters say: the whole plane integrates to
     * T (e^P0 + e^P2), T = e^{-(1-a) tau}(1 - e^{-a tau}), P_i from the monomials directly */
    double taus[] = {0.7, 2.385, 9.1}, albs[] = {0.15, 0.62, 0.97}, Bs[] = {0.011, 0.0685, 0.21};
    for (int g = 0; g < 2; g++)
        for (int i = 0; i < 3; i++)
            for (int j = 0; j < 3; j++) {
                double tau = taus[i], a = albs[j], B = Bs[(i + j) % 3], p[NBT_BEAM_FIT_PARTS], t[NBT_BEAM_FIT_TERMS];
                t_true(nbt_beam_fit_params(f, g, tau, a, B, p) == NBT_OK, "params");
                nbt_beam_fit_terms(f, tau, a, B, t);
                double P0 = 0, P2 = 0;
                for (int k = 0; k < NBT_BEAM_FIT_TERMS; k++) {
                    P0 += f->c[g][0][k] * t[k];
                    P2 += f->c[g][2][k] * t[k];
                }
                double T = exp(-(1 - a) * tau) * (1 - exp(-a * tau)), v, e;
                rctx c = {p, 0, 0};
                nbt_quad_gk(ws, mass_f, &c, 1, 0, 1, 0, 1e-11, &v, &e);
                t_rel(v, T * (exp(P0) + exp(P2)), 1e-8, "geometry %d tau %g albedo %g B %g: int 2 pi r Psi = T (e^P0 + e^P2)",
                      g, tau, a, B);
                /* the core alone: sqrt(2 pi) a b = T e^P0 */
                double pc[NBT_BEAM_FIT_PARTS];
                memcpy(pc, p, sizeof pc);
                pc[2] = 0;
                c.p = pc;
                nbt_quad_gk(ws, mass_f, &c, 1, 0, 1, 0, 1e-11, &v, &e);
                t_rel(v, T * exp(P0), 1e-8, "  the core carries T e^P0");
            }

    /* sigma_t scaling: Psi(sigma_t, z, r) = sigma_t^2 Psi(1, sigma_t z, sigma_t r) */
    nbt_beam_medium m2 = nbt_beam_homogeneous(2.385, 0.8, 0.05), m1 = nbt_beam_homogeneous(1.0, 0.8, 0.05);
    double a1, a2;
    nbt_beam_fit_psi(f, 1, &m2, 1.3, 0.41, &a2);
    nbt_beam_fit_psi(f, 1, &m1, 2.385 * 1.3, 2.385 * 0.41, &a1);
    t_rel(a2, 2.385 * 2.385 * a1, 1e-13, "sigma_t scaling");
    /* several lobes: B_mix */
    nbt_beam_medium ml = m1;
    ml.nlobes = 2;
    ml.w[0] = 0.25;
    ml.B[0] = 0.02;
    ml.w[1] = 0.75;
    ml.B[1] = 0.06;
    nbt_beam_fit_psi(f, 0, &ml, 3, 0.7, &a1);
    nbt_beam_fit_psi(f, 0, &m1, 3, 0.7, &a2); /* B = 0.05 = 0.25 0.02 + 0.75 0.06 */
    t_rel(a1, a2, 1e-14, "two lobes evaluate with B_mix");

    /* outside the fitted range the log-parameters stay at their edge values */
    double pe[NBT_BEAM_FIT_PARTS], po[NBT_BEAM_FIT_PARTS];
    double te = f->range[0][1], to = 3 * te;
    nbt_beam_fit_params(f, 0, te, 0.5, 0.05, pe);
    nbt_beam_fit_params(f, 0, to, 0.5, 0.05, po);
    t_rel(po[1] / to, pe[1] / te, 1e-13, "beyond the deepest fitted tau, b / L stays at its edge value");
    t_rel(po[4] / po[3], pe[4] / pe[3], 1e-13, "  and so does h / s");
    nbt_beam_fit_params(f, 1, 0.001, 0.5, 0.05, po);
    t_true(isfinite(po[0]) && isfinite(po[1]) && isfinite(po[2]) && isfinite(po[3]) && isfinite(po[4]) && po[1] > 0,
           "tau = 0.001: finite");
    nbt_beam_fit_params(f, 1, 2.0, 1.0, 0.001, po);
    t_true(isfinite(po[0]) && po[0] > 0 && po[2] > 0, "albedo 1, B below the range: finite, > 0");

    /* bad input */
    t_true(nbt_beam_fit_params(f, 0, 0, 0.5, 0.05, po) == NBT_EDOM, "tau = 0 rejected");
    t_true(nbt_beam_fit_params(f, 0, 1, 1.5, 0.05, po) == NBT_EDOM, "albedo > 1 rejected");
    t_true(nbt_beam_fit_params(f, 0, 1, 0.5, NAN, po) == NBT_EDOM, "B = NaN rejected");
    /* layers: a constant density rho is exactly the homogeneous medium with rho sigma_t; no medium
     * crossed yet (a vacuum first layer): no scattered light; a step is finite and continuous in z */
    double zl[2] = {0, 1.3}, rl[2] = {2.385, 2.385};
    nbt_beam_medium lay = m1;
    lay.nlayers = 2;
    lay.z = zl;
    lay.rho = rl;
    nbt_beam_medium hom = nbt_beam_homogeneous(2.385, 0.8, 0.05);
    for (int g = 0; g < 2; g++) {
        nbt_beam_fit_psi(f, g, &lay, 2.7, 0.61, &a1);
        nbt_beam_fit_psi(f, g, &hom, 2.7, 0.61, &a2);
        t_rel(a1, a2, 1e-9, "geometry %d: constant density 2.385 in two layers = sigma_t x 2.385", g);
    }
    rl[0] = 0;
    rl[1] = 1.7;
    t_true(nbt_beam_fit_psi(f, 0, &lay, 1.0, 0.2, &a1) == NBT_OK && a1 == 0, "inside a vacuum first layer: 0");
    double near, mid;
    t_true(nbt_beam_fit_psi(f, 0, &lay, 1.3 + 1e-9, 0.05, &near) == NBT_OK && isfinite(near) && near >= 0,
           "just past the vacuum (zeta = 1.7e-9): finite (%g)", near);
    t_true(nbt_beam_fit_psi(f, 1, &lay, 3.1, 0.4, &mid) == NBT_OK && isfinite(mid) && mid > 0, "inside the second layer: > 0");
    nbt_beam_medium badl = lay;
    badl.albedo = 1.5;
    t_true(nbt_beam_fit_psi(f, 0, &badl, 2, 0.5, &a1) == NBT_EDOM, "bad medium rejected");
    nbt_beam_fit half = *f;
    half.have[1] = 0;
    t_true(nbt_beam_fit_params(&half, 1, 1, 0.5, 0.05, po) == NBT_EDOM, "a geometry the model lacks rejected");

    /* file round trip: %.17g brings every coefficient back exactly */
    char path[] = "/tmp/nbt-test-beamfit-XXXXXX";
    int fd = mkstemp(path);
    FILE *fp = fdopen(fd, "w");
    t_true(nbt_beam_fit_fprint(fp, f, "# a comment\n") == NBT_OK, "write");
    fclose(fp);
    nbt_beam_fit back;
    char err[512] = "";
    t_true(nbt_beam_fit_read(path, &back, err, sizeof err) == NBT_OK, "read back: %s", err);
    t_true(memcmp(back.c, f->c, sizeof back.c) == 0 && memcmp(back.range, f->range, sizeof back.range) == 0 &&
               back.have[0] == 1 && back.have[1] == 1,
           "coefficients and range identical after the round trip");
    static const char *const bad[][2] = {
        {"half P0 1 2 3\n", "expected 16 finite numbers"},
        {"half P5 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0\n", "expected 'half|infinite P0..P4'"},
        {"upper P0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0\n", "expected 'half|infinite P0..P4'"},
        {"half P0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 7\n", "more than 16 numbers"},
        {"half P0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 nan\n", "expected 16 finite numbers"},
        {"half P0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0\n", "needs all of P0 .. P4"},
        {"range tau 5 1\n", "expected 'range tau|albedo|B LO HI'"},
        {"# nothing\n", "no coefficients"}};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        fp = fopen(path, "w");
        fputs(bad[i][0], fp);
        fclose(fp);
        nbt_status st = nbt_beam_fit_read(path, &back, err, sizeof err);
        t_true(st == NBT_EFORMAT && strstr(err, bad[i][1]) != NULL, "bad file %zu rejected: %s", i, err);
    }
    unlink(path);
    t_true(nbt_beam_fit_read("/nonexistent/model.txt", &back, err, sizeof err) == NBT_EIO, "missing file: %s", err);

    /* the shipped model against photon counts it was not fitted to (another seed, 2e5 photons):
     * the goal is 5% relative RMS; doc/kernelmodel_rms.txt measures 1.5-3% at these
     * points with 2e6 photons; the counts' own noise adds in quadrature */
    static const double pts[][2] = {{0.5, 0.0685}, {0.9, 0.154}}; /* (albedo, B): 30 and 45 deg */
    for (int g = 0; g < 2; g++)
        for (int i = 0; i < 2; i++) {
            double noise = NAN, r = rms_vs_mc(f, g, pts[i][0], pts[i][1], ws, &noise);
            t_true(r <= 0.05, "%s, albedo %g, dtheta %.0f deg: RMS %.4f vs photon counts (their noise %.4f) <= 0.05",
                   g ? "infinite" : "half-space", pts[i][0], 2 * sqrt(pts[i][1]) * 180 / M_PI, r, noise);
        }
    nbt_quad_ws_free(ws);
    test_fit_equivalent(f);
    test_from_P();
    return t_done();
}
