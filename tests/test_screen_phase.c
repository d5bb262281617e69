/* tests/test_screen_phase.c: screen kernels built for a phase function
 * (nbt_screen_kernel_phase), RGB kernels and the fitted model's container,
 * against independent quadrature, photon counts and closed forms. */
#include <config.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include <nbt/nbt.h>
#include <nbt/mc.h>
#include "testutil.h"

/* ---- the first order by direct 2-D quadrature ----
 * A wall at distance D (sigma_t = 1 units: D = tau) of unit radiance seen
 * along its normal; light leaves the wall point at lateral distance r, meets
 * the view ray at depth t after a path (D - t)/cos(th), scatters by th into
 * the camera. Mass within r < rho D:
 *   a int_0^{pi/2} 2 pi sin th p(cos th) int_{t0}^{D} e^{-t} e^{-(D-t)/cos th} dt dth,
 * t0 = max(0, D - rho D cot th). The t integral is done numerically here
 * (the library has it in closed form). */
typedef struct {
    const nbt_phase *p;
    double D, rho, th;
    nbt_quad_ws *ws;
} fo_ctx;

static int fo_t(double t, void *vp, unsigned fdim, double *f)
{
    (void)fdim;
    fo_ctx *c = vp;
    f[0] = exp(-t - (c->D - t) / cos(c->th));
    return 0;
}

static int fo_th(double th, void *vp, unsigned fdim, double *f)
{
    (void)fdim;
    fo_ctx *c = vp;
    c->th = th;
    double t0 = isinf(c->rho) ? 0 : fmax(0.0, c->D - c->rho * c->D / tan(th)), v = 0, e;
    if (t0 < c->D)
        nbt_quad_gk(c->ws, fo_t, c, 1, t0, c->D, 1e-300, 1e-12, &v, &e);
    f[0] = 2.0 * M_PI * sin(th) * nbt_phase_eval(c->p, cos(th)) * v;
    return 0;
}

static double first_ref(const nbt_phase *p, double D, double rho)
{
    fo_ctx c = {p, D, rho, 0, nbt_quad_ws_alloc(1, 2000)};
    nbt_quad_ws *wo = nbt_quad_ws_alloc(1, 2000);
    const double pts[] = {1e-3, 3e-3, 1e-2, 3e-2, 0.1, 0.3, 1.0, 1.4};
    double v, e;
    nbt_quad_gk_pts(wo, fo_th, &c, 1, 0, M_PI / 2, pts, sizeof pts / sizeof pts[0], 1e-300, 1e-10, &v, &e);
    nbt_quad_ws_free(wo);
    nbt_quad_ws_free(c.ws);
    return v;
}

/* a kernel's mass within r < R (world units; R = inf: all of it) */
static double kern_mass(const nbt_screen_kern *k, double R)
{
    double m = 0;
    for (size_t a = 0; a < k->n; a++)
        m += k->mass[a] * (isinf(R) ? 1.0 : nbt_screen_atom_mass(k->shape[a], 0, R / k->scale[a]));
    return m;
}

static void test_first_order(void)
{
    nbt_phase *hg = nbt_phase_hg(0.9), *two = NULL, *iso = nbt_phase_hg(0);
    char err[256];
    nbt_phase_parse("hg2:g1=0.8,g2=-0.3,w=0.7", &two, err, sizeof err);
    const nbt_phase *ps[3] = {hg, two, iso};
    /* sigma_t 0.5 and albedo 0.8 in the kernel: masses scale by the albedo, lengths by sigma_t */
    const double st = 0.5, alb = 0.8;
    /* thin media too: there the oblique legs' attenuation 1 - e^{-tau (sec th - 1)} turns over within
     * ~tau of th = pi/2, which an angle rule must resolve (isotropic: most of the mass is there) */
    const double taus[] = {2.0 /* a node of the shape grid */, 0.7 /* between nodes */, 11.3, 0.003, 0.0214};
    for (int ip = 0; ip < 3; ip++) {
        nbt_screen_kernel *k = nbt_screen_kernel_phase(NBT_SKERNEL_FIRST, st, alb, ps[ip], NBT_SCREEN_INSIDE, NULL);
        t_true(k != NULL, "first-order kernel for %s", nbt_phase_name(ps[ip]));
        if (!k)
            continue;
        for (size_t it = 0; it < sizeof taus / sizeof taus[0]; it++) {
            double tau = taus[it], D = tau / st;
            nbt_screen_kern kn;
            nbt_screen_kernel_eval(k, D, &kn);
            t_rel(kn.T, exp(-tau), 1e-14, "first order %s tau %g: T", nbt_phase_name(ps[ip]), tau);
            double tot = alb * first_ref(ps[ip], tau, INFINITY);
            /* the whole mass is computed exactly (one integral over the angle) */
            t_rel(kern_mass(&kn, INFINITY), tot, 1e-7, "first order %s tau %g: mass", nbt_phase_name(ps[ip]), tau);
            const double rhos[] = {0.01, 0.05, 0.3, 2.0};
            for (size_t ir = 0; ir < sizeof rhos / sizeof rhos[0]; ir++) {
                double want = alb * first_ref(ps[ip], tau, rhos[ir]);
                /* the radial shape: fitted on 1/4-octave radii to ~1e-5 at the depth nodes, and interpolated
                 * linearly in log depth between them (a 2^(1/4) step: up to ~2e-3 of the mass) */
                t_abs(kern_mass(&kn, rhos[ir] * D) / tot, want / tot, it == 0 ? 3e-4 : 3e-3,
                      "first order %s tau %g: mass within %g D", nbt_phase_name(ps[ip]), tau, rhos[ir]);
            }
        }
        nbt_screen_kernel_free(k);
    }
    nbt_phase_free(hg);
    nbt_phase_free(two);
    nbt_phase_free(iso);
}

/* ---- photon counts of the first order agree with it (an independent route: paths, not angles) ---- */
static void test_first_order_mc(void)
{
    nbt_phase *hg = nbt_phase_hg(0.75);
    const double z[] = {1.5}, edges[] = {0.02, 0.1, 0.4}, alb[] = {1.0};
    nbt_mc_kernel_config cfg = {hg, 1, 1, z, 3, edges, 1, alb, 1, 0, 400000, 7, 0, NULL, NULL};
    nbt_mc_kernel_result *r = NULL;
    t_true(nbt_mc_kernel_run(&cfg, &r) == NBT_OK, "mc kernel run");
    nbt_screen_kernel *k = nbt_screen_kernel_phase(NBT_SKERNEL_FIRST, 1.0, 1.0, hg, NBT_SCREEN_INSIDE, NULL);
    nbt_screen_kern kn;
    nbt_screen_kernel_eval(k, 1.5, &kn);
    double lo = 0;
    for (size_t b = 0; r && b < 4; b++) {
        double hi = b < 3 ? edges[b] * 1.5 : INFINITY;
        double want = kern_mass(&kn, hi) - kern_mass(&kn, lo), got = r->mass[b], se = r->mass_se[b];
        /* 4.5 standard errors plus the shape's interpolation (tau 1.5 is between nodes) */
        t_abs(got, want, 4.5 * se + 2e-3 * kern_mass(&kn, INFINITY),
              "first order vs photon counts, hg 0.75 tau 1.5, bin %zu (se %.2g)", b, se);
        lo = hi;
    }
    nbt_mc_kernel_result_free(r);
    nbt_screen_kernel_free(k);
    nbt_phase_free(hg);
}

/* ---- pixel weights: the operator on one bright pixel is the kernel integrated over pixels ---- */
static void test_far_weights(void)
{
    const size_t w = 91, h = 57, sx = 23, sy = 31;
    float *rgb = calloc(w * h * 3, sizeof *rgb), *D = malloc(w * h * sizeof *D);
    double *S = malloc(w * h * 3 * sizeof *S);
    for (size_t i = 0; i < w * h; i++)
        D[i] = 40.0f;
    rgb[(sy * w + sx) * 3 + 1] = 1000.0f;
    nbt_phase *hg = nbt_phase_hg(0.8);
    /* tau 1 and a wide pixel angle: the kernel's core spans a few pixels, its tail many */
    nbt_screen_kernel *k = nbt_screen_kernel_phase(NBT_SKERNEL_FIRST, 0.025, 0.9, hg, NBT_SCREEN_INSIDE, NULL);
    double dtheta = 0.004;
    nbt_screen_input in = {w, h, rgb, D, dtheta, NULL};
    t_true(nbt_screen_brute(&in, k, NBT_SCREEN_NEAR, 1e-9, 1, S, NULL) == NBT_OK, "brute force, one source");
    nbt_screen_kern kn;
    nbt_screen_kernel_eval(k, 40.0, &kn);
    double px = 40.0 * dtheta;
    const long off[][2] = {{0, 0}, {3, -2}, {-7, 11}, {25, 9}, {-20, -28}, {60, 20}, {-23, 25}};
    for (size_t j = 0; j < sizeof off / sizeof off[0]; j++) {
        double want = 0;
        for (size_t a = 0; a < kn.n; a++)
            want += kn.mass[a] * nbt_screen_atom_pixel(kn.shape[a], kn.scale[a] / px, off[j][0], off[j][1]);
        size_t x = (size_t)((long)sx + off[j][0]), y = (size_t)((long)sy + off[j][1]);
        /* within 24 px the weights are exact sums; beyond, a radial profile with its Laplacian correction
         * (error ~ f''''/1920 relative, < 1e-4 for kernels smooth on the pixel scale) */
        t_rel(S[(y * w + x) * 3 + 1], 1000.0 * want, 2e-4, "weight at offset (%ld, %ld)", off[j][0], off[j][1]);
        t_abs(S[(y * w + x) * 3], 0, 0, "red stays dark at (%ld, %ld)", off[j][0], off[j][1]);
    }
    nbt_screen_kernel_free(k);
    nbt_phase_free(hg);
    free(rgb);
    free(D);
    free(S);
}

/* ---- an RGB kernel is three grey runs, channel by channel ---- */
static void test_rgb(void)
{
    const size_t w = 48, h = 37;
    float *rgb = malloc(w * h * 3 * sizeof *rgb), *D = malloc(w * h * sizeof *D);
    for (size_t y = 0; y < h; y++)
        for (size_t x = 0; x < w; x++) {
            size_t i = y * w + x;
            D[i] = x < 20 ? 3.0f : y < 15 ? 7.5f : INFINITY;
            for (int c = 0; c < 3; c++)
                rgb[3 * i + (size_t)c] = (float)(0.2 + 0.1 * c + ((x * 7 + y * 3 + (size_t)c) % 5) * 0.3);
        }
    nbt_phase *hg = nbt_phase_hg(0.85);
    const double st[3] = {0.3, 0.2, 0.1}, alb[3] = {0.9, 0.95, 0.99};
    nbt_screen_kernel *kc[3];
    for (int c = 0; c < 3; c++)
        kc[c] = nbt_screen_kernel_phase(NBT_SKERNEL_FIRST, st[c], alb[c], hg, NBT_SCREEN_INSIDE, NULL);
    nbt_screen_kernel *k = nbt_screen_kernel_rgb(kc[0], kc[1], kc[2]);
    t_true(k && nbt_screen_kernel_channels(k) == 3, "rgb kernel has three channels");
    nbt_screen_input in = {w, h, rgb, D, 0.01, NULL};
    double *S = malloc(w * h * 3 * sizeof *S), *Sc = malloc(w * h * 3 * sizeof *Sc);
    t_true(nbt_screen_layered(&in, k, NBT_SCREEN_NEAR, 1e-8, 8, 1, S, NULL) == NBT_OK, "rgb layered");
    for (int c = 0; c < 3; c++) {
        nbt_screen_kernel *g = nbt_screen_kernel_phase(NBT_SKERNEL_FIRST, st[c], alb[c], hg, NBT_SCREEN_INSIDE, NULL);
        nbt_screen_layered(&in, g, NBT_SCREEN_NEAR, 1e-8, 8, 1, Sc, NULL);
        double d = 0, n = 0;
        for (size_t i = 0; i < w * h; i++) {
            d = fmax(d, fabs(S[3 * i + (size_t)c] - Sc[3 * i + (size_t)c]));
            n = fmax(n, fabs(Sc[3 * i + (size_t)c]));
        }
        t_abs(d / n, 0, 1e-12, "rgb channel %d equals its grey run", c);
        nbt_screen_kernel_free(g);
    }
    /* brute force agrees with the FFT channel by channel */
    t_true(nbt_screen_brute(&in, k, NBT_SCREEN_NEAR, 1e-8, 1, Sc, NULL) == NBT_OK, "rgb brute force");
    double d = 0, n = 0;
    for (size_t i = 0; i < w * h * 3; i++) {
        d = fmax(d, fabs(S[i] - Sc[i]));
        n = fmax(n, fabs(Sc[i]));
    }
    t_abs(d / n, 0, 1e-9, "rgb brute force = layered FFT");
    nbt_screen_kernel_free(k);
    nbt_phase_free(hg);
    free(rgb);
    free(D);
    free(S);
    free(Sc);
}

/* ---- the model container: set, write, read, evaluate ---- */
static void test_model(void)
{
    const double g[] = {0.5, 0.9}, alb[] = {0.6, 0.95}, tau[] = {0.5, 4.0};
    nbt_screen_model *m = nbt_screen_model_alloc(NULL, 2, g, 2, alb, 2, tau);
    t_true(m != NULL, "model alloc");
    for (int geo = 0; geo < 2; geo++)
        for (size_t ip = 0; ip < 2; ip++)
            for (size_t ia = 0; ia < 2; ia++)
                for (size_t it = 0; it < 2; it++) {
                    nbt_screen_shape s;
                    memset(&s, 0, sizeof s);
                    double M = 0.01 * (1 + (double)ip) * (1 + 3 * (double)ia) * (1 + 7 * (double)it) * (1 + geo);
                    s.erfc[10 + ip + 2 * it] = 0.75 * M; /* where the mass lies depends on g and tau */
                    s.gauss[20 + ia] = 0.25 * M;
                    nbt_screen_model_set(m, (nbt_screen_geometry)geo, ip, ia, it, &s);
                }
    char path[] = "/tmp/nbt_test_modelXXXXXX";
    int fd = mkstemp(path);
    close(fd);
    char err[256];
    t_true(nbt_screen_model_write(m, path, "test", err, sizeof err) == NBT_OK, "model write");
    nbt_screen_model *r = NULL;
    t_true(nbt_screen_model_read(path, &r, err, sizeof err) == NBT_OK, "model read: %s", err);
    unlink(path);
    nbt_phase *p9 = nbt_phase_hg(0.9), *p7 = nbt_phase_hg(0.7), *p97 = nbt_phase_hg(0.97), *pn = nbt_phase_hg(-0.2);
    t_true(r && nbt_screen_model_covers(r, p7, NBT_SCREEN_INSIDE, err, sizeof err) == NBT_OK, "covers g 0.7");
    t_true(r && nbt_screen_model_covers(r, p97, NBT_SCREEN_INSIDE, err, sizeof err) == NBT_EDOM,
           "refuses g 0.97 above its range");
    t_true(r && nbt_screen_model_covers(r, pn, NBT_SCREEN_INSIDE, err, sizeof err) == NBT_EDOM,
           "refuses g -0.2 below its range");
    if (r) {
        nbt_screen_shape o;
        int ex = -1;
        /* at a node: the set values (the text form keeps 3 digits) */
        nbt_screen_model_eval(r, p9, NBT_SCREEN_ENTERING, 0.6, 4.0, &o, &ex);
        double M = 0.01 * 2 * 1 * 8 * 2;
        t_rel(o.erfc[10 + 1 + 2], 0.75 * M, 2e-3, "model at a node: erfc slot");
        t_rel(o.gauss[20], 0.25 * M, 2e-3, "model at a node: gauss slot");
        t_true(ex == 0, "model at a node is not an extrapolation");
        /* between albedo nodes: log mass linear in -ln(1 - a) */
        double a = 1 - sqrt(0.4 * 0.05), Mm = sqrt(0.01 * 1 * 1 * 1 * 0.01 * 1 * 4 * 1); /* g 0.5, tau 0.5, inside */
        nbt_phase *p5 = nbt_phase_hg(0.5);
        nbt_screen_model_eval(r, p5, NBT_SCREEN_INSIDE, a, 0.5, &o, &ex);
        double tot = 0;
        for (int s = 0; s < NBT_SCREEN_NSLOTS; s++)
            tot += o.erfc[s] + o.gauss[s];
        t_rel(tot, Mm, 3e-3, "model between albedo nodes: geometric mean of the masses");
        t_rel(o.gauss[20] + o.gauss[21], 0.25 * Mm, 3e-3, "model between albedo nodes: shape kept");
        nbt_phase_free(p5);
    }
    nbt_screen_model_free(r);
    nbt_screen_model_free(m);
    nbt_phase_free(p9);
    nbt_phase_free(p7);
    nbt_phase_free(p97);
    nbt_phase_free(pn);
}

/* ---- between nodes the log mass is cubic in -ln(1 - albedo) and ln(tau): exact for cubic data ---- */
static double cubic_logm(double a, double tau)
{
    double x = -log1p(-a), y = log(tau);
    return -1.0 + 0.3 * x - 0.05 * x * x + 0.004 * x * x * x + 0.5 * y - 0.08 * y * y + 0.01 * y * y * y;
}

/* every node of both geometries of a one-g model: one erfc atom (slot 12) of
 * mass exp(logm(albedo, tau)) */
static void fill_one_atom(nbt_screen_model *m, const double *alb, size_t na, const double *tau, size_t nt,
                          double (*logm)(double, double))
{
    for (int geo = 0; m && geo < 2; geo++)
        for (size_t ia = 0; ia < na; ia++)
            for (size_t it = 0; it < nt; it++) {
                nbt_screen_shape s;
                memset(&s, 0, sizeof s);
                s.erfc[12] = exp(logm(alb[ia], tau[it]));
                nbt_screen_model_set(m, (nbt_screen_geometry)geo, 0, ia, it, &s);
            }
}

static void test_model_cubic(void)
{
    const double g[] = {0.9}, alb[] = {0.5, 0.8, 0.95, 0.99, 0.999}, tau[] = {0.25, 1.0, 4.0, 16.0};
    nbt_screen_model *m = nbt_screen_model_alloc(NULL, 1, g, 5, alb, 4, tau);
    fill_one_atom(m, alb, 5, tau, 4, cubic_logm);
    nbt_phase *p = nbt_phase_hg(0.9);
    /* asymmetric points: an inner interval (cubic on four nodes) and an end interval (quadratic on three) */
    const double pts[][2] = {{0.9, 2.5}, {0.97, 0.4}, {0.6, 9.0}, {0.995, 11.0}};
    for (size_t j = 0; j < sizeof pts / sizeof pts[0]; j++) {
        nbt_screen_shape o;
        nbt_screen_model_eval(m, p, NBT_SCREEN_INSIDE, pts[j][0], pts[j][1], &o, NULL);
        double x = -log1p(-pts[j][0]), y = log(pts[j][1]);
        int inner_a = x > -log1p(-0.8) && x < -log1p(-0.99), inner_t = y > 0 && y < log(4.0);
        /* cubic data: exact where four nodes serve both axes; a quadratic at an end interval misses the
         * cubic term by up to 0.004 |(x - x0)(x - x1)(x - x2)| ~ 1e-3 in the log */
        t_rel(nbt_screen_shape_mass(&o, 0, INFINITY), exp(cubic_logm(pts[j][0], pts[j][1])),
              inner_a && inner_t ? 1e-12 : 2e-2, "model: log mass cubic at albedo %g, tau %g", pts[j][0], pts[j][1]);
    }
    nbt_phase_free(p);
    nbt_screen_model_free(m);
}

/* ---- three nodes on an axis: the log mass quadratic through them (exact for quadratic data; the
 * documented rule is linear only on two nodes) ---- */
static double quad_logm(double a, double tau)
{
    double x = -log1p(-a), y = log(tau);
    return -1.0 + 0.3 * x - 0.07 * x * x + 0.5 * y - 0.09 * y * y;
}

static void test_model_three_nodes(void)
{
    const double g[] = {0.9}, alb[] = {0.5, 0.8, 0.95}, tau[] = {0.25, 1.0, 4.0};
    nbt_screen_model *m = nbt_screen_model_alloc(NULL, 1, g, 3, alb, 3, tau);
    fill_one_atom(m, alb, 3, tau, 3, quad_logm);
    nbt_phase *p = nbt_phase_hg(0.9);
    /* asymmetric points in both intervals of each axis; linear there would miss by
     * 0.07 (x - x0)(x1 - x) + 0.09 (y - y0)(y1 - y), ~5e-2 in the log at the first point */
    const double pts[][2] = {{0.7, 0.4}, {0.9, 2.5}};
    for (size_t j = 0; m && j < 2; j++) {
        nbt_screen_shape o;
        nbt_screen_model_eval(m, p, NBT_SCREEN_ENTERING, pts[j][0], pts[j][1], &o, NULL);
        t_rel(nbt_screen_shape_mass(&o, 0, INFINITY), exp(quad_logm(pts[j][0], pts[j][1])), 1e-12,
              "model on 3 x 3 nodes: log mass quadratic at albedo %g, tau %g", pts[j][0], pts[j][1]);
    }
    t_true(m != NULL, "a 3 x 3 model allocated");
    nbt_phase_free(p);
    nbt_screen_model_free(m);
}

/* ---- beyond the deepest depth the log mass goes on along its slope between
 * the last two depths: data with the same log mass ln 0.02 - 0.3 tau at every
 * (g, albedo) node continue exactly as 0.02 e^{-0.3 tau}, at a point between
 * nodes on both other axes (where all four corners' slopes have weight) ---- */
static void test_model_deep(void)
{
    const double g[] = {0.5, 0.9}, alb[] = {0.6, 0.95}, tau[] = {1.0, 3.0};
    nbt_screen_model *m = nbt_screen_model_alloc(NULL, 2, g, 2, alb, 2, tau);
    for (int geo = 0; m && geo < 2; geo++)
        for (size_t ip = 0; ip < 2; ip++)
            for (size_t ia = 0; ia < 2; ia++)
                for (size_t it = 0; it < 2; it++) {
                    nbt_screen_shape s;
                    memset(&s, 0, sizeof s);
                    s.erfc[12] = 0.02 * exp(-0.3 * tau[it]);
                    nbt_screen_model_set(m, (nbt_screen_geometry)geo, ip, ia, it, &s);
                }
    nbt_phase *p = nbt_phase_hg(0.7);
    nbt_screen_shape o;
    int ex = 0;
    t_true(m && nbt_screen_model_eval(m, p, NBT_SCREEN_INSIDE, 0.8, 7.5, &o, &ex) == NBT_OK, "model eval at tau 7.5");
    /* 1e-12: exact arithmetic on exact data; one corner's slope missing is 20% */
    t_rel(nbt_screen_shape_mass(&o, 0, INFINITY), 0.02 * exp(-0.3 * 7.5), 1e-12,
          "model beyond its deepest depth (g 0.7, albedo 0.8, tau 7.5 > 3): the slope of all four corners");
    t_true(ex != 0, "tau 7.5 beyond the grid is flagged an extrapolation (%d)", ex);
    nbt_phase_free(p);
    nbt_screen_model_free(m);
}

/* ---- the shipped model covers HG 0..0.95; the fitted kernel adds it to the exact first order ---- */
static void test_fitted(void)
{
    const nbt_screen_model *m = nbt_screen_model_default();
    t_true(m != NULL, "the shipped model is compiled in");
    if (!m)
        return;
    nbt_phase *p = nbt_phase_hg(0.9);
    nbt_screen_kernel *kf = nbt_screen_kernel_phase(NBT_SKERNEL_FITTED, 0.2, 0.95, p, NBT_SCREEN_INSIDE, NULL),
                      *k1 = nbt_screen_kernel_phase(NBT_SKERNEL_FIRST, 0.2, 0.95, p, NBT_SCREEN_INSIDE, NULL),
                      *ke = nbt_screen_kernel_phase(NBT_SKERNEL_ELEK, 0.2, 0.95, p, NBT_SCREEN_INSIDE, NULL);
    nbt_screen_kern a, b, e;
    nbt_screen_kernel_eval(kf, 10.0, &a);
    nbt_screen_kernel_eval(k1, 10.0, &b);
    nbt_screen_kernel_eval(ke, 10.0, &e);
    nbt_screen_shape hi;
    nbt_screen_model_eval(m, p, NBT_SCREEN_INSIDE, 0.95, 2.0, &hi, NULL);
    double mh = nbt_screen_shape_mass(&hi, 0, INFINITY);
    t_rel(kern_mass(&a, INFINITY), kern_mass(&b, INFINITY) + mh, 1e-12, "fitted = first order + model");
    t_true(mh > 0.2 * kern_mass(&b, INFINITY), "higher orders matter at albedo 0.95, tau 2 (%g vs %g)", mh,
           kern_mass(&b, INFINITY));
    /* elek: one Gaussian of the fitted mass, 1/(2 W^2) = 2 sa/(3 D) + 4/(D^3 ss (1 - g)) (Elek et al.) */
    t_true(e.n == 1 && e.shape[0] == NBT_ATOM_GAUSS, "elek kernel: one Gaussian");
    t_rel(e.mass[0], kern_mass(&a, INFINITY), 1e-12, "elek kernel carries the fitted mass");
    double inv = 2.0 * 0.2 * 0.05 / (3.0 * 10.0) + 4.0 / (1000.0 * 0.19 * 0.1);
    t_rel(e.scale[0], sqrt(0.5 / inv), 1e-12, "elek width from the phase's mean cosine");
    nbt_phase *out = nbt_phase_hg(0.97);
    nbt_set_error_handler(NULL);
    t_true(nbt_screen_kernel_phase(NBT_SKERNEL_FITTED, 0.2, 0.95, out, NBT_SCREEN_INSIDE, NULL) == NULL,
           "fitted refuses g 0.97, outside the shipped model");
    nbt_screen_kernel_free(kf);
    nbt_screen_kernel_free(k1);
    nbt_screen_kernel_free(ke);
    nbt_phase_free(p);
    nbt_phase_free(out);
}

/* ---- one set of paths serves every albedo: the counts at albedo a are
 * those of a run at a alone (same seed, bit for bit), and a path scattered
 * once weighs a, so first-order masses scale exactly by a (a random mutant
 * reading another albedo's row of weights survived the one-albedo tests) ---- */
static void test_mc_albedos(void)
{
    nbt_phase *hg = nbt_phase_hg(0.6);
    const double z[] = {0.7, 2.0}, edges[] = {0.1, 0.5}, alb2[] = {1.0, 0.6, 0.35}, alb1[] = {0.6};
    nbt_mc_kernel_config cfg = {hg, 1, 2, z, 2, edges, 3, alb2, 60, 0, 20000, 11, 2, NULL, NULL};
    nbt_mc_kernel_result *r3 = NULL, *r1 = NULL;
    t_true(nbt_mc_kernel_run(&cfg, &r3) == NBT_OK, "mc kernel run, three albedos");
    cfg.nalbedo = 1, cfg.albedo = alb1;
    t_true(nbt_mc_kernel_run(&cfg, &r1) == NBT_OK, "mc kernel run, albedo 0.6 alone");
    if (r3 && r1) {
        size_t nb = r3->nbins, same = 1;
        double worst = 0, worst_se = 0, worst_b = 0, N = 20000;
        for (size_t j = 0; j < 2; j++)
            for (size_t o = 0; o < 2; o++)
                for (size_t b = 0; b < nb; b++) {
                    same &= r3->mass[((j * 3 + 1) * 2 + o) * nb + b] == r1->mass[((j * 1 + 0) * 2 + o) * nb + b];
                    for (size_t k = 1; o == 0 && k < 3; k++) {
                        double m1 = r3->mass[((j * 3 + 0) * 2 + 0) * nb + b], mk = r3->mass[((j * 3 + k) * 2 + 0) * nb + b];
                        worst = fmax(worst, fabs(mk - alb2[k] * m1) / fmax(m1, 1e-300));
                        /* each photon's first-order tally at albedo a is a times its tally at albedo 1,
                         * so the standard error scales by a too */
                        double s1 = r3->mass_se[((j * 3 + 0) * 2 + 0) * nb + b], sk = r3->mass_se[((j * 3 + k) * 2 + 0) * nb + b];
                        worst_se = fmax(worst_se, fabs(sk - alb2[k] * s1) / fmax(s1, 1e-300));
                    }
                    if (o == 0) { /* at albedo 1 a photon adds 0 or 1 to a first-order cell: Bernoulli */
                        double m1 = r3->mass[((j * 3 + 0) * 2 + 0) * nb + b], s1 = r3->mass_se[((j * 3 + 0) * 2 + 0) * nb + b];
                        worst_b = fmax(worst_b, fabs(s1 - sqrt(m1 * (1 - m1) / (N - 1))) / fmax(s1, 1e-300));
                    }
                }
        t_true(same, "albedo 0.6 among three = albedo 0.6 alone, bit for bit (same seed and order cap)");
        t_true(worst < 1e-12, "first order at albedo a = a x first order at albedo 1 (worst %.2g)", worst);
        /* rounding of 20000-term sums: ~1e-12 relative in a variance, the SE's square root halves it */
        t_true(worst_se < 1e-9, "first-order standard error at albedo a = a x at albedo 1 (worst %.2g)", worst_se);
        t_true(worst_b < 1e-9, "first-order standard error at albedo 1 = sqrt(m (1 - m) / (N - 1)) (worst %.2g)",
               worst_b);
    }
    nbt_mc_kernel_result_free(r3);
    nbt_mc_kernel_result_free(r1);
    nbt_phase_free(hg);
}

/* ---- the weight of paths cut at order_max, per photon (nbt_mc_kernel_result.lost):
 * one plane at depth 60 in an infinite medium and a cap of 3 scatterings. No path
 * can end before its 3rd scattering: reaching the plane (or -z_cut = -140) takes
 * four unit-mean flights summing to ~60, P ~ e^-60 60^3/3! ~ 3e-22, so with 4096
 * photons every path is cut and lost = albedo^3 exactly (N equal terms summed:
 * rounding ~1e-13 relative). A random mutant that multiplied by the photon count
 * instead of dividing survived: nothing else reads this field ---- */
static void test_mc_lost(void)
{
    nbt_phase *hg = nbt_phase_hg(0.6);
    const double z[] = {60.0}, edges[] = {0.1, 0.5}, alb[] = {1.0, 0.6, 0.35};
    nbt_mc_kernel_config cfg = {hg, 1, 1, z, 2, edges, 3, alb, 3, 0, 4096, 7, 2, NULL, NULL};
    nbt_mc_kernel_result *r = NULL;
    t_true(nbt_mc_kernel_run(&cfg, &r) == NBT_OK && r && r->lost, "mc kernel run, order cap 3, plane at 60");
    for (size_t k = 0; r && r->lost && k < 3; k++)
        t_rel(r->lost[k], alb[k] * alb[k] * alb[k], 1e-12, "lost weight per photon at albedo %g = albedo^3", alb[k]);
    nbt_mc_kernel_result_free(r);
    nbt_phase_free(hg);
}

int main(void)
{
    test_first_order();
    test_first_order_mc();
    test_mc_albedos();
    test_mc_lost();
    test_far_weights();
    test_rgb();
    test_model();
    test_model_cubic();
    test_model_three_nodes();
    test_model_deep();
    test_fitted();
    return t_done();
}
