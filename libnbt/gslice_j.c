/* libnbt/gslice_j.c: the J side of g-sliced tables (nbt/gslice.h): the
 * slices of J_p^n(T, theta; g) in the table's value form, the value and
 * bound of a lookup, surface radiance from g-sliced J^1 and J^n tables. */
#include <config.h>
#include <math.h>
#include <stdio.h>
#include <nbt/gslice.h>
#include "internal.h"
#include "gslice_j.h"

double nbt__gslice_j_at(const nbt_table *t, double T, double theta, double g, double *err)
{
    /* the bound of the T row, theta band and g cell the lookup interpolates
     * in (older files: the row's, or the g cell's) */
    double v, e = nbt_table_err_at3(t, 0, T, theta, g);
    nbt_table_lookup3(t, T, theta, g, &v);
    if (t->form != NBT_FORM_LOG_ET) {
        *err = e;
        return v;
    }
    /* v and the true T + ln J differ by at most e: J within J_lookup e^{+-e} */
    v = exp(v - T);
    *err = v * expm1(e);
    return v;
}

nbt_status nbt__gslice_j_slices(const nbt_table *t, const double *g, size_t m, const nbt_build_opts *o,
                                nbt__jcache *gc, nbt_table **out)
{
    nbt_status st = NBT_OK;
    for (size_t i = 0; i < m; i++) {
        out[i] = nbt_table_alloc(NBT_TABLE_J, &t->axis[0], &t->axis[1], 1);
        if (!out[i]) {
            st = nbt__fail(NBT_ENOMEM, "g-sliced J table: out of memory");
            continue;
        }
        out[i]->k[0] = -1;
        out[i]->n = t->n;
        /* the in-slice error per T row too (nbt_gslice_fill's row bound) */
        if (o->measure_error && (nbt_table_row_err_alloc(out[i]) != NBT_OK ||
                                 (t->theta_err && nbt_table_theta_err_alloc(out[i], t->theta_cells) != NBT_OK)))
            st = nbt__fail(NBT_ENOMEM, "g-sliced J table: out of memory");
        out[i]->form = t->form;
        snprintf(out[i]->phase, sizeof out[i]->phase, "hg:%.17g", g[i]);
    }
    /* all slices in one pass (one quadrature per node for every g) */
    if (st == NBT_OK)
        st = nbt__j_table_build_hg(out, m, g, o, gc);
    for (size_t i = 0; i < m && st != NBT_OK; i++) {
        nbt_table_free(out[i]);
        out[i] = NULL;
    }
    return st;
}

static nbt_status check_gj(const nbt_table *t, double g)
{
    if (!nbt_table_is_gslice(t) || t->kind != NBT_TABLE_J)
        NBT_FAIL(NBT_EINVAL, "surface: the table is not a g-sliced J table");
    if (!(g >= t->axis[2].lo && g <= t->axis[2].hi))
        NBT_FAIL(NBT_EDOM, "g lies outside the table's g range");
    return NBT_OK;
}

static double surface_direct_term(const nbt_surface_geom *g)
{
    double cs = fmax(cos(g->theta_s), 0.0), cr = fmax(cos(g->theta_r), 0.0);
    return g->I0 * exp(-g->kappa_t * g->dsp) / (g->dsp * g->dsp) * (g->kd * cs + g->ks * pow(cr, g->n));
}

nbt_status nbt_surface_table_g(const nbt_table *diffuse, const nbt_table *specular, double g,
                               const nbt_surface_geom *geo, double fallback_tol, double *Lp, double *abserr)
{
    nbt_status st = nbt_surface_check(geo);
    if (st != NBT_OK)
        return st;
    if ((geo->kd > 0 && !diffuse) || (geo->ks > 0 && !specular))
        NBT_FAIL(NBT_EINVAL, "surface: a lobe with a non-zero coefficient has no table");
    if (diffuse && (st = check_gj(diffuse, g)) != NBT_OK)
        return st;
    if (specular && (st = check_gj(specular, g)) != NBT_OK)
        return st;
    if (diffuse && diffuse->n != 1)
        NBT_FAIL(NBT_EINVAL, "surface: the diffuse table must have n = 1");
    if (specular && specular->n != geo->n)
        NBT_FAIL(NBT_EINVAL, "surface: the specular table must have the geometry's n");
    double T = geo->kappa_t * geo->dsp, sd = 0, ss = 0, ed = 0, es = 0;
    int out = 0;
    if (geo->kd > 0) {
        sd = nbt__gslice_j_at(diffuse, T, geo->theta_s, g, &ed);
        out |= T > diffuse->axis[0].hi;
    }
    if (geo->ks > 0) {
        ss = nbt__gslice_j_at(specular, T, geo->theta_r, g, &es);
        out |= T > specular->axis[0].hi;
    }
    double f = geo->kappa_s * geo->I0 / (4.0 * NBT_PI * geo->dsp);
    *Lp = surface_direct_term(geo) + f * (geo->kd * sd + geo->ks * ss);
    *abserr = f * (geo->kd * ed + geo->ks * es);
    if (fallback_tol > 0 && !(*abserr <= NBT__TABLE_RAY_FRAC * fabs(*Lp))) {
        nbt_phase *p = nbt_phase_hg(g);
        if (!p)
            NBT_FAIL(NBT_ENOMEM, "surface: out of memory");
        double L, E;
        st = nbt_surface_direct(p, geo, fallback_tol, &L, &E);
        nbt_phase_free(p);
        if (st == NBT_OK || (st == NBT_ETOL && E < *abserr)) {
            *Lp = L;
            *abserr = E;
            return st;
        }
    }
    return out ? NBT_ETOL : NBT_OK;
}
