/* tests/pyref.c: libnbt's own results for tests/test_python.py, which makes
 * the same calls through the Python package (ctypes) and must get the same
 * doubles bit for bit. One line per result: a key, then C's %a (exact hex)
 * for each value. The inputs here are written again in test_python.py. */
#include <config.h>
#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <nbt/airlight.h>
#include <nbt/beam.h>
#include <nbt/mc.h>
#include <nbt/phase.h>
#include <nbt/plan.h>
#include <nbt/screen.h>
#include <nbt/screen_path.h>
#include <nbt/surface.h>
#include <nbt/table.h>

static void put(const char *key, const double *v, size_t n)
{
    printf("%s", key);
    for (size_t i = 0; i < n; i++)
        printf(" %a", v[i]);
    printf("\n");
}

static void put1(const char *key, double v) { put(key, &v, 1); }

static void die(const char *what)
{
    fprintf(stderr, "pyref: %s failed\n", what);
    exit(1);
}

/* the test image: w x h, colours from a fixed pattern, two depth layers and a sky pixel */
static void image(size_t w, size_t h, float *rgb, float *D, double near, double far)
{
    for (size_t y = 0; y < h; y++)
        for (size_t x = 0; x < w; x++) {
            for (size_t c = 0; c < 3; c++)
                rgb[(y * w + x) * 3 + c] = (float)(0.05 + 0.9 * ((double)((x * 7 + y * 3 + c * 5) % 11) / 10.0));
            D[y * w + x] = (float)(x < w / 2 ? near : far);
        }
    D[w - 1] = (float)NBT_SCREEN_SKY; /* top right: sky */
}

int main(void)
{
#define SZ(t) printf("sizeof %s %zu\n", #t, sizeof(t))
    SZ(nbt_axis); SZ(nbt_table); SZ(nbt_beam_medium); SZ(nbt_airlight_geom); SZ(nbt_surface_geom);
    SZ(nbt_build_opts); SZ(nbt_screen_kern); SZ(nbt_screen_input); SZ(nbt_screen_world);
    SZ(nbt_screen_path_medium); SZ(nbt_screen_path_opts); SZ(nbt_mc_config); SZ(nbt_mc_result); SZ(nbt_scene);
    SZ(nbt_plan_request); SZ(nbt_plan_set); SZ(nbt_tableset);

    /* phase functions: a two-term HG (closed-form moments) and a Gaussian (quadrature) */
    nbt_phase *p2 = NULL, *pg = NULL, *hg = nbt_phase_hg(0.6);
    if (nbt_phase_parse("hg2:g1=0.8,g2=-0.3,w=0.7", &p2, NULL, 0) != NBT_OK ||
        nbt_phase_parse("gauss:B=0.05", &pg, NULL, 0) != NBT_OK || !hg)
        die("phase");
    const double mus[5] = {-0.9, -0.2, 0.0, 0.35, 0.99};
    double v[64];
    for (int i = 0; i < 5; i++)
        v[i] = nbt_phase_eval(p2, mus[i]);
    put("hg2.eval", v, 5);
    nbt_phase_moments(p2, 6, v);
    put("hg2.moments", v, 7);
    put1("hg2.g", nbt_phase_mean_cosine(p2));
    nbt_phase_moments(pg, 5, v);
    put("gauss.moments", v, 6);

    /* beam kernels: two lobes, unequal weights */
    nbt_beam_medium m = nbt_beam_homogeneous(1.3, 0.85, 0.02);
    m.nlobes = 2;
    m.w[0] = 0.6, m.w[1] = 0.4, m.B[1] = 0.2;
    const double zs[2] = {0.7, 2.9};
    for (int i = 0; i < 2; i++) {
        double M[4];
        if (nbt_beam_moments(&m, NBT_BEAM_ISHIMARU, zs[i], &M[0], &M[1], NULL) != NBT_OK ||
            nbt_beam_moments(&m, NBT_BEAM_SMALLANGLE, zs[i], &M[2], &M[3], NULL) != NBT_OK)
            die("moments");
        put(i ? "beam.moments.1" : "beam.moments.0", M, 4);
    }
    for (int k = 0; k <= NBT_PSI_ELEK; k++)
        if (nbt_beam_psi(&m, (nbt_psi_model)k, 2.1, 0.37, &v[k], NULL) != NBT_OK)
            die("psi");
    put("beam.psi", v, 5);
    const nbt_beam_fit *fit = nbt_beam_fit_default();
    if (nbt_beam_fit_psi(fit, 0, &m, 2.1, 0.37, &v[0]) != NBT_OK || nbt_beam_fit_psi(fit, 1, &m, 2.1, 0.37, &v[1]))
        die("fit_psi");
    put("beam.fit_psi", v, 2);

    /* H_k, J_k^n, airlight and surface radiance by series (HG 0.6, 12 terms) */
    double e[8];
    nbt_hk(5, 0.8, -0.3, 1e-10, v, e);
    put("hk", v, 6);
    nbt_jk(3, 1, 1.4, 0.6, 1e-10, v, e);
    put("jk", v, 4);
    double b[12];
    nbt_phase_moments(hg, 11, b);
    nbt_airlight_geom ag = {0.1, 0.25, 2.0, 5.0, 0.7, 8.0};
    double La, err;
    if (nbt_airlight_series(b, 12, &ag, 1e-8, &La, &err) != NBT_OK)
        die("airlight_series");
    put1("airlight.series", La);
    nbt_surface_geom sg = {0.1, 0.25, 2.0, 3.0, 0.4, 1.1, 0.6, 0.3, 8};
    if (nbt_surface_series(b, 12, &sg, 1e-8, &La, &err) != NBT_OK)
        die("surface_series");
    put1("surface.series", La);

    /* a planned H table (orders 0..3, 17 x 9 nodes) and two lookups */
    nbt_plan_request rq = {NBT_TABLE_H, 0, 4, NULL, 5.0, 0.0, {17, 9}, 0, 0};
    nbt_plan *pl = NULL;
    nbt_tableset ts;
    if (nbt_plan_tables(&rq, 1, 1, &pl, NULL, 0) != NBT_OK || nbt_plan_execute(pl, 0, &ts, NULL, 0) != NBT_OK)
        die("plan");
    nbt_table_lookup(ts.t[0], 0.3, 0.1, v);
    nbt_table_lookup(ts.t[0], 1.7, -0.8, v + 4);
    put("table.lookup", v, 8);
    const nbt_table *tp[1] = {ts.t[0]};
    if (nbt_airlight_table_e(tp, 1, b, 4, NULL, &ag, &La, &err) != NBT_OK)
        die("airlight_table");
    put1("airlight.table", La);
    nbt_tableset_free(&ts);
    nbt_plan_free(pl);
    /* a planned J^1 table (orders 0..3, 17 x 9) and surface radiance from it (diffuse only) */
    nbt_plan_request rj = {NBT_TABLE_J, 1, 4, NULL, 4.0, 0.0, {17, 9}, 0, 0};
    if (nbt_plan_tables(&rj, 1, 1, &pl, NULL, 0) != NBT_OK || nbt_plan_execute(pl, 0, &ts, NULL, 0) != NBT_OK)
        die("plan J");
    nbt_surface_geom sd = {0.1, 0.25, 2.0, 3.0, 0.4, 1.1, 0.6, 0.0, 1};
    const nbt_table *tj[1] = {ts.t[0]};
    if (nbt_surface_table(tj, 1, NULL, 0, b, 4, &sd, &La) != NBT_OK)
        die("surface_table");
    put1("surface.table", La);
    nbt_tableset_free(&ts);
    nbt_plan_free(pl);

    /* the photon counter: 4096 photons, seed 3, two planes, 3 bins */
    const double zp[2] = {0.5, 1.5};
    nbt_mc_config mc = {0};
    mc.sigma_t = 1.0, mc.albedo = 0.9, mc.phase = hg, mc.nplanes = 2, mc.z_planes = zp, mc.r_bins = 3;
    mc.r_max_scale = 0.8, mc.photons = 4096, mc.seed = 3, mc.threads = 1;
    nbt_mc_result *mr = NULL;
    if (nbt_mc_run(&mc, &mr) != NBT_OK)
        die("mc");
    put("mc.psi", mr->psi, 6);
    put("mc.M0", mr->M0, 2);
    put("mc.M2", mr->M2, 2);
    nbt_mc_result_free(mr);

    /* screen-space operators on a 9 x 5 image (non-square, sky in the top right) */
    enum { W = 9, H = 5 };
    float rgb[W * H * 3], D[W * H];
    double S[W * H * 3], T[W * H];
    image(W, H, rgb, D, 2.5, 7.0);
    nbt_screen_input in = {W, H, rgb, D, 0.02, NULL};
    nbt_screen_kernel *kf = nbt_screen_kernel_phase(NBT_SKERNEL_FITTED, 0.4, 0.8, hg, NBT_SCREEN_ENTERING, NULL);
    if (!kf || nbt_screen_layered(&in, kf, NBT_SCREEN_NEAR, 1e-7, 4, 1, S, T) != NBT_OK)
        die("layered");
    put("screen.layered.S", S, W * H * 3);
    put("screen.layered.T", T, W * H);
    nbt_screen_kernel *ke = nbt_screen_kernel_phase(NBT_SKERNEL_ELEK, 0.4, 0.8, hg, NBT_SCREEN_INSIDE, NULL);
    if (!ke || nbt_screen_brute(&in, ke, NBT_SCREEN_SOURCE, 1e-7, 1, S, NULL) != NBT_OK)
        die("brute elek");
    put("screen.brute.elek", S, W * H * 3);
    nbt_screen_kernel *km = nbt_screen_kernel_alloc(NBT_SKERNEL_MOMENT, &m, NULL);
    if (!km || nbt_screen_brute(&in, km, NBT_SCREEN_NEAR, 1e-7, 1, S, T) != NBT_OK)
        die("brute moment");
    put("screen.brute.moment", S, W * H * 3);
    nbt_screen_kern kk;
    nbt_screen_kernel_eval(kf, 3.3, &kk);
    put1("kernel.T", kk.T);
    put("kernel.mass", kk.mass, kk.n);
    put("kernel.scale", kk.scale, kk.n);
    nbt_screen_kernel_free(kf);
    nbt_screen_kernel_free(ke);
    nbt_screen_kernel_free(km);

    /* the path tracer: a 7 x 4 world, display window 5 x 3 at (1, 1), RGB medium */
    enum { PW = 7, PH = 4 };
    float prgb[PW * PH * 3], PZ[PW * PH];
    image(PW, PH, prgb, PZ, 1.5, 4.0);
    nbt_screen_world wd = {PW, PH, prgb, PZ, 0.05, 3.2, 2.1, 1, 1, 5, 3};
    nbt_screen_path_medium pm = {{0.3, 0.35, 0.4}, {0.9, 0.8, 0.7}, hg, INFINITY, {0.1, 0.2, 0.3}};
    nbt_screen_path_opts po = {0};
    po.spp = 4, po.seed = 11, po.nthreads = 1;
    double PS[5 * 3 * 3], Pse[5 * 3 * 3];
    unsigned long done = 0;
    if (nbt_screen_path(&wd, &pm, &po, PS, Pse, &done) != NBT_OK)
        die("path");
    put("path.S", PS, 45);
    put("path.se", Pse, 45);

    nbt_phase_free(p2);
    nbt_phase_free(pg);
    nbt_phase_free(hg);
    return 0;
}
