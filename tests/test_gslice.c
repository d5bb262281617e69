/* tests/test_gslice.c: g-sliced H and J tables (nbt/gslice.h) against
 * independently integrated H_p, J_p^n (nbt_h_phase, nbt_j_phase with
 * nbt_phase_hg) and the direct integrals (nbt_airlight_direct,
 * nbt_surface_direct). Small tables keep it to about a second. */
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include <nbt/nbt.h>
#include "testutil.h"
#include "table_roundtrip.h"

/* deterministic uniforms in [0, 1) (LCG: high-entropy points, reproducible) */
static unsigned long long rs = 0x2385u;
static double uni(void)
{
    rs = rs * 6364136223846793005ull + 1442695040888963407ull;
    return (double)(rs >> 11) / 9007199254740992.0;
}

static nbt_table *small_table(nbt_table_kind kind, int n, size_t nx, size_t ny, size_t ng, double glo, double ghi)
{
    nbt_axis a0 = {0, 4.0, NBT_AXIS_LOG1P_CBRT, 10.0, nx};
    /* H: v on the planner's mapping (ends, c = 16), whose error map check_tail tests */
    nbt_axis a1 = kind == NBT_TABLE_H ? (nbt_axis){-M_PI / 2, M_PI / 2, NBT_AXIS_ENDS, 16.0, ny}
                                      : (nbt_axis){0, M_PI, NBT_AXIS_LINEAR, 0, ny};
    nbt_axis a2 = {glo, ghi, kind == NBT_TABLE_H ? NBT_AXIS_ATANH : NBT_AXIS_COS, 0, ng};
    nbt_table *t = nbt_table_alloc3(kind, &a0, &a1, &a2, 1);
    t->n = n;
    nbt_build_opts o = {1e-10, 1, 2};
    nbt_status st = nbt_gslice_fill(t, &o);
    t_true(st == NBT_OK, "%s g-sliced fill %zux%zux%zu: status %d", nbt_table_kind_name(kind), nx, ny, ng, st);
    return t;
}

/* two-term HG, a HG(g1) + (1 - a) HG(g2), tabulated at 4001 mu clustered at
 * both ends (spacing ~3e-7 there): an independent phase object for the
 * mixture's references (piecewise-linear error below 1e-7 relative) */
static nbt_phase *tthg_tabulated(double a, double g1, double g2)
{
    enum { N = 4001 };
    static double mu[N], pv[N];
    nbt_phase *h1 = nbt_phase_hg(g1), *h2 = nbt_phase_hg(g2);
    for (int i = 0; i < N; i++) {
        mu[i] = i == 0 ? -1.0 : i == N - 1 ? 1.0 : -cos(M_PI * i / (N - 1));
        pv[i] = a * nbt_phase_eval(h1, mu[i]) + (1 - a) * nbt_phase_eval(h2, mu[i]);
    }
    nbt_phase_free(h1);
    nbt_phase_free(h2);
    return nbt_phase_tabulated(N, mu, pv);
}

/* H_p or J_p^n of the table's kind for HG(g), independently integrated */
static double exact(const nbt_table *t, double x, double y, double g)
{
    double v, e;
    nbt_phase *p = nbt_phase_hg(g);
    if (t->kind == NBT_TABLE_H)
        nbt_h_phase(p, x, y, 1e-11, &v, &e);
    else
        nbt_j_phase(p, t->n, x, y, 1e-11, &v, &e);
    nbt_phase_free(p);
    return v;
}

/* the recorded max_err bounds |lookup3 - exact| at random (x, y, g); node
 * slices hold the fixed-phase values to the quadrature tolerance */
static void check_table(const nbt_table *t, int npts)
{
    double worst = 0;
    for (int i = 0; i < npts; i++) {
        double x = t->axis[0].lo + (t->axis[0].hi - t->axis[0].lo) * pow(uni(), 3.0);
        double y = t->axis[1].lo + (t->axis[1].hi - t->axis[1].lo) * uni();
        double g = t->axis[2].lo + (t->axis[2].hi - t->axis[2].lo) * uni(), ex = exact(t, x, y, g), L;
        nbt_table_lookup3(t, x, y, g, &L);
        worst = fmax(worst, fabs(L - ex));
    }
    t_true(worst <= t->max_err[0], "%s g-sliced: true error %.3e at %d random (x, y, g) <= recorded %.3e",
           nbt_table_kind_name(t->kind), worst, npts, t->max_err[0]);
    /* the recorded error is a bound, not a gross overestimate (factor 30) */
    t_true(t->max_err[0] <= 30 * worst, "%s g-sliced: recorded %.3e within 30x of the true %.3e",
           nbt_table_kind_name(t->kind), t->max_err[0], worst);
    /* a node of a slice is the fixed-phase value (float storage: 1e-6 rel) */
    size_t m = t->axis[2].n - 2, j = t->axis[1].n / 3, ii = t->axis[0].n / 2;
    double g = nbt_axis_node(&t->axis[2], m), x = nbt_axis_node(&t->axis[0], ii), y = nbt_axis_node(&t->axis[1], j);
    t_rel(t->data[(m * t->axis[1].n + j) * t->axis[0].n + ii], exact(t, x, y, g), 1e-6, "%s slice %zu node = fixed-phase value",
          nbt_table_kind_name(t->kind), m);
}

/* The tail form: C(u, v; g) is the unobstructed airlight of a ray whose
 * foot point lies at distance h = 1 from the source with theta_0 = v, in a
 * medium with kappa_t = u (kappa_s = I0 = 1): L_a = e^{-u d_sv} C/(4 pi)
 * (doc/tables.md), so nbt_airlight_direct (Nishita's integral along the
 * ray, adaptive) is an independent reference. The error map's bound
 * (abserr of the pure lookup) covers |lookup - direct| at random (u, v, g)
 * and a node holds log(C W) within float rounding. */
static double tail_exact(double u, double v, double g, double *L, double *err)
{
    nbt_airlight_geom geo = {u, u, 1.0, 1.0 / cos(v), v + M_PI_2, INFINITY};
    nbt_phase *p = nbt_phase_hg(g);
    nbt_airlight_direct(p, &geo, 1e-11, L, err);
    nbt_phase_free(p);
    return *L * 4.0 * M_PI / u * exp(u * geo.dsv);
}

static void check_tail(const nbt_table *t, int npts)
{
    double worst = 0, worst_rel = 0;
    int inside = 0;
    for (int i = 0; i < npts; i++) {
        double u = 1e-3 + (t->axis[0].hi - 1e-3) * pow(uni(), 3.0), v = -1.55 + 3.1 * uni();
        double g = t->axis[2].lo + (t->axis[2].hi - t->axis[2].lo) * uni(), R, RE, L, E;
        tail_exact(u, v, g, &R, &RE);
        nbt_airlight_geom geo = {u, u, 1.0, 1.0 / cos(v), v + M_PI_2, INFINITY};
        nbt_status st = nbt_airlight_table_g_lookup(t, g, &geo, &L, &E);
        if (st != NBT_OK || !(fabs(L - R) <= E + RE)) {
            t_true(0, "tail lookup u=%.4g v=%.4f g=%.4f: |%.10g - %.10g| = %.2e <= bound %.2e (status %d)", u, v, g,
                   L, R, fabs(L - R), E, st);
            return;
        }
        worst = fmax(worst, fabs(L - R) / E);
        worst_rel = fmax(worst_rel, fabs(L - R) / R);
        inside += E <= 1e-2 * R;
    }
    t_true(1, "H tail form: |lookup - direct| <= the error map's bound at %d random (u, v, g) (worst %.2f of it, "
           "%.2e relative)", npts, worst, worst_rel);
    /* a bound, not a gross overestimate: somewhere the true error reaches 1/30 of it */
    t_true(worst >= 1.0 / 30, "H tail form: the bound is reached within 30x (worst true/bound %.3f)", worst);
    t_true(inside >= npts / 2, "H tail form: the bound is under 1e-2 relative at %d of %d points", inside, npts);
    /* a node: log(C W) */
    size_t m = t->axis[2].n - 2, j = t->axis[1].n / 3, ii = t->axis[0].n / 2;
    double g = nbt_axis_node(&t->axis[2], m), u = nbt_axis_node(&t->axis[0], ii), v = nbt_axis_node(&t->axis[1], j);
    double R, RE, s = tan(M_PI / 4 + v / 2);
    double C = tail_exact(u, v, g, &R, &RE);
    /* float: rounding of log C W (~1e-7); half: the error map there, which takes the rounding in */
    size_t at = ((m * t->axis[1].n + j) * t->axis[0].n + ii) * t->nch;
    t_rel(exp(t->data[at]), C * (1 + s / 2 + u * s * s / 2), t->half ? t->data[at + 1] : 1e-6,
          "H tail slice %zu node = log(C W) of the direct integral", m);
}

static void test_airlight(const nbt_table *t)
{
    /* lookup within its bound (plus the reference's error) of the direct
     * integral; where the bound is large the ray integral is returned (on
     * this small table: all but the forward rays) */
    int fell = 0, n = 40;
    for (int i = 0; i < n; i++) {
        nbt_airlight_geom geo = {0.3, 0.5, 2.0, 1.0 + 4.0 * uni(), 0.05 + 3.0 * uni(),
                                 i % 3 == 0 ? INFINITY : 0.5 + 6.0 * uni()};
        double g = t->axis[2].lo + (t->axis[2].hi - t->axis[2].lo) * uni(), L, E, R, RE;
        nbt_phase *p = nbt_phase_hg(g);
        nbt_airlight_direct(p, &geo, 1e-10, &R, &RE);
        nbt_phase_free(p);
        nbt_status st = nbt_airlight_table_g(t, g, &geo, &L, &E);
        if (E < 1e-8 * fabs(L))
            fell++; /* the ray integral's estimate */
        t_true(st == NBT_OK && fabs(L - R) <= E + RE + 1e-12 * fabs(R),
               "airlight_table_g g=%.3f gamma=%.3f dvp=%g: |%.8g - %.8g| <= bound %.2e", g, geo.gamma, geo.dvp, L, R,
               E);
        /* the tail route's promise: a lookup only where its bound is within 1e-3 */
        t_true(E <= 1e-3 * fabs(L), "airlight_table_g g=%.3f gamma=%.3f: bound %.2e <= 1e-3 of the value", g,
               geo.gamma, E / fabs(L));
    }
    t_true(fell <= n / 4, "airlight_table_g (tail form): the lookup served %d of %d rays", n - fell, n);
    /* on the source axis the ray integral with HG(g) */
    nbt_airlight_geom ax = {0.3, 0.5, 2.0, 3.0, M_PI, 5.0};
    double L, E, R, RE;
    nbt_phase *p = nbt_phase_hg(0.31);
    nbt_airlight_direct(p, &ax, 1e-10, &R, &RE);
    nbt_phase_free(p);
    nbt_status st = nbt_airlight_table_g(t, 0.31, &ax, &L, &E);
    t_true(st == NBT_OK, "airlight_table_g on the axis: status %d", st);
    t_rel(L, R, 1e-8, "airlight_table_g on the axis = direct");
    /* errors */
    t_true(nbt_airlight_table_g(t, t->axis[2].hi + 0.01, &ax, &L, &E) == NBT_EDOM, "g beyond the range: EDOM");
}

static void test_surface(const nbt_table *J)
{
    for (int i = 0; i < 3; i++) {
        nbt_surface_geom geo = {0.4, 0.5, 2.0, 2.0 + 4.0 * uni(), 0.3 + 2.5 * uni(), 0.5, 0.7, 0, 1};
        double g = J->axis[2].lo + (J->axis[2].hi - J->axis[2].lo) * uni(), L, E, R, RE;
        nbt_phase *p = nbt_phase_hg(g);
        nbt_surface_direct(p, &geo, 1e-8, &R, &RE);
        nbt_phase_free(p);
        nbt_status st = nbt_surface_table_g(J, NULL, g, &geo, 0, &L, &E);
        if (getenv("NBT_TEST_VERBOSE"))
            printf("surface: |L - R| %.3g bound %.3g ref err %.3g\n", fabs(L - R), E, RE);
        t_true(st == NBT_OK && fabs(L - R) <= E + RE + 1e-10 * fabs(R),
               "surface_table_g g=%.3f theta=%.3f: |%.8g - %.8g| <= bound %.2e", g, geo.theta_s, L, R, E);
    }
    /* a specular lobe of exponent 1 from the same table (theta_r != theta_s): the specular term counts */
    {
        nbt_surface_geom geo = {0.4, 0.5, 2.0, 3.1, 0.6, 1.9, 0.5, 0.8, 1};
        double g = J->axis[2].lo + 0.37 * (J->axis[2].hi - J->axis[2].lo), L, E, R, RE;
        nbt_phase *p = nbt_phase_hg(g);
        nbt_surface_direct(p, &geo, 1e-8, &R, &RE);
        nbt_phase_free(p);
        nbt_status st = nbt_surface_table_g(J, J, g, &geo, 0, &L, &E);
        t_true(st == NBT_OK && fabs(L - R) <= E + RE + 1e-10 * fabs(R),
               "surface_table_g with a specular lobe (ks 0.8, theta_r 1.9): |%.8g - %.8g| <= bound %.2e", L, R, E);
    }
    /* at a node g the lookup is the fixed-phase table route's (surface.c's
     * nbt_surface_table over a 2-D HG(g_m) table on the same axes) */
    double gm = nbt_axis_node(&J->axis[2], 6), L, E, Lf;
    nbt_table *F = nbt_table_alloc(NBT_TABLE_J, &J->axis[0], &J->axis[1], 1);
    nbt_phase *ph = nbt_phase_hg(gm);
    nbt_build_opts o = {1e-10, 0, 2};
    F->k[0] = -1;
    F->n = 1;
    nbt_j_table_build(F, ph, &o);
    nbt_phase_free(ph);
    nbt_surface_geom sg = {0.4, 0.5, 2.0, 3.3, 1.9, 0.5, 0.7, 0, 1};
    const nbt_table *Fs[1] = {F};
    nbt_surface_table(Fs, 1, NULL, 0, NULL, 0, &sg, &Lf);
    nbt_surface_table_g(J, NULL, gm, &sg, 0, &L, &E);
    t_rel(L, Lf, 1e-6, "surface_table_g at node g = %.4f = the fixed-phase table route", gm);
    nbt_table_free(F);
    nbt_surface_geom geo = {0.4, 0.5, 2.0, 9.0, 1.0, 0.5, 0.7, 0, 2};
    t_true(nbt_surface_table_g(J, NULL, 0.1, &geo, 0, &L, &E) == NBT_ETOL, "T = 4.5 beyond the table's 4: ETOL");
    geo.dsp = 3.0;
    t_true(nbt_surface_table_g(J, NULL, 0.8, &geo, 0, &L, &E) == NBT_EDOM, "g = 0.8 beyond the table's g: EDOM");
    geo.ks = 0.3;
    t_true(nbt_surface_table_g(J, NULL, 0.1, &geo, 0, &L, &E) == NBT_EINVAL, "specular lobe without table: EINVAL");
    t_true(nbt_surface_table_g(J, J, 0.1, &geo, 0, &L, &E) == NBT_EINVAL, "specular table with n != geo n: EINVAL");
    /* a diffuse term (kd = 0.7, inside (0, 1]) without its table: refused, not read through NULL */
    geo.ks = 0;
    t_true(nbt_surface_table_g(NULL, NULL, 0.1, &geo, 0, &L, &E) == NBT_EINVAL, "diffuse kd = 0.7 without table: EINVAL");
}

static void test_errors(nbt_table *H, nbt_table *J)
{
    nbt_build_opts o = {1e-10, 0, 1};
    nbt_axis a0 = {0, 1, NBT_AXIS_LINEAR, 0, 3}, a1 = {-1, 1, NBT_AXIS_LINEAR, 0, 3}, a2 = {-0.995, 0.5, NBT_AXIS_COS, 0, 2};
    nbt_table *t2 = nbt_table_alloc(NBT_TABLE_H, &a0, &a1, 1);
    t_true(nbt_gslice_fill(t2, &o) == NBT_EINVAL, "fill of a 2-D table: EINVAL");
    nbt_table_free(t2);
    nbt_table *t3 = nbt_table_alloc3(NBT_TABLE_H, &a0, &a1, &a2, 1);
    t_true(nbt_gslice_fill(t3, &o) == NBT_EDOM, "fill with g = -0.995: EDOM");
    t3->kind = NBT_TABLE_PSI;
    t_true(nbt_gslice_fill(t3, &o) == NBT_EINVAL, "fill of a PSI table: EINVAL");
    nbt_table_free(t3);
    nbt_axis b0 = {0, 1, NBT_AXIS_LINEAR, 0, 3}, b1 = {-M_PI / 2, M_PI / 2, NBT_AXIS_COS, 0, 3};
    nbt_table *t4 = nbt_table_alloc3(NBT_TABLE_H, &b0, &b1, &(nbt_axis){-0.5, 0.5, NBT_AXIS_ATANH, 0, 2}, 1);
    t_true(nbt_gslice_fill(t4, &o) == NBT_EINVAL, "tail form with 2 g slices: EINVAL (quadratic in g needs 3)");
    nbt_table_free(t4);
    t4 = nbt_table_alloc3(NBT_TABLE_J, &b0, &a1, &(nbt_axis){-0.5, 0.5, NBT_AXIS_ATANH, 0, 3}, 1);
    t4->n = 1;
    t_true(nbt_gslice_fill_form(t4, NBT_FORM_TAIL, &o) == NBT_EINVAL, "tail form for a J table: EINVAL");
    t4->interp2 = 3; /* cubic: measured for the tail form only */
    t_true(nbt_gslice_fill_form(t4, NBT_FORM_LOG_ET, &o) == NBT_EINVAL, "log_et J with interp2 3: EINVAL");
    t4->interp2 = 1;
    nbt_table_free(t4);
    nbt_airlight_geom geo = {0.3, 0.5, 2.0, 3.0, 1.0, 5.0};
    double L, E;
    t_true(nbt_airlight_table_g(J, 0.1, &geo, &L, &E) == NBT_EINVAL, "airlight from a J table: EINVAL");
    nbt_surface_geom sg = {0.4, 0.5, 2.0, 3.0, 1.0, 0.5, 0.7, 0, 1};
    t_true(nbt_surface_table_g(H, NULL, 0.1, &sg, 0, &L, &E) == NBT_EINVAL, "surface from an H table: EINVAL");
    char err[256] = "";
    nbt_table *out;
    nbt_gslice_request r = {NBT_TABLE_H, 0, 4.0, {0.5, 0.2}, 1e-2, {0, 0, 0}, 0};
    t_true(nbt_gslice_build(&r, 1, &out, NULL, err, sizeof err) == NBT_EDOM && strstr(err, "g = 0.5:0.2"),
           "request g 0.5:0.2: EDOM naming it (%s)", err);
    r = (nbt_gslice_request){NBT_TABLE_H, 0, 4.0, {-0.5, 0.2}, 0, {33, 33, 1}, 0};
    t_true(nbt_gslice_build(&r, 1, &out, NULL, err, sizeof err) == NBT_EDOM && strstr(err, "33x33x1"),
           "request size 33x33x1: EDOM naming it (%s)", err);
    r = (nbt_gslice_request){NBT_TABLE_J, 0, 4.0, {-0.5, 0.2}, 1e-2, {0, 0, 0}, 0};
    t_true(nbt_gslice_build(&r, 1, &out, NULL, err, sizeof err) == NBT_EDOM && strstr(err, "n = 0"),
           "request J n = 0: EDOM naming it (%s)", err);
}

/* The log_et form (ln(e^T J)): a J^1 table on an atanh g axis, quadratic
 * in g, over [-0.95, 0.95]. Its recorded error is in ln, i.e. relative:
 * at random (T, theta, g), above and below the horizon, the lookup's J is
 * within J (e^err - 1) of nbt_j_phase (plus that reference's own error),
 * and the surface route within its bound of nbt_surface_direct. */
static void test_log_form(void)
{
    nbt_axis a0 = {0, 6.0, NBT_AXIS_LOG1P_CBRT, 10.0, 25}, a1 = {0, M_PI, NBT_AXIS_LINEAR, 0, 25};
    nbt_axis a2 = {-0.95, 0.95, NBT_AXIS_ATANH, 0, 9};
    nbt_table *t = nbt_table_alloc3(NBT_TABLE_J, &a0, &a1, &a2, 1);
    t->n = 1;
    t->form = NBT_FORM_LOG_ET;
    t->interp2 = 2;
    nbt_build_opts o = {1e-10, 1, 2};
    nbt_status st = nbt_gslice_fill(t, &o);
    t_true(st == NBT_OK, "log_et J^1 25x25x9 fill: status %d", st);
    if (st != NBT_OK) {
        nbt_table_free(t);
        return;
    }
    /* a node is T + ln of the fixed-phase value */
    size_t m = 7, j = 17, i = 11;
    double g = nbt_axis_node(&a2, m), T = nbt_axis_node(&a0, i), th = nbt_axis_node(&a1, j);
    t_rel(exp(t->data[(m * a1.n + j) * a0.n + i] - T), exact(t, T, th, g), 1e-6,
          "log_et node (g %.3f, T %.2f, theta %.2f) = T + ln J", g, T, th);
    double worst = 0, wbound = 0;
    for (int k = 0; k < 60; k++) {
        T = 6.0 * pow(uni(), 2.0);
        th = M_PI * uni();
        g = -0.95 + 1.9 * uni();
        double v, ex = exact(t, T, th, g);
        nbt_table_lookup3(t, T, th, g, &v);
        double rel = fabs(exp(v - T) - ex) / ex, b = expm1(nbt_table_err_at(t, 0, g));
        worst = fmax(worst, rel / b);
        wbound = fmax(wbound, b);
    }
    t_true(worst <= 1.0, "log_et: relative error at 60 random (T, theta, g) within the recorded bound "
           "(worst %.2f of it; bound up to %.2e)", worst, wbound);
    t_true(worst >= 1.0 / 30, "log_et: the recorded bound within 30x of the true error (%.3f)", worst);
    int kept = 0, n = 6;
    for (int k = 0; k < n; k++) {
        nbt_surface_geom geo = {0.3, 0.5, 1.0, 1.0 + 10.0 * uni(), M_PI * uni(), 0.5, 0.7, 0, 1};
        double L, E, R, RE;
        g = -0.95 + 1.9 * uni();
        nbt_phase *p = nbt_phase_hg(g);
        nbt_surface_direct(p, &geo, 1e-8, &R, &RE);
        nbt_phase_free(p);
        st = nbt_surface_table_g(t, NULL, g, &geo, 0, &L, &E);
        kept += E <= 0.1 * fabs(L);
        t_true(st == NBT_OK && fabs(L - R) <= E + RE + 1e-10 * fabs(R),
               "log_et surface g=%.3f d=%.2f theta=%.3f: |%.8g - %.8g| <= bound %.2e", g, geo.dsp, geo.theta_s, L, R,
               E);
    }
    /* per g cell: the bound near g = 0 is far below the one set by the peaked ends */
    t_true(nbt_table_err_at(t, 0, 0.0) < 0.5 * t->max_err[0], "log_et: cell error at g = 0 %.2e < half of max_err %.2e "
           "(surface bound under 10%% at %d of %d geometries)", nbt_table_err_at(t, 0, 0.0), t->max_err[0], kept, n);
    /* the EXR keeps the form */
    nbt_table *back = exr_round_trip(t);
    t_true(back && back->form == NBT_FORM_LOG_ET && back->interp2 == 2, "EXR keeps form log_et");
    nbt_table_free(back);
    /* Legendre channels can be negative: the log form is refused */
    nbt_table *L2 = nbt_table_alloc(NBT_TABLE_J, &a0, &a1, 1);
    L2->n = 1;
    L2->form = NBT_FORM_LOG_ET;
    o.measure_error = 0;
    t_true(nbt_j_table_build(L2, NULL, &o) == NBT_EINVAL, "log_et for Legendre channels: EINVAL");
    nbt_table_free(L2);
    nbt_table_free(t);
}

/* The one-pass fill (all slices' quadratures at once) against per-slice
 * fixed-phase builds: every node of every slice equal within the two
 * recorded quadrature errors and float rounding (J^20, plain, g to +-0.95;
 * J^1 in log_et, where the quadrature error is relative) */
static void test_one_pass(void)
{
    for (int form = 0; form < 2; form++) {
        int n = form ? 1 : 20;
        nbt_axis a0 = {0, 6.0, NBT_AXIS_LOG1P_CBRT, 10.0, 9}, a1 = {0, M_PI, NBT_AXIS_COS, 0, 9};
        nbt_axis a2 = {-0.95, 0.95, NBT_AXIS_ATANH, 0, 5};
        nbt_table *t = nbt_table_alloc3(NBT_TABLE_J, &a0, &a1, &a2, 1);
        t->n = n;
        t->form = form ? NBT_FORM_LOG_ET : NBT_FORM_PLAIN;
        nbt_build_opts o = {1e-10, 0, 2};
        t_true(nbt_gslice_fill(t, &o) == NBT_OK, "one-pass fill J^%d", n);
        double worst = 0;
        for (size_t m = 0; m < a2.n; m++) {
            nbt_table *s = nbt_table_alloc(NBT_TABLE_J, &a0, &a1, 1);
            nbt_phase *p = nbt_phase_hg(nbt_axis_node(&a2, m));
            s->n = n;
            s->k[0] = -1;
            s->form = t->form;
            nbt_j_table_build(s, p, &o);
            for (size_t k = 0; k < a0.n * a1.n; k++) {
                double a = t->data[m * a0.n * a1.n + k], b = s->data[k];
                worst = fmax(worst, fabs(a - b) / (t->quad_err + s->quad_err + 2.5 * FLT_EPSILON * fabs(b)));
            }
            nbt_phase_free(p);
            nbt_table_free(s);
        }
        t_true(worst <= 1.0, "one-pass J^%d (%s) = per-slice builds within the quadrature errors (worst %.2f of them, "
               "quad_err %.1e)", n, form ? "log_et" : "plain", worst, t->quad_err);
        nbt_table_free(t);
    }
}

/* The tail form cubic in g (issue 21) at asymmetric points in the end g
 * cells of a table on g in [-0.9, 0.6] (17 slices): near g = -0.9 where HG's
 * backward peak sits at v -> pi/2, and near 0.6, each at 0.382 of a cell
 * from the end, where the one-sided stencil's error polynomial peaks, at
 * (u, v) between nodes: the lookup within the error map's bound of the
 * direct ray integral (nbt_airlight_direct, tol 1e-11, its own estimate
 * added), and closer to it than the quadratic lookup. A 3-slice table
 * (quadratic, as H files before the cubic) still bounds its lookups and
 * keeps interp2 = 2 through an EXR file. */
static void test_tail_cubic(void)
{
    nbt_axis a0 = {0, 4.0, NBT_AXIS_LOG1P_CBRT, 10.0, 49}, a1 = {-M_PI_2, M_PI_2, NBT_AXIS_ENDS, 16.0, 97};
    nbt_axis a2 = {-0.9, 0.6, NBT_AXIS_ATANH, 0, 17};
    nbt_table *t = nbt_table_alloc3(NBT_TABLE_H, &a0, &a1, &a2, 1);
    nbt_build_opts o = {1e-10, 1, 2};
    nbt_status st = t ? nbt_gslice_fill(t, &o) : NBT_ENOMEM;
    t_true(st == NBT_OK && t->interp2 == 3, "tail H 49x97x17 on g [-0.9, 0.6]: fill, cubic in g (interp2 %d)",
           t ? t->interp2 : 0);
    if (st != NBT_OK) {
        nbt_table_free(t);
        return;
    }
    double ec = 0, eq = 0;
    static const double pt[4][3] = {{0.37, 1.31, 0.382}, {1.73, 1.47, 0.618}, {0.58, -1.23, 16 - 0.382}, {2.9, 0.44, 14.5}};
    for (int k = 0; k < 4; k++) {
        double u = pt[k][0], v = pt[k][1], g = nbt_axis_from_unit(&a2, pt[k][2] / 16.0), R, RE, L, E, Lq, Eq;
        tail_exact(u, v, g, &R, &RE);
        nbt_airlight_geom geo = {u, u, 1.0, 1.0 / cos(v), v + M_PI_2, INFINITY};
        nbt_status sl = nbt_airlight_table_g_lookup(t, g, &geo, &L, &E);
        t->interp2 = 2;
        nbt_airlight_table_g_lookup(t, g, &geo, &Lq, &Eq);
        t->interp2 = 3;
        t_true(sl == NBT_OK && fabs(L - R) <= E + RE,
               "tail cubic in g at u %.2f v %+.2f g %+.4f: |lookup - direct| %.2e relative <= the bound %.2e "
               "(quadratic: %.2e)", u, v, g, fabs(L - R) / R, E / R, fabs(Lq - R) / R);
        ec += fabs(L - R) / R;
        eq += fabs(Lq - R) / R;
    }
    /* the (u, v) error is the same for both: what the cubic removes is most of the g error
     * (0.33 of the quadratic's total measured; the g error alone falls ~5x at 33 slices) */
    t_true(ec < 0.6 * eq, "tail: cubic in g errs %.2e in total at the 4 points, under 0.6 of quadratic's %.2e", ec, eq);
    nbt_table_free(t);
    /* the end g cells' 16/15: on 5 slices (g error dominant) at every (u, v) node, at x = 0.382
     * of the first and last g cells (where the one-sided cubic's error peaks, 16/15 of its
     * midpoint value), the lookup within the map's bound; the true error reaches 0.98 of it
     * there (0.94 at the midpoint), so a map without the 16/15 would be exceeded */
    nbt_axis c0 = {0, 4.0, NBT_AXIS_LOG1P_CBRT, 10.0, 33}, c1 = {-M_PI_2, M_PI_2, NBT_AXIS_ENDS, 16.0, 65};
    nbt_axis c2 = {-0.9, 0.6, NBT_AXIS_ATANH, 0, 5};
    t = nbt_table_alloc3(NBT_TABLE_H, &c0, &c1, &c2, 1);
    st = t ? nbt_gslice_fill(t, &o) : NBT_ENOMEM;
    double wr = 0;
    int over = 0;
    for (int side = 0; st == NBT_OK && side < 2; side++) {
        double g = nbt_axis_from_unit(&c2, (side ? 4 - 0.382 : 0.382) / 4.0);
        nbt_phase *ph = nbt_phase_hg(g);
        for (size_t j = 1; j + 1 < c1.n; j++)
            for (size_t i = 1; i < c0.n; i++) {
                double u = nbt_axis_node(&c0, i), v = nbt_axis_node(&c1, j), R, RE, L, E;
                if (fabs(v) > 1.55)
                    continue;
                nbt_airlight_geom geo = {u, u, 1.0, 1.0 / cos(v), v + M_PI_2, INFINITY};
                nbt_airlight_direct(ph, &geo, 1e-11, &R, &RE);
                nbt_airlight_table_g_lookup(t, g, &geo, &L, &E);
                over += !(fabs(L - R) <= E + RE);
                wr = fmax(wr, fabs(L - R) / (E + RE));
            }
        nbt_phase_free(ph);
    }
    t_true(st == NBT_OK && over == 0 && wr >= 0.9, "tail 33x65x5, 0.382 into the end g cells: every node within the "
           "map's bound (%d over, worst %.3f of it, >= 0.9: the check is tight)", over, wr);
    nbt_table_free(t);
    nbt_axis q2 = {-0.9, -0.75, NBT_AXIS_ATANH, 0, 3};
    t = nbt_table_alloc3(NBT_TABLE_H, &a0, &a1, &q2, 1);
    st = t ? nbt_gslice_fill(t, &o) : NBT_ENOMEM;
    t_true(st == NBT_OK && t->interp2 == 2, "tail H with 3 slices: quadratic in g (interp2 %d)", t ? t->interp2 : 0);
    if (st == NBT_OK) {
        check_tail(t, 40);
        nbt_table *back = exr_round_trip(t);
        t_true(back && back->interp2 == 2 && back->form == NBT_FORM_TAIL, "3-slice tail file keeps interp2 2");
        nbt_table_free(back);
    }
    nbt_table_free(t);
}

/* nbt_gslice_plan and nbt_gslice_execute called directly (not through
 * nbt_gslice_build): the plan's axes are the table's; a plan edited by the
 * caller (6 more T nodes) is built as edited; the table's specular surface
 * radiance at g of both signs (-0.41, 0.33) and an off-axis geometry matches
 * nbt_surface_direct with HG(g) within the two bounds. */
static void test_plan_execute(void)
{
    nbt_gslice_request r = {NBT_TABLE_J, 20, 4.0, {-0.45, 0.35}, 2e-2, {0, 0, 0}, 0};
    nbt_gslice_plan_t p;
    char err[256] = "";
    nbt_status st = nbt_gslice_plan(&r, 2, &p, err, sizeof err);
    t_true(st == NBT_OK && p.axis[2].map == NBT_AXIS_ATANH && p.axis[2].lo == -0.45 && p.axis[2].hi == 0.35 &&
               p.axis[0].hi == 4.0 && p.pred_seconds > 0 && p.bytes > 0,
           "gslice_plan J^20: status %d %s, %zux%zux%zu, g [%g, %g]", st, err, p.axis[0].n, p.axis[1].n, p.axis[2].n,
           p.axis[2].lo, p.axis[2].hi);
    if (st != NBT_OK)
        return;
    size_t planned = p.axis[0].n;
    p.axis[0].n = planned + 6; /* the caller's edit: execute builds what the plan says */
    nbt_table *t = NULL;
    st = nbt_gslice_execute(&p, 2, &t, err, sizeof err);
    int same = st == NBT_OK;
    for (int a = 0; a < 3 && same; a++)
        same = t->axis[a].n == p.axis[a].n && t->axis[a].lo == p.axis[a].lo && t->axis[a].hi == p.axis[a].hi &&
               t->axis[a].map == p.axis[a].map;
    t_true(same && t->n == 20 && t->axis[0].n == planned + 6,
           "gslice_execute: the table has the plan's axes (T %zu nodes, planned %zu + 6): %s",
           st == NBT_OK ? t->axis[0].n : 0, planned, err);
    if (st != NBT_OK)
        return;
    double worst = 0;
    for (int k = 0; k < 2; k++) {
        double g = k ? 0.33 : -0.41, L, E, R, RE;
        nbt_surface_geom geo = {0.3, 0.5, 1.0, 3.7, 0.4, 0.9 - 0.5 * k, 0.0, 1.0, 20};
        nbt_status s1 = nbt_surface_table_g(NULL, t, g, &geo, 0, &L, &E);
        nbt_phase *hg = nbt_phase_hg(g);
        nbt_status s2 = nbt_surface_direct(hg, &geo, 1e-8, &R, &RE);
        nbt_phase_free(hg);
        worst = fmax(worst, (s1 == NBT_OK || s1 == NBT_ETOL) && s2 == NBT_OK ? fabs(L - R) / (E + RE) : INFINITY);
    }
    t_true(worst <= 1, "executed J^20: specular radiance at g -0.41 and 0.33 = nbt_surface_direct within the bounds "
                       "(worst %.2f of them)", worst);
    nbt_table_free(t);
}

/* nbt_scene_basis called directly: its table is the scene's first set (H with
 * airlight; J^1 with diffuse; else the first Phong exponent, here 30), over
 * [0, max kappa_t x max distance] = [0, 0.7 x 6] and the scene's g range; a
 * Legendre request names the orders nbt_plan_legendre_terms needs for |g| up to
 * 0.6 at that xmax and tol (both signs); a scene without a g range: NBT_EINVAL. */
static void test_scene_basis(void)
{
    nbt_scene s;
    nbt_scene_init(&s);
    s.kappa_t[0] = 0.2, s.kappa_t[1] = 0.7, s.distance[0] = 1, s.distance[1] = 6;
    s.have_g = 1, s.g[0] = -0.6, s.g[1] = 0.35, s.tol = 2e-2;
    s.airlight = 0, s.diffuse = 0, s.phong[0] = 30, s.phong[1] = 5, s.nphong = 2;
    s.basis = NBT_BASIS_SLICES;
    nbt_basis_choice c;
    char err[256] = "";
    nbt_status st = nbt_scene_basis(&s, 2, &c, err, sizeof err);
    t_true(st == NBT_OK && c.basis == NBT_BASIS_SLICES && c.sl_plan.req.kind == NBT_TABLE_J && c.sl_plan.req.n == 30 &&
               fabs(c.sl_plan.req.xmax - 4.2) < 1e-12 && c.sl_plan.req.g[0] == -0.6 && c.sl_plan.req.g[1] == 0.35 &&
               c.sl_plan.req.tol == 2e-2,
           "scene_basis slices: J^30 (the first Phong set) over T to 4.2, g -0.6:0.35 (status %d, kind %d n %d xmax %g) %s",
           st, (int)c.sl_plan.req.kind, c.sl_plan.req.n, c.sl_plan.req.xmax, err);
    s.basis = NBT_BASIS_LEGENDRE;
    s.orders_max = 512;
    s.airlight = 1;
    nbt_plan_legendre leg;
    nbt_plan_legendre_terms(0.6, 4.2, 2e-2, 512, &leg);
    st = nbt_scene_basis(&s, 2, &c, err, sizeof err);
    t_true(st == NBT_OK && c.basis == NBT_BASIS_LEGENDRE && c.leg_nterms == leg.nterms && leg.nterms > 4,
           "scene_basis legendre with airlight: %zu orders (the budget for |g| 0.6 at u 4.2: %zu) %s", c.leg_nterms,
           leg.nterms, err);
    s.have_g = 0;
    nbt_phase *iso = nbt_phase_iso();
    s.phase = iso;
    t_true(nbt_scene_basis(&s, 2, &c, err, sizeof err) == NBT_EINVAL, "scene_basis without a g range: NBT_EINVAL");
    nbt_phase_free(iso);
}

/* an error-driven build meets its tolerance, and an EXR round trip keeps
 * the table a g-sliced one */
static void test_build_io(void)
{
    nbt_gslice_request r = {NBT_TABLE_H, 0, 3.0, {-0.3, 0.6}, 2e-2, {0, 0, 0}, 0};
    nbt_table *t = NULL;
    char err[256] = "";
    nbt_status st = nbt_gslice_build(&r, 2, &t, NULL, err, sizeof err);
    t_true(st == NBT_OK, "error-driven build tol 2e-2: status %d %s", st, err);
    if (st != NBT_OK)
        return;
    t_true(t->form == NBT_FORM_TAIL && t->axis[2].map == NBT_AXIS_ATANH && t->interp2 == 3,
           "build: H in the tail form on an atanh g axis, cubic in g");
    t_true(t->axis[1].map == NBT_AXIS_ENDS && t->axis[1].c == 16.0 && t->axis[1].lo == -M_PI_2 && t->axis[1].hi == M_PI_2,
           "build: v on the ends mapping, c = 16 (the planner's rule)");
    check_tail(t, 60);
    /* a two-term HG from the same table (0.8 HG(0.55) + 0.2 HG(-0.25)) against the ray
     * integral of the tabulated mixture */
    {
        double w[2] = {0.8, 0.2}, gg[2] = {0.55, -0.25}, worst = 0;
        nbt_phase *tt = tthg_tabulated(0.8, 0.55, -0.25);
        for (int k = 0; k < 8; k++) {
            nbt_airlight_geom geo = {0.3, 0.5, 2.0, 0.5 + 5.0 * uni(), 0.1 + 2.9 * uni(), k % 2 ? INFINITY : 4.0};
            double L, E, R, RE;
            nbt_status sm = nbt_airlight_table_hg_mix(t, 2, w, gg, &geo, &L, &E);
            nbt_airlight_direct(tt, &geo, 1e-9, &R, &RE);
            worst = fmax(worst, sm == NBT_OK ? fabs(L - R) / (E + RE + 1e-6 * fabs(R)) : INFINITY);
        }
        t_true(worst <= 1, "two-term HG airlight = its ray integral within the summed bounds (worst %.2f of them)",
               worst);
        nbt_airlight_geom geo = {0.3, 0.5, 2.0, 2.0, 1.0, INFINITY};
        double L, E;
        t_true(nbt_airlight_table_hg_mix(t, 2, (double[]){0.8, 0.3}, gg, &geo, &L, &E) == NBT_EDOM &&
                   nbt_airlight_table_hg_mix(t, 0, w, gg, &geo, &L, &E) == NBT_EDOM &&
                   nbt_airlight_table_hg_mix(t, 2, w, (double[]){0.55, -0.5}, &geo, &L, &E) == NBT_EDOM,
               "HG mixture: weights not summing to 1, no lobe, a lobe outside the g range: NBT_EDOM");
        nbt_phase_free(tt);
    }
    nbt_table *back = exr_round_trip(t);
    t_true(back && nbt_table_is_gslice(back) && back->axis[2].n == t->axis[2].n &&
               back->max_err[0] == t->max_err[0] && back->form == NBT_FORM_TAIL && back->interp2 == 3 &&
               back->nch == 2 && back->data[5] == t->data[5],
           "EXR round trip keeps the g-sliced table (%zu slices)", t->axis[2].n);
    /* the v mapping survives the file: same map and c, and a lookup between
     * nodes near each end (where a different mapping lands elsewhere) is the
     * same number */
    if (back) {
        double a[NBT_TABLE_MAX_CH], b[NBT_TABLE_MAX_CH], worst = 0;
        for (int k = 0; k < 2; k++) {
            double v = k ? 1.4137 : -1.3391;
            nbt_table_lookup3(t, 0.77, v, 0.21, a);
            nbt_table_lookup3(back, 0.77, v, 0.21, b);
            worst = fmax(worst, fabs(a[0] - b[0]));
        }
        t_true(back->axis[1].map == NBT_AXIS_ENDS && back->axis[1].c == 16.0 && worst == 0.0,
               "EXR round trip keeps v's ends mapping (c %g) and lookups (difference %.1e)", back->axis[1].c, worst);
    }
    nbt_table_free(back);
    nbt_table_free(t);
    /* half floats: log values rounded to 11 bits (up to 2.4e-4 of |log C W| <= ~7), which the
     * error map takes in */
    r.half = 1;
    st = nbt_gslice_build(&r, 2, &t, NULL, err, sizeof err);
    t_true(st == NBT_OK && t->half, "error-driven build, half floats: status %d %s", st, err);
    if (st == NBT_OK)
        check_tail(t, 60);
    nbt_table_free(t);

    /* J: the planner's rule at tol 1e-2 (T <= 20, g over +-0.95) gives a log_et
     * table, quadratic on an atanh g axis, whose pure lookup (no fallback) is
     * within tol of nbt_surface_direct at random geometries (the direct term
     * included, as a renderer sees it; the reference's own error added) */
    nbt_gslice_request rj = {NBT_TABLE_J, 1, 20.0, {-0.95, 0.95}, 1e-2, {0, 0, 0}, 0};
    st = nbt_gslice_build(&rj, 2, &t, NULL, err, sizeof err);
    t_true(st == NBT_OK && t->form == NBT_FORM_LOG_ET && t->interp2 == 2 && t->axis[2].map == NBT_AXIS_ATANH,
           "J build tol 1e-2: log_et, quadratic, atanh g (status %d %s)", st, err);
    double worst = 0;
    for (int k = 0; st == NBT_OK && k < 12; k++) {
        nbt_surface_geom geo = {0.4, 0.5, 1.0, 0.5 + 39.0 * uni() * uni(), M_PI * uni(), 0.5, 1.0, 0, 1};
        double g = -0.95 + 1.9 * uni(), L, E, R, RE;
        nbt_phase *ph = nbt_phase_hg(g);
        nbt_surface_direct(ph, &geo, 1e-8, &R, &RE);
        nbt_phase_free(ph);
        nbt_surface_table_g(t, NULL, g, &geo, 0, &L, &E);
        worst = fmax(worst, (fabs(L - R) - RE) / fabs(R));
    }
    t_true(worst <= 1e-2, "J rule tol 1e-2: 12 random surface lookups within 1e-2 of the direct integral (worst %.2e)",
           worst);
    /* two-term HG (0.85 HG(0.9) + 0.15 HG(-0.5)) from the same J table against the direct
     * integral of the mixture in closed form (nbt_phase_hg2, not the table route's lobes): within
     * tol as above. (A tabulated mixture's kinks made the nested 1e-8 / 1e-9 quadrature of
     * nbt_surface_direct take over 10 minutes at d_sp 0.76, theta_s 0.96.) */
    nbt_phase *tt = nbt_phase_hg2(0.9, -0.5, 0.85);
    double wm = 0;
    for (int k = 0; st == NBT_OK && k < 4; k++) {
        nbt_surface_geom geo = {0.4, 0.5, 1.0, 0.5 + 19.0 * uni(), M_PI * uni(), 0.5, 1.0, 0, 1};
        double L, E, R, RE;
        nbt_surface_direct(tt, &geo, 1e-8, &R, &RE);
        nbt_surface_table_hg_mix(t, NULL, 2, (double[]){0.85, 0.15}, (double[]){0.9, -0.5}, &geo, 0, &L, &E);
        wm = fmax(wm, (fabs(L - R) - RE) / fabs(R));
    }
    nbt_phase_free(tt);
    t_true(wm <= 1e-2, "two-term HG surface radiance within 1e-2 of its direct integral (worst %.2e)", wm);
    nbt_table_free(t);
}

/* The per-g-cell record takes both quadratic stencils that meet at a g
 * midpoint: a lookup just below the midpoint of cell m interpolates slices
 * m-1..m+1, just above it m..m+2 (nbt_table_lookup3), and either may be the
 * worse. In the planner's J tables (log_et form, atanh g) the two differ by
 * 15% at most and the in-slice term 1.25 se of the record covers that, so a
 * record from one stencil looks fine there. J^1 in the plain form on g's cos
 * axis over [-0.9, 0.9] with 5 slices (17 x 17 T, theta nodes) curves
 * unevenly in g: in the cell g in [0, 0.64] the stencil below the midpoint
 * errs by 1.46 at worst, the one above by 0.33, and a record of the upper
 * stencil alone (0.51) would be 2.9x too small. At every (T, theta) node,
 * where the in-slice interpolation is exact, |lookup3 - exact| just below
 * and just above every g midpoint must lie within the cell's record; exact:
 * fixed-phase J^1 tables built at the midpoint g (nbt_j_table_build, not the
 * g-sliced one-pass fill; float storage), and the worst node once against
 * nbt_j_phase's integral. */
static void test_cell_stencils(void)
{
    nbt_axis a0 = {0, 2.0, NBT_AXIS_LOG1P_CBRT, 10.0, 17}, a1 = {0, M_PI, NBT_AXIS_LINEAR, 0, 17};
    nbt_axis a2 = {-0.9, 0.9, NBT_AXIS_COS, 0, 5};
    nbt_table *t = nbt_table_alloc3(NBT_TABLE_J, &a0, &a1, &a2, 1);
    t->n = 1;
    t->form = NBT_FORM_PLAIN;
    t->interp2 = 2;
    nbt_build_opts o = {1e-10, 1, 2};
    nbt_status st = nbt_gslice_fill(t, &o);
    t_true(st == NBT_OK, "plain J^1 17x17x5, quadratic in g: fill");
    if (st != NBT_OK) {
        nbt_table_free(t);
        return;
    }
    double worst_ratio = 0, spread = 0, wT = 0, wth = 0, wg = 0, wv = 0;
    for (size_t m = 0; m + 1 < a2.n; m++) {
        double gm = nbt_axis_from_unit(&a2, ((double)m + 0.5) / (double)(a2.n - 1)), e[2] = {0, 0};
        nbt_table *s = nbt_table_alloc(NBT_TABLE_J, &a0, &a1, 1);
        nbt_phase *p = nbt_phase_hg(gm);
        s->n = 1;
        s->k[0] = -1;
        nbt_build_opts os = {1e-10, 0, 2};
        t_true(nbt_j_table_build(s, p, &os) == NBT_OK, "fixed-phase J^1 at g = %.4f", gm);
        for (int side = 0; side < 2; side++) {
            double g = gm + (side ? 1e-9 : -1e-9), bound = nbt_table_err_at(t, 0, g);
            for (size_t j = 0; j < a1.n; j++)
                for (size_t i = 0; i < a0.n; i++) {
                    double T = nbt_axis_node(&a0, i), th = nbt_axis_node(&a1, j), v, ex = s->data[j * a0.n + i];
                    nbt_table_lookup3(t, T, th, g, &v);
                    double d = fabs(v - ex);
                    if (d > e[side])
                        e[side] = d;
                    if (d / bound > worst_ratio)
                        worst_ratio = d / bound, wT = T, wth = th, wg = gm, wv = ex;
                }
        }
        spread = fmax(spread, fmax(e[0], e[1]) / fmin(e[0], e[1]));
        nbt_phase_free(p);
        nbt_table_free(s);
    }
    t_true(worst_ratio <= 1.0, "plain J^1 quadratic in g: |lookup - exact| at every node just below and above every g "
           "midpoint within the cell's record (worst %.2f of it)", worst_ratio);
    t_true(spread > 3.0, "the two stencils at a g midpoint differ (worst/best up to %.1f)", spread);
    double ex, ee;
    nbt_phase *p = nbt_phase_hg(wg);
    nbt_j_phase(p, 1, wT, wth, 1e-11, &ex, &ee);
    nbt_phase_free(p);
    t_rel(wv, ex, 1e-6, "the reference at the worst node (T %.3f, theta %.3f, g %.4f) = nbt_j_phase", wT, wth, wg);
    nbt_table_free(t);
}

/* basis legendre for a g range no Legendre series within 512 orders serves: refused, and the
 * message says "more than 512" (the planner reports 513 for "not reached by 512") */
static void test_basis_legendre_out_of_reach(void)
{
    nbt_gslice_request r = {NBT_TABLE_H, 0, 10.0, {-0.99, 0.99}, 1e-3, {0, 0, 0}, 0};
    nbt_basis_choice ch;
    char err[512] = "";
    nbt_status st = nbt_basis_choose(&r, 512, NBT_BASIS_LEGENDRE, 2, &ch, err, sizeof err);
    t_true(st == NBT_ETOL && strstr(err, "needs more than 512 Legendre orders at tol 0.001"),
           "basis legendre, |g| to 0.99 at 1e-3: ETOL naming 'more than 512' (%d: %s)", st, err);
}

int main(void)
{
    /* the bases' documented names (nbt/gslice.h), parse inverts name, others refused */
    {
        static const char *const bn[3] = {"auto", "legendre", "slices"};
        int ok = 1;
        for (int i = 0; i < 3; i++) {
            nbt_basis b = (nbt_basis)-1;
            ok &= !strcmp(nbt_basis_name((nbt_basis)i), bn[i]) && nbt_basis_parse(bn[i], &b) == NBT_OK &&
                  b == (nbt_basis)i;
        }
        nbt_basis b;
        t_true(ok && nbt_basis_parse("slice", &b) == NBT_EINVAL, "basis names auto, legendre, slices; 'slice' refused");
    }
    nbt_table *H = small_table(NBT_TABLE_H, 0, 97, 97, 9, -0.4, 0.5);
    nbt_table *J = small_table(NBT_TABLE_J, 1, 33, 33, 9, -0.5, 0.7);
    t_true(nbt_table_is_gslice(H) && nbt_table_is_gslice(J), "fill marks the tables g-sliced");
    check_tail(H, 200);
    check_table(J, 80);
    test_tail_cubic();
    test_plan_execute();
    test_scene_basis();
    /* the plain form (older files) still builds and bounds its error */
    nbt_table *P = nbt_table_alloc3(NBT_TABLE_H, &H->axis[0], &H->axis[1],
                                    &(nbt_axis){-0.4, 0.5, NBT_AXIS_COS, 0, 9}, 1);
    nbt_build_opts po = {1e-10, 1, 2};
    t_true(nbt_gslice_fill_form(P, NBT_FORM_PLAIN, &po) == NBT_OK && P->form == NBT_FORM_PLAIN && P->nch == 1,
           "plain-form H fill");
    check_table(P, 100);
    /* a plain-form file (as written before the tail form) reads back plain and still evaluates:
     * the difference of two lookups with its bound, or the ray integral */
    nbt_table *Pb = exr_round_trip(P);
    nbt_status pst = Pb ? NBT_OK : NBT_EIO;
    t_true(Pb && Pb->form == NBT_FORM_PLAIN && Pb->nch == 1 && nbt_table_is_gslice(Pb),
           "plain-form file reads back plain");
    for (int i = 0; pst == NBT_OK && i < 6; i++) {
        nbt_airlight_geom geo = {0.3, 0.5, 2.0, 1.0 + 3.0 * uni(), 0.1 + 2.9 * uni(), i % 2 ? INFINITY : 3.0};
        double g = -0.4 + 0.9 * uni(), L, E, R, RE;
        nbt_phase *ph = nbt_phase_hg(g);
        nbt_airlight_direct(ph, &geo, 1e-10, &R, &RE);
        nbt_phase_free(ph);
        nbt_status est = nbt_airlight_table_g(Pb, g, &geo, &L, &E);
        t_true(est == NBT_OK && fabs(L - R) <= E + RE + 1e-12 * fabs(R),
               "plain file: airlight_table_g g=%.3f gamma=%.3f: |%.8g - %.8g| <= bound %.2e", g, geo.gamma, L, R, E);
    }
    nbt_table_free(Pb);
    nbt_table_free(P);
    test_airlight(H);
    test_surface(J);
    test_errors(H, J);
    test_basis_legendre_out_of_reach();
    test_build_io();
    test_log_form();
    test_cell_stencils();
    test_one_pass();
    nbt_table_free(H);
    nbt_table_free(J);
    return t_done();
}
