#define _GNU_SOURCE 1 /* memmem */
/* tests/test_table.c: axis maps, GPU-equivalent bilinear lookup, half
 * rounding, EXR round trips and bad files, recorded H interpolation error. */
#include <math.h>
#include <stdio.h>
#include <string.h>
#include <stdint.h>
#include <unistd.h>
#include <nbt/nbt.h>
#include "testutil.h"

/* What a GPU does: texcoord tc = (s(N-1) + 0.5)/N, texel space p = tc N - 0.5, clamp. */
static double hand_bilinear(const nbt_table *t, double x0, double x1, size_t c)
{
    size_t i[2];
    double f[2];
    for (int a = 0; a < 2; a++) {
        double s = nbt_axis_to_unit(&t->axis[a], a ? x1 : x0), N = (double)t->axis[a].n;
        double tc = (s * (N - 1) + 0.5) / N, p = tc * N - 0.5;
        double fl = floor(p);
        if (fl > N - 2)
            fl = N - 2;
        i[a] = (size_t)fl;
        f[a] = p - fl;
    }
    size_t nx = t->axis[0].n, nc = t->nch;
#define V(a, b) ((double)t->data[((i[1] + (b)) * nx + i[0] + (a)) * nc + c])
    return (1 - f[1]) * ((1 - f[0]) * V(0, 0) + f[0] * V(1, 0)) + f[1] * ((1 - f[0]) * V(0, 1) + f[0] * V(1, 1));
#undef V
}

/* progress calls of nbt_table_write_exr_progress */
typedef struct {
    int n;
    double f[64];
} wrec;
static void on_write(double f, void *vp)
{
    wrec *w = vp;
    if (w->n < 64)
        w->f[w->n] = f;
    w->n++;
}

static int same_tables(const nbt_table *a, const nbt_table *b)
{
    if (a->kind != b->kind || a->nch != b->nch || a->n != b->n || a->half != b->half || strcmp(a->phase, b->phase))
        return 0;
    for (int i = 0; i < 3; i++)
        if (a->axis[i].n != b->axis[i].n || a->axis[i].lo != b->axis[i].lo || a->axis[i].hi != b->axis[i].hi ||
            a->axis[i].map != b->axis[i].map || a->axis[i].c != b->axis[i].c)
            return 0;
    for (size_t c = 0; c < a->nch; c++)
        if (a->k[c] != b->k[c] || a->max_err[c] != b->max_err[c] || a->max_abs[c] != b->max_abs[c])
            return 0;
    if (a->form != b->form || a->interp2 != b->interp2 || !a->cell_err != !b->cell_err)
        return 0;
    for (size_t i = 0; a->cell_err && i < (a->axis[2].n - 1) * a->nch; i++) /* NaN: not recorded */
        if (!(a->cell_err[i] == b->cell_err[i] || (isnan(a->cell_err[i]) && isnan(b->cell_err[i]))))
            return 0;
    return !memcmp(a->data, b->data, nbt_table_size(a) * sizeof(float)) &&
           a->quad_tol == b->quad_tol && a->quad_err == b->quad_err;
}

/* Replace the first occurrence of `from` in a file by `to` (same length), or
 * with to == NULL set the int32 value of the int attribute named `from`:
 * corrupts one header attribute of an EXR for the reader's error paths. */
static int patch_file(const char *path, const char *from, const char *to, int32_t ival)
{
    FILE *f = fopen(path, "r+b");
    if (!f)
        return 0;
    static char buf[1 << 16];
    size_t n = fread(buf, 1, sizeof buf, f), fl = strlen(from) + 1;
    int ok = 0;
    for (size_t i = 0; i + fl + 12 <= n && !ok; i++)
        if (!memcmp(buf + i, from, fl - (to != NULL))) {
            size_t at = to ? i : i + fl + 4 + 4; /* name, "int", size */
            if (to)
                memcpy(buf + at, to, fl - 1);
            else
                memcpy(buf + at, &ival, 4);
            ok = fseek(f, 0, SEEK_SET) == 0 && fwrite(buf, 1, n, f) == n;
        }
    fclose(f);
    return ok;
}

static int quad_fn(double x0, double x1, double *out, void *ctx)
{
    (void)ctx;
    out[0] = x0 * x0 + 3 * x1;
    return 0;
}
static int saddle_fn(double x0, double x1, double *out, void *ctx)
{
    (void)ctx;
    out[0] = x0 * x0 - x1 * x1;
    return 0;
}
static int exp_fn(double x0, double x1, double *out, void *ctx)
{
    (void)ctx;
    out[0] = exp(2.7 * x0) * (1 + 0.4 * x1);
    return 0;
}
static int bowl_fn(double x0, double x1, double *out, void *ctx)
{
    (void)ctx;
    out[0] = x0 * x0 + x1 * x1;
    return 0;
}
/* a bump about a cell wide, its curvature peaking in a cell the H and J
 * fills would estimate from second differences (cell 13 of 16 below) */
#define BUMP_C (-1.3 + 13.5 * 3.8 / 16)
static int bump_fn(double x0, double x1, double *out, void *ctx)
{
    (void)ctx;
    (void)x1;
    out[0] = exp(-(x0 - BUMP_C) * (x0 - BUMP_C) / (0.3 * 0.3));
    return 0;
}
static int fail_fn(double x0, double x1, double *out, void *ctx)
{
    (void)x0;
    (void)x1;
    (void)out;
    (void)ctx;
    return 1;
}

/* (0.5, x0, -2 x1): the largest |value| sits in the last channel */
static int lin3_fn(double x0, double x1, double *out, void *ctx)
{
    (void)ctx;
    out[0] = 0.5;
    out[1] = x0;
    out[2] = -2 * x1;
    return 0;
}

/* The axis maps at an interior point against the header's formulas written
 * here (the round trip above cannot see a bug made in both directions), the
 * recorded max |value| of a non-square 3-channel table, and the documented
 * names. r = 0.3 and s = 0.3 are not symmetric points of any map. */
/* nbt_table_lookup and nbt_table_lookup_grid on a non-square 2-D table (7 x 5, two
 * channels) of a function bilinear in (x0, x1) on linear axes: bilinear interpolation
 * reproduces it, so the closed form is the reference to the float rounding of the
 * nodes (2e-7 of the largest value, here ~13). A swapped stride, axis or channel, or
 * an off-by-one in the cell index, shows at the asymmetric points (last cell,
 * both ends of each axis, outside: clamped). */
static double bilin(int c, double x0, double x1)
{
    return c == 0 ? 0.7 - 1.3 * x0 + 2.1 * x1 + 0.9 * x0 * x1 : -2.0 + 0.4 * x0 - 3.3 * x1 - 1.7 * x0 * x1;
}
static void test_lookup_bilinear(void)
{
    nbt_axis a0 = {-0.4, 2.3, NBT_AXIS_LINEAR, 0, 7}, a1 = {1.1, 1.9, NBT_AXIS_LINEAR, 0, 5};
    nbt_table *t = nbt_table_alloc(NBT_TABLE_H, &a0, &a1, 2);
    for (size_t j = 0; j < 5; j++)
        for (size_t i = 0; i < 7; i++)
            for (int c = 0; c < 2; c++)
                t->data[(j * 7 + i) * 2 + c] = (float)bilin(c, nbt_axis_node(&a0, i), nbt_axis_node(&a1, j));
    const double pts[][2] = {{-0.4, 1.1}, {2.3, 1.9}, {2.3, 1.1}, {-0.4, 1.9}, {2.21, 1.87}, {0.123, 1.234},
                             {1.7, 1.35}, {-0.35, 1.88}, {2.29, 1.12}};
    double worst = 0, v[2];
    for (size_t p = 0; p < sizeof pts / sizeof pts[0]; p++) {
        nbt_table_lookup(t, pts[p][0], pts[p][1], v);
        for (int c = 0; c < 2; c++)
            worst = fmax(worst, fabs(v[c] - bilin(c, pts[p][0], pts[p][1])));
    }
    t_true(worst < 2e-6, "lookup of a bilinear function on a 7x5 table: within %.2g of the closed form", worst);
    /* outside the axes: clamped to the edge (CLAMP_TO_EDGE) */
    nbt_table_lookup(t, 3.0, 0.5, v);
    t_abs(v[1], bilin(1, 2.3, 1.1), 2e-6, "beyond hi of axis 0 and below lo of axis 1: the corner value");
    /* the grid lookup: 3 x 4 points (non-square), out[(j n0 + i) nch + c] */
    const double g0[] = {2.25, -0.1, 1.05}, g1[] = {1.85, 1.15, 1.5, 1.899};
    double out[3 * 4 * 2];
    t_true(nbt_table_lookup_grid(t, g0, 3, g1, 4, out) == NBT_OK, "lookup_grid 3x4");
    int same = 1;
    worst = 0;
    for (size_t j = 0; j < 4; j++)
        for (size_t i = 0; i < 3; i++) {
            nbt_table_lookup(t, g0[i], g1[j], v);
            for (int c = 0; c < 2; c++) {
                same &= out[(j * 3 + i) * 2 + c] == v[c];
                worst = fmax(worst, fabs(out[(j * 3 + i) * 2 + c] - bilin(c, g0[i], g1[j])));
            }
        }
    t_true(same && worst < 2e-6, "lookup_grid = lookup at each point (%d), within %.2g of the closed form", same, worst);
    nbt_table_free(t);
}

/* nbt_table_row_err_alloc on a 7 x 5 x 4 table of 3 channels: (4-1)(7-1)3 = 54 NaN
 * values (NaN: the table's max_err applies); a value set in row cell 5 (the last),
 * g cell 2 (the last), channel 2 is what nbt_table_err_at_row reads there and only
 * there; a second alloc replaces it with NaN again. 2-D: (7-1)3 values. */
static void test_row_err_alloc(void)
{
    nbt_axis a0 = {0, 3, NBT_AXIS_LINEAR, 0, 7}, a1 = {-1, 1, NBT_AXIS_LINEAR, 0, 5}, a2 = {-0.5, 0.7, NBT_AXIS_LINEAR, 0, 4};
    nbt_table *t = nbt_table_alloc3(NBT_TABLE_J, &a0, &a1, &a2, 3);
    for (int c = 0; c < 3; c++)
        t->max_err[c] = 0.25 * (c + 1); /* exact: 0.25, 0.5, 0.75 */
    t_true(nbt_table_row_err_alloc(t) == NBT_OK && nbt_table_row_err_len(t) == 54, "row_err: 54 values (%zu)",
           nbt_table_row_err_len(t));
    int allnan = 1;
    for (size_t i = 0; i < 54; i++)
        allnan &= isnan(t->row_err[i]) != 0;
    t->row_err[(2 * 6 + 5) * 3 + 2] = 7e-4;
    double in = nbt_table_err_at_row(t, 2, 2.9, 0.65), other_c = nbt_table_err_at_row(t, 1, 2.9, 0.65),
           other_i = nbt_table_err_at_row(t, 2, 2.4, 0.65), other_m = nbt_table_err_at_row(t, 2, 2.9, 0.25);
    t_true(allnan && in == 7e-4 && other_c == 0.5 && other_i == 0.75 && other_m == 0.75,
           "row_err: all NaN (%d); set at (i 5, g cell 2, c 2) it is read there (%g), elsewhere max_err (%g %g %g)",
           allnan, in, other_c, other_i, other_m);
    t_true(nbt_table_row_err_alloc(t) == NBT_OK && isnan(t->row_err[(2 * 6 + 5) * 3 + 2]) &&
               nbt_table_err_at_row(t, 2, 2.9, 0.65) == 0.75, "row_err: a second alloc replaces it (NaN again)");
    nbt_table_free(t);
    t = nbt_table_alloc(NBT_TABLE_H, &a0, &a1, 3);
    t_true(nbt_table_row_err_alloc(t) == NBT_OK && nbt_table_row_err_len(t) == 18, "row_err of a 2-D 7x5 table: 18 values");
    nbt_table_free(t);
}

static void test_maps_closed_forms(void)
{
    const double r = 0.3;
    struct {
        nbt_axis a;
        double s;
    } m[6] = {{{-1.5, 2.385, NBT_AXIS_LINEAR, 0, 9}, r},
              {{0, 10, NBT_AXIS_SQRT, 0, 9}, sqrt(r)},
              {{0, 10, NBT_AXIS_LOG1P, 100, 9}, log(1 + 100 * r) / log(101.0)},
              {{0, 3, NBT_AXIS_LOG1P, -0.99, 9}, log(1 - 0.99 * r) / log(0.01)},
              {{-M_PI_2, M_PI_2, NBT_AXIS_COS, 0, 9}, acos(1 - 2 * r) / M_PI},
              {{-0.95, 0.9, NBT_AXIS_ATANH, 0, 7}, 0}};
    /* atanh: x = lo + r (hi - lo) = -0.395, s = (atanh x - atanh lo)/(atanh hi - atanh lo) */
    m[5].s = (atanh(-0.395) - atanh(-0.95)) / (atanh(0.9) - atanh(-0.95));
    for (int i = 0; i < 6; i++) {
        const nbt_axis *a = &m[i].a;
        double x = a->lo + r * (a->hi - a->lo);
        t_rel(nbt_axis_to_unit(a, x), m[i].s, 1e-13, "%s(c=%g) at r = 0.3: s = %.15g", nbt_axis_map_name(a->map), a->c,
              m[i].s);
        t_rel(nbt_axis_from_unit(a, m[i].s), x, 1e-13, "%s(c=%g): from_unit(%.6g) = %.15g", nbt_axis_map_name(a->map),
              a->c, m[i].s, x);
    }
    /* node 2 of 7 of the linear axis (-1.5 .. 2.385): lo + (2/6)(hi - lo) */
    t_rel(nbt_axis_node(&(nbt_axis){-1.5, 2.385, NBT_AXIS_LINEAR, 0, 7}, 2), -1.5 + 3.885 / 3, 1e-15, "linear node 2 of 7");

    nbt_axis a0 = {-1.5, 2.385, NBT_AXIS_LINEAR, 0, 7}, a1 = {0, 3, NBT_AXIS_LINEAR, 0, 5};
    nbt_table *t = nbt_table_alloc(NBT_TABLE_J, &a0, &a1, 3);
    t_true(t && nbt_table_tabulate(t, lin3_fn, NULL, 1) == NBT_OK, "tabulate (0.5, x0, -2 x1) on 7 x 5");
    if (t) {
        /* linear in each cell: the largest |value| is at the nodes: 0.5, 2.385, 2 3 = 6
         * (0.5 and 6 exact in float; 2.385 to float rounding, 1e-6) */
        t_true(t->max_abs[0] == 0.5 && fabs(t->max_abs[1] - 2.385) < 1e-6 && t->max_abs[2] == 6,
               "max |value| per channel (0.5, 2.385, 6): (%g, %g, %g)", t->max_abs[0], t->max_abs[1], t->max_abs[2]);
        t_true(nbt_table_max_abs(t) == 6, "nbt_table_max_abs over the channels = 6 (the last): %g", nbt_table_max_abs(t));
        nbt_table_free(t);
    }
    /* names as nbt/table.h documents them, and parse inverts name */
    static const char *const forms[3] = {"plain", "tail", "log_et"};
    int ok = 1;
    for (int f = 0; f < 3; f++) {
        nbt_table_form g = (nbt_table_form)-1;
        ok &= !strcmp(nbt_table_form_name((nbt_table_form)f), forms[f]) && nbt_table_form_parse(forms[f], &g) == NBT_OK &&
              g == (nbt_table_form)f;
    }
    nbt_table_form g;
    t_true(ok && nbt_table_form_parse("log", &g) == NBT_EFORMAT, "forms plain, tail, log_et; 'log' refused");
    static const char *const ax[4][3] = {{"u", "v", "g"}, {"T", "theta", "g"}, {"r/z", "z", "slice"}, {"tau", "albedo", "slice"}};
    ok = 1;
    for (int k = 0; k < 4; k++)
        for (int i = 0; i < 3; i++)
            ok &= !strcmp(nbt_table_axis_name((nbt_table_kind)k, i), ax[k][i]);
    t_true(ok, "axis names of H, J, PSI, KERNEL as documented");
}

/* Form sub (issue 21; doc/tables.md, "33^2 at 1e-3"): the default scene's
 * tables (H_0..3, J_0..3^1, J_0..3^20 over [0, 10] on the planner's
 * mappings) hold the value minus a fitted closed form S = d(x) sum c_q b_q(y)
 * that the lookup adds back. At 33^2 they record <= 1e-3 relative (plain:
 * 1.36e-3, 1.78e-3, 1.60e-3), the lookup is within 1e-3 and within the
 * recorded error of nbt_hk/nbt_jk at random points (the bilinear error of
 * the remainder peaks at cell midpoints, which the measurement visits), and
 * the error still falls as h^2 (33^2 -> 65^2 ratio >= 3.5: recorded 3.66,
 * 3.59, 3.63). H's S is exact: H_k(0, v) = int P_k(-sin t) dt lies in the
 * span of 1, v, cos mv, sin mv, so S must equal nbt_hk(u = 0)/(1 + u) to the
 * float coefficients' rounding (1e-6 of H_0's scale pi); J's decays as e^-T. */
static void test_form_sub(void)
{
    const char *name[3] = {"H", "J^1", "J^20"};
    double rel33[3] = {0}, rel65[3] = {0};
    for (int s = 0; s < 3; s++) {
        int n = s == 0 ? 0 : s == 1 ? 1 : 20;
        nbt_table *t[2] = {NULL, NULL};
        for (int z = 0; z < 2; z++) {
            size_t N = z ? 65 : 33;
            nbt_axis a0 = {0, 10, NBT_AXIS_LOG1P_CBRT, 10, N};
            nbt_axis a1 = s == 0   ? (nbt_axis){-M_PI_2, M_PI_2, NBT_AXIS_COS, 0, N}
                          : s == 1 ? (nbt_axis){0, M_PI, NBT_AXIS_ASINH, 1, N}
                                   : (nbt_axis){0, M_PI, NBT_AXIS_LOG1P, 20, N};
            t[z] = nbt_table_alloc(s ? NBT_TABLE_J : NBT_TABLE_H, &a0, &a1, 4);
            for (int c = 0; c < 4; c++)
                t[z]->k[c] = c;
            t[z]->n = n;
            t[z]->form = NBT_FORM_SUB;
            nbt_build_opts o = {1e-10, 1, 2};
            nbt_status st = s ? nbt_j_table_build(t[z], NULL, &o) : nbt_h_table_build(t[z], NULL, &o);
            t_true(st == NBT_OK, "%s %zu^2 form sub built", name[s], N);
            (z ? rel65 : rel33)[s] = nbt_table_max_err(t[z]) / t[z]->max_abs[0];
        }
        nbt_table *a = t[0];
        /* max_abs is the quantity's: H_0's largest value is H_0(0, pi/2) = pi */
        if (s == 0)
            t_rel(a->max_abs[0], M_PI, 1e-6, "H sub: max_abs[0] is H_0's largest value pi, not the remainder's");
        t_true(rel33[s] <= 1e-3, "%s form sub at 33^2: recorded relative error %.3g <= 1e-3", name[s], rel33[s]);
        t_true(rel33[s] / rel65[s] >= 3.5, "%s form sub: recorded %.3g at 33^2, %.3g at 65^2, ratio %.2f >= 3.5",
               name[s], rel33[s], rel65[s], rel33[s] / rel65[s]);
        /* random points, uniform in unit coordinates (u, T -> 0 as densely
         * as the nodes), the last cells included */
        double worst = 0, wr = 0, ex[4], ee[4], lk[4];
        for (int q = 0; q < 120; q++) {
            double x = nbt_axis_from_unit(&a->axis[0], t_uniform()), y = nbt_axis_from_unit(&a->axis[1], t_uniform());
            if (q == 0) { /* the last cell on both axes */
                x = nbt_axis_from_unit(&a->axis[0], 0.99);
                y = nbt_axis_from_unit(&a->axis[1], 0.995);
            }
            if (s)
                nbt_jk(3, n, x, y, 1e-11, ex, ee);
            else
                nbt_hk(3, x, y, 1e-12, ex, ee);
            nbt_table_lookup(a, x, y, lk);
            for (int c = 0; c < 4; c++) {
                worst = fmax(worst, fabs(lk[c] - ex[c]) + ee[c]);
                wr = fmax(wr, (fabs(lk[c] - ex[c]) - ee[c]) / a->max_err[c]);
            }
        }
        t_true(worst <= 1e-3 * a->max_abs[0] && wr <= 1.0,
               "%s form sub 33^2: lookup within 1e-3 of the exact values at random points (%.3g) and within the "
               "recorded error (worst ratio %.2f)", name[s], worst / a->max_abs[0], wr);
        /* the grid lookup adds the same S; outside the range S is clamped as the bilinear part is */
        double xg[3] = {0.013, 2.7, 10}, yg[2], g[3 * 2 * 4], one[4], clamp[4], edge[4];
        yg[0] = a->axis[1].lo + 0.3 * (a->axis[1].hi - a->axis[1].lo);
        yg[1] = a->axis[1].hi;
        int same = nbt_table_lookup_grid(a, xg, 3, yg, 2, g) == NBT_OK;
        for (int j = 0; j < 2; j++)
            for (int i = 0; i < 3; i++) {
                nbt_table_lookup(a, xg[i], yg[j], one);
                for (int c = 0; c < 4; c++)
                    same &= fabs(g[(j * 3 + i) * 4 + c] - one[c]) <= 1e-12 * a->max_abs[0];
            }
        nbt_table_lookup(a, 13.0, yg[0], clamp);
        nbt_table_lookup(a, 10.0, yg[0], edge);
        for (int c = 0; c < 4; c++)
            same &= fabs(clamp[c] - edge[c]) <= 1e-12 * a->max_abs[0];
        t_true(same, "%s form sub: lookup_grid equals lookup; x0 = 13 beyond the range reads x0 = 10", name[s]);
        if (s == 0) {
            double dmax = 0, h0[4], e0[4];
            for (int q = 0; q < 9; q++) {
                double u = q * 1.25, v = -M_PI_2 + M_PI * (q + 0.5) / 9.0;
                nbt_hk(3, 0, v, 1e-13, h0, e0);
                for (int c = 0; c < 4; c++)
                    dmax = fmax(dmax, fabs(nbt_table_sub(a, (size_t)c, u, v) - h0[c] / (1.0 + u)));
            }
            t_abs(dmax, 0, 1e-6 * M_PI, "H sub: S = H_k(0, v)/(1 + u) at 9 points, every order");
        } else {
            double dmax = 0;
            for (int c = 0; c < 4; c++)
                dmax = fmax(dmax, fabs(nbt_table_sub(a, (size_t)c, 2.5, 0.7) -
                                       exp(-2.5) * nbt_table_sub(a, (size_t)c, 0, 0.7)));
            t_abs(dmax, 0, 1e-12 * a->max_abs[0], "%s sub: S decays as e^-T", name[s]);
        }
        /* EXR round trip: form, decay, w and coefficients exact, lookups bit-equal */
        char path[] = "/tmp/nbt-test-subXXXXXX", err[512];
        int fd = mkstemp(path);
        close(fd);
        nbt_table *r = NULL;
        int ok = nbt_table_write_exr(a, path, NBT_EXR_ZIP) == NBT_OK &&
                 nbt_table_read_exr(path, &r, err, sizeof err) == NBT_OK;
        ok = ok && r->form == NBT_FORM_SUB && r->sub_decay == a->sub_decay && r->sub_w == a->sub_w &&
             !memcmp(r->sub_c, a->sub_c, sizeof a->sub_c);
        for (int q = 0; ok && q < 20; q++) {
            double x = 10 * t_uniform(), y = nbt_axis_from_unit(&a->axis[1], t_uniform()), la[4], lb[4];
            nbt_table_lookup(a, x, y, la);
            nbt_table_lookup(r, x, y, lb);
            ok = !memcmp(la, lb, sizeof la);
        }
        t_true(ok, "%s form sub: EXR round trip keeps form, decay (%s), w (%g), coefficients and lookups", name[s],
               a->sub_decay == NBT_SUB_EXP ? "exp" : "recip", a->sub_w);
        nbt_table_free(r);
        r = NULL;
        if (s == 2) { /* a file whose coefficients went missing is refused, not read as a plain table */
            int pt = patch_file(path, "nbt.sub.R", "nbt.sub.X", 0);
            nbt_status st = nbt_table_read_exr(path, &r, err, sizeof err);
            t_true(pt && st == NBT_EFORMAT && r == NULL && strstr(err, "nbt.sub.R"),
                   "form sub without nbt.sub.R: refused (%s)", err);
        }
        unlink(path);
        nbt_table_free(t[0]);
        nbt_table_free(t[1]);
    }
    /* form sub is for 2-D H and J tables */
    nbt_axis p0 = {0, 1, NBT_AXIS_LINEAR, 0, 5}, p1 = {0, 1, NBT_AXIS_LINEAR, 0, 4};
    nbt_table *tp = nbt_table_alloc(NBT_TABLE_PSI, &p0, &p1, 1);
    tp->form = NBT_FORM_SUB;
    t_true(nbt_table_tabulate(tp, quad_fn, NULL, 1) == NBT_EINVAL, "form sub on a PSI table: NBT_EINVAL");
    nbt_table_free(tp);
}

int main(void)
{
    /* ---- axis maps ---- */
    nbt_axis maps[8] = {{-1.5, 2.385, NBT_AXIS_LINEAR, 0, 9}, {0, 10, NBT_AXIS_SQRT, 0, 9},
                        {0, 10, NBT_AXIS_LOG1P, 100, 9},     {0, 3, NBT_AXIS_LOG1P, -0.99, 9},
                        {-M_PI_2, M_PI_2, NBT_AXIS_COS, 0, 9}, {0, 12.5, NBT_AXIS_LOG1P_CBRT, 12.5, 9},
                        {0.25, M_PI, NBT_AXIS_ASINH, 3, 9},  {-M_PI_2, M_PI_2, NBT_AXIS_ENDS, 16, 9}};
    for (int m = 0; m < 8; m++) {
        double worst = 0;
        for (double s = 0; s <= 1.0; s += 1.0 / 64)
            worst = fmax(worst, fabs(nbt_axis_to_unit(&maps[m], nbt_axis_from_unit(&maps[m], s)) - s));
        t_abs(worst, 0, 1e-13, "%s(c=%g): to_unit(from_unit(s)) = s", nbt_axis_map_name(maps[m].map), maps[m].c);
        t_true(nbt_axis_node(&maps[m], 0) == maps[m].lo && nbt_axis_node(&maps[m], 8) == maps[m].hi,
               "%s: first and last nodes are exactly the range ends", nbt_axis_map_name(maps[m].map));
        t_true(nbt_axis_to_unit(&maps[m], maps[m].lo - 5) == 0 && nbt_axis_to_unit(&maps[m], maps[m].hi + 5) == 1,
               "%s: clamped outside the range", nbt_axis_map_name(maps[m].map));
    }
    nbt_axis_map mm;
    t_true(nbt_axis_map_parse("cubic", &mm) == NBT_EFORMAT, "unknown mapping name rejected");
    t_true(nbt_axis_map_parse("log1p_cbrt", &mm) == NBT_OK && mm == NBT_AXIS_LOG1P_CBRT, "log1p_cbrt parses");
    /* log1p_cbrt: s = cbrt(log1p(c r)/log1p(c)), closed form at r = 0.3 */
    t_rel(nbt_axis_to_unit(&maps[5], 0.3 * 12.5), cbrt(log(1 + 12.5 * 0.3) / log(13.5)), 1e-15, "log1p_cbrt at r = 0.3");
    /* near lo, x - lo ~ s^3 (what makes u log u smooth): x(s)/s^3 -> (hi - lo) log1p(c)/c */
    t_rel(nbt_axis_from_unit(&maps[5], 1e-3) / 1e-9, 12.5 * log(13.5) / 12.5, 1e-6, "log1p_cbrt: x ~ s^3 near lo");
    nbt_axis badc = {0, 1, NBT_AXIS_LOG1P_CBRT, -0.5, 9};
    t_true(nbt_table_alloc(NBT_TABLE_H, &badc, &maps[4], 1) == NULL, "log1p_cbrt with c <= 0 rejected");
    /* asinh: s = 1/2 + asinh(c (2r - 1))/(2 asinh c), closed form at r = 0.3
     * (log form of asinh); the middle maps to s = 1/2; node spacing at the
     * middle and at the ends against linear: asinh(c)/c and
     * asinh(c) sqrt(1 + c^2)/c (derivative of the inverse) */
    /* ends (c = 16 as the planner writes H's v): log1p with c/2 = 8 from lo,
     * c = 16 from hi, split at s = f where the slopes meet:
     * f = k1/(k1 + k2), k1 = log(9) 9/8, k2 = log(17) 17/16 (the slopes
     * ds/dr of each half at r = 1/2, up to the common factor 2).
     * Closed forms at r = 0.3 and r = 0.8 (one point per half, so that c/2
     * and c swapped or a half's formula on the other side shows); the middle
     * at s = f with equal one-sided slopes (C^1); node spacing at lo and hi
     * 1/9 and 1/17 of the middle's */
    t_true(nbt_axis_map_parse("ends", &mm) == NBT_OK && mm == NBT_AXIS_ENDS && !strcmp(nbt_axis_map_name(mm), "ends"),
           "ends parses and names itself");
    {
        const nbt_axis *en = &maps[7];
        double L = M_PI, k1 = log(9.0) * 9.0 / 8.0, k2 = log(17.0) * 17.0 / 16.0, f = k1 / (k1 + k2);
        t_rel(nbt_axis_to_unit(en, en->lo + 0.3 * L), f * log(1 + 16 * 0.3) / log(9.0), 1e-14, "ends at r = 0.3");
        t_rel(nbt_axis_to_unit(en, en->lo + 0.8 * L), 1 - (1 - f) * log(1 + 32 * 0.2) / log(17.0), 1e-14,
              "ends at r = 0.8");
        t_abs(nbt_axis_from_unit(en, f), 0.0, 1e-15, "ends: s = f is the middle of the range");
        double h = 1e-6, left = (nbt_axis_from_unit(en, f) - nbt_axis_from_unit(en, f - h)) / h;
        double right = (nbt_axis_from_unit(en, f + h) - nbt_axis_from_unit(en, f)) / h;
        t_rel(left, right, 1e-5, "ends: equal slopes on both sides of the middle (C^1)");
        double lo_sp = (nbt_axis_from_unit(en, h) - en->lo) / h, hi_sp = (en->hi - nbt_axis_from_unit(en, 1 - h)) / h;
        t_rel(left / lo_sp, 9.0, 1e-5, "ends: nodes 1 + c/2 = 9 times denser at lo than at the middle");
        t_rel(left / hi_sp, 17.0, 1e-5, "ends: nodes 1 + c = 17 times denser at hi than at the middle");
        nbt_axis e0 = {0, 1, NBT_AXIS_ENDS, 0, 9}, en2 = {0, 1, NBT_AXIS_ENDS, NAN, 9}, eb = {0, 1, NBT_AXIS_ENDS, 1001, 9};
        t_true(nbt_table_alloc(NBT_TABLE_H, &maps[5], &e0, 1) == NULL && nbt_table_alloc(NBT_TABLE_H, &maps[5], &en2, 1) == NULL &&
                   nbt_table_alloc(NBT_TABLE_H, &maps[5], &eb, 1) == NULL,
               "ends with c <= 0, NaN or > 1000 rejected");
    }
    t_true(nbt_axis_map_parse("asinh", &mm) == NBT_OK && mm == NBT_AXIS_ASINH, "asinh parses");
    {
        const nbt_axis *as = &maps[6];
        double L = as->hi - as->lo, z = 3 * (2 * 0.3 - 1), A = log(3 + sqrt(10.0));
        t_rel(nbt_axis_to_unit(as, as->lo + 0.3 * L), 0.5 - 0.5 * log(-z + sqrt(z * z + 1)) / A, 1e-14,
              "asinh at r = 0.3");
        t_abs(nbt_axis_to_unit(as, as->lo + 0.5 * L), 0.5, 1e-15, "asinh: the middle of the range at s = 1/2");
        double h = 1e-6, mid = (nbt_axis_from_unit(as, 0.5 + h) - nbt_axis_from_unit(as, 0.5 - h)) / (2 * h * L);
        double end = (nbt_axis_from_unit(as, h) - as->lo) / (h * L);
        t_rel(mid, A / 3, 1e-8, "asinh: spacing at the middle asinh(c)/c of linear");
        t_rel(end, A * sqrt(10.0) / 3, 1e-5, "asinh: spacing at the ends asinh(c) sqrt(1 + c^2)/c of linear");
        nbt_axis bad0 = {0, 1, NBT_AXIS_ASINH, 0, 9}, badn = {0, 1, NBT_AXIS_ASINH, NAN, 9};
        t_true(nbt_table_alloc(NBT_TABLE_H, &bad0, &maps[4], 1) == NULL &&
                   nbt_table_alloc(NBT_TABLE_H, &badn, &maps[4], 1) == NULL,
               "asinh with c <= 0 or NaN rejected");
    }

    test_maps_closed_forms();
    test_lookup_bilinear();
    test_row_err_alloc();
    test_form_sub();

    /* ---- lookup = hand bilinear, on a table of arbitrary values ---- */
    nbt_table *t = nbt_table_alloc(NBT_TABLE_J, &maps[2], &maps[3], 3);
    for (size_t i = 0; i < 9 * 9 * 3; i++)
        t->data[i] = (float)(t_uniform() * 4 - 2);
    double worst = 0;
    for (int j = 0; j < 500; j++) {
        double x0 = -1 + 12 * t_uniform(), x1 = -0.5 + 4 * t_uniform(), v[4];
        nbt_table_lookup(t, x0, x1, v);
        for (size_t c = 0; c < 3; c++)
            worst = fmax(worst, fabs(v[c] - hand_bilinear(t, x0, x1, c)));
    }
    t_abs(worst, 0, 1e-14, "lookup equals the GPU-style bilinear at 500 points (in and out of range)");
    /* the grid lookup (previews): the same bilinear at every grid point */
    {
        double gx[23], gy[17], gv[23 * 17 * 3], gw = 0;
        for (int i = 0; i < 23; i++)
            gx[i] = -1 + 12 * t_uniform();
        for (int j = 0; j < 17; j++)
            gy[j] = -0.5 + 4 * t_uniform();
        t_true(nbt_table_lookup_grid(t, gx, 23, gy, 17, gv) == NBT_OK, "grid lookup runs");
        for (int j = 0; j < 17; j++)
            for (int i = 0; i < 23; i++)
                for (size_t c = 0; c < 3; c++)
                    gw = fmax(gw, fabs(gv[(j * 23 + i) * 3 + c] - hand_bilinear(t, gx[i], gy[j], c)));
        t_abs(gw, 0, 1e-14, "grid lookup equals the GPU-style bilinear at 23 x 17 points (in and out of range)");
    }
    double v[4];
    nbt_table_lookup(t, nbt_axis_node(&maps[2], 3), nbt_axis_node(&maps[3], 5), v);
    t_abs(v[1], t->data[(5 * 9 + 3) * 3 + 1], 1e-6, "lookup at a node returns the node value");

    /* every node reproduced exactly, the last ones included (an off-by-one
     * clamp makes the last cell extrapolate from the one before) */
    worst = 0;
    for (size_t j = 0; j < 9; j++)
        for (size_t i = 0; i < 9; i++) {
            nbt_table_lookup(t, nbt_axis_node(&maps[2], i), nbt_axis_node(&maps[3], j), v);
            for (size_t c = 0; c < 3; c++)
                worst = fmax(worst, fabs(v[c] - t->data[(j * 9 + i) * 3 + c]));
        }
    t_abs(worst, 0, 1e-6, "lookup at all 81 nodes returns the node values");

    /* ---- the recorded interpolation error, checked independently: x0^2 - x1^2
     * on equal steps h. Bilinear interpolation errs by fx(1-fx)h^2 - fy(1-fy)h^2,
     * zero at cell centres, h^2/4 at edge midpoints (the true maximum). The
     * recorded error must bound the error at random points (exact values
     * computed here) and be no larger than h^2/4, up to float storage (values
     * <= 16, rounding <= 1e-6). ---- */
    {
        nbt_axis sa0 = {-1.3, 2.5, NBT_AXIS_LINEAR, 0, 17}, sa1 = {0.2, 4.0, NBT_AXIS_LINEAR, 0, 17};
        nbt_table *sd = nbt_table_alloc(NBT_TABLE_J, &sa0, &sa1, 1);
        t_true(nbt_table_tabulate(sd, saddle_fn, NULL, 1) == NBT_OK, "tabulate x0^2 - x1^2");
        double h = 3.8 / 16, seen = 0, vv[1];
        for (int k = 0; k < 20000; k++) {
            double x0 = -1.3 + 3.8 * t_uniform(), x1 = 0.2 + 3.8 * t_uniform();
            nbt_table_lookup(sd, x0, x1, vv);
            seen = fmax(seen, fabs(vv[0] - (x0 * x0 - x1 * x1)));
        }
        t_true(seen <= sd->max_err[0] + 1e-6, "recorded error %.6g bounds the error %.6g at 20000 random points",
               sd->max_err[0], seen);
        /* nbt_table_tabulate computes every midpoint, so the record is the true
         * maximum h^2/4; a row bounded by second differences plus the y error
         * instead would give h^2/2 at the saddle's cell centres, where the truth
         * is 0 (the bowl below: exactly h^2/2 either way) */
        t_abs(sd->max_err[0], h * h / 4, 2e-6, "recorded error %.6g = h^2/4 = %.6g, the true maximum",
              sd->max_err[0], h * h / 4);
        t_true(seen > 0.9 * h * h / 4, "random points come near the maximum (%.6g)", seen);
        nbt_table_free(sd);
        sd = nbt_table_alloc(NBT_TABLE_J, &sa0, &sa1, 1);
        t_true(nbt_table_tabulate(sd, bowl_fn, NULL, 1) == NBT_OK, "tabulate x0^2 + x1^2");
        seen = 0;
        for (int k = 0; k < 20000; k++) {
            double x0 = -1.3 + 3.8 * t_uniform(), x1 = 0.2 + 3.8 * t_uniform();
            nbt_table_lookup(sd, x0, x1, vv);
            seen = fmax(seen, fabs(vv[0] - (x0 * x0 + x1 * x1)));
        }
        t_true(seen <= sd->max_err[0] + 1e-6, "bowl: recorded error %.6g bounds the error %.6g at random points",
               sd->max_err[0], seen);
        t_abs(sd->max_err[0], h * h / 2, 4e-6, "bowl: recorded error = the true maximum h^2/2 (cell centres)");
        nbt_table_free(sd);
        /* nbt_table_tabulate measures every midpoint: an under-resolved bump is
         * recorded at its true error (second differences would give half) */
        sd = nbt_table_alloc(NBT_TABLE_J, &sa0, &sa1, 1);
        t_true(nbt_table_tabulate(sd, bump_fn, NULL, 1) == NBT_OK, "tabulate a bump in x0");
        seen = 0;
        for (int k = 0; k < 20000; k++) {
            double x0 = BUMP_C + 2.0 * h * (t_uniform() - 0.5), x1 = 0.2 + 3.8 * t_uniform();
            nbt_table_lookup(sd, x0, x1, vv);
            seen = fmax(seen, fabs(vv[0] - exp(-(x0 - BUMP_C) * (x0 - BUMP_C) / 0.09)));
        }
        t_true(seen <= sd->max_err[0] + 1e-6 && sd->max_err[0] < 1.5 * seen,
               "bump: recorded error %.6g bounds the error %.6g near its peak, within 1.5x", sd->max_err[0], seen);
        nbt_table_free(sd);
    }

    /* ---- the last cell row counts: f = e^{2.7 x0} (1 + 0.4 x1) on 12 x 7 equal steps.
     * Linear in x1, so bilinear interpolation errs only in x0, by
     * (g(x_i) + g(x_i+1))/2 - g(x_i + h/2) = g(mid)(cosh(2.7 h/2) - 1) times
     * (1 + 0.4 x1) at a midpoint: largest in the LAST x0 cell (the one before
     * it: e^{-2.7 h} = 0.65 of that) and at the last x1 node. The record is
     * that, computed here from g (float storage of values up to 260: 1e-5);
     * random points of the last cell row may exceed the midpoint by 0.13%
     * (the maximum of an exponential's chord error lies just off the
     * midpoint), hence 1.002. ---- */
    {
        nbt_axis ea0 = {0.15, 1.9, NBT_AXIS_LINEAR, 0, 12}, ea1 = {-0.6, 1.3, NBT_AXIS_LINEAR, 0, 7};
        nbt_table *te = nbt_table_alloc(NBT_TABLE_J, &ea0, &ea1, 1);
        t_true(nbt_table_tabulate(te, exp_fn, NULL, 1) == NBT_OK, "tabulate e^{2.7 x0} (1 + 0.4 x1)");
        double h = 1.75 / 11, want = 0, prev = 0;
        for (int i = 0; i < 11; i++) {
            double xa = 0.15 + h * i, e = 0.5 * (exp(2.7 * xa) + exp(2.7 * (xa + h))) - exp(2.7 * (xa + 0.5 * h));
            prev = want;
            want = fmax(want, e * (1 + 0.4 * 1.3));
        }
        t_true(prev < 0.7 * want, "the largest error sits in the last cell row (%.4g, the row before %.4g)", want, prev);
        t_rel(te->max_err[0], want, 1e-5, "recorded error = the last cell row's midpoint error %.6g", want);
        double seen = 0, vv[1];
        for (int k = 0; k < 4000; k++) {
            double x0 = 1.9 - h * t_uniform(), x1 = -0.6 + 1.9 * t_uniform();
            nbt_table_lookup(te, x0, x1, vv);
            seen = fmax(seen, fabs(vv[0] - exp(2.7 * x0) * (1 + 0.4 * x1)));
        }
        t_true(seen <= 1.002 * te->max_err[0] && seen > 0.9 * want,
               "recorded error %.6g bounds the error %.6g at 4000 random points of the last cell row (1.002x)",
               te->max_err[0], seen);
        nbt_table_free(te);
    }

    /* ---- EXR round trips ---- */
    t->k[0] = 0;
    t->k[1] = 1;
    t->k[2] = 2;
    t->n = 20;
    t->quad_tol = 1e-10;
    t->quad_err = 3.5e-12;
    for (int c = 0; c < 3; c++) {
        t->max_err[c] = 1e-4 * (c + 1);
        t->max_abs[c] = 2;
    }
    char path[] = "/tmp/nbt-test-tableXXXXXX";
    int fd = mkstemp(path);
    close(fd);
    char err[512];
    nbt_table *r = NULL;
    for (int comp = 0; comp < 2; comp++) {
        t_true(nbt_table_write_exr(t, path, comp ? NBT_EXR_NONE : NBT_EXR_ZIP) == NBT_OK, "write EXR (%s)", comp ? "none" : "zip");
        t_true(nbt_table_read_exr(path, &r, err, sizeof err) == NBT_OK, "read it back");
        t_true(r && same_tables(t, r), "float round trip is bit-exact, metadata included (%s)", comp ? "none" : "zip");
        nbt_table_free(r);
    }
    nbt_table_round_half(t);
    int halfok = 1;
    for (size_t i = 0; i < 9 * 9 * 3; i++)
        halfok &= fabsf(t->data[i]) < 1.0f / 1024 || fabsf(ldexpf(t->data[i], 11 - ilogbf(t->data[i])) -
                                                           nearbyintf(ldexpf(t->data[i], 11 - ilogbf(t->data[i])))) == 0;
    t_true(halfok, "half rounding leaves 11 significant bits");
    /* known IEEE half values: 1 + 2^-10 is a half, 1 + 2^-11 ties to even (1),
     * pi -> 3.140625 (0x4248), 0.1 -> 0.0999755859375 (0x2e66), 1e-6 -> 17 x 2^-24
     * (subnormal), 65504 the largest half */
    {
        nbt_axis q2 = {0, 1, NBT_AXIS_LINEAR, 0, 3};
        nbt_table *hq = nbt_table_alloc(NBT_TABLE_H, &q2, &q2, 1);
        const float in[9] = {1.0009765625f, 1.00048828125f, 3.14159265f, 0.1f, 1e-6f, 65504.0f, -2.5f, 0.0f, 1.0f};
        const double want[9] = {1.0009765625, 1.0, 3.140625, 0.0999755859375, 17.0 / 16777216.0, 65504.0, -2.5, 0.0, 1.0};
        memcpy(hq->data, in, sizeof in);
        nbt_table_round_half(hq);
        int same = 1;
        for (int i = 0; i < 9; i++)
            same &= (double)hq->data[i] == want[i];
        t_true(same, "half rounding gives the IEEE half values (1+2^-10, ties to even, pi, 0.1, subnormal, 65504)");
        nbt_table_free(hq);
    }
    t_true(nbt_table_write_exr(t, path, NBT_EXR_ZIP) == NBT_OK && nbt_table_read_exr(path, &r, err, sizeof err) == NBT_OK &&
               same_tables(t, r), "half round trip is bit-exact");
    nbt_table_free(r);
    /* the writer's progress: after every chunk of scan lines (16 for ZIP, 1 without compression) the
     * fraction written, rising, 1 at the end; 37 lines: 16/37, 32/37, 1 and 1/37 .. 37/37; the same file */
    {
        nbt_axis ax = {0, 2.385, NBT_AXIS_LINEAR, 0, 5}, ay = {-1, 1, NBT_AXIS_LINEAR, 0, 37};
        nbt_table *pt = nbt_table_alloc(NBT_TABLE_H, &ax, &ay, 2);
        for (size_t i = 0; i < 5 * 37 * 2; i++)
            pt->data[i] = (float)sin(0.37 * (double)i);
        pt->k[0] = 0;
        pt->k[1] = 1;
        for (int comp = 0; comp < 2; comp++) {
            wrec w = {0, {0}};
            r = NULL;
            int okw = nbt_table_write_exr_progress(pt, path, comp ? NBT_EXR_NONE : NBT_EXR_ZIP, on_write, &w) == NBT_OK;
            int rising = w.n > 0 && w.f[w.n - 1] == 1.0;
            for (int i = 1; i < w.n; i++)
                rising &= w.f[i] > w.f[i - 1];
            int want_n = comp ? 37 : 3;
            double want_first = comp ? 1.0 / 37 : 16.0 / 37;
            t_true(okw && w.n == want_n && rising && fabs(w.f[0] - want_first) < 1e-15 &&
                       nbt_table_read_exr(path, &r, err, sizeof err) == NBT_OK && same_tables(pt, r),
                   "write with progress (%s): %d calls (want %d), first %.4g (want %.4g), rising to 1, same file",
                   comp ? "none" : "zip", w.n, want_n, w.n ? w.f[0] : NAN, want_first);
            nbt_table_free(r);
        }
        nbt_table_free(pt);
    }
    /* a single-channel fixed-phase table keeps its phase */
    nbt_table *p1 = nbt_table_alloc(NBT_TABLE_H, &maps[1], &maps[4], 1);
    p1->k[0] = -1;
    snprintf(p1->phase, sizeof p1->phase, "hg:g=0.8");
    t_true(nbt_table_write_exr(p1, path, NBT_EXR_ZIP) == NBT_OK && nbt_table_read_exr(path, &r, err, sizeof err) == NBT_OK &&
               same_tables(p1, r), "fixed-phase single-channel round trip");
    nbt_table_free(r);
    nbt_table_free(p1);
    /* a header claiming a huge data window (60000 x 60000 x 4 floats = 58 GB)
     * in a 1 kB file is refused before any allocation (fuzzing found it) */
    {
        t_true(nbt_table_write_exr(t, path, NBT_EXR_NONE) == NBT_OK, "write a table to corrupt");
        FILE *fc = fopen(path, "rb");
        static unsigned char buf[1 << 16];
        size_t len = fread(buf, 1, sizeof buf, fc);
        fclose(fc);
        static const char key[] = "dataWindow\0box2i";
        unsigned char *w = memmem(buf, len, key, sizeof key);
        t_true(w != NULL, "dataWindow attribute found");
        if (w) {
            unsigned char *box = w + sizeof key + 4; /* after the 4-byte attribute size: xmin ymin xmax ymax */
            int32_t big = 59999;
            memcpy(box + 8, &big, 4);
            memcpy(box + 12, &big, 4);
            fc = fopen(path, "wb");
            fwrite(buf, 1, len, fc);
            fclose(fc);
            nbt_table *rb = NULL;
            nbt_status s = nbt_table_read_exr(path, &rb, err, sizeof err);
            t_true(s != NBT_OK && rb == NULL && strstr(err, "more than the file can hold"), "huge data window refused: %s", err);
            nbt_table_free(rb);
        }
    }
    /* bad files */
    FILE *f = fopen(path, "w");
    fputs("not an EXR file\n", f);
    fclose(f);
    t_true(nbt_table_read_exr(path, &r, err, sizeof err) == NBT_EFORMAT && r == NULL && err[0], "non-EXR: %s", err);
    nbt_table_write_exr(t, path, NBT_EXR_ZIP);
    f = fopen(path, "r+");
    fseek(f, 0, SEEK_END);
    long sz = ftell(f);
    fclose(f);
    t_true(truncate(path, sz / 2) == 0, "truncate");
    t_true(nbt_table_read_exr(path, &r, err, sizeof err) != NBT_OK && r == NULL, "truncated EXR rejected: %s", err);
    unlink(path);
    t_true(nbt_table_read_exr("/nonexistent/t.exr", &r, err, sizeof err) == NBT_EIO, "missing file: %s", err);
    t_true(nbt_table_write_exr(t, "/nonexistent/dir/t.exr", NBT_EXR_ZIP) == NBT_EIO &&
               access("/nonexistent/dir/t.exr", F_OK) != 0, "unwritable path: NBT_EIO, nothing left");
    nbt_table_free(t);
    t_true(nbt_table_alloc(NBT_TABLE_H, &(nbt_axis){0, 0, NBT_AXIS_LINEAR, 0, 9}, &maps[4], 1) == NULL,
           "empty axis range rejected");
    t_true(nbt_table_alloc(NBT_TABLE_H, &maps[1], &maps[4], 5) == NULL, "more than 4 channels rejected");

    /* ---- 3-D (g-sliced) tables: trilinear lookup as a sampler3D, EXR round
     * trip with the slices stacked ---- */
    {
        nbt_axis a0 = {0, 10, NBT_AXIS_LOG1P_CBRT, 10, 7}, a1 = {-1.2, 1.5, NBT_AXIS_COS, 0, 5},
                 a2 = {-0.95, 0.95, NBT_AXIS_COS, 0, 6};
        nbt_table *t3 = nbt_table_alloc3(NBT_TABLE_H, &a0, &a1, &a2, 2);
        t_true(t3 && nbt_table_size(t3) == 7 * 5 * 6 * 2, "alloc3: 7 x 5 x 6 x 2 values");
        /* node values v = a + b s0 + c s1 + d s2 + e s0 s1 s2 in the unit
         * coordinates: trilinear in s, so the lookup reproduces it exactly */
        for (size_t m = 0; m < 6; m++)
            for (size_t j = 0; j < 5; j++)
                for (size_t i = 0; i < 7; i++)
                    for (size_t c = 0; c < 2; c++) {
                        double s0 = i / 6.0, s1 = j / 4.0, s2 = m / 5.0;
                        t3->data[((m * 5 + j) * 7 + i) * 2 + c] =
                            (float)(0.385 + 1.25 * s0 - 0.75 * s1 + (c ? -2.0 : 2.0) * s2 + 0.5 * s0 * s1 * s2);
                    }
        double worst3 = 0, out[2], o2[2];
        for (int rep = 0; rep < 200; rep++) {
            double x0 = 10 * t_uniform(), x1 = -1.2 + 2.7 * t_uniform(), x2 = -0.95 + 1.9 * t_uniform();
            double s0 = nbt_axis_to_unit(&a0, x0), s1 = nbt_axis_to_unit(&a1, x1), s2 = nbt_axis_to_unit(&a2, x2);
            nbt_table_lookup3(t3, x0, x1, x2, out);
            for (int c = 0; c < 2; c++)
                worst3 = fmax(worst3, fabs(out[c] - (0.385 + 1.25 * s0 - 0.75 * s1 + (c ? -2.0 : 2.0) * s2 +
                                                    0.5 * s0 * s1 * s2)));
        }
        t_abs(worst3, 0, 2e-6, "trilinear lookup reproduces a trilinear function (200 random points)");
        nbt_table_lookup3(t3, 3.3, 0.4, 7.0, out);
        nbt_table_lookup3(t3, 3.3, 0.4, 0.95, o2);
        t_true(out[0] == o2[0] && out[1] == o2[1], "g beyond the range clamps to the last slice");
        nbt_table_lookup3(t3, 3.3, 0.4, -0.95, out);
        nbt_table_lookup(t3, 3.3, 0.4, o2);
        t_true(out[0] == o2[0] && out[1] == o2[1], "2-D lookup of a 3-D table is slice 0");
        t3->max_err[0] = 1.5e-4;
        t3->max_abs[0] = 2.9;
        snprintf(t3->phase, sizeof t3->phase, "hg");
        char p3[64];
        snprintf(p3, sizeof p3, "/tmp/nbt_test_table3_%ld.exr", (long)getpid());
        for (int half = 0; half < 2; half++) {
            if (half)
                nbt_table_round_half(t3);
            nbt_table *r3 = NULL;
            t_true(nbt_table_write_exr(t3, p3, NBT_EXR_ZIP) == NBT_OK &&
                       nbt_table_read_exr(p3, &r3, err, sizeof err) == NBT_OK && same_tables(t3, r3),
                   "3-D EXR round trip (%s): axes, slices, values identical", half ? "half" : "float");
            nbt_table_free(r3);
        }
        unlink(p3);
        t_true(nbt_table_alloc3(NBT_TABLE_H, &a0, &a1, &(nbt_axis){-0.9, 0.9, NBT_AXIS_COS, 0, 0}, 1) == NULL,
               "alloc3: empty slice axis rejected");
        nbt_table_free(t3);
    }

    /* ---- the atanh g axis, quadratic interpolation in g, per-cell errors ---- */
    {
        nbt_axis ga = {-0.95, 0.9, NBT_AXIS_ATANH, 0, 7};
        double wr = 0;
        for (int i = 0; i < 7; i++) {
            double s = i / 6.0, x = nbt_axis_from_unit(&ga, s);
            /* atanh x = atanh lo + s (atanh hi - atanh lo), and back */
            wr = fmax(wr, fabs(atanh(x) - (atanh(-0.95) + s * (atanh(0.9) - atanh(-0.95)))));
            wr = fmax(wr, fabs(nbt_axis_to_unit(&ga, x) - s));
        }
        t_abs(wr, 0, 1e-14, "atanh axis: nodes uniform in atanh g, to_unit inverts from_unit");
        t_true(nbt_axis_node(&ga, 0) == -0.95 && nbt_axis_node(&ga, 6) == 0.9 && nbt_axis_to_unit(&ga, 0.95) == 1.0 &&
                   nbt_axis_to_unit(&ga, -1.0) == 0.0, "atanh axis: ends exact, clamps beyond them");
        nbt_axis ao = {-0.95, 1.0, NBT_AXIS_ATANH, 0, 5};
        t_true(nbt_table_alloc(NBT_TABLE_H, &ao, &ga, 1) == NULL, "atanh axis reaching 1 rejected");
        /* values quadratic in s2 (and bilinear in s0, s1): the quadratic
         * lookup reproduces them exactly anywhere, the trilinear one not */
        nbt_axis b0 = {0, 4, NBT_AXIS_SQRT, 0, 5}, b1 = {0, 1, NBT_AXIS_LINEAR, 0, 4};
        nbt_table *q = nbt_table_alloc3(NBT_TABLE_J, &b0, &b1, &ga, 1);
        t_true(q && q->interp2 == 1 && q->cell_err && isnan(q->cell_err[5]), "alloc3: linear in g, no cell errors");
#define QF(s0, s1, s2) (0.3 + (s0) * (s1) - 1.7 * (s2) + 2.9 * (s2) * (s2) * (1 + (s0)))
        for (size_t m = 0; m < 7; m++)
            for (size_t j = 0; j < 4; j++)
                for (size_t i = 0; i < 5; i++)
                    q->data[(m * 4 + j) * 5 + i] = (float)QF(i / 4.0, j / 3.0, m / 6.0);
        q->interp2 = 2;
        double wq = 0, wl = 0, o;
        for (int rep = 0; rep < 300; rep++) {
            double x0 = 4 * t_uniform(), x1 = t_uniform(), x2 = -0.95 + 1.85 * t_uniform();
            double e = QF(nbt_axis_to_unit(&b0, x0), nbt_axis_to_unit(&b1, x1), nbt_axis_to_unit(&ga, x2));
            nbt_table_lookup3(q, x0, x1, x2, &o);
            wq = fmax(wq, fabs(o - e));
            q->interp2 = 1;
            nbt_table_lookup3(q, x0, x1, x2, &o);
            q->interp2 = 2;
            wl = fmax(wl, fabs(o - e));
        }
#undef QF
        /* float node values: 4 ulp of |values| <= 3 */
        t_abs(wq, 0, 2e-6, "quadratic-in-g lookup reproduces a function quadratic in g's unit coordinate");
        t_true(wl > 1e-2, "the trilinear lookup does not (worst %.2g): the check above can fail", wl);
        {
            /* the fewest slices a quadratic takes, three: still quadratic (a 2 x 2 x 3
             * table of f = 0.4 + 1.1 s2 - 2.3 s2^2, s2 = (x2 + 0.5) / 1.2; the chord
             * between slices errs by up to 2.3/16 = 0.14 there) */
            nbt_axis c0 = {0, 1, NBT_AXIS_LINEAR, 0, 2}, c2 = {-0.5, 0.7, NBT_AXIS_LINEAR, 0, 3};
            nbt_table *q3 = nbt_table_alloc3(NBT_TABLE_J, &c0, &c0, &c2, 1);
            for (size_t m = 0; q3 && m < 3; m++)
                for (size_t k = 0; k < 4; k++)
                    q3->data[m * 4 + k] = (float)(0.4 + 1.1 * (m / 2.0) - 2.3 * (m / 2.0) * (m / 2.0));
            double w3 = 0;
            for (int k = 0; q3 && k < 7; k++) {
                double x2 = -0.5 + 1.2 * k / 6.0, s2 = k / 6.0, o3;
                q3->interp2 = 2;
                nbt_table_lookup3(q3, 0.3, 0.8, x2, &o3);
                w3 = fmax(w3, fabs(o3 - (0.4 + 1.1 * s2 - 2.3 * s2 * s2)));
            }
            /* float node values <= 1: 1e-6 */
            t_true(q3 && w3 < 1e-6, "three slices, quadratic in g: lookup3 exact at 7 points (worst %.2g)", w3);
            /* cubic needs four slices: a 3-slice file claiming interp 3 is refused */
            char p3[64];
            snprintf(p3, sizeof p3, "/tmp/nbt_test_table3_%ld.exr", (long)getpid());
            nbt_table *r3 = NULL;
            t_true(q3 && nbt_table_write_exr(q3, p3, NBT_EXR_NONE) == NBT_OK && patch_file(p3, "nbt.axis2.interp", NULL, 3) &&
                       nbt_table_read_exr(p3, &r3, err, sizeof err) == NBT_EFORMAT && !r3 && strstr(err, "at least 4"),
                   "interp 3 with 3 slices refused: %s", err);
            unlink(p3);
            nbt_table_free(q3);
        }
        {
            /* cubic in g (interp2 = 3): for f = s0 s1 + P^4/64, P = s2 (n - 1) the slice
             * index, Lagrange through slices m0..m0+3 errs by exactly -(P - m0)(P - m0 - 1)
             * (P - m0 - 2)(P - m0 - 3)/64 (f's 4th derivative / 4! = 1/64; bilinear is exact
             * for s0 s1), m0 = floor(P) - 1 clamped to [0, n - 4]: a closed form that
             * pins the stencil, in the first and last cells too (an off-by-one stencil
             * there errs by up to 24/64 instead of 1/64) */
            nbt_table *qc = nbt_table_dup(q);
            for (size_t m = 0; qc && m < 7; m++)
                for (size_t j = 0; j < 4; j++)
                    for (size_t i = 0; i < 5; i++)
                        qc->data[(m * 4 + j) * 5 + i] = (float)(i / 4.0 * (j / 3.0) + pow((double)m, 4) / 64.0);
            double wc = 0, wcq = 0, wend = 0;
            for (int rep = 0; qc && rep < 400; rep++) {
                /* a quarter of the points in the last cell, a quarter in the first */
                double x0 = 4 * t_uniform(), x1 = t_uniform(), P = rep % 4 == 0 ? 5 + t_uniform() : rep % 4 == 1 ? t_uniform() : 6 * t_uniform();
                double x2 = nbt_axis_from_unit(&ga, P / 6.0), oc;
                P = nbt_axis_to_unit(&ga, x2) * 6.0;
                double m0 = fmin(fmax(floor(P) - 1.0, 0.0), 3.0), x = P - m0;
                double e = nbt_axis_to_unit(&b0, x0) * nbt_axis_to_unit(&b1, x1) + pow(P, 4) / 64.0 -
                           x * (x - 1) * (x - 2) * (x - 3) / 64.0;
                qc->interp2 = 3;
                nbt_table_lookup3(qc, x0, x1, x2, &oc);
                wc = fmax(wc, fabs(oc - e));
                if (rep % 4 < 2)
                    wend = fmax(wend, fabs(oc - e));
                qc->interp2 = 2;
                nbt_table_lookup3(qc, x0, x1, x2, &oc);
                wcq = fmax(wcq, fabs(oc - e));
            }
            /* float node values <= 21: 1e-5 */
            t_true(qc && wc < 1e-5, "cubic-in-g lookup = f minus its closed-form interpolation error (worst %.2g, "
                   "first and last cells %.2g)", wc, wend);
            t_true(wcq > 1e-3, "the quadratic lookup is not (worst %.2g): the check above can fail", wcq);
            /* the file keeps interp2 = 3 (an older reader refuses it: 'must be 1 or 2') */
            char pc[64];
            snprintf(pc, sizeof pc, "/tmp/nbt_test_tablec_%ld.exr", (long)getpid());
            nbt_table *rc = NULL;
            if (qc)
                qc->interp2 = 3;
            t_true(qc && nbt_table_write_exr(qc, pc, NBT_EXR_NONE) == NBT_OK &&
                       nbt_table_read_exr(pc, &rc, err, sizeof err) == NBT_OK && rc->interp2 == 3 && same_tables(qc, rc),
                   "cubic table written and read: interp2 3 kept");
            nbt_table_free(rc);
            rc = NULL;
            t_true(patch_file(pc, "nbt.axis2.interp", NULL, 4) && nbt_table_read_exr(pc, &rc, err, sizeof err) == NBT_EFORMAT &&
                       !rc && strstr(err, "interp"), "interp 4 refused: %s", err);
            unlink(pc);
            nbt_table_free(qc);
        }
        q->max_err[0] = 0.25;
        for (size_t m = 0; m < 6; m++)
            q->cell_err[m] = 0.01 * (double)(m + 1);
        t_true(nbt_table_err_at(q, 0, -0.95) == 0.01 && nbt_table_err_at(q, 0, 0.9) == 0.06 &&
                   nbt_table_err_at(q, 0, 5.0) == 0.06 && nbt_table_err_at(q, 0, nbt_axis_from_unit(&ga, 2.5 / 6)) == 0.03,
               "err_at: the cell's recorded error, clamped to the axis");
        q->cell_err[3] = NAN;
        t_true(nbt_table_err_at(q, 0, nbt_axis_from_unit(&ga, 3.5 / 6)) == 0.25, "err_at: max_err where not recorded");
        q->cell_err[3] = 1.0 / 3.0; /* not a float: the file rounds it up */
        nbt_table *d = nbt_table_dup(q);
        t_true(d && same_tables(q, d) && d->data != q->data && d->cell_err != q->cell_err, "dup: a deep copy");
        nbt_table_free(d);
        char pq[64];
        snprintf(pq, sizeof pq, "/tmp/nbt_test_tableq_%ld.exr", (long)getpid());
        nbt_table *rq = NULL;
        t_true(nbt_table_write_exr(q, pq, NBT_EXR_NONE) == NBT_OK && nbt_table_read_exr(pq, &rq, err, sizeof err) == NBT_OK,
               "quadratic, atanh table written and read: %s", rq ? "ok" : err);
        int same = rq && rq->interp2 == 2 && rq->form == NBT_FORM_PLAIN && rq->axis[2].map == NBT_AXIS_ATANH;
        for (size_t m = 0; rq && m < 6; m++)
            same = same && rq->cell_err[m] >= q->cell_err[m] && rq->cell_err[m] - q->cell_err[m] <= 1e-7 * q->cell_err[m];
        t_true(same && rq && !memcmp(rq->data, q->data, nbt_table_size(q) * sizeof(float)),
               "EXR keeps interp2, form, atanh and the cell errors (rounded up to float)");
        nbt_table_free(rq);
        rq = NULL;
        t_true(patch_file(pq, "nbt.axis2.interp", NULL, 5) && nbt_table_read_exr(pq, &rq, err, sizeof err) == NBT_EFORMAT &&
                   !rq && strstr(err, "interp"), "interp 5 refused: %s", err);
        t_true(nbt_table_write_exr(q, pq, NBT_EXR_NONE) == NBT_OK && patch_file(pq, "plain", "plein", 0) &&
                   nbt_table_read_exr(pq, &rq, err, sizeof err) == NBT_EFORMAT && !rq && strstr(err, "nbt.form"),
               "an unknown value form refused: %s", err);
        unlink(pq);
        nbt_table_free(q);
    }

    /* ---- a file's error bounds must each be >= 0 and finite: a row bound of +inf is
     * refused wherever it stands, the first of the 6 (a random mutant that checked the
     * next value's finiteness instead accepted it, and read one past the vector) ---- */
    {
        nbt_axis r0 = {0, 6, NBT_AXIS_LINEAR, 0, 7}, r1 = {0, 1, NBT_AXIS_LINEAR, 0, 3};
        nbt_table *rt = nbt_table_alloc(NBT_TABLE_KERNEL, &r0, &r1, 1), *rr = NULL;
        int okr = rt && nbt_table_row_err_alloc(rt) == NBT_OK && nbt_table_row_err_len(rt) == 6;
        char pr[64];
        snprintf(pr, sizeof pr, "/tmp/nbt_test_tablerow_%ld.exr", (long)getpid());
        for (size_t i = 0; okr && i < 6; i++)
            rt->row_err[i] = 0.125 * (double)(i + 1);
        if (okr)
            rt->max_err[0] = 1.0;
        snprintf(err, sizeof err, "not written");
        int rd = okr && nbt_table_write_exr(rt, pr, NBT_EXR_NONE) == NBT_OK &&
                 nbt_table_read_exr(pr, &rr, err, sizeof err) == NBT_OK;
        t_true(rd && rr && rr->row_err && rr->row_err[0] == 0.125 && rr->row_err[5] == 0.75,
               "6 finite row bounds written and read back (exact in float): %s", rd ? "ok" : err);
        nbt_table_free(rr);
        rr = NULL;
        for (size_t at = 0; okr && at < 6; at += 5) {
            rt->row_err[at] = INFINITY;
            t_true(nbt_table_write_exr(rt, pr, NBT_EXR_NONE) == NBT_OK &&
                       nbt_table_read_exr(pr, &rr, err, sizeof err) == NBT_EFORMAT && !rr &&
                       strstr(err, "an nbt.row_err value is negative or not finite"),
                   "a row bound of +inf at place %zu of 6 refused: %s", at, err);
            nbt_table_free(rr);
            rr = NULL;
            rt->row_err[at] = 0.125 * (double)(at + 1);
        }
        /* a theta map (1 theta cell per band: 2 bands x 6) whose file lacks nbt.theta_err.cells (the name
         * patched to ...cellz): refused, not read with a guessed band width */
        okr = okr && nbt_table_theta_err_alloc(rt, 1) == NBT_OK && nbt_table_theta_err_len(rt) == 12;
        for (size_t i = 0; okr && i < 12; i++)
            rt->theta_err[i] = 0.0625 * (double)(i + 1);
        t_true(okr && nbt_table_write_exr(rt, pr, NBT_EXR_NONE) == NBT_OK &&
                   nbt_table_read_exr(pr, &rr, err, sizeof err) == NBT_OK && rr && rr->theta_cells == 1 &&
                   rr->theta_err && rr->theta_err[11] == 0.75,
               "a theta map of 1 cell per band written and read back");
        nbt_table_free(rr);
        rr = NULL;
        snprintf(err, sizeof err, "read without error");
        t_true(okr && patch_file(pr, "nbt.theta_err.cells", "nbt.theta_err.cellz", 0) &&
                   nbt_table_read_exr(pr, &rr, err, sizeof err) == NBT_EFORMAT && !rr &&
                   strstr(err, "needs nbt.theta_err.cells"),
               "a theta map without nbt.theta_err.cells refused: %s", err);
        nbt_table_free(rr);
        unlink(pr);
        nbt_table_free(rt);
    }

    /* ---- tabulating a function: f = x0^2 + 3 x1 on uniform axes has bilinear
     * error exactly h^2/4 at the cell midpoints along x0 ---- */
    nbt_axis u0 = {0, 2, NBT_AXIS_LINEAR, 0, 9}, u1 = {-1, 1, NBT_AXIS_LINEAR, 0, 5};
    nbt_table *tf = nbt_table_alloc(NBT_TABLE_KERNEL, &u0, &u1, 1);
    t_true(nbt_table_tabulate(tf, quad_fn, NULL, 1) == NBT_OK, "tabulate");
    t_rel(tf->max_err[0], 0.25 * 0.25 / 4, 1e-6, "recorded error = h^2/4 for x^2");
    t_rel(tf->data[(3 * 9 + 4) * 1], 1.0 + 3 * 0.5, 1e-7, "node value");
    t_true(nbt_table_tabulate(tf, fail_fn, NULL, 0) == NBT_EDOM, "a failing function aborts with NBT_EDOM");
    nbt_table_free(tf);

    /* ---- recorded interpolation error of an H table is honest ---- */
    nbt_axis a0 = {0, 10, NBT_AXIS_LOG1P, 100, 65}, a1 = {-M_PI_2, M_PI_2, NBT_AXIS_COS, 0, 65};
    nbt_table *h = nbt_table_alloc(NBT_TABLE_H, &a0, &a1, 4);
    for (int c = 0; c < 4; c++)
        h->k[c] = c;
    nbt_build_opts o = {1e-10, 1, 2};
    t_true(nbt_h_table_build(h, NULL, &o) == NBT_OK, "H table builds");
    double ratio = 0, Hk[4], E[4];
    for (int j = 0; j < 400; j++) {
        double u = j < 200 ? 10 * t_uniform() : 0.05 * t_uniform(), vv = -M_PI_2 + M_PI * t_uniform();
        nbt_table_lookup(h, u, vv, v);
        nbt_hk(3, u, vv, 1e-12, Hk, E);
        for (int c = 0; c < 4; c++)
            ratio = fmax(ratio, fabs(v[c] - Hk[c]) / h->max_err[c]);
    }
    t_true(ratio <= 1.25, "H table: 400 random points within 1.25x the recorded error (worst ratio %.2f)", ratio);
    /* same table with 1 and 2 threads: identical */
    nbt_table *h1 = nbt_table_alloc(NBT_TABLE_H, &a0, &a1, 4);
    memcpy(h1->k, h->k, sizeof h->k);
    o.nthreads = 1;
    nbt_h_table_build(h1, NULL, &o);
    t_true(same_tables(h, h1), "H table identical with 1 and 2 threads");
    nbt_table_free(h);
    nbt_table_free(h1);

    /* ---- H nodes from the fixed per-cell rules (libnbt/airlight.c) at the
     * edges of the domain: the boundary layer at v -> pi/2 for small u
     * (width ~u, inside the last cell), large u (the integrand gone within
     * the first cells), a high order, and a table starting above -pi/2.
     * Each node must match nbt_hk (tol 1e-13, its own estimate added) within
     * float rounding (6e-8 relative) plus the recorded quadrature error,
     * and that error must be small (quad_tol 1e-10 asks for ~1e-11). ---- */
    {
        struct {
            double u0, u1, v0, v1;
            int K;
            size_t n;
        } ed[5] = {{0, 1e-6, 1.5, M_PI_2, 3, 9}, {1e-9, 1e-3, -M_PI_2, M_PI_2, 3, 7},
                   {100, 5e3, -M_PI_2, M_PI_2, 3, 9}, {0, 2.5, -1.2, 1.4, 11, 5}, {0.3, 0.7, -M_PI_2, -1.5, 3, 3}};
        double eworst = 0, qmax = 0;
        for (int q = 0; q < 5; q++) {
            nbt_axis ax = {ed[q].u0, ed[q].u1, NBT_AXIS_LINEAR, 0, ed[q].n};
            nbt_axis ay = {ed[q].v0, ed[q].v1, NBT_AXIS_COS, 0, ed[q].n};
            size_t np = (size_t)(ed[q].K + 4) / 4;
            nbt_table *hs[3];
            for (size_t p = 0; p < np; p++) {
                hs[p] = nbt_table_alloc(NBT_TABLE_H, &ax, &ay, 4);
                for (int c = 0; c < 4; c++)
                    hs[p]->k[c] = (int)(4 * p) + c;
            }
            nbt_build_opts oe = {1e-10, 1, 2};
            t_true(nbt_h_table_build_set(hs, np, NULL, &oe) == NBT_OK, "edge H set %d builds", q);
            qmax = fmax(qmax, hs[0]->quad_err);
            for (size_t i = 0; i < ed[q].n; i++)
                for (size_t j = 0; j < ed[q].n; j++) {
                    double x = nbt_axis_node(&ax, i), y = nbt_axis_node(&ay, j), ex[12], ee[12];
                    nbt_hk((size_t)ed[q].K, x, y, 1e-13, ex, ee);
                    for (size_t p = 0; p < np; p++)
                        for (int c = 0; c < 4; c++) {
                            int k = 4 * (int)p + c;
                            double d = fabs(hs[p]->data[(j * ed[q].n + i) * 4 + c] - ex[k]) - ee[k] -
                                       6e-8 * fabs(ex[k]);
                            eworst = fmax(eworst, d / hs[p]->quad_err);
                        }
                }
            for (size_t p = 0; p < np; p++)
                nbt_table_free(hs[p]);
        }
        t_true(eworst <= 1.0 && qmax <= 1e-9,
               "H nodes at the domain edges within float rounding + quad_err (eworst %.2g of it; quad_err <= %.1e)",
               eworst, qmax);
    }

    /* ---- J nodes (G on panels in g, M by the kernel's kinks: libnbt/surface.c)
     * against nbt_jk / nbt_j_phase at 1e-12 (their estimates added): within
     * float rounding (6e-8 relative) plus the recorded quadrature error. The
     * cases where the former 5-point check under-bounded the node error (by
     * 74x at 3x4 nodes, order 11; 17x for Phong n = 20 order 3): G's
     * T g log g term at g = 0, visible at T ~ 1..5 and theta = 0, which no
     * corner or centre check sees. With the first panel in y^4 the Legendre
     * sets must stay small (<= 1e-9 at quad_tol 1e-10: a polynomial in g
     * there leaves 5e-9 .. 2e-7). Fixed HG g = 0.99, -0.97: the peak makes a
     * feature of width ~1 - |g| at g = 0 (forward) or pi (backward), to
     * which the panels are graded (<= 1e-6; ungraded 3.5e-5, 6.6e-5). A
     * tabulated phase with peaks at both ends (mean cosine 0: no grading,
     * and kinks at mu = +-0.99) leaves ~2e-4 that only the halved-panel
     * check bounds. ---- */
    {
        /* and the fixed-rule G rows at the edges of T: T -> 0 (G's w -> 0
         * layer), large T, order 11 on [0.1, 3]; g = 2: the tabulated phase */
        struct {
            int n, K;
            double g, Tlo, Thi;
            size_t nx, ny;
        } jc[9] = {{1, 11, 0, 0, 10, 3, 4},   {20, 3, 0, 0, 10, 3, 4},    {1, 3, 0, 0, 1, 5, 5},
                   {1, 0, 0.99, 0, 1, 5, 5},  {1, 0, -0.97, 0, 1, 3, 3}, {1, 0, 2, 0, 3, 3, 3},
                   {1, 3, 0, 0, 1e-5, 3, 4},  {1, 3, 0, 2, 60, 3, 4},     {1, 11, 0, 0.1, 3, 3, 4}};
        double eworst = 0, qleg = 0, qhg = 0, mu2[4] = {-1, -0.99, 0.99, 1}, p2[4] = {30, 1, 1, 30};
        for (int q = 0; q < 9; q++) {
            nbt_axis ax = {jc[q].Tlo, jc[q].Thi, NBT_AXIS_LINEAR, 0, jc[q].nx};
            nbt_axis ay = {0, M_PI, NBT_AXIS_LINEAR, 0, jc[q].ny};
            nbt_phase *ph = jc[q].g == 2 ? nbt_phase_tabulated(4, mu2, p2) : jc[q].g != 0 ? nbt_phase_hg(jc[q].g) : NULL;
            size_t np = ph ? 1 : (size_t)(jc[q].K + 4) / 4;
            nbt_table *js[3];
            for (size_t p = 0; p < np; p++) {
                js[p] = nbt_table_alloc(NBT_TABLE_J, &ax, &ay, ph ? 1 : 4);
                js[p]->n = jc[q].n;
                for (size_t c = 0; c < js[p]->nch; c++)
                    js[p]->k[c] = (int)(4 * p + c);
            }
            nbt_build_opts oj = {1e-10, 1, 2};
            t_true(nbt_j_table_build_set(js, np, ph, &oj) == NBT_OK, "J node set %d builds", q);
            if (!ph)
                qleg = fmax(qleg, js[0]->quad_err);
            else if (jc[q].g != 2)
                qhg = fmax(qhg, js[0]->quad_err);
            for (size_t i = 0; i < jc[q].nx; i++)
                for (size_t j = 0; j < jc[q].ny; j++) {
                    double x = nbt_axis_node(&ax, i), y = nbt_axis_node(&ay, j), ex[12], ee[12];
                    if (ph)
                        nbt_j_phase(ph, jc[q].n, x, y, 1e-12, ex, ee);
                    else
                        nbt_jk((size_t)jc[q].K, jc[q].n, x, y, 1e-12, ex, ee);
                    for (size_t p = 0; p < np; p++)
                        for (size_t c = 0; c < js[p]->nch; c++) {
                            size_t k = 4 * p + c;
                            double d = fabs(js[p]->data[(j * jc[q].nx + i) * js[p]->nch + c] - ex[k]) - ee[k] -
                                       6e-8 * fabs(ex[k]);
                            eworst = fmax(eworst, d / js[p]->quad_err);
                        }
                }
            for (size_t p = 0; p < np; p++)
                nbt_table_free(js[p]);
            nbt_phase_free(ph);
        }
        t_true(eworst <= 1.0 && qleg <= 1e-9 && qhg <= 1e-6,
               "J nodes within float rounding + quad_err (eworst %.2g of it; quad_err Legendre <= %.1e, HG <= %.1e)",
               eworst, qleg, qhg);
    }

    /* ---- second order on log1p_cbrt (doc/tables.md): the recorded error
     * (honest: above, and tests/test_plan.c at random points) falls by
     * >= 3.5 from 65 to 129 nodes in u/T over [0, 10] with c = 10, where
     * log1p(c = 1000) gives 3.2 for H. H: both axes refined; J^1: T only
     * (theta at 257 linear nodes), because J^1's own error at 129^2 is
     * theta's: its Lambert horizon at theta = pi/2 converges as ~N^-1.7 ---- */
    for (int kind = 0; kind < 2; kind++) {
        double e[2][2];
        for (int m = 0; m < 2; m++)
            for (int q = 0; q < 2; q++) {
                size_t N = q ? 129 : 65;
                nbt_axis b0 = {0, 10, m ? NBT_AXIS_LOG1P : NBT_AXIS_LOG1P_CBRT, m ? 1000 : 10, N};
                nbt_axis b1 = kind ? (nbt_axis){0, M_PI, NBT_AXIS_LINEAR, 0, 257} : (nbt_axis){-M_PI_2, M_PI_2, NBT_AXIS_COS, 0, N};
                nbt_table *tb = nbt_table_alloc(kind ? NBT_TABLE_J : NBT_TABLE_H, &b0, &b1, 4);
                for (int c = 0; c < 4; c++)
                    tb->k[c] = c;
                tb->n = kind;
                nbt_build_opts ob = {1e-10, 1, 2};
                nbt_status sb = kind ? nbt_j_table_build(tb, NULL, &ob) : nbt_h_table_build(tb, NULL, &ob);
                e[m][q] = 0;
                for (int c = 0; c < 4; c++)
                    e[m][q] = fmax(e[m][q], tb->max_err[c]);
                e[m][q] = sb == NBT_OK ? e[m][q] / tb->max_abs[0] : NAN;
                nbt_table_free(tb);
            }
        t_true(e[0][0] / e[0][1] >= 3.5, "%s on log1p_cbrt: error %.3g at 65, %.3g at 129 nodes, ratio %.2f >= 3.5",
               kind ? "J^1 (T)" : "H", e[0][0], e[0][1], e[0][0] / e[0][1]);
        t_true(e[0][1] <= e[1][1], "%s: log1p_cbrt (%.3g) no worse than log1p(c = 1000) (%.3g, ratio %.2f) at 129",
               kind ? "J^1 (T)" : "H", e[0][1], e[1][1], e[1][0] / e[1][1]);
    }

    /* ---- J^1 on square grids, theta as the planner maps it: asinh(c = 1)
     * against linear. The Lambert horizon, (theta - pi/2)^2 log|theta - pi/2|,
     * limited linear theta to 3.39 from 65^2 to 129^2 (N^-2 log N); asinh
     * must give >= 3.5 and no larger error at 129^2 (measured 3.97,
     * 1.15e-4 against 1.32e-4). The recorded errors are the measured ones
     * (bounded at random points in tests/test_plan.c). ---- */
    {
        double e[2][2];
        for (int m = 0; m < 2; m++)
            for (int q = 0; q < 2; q++) {
                size_t N = q ? 129 : 65;
                nbt_axis b0 = {0, 10, NBT_AXIS_LOG1P_CBRT, 10, N};
                nbt_axis b1 = {0, M_PI, m ? NBT_AXIS_LINEAR : NBT_AXIS_ASINH, m ? 0 : 1, N};
                nbt_table *tb = nbt_table_alloc(NBT_TABLE_J, &b0, &b1, 4);
                for (int c = 0; c < 4; c++)
                    tb->k[c] = c;
                tb->n = 1;
                nbt_build_opts ob = {1e-10, 1, 2};
                nbt_status sb = nbt_j_table_build(tb, NULL, &ob);
                e[m][q] = nbt_table_max_err(tb) / tb->max_abs[0];
                if (sb != NBT_OK)
                    e[m][q] = NAN;
                nbt_table_free(tb);
            }
        t_true(e[0][0] / e[0][1] >= 3.5, "J^1 on theta asinh(c = 1): error %.3g at 65^2, %.3g at 129^2, ratio %.2f >= 3.5",
               e[0][0], e[0][1], e[0][0] / e[0][1]);
        t_true(e[0][1] <= e[1][1], "J^1: theta asinh (%.3g) no worse than linear (%.3g, ratio %.2f) at 129^2", e[0][1],
               e[1][1], e[1][0] / e[1][1]);
    }
    {
        /* the bound where no cell map is recorded is the channel's own
         * max_err (nbt/table.h), for every channel up to the last; a channel
         * past nch is NaN. Unequal values so a neighbour's shows */
        nbt_axis c0 = {0, 2, NBT_AXIS_LINEAR, 0, 5}, c1 = {-1, 1, NBT_AXIS_LINEAR, 0, 3};
        nbt_table *tc = nbt_table_alloc(NBT_TABLE_H, &c0, &c1, 3);
        t_true(tc != NULL, "a 3-channel table without a cell map");
        if (tc) {
            tc->max_err[0] = 1e-3;
            tc->max_err[1] = 2e-3;
            tc->max_err[2] = 4e-3;
            int same = 1;
            for (size_t c = 0; c < 3; c++)
                same &= nbt_table_err_at(tc, c, 0.37) == tc->max_err[c];
            t_true(same && isnan(nbt_table_err_at(tc, 3, 0.37)),
                   "err_at without a cell map: max_err of channels 0, 1, 2 (%g %g %g); channel 3 NaN",
                   nbt_table_err_at(tc, 0, 0.37), nbt_table_err_at(tc, 1, 0.37), nbt_table_err_at(tc, 2, 0.37));
            nbt_table_free(tc);
        }
    }
    return t_done();
}
