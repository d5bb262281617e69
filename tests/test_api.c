/* tests/test_api.c: public functions no other test calls directly, each at
 * asymmetric arguments against an independent closed form: the camera ray
 * of a pixel (non-square image, non-unit and non-orthogonal fwd/up, every
 * corner), the box of a density grid (unequal sizes, an off-centre origin),
 * the two-term HG phase (values at both signs of mu, odd moments, the mean
 * cosine), the direct beam through a layered medium, a zero-width screen
 * atom, status messages and the version. */
#include <config.h>
#include <math.h>
#include <string.h>
#include <nbt/nbt.h>
#include <nbt/grid.h>
#include "internal.h" /* the G-row store */
#include "gslice_tail.h" /* the tail form's error map */
#include "testutil.h"

/* The documented camera: the image plane at unit distance along fwd,
 * pixel pitch dtheta, centred; x to the right (fwd x up), row 0 at the top
 * (towards up). Here fwd = -2 z (not unit) and up = 3 y + 0.5 z (not
 * orthogonal to fwd): right = +x, the true up = +y, so the ray of pixel
 * (x, y) is (u, -v, -1) normalised, u, v the pixel centre's offsets. */
static void test_camera_ray(void)
{
    const nbt_camera cam = {{1, 2, 3}, {0, 0, -2}, {0, 3, 0.5}};
    const size_t w = 7, h = 4;
    const double dth = 0.1;
    const size_t px[5][2] = {{0, 0}, {6, 0}, {0, 3}, {6, 3}, {2, 1}};
    double worst = 0;
    for (int k = 0; k < 5; k++) {
        size_t x = px[k][0], y = px[k][1];
        double u = ((double)x + 0.5 - 3.5) * dth, v = ((double)y + 0.5 - 2.0) * dth;
        double n = sqrt(1 + u * u + v * v), want[3] = {u / n, -v / n, -1 / n}, d[3];
        nbt_camera_ray(&cam, w, h, dth, x, y, d);
        for (int i = 0; i < 3; i++)
            worst = fmax(worst, fabs(d[i] - want[i]));
        /* the planar depth Z along fwd is Z / cos of the angle to the axis: */
        double Z = 4.5, D = nbt_screen_ray_distance(Z, w, h, dth, x, y);
        t_rel(D, Z / -d[2], 1e-14, "pixel (%zu, %zu): ray distance Z / cos = %.15g", x, y, Z / -d[2]);
    }
    t_true(worst < 1e-15, "camera rays of the corners of a 7x4 image match (u, -v, -1)/n: worst %.2g", worst);
    /* the top-left ray looks left and up; the bottom-right one right and down */
    double a[3], b[3];
    nbt_camera_ray(&cam, w, h, dth, 0, 0, a);
    nbt_camera_ray(&cam, w, h, dth, w - 1, h - 1, b);
    t_true(a[0] < 0 && a[1] > 0 && b[0] > 0 && b[1] < 0, "row 0 is towards up, column 0 to the left");
}

/* lo = origin - voxel/2, hi = lo + n voxel, per axis */
static void test_grid_box(void)
{
    const double o[3] = {1.0, -2.0, 0.5};
    nbt_grid *g = nbt_grid_alloc(3, 5, 2, o, 0.25);
    t_true(g != NULL, "grid 3x5x2");
    if (!g)
        return;
    double lo[3], hi[3];
    nbt_grid_box(g, lo, hi);
    const double wlo[3] = {0.875, -2.125, 0.375}, whi[3] = {1.625, -0.875, 0.875};
    int ok = 1;
    for (int i = 0; i < 3; i++)
        ok &= fabs(lo[i] - wlo[i]) < 1e-15 && fabs(hi[i] - whi[i]) < 1e-15;
    t_true(ok, "grid box [%g %g %g] .. [%g %g %g]", lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]);
    nbt_grid_free(g);
}

static double hg(double g, double mu)
{
    return (1 - g * g) / (4 * M_PI * pow(1 + g * g - 2 * g * mu, 1.5));
}

/* w HG(g1) + (1 - w) HG(g2): values, b_k = w g1^k + (1 - w) g2^k */
static void test_hg2(void)
{
    const double g1 = 0.8, g2 = -0.3, w = 0.7;
    nbt_phase *p = nbt_phase_hg2(g1, g2, w);
    t_true(p && nbt_phase_get_kind(p) == NBT_PHASE_HG2, "hg2 kind");
    if (!p)
        return;
    const double mus[5] = {-1, -0.5, 0.1, 0.5, 0.99};
    for (int i = 0; i < 5; i++)
        t_rel(nbt_phase_eval(p, mus[i]), w * hg(g1, mus[i]) + (1 - w) * hg(g2, mus[i]), 1e-13, "hg2 at mu = %g",
              mus[i]);
    double b[8];
    t_true(nbt_phase_moments(p, 7, b) == NBT_OK, "hg2 moments");
    for (int k = 0; k <= 7; k += 1)
        t_rel(b[k], w * pow(g1, k) + (1 - w) * pow(g2, k), 1e-12, "hg2 b_%d", k);
    t_rel(nbt_phase_mean_cosine(p), w * g1 + (1 - w) * g2, 1e-12, "hg2 mean cosine");
    nbt_phase_free(p);
    t_true(nbt_phase_hg2(1.0, 0, 0.5) == NULL && nbt_phase_hg2(0.5, 0, 1.5) == NULL, "hg2: g = 1 or w > 1 refused");
}

/* exp(-sigma_t zeta(z)), zeta through two layers of unequal density */
static void test_beam_direct(void)
{
    nbt_beam_medium m = nbt_beam_homogeneous(0.3, 0.9, 0.01);
    t_rel(nbt_beam_direct(&m, 2.5), exp(-0.75), 1e-14, "direct beam, homogeneous");
    const double z[2] = {0, 1.5}, rho[2] = {0.4, 2.0};
    m.nlayers = 2, m.z = z, m.rho = rho;
    t_rel(nbt_beam_direct(&m, 1.0), exp(-0.3 * 0.4), 1e-14, "direct beam in the first layer");
    t_rel(nbt_beam_direct(&m, 2.5), exp(-0.3 * (0.4 * 1.5 + 2.0 * 1.0)), 1e-14, "direct beam past the interface");
}

/* an atom of zero width is a delta: all its mass in its own pixel, for
 * both shapes (a random mutant inverting that survived: no test reached
 * the zero-width branch); a width of 0.05 px leaves erf(10/sqrt 2)^2 */
static void test_atom_zero_width(void)
{
    for (int s = 0; s < 2; s++) {
        nbt_atom_shape sh = s ? NBT_ATOM_GAUSS : NBT_ATOM_ERFC;
        double c = nbt_screen_atom_pixel(sh, 0, 0, 0), e = nbt_screen_atom_pixel(sh, 0, 1, 0),
               d = nbt_screen_atom_pixel(sh, 0, -1, 2);
        t_true(c == 1 && e == 0 && d == 0, "%s atom of width 0: 1 in its pixel (%g), 0 beside it (%g, %g)",
               s ? "Gaussian" : "erfc", c, e, d);
    }
    t_rel(nbt_screen_atom_pixel(NBT_ATOM_GAUSS, 0.05, 0, 0), pow(erf(10 / sqrt(2.0)), 2), 1e-14,
          "Gaussian atom of width 0.05 px: its pixel holds erf(10/sqrt 2)^2");
}

/* libnbt's NNLS (internal.h, exported for the tests): a problem whose first
 * column is already along e1, where a Householder reflection with the
 * wrong sign divides by zero (a random mutant of that sign survived the
 * kernel fits, whose columns never are); and an active bound */
static void test_nnls(void)
{
    const double A[3 * 2] = {2, 0, 0, 3, 0, 0}, b[3] = {4, 6, 1};
    double x[2], r;
    nbt_status st = nbt__nnls(A, 3, 2, b, x, &r);
    t_true(st == NBT_OK && fabs(x[0] - 2) < 1e-15 && fabs(x[1] - 2) < 1e-15 && fabs(r - 1) < 1e-15,
           "nnls, columns along e1 and e2: x = (2, 2), residual 1: (%g, %g), %g", x[0], x[1], r);
    const double b2[3] = {4, -6, 1}; /* the second unknown wants -2: held at 0 */
    st = nbt__nnls(A, 3, 2, b2, x, &r);
    t_true(st == NBT_OK && fabs(x[0] - 2) < 1e-15 && x[1] == 0 && fabs(r - sqrt(37.0)) < 1e-14,
           "nnls with an active bound: x = (2, 0), residual sqrt 37: (%g, %g), %g", x[0], x[1], r);
}

/* libnbt's phase sampler (internal.h, exported for the tests) at the ends of
 * its uniform draw: the HG inverse CDF maps u = 0 to mu = -1 exactly (the
 * cosine of a photon sent straight back). In doubles, g = 0.3 and 0.99 round
 * to just below -1 there and must be clamped to -1, not to +1 (u = 0 is one
 * draw in 2^53 of the generator: rare, but a photon turned the wrong way) */
static double draw_fixed(void *vp)
{
    return *(const double *)vp;
}

static void test_sample_ends(void)
{
    const double gs[] = {0.3, 0.99, -0.5};
    for (int i = 0; i < 3; i++) {
        nbt_phase *p = nbt_phase_hg(gs[i]);
        double u0 = 0, u1 = 1 - 0x1p-53;
        double lo = nbt__phase_sample_mu(p, draw_fixed, &u0), hi = nbt__phase_sample_mu(p, draw_fixed, &u1);
        /* u = 1 - 2^-53: mu within 2^-53 / q(1) of 1, q the sampled density in mu (>= 0.11 here) */
        t_true(lo == -1.0 && fabs(hi - 1.0) < 1e-12, "HG g = %g sampled at u = 0: mu = %.17g (want -1), at u -> 1: %.17g",
               gs[i], lo, hi);
        nbt_phase_free(p);
    }
    /* Rayleigh by Cardano: the sampled mu inverts the CDF (mu^3 + 3 mu + 4)/8 at asymmetric draws */
    nbt_phase *r = nbt_phase_rayleigh();
    double worst = 0;
    for (int i = 0; i < 5; i++) {
        double u = (double[]){0.01, 0.3, 0.5, 0.77, 0.999}[i], mu = nbt__phase_sample_mu(r, draw_fixed, &u);
        worst = fmax(worst, fabs((mu * mu * mu + 3.0 * mu + 4.0) / 8.0 - u));
    }
    t_true(worst < 1e-12, "Rayleigh sampled mu: CDF(mu) = u at u = 0.01 .. 0.999 (worst %.2g)", worst);
    nbt_phase_free(r);
    /* a coarse tabulated phase (3 nodes, both segments sloped, unequal widths): the sampled mu inverts
     * the CDF A(mu)/A(1), A the integral of the piecewise-linear p from -1 (trapezoids, done here) */
    const double tm[3] = {-1, 0.2, 1}, tp[3] = {0.1, 0.3, 1.5};
    nbt_phase *tb = nbt_phase_tabulated(3, tm, tp);
    double A1 = 0.5 * (tp[0] + tp[1]) * (tm[1] - tm[0]) + 0.5 * (tp[1] + tp[2]) * (tm[2] - tm[1]);
    worst = 0;
    for (int i = 0; tb && i < 5; i++) {
        double u = (double[]){0.01, 0.2, 0.5, 0.77, 0.999}[i], mu = nbt__phase_sample_mu(tb, draw_fixed, &u), A = 0;
        for (int s = 0; s < 2; s++) {
            double b = fmin(fmax(mu, tm[s]), tm[s + 1]), pb = tp[s] + (tp[s + 1] - tp[s]) * (b - tm[s]) / (tm[s + 1] - tm[s]);
            A += 0.5 * (tp[s] + pb) * (b - tm[s]);
        }
        worst = fmax(worst, fabs(A / A1 - u));
    }
    t_true(tb && worst < 1e-12, "tabulated phase (3 nodes) sampled mu: CDF(mu) = u at u = 0.01 .. 0.999 (worst %.2g)",
           worst);
    nbt_phase_free(tb);
}

/* the g-sliced tail table's error map (channel 1) at a point: the largest of the 8 nodes around its
 * cell. A 4 x 3 x 3 table on linear axes with scattered values (node k: frac(0.618034 k + 0.1)); the
 * point (0.5, 0.2, 0.7) lies in cell (1, 0, 1), away from every end */
static void test_tail_err_at(void)
{
    nbt_axis a0 = {0, 1, NBT_AXIS_LINEAR, 0, 4}, a1 = {0, 1, NBT_AXIS_LINEAR, 0, 3}, a2 = {0, 1, NBT_AXIS_LINEAR, 0, 3};
    nbt_table *t = nbt_table_alloc3(NBT_TABLE_H, &a0, &a1, &a2, 2);
    double want = 0, got = -1;
    if (t) {
        for (size_t k = 0; k < 4 * 3 * 3; k++) {
            t->data[2 * k] = 1.0f;
            t->data[2 * k + 1] = (float)fmod(0.618034 * (double)k + 0.1, 1.0);
        }
        for (size_t m = 1; m <= 2; m++)
            for (size_t j = 0; j <= 1; j++)
                for (size_t i = 1; i <= 2; i++)
                    want = fmax(want, t->data[((m * 3 + j) * 4 + i) * 2 + 1]);
        got = nbt__tail_err_at(t, 0.5, 0.2, 0.7);
    }
    t_true(got == want, "tail error map at (0.5, 0.2, 0.7): %.9g = max of its cell's 8 nodes %.9g", got, want);
    nbt_table_free(t);
}

/* the store of G rows shared by a plan's J builds (internal): 700 rows put,
 * the table grown from 256 to 2048 slots on the way, and every row found
 * again with its own values (a row moved to the wrong slot on growth is
 * missed, and recomputed by every build that wants it) */
static void test_jcache(void)
{
    nbt__jcache *c = nbt__jcache_alloc(1u << 20);
    int ok = c != NULL, hits = 0;
    for (int i = 0; ok && i < 700; i++) {
        nbt__jkey k = {0.37 + 0.013 * i, 1e-9, 3, 4, 2, 1, i % 2, NULL};
        double row[3] = {k.T, -k.T, i};
        double e = 0.5 * i;
        nbt__jcache_put(c, &k, row, &e);
    }
    for (int i = 0; ok && i < 700; i++) {
        nbt__jkey k = {0.37 + 0.013 * i, 1e-9, 3, 4, 2, 1, i % 2, NULL};
        double row[3] = {0}, e = -1;
        if (nbt__jcache_get(c, &k, row, &e))
            hits += row[0] == k.T && row[1] == -k.T && row[2] == i && e == 0.5 * i;
    }
    nbt__jkey other = {0.37, 1e-9, 3, 4, 2, 1, 1, NULL}; /* key 0 with another split: not stored */
    double row[3], e;
    t_true(ok && hits == 700 && !nbt__jcache_get(c, &other, row, &e),
           "G-row store: %d of 700 rows found with their values after growing to 2048 slots; an unstored key missed",
           hits);
    nbt__jcache_free(c);
}

static void test_messages(void)
{
    const nbt_status all[7] = {NBT_OK, NBT_EDOM, NBT_ENOMEM, NBT_ETOL, NBT_EIO, NBT_EFORMAT, NBT_EINVAL};
    int ok = 1;
    for (int i = 0; i < 7; i++) {
        const char *s = nbt_strerror(all[i]);
        ok &= s && *s;
        for (int j = 0; j < i; j++)
            ok &= strcmp(s, nbt_strerror(all[j])) != 0;
    }
    t_true(ok, "nbt_strerror: a distinct message per status");
    t_true(nbt_strerror((nbt_status)99) != NULL, "nbt_strerror of an unknown status");
    t_true(!strcmp(nbt_version(), PACKAGE_VERSION), "nbt_version %s = %s", nbt_version(), PACKAGE_VERSION);
}

int main(void)
{
    test_camera_ray();
    test_grid_box();
    test_hg2();
    test_beam_direct();
    test_atom_zero_width();
    test_nnls();
    test_sample_ends();
    test_tail_err_at();
    test_jcache();
    test_messages();
    return t_done();
}
