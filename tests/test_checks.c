/* tests/test_checks.c: the public argument checks (nbt_airlight_check,
 * nbt_surface_check, nbt_beam_check, nbt_screen_check, and nbt_screen_path's
 * world check) called directly, at
 * every bound from both sides: the value just inside is accepted, the value
 * just outside (and NaN, inf) refused with NBT_EDOM and one line through the
 * error handler that names the field and the bad value. Before, these were
 * reached only through their callers' bad-input tests, which never put a
 * value next to a bound, and the messages named no value. */
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <string.h>
#include <nbt/airlight.h>
#include <nbt/beam.h>
#include <nbt/grid.h>
#include <nbt/phase.h>
#include <nbt/screen.h>
#include <nbt/screen_path.h>
#include <nbt/surface.h>
#include "testutil.h"

static char last[512];
static int calls;

static void handler(const char *reason, nbt_status st)
{
    (void)st;
    snprintf(last, sizeof last, "%s", reason);
    calls++;
}

/* st must be want; for a refusal the handler got exactly one line holding every word of `words` ('|'-separated) */
static void expect(nbt_status st, nbt_status want, const char *words, const char *label)
{
    int ok = st == want;
    if (want == NBT_OK)
        ok = ok && calls == 0;
    else {
        ok = ok && calls == 1 && !strchr(last, '\n');
        char buf[256];
        snprintf(buf, sizeof buf, "%s", words);
        for (char *w = strtok(buf, "|"); w && ok; w = strtok(NULL, "|"))
            ok = strstr(last, w) != NULL;
    }
    t_true(ok, "%s: status %d (want %d), %d handler call(s), '%s' (want '%s')", label, st, want, calls,
           calls ? last : "", words ? words : "");
    calls = 0;
    last[0] = '\0';
}

static void test_airlight(void)
{
    const nbt_airlight_geom ok = {0.3, 0.5, 2.0, 4.0, 1.1, 3.0};
    nbt_airlight_geom g = ok;
    expect(nbt_airlight_check(&g), NBT_OK, NULL, "airlight: a valid geometry");
    /* kappa_s >= 0 (0 accepted), kappa_t >= kappa_s (equal accepted) */
    g = ok, g.kappa_s = 0;
    expect(nbt_airlight_check(&g), NBT_OK, NULL, "airlight: kappa_s = 0");
    g = ok, g.kappa_s = -1e-300;
    expect(nbt_airlight_check(&g), NBT_EDOM, "kappa_s = -1e-300|>= 0", "airlight: kappa_s < 0");
    g = ok, g.kappa_s = NAN;
    expect(nbt_airlight_check(&g), NBT_EDOM, "kappa_s = nan", "airlight: kappa_s NaN");
    g = ok, g.kappa_t = 0.3;
    expect(nbt_airlight_check(&g), NBT_OK, NULL, "airlight: kappa_t = kappa_s");
    g = ok, g.kappa_t = nextafter(0.3, 0);
    expect(nbt_airlight_check(&g), NBT_EDOM, "kappa_t = 0.3 |kappa_s = 0.3", "airlight: kappa_t just below kappa_s");
    g = ok, g.kappa_t = INFINITY;
    expect(nbt_airlight_check(&g), NBT_EDOM, "kappa_t = inf", "airlight: kappa_t inf");
    g = ok, g.I0 = 0;
    expect(nbt_airlight_check(&g), NBT_OK, NULL, "airlight: I0 = 0");
    g = ok, g.I0 = -2;
    expect(nbt_airlight_check(&g), NBT_EDOM, "I0 = -2", "airlight: I0 < 0");
    g = ok, g.I0 = INFINITY;
    expect(nbt_airlight_check(&g), NBT_EDOM, "I0 = inf", "airlight: I0 inf");
    g = ok, g.dsv = 0;
    expect(nbt_airlight_check(&g), NBT_EDOM, "dsv = 0|> 0", "airlight: dsv = 0");
    g = ok, g.dsv = INFINITY;
    expect(nbt_airlight_check(&g), NBT_EDOM, "dsv = inf", "airlight: dsv inf");
    /* gamma in [0, pi]: both ends accepted, just beyond refused */
    g = ok, g.gamma = 0, g.dvp = 3.0;
    expect(nbt_airlight_check(&g), NBT_OK, NULL, "airlight: gamma = 0, surface before the source");
    g = ok, g.gamma = M_PI;
    expect(nbt_airlight_check(&g), NBT_OK, NULL, "airlight: gamma = pi");
    g = ok, g.gamma = nextafter(M_PI, 4);
    expect(nbt_airlight_check(&g), NBT_EDOM, "gamma = 3.14159|[0, pi]", "airlight: gamma just above pi");
    g = ok, g.gamma = -1e-9;
    expect(nbt_airlight_check(&g), NBT_EDOM, "gamma = -1e-09", "airlight: gamma < 0");
    g = ok, g.dvp = INFINITY;
    expect(nbt_airlight_check(&g), NBT_OK, NULL, "airlight: dvp infinite");
    g = ok, g.dvp = 0;
    expect(nbt_airlight_check(&g), NBT_EDOM, "dvp = 0", "airlight: dvp = 0");
    /* gamma = 0: the ray meets the source when dvp >= dsv (equal: it ends on it) */
    g = ok, g.gamma = 0, g.dvp = nextafter(4.0, 0);
    expect(nbt_airlight_check(&g), NBT_OK, NULL, "airlight: gamma = 0, dvp just short of dsv");
    g = ok, g.gamma = 0, g.dvp = 4.0;
    expect(nbt_airlight_check(&g), NBT_EDOM, "dvp = 4 >= dsv = 4|infinite", "airlight: gamma = 0, dvp = dsv");
    g = ok, g.gamma = 1e-12, g.dvp = INFINITY;
    expect(nbt_airlight_check(&g), NBT_OK, NULL, "airlight: gamma 1e-12, dvp infinite (misses the source)");
}

static void test_surface(void)
{
    const nbt_surface_geom ok = {0.3, 0.5, 2.0, 4.0, 0.7, 1.9, 0.6, 0.25, 20};
    nbt_surface_geom g = ok;
    expect(nbt_surface_check(&g), NBT_OK, NULL, "surface: a valid geometry");
    g = ok, g.kappa_s = -0.5;
    expect(nbt_surface_check(&g), NBT_EDOM, "kappa_s = -0.5", "surface: kappa_s < 0");
    g = ok, g.kappa_t = 0.3;
    expect(nbt_surface_check(&g), NBT_OK, NULL, "surface: kappa_t = kappa_s");
    g = ok, g.kappa_t = 0.25;
    expect(nbt_surface_check(&g), NBT_EDOM, "kappa_t = 0.25|kappa_s = 0.3", "surface: kappa_t < kappa_s");
    g = ok, g.I0 = -1;
    expect(nbt_surface_check(&g), NBT_EDOM, "I0 = -1", "surface: I0 < 0");
    g = ok, g.dsp = 0;
    expect(nbt_surface_check(&g), NBT_EDOM, "dsp = 0", "surface: dsp = 0");
    g = ok, g.dsp = 1e-300;
    expect(nbt_surface_check(&g), NBT_OK, NULL, "surface: dsp tiny");
    /* theta_s and theta_r each in [0, pi], named separately */
    g = ok, g.theta_s = 0, g.theta_r = M_PI;
    expect(nbt_surface_check(&g), NBT_OK, NULL, "surface: theta_s = 0, theta_r = pi");
    g = ok, g.theta_s = M_PI, g.theta_r = 0;
    expect(nbt_surface_check(&g), NBT_OK, NULL, "surface: theta_s = pi, theta_r = 0");
    g = ok, g.theta_s = nextafter(M_PI, 4);
    expect(nbt_surface_check(&g), NBT_EDOM, "theta_s = 3.14159", "surface: theta_s above pi");
    g = ok, g.theta_r = -0.25;
    expect(nbt_surface_check(&g), NBT_EDOM, "theta_r = -0.25", "surface: theta_r < 0");
    g = ok, g.theta_r = NAN;
    expect(nbt_surface_check(&g), NBT_EDOM, "theta_r = nan", "surface: theta_r NaN");
    g = ok, g.kd = 0, g.ks = 0;
    expect(nbt_surface_check(&g), NBT_OK, NULL, "surface: kd = ks = 0");
    g = ok, g.kd = -0.125;
    expect(nbt_surface_check(&g), NBT_EDOM, "kd = -0.125", "surface: kd < 0");
    g = ok, g.ks = INFINITY;
    expect(nbt_surface_check(&g), NBT_EDOM, "ks = inf", "surface: ks inf");
    g = ok, g.n = 1;
    expect(nbt_surface_check(&g), NBT_OK, NULL, "surface: n = 1");
    g = ok, g.n = 0;
    expect(nbt_surface_check(&g), NBT_EDOM, "n = 0|>= 1", "surface: n = 0");
}

static void test_beam(void)
{
    nbt_beam_medium ok = nbt_beam_homogeneous(1.7, 0.6, 0.02);
    ok.nlobes = 2, ok.w[0] = 0.25, ok.B[0] = 0.02, ok.w[1] = 0.75, ok.B[1] = 0.06;
    nbt_beam_medium m = ok;
    expect(nbt_beam_check(&m), NBT_OK, NULL, "beam: a valid medium");
    m = ok, m.sigma_t = 0;
    expect(nbt_beam_check(&m), NBT_EDOM, "sigma_t = 0|> 0", "beam: sigma_t = 0");
    m = ok, m.sigma_t = INFINITY;
    expect(nbt_beam_check(&m), NBT_EDOM, "sigma_t = inf", "beam: sigma_t inf");
    m = ok, m.albedo = 0;
    expect(nbt_beam_check(&m), NBT_OK, NULL, "beam: albedo 0");
    m = ok, m.albedo = 1;
    expect(nbt_beam_check(&m), NBT_OK, NULL, "beam: albedo 1");
    m = ok, m.albedo = nextafter(1, 2);
    expect(nbt_beam_check(&m), NBT_EDOM, "albedo = 1|[0, 1]", "beam: albedo just above 1");
    m = ok, m.albedo = -1e-3;
    expect(nbt_beam_check(&m), NBT_EDOM, "albedo = -0.001", "beam: albedo < 0");
    /* lobes: 1..16, weights >= 0 summing to 1, spreads > 0; the message names the lobe */
    m = ok, m.nlobes = 0;
    expect(nbt_beam_check(&m), NBT_EDOM, "0 Gaussian lobes|1 to 16", "beam: no lobe");
    m = ok, m.nlobes = NBT_BEAM_MAX_LOBES;
    for (int i = 0; i < NBT_BEAM_MAX_LOBES; i++)
        m.w[i] = 1.0 / 16, m.B[i] = 0.01 * (i + 1);
    expect(nbt_beam_check(&m), NBT_OK, NULL, "beam: 16 lobes");
    m.nlobes = NBT_BEAM_MAX_LOBES + 1;
    expect(nbt_beam_check(&m), NBT_EDOM, "17 Gaussian lobes", "beam: 17 lobes");
    m = ok, m.w[0] = 0, m.w[1] = 1;
    expect(nbt_beam_check(&m), NBT_OK, NULL, "beam: a lobe of weight 0");
    m = ok, m.w[1] = -0.75, m.w[0] = 1.75;
    expect(nbt_beam_check(&m), NBT_EDOM, "lobe 1's weight w = -0.75", "beam: negative weight in lobe 1");
    m = ok, m.B[1] = 0;
    expect(nbt_beam_check(&m), NBT_EDOM, "lobe 1's spread B = 0", "beam: spread 0 in lobe 1");
    m = ok, m.B[0] = NAN;
    expect(nbt_beam_check(&m), NBT_EDOM, "lobe 0's spread B = nan", "beam: spread NaN in lobe 0");
    m = ok, m.w[1] = 0.75 + 5e-13;
    expect(nbt_beam_check(&m), NBT_OK, NULL, "beam: weights off 1 by 5e-13 (round-off)");
    m = ok, m.w[1] = 0.7;
    expect(nbt_beam_check(&m), NBT_EDOM, "summing to 0.95", "beam: weights summing to 0.95");
    /* layers: z[0] = 0, increasing and finite, densities >= 0 and finite */
    const double z[3] = {0, 1.5, 2.25}, rho[3] = {1.5, 0, 0.3};
    m = ok, m.nlayers = 3, m.z = z, m.rho = rho;
    expect(nbt_beam_check(&m), NBT_OK, NULL, "beam: three layers, one empty");
    const double z0[3] = {0.5, 1.5, 2.25}, zdec[3] = {0, 1.5, 1.5}, zinf[3] = {0, 1.5, INFINITY};
    const double rneg[3] = {1.5, 0, -0.3}, rinf[3] = {1.5, INFINITY, 0.3};
    m.z = z0;
    expect(nbt_beam_check(&m), NBT_EDOM, "z[0] = 0.5|must be 0", "beam: layers from z 0.5");
    m.z = zdec;
    expect(nbt_beam_check(&m), NBT_EDOM, "z[2] = 1.5|z[1] = 1.5", "beam: repeated boundary");
    m.z = zinf;
    expect(nbt_beam_check(&m), NBT_EDOM, "z[2] = inf", "beam: infinite boundary");
    m.z = z, m.rho = rneg;
    expect(nbt_beam_check(&m), NBT_EDOM, "layer 2's density rho = -0.3", "beam: negative density in layer 2");
    m.rho = rinf;
    expect(nbt_beam_check(&m), NBT_EDOM, "layer 1's density rho = inf", "beam: infinite density in layer 1");
    m.rho = NULL;
    expect(nbt_beam_check(&m), NBT_EDOM, "rho is NULL", "beam: layers without densities");
}

static void test_screen(void)
{
    /* 3x2, non-square: a bad pixel at (2, 1) is the last one, at (1, 0) the second */
    float rgb[18], D[6] = {1, 2, 3, 4, 5, INFINITY};
    for (int i = 0; i < 18; i++)
        rgb[i] = 0.1f * (float)i;
    nbt_screen_pixkern pix[6];
    for (int i = 0; i < 6; i++)
        pix[i] = (nbt_screen_pixkern){0.5, 0.25, 3.0};
    nbt_screen_input ok = {3, 2, rgb, D, 1e-3, NULL};
    nbt_screen_input in = ok;
    expect(nbt_screen_check(&in), NBT_OK, NULL, "screen: a valid 3x2 input with a sky pixel");
    in = ok, in.h = 0;
    expect(nbt_screen_check(&in), NBT_EINVAL, "empty image|3x0", "screen: 3x0");
    in = ok, in.D = NULL;
    expect(nbt_screen_check(&in), NBT_EINVAL, "no depths", "screen: no depth map");
    in = ok, in.dtheta = 0;
    expect(nbt_screen_check(&in), NBT_EDOM, "dtheta = 0", "screen: dtheta 0");
    in = ok, in.dtheta = INFINITY;
    expect(nbt_screen_check(&in), NBT_EDOM, "dtheta = inf", "screen: dtheta inf");
    D[1] = 0;
    expect(nbt_screen_check(&ok), NBT_OK, NULL, "screen: depth 0 accepted");
    D[1] = -0.5f;
    expect(nbt_screen_check(&ok), NBT_EDOM, "pixel (1, 0)|depth -0.5", "screen: negative depth at (1, 0)");
    D[1] = NAN;
    expect(nbt_screen_check(&ok), NBT_EDOM, "pixel (1, 0)|depth nan", "screen: NaN depth at (1, 0)");
    D[1] = 2;
    rgb[3 * 5 + 2] = INFINITY;
    expect(nbt_screen_check(&ok), NBT_EDOM, "pixel (2, 1)|channel 2 = inf", "screen: inf blue at (2, 1)");
    rgb[3 * 5 + 2] = -1e6f;
    expect(nbt_screen_check(&ok), NBT_OK, NULL, "screen: a negative colour is finite (the operators are linear)");
    rgb[3 * 5 + 2] = 1;
    in = ok, in.pix = pix;
    expect(nbt_screen_check(&in), NBT_OK, NULL, "screen: per-pixel kernels");
    pix[4].T = 1, pix[4].M0 = 0, pix[4].beta_px = 0;
    expect(nbt_screen_check(&in), NBT_OK, NULL, "screen: a kernel at T = 1, M0 = beta = 0");
    pix[4].T = nextafter(1, 2);
    expect(nbt_screen_check(&in), NBT_EDOM, "pixel (1, 1)|T = 1", "screen: T just above 1 at (1, 1)");
    pix[4].T = 0.5, pix[4].beta_px = -2;
    expect(nbt_screen_check(&in), NBT_EDOM, "pixel (1, 1)|beta = -2", "screen: negative beta at (1, 1)");
    pix[4].beta_px = 3, pix[4].M0 = INFINITY;
    expect(nbt_screen_check(&in), NBT_EDOM, "pixel (1, 1)|M0 = inf", "screen: infinite M0 at (1, 1)");
}

/* nbt_screen_path's world: a bad depth or colour is named by its pixel (x, y) */
static void test_screen_path(void)
{
    /* 3x2, non-square: pixel (1, 1) is index 4, (2, 1) index 5 */
    float rgb[18], Z[6] = {1, 2, 3, 4, 5, INFINITY};
    for (int i = 0; i < 18; i++)
        rgb[i] = 0.1f * (float)i;
    nbt_phase *p = nbt_phase_iso();
    nbt_screen_world W = {3, 2, rgb, Z, 0.01, 1.5, 1.0, 0, 0, 3, 2};
    nbt_screen_path_medium m = {{1, 1, 1}, {0.5, 0.5, 0.5}, p, INFINITY, {0, 0, 0}};
    nbt_screen_path_opts o = {.spp = 2, .seed = 1, .nthreads = 1};
    double S[18];
    expect(nbt_screen_path(&W, &m, &o, S, NULL, NULL), NBT_OK, NULL, "screen path: a valid 3x2 world with a sky pixel");
    Z[4] = 0;
    expect(nbt_screen_path(&W, &m, &o, S, NULL, NULL), NBT_EDOM, "depth 0 at pixel (1, 1)", "screen path: depth 0 at (1, 1)");
    Z[4] = 5;
    rgb[3 * 5 + 1] = NAN;
    expect(nbt_screen_path(&W, &m, &o, S, NULL, NULL), NBT_EDOM, "colour nan at pixel (2, 1)",
           "screen path: NaN green at (2, 1)");
    nbt_phase_free(p);
}

/* nbt_grid_check reports in err (the grid API's convention): every size, the voxel
 * and each origin component at its bound, and a bad density at the last voxel of a
 * 3 x 4 x 2 grid and inside it, named by its (i, j, k) */
static void grid_expect(const nbt_grid *g, nbt_status want, const char *words, const char *label)
{
    char err[256] = "";
    nbt_status st = nbt_grid_check(g, err, sizeof err);
    int ok = st == want && (want == NBT_OK || strstr(err, words) != NULL);
    t_true(ok, "grid: %s: status %d (want %d), '%s' (want '%s')", label, st, want, err, want == NBT_OK ? "" : words);
}
static void test_grid(void)
{
    nbt_grid *g = nbt_grid_alloc(3, 4, 2, (const double[3]){-1.5, 0.25, 2.0}, 0.5);
    grid_expect(g, NBT_OK, NULL, "a zero grid 3x4x2");
    nbt_grid b = *g;
    size_t *n[3] = {&b.nx, &b.ny, &b.nz};
    for (int a = 0; a < 3; a++) {
        b = *g;
        *n[a] = 0;
        grid_expect(&b, NBT_EDOM, a == 0 ? "size 0 x 4 x 2, each must be >= 1" : a == 1 ? "size 3 x 0 x 2" : "size 3 x 4 x 0",
                    a == 0 ? "nx = 0" : a == 1 ? "ny = 0" : "nz = 0");
    }
    b = *g;
    b.data = NULL;
    grid_expect(&b, NBT_EDOM, "empty grid: no data", "no data");
    const double voxels[] = {0.0, -0.5, INFINITY, NAN};
    for (int v = 0; v < 4; v++) {
        b = *g;
        b.voxel = voxels[v];
        grid_expect(&b, NBT_EDOM, v == 0 ? "voxel size 0 is not accepted: finite and > 0" : v == 1 ? "voxel size -0.5 is" :
                                  v == 2 ? "voxel size inf is" : "voxel size nan is",
                    v == 0 ? "voxel 0" : v == 1 ? "voxel -0.5" : v == 2 ? "voxel inf" : "voxel nan");
    }
    b = *g;
    b.voxel = 1e-300;
    grid_expect(&b, NBT_OK, NULL, "voxel 1e-300");
    for (int a = 0; a < 3; a++) {
        b = *g;
        b.origin[a] = a == 1 ? INFINITY : NAN;
        grid_expect(&b, NBT_EDOM, a == 0 ? "origin (nan, 0.25, 2) is not accepted: finite" : a == 1 ? "origin (-1.5, inf, 2)" :
                                  "origin (-1.5, 0.25, nan)",
                    a == 0 ? "origin x nan" : a == 1 ? "origin y inf" : "origin z nan");
    }
    g->data[(1 * 4 + 3) * 3 + 2] = -1e-30f; /* the last voxel (2, 3, 1) */
    grid_expect(g, NBT_EDOM, "density -1e-30 at voxel (2, 3, 1)", "a negative density at the last voxel");
    g->data[(1 * 4 + 3) * 3 + 2] = 0.0f;
    g->data[(0 * 4 + 2) * 3 + 1] = NAN; /* (1, 2, 0) */
    grid_expect(g, NBT_EDOM, "at voxel (1, 2, 0)", "NaN at (1, 2, 0)");
    g->data[(0 * 4 + 2) * 3 + 1] = INFINITY;
    grid_expect(g, NBT_EDOM, "density inf at voxel (1, 2, 0)", "inf at (1, 2, 0)");
    g->data[(0 * 4 + 2) * 3 + 1] = FLT_MAX;
    grid_expect(g, NBT_OK, NULL, "the largest finite densities");
    nbt_grid_free(g);
}

int main(void)
{
    nbt_set_error_handler(handler);
    test_airlight();
    test_surface();
    test_beam();
    test_screen();
    test_screen_path();
    test_grid();
    return t_done();
}
