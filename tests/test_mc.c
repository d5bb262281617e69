/* tests/test_mc.c: photon counting against van de Hulst's slab values and
 * single-scattering theory; determinism; bad configurations. */
#include <math.h>
#include <string.h>
#include <nbt/nbt.h>
#include "testutil.h"

typedef struct {
    const nbt_beam_medium *m;
    double z;
} ann_ctx;
static int ann_f(double r, void *vp, unsigned fdim, double *f)
{
    (void)fdim;
    const ann_ctx *c = vp;
    double p;
    nbt_beam_psi(c->m, NBT_PSI_SINGLE, c->z, r, &p, NULL);
    f[0] = 2 * M_PI * r * p;
    return 0;
}

static double rho_smooth(double z, void *d)
{
    (void)d;
    return 1.0 + 0.5 * sin(z);
}

int main(void)
{
    /* van de Hulst (as quoted in the MCML manual): albedo 0.9, tau 2, HG g 0.75, n = 1 */
    nbt_phase *hg = nbt_phase_hg(0.75);
    nbt_mc_config c;
    memset(&c, 0, sizeof c);
    c.sigma_t = 1;
    c.albedo = 0.9;
    c.phase = hg;
    c.slab = 2;
    nbt_mc_result *r1, *r2;
    /* four independent seeds, 1M photons each, combined; a check of the
     * estimator over 60 seeds gave z-scores of mean 0.18 +- 0.13, sd 0.95 */
    double Rs = 0, Ts = 0, Rv = 0, Tv = 0;
    c.photons = 1000000;
    for (int s = 0; s < 4; s++) {
        c.seed = 2385 + 1000 * (uint64_t)s;
        t_true(nbt_mc_run(&c, &r1) == NBT_OK, "slab run, seed %d", 2385 + 1000 * s);
        Rs += r1->R / 4;
        Ts += r1->T / 4;
        Rv += r1->R_se * r1->R_se / 16;
        Tv += r1->T_se * r1->T_se / 16;
        nbt_mc_result_free(r1);
    }
    /* 3 standard errors, plus the reference's last digit */
    t_abs(Rs, 0.09739, 3 * sqrt(Rv) + 1e-5, "slab R = 0.09739 (se %.1e)", sqrt(Rv));
    t_abs(Ts, 0.66096, 3 * sqrt(Tv) + 1e-5, "slab T = 0.66096 (se %.1e)", sqrt(Tv));
    c.threads = 1;
    c.photons = 200000;
    nbt_mc_run(&c, &r1);
    c.threads = 2;
    nbt_mc_run(&c, &r2);
    t_true(r1->R == r2->R && r1->T == r2->T && r1->R_se == r2->R_se && r1->interactions == r2->interactions,
           "slab results identical with 1 and 2 threads");
    nbt_mc_result_free(r2);
    c.seed = 2386;
    nbt_mc_run(&c, &r2);
    t_true(r1->R != r2->R, "another seed gives another sample");
    nbt_mc_result_free(r1);
    nbt_mc_result_free(r2);

    /* a tabulated HG samples like HG */
    double mu[2001], pv[2001];
    for (int i = 0; i <= 2000; i++) {
        mu[i] = i == 2000 ? 1.0 : -1.0 + i / 1000.0;
        pv[i] = nbt_phase_eval(hg, mu[i]);
    }
    nbt_phase *tab = nbt_phase_tabulated(2001, mu, pv);
    c.phase = tab;
    c.photons = 1000000;
    nbt_mc_run(&c, &r1);
    t_abs(r1->R, 0.09739, 3 * r1->R_se + 2e-4, "tabulated HG slab R (se %.1e)", r1->R_se);
    t_abs(r1->T, 0.66096, 3 * r1->T_se + 2e-4, "tabulated HG slab T (se %.1e)", r1->T_se);
    nbt_mc_result_free(r1);

    /* low albedo, narrow Gaussian: single scattering, where the small-angle
     * theory is exact up to O(B): M0, M2 and the r-resolved Psi per unit area */
    double B = 0.001, planes[2] = {1.0, 2.0};
    nbt_phase *ga = nbt_phase_gauss(B);
    memset(&c, 0, sizeof c);
    c.sigma_t = 1;
    c.albedo = 0.03;
    c.phase = ga;
    c.nplanes = 2;
    c.z_planes = planes;
    c.r_bins = 10;
    c.r_max_scale = 0.1;
    c.photons = 4000000;
    c.seed = 7;
    t_true(nbt_mc_run(&c, &r1) == NBT_OK, "plane run");
    nbt_beam_medium m = nbt_beam_homogeneous(1.0, 0.03, B);
    nbt_quad_ws *ws = nbt_quad_ws_alloc(1, 1000);
    for (int j = 0; j < 2; j++) {
        double z = planes[j], M0, M2, M0i, M2i;
        /* The small-angle random walk is exact for a photon counter in the
         * small-angle limit (every scattering at y adds 4B (z-y)^2 to E r^2);
         * model error: path length 1/cos(theta) ~ 1 + 2B, tan vs theta ~ 4B/3. */
        nbt_beam_moments(&m, NBT_BEAM_SMALLANGLE, z, &M0, &M2, NULL);
        t_abs(r1->M0[j], M0, 3 * r1->M0_se[j] + 0.005 * M0, "M0 at z=%g: MC %.5g vs %.5g", z, r1->M0[j], M0);
        t_abs(r1->M2[j], M2, 3 * r1->M2_se[j] + 0.01 * M2, "M2 at z=%g: MC %.5g vs random walk %.5g", z, r1->M2[j], M2);
        /* Ishimaru's eq. 26 is ~(1 + 1.5 sigma_s z) times that already here: the counter sides with the walk */
        nbt_beam_moments(&m, NBT_BEAM_ISHIMARU, z, &M0i, &M2i, NULL);
        t_true(fabs(r1->M2[j] - M2) < fabs(r1->M2[j] - M2i), "z=%g: MC M2 closer to the random walk (%.4g) than to eq. 26 (%.4g)",
               z, M2, M2i);
        int ok = 1;
        for (size_t k = 0; k < 10; k++) {
            double dr = 0.1 * z / 10, lo = k * dr, hi = lo + dr, v, e;
            ann_ctx ac = {&m, z};
            nbt_quad_gk(ws, ann_f, &ac, 1, lo > 0 ? lo : 1e-12, hi, 0, 1e-9, &v, &e);
            double want = v / (M_PI * (hi * hi - lo * lo)) * exp(0.0);
            /* the multiply scattered part is O(sigma_s z) of the single at this albedo */
            double got = r1->psi[j * 10 + k], se = r1->psi_se[j * 10 + k];
            ok &= fabs(got - want) <= 3 * se + 0.02 * want + 0.03 * z * want;
            if (!(fabs(got - want) <= 3 * se + 0.02 * want + 0.03 * z * want))
                printf("  z=%g bin %zu: MC %.5g +- %.2g, single scattering %.5g\n", z, k, got, se, want);
        }
        t_true(ok, "Psi per unit area matches single scattering, every bin at z=%g", z);
    }
    nbt_mc_result_free(r1);
    nbt_quad_ws_free(ws);

    /* layers: a vacuum gap changes nothing for M0 (forward photons cross once) */
    double zl[3] = {0, 1, 2}, rl[3] = {1, 0, 1}, p3[1] = {3.0};
    c.nlayers = 3;
    c.z = zl;
    c.rho = rl;
    c.nplanes = 1;
    c.z_planes = p3;
    c.albedo = 0.5;
    c.photons = 1000000;
    nbt_mc_run(&c, &r1);
    nbt_mc_config bad_base = c;
    m.albedo = 0.5;
    m.nlayers = 3;
    m.z = zl;
    m.rho = rl;
    double M0, M2;
    nbt_beam_moments(&m, NBT_BEAM_ISHIMARU, 3.0, &M0, &M2, NULL);
    t_abs(r1->M0[0], M0, 3 * r1->M0_se[0] + 0.005 * M0, "vacuum gap: M0 = e^-sa zeta (1 - e^-ss zeta): %.5g vs %.5g", r1->M0[0], M0);
    nbt_mc_result_free(r1);

    /* a continuous density by delta tracking: M0 depends on zeta only */
    memset(&c, 0, sizeof c);
    c.sigma_t = 1;
    c.albedo = 0.5;
    c.phase = ga;
    c.rho_fn = rho_smooth;
    c.rho_max = 1.5;
    c.nplanes = 1;
    c.z_planes = p3;
    c.r_bins = 4;
    c.r_max_scale = 0.1;
    c.photons = 1000000;
    c.seed = 3;
    t_true(nbt_mc_run(&c, &r1) == NBT_OK, "delta-tracking run");
    double zeta3 = 3 + 0.5 * (1 - cos(3.0)), M0c = exp(-0.5 * zeta3) * (1 - exp(-0.5 * zeta3));
    t_abs(r1->M0[0], M0c, 3 * r1->M0_se[0] + 0.005 * M0c, "callback density: M0 %.5g vs %.5g", r1->M0[0], M0c);
    nbt_mc_result_free(r1);
    c.rho_max = 1.2;
    t_true(nbt_mc_run(&c, &r1) == NBT_EDOM && r1 == NULL, "a callback above rho_max is detected");
    c.rho_max = 0;
    t_true(nbt_mc_run(&c, &r1) == NBT_EDOM, "a callback without a bound is rejected");
    c = bad_base;

    /* bad configurations */
    nbt_mc_config bad = c;
    bad.albedo = 1.5;
    t_true(nbt_mc_run(&bad, &r1) == NBT_EDOM && r1 == NULL, "albedo 1.5 rejected");
    bad = c;
    bad.photons = 10;
    t_true(nbt_mc_run(&bad, &r1) == NBT_EDOM, "fewer than 64 photons rejected");
    bad = c;
    double pb[2] = {2, 1};
    bad.nplanes = 2;
    bad.z_planes = pb;
    t_true(nbt_mc_run(&bad, &r1) == NBT_EDOM, "decreasing planes rejected");
    bad = c;
    bad.nplanes = 0;
    bad.slab = 0;
    t_true(nbt_mc_run(&bad, &r1) == NBT_EINVAL, "nothing to tally rejected");
    bad = c;
    bad.sigma_t = NAN;
    t_true(nbt_mc_run(&bad, &r1) == NBT_EDOM, "sigma_t NaN rejected");
    nbt_phase_free(hg);
    nbt_phase_free(tab);
    nbt_phase_free(ga);
    return t_done();
}
