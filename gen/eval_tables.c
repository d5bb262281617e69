/* gen/eval_tables.c: "nbt-gen eval airlight|surface --method table --tables
 * FILE.exr [FILE.exr ...]": airlight or surface radiance from given table
 * files (Legendre packs, one fixed-phase table, or a g-sliced table)
 * instead of building them; the value and the bound the tables record. */
#include <config.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "cli.h"
#include "commands.h"

typedef struct {
    nbt_table *t[64];
    size_t n;
} tlist;

static void tlist_free(tlist *l)
{
    for (size_t i = 0; i < l->n; i++)
        nbt_table_free(l->t[i]);
    l->n = 0;
}

/* Legendre truncation beyond K orders: |series(2K) - series(K)|, the
 * first neglected block bounding a decaying tail (as eval's series) */
static double truncation(int surface, const void *geo, const nbt_phase *p, size_t K)
{
    double *b = malloc((2 * K + 1) * sizeof(double)), v1 = 0, v2 = 0, e;
    if (!b || nbt_phase_moments(p, 2 * K, b) != NBT_OK)
        die("cannot compute the Legendre moments");
    if (surface) {
        nbt_surface_series(b, K, geo, 1e-10, &v1, &e);
        nbt_surface_series(b, 2 * K, geo, 1e-10, &v2, &e);
    } else {
        nbt_airlight_series(b, K, geo, 1e-10, &v1, &e);
        nbt_airlight_series(b, 2 * K, geo, 1e-10, &v2, &e);
    }
    free(b);
    return fabs(v2 - v1);
}

int eval_from_tables(int surface, const void *geo, const char *const *files, size_t nfiles, const char *g_arg,
                     const char *phase_arg)
{
    const char *cmd = surface ? "surface" : "airlight";
    nbt_table_kind want = surface ? NBT_TABLE_J : NBT_TABLE_H;
    const nbt_surface_geom *sg = geo;
    tlist L = {{0}, 0};
    int nslice = 0, nfixed = 0, nleg = 0;
    if (nfiles > 64)
        die_usage("--tables: %zu files given, at most 64 accepted", nfiles);
    for (size_t i = 0; i < nfiles; i++) {
        char err[512];
        nbt_table *t;
        if (nbt_table_read_exr(files[i], &t, err, sizeof err) != NBT_OK)
            die_usage("--tables: %s", err);
        L.t[L.n++] = t;
        if (t->kind != want)
            die_usage("--tables: '%s' is a %s table; eval %s takes %s tables", files[i], nbt_table_kind_name(t->kind),
                      cmd, nbt_table_kind_name(want));
        if (surface && t->n != 1 && t->n != sg->n)
            die_usage("--tables: '%s' has n = %d; eval surface takes n = 1 (diffuse) or n = %d (--n) tables", files[i],
                      t->n, sg->n);
        if (nbt_table_is_gslice(t))
            nslice++;
        else if (t->axis[2].n >= 2)
            die_usage("--tables: '%s' is a 3-D table but not a g-sliced HG one", files[i]);
        else if (t->k[0] < 0)
            nfixed++;
        else
            nleg++;
    }
    if ((nslice > 0) + (nfixed > 0) + (nleg > 0) != 1)
        die_usage("--tables: the files mix Legendre, fixed-phase and g-sliced tables: give one kind");
    double v = NAN, e = NAN, g = 0;
    nbt_status st;
    const char *what;
    if (nslice || nleg) {
        if (nslice && phase_arg)
            die_usage("--tables: g-sliced tables take the run-time asymmetry with --g G, not --phase");
        if (!g_arg && !phase_arg)
            die_usage("--tables: %s tables need the phase: --g G%s", nslice ? "g-sliced" : "Legendre",
                      nslice ? "" : " or --phase SPEC");
    } else if (g_arg || phase_arg)
        die_usage("--tables: a fixed-phase table fixes the phase ('%s'): --g and --phase do not apply", L.t[0]->phase);
    if (g_arg)
        g = opt_double("--g", g_arg, -1, 1, 1, 1);
    if (nslice) {
        const nbt_table *dif = NULL, *spe = NULL;
        for (size_t i = 0; i < L.n; i++) {
            if (!(g >= L.t[i]->axis[2].lo && g <= L.t[i]->axis[2].hi))
                die_usage("--g: %g is not accepted: '%s' covers g in [%g, %g]", g, files[i], L.t[i]->axis[2].lo,
                          L.t[i]->axis[2].hi);
            if (surface && L.t[i]->n == sg->n && sg->ks > 0)
                spe = L.t[i];
            if (surface && L.t[i]->n == 1)
                dif = L.t[i];
        }
        if (!surface) {
            if (L.n != 1)
                die_usage("--tables: eval airlight takes one g-sliced H table, %zu given", L.n);
            st = nbt_airlight_table_g(L.t[0], g, geo, &v, &e);
        } else {
            if ((sg->kd > 0 && !dif) || (sg->ks > 0 && !spe))
                die_usage("--tables: no g-sliced J table for the %s lobe (n = %d)", sg->kd > 0 && !dif ? "diffuse" : "specular",
                          sg->kd > 0 && !dif ? 1 : sg->n);
            /* the airlight route's policy: where the bound exceeds 10% of the
             * value, the direct integral */
            st = nbt_surface_table_g(dif, spe, g, sg, 1e-9, &v, &e);
        }
        what = "g-sliced";
    } else if (nfixed) {
        if (!surface) {
            if (L.n != 1)
                die_usage("--tables: eval airlight takes one fixed-phase H table, %zu given", L.n);
            st = nbt_airlight_table_e((const nbt_table *const *)L.t, 1, NULL, 0, NULL, geo, &v, &e);
        } else {
            const nbt_table *d[1] = {NULL}, *s[1] = {NULL};
            for (size_t i = 0; i < L.n; i++) {
                if (L.t[i]->n == 1)
                    d[0] = L.t[i];
                if (L.t[i]->n == sg->n)
                    s[0] = L.t[i];
            }
            if ((sg->kd > 0 && !d[0]) || (sg->ks > 0 && !s[0]))
                die_usage("--tables: no fixed-phase J table for the %s lobe", sg->kd > 0 && !d[0] ? "diffuse" : "specular");
            st = nbt_surface_table(d, d[0] != NULL, s, s[0] != NULL, NULL, 0, sg, &v);
            e = sg->kappa_s * sg->I0 / (4 * M_PI * sg->dsp) *
                (sg->kd * (d[0] ? d[0]->max_err[0] : 0) + sg->ks * (s[0] ? s[0]->max_err[0] : 0));
        }
        what = "fixed-phase";
    } else {
        nbt_phase *p = NULL;
        char err[256];
        if (g_arg && phase_arg)
            die_usage("eval: --g and --phase exclude each other");
        if (g_arg)
            p = nbt_phase_hg(g);
        else if (nbt_phase_parse(phase_arg, &p, err, sizeof err) != NBT_OK)
            die_usage("--phase: %s", err);
        size_t K = 0;
        for (size_t i = 0; i < L.n; i++)
            for (size_t c = 0; c < L.t[i]->nch; c++)
                if ((size_t)L.t[i]->k[c] + 1 > K)
                    K = (size_t)L.t[i]->k[c] + 1;
        double *b = malloc((K + 1) * sizeof(double));
        if (!p || !b || nbt_phase_moments(p, K, b) != NBT_OK)
            die("cannot compute the Legendre moments");
        if (!surface)
            st = nbt_airlight_table_e((const nbt_table *const *)L.t, L.n, b, K, NULL, geo, &v, &e);
        else {
            const nbt_table *d[64], *s[64];
            size_t nd = 0, ns = 0;
            double w = 0;
            for (size_t i = 0; i < L.n; i++) {
                const nbt_table *t = L.t[i];
                int isd = t->n == 1, iss = t->n == sg->n;
                if (isd)
                    d[nd++] = t;
                if (iss)
                    s[ns++] = t;
                for (size_t c = 0; c < t->nch; c++)
                    w += (isd * sg->kd + iss * sg->ks) * fabs((2.0 * t->k[c] + 1.0) * b[t->k[c]]) * t->max_err[c];
            }
            if ((sg->kd > 0 && nd == 0) || (sg->ks > 0 && ns == 0))
                die_usage("--tables: no Legendre J tables for the %s lobe", sg->kd > 0 && nd == 0 ? "diffuse" : "specular");
            st = nbt_surface_table(d, nd, s, ns, b, K, sg, &v);
            e = sg->kappa_s * sg->I0 / (4 * M_PI * sg->dsp) * w;
        }
        double tr = truncation(surface, geo, p, K);
        fprintf(stderr, "nbt-gen: %zu Legendre orders from the tables; series truncation beyond them %.2e "
                "(included in the bound)\n", K, tr);
        e += tr;
        free(b);
        nbt_phase_free(p);
        what = "Legendre";
    }
    tlist_free(&L);
    if (st == NBT_ETOL) {
        fprintf(stderr, "nbt-gen: warning: outside the table's range, clamped (the bound does not cover that)\n");
        st = NBT_OK;
    }
    if (st != NBT_OK)
        die("evaluation failed: %s", nbt_strerror(st));
    fprintf(stderr, "nbt-gen: %s tables from %zu file(s)\n", what, nfiles);
    printf("%.17g %.17g\n", v, e);
    return 0;
}
