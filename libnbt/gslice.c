/* libnbt/gslice.c: g-sliced H and J tables (nbt/gslice.h): per-slice
 * fixed-phase builds, the g interpolation error, sizing, evaluation. */
#include <config.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <nbt/gslice.h>
#include <nbt/plan.h>
#include "internal.h"
#include "gslice_tail.h"
#include "gslice_j.h"

/* a predicted wall time as the CPU time it stands for, by the CPU/wall
 * ratio of the planning that measured it (its proxy builds) */
static double as_cpu(double pred_wall, double cpu, double wall)
{
    return cpu > 0 && wall > 0 ? pred_wall * cpu / wall : pred_wall;
}

int nbt_table_is_gslice(const nbt_table *t)
{
    return t && (t->kind == NBT_TABLE_H || t->kind == NBT_TABLE_J) && t->axis[2].n >= 2 &&
           (t->nch == 1 || (t->nch == 2 && t->form == NBT_FORM_TAIL)) && t->k[0] == -1 && !strcmp(t->phase, "hg");
}

/* One fixed-phase slice at g over the table's axes 0 and 1. */
static nbt_status build_slice(const nbt_table *t, double g, const nbt_build_opts *o, nbt_table **out)
{
    *out = NULL;
    nbt_table *s = nbt_table_alloc(t->kind, &t->axis[0], &t->axis[1], 1);
    nbt_phase *p = nbt_phase_hg(g);
    if (!s || !p) {
        nbt_table_free(s);
        nbt_phase_free(p);
        NBT_FAIL(NBT_ENOMEM, "g-sliced table: out of memory");
    }
    s->k[0] = -1;
    s->n = t->n;
    nbt_status st = t->kind == NBT_TABLE_H ? nbt_h_table_build(s, p, o) : nbt_j_table_build(s, p, o);
    nbt_phase_free(p);
    if (st != NBT_OK)
        nbt_table_free(s);
    else
        *out = s;
    return st;
}

/* The slices at g[0..m-1] over t's axes 0 and 1, in t's value form, as 2-D
 * one-channel tables (quad_err, max_abs and, with o->measure_error, max_err
 * set): the one place that knows how a kind and form are built. */
static nbt_status build_slices(const nbt_table *t, const double *g, size_t m, const nbt_build_opts *o,
                               nbt__jcache *gc, nbt_table **out)
{
    if (t->kind == NBT_TABLE_J)
        return nbt__gslice_j_slices(t, g, m, o, gc, out);
    nbt_status st = NBT_OK;
    for (size_t i = 0; i < m; i++)
        out[i] = NULL;
    for (size_t i = 0; i < m && st == NBT_OK; i++)
        st = build_slice(t, g[i], o, &out[i]);
    if (st != NBT_OK)
        for (size_t i = 0; i < m; i++) {
            nbt_table_free(out[i]);
            out[i] = NULL;
        }
    return st;
}

static nbt_status fill_form(nbt_table *t, nbt_table_form form, const nbt_build_opts *o, nbt__jcache *gc);

/* e added to every recorded bound of a one-channel g-sliced table: per g
 * cell, per (T row, g cell) and per (T row, theta band, g cell) */
static void add_to_bounds(nbt_table *t, double e)
{
    for (size_t m = 0; m + 1 < t->axis[2].n; m++)
        t->cell_err[m] += e;
    for (size_t k = 0; t->row_err && k < nbt_table_row_err_len(t); k++)
        t->row_err[k] += e;
    for (size_t k = 0; t->theta_err && k < nbt_table_theta_err_len(t); k++)
        t->theta_err[k] += e;
}

static nbt_table_form default_form(const nbt_table *t)
{
    return t->kind == NBT_TABLE_H ? NBT_FORM_TAIL : t->form == NBT_FORM_LOG_ET ? NBT_FORM_LOG_ET : NBT_FORM_PLAIN;
}

nbt_status nbt_gslice_fill(nbt_table *t, const nbt_build_opts *o)
{
    return fill_form(t, default_form(t), o, NULL);
}

/* theta bands of a g-sliced J table's error map (theta_err): 16 bands of
 * 16 cells at the planner's 257 theta nodes. The error peaks in a few
 * cells (J^1's horizon, J^n's lobe edge) and is orders smaller elsewhere,
 * so narrow bands keep the peak out of most of theta. bench/bench_gslice
 * (J^1 + J^20, 65x257x33, 1000 geometries) certifies 1e-3 at 73, 81, 85,
 * 88% with 8, 16, 32, 64 bands (the row bound 32%): 16 is the knee, 64 rows
 * x 16 bands x 32 g cells = 32768 floats (131 kB, 6% of the table's 2.2 MB),
 * where the whole per-cell map would be as large as the table. */
#define THETA_BANDS 16

nbt_status nbt_gslice_fill_form(nbt_table *t, nbt_table_form form, const nbt_build_opts *o)
{
    return fill_form(t, form, o, NULL);
}

/* gc: G rows shared with other J builds (nbt_gslice_build_set), or NULL */
static nbt_status fill_form(nbt_table *t, nbt_table_form form, const nbt_build_opts *o, nbt__jcache *gc)
{
    if (form != NBT_FORM_PLAIN && !(form == NBT_FORM_TAIL && t->kind == NBT_TABLE_H) &&
        !(form == NBT_FORM_LOG_ET && t->kind == NBT_TABLE_J))
        NBT_FAIL(NBT_EINVAL, "g-sliced table: the forms are plain, tail (H only) and log_et (J only)");
    if (t->kind != NBT_TABLE_H && t->kind != NBT_TABLE_J)
        NBT_FAIL(NBT_EINVAL, "g-sliced table: the kind must be H or J");
    if (t->axis[2].n < 2)
        NBT_FAIL(NBT_EINVAL, "g-sliced table: axis 2 (g) needs at least 2 nodes");
    if (!(t->axis[2].lo >= -NBT_GSLICE_GMAX && t->axis[2].hi <= NBT_GSLICE_GMAX))
        NBT_FAIL(NBT_EDOM, "g-sliced table: the g axis must lie in [-0.99, 0.99]");
    t->nch = 1;
    t->k[0] = -1;
    for (int c = 1; c < NBT_TABLE_MAX_CH; c++)
        t->k[c] = 0, t->max_err[c] = t->max_abs[c] = NAN;
    snprintf(t->phase, sizeof t->phase, "hg");
    if (t->kind == NBT_TABLE_H)
        t->n = 0;
    free(t->row_err); /* a refill records its own, or none */
    free(t->theta_err);
    t->row_err = t->theta_err = NULL;
    t->theta_cells = 0;
    if (form == NBT_FORM_TAIL)
        return nbt__tail_fill(t, o);
    /* the error measurement below knows the quadratic and linear stencils */
    if (t->interp2 != 1 && t->interp2 != 2)
        NBT_FAIL(NBT_EINVAL, "g-sliced table: interp2 must be 1 or 2 for the plain and log_et forms (3, cubic in g, "
                             "is the tail form's)");
    t->form = form;
    nbt_status st0 = NBT_OK;
    size_t nx = t->axis[0].n, ny = t->axis[1].n, ng = t->axis[2].n, ns = nx * ny;
    double qerr = 0, amax = 0;
    /* per T row (cell between T nodes i and i + 1) and theta band
     * (THETA_BANDS of them, cpb theta cells each): the slices' in-slice
     * error (srow), the g error at the nodes of the band's cells in the
     * row (grow) */
    size_t nr = nx - 1, cpb = (ny - 1 + THETA_BANDS - 1) / THETA_BANDS, nb = (ny - 1 + cpb - 1) / cpb;
    double *gs = calloc(ng, sizeof *gs), *serr = calloc(ng, sizeof *serr);
    double *srow = calloc(ng * nb * nr, sizeof *srow), *grow = calloc(nb * nr, sizeof *grow);
    nbt_table **sl = calloc(ng, sizeof *sl);
    if (!gs || !sl || !serr || !srow || !grow) {
        free(gs);
        free(sl);
        free(serr);
        free(srow);
        free(grow);
        NBT_FAIL(NBT_ENOMEM, "g-sliced table: out of memory");
    }
    /* the row bound where the slices record their rows (J) */
    int rows = o->measure_error && t->kind == NBT_TABLE_J;
    if (rows && (nbt_table_row_err_alloc(t) != NBT_OK || nbt_table_theta_err_alloc(t, cpb) != NBT_OK))
        st0 = NBT_ENOMEM;
    for (size_t m = 0; m < ng; m++)
        gs[m] = nbt_axis_node(&t->axis[2], m);
    nbt_status st = st0 != NBT_OK ? st0 : build_slices(t, gs, ng, o, gc, sl);
    for (size_t m = 0; m < ng && st == NBT_OK; m++) {
        memcpy(t->data + m * ns, sl[m]->data, ns * sizeof(float));
        serr[m] = o->measure_error ? sl[m]->max_err[0] : NAN;
        /* a slice without its bands: its slice-wide error in every one */
        for (size_t k = 0; rows && k < nb * nr; k++)
            srow[m * nb * nr + k] = sl[m]->theta_err && !isnan(sl[m]->theta_err[k]) ? sl[m]->theta_err[k] : serr[m];
        qerr = fmax(qerr, sl[m]->quad_err);
        amax = fmax(amax, sl[m]->max_abs[0]);
    }
    for (size_t m = 0; m < ng; m++) {
        nbt_table_free(sl[m]);
        sl[m] = NULL;
    }
    /* the interpolation in g: exact slices at every g midpoint against the
     * lookup at every (u, v) node (quadratic: both stencils that meet there) */
    nbt_build_opts om = *o;
    om.measure_error = 0;
    if (st == NBT_OK && o->measure_error) {
        for (size_t m = 0; m + 1 < ng; m++)
            gs[m] = nbt_axis_from_unit(&t->axis[2], ((double)m + 0.5) / (double)(ng - 1));
        st = build_slices(t, gs, ng - 1, &om, gc, sl);
    }
    int quad = t->interp2 == 2 && ng >= 3;
    double maxe = 0;
    for (size_t m = 0; m + 1 < ng && st == NBT_OK && o->measure_error; m++) {
        double gm = 0, se = 0;
        for (size_t k = 0; k < nb * nr; k++)
            grow[k] = 0;
        double *rerr = rows ? t->theta_err + m * nb * nr : NULL;
        for (size_t k = 0; rows && k < nb * nr; k++)
            rerr[k] = 0;
        for (size_t c = m; c <= m + 1; c++) {
            /* stencil centre and weights at the midpoint p = m + 1/2 */
            size_t mc = quad ? (c < 1 ? 1 : c > ng - 2 ? ng - 2 : c) : m;
            double tt = (double)m + 0.5 - (double)mc;
            double w[3];
            nbt__quad_weights(tt, w);
            if (!quad)
                w[0] = w[1] = 0.5, w[2] = 0.0; /* slices m, m + 1 */
            size_t m0 = quad ? mc - 1 : m; /* w[q] weighs slice m0 + q */
            for (int q = 0; q < 3; q++)
                if (w[q] != 0.0) {
                    se = fmax(se, serr[m0 + (size_t)q]);
                    for (size_t k = 0; rows && k < nb * nr; k++)
                        rerr[k] = fmax(rerr[k], srow[(m0 + (size_t)q) * nb * nr + k]);
                }
            for (size_t k = 0; k < ns; k++) {
                double v = 0;
                for (int q = 0; q < 3; q++)
                    if (w[q] != 0.0)
                        v += w[q] * (double)t->data[(m0 + (size_t)q) * ns + k];
                double d = fabs(v - (double)sl[m]->data[k]);
                gm = fmax(gm, d);
                /* node (i, j) = (k % nx, k / nx): the rows i - 1 and i
                 * and the theta cells j - 1 and j meet there */
                size_t i = k % nx, j = k / nx;
                for (size_t jc = j >= 1 ? j - 1 : 0; jc <= j && jc + 1 < ny; jc++) {
                    double *gb = grow + jc / cpb * nr;
                    if (i < nr)
                        gb[i] = fmax(gb[i], d);
                    if (i >= 1)
                        gb[i - 1] = fmax(gb[i - 1], d);
                }
            }
        }
        qerr = fmax(qerr, sl[m]->quad_err);
        /* in-slice errors weighted by sum |w| <= 1.25 (quadratic), 1 (linear) */
        double wsum = quad ? 1.25 : 1.0;
        t->cell_err[m] = gm + wsum * se;
        maxe = fmax(maxe, t->cell_err[m]);
        /* the same per row and band: the g error at its nodes and the
         * in-slice errors of its slices there; a row's is its bands' max */
        for (size_t k = 0; rows && k < nb * nr; k++)
            rerr[k] = grow[k] + wsum * rerr[k];
        if (rows)
            nbt__band_max(rerr, nb, nr, t->row_err + m * nr);
    }
    if (st == NBT_OK && o->measure_error)
        add_to_bounds(t, qerr);
    if (st != NBT_OK || !o->measure_error) {
        free(t->row_err);
        free(t->theta_err);
        t->row_err = t->theta_err = NULL;
        t->theta_cells = 0;
    }
    for (size_t m = 0; m < ng; m++)
        nbt_table_free(sl[m]);
    free(sl);
    free(gs);
    free(serr);
    free(srow);
    free(grow);
    if (st != NBT_OK)
        return st;
    t->quad_tol = o->quad_tol;
    t->quad_err = qerr;
    t->max_abs[0] = amax;
    t->max_err[0] = o->measure_error ? maxe + qerr : NAN;
    return NBT_OK;
}

/* ---- error-driven size ---- */

#define failf nbt__failf

static const size_t GSIZES[] = {9, 13, 17, 25, 33, 49, 65, 97, 129, 193, 257, 385, 513, 769, 1024};
#define NGSIZES (sizeof GSIZES / sizeof GSIZES[0])
/* the ends mapping's strength on H's v (c/2 at -pi/2, c at pi/2): of c = 8 .. 24
 * (lo 4 .. 12) on 97 x 193 x 33, c = 16 had the fewest rays above 1e-3 (5 of 1e5);
 * the symmetric form (log1p with c from both ends) had 13-14 */
#define NBT_GSLICE_V_ENDS_C 16.0
static const size_t PSIZES[] = {17, 33, 49, 65, 97, 129, 193, 257, 385, 513, 769, 1025, 1537, 2049, 3073, 4097};
#define NPSIZES (sizeof PSIZES / sizeof PSIZES[0])


/* uniform in atanh g (H's tail form is cubic in g, J's log_et form quadratic) */
static nbt_axis g_axis(const nbt_gslice_request *r, size_t n)
{
    return (nbt_axis){r->g[0], r->g[1], NBT_AXIS_ATANH, 0, n};
}

static nbt_status check_request(const nbt_gslice_request *r, char *err, size_t errlen)
{
    if (r->kind != NBT_TABLE_H && r->kind != NBT_TABLE_J)
        return failf(err, errlen, NBT_EINVAL, "g-sliced table: the kind must be H or J");
    if (r->kind == NBT_TABLE_J && (r->n < 1 || r->n > 10000))
        return failf(err, errlen, NBT_EDOM, "g-sliced table: n = %d is not accepted: 1 .. 10000", r->n);
    if (!(r->g[0] >= -NBT_GSLICE_GMAX && r->g[0] < r->g[1] && r->g[1] <= NBT_GSLICE_GMAX))
        return failf(err, errlen, NBT_EDOM, "g-sliced table: g = %g:%g is not accepted: -%g <= lo < hi <= %g",
                     r->g[0], r->g[1], NBT_GSLICE_GMAX, NBT_GSLICE_GMAX);
    if (!(r->xmax > 0 && r->xmax <= 1e6))
        return failf(err, errlen, NBT_EDOM, "g-sliced table: xmax = %g is not accepted: 0 < xmax <= 1e6", r->xmax);
    if (!(r->tol >= 0 && r->tol < 1))
        return failf(err, errlen, NBT_EDOM, "g-sliced table: tol = %g is not accepted: 0 (fixed size) or in (0, 1)",
                     r->tol);
    if (r->tol == 0 && (r->size[0] < 2 || r->size[1] < 2 || r->size[0] > 4096 || r->size[1] > 4096 ||
                        r->size[2] < 2 || r->size[2] > 1024))
        return failf(err, errlen, NBT_EDOM, "g-sliced table: size %zux%zux%zu is not accepted: 2 .. 4096 per axis, "
                     "g 2 .. 1024", r->size[0], r->size[1], r->size[2]);
    return NBT_OK;
}

static nbt_status build_at(const nbt_gslice_request *r, const nbt_axis *a0, const nbt_axis *a1, size_t ng,
                           unsigned nthreads, int measure, nbt__jcache *gc, nbt_table **out)
{
    nbt_axis a2 = g_axis(r, ng);
    *out = nbt_table_alloc3(r->kind, a0, a1, &a2, 1);
    if (!*out)
        NBT_FAIL(NBT_ENOMEM, "g-sliced table: out of memory or too large");
    (*out)->n = r->kind == NBT_TABLE_J ? r->n : 0;
    if (r->kind == NBT_TABLE_J) { /* ln(e^T J), quadratic in g */
        (*out)->form = NBT_FORM_LOG_ET;
        (*out)->interp2 = ng >= 3 ? 2 : 1;
    }
    nbt_build_opts o = {1e-10, measure, nthreads};
    nbt_status st = fill_form(*out, default_form(*out), &o, gc);
    if (st != NBT_OK) {
        nbt_table_free(*out);
        *out = NULL;
    }
    return st;
}

/* Sizes by rules measured with bench/bench_gslice (doc/tables.md), no
 * error-driven proxies: at tol 1e-3 relative,
 *   H (tail form): u 97 nodes (log1p_cbrt, c = 10), v 193 (ends, c = 16:
 *     HG's peaks of width ~1 - |g| at v = pi/2 for g < 0 and -pi/2 for g > 0;
 *     with bench/gslice_accuracy on 1e5 rays, 4.9 MB, quadratic in g: 5 rays
 *     above 1e-3, worst 1.2e-3 (cubic in g, as filled now: none, worst
 *     7.9e-4), where 129^2 on cos (4.4 MB) had 487, worst 3.5e-3; the
 *     v error dominated: 129 x 257 on cos had none above);
 *   J (log_et form, T <= 20): T 65 nodes (log1p_cbrt, c = 20), theta 257
 *     (linear for Lambert, cos for Phong lobes);
 * the bilinear error falling as N^-2; g uniform in atanh with 33 slices for
 * atanh(g) spanning [-atanh 0.95, atanh 0.95] at 1e-3, quadratic, so the
 * slice count scales with the atanh span and tol^(-1/3). The predicted
 * time scales a small proxy's by the node count. */
static size_t ladder_at_least(const size_t *lad, size_t n, double want)
{
    for (size_t i = 0; i < n; i++)
        if ((double)lad[i] >= want - 1e-9)
            return lad[i];
    return lad[n - 1];
}

static nbt_status plan_rule(const nbt_gslice_request *r, unsigned nthreads, nbt__jcache *gc,
                            nbt_gslice_plan_t *out, double t0, char *err, size_t errlen)
{
    int H = r->kind == NBT_TABLE_H;
    size_t n0 = r->size[0] > 0 ? r->size[0] : H ? 97 : 65, n1 = r->size[1] > 0 ? r->size[1] : H ? 193 : 257;
    size_t ng = r->size[2];
    if (r->tol > 0) {
        double q = 1e-3 / r->tol, span = (atanh(r->g[1]) - atanh(r->g[0])) / (2.0 * atanh(0.95));
        n0 = ladder_at_least(PSIZES, NPSIZES, (H ? 97.0 : 65.0) * sqrt(q));
        n1 = ladder_at_least(PSIZES, NPSIZES, (H ? 193.0 : 257.0) * sqrt(q));
        ng = ladder_at_least(GSIZES, NGSIZES, fmax(5.0, 1.0 + 32.0 * span * cbrt(q)));
        n0 = n0 > 4096 ? 4096 : n0;
        n1 = n1 > 4096 ? 4096 : n1;
    }
    if (H) {
        out->axis[0] = (nbt_axis){0.0, r->xmax, NBT_AXIS_LOG1P_CBRT, 10.0, n0};
        out->axis[1] = (nbt_axis){-NBT_PI_2, NBT_PI_2, NBT_AXIS_ENDS, NBT_GSLICE_V_ENDS_C, n1};
    } else {
        out->axis[0] = (nbt_axis){0.0, r->xmax, NBT_AXIS_LOG1P_CBRT, 20.0, n0};
        out->axis[1] = (nbt_axis){0.0, NBT_PI, r->n == 1 ? NBT_AXIS_LINEAR : NBT_AXIS_COS, 0.0, n1};
    }
    out->axis[2] = g_axis(r, ng);
    out->pred_err = r->tol;
    /* the time: a 33x33x3 proxy through the same code (error measurement
     * included), scaled by the node count, so that it compares with the
     * Legendre planner's measured proxies on this machine and build. In a
     * set (gc) the proxies of J^1 and J^n share their G rows (the same T
     * nodes and g), as the tables do: the later ones predict what they cost
     * there */
    nbt_axis p0 = out->axis[0], p1 = out->axis[1];
    p0.n = p1.n = 33;
    nbt_table *proxy;
    double tp = nbt__now_s();
    nbt_status st = build_at(r, &p0, &p1, 3, nthreads, 1, gc, &proxy);
    tp = nbt__now_s() - tp;
    nbt_table_free(proxy);
    if (st != NBT_OK)
        return nbt__failf(err, errlen, st, "g-sliced table: the proxy build failed: %s", nbt_strerror(st));
    out->pred_seconds = tp * (double)n0 * (double)n1 * (double)ng / (33.0 * 33.0 * 3.0);
    out->bytes = (double)n0 * (double)n1 * (double)ng * (H ? 2.0 : 1.0) * (r->half ? 2.0 : 4.0);
    out->plan_seconds = nbt__now_s() - t0;
    return NBT_OK;
}

static nbt_status plan_gc(const nbt_gslice_request *r, unsigned nthreads, nbt__jcache *gc, nbt_gslice_plan_t *out,
                          char *err, size_t errlen)
{
    memset(out, 0, sizeof *out);
    out->req = *r;
    double t0 = nbt__now_s();
    nbt_status st = check_request(r, err, errlen);
    if (st != NBT_OK)
        return st;
    return plan_rule(r, nthreads, gc, out, t0, err, errlen);
}

nbt_status nbt_gslice_plan(const nbt_gslice_request *r, unsigned nthreads, nbt_gslice_plan_t *out, char *err,
                           size_t errlen)
{
    return plan_gc(r, nthreads, NULL, out, err, errlen);
}

static nbt_status execute(const nbt_gslice_plan_t *p, unsigned nthreads, nbt__jcache *gc, nbt_table **out,
                          char *err, size_t errlen);

nbt_status nbt_gslice_execute(const nbt_gslice_plan_t *p, unsigned nthreads, nbt_table **out, char *err,
                              size_t errlen)
{
    return execute(p, nthreads, NULL, out, err, errlen);
}

static nbt_status execute(const nbt_gslice_plan_t *p, unsigned nthreads, nbt__jcache *gc, nbt_table **out,
                          char *err, size_t errlen)
{
    /* sized by the plan's rule: the recorded max_err does not decide (tail:
     * set by the corner u -> 0, v -> pi/2, where the error map bounds each
     * lookup; log_et: the slices' largest error, set by the horizon at
     * large T; doc/tables.md) */
    const nbt_gslice_request *r = &p->req;
    nbt_status st = build_at(r, &p->axis[0], &p->axis[1], p->axis[2].n, nthreads, 1, gc, out);
    if (st != NBT_OK)
        return failf(err, errlen, st, "g-sliced table: the build failed: %s", nbt_strerror(st));
    if (r->half && (*out)->form == NBT_FORM_TAIL)
        return nbt__tail_round_half(*out);
    if (r->half && (*out)->form == NBT_FORM_LOG_ET) {
        /* ln(e^T J) rounded to half: the largest change at a node, times the
         * lookup's weight sum, is an error in ln J, i.e. relative */
        nbt_table *t = *out;
        double e = nbt__lookup_weight_sum(t) * nbt__table_round_half_change(t, 0);
        add_to_bounds(t, e);
        t->max_err[0] += e;
    } else if (r->half)
        nbt_table_round_half(*out);
    return NBT_OK;
}

static nbt_status build_gc(const nbt_gslice_request *r, unsigned nthreads, nbt__jcache *gc, nbt_table **out,
                           double *seconds, char *err, size_t errlen)
{
    *out = NULL;
    double t0 = nbt__now_s();
    nbt_gslice_plan_t p;
    nbt_status st = plan_gc(r, nthreads, gc, &p, err, errlen);
    if (st == NBT_OK)
        st = execute(&p, nthreads, gc, out, err, errlen);
    if (seconds)
        *seconds = nbt__now_s() - t0;
    return st;
}

nbt_status nbt_gslice_build(const nbt_gslice_request *r, unsigned nthreads, nbt_table **out, double *seconds,
                            char *err, size_t errlen)
{
    return build_gc(r, nthreads, NULL, out, seconds, err, errlen);
}

/* the G rows of a 1e-3 J^1 + J^20 pair (65 T nodes and the measured
 * midpoints, both g passes, the check): about 12 MB; beyond this a build
 * computes its rows again */
#define GSLICE_JCACHE_BYTES ((size_t)256 << 20)

nbt_status nbt_gslice_build_set(const nbt_gslice_request *r, size_t n, unsigned nthreads, nbt_table **out,
                                double *seconds, char *err, size_t errlen)
{
    for (size_t i = 0; i < n; i++)
        out[i] = NULL;
    nbt__jcache *gc = nbt__jcache_alloc(GSLICE_JCACHE_BYTES);
    if (!gc)
        return failf(err, errlen, NBT_ENOMEM, "g-sliced tables: out of memory");
    nbt_status st = NBT_OK;
    for (size_t i = 0; i < n && st == NBT_OK; i++)
        st = build_gc(&r[i], nthreads, gc, &out[i], seconds ? &seconds[i] : NULL, err, errlen);
    nbt__jcache_free(gc);
    for (size_t i = 0; i < n && st != NBT_OK; i++) {
        nbt_table_free(out[i]);
        out[i] = NULL;
    }
    return st;
}

/* ---- mixtures of HG lobes ---- */

typedef struct {
    const nbt_table *t, *t2;
    const nbt_airlight_geom *ag;
    const nbt_surface_geom *sg;
    double fallback_tol;
} mix_ctx;

static nbt_status mix_lobe(const mix_ctx *c, double g, double *L, double *E)
{
    return c->ag ? nbt_airlight_table_g(c->t, g, c->ag, L, E)
                 : nbt_surface_table_g(c->t, c->t2, g, c->sg, c->fallback_tol, L, E);
}

/* sum_i w_i (lobe i), bound sum_i |w_i| (its bound): the quantity is linear in p */
static nbt_status hg_mix(const mix_ctx *c, size_t n, const double *w, const double *g, double *L, double *abserr)
{
    *L = *abserr = NAN;
    double ws = 0;
    for (size_t i = 0; i < n && n <= NBT_HG_MIX_MAX; i++)
        ws += w[i];
    if (n < 1 || n > NBT_HG_MIX_MAX || !(fabs(ws - 1.0) <= 1e-12))
        NBT_FAIL(NBT_EDOM, "HG mixture: 1 to 8 lobes whose weights sum to 1");
    nbt_status st = NBT_OK;
    double s = 0, e = 0;
    for (size_t i = 0; i < n; i++) {
        double Li, Ei;
        nbt_status si = mix_lobe(c, g[i], &Li, &Ei);
        if (si != NBT_OK && si != NBT_ETOL)
            return si;
        if (st == NBT_OK)
            st = si;
        s += w[i] * Li;
        e += fabs(w[i]) * Ei;
    }
    *L = s;
    *abserr = e;
    return st;
}

nbt_status nbt_airlight_table_hg_mix(const nbt_table *t, size_t n, const double *w, const double *g,
                                     const nbt_airlight_geom *geo, double *La, double *abserr)
{
    mix_ctx c = {t, NULL, geo, NULL, 0.0};
    return hg_mix(&c, n, w, g, La, abserr);
}

nbt_status nbt_surface_table_hg_mix(const nbt_table *diffuse, const nbt_table *specular, size_t n, const double *w,
                                    const double *g, const nbt_surface_geom *geo, double fallback_tol, double *Lp,
                                    double *abserr)
{
    mix_ctx c = {diffuse, specular, NULL, geo, fallback_tol};
    return hg_mix(&c, n, w, g, Lp, abserr);
}

/* ---- Legendre packs or g slices ---- */

const char *nbt_basis_name(nbt_basis b)
{
    return b == NBT_BASIS_LEGENDRE ? "legendre" : b == NBT_BASIS_SLICES ? "slices" : "auto";
}

nbt_status nbt_basis_parse(const char *name, nbt_basis *b)
{
    if (!strcmp(name, "auto"))
        *b = NBT_BASIS_AUTO;
    else if (!strcmp(name, "legendre"))
        *b = NBT_BASIS_LEGENDRE;
    else if (!strcmp(name, "slices"))
        *b = NBT_BASIS_SLICES;
    else
        return NBT_EINVAL;
    return NBT_OK;
}

/* --basis auto takes slices when their predicted build is this many times faster */
#define AUTO_SLICES_GAIN 1.5

nbt_status nbt_basis_choose(const nbt_gslice_request *r, size_t orders_max, nbt_basis want, unsigned nthreads,
                            nbt_basis_choice *out, char *err, size_t errlen)
{
    memset(out, 0, sizeof *out);
    out->leg_seconds = out->leg_bytes = out->sl_seconds = out->sl_bytes = INFINITY;
    out->leg_err = out->sl_err = NAN;
    if (want != NBT_BASIS_AUTO && want != NBT_BASIS_LEGENDRE && want != NBT_BASIS_SLICES)
        return failf(err, errlen, NBT_EINVAL, "basis %d is not accepted: auto, legendre or slices", (int)want);
    if (!(r->tol > 0 && r->tol < 1))
        return failf(err, errlen, NBT_EDOM, "basis: tol = %g is not accepted: in (0, 1)", r->tol);
    double gmax = fmax(fabs(r->g[0]), fabs(r->g[1]));
    double leg_wall = 0, leg_cpu = 0, sl_wall = 0, sl_cpu = 0;
    nbt_status st;
    if (want != NBT_BASIS_SLICES) {
        nbt_plan_legendre leg;
        st = nbt_plan_legendre_terms(gmax, r->xmax, r->tol, orders_max, &leg);
        out->leg_nterms = leg.nterms;
        if (st == NBT_OK) {
            nbt_plan_request q = {r->kind, r->kind == NBT_TABLE_J ? r->n : 0, leg.nterms, NULL, r->xmax,
                                  leg.table_tol, {0, 0}, r->half, 0};
            nbt_plan *plan = NULL;
            double w0 = nbt__now_s(), c0 = nbt__cpu_s();
            if ((st = nbt_plan_tables(&q, 1, nthreads, &plan, err, errlen)) != NBT_OK)
                return st;
            leg_wall = nbt__now_s() - w0;
            leg_cpu = nbt__cpu_s() - c0;
            const nbt_plan_set *ps = nbt_plan_get(plan, 0);
            out->leg_seconds = ps->pred_seconds;
            out->leg_err = ps->pred_err;
            out->leg_bytes = (double)ps->axis[0].n * (double)ps->axis[1].n * 4.0 * (double)ps->npacks *
                             (r->half ? 2.0 : 4.0);
            nbt_plan_free(plan);
        } else if (st != NBT_ETOL)
            return failf(err, errlen, st, "basis: the Legendre budget failed: %s", nbt_strerror(st));
    }
    if (want != NBT_BASIS_LEGENDRE) {
        nbt_gslice_plan_t p;
        double w0 = nbt__now_s(), c0 = nbt__cpu_s();
        if ((st = nbt_gslice_plan(r, nthreads, &p, err, errlen)) != NBT_OK)
            return st;
        sl_wall = nbt__now_s() - w0;
        sl_cpu = nbt__cpu_s() - c0;
        out->sl_seconds = p.pred_seconds;
        out->sl_bytes = p.bytes;
        out->sl_err = p.pred_err;
        out->sl_size[0] = p.axis[0].n;
        out->sl_size[1] = p.axis[1].n;
        out->sl_size[2] = p.axis[2].n;
        out->sl_plan = p;
    }
    if (want == NBT_BASIS_LEGENDRE && isinf(out->leg_seconds))
        return failf(err, errlen, NBT_ETOL, "basis legendre: |g| up to %g needs %s%zu Legendre orders at tol %g, more "
                     "than %zu: use basis slices", gmax, out->leg_nterms > 512 ? "more than " : "",
                     out->leg_nterms > 512 ? (size_t)512 : out->leg_nterms, r->tol, orders_max);
    if (want != NBT_BASIS_AUTO) {
        out->basis = want;
        snprintf(out->reason, sizeof out->reason, "%s: requested", nbt_basis_name(want));
    } else if (isinf(out->leg_seconds)) {
        out->basis = NBT_BASIS_SLICES;
        snprintf(out->reason, sizeof out->reason,
                 "slices: |g| up to %g needs %s%zu Legendre orders at tol %g (at most %zu); slices %zux%zux%zu, "
                 "%.1f MB, predicted %.2g s", gmax, out->leg_nterms > 512 ? "more than " : "",
                 out->leg_nterms > 512 ? (size_t)512 : out->leg_nterms, r->tol, orders_max, out->sl_size[0],
                 out->sl_size[1], out->sl_size[2], 1e-6 * out->sl_bytes, out->sl_seconds);
    } else {
        /* compared in CPU time (the work), not wall time: the proxies take a few 0.01 s and their wall
         * times moved 6x against each other with the machine's load (example scene: Legendre 0.011 s vs
         * slices 0.04 s idle, 0.092 s vs 0.056 s loaded), so that a scene's basis flipped with the load;
         * and slices only when clearly cheaper */
        double lc = as_cpu(out->leg_seconds, leg_cpu, leg_wall), sc = as_cpu(out->sl_seconds, sl_cpu, sl_wall);
        out->basis = lc <= AUTO_SLICES_GAIN * sc ? NBT_BASIS_LEGENDRE : NBT_BASIS_SLICES;
        snprintf(out->reason, sizeof out->reason,
                 "%s: predicted build Legendre %zu orders %.2g s (CPU %.2g s), %.1f MB; slices %zux%zux%zu %.2g s "
                 "(CPU %.2g s), %.1f MB", nbt_basis_name(out->basis), out->leg_nterms, out->leg_seconds, lc,
                 1e-6 * out->leg_bytes, out->sl_size[0], out->sl_size[1], out->sl_size[2], out->sl_seconds, sc,
                 1e-6 * out->sl_bytes);
    }
    return NBT_OK;
}

/* ---- evaluation ---- */

static nbt_status check_g(const nbt_table *t, double g, nbt_table_kind kind)
{
    if (!nbt_table_is_gslice(t) || t->kind != kind)
        NBT_FAIL(NBT_EINVAL, kind == NBT_TABLE_H ? "airlight: the table is not a g-sliced H table"
                                                 : "surface: the table is not a g-sliced J table");
    if (!(g >= t->axis[2].lo && g <= t->axis[2].hi))
        NBT_FAIL(NBT_EDOM, "g lies outside the table's g range");
    return NBT_OK;
}

static nbt_status check_airlight_g(const nbt_table *t, double g, const nbt_airlight_geom *geo)
{
    nbt_status st = nbt_airlight_check(geo);
    return st != NBT_OK ? st : check_g(t, g, NBT_TABLE_H);
}

nbt_status nbt_airlight_table_g_lookup(const nbt_table *t, double g, const nbt_airlight_geom *geo, double *La,
                                       double *abserr)
{
    nbt_status st = check_airlight_g(t, g, geo);
    if (st != NBT_OK)
        return st;
    double h = geo->dsv * sin(geo->gamma), tt = geo->dsv * cos(geo->gamma);
    if (!(h > 0.0))
        NBT_FAIL(NBT_EDOM, "airlight: the lookup is undefined on the source axis (gamma = 0 or pi)");
    if (t->form == NBT_FORM_TAIL) {
        int gauss;
        nbt__airlight_tail(t, g, geo, La, abserr, &gauss);
    } else {
        double u = geo->kappa_t * h, th0 = geo->gamma - NBT_PI_2, a[NBT_TABLE_MAX_CH], b[NBT_TABLE_MAX_CH];
        double thd = isinf(geo->dvp) ? NBT_PI_2 : atan2(geo->dvp - tt, h);
        nbt_table_lookup3(t, u, thd, g, a);
        nbt_table_lookup3(t, u, th0, g, b);
        nbt__airlight_from_diff(geo, h, tt, a[0] - b[0], 2.0 * t->max_err[0], La, abserr);
    }
    return geo->kappa_t * h > t->axis[0].hi ? NBT_ETOL : NBT_OK;
}

nbt_status nbt_airlight_table_g(const nbt_table *t, double g, const nbt_airlight_geom *geo, double *La,
                                double *abserr)
{
    nbt_status st = check_airlight_g(t, g, geo);
    if (st != NBT_OK)
        return st;
    double h = geo->dsv * sin(geo->gamma);
    double Lt = NAN, Et = INFINITY;
    int outside = 0;
    if (h > 0.0) {
        st = nbt_airlight_table_g_lookup(t, g, geo, &Lt, &Et);
        outside = st == NBT_ETOL;
        /* tail form: the ray integral where the bound misses 1e-3; plain: 10% */
        double frac = t->form == NBT_FORM_TAIL ? NBT_TAIL_RAY_TOL : NBT__TABLE_RAY_FRAC;
        if (isnan(Et) || Et <= frac * fabs(Lt)) {
            *La = Lt;
            *abserr = Et;
            return st;
        }
    }
    nbt_phase *p = nbt_phase_hg(g);
    if (!p)
        NBT_FAIL(NBT_ENOMEM, "airlight: out of memory");
    st = nbt__airlight_ray_or_lookup(p, NULL, 0, geo, h, Lt, Et, outside, La, abserr);
    nbt_phase_free(p);
    return st;
}

nbt_status nbt_scene_basis(const nbt_scene *s, unsigned nthreads, nbt_basis_choice *out, char *err, size_t errlen)
{
    nbt_status st = nbt_scene_check(s, err, errlen);
    if (st != NBT_OK)
        return st;
    if (!s->have_g)
        return failf(err, errlen, NBT_EINVAL, "basis: the scene has no g range");
    nbt_basis want = (nbt_basis)s->basis;
    if (!(s->g[0] < s->g[1]))
        want = NBT_BASIS_LEGENDRE; /* one g (basis slices is refused by the check) */
    nbt_gslice_request r = {s->airlight ? NBT_TABLE_H : NBT_TABLE_J, s->airlight || s->diffuse ? 1 : s->phong[0],
                            s->kappa_t[1] * s->distance[1], {s->g[0], s->g[1]}, s->tol, {0, 0, 0}, s->half};
    return nbt_basis_choose(&r, s->orders_max, want, nthreads, out, err, errlen);
}
