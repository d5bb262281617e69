/* tests/test_phase.c: normalisation, Legendre moments, series, truncation errors, SPEC parsing. */
#include <math.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>
#include <nbt/nbt.h>
#include "testutil.h"

static int p_mu(double mu, void *vp, unsigned fdim, double *f)
{
    (void)fdim;
    f[0] = 2.0 * M_PI * nbt_phase_eval(vp, mu);
    return 0;
}

/* P_k(x) written here, not taken from the library: the closed forms up to
 * P_3, then Bonnet's recurrence (k+1) P_{k+1} = (2k+1) x P_k - k P_{k-1} */
static double leg(int k, double x)
{
    double p0 = 1, p1 = x, p2 = 0.5 * (3 * x * x - 1), p3 = 0.5 * (5 * x * x * x - 3 * x);
    if (k < 4)
        return k == 0 ? p0 : k == 1 ? p1 : k == 2 ? p2 : p3;
    double a = p2, b = p3;
    for (int j = 3; j < k; j++) {
        double c = ((2 * j + 1) * x * b - j * a) / (j + 1);
        a = b;
        b = c;
    }
    return b;
}

/* 2 pi int p(mu) P_k(mu) dmu, integrated in theta (smooth for the Gaussian) */
typedef struct {
    const nbt_phase *p;
    int k;
} mom_ctx;
static int p_theta(double th, void *vp, unsigned fdim, double *f)
{
    (void)fdim;
    const mom_ctx *c = vp;
    f[0] = 2.0 * M_PI * nbt_phase_eval(c->p, cos(th)) * leg(c->k, cos(th)) * sin(th);
    return 0;
}

int main(void)
{
    nbt_quad_ws *ws = nbt_quad_ws_alloc(1, 2000);
    double r, e, b[64];
    nbt_phase *ph[9] = {nbt_phase_iso(), nbt_phase_rayleigh(), nbt_phase_hg(-0.7), nbt_phase_hg(0.385),
                        nbt_phase_hg(0.9), nbt_phase_gauss(0.0685), nbt_phase_gauss(0.6), nbt_phase_gauss(3.0),
                        NULL};
    double sw[3] = {0.2, 0.5, 0.3}, sB[3] = {0.01, 0.1, 1.0};
    ph[8] = nbt_phase_sog(3, sw, sB);
    for (int i = 0; i < 9; i++) {
        /* normalisation over the sphere, in theta (the Gaussian's mu = -1 singularity is integrable there) */
        mom_ctx c0 = {ph[i], 0};
        nbt_quad_gk(ws, p_theta, &c0, 1, 0.0, M_PI, 0.0, 1e-12, &r, &e);
        t_rel(r, 1.0, 1e-10, "%s is normalised over the sphere", nbt_phase_name(ph[i]));
        /* moments: closed form / library quadrature vs independent quadrature of p P_k */
        nbt_phase_moments(ph[i], 8, b);
        for (int k = 0; k <= 8; k++) {
            mom_ctx c = {ph[i], k};
            nbt_quad_gk(ws, p_theta, &c, 1, 0.0, M_PI, 1e-14, 1e-11, &r, &e);
            t_abs(b[k], r, 1e-10, "%s: b_%d matches 2 pi int p P_k", nbt_phase_name(ph[i]), k);
        }
        t_true(isfinite(nbt_phase_eval(ph[i], -1.0)) && isfinite(nbt_phase_eval(ph[i], 1.0)),
               "%s finite at mu = +-1", nbt_phase_name(ph[i]));
    }
    /* the library's P_k against the ones written here */
    {
        double P[41], worst = 0;
        for (double x = -1; x <= 1.0; x += 0.0385) {
            nbt_legendre_p(40, x, P);
            for (int k = 0; k <= 40; k++)
                worst = fmax(worst, fabs(P[k] - leg(k, x)));
        }
        t_abs(worst, 0, 1e-13, "nbt_legendre_p matches P_0..P_40 (closed forms + Bonnet)");
    }
    /* closed forms */
    nbt_phase_moments(ph[4], 40, b);
    t_rel(b[40], pow(0.9, 40), 1e-14, "HG b_40 = g^40");
    nbt_phase_moments(ph[1], 4, b);
    t_abs(b[2], 0.1, 0, "Rayleigh b_2 = 1/10");
    t_abs(b[1] + b[3] + b[4], 0, 0, "Rayleigh odd and high moments vanish");
    /* small-B Gaussian: mean cosine 1 - 2B + 4/3 B^2 + O(B^3) (theta Rayleigh-distributed, E theta^2 = 4B) */
    nbt_phase *gs = nbt_phase_gauss(1e-3);
    t_abs(nbt_phase_mean_cosine(gs), 1 - 2e-3 + 4.0 / 3.0 * 1e-6, 1e-8, "Gaussian B=1e-3 mean cosine");
    nbt_phase_free(gs);
    /* a lobe far narrower than [0, pi] (fuzzing found b_0 = 7e-18 at B = 1e-6):
     * O(B^3) = 1e-18, the quadrature tolerance ~1e-13 */
    for (double Bn = 1e-6; Bn > 1e-13; Bn *= 1e-3) {
        double bn[2];
        gs = nbt_phase_gauss(Bn);
        t_true(gs && nbt_phase_moments(gs, 1, bn) == NBT_OK, "Gaussian B=%g moments", Bn);
        t_abs(bn[0], 1, 1e-12, "Gaussian B=%g b_0", Bn);
        t_abs(bn[1], 1 - 2 * Bn + 4.0 / 3.0 * Bn * Bn, 1e-12, "Gaussian B=%g mean cosine", Bn);
        nbt_phase_free(gs);
    }
    /* the Legendre series reproduces HG */
    {
        size_t N = 80;
        double bb[81], worst = 0;
        nbt_phase_moments(ph[3], N, bb);
        for (double mu = -1; mu <= 1.0; mu += 0.0385) {
            double s = 0;
            for (size_t k = 0; k <= N; k++)
                s += (2.0 * k + 1.0) * bb[k] * leg((int)k, mu);
            worst = fmax(worst, fabs(s / (4 * M_PI) / nbt_phase_eval(ph[3], mu) - 1));
        }
        t_abs(worst, 0, 1e-12, "80-term series reproduces HG g=0.385");
    }
    /* truncation errors: closed forms vs brute-force tails */
    double gs_[3] = {0.385, -0.6, 0.9};
    for (int i = 0; i < 3; i++) {
        double g = gs_[i], a = fabs(g);
        for (size_t N = 0; N <= 20; N += 5) {
            double tail = 0, tail2 = 0, tot2 = 0;
            for (size_t k = 0; k < 20000; k++) {
                double t = (2.0 * k + 1.0) * pow(a, (double)k), t2 = (2.0 * k + 1.0) * pow(g * g, (double)k);
                if (k > N) {
                    tail += t;
                    tail2 += t2;
                }
                tot2 += t2;
            }
            double pmax = (1 + a) / ((1 - a) * (1 - a)); /* 4 pi max p */
            t_rel(nbt_phase_hg_trunc_error(g, N, NBT_NORM_MAX), tail / pmax, 1e-12, "HG g=%g N=%zu max-norm tail", g, N);
            t_rel(nbt_phase_hg_trunc_error(g, N, NBT_NORM_L2), sqrt(tail2 / tot2), 1e-12, "HG g=%g N=%zu L2 tail", g, N);
        }
        size_t N = nbt_phase_hg_terms(g, 1e-4, NBT_NORM_L2, 1000);
        t_true(nbt_phase_hg_trunc_error(g, N, NBT_NORM_L2) <= 1e-4 &&
                   (N == 0 || nbt_phase_hg_trunc_error(g, N - 1, NBT_NORM_L2) > 1e-4),
               "HG g=%g: N=%zu is the smallest meeting 1e-4", g, N);
    }
    /* SPEC parsing */
    char err[256];
    nbt_phase *p;
    t_true(nbt_phase_parse("hg:g=0.8", &p, err, sizeof err) == NBT_OK && fabs(nbt_phase_mean_cosine(p) - 0.8) < 1e-15,
           "parse hg:g=0.8");
    nbt_phase_free(p);
    t_true(nbt_phase_parse("hg:g=1", &p, err, sizeof err) == NBT_EDOM && strstr(err, "(-1, 1)") && !p, "hg:g=1 rejected: %s", err);
    t_true(nbt_phase_parse("gauss:B=-2", &p, err, sizeof err) == NBT_EDOM && strstr(err, "B"), "gauss:B=-2 rejected: %s", err);
    t_true(nbt_phase_parse("gauss:B=1e308", &p, err, sizeof err) == NBT_EDOM && strstr(err, "(0, 1000]") && !p,
           "gauss:B=1e308 rejected (4B overflows): %s", err);
    nbt_phase *g1000 = nbt_phase_gauss(1e3);
    t_true(g1000 != NULL && nbt_phase_gauss(1001) == NULL, "B up to 1000 accepted, 1001 not");
    nbt_phase_free(g1000);
    t_true(nbt_phase_parse("hg:g=0.8x", &p, err, sizeof err) == NBT_EDOM, "trailing garbage rejected");
    t_true(nbt_phase_parse("mie", &p, err, sizeof err) == NBT_EFORMAT && strstr(err, "mie"), "unknown kind rejected: %s", err);
    t_true(nbt_phase_parse("table:/nonexistent/x", &p, err, sizeof err) == NBT_EIO, "missing table file: %s", err);
    /* a tabulated HG, 4001 points: moments within the piecewise-linear error */
    char path[] = "/tmp/nbt-test-phaseXXXXXX";
    int fd = mkstemp(path);
    FILE *f = fdopen(fd, "w");
    fprintf(f, "# HG g=0.5, unnormalised on purpose\n");
    for (int i = 0; i <= 4000; i++) {
        double mu = i == 4000 ? 1.0 : -1.0 + i / 2000.0;
        fprintf(f, "%.17g %.17g\n", mu, 7.0 * 0.75 / pow(1.25 - mu, 1.5)); /* 7 x 4 pi HG(0.5) */
    }
    fclose(f);
    char spec[64];
    snprintf(spec, sizeof spec, "table:%s", path);
    t_true(nbt_phase_parse(spec, &p, err, sizeof err) == NBT_OK, "parse a table file");
    nbt_phase_moments(p, 4, b);
    for (int k = 1; k <= 4; k++)
        t_abs(b[k], pow(0.5, k), 2e-6, "tabulated HG 0.5: b_%d", k);
    nbt_quad_gk(ws, p_mu, p, 1, -1.0, 1.0, 0.0, 1e-12, &r, &e);
    t_rel(r, 1.0, 1e-9, "tabulated phase renormalised");
    nbt_phase_free(p);
    f = fopen(path, "w");
    fprintf(f, "-1 1\n0.5 oops\n1 1\n");
    fclose(f);
    t_true(nbt_phase_parse(spec, &p, err, sizeof err) == NBT_EFORMAT && strstr(err, ":2: phase table: '0.5 oops' is not accepted"), "bad table line: %s", err);
    f = fopen(path, "w");
    fprintf(f, "-0.9 1\n1 1\n");
    fclose(f);
    t_true(nbt_phase_parse(spec, &p, err, sizeof err) == NBT_EFORMAT, "table not starting at -1: %s", err);
    unlink(path);
    t_true(nbt_phase_hg(1.0) == NULL && nbt_phase_gauss(0) == NULL && nbt_phase_sog(1, sw, (double[]){-1}) == NULL,
           "constructors reject out-of-range parameters");
    for (int i = 0; i < 9; i++)
        nbt_phase_free(ph[i]);
    nbt_quad_ws_free(ws);
    return t_done();
}
