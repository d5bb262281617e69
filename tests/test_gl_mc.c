/* tests/test_gl_mc.c: the GLSL compute photon counter (nbt/gl_mc.h) on
 * whatever GL the machine has (CI: Mesa llvmpipe via EGL surfaceless):
 * van de Hulst's slab and the CPU counter within 4 standard errors, the
 * same bits for any work-group size and dispatch split, refusals.
 * Fails with a clear message when no GL context can be created. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include <nbt/nbt.h>
#include <nbt/gl_mc.h>
#include "../examples/egl_headless.h"
#include "testutil.h"
#include "mcref.h"

/* the GL driver leaks at eglTerminate: no leak report for this program */
const char *__asan_default_options(void);
const char *__asan_default_options(void)
{
    return "detect_leaks=0";
}

extern const char nbt_glsl_nbt_mc[]; /* the module's text in libnbt-gl */

/* the module as nbt_gl_mc_run assembles it passes the reference compiler */
static void validate(void)
{
    char path[] = "/tmp/nbt-test-glmc-XXXXXX";
    int fd = mkstemp(path);
    FILE *f = fd >= 0 ? fdopen(fd, "w") : NULL;
    if (f) {
        fprintf(f, "#version 430\n#define NBT_MC_WG 64\n%s", nbt_glsl_nbt_mc);
        fclose(f);
    }
    char cmd[256];
    snprintf(cmd, sizeof cmd, "glslangValidator -S comp %s >/dev/null 2>&1", path);
    int rc = f ? system(cmd) : -1;
    t_true(rc == 0, "glslangValidator accepts nbt_mc.glsl%s", rc == 0 ? "" : " (is glslang-tools installed?)");
    unlink(path);
}

static int same(const nbt_mc_result *a, const nbt_mc_result *b)
{
    size_t nv = a->nplanes * a->r_bins, np = a->nplanes;
    return a->R == b->R && a->T == b->T && a->R_se == b->R_se && a->interactions == b->interactions &&
           !memcmp(a->psi, b->psi, nv * sizeof(double)) && !memcmp(a->psi_se, b->psi_se, nv * sizeof(double)) &&
           !memcmp(a->M0, b->M0, np * sizeof(double)) && !memcmp(a->M2, b->M2, np * sizeof(double));
}

int main(void)
{
    char err[256];
    validate();
    if (egl_headless_open(err, sizeof err)) {
        t_true(0, "a GL context for the compute counter: %s", err);
        return t_done();
    }
    nbt_phase *hg = nbt_phase_hg(0.75);
    nbt_mc_config c = {.sigma_t = 1, .albedo = 0.9, .phase = hg, .slab = 2, .photons = 400000, .seed = 2385};
    nbt_mc_result *g1 = NULL, *g2 = NULL, *cpu = NULL;
    t_true(nbt_gl_mc_run(&c, 64, 0, &g1) == NBT_OK && g1, "GPU slab run");
    if (!g1)
        return t_done();
    /* 4 standard errors plus the reference's last digit; single precision
     * moves a path by ~1e-7 mean free paths, far below that */
    t_abs(g1->R, 0.09739, 4 * g1->R_se + 1e-5, "GPU slab R = 0.09739: %.5f (se %.1e)", g1->R, g1->R_se);
    t_abs(g1->T, 0.66096, 4 * g1->T_se + 1e-5, "GPU slab T = 0.66096: %.5f (se %.1e)", g1->T, g1->T_se);
    t_true(nbt_gl_mc_run(&c, 32, 1000, &g2) == NBT_OK && same(g1, g2),
           "slab: identical for work groups of 64 and 32, one dispatch per batch and dispatches of 1000");
    nbt_mc_result_free(g2);
    nbt_mc_result_free(g1);

    /* planes in a half-space, Gaussian phase (40 deg): against the CPU
     * counter (another random stream) within 4 combined standard errors */
    nbt_phase *ga = nbt_phase_gauss(0.12);
    double planes[3] = {0.7, 1.9, 3.1};
    c = (nbt_mc_config){
        .sigma_t = 1.1, .albedo = 0.8, .phase = ga, .nplanes = 3, .z_planes = planes, .r_bins = 12, .r_max_scale = 1.2,
        .photons = 200000, .seed = 99
    };
    t_true(nbt_gl_mc_run(&c, 64, 0, &g1) == NBT_OK && nbt_mc_run(&c, &cpu) == NBT_OK, "GPU and CPU plane runs");
    int nbad = 0, mbad = 0;
    for (size_t j = 0; j < 3; j++) {
        mbad += !(fabs(g1->M0[j] - cpu->M0[j]) <= 4 * hypot(g1->M0_se[j], cpu->M0_se[j]));
        mbad += !(fabs(g1->M2[j] - cpu->M2[j]) <= 4 * hypot(g1->M2_se[j], cpu->M2_se[j]));
        for (size_t k = 0; k < 12; k++) {
            size_t i = j * 12 + k;
            double se = hypot(g1->psi_se[i], cpu->psi_se[i]);
            if (!(fabs(g1->psi[i] - cpu->psi[i]) <= 4 * se) && nbad++ < 5)
                printf("  z=%g bin %zu: GPU %.5g, CPU %.5g, se %.2g\n", planes[j], k, g1->psi[i], cpu->psi[i], se);
        }
    }
    t_true(mbad == 0, "GPU M0, M2 = CPU within 4 se at 3 planes (%d off)", mbad);
    t_true(nbad == 0, "GPU Psi = CPU within 4 se in all 36 bins (%d off)", nbad);
    t_true(nbt_gl_mc_run(&c, 256, 777, &g2) == NBT_OK && same(g1, g2),
           "planes: identical for work groups of 64 and 256, dispatches of 1 batch and of 777 photons");
    nbt_mc_result_free(g2);
    c.order_max = 1;
    nbt_mc_result *gi;
    t_true(nbt_gl_mc_run(&c, 64, 0, &gi) == NBT_OK, "GPU single-scattering run");
    /* order 1 only: the CPU's own single-scattering run as the reference */
    nbt_mc_result *ci;
    nbt_mc_run(&c, &ci);
    t_abs(gi->M0[2], ci->M0[2], 4 * hypot(gi->M0_se[2], ci->M0_se[2]), "order_max 1: GPU M0 %.5f vs CPU %.5f", gi->M0[2],
          ci->M0[2]);
    nbt_mc_result_free(gi);
    nbt_mc_result_free(ci);
    nbt_mc_result_free(g1);
    nbt_mc_result_free(cpu);

    /* a very narrow Gaussian (B = 1e-5), albedo 0.99: nearly every direction
     * stays within 0.0045 rad of the axis, where a turn that forgets the
     * tilt loses 5% of M2 at z = 8; against the small-angle random walk
     * (exact as B -> 0; model error below 0.5%, see test_mc), 3 se + 1.5% */
    {
        nbt_phase *gn = nbt_phase_gauss(1e-5);
        double zn = 8.0, M0, M2;
        c = (nbt_mc_config){
            .sigma_t = 1, .albedo = 0.99, .phase = gn, .nplanes = 1, .z_planes = &zn, .r_bins = 4,
            .r_max_scale = 0.2, .photons = 200000, .seed = 31
        };
        nbt_beam_medium m = nbt_beam_homogeneous(1.0, 0.99, 1e-5);
        nbt_beam_moments(&m, NBT_BEAM_SMALLANGLE, zn, &M0, &M2, NULL);
        t_true(nbt_gl_mc_run(&c, 64, 0, &g1) == NBT_OK && g1, "GPU narrow Gaussian run");
        if (g1) {
            t_abs(g1->M2[0], M2, 3 * g1->M2_se[0] + 0.015 * M2,
                  "GPU B = 1e-5, albedo 0.99: M2 at z = 8 %.5g (se %.1e) = random walk %.5g (every tilt)", g1->M2[0],
                  g1->M2_se[0], M2);
            nbt_mc_result_free(g1);
        }
        nbt_phase_free(gn);
    }

    /* a wide Gaussian (B = 1000), whose truncation at theta = pi matters:
     * single-scattering slab reflectance against the quadrature of
     * tests/mcref.h within 4 standard errors */
    nbt_phase *gw = nbt_phase_gauss(1000);
    c = (nbt_mc_config){
        .sigma_t = 1, .albedo = 1, .phase = gw, .slab = 0.5, .order_max = 1, .photons = 400000, .seed = 12
    };
    t_true(nbt_gl_mc_run(&c, 64, 0, &g1) == NBT_OK && g1, "GPU wide Gaussian slab run");
    if (g1) {
        double ref = mcref_slab_r1(gw, 0.5, 1.0);
        t_abs(g1->R, ref, 4 * g1->R_se + 1e-9, "GPU B = 1000: single-scattering slab R %.5f = %.5f (se %.1e)", g1->R, ref,
              g1->R_se);
        nbt_mc_result_free(g1);
    }
    nbt_phase_free(gw);

    /* refusals */
    nbt_phase *ray = nbt_phase_rayleigh();
    c.order_max = 0;
    c.phase = ray;
    t_true(nbt_gl_mc_run(&c, 64, 0, &g1) == NBT_EINVAL && g1 == NULL, "Rayleigh refused");
    c.phase = ga;
    c.estimator = NBT_MC_WEIGHTED;
    t_true(nbt_gl_mc_run(&c, 64, 0, &g1) == NBT_EINVAL, "weighted refused");
    c.estimator = NBT_MC_ANALOG;
    c.albedo = 2;
    t_true(nbt_gl_mc_run(&c, 64, 0, &g1) == NBT_EDOM, "albedo 2 refused");
    c.albedo = 0.5;
    t_true(nbt_gl_mc_run(&c, 2000, 0, &g1) == NBT_EDOM, "work group 2000 refused");
    nbt_phase_free(ray);
    nbt_phase_free(ga);
    nbt_phase_free(hg);
    egl_headless_close();
    return t_done();
}
