/* bench/bench_gslice.c: run-time g, Legendre packs against g-sliced tables,
 * in one process: for HG g ranges [-G, G], G = 0.5, 0.8, 0.9, 0.95, the
 * size, build time and error of each at the same tolerance, and the
 * airlight over random rays and g against the direct integral: the pure
 * lookup (what a shader computes) and the library route with its fallback
 * (nbt_airlight_table_g / nbt_airlight_table_e).
 * Then surface radiance from g-sliced J^1 and J^20 tables, before and after
 * the one-pass log_et fill (Legendre J packs: see bench_tables).
 * Usage: bench_gslice [tol] [rays] [max_legendre_seconds] [j: surface only]   (make bench) */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <nbt/nbt.h>
#include "../tests/table_roundtrip.h"

static double now(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

static unsigned long long rs = 0x9e3779b97f4a7c15ull;
static double uni(void)
{
    rs = rs * 6364136223846793005ull + 1442695040888963407ull;
    return (double)(rs >> 11) / 9007199254740992.0;
}

#define XMAX 10.0

/* a random ray with u = kappa_t h <= XMAX (kappa_t = 0.5, d_sv <= 19) */
static nbt_airlight_geom ray(int i)
{
    nbt_airlight_geom g = {0.3, 0.5, 1.0, 0.5 + 18.5 * uni(), 0.02 + (M_PI - 0.04) * uni(), 0};
    g.dvp = i % 3 == 0 ? INFINITY : 0.1 + 25.0 * uni();
    return g;
}

/* the shader's arithmetic: prefactor times the difference of two lookups,
 * summed over channels with weights (2k+1) g^k (Legendre) or 1 */
static double pure_lookup(const nbt_table *const *t, size_t nt, double g, const nbt_airlight_geom *geo)
{
    double h = geo->dsv * sin(geo->gamma), tt = geo->dsv * cos(geo->gamma), u = geo->kappa_t * h;
    double th0 = geo->gamma - M_PI_2, thd = isinf(geo->dvp) ? M_PI_2 : atan2(geo->dvp - tt, h), s = 0;
    for (size_t i = 0; i < nt; i++) {
        double a[4], b[4];
        nbt_table_lookup3(t[i], u, thd, g, a);
        nbt_table_lookup3(t[i], u, th0, g, b);
        for (size_t c = 0; c < t[i]->nch; c++) {
            int k = t[i]->k[c];
            s += (k < 0 ? 1.0 : (2.0 * k + 1.0) * pow(g, k)) * (a[c] - b[c]);
        }
    }
    return geo->kappa_s * geo->I0 * exp(-geo->kappa_t * tt) / (4.0 * M_PI * h) * s;
}

typedef struct {
    double worst_pure, worst_route, p99_pure, fallback_frac;
    double worst_inf;    /* |lookup - direct| / the unobstructed ray's airlight */
    double frac_1e3;     /* rays whose lookup is within 1e-3 relative */
    char worst_ray[96];  /* the pure lookup's worst ray */
} ray_stats;

static int cmpd(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

/* over nrays random rays and g in [-G, G] */
static ray_stats rays(const nbt_table *const *t, size_t nt, int sliced, double G, int nrays)
{
    ray_stats r = {0, 0, 0, 0, 0, 0, ""};
    int ok3 = 0;
    double *rel = malloc((size_t)nrays * sizeof(double));
    int fell = 0;
    size_t K = 0;
    for (size_t i = 0; i < nt; i++)
        for (size_t c = 0; c < t[i]->nch; c++)
            if ((size_t)t[i]->k[c] + 1 > K)
                K = (size_t)t[i]->k[c] + 1;
    double *b = malloc((K + 1) * sizeof(double));
    for (int i = 0; i < nrays; i++) {
        nbt_airlight_geom geo = ray(i);
        double g = -G + 2.0 * G * uni(), R, RE, L, E;
        nbt_phase *p = nbt_phase_hg(g);
        nbt_airlight_direct(p, &geo, 1e-10, &R, &RE);
        nbt_phase_free(p);
        double Lp, Rinf = R, e2, EL;
        if (sliced)
            nbt_airlight_table_g_lookup(t[0], g, &geo, &Lp, &EL); /* the shader's arithmetic */
        else
            Lp = pure_lookup(t, nt, g, &geo);
        if (!isinf(geo.dvp)) {
            nbt_airlight_geom gi = geo;
            gi.dvp = INFINITY;
            nbt_phase *q = nbt_phase_hg(g);
            nbt_airlight_direct(q, &gi, 1e-10, &Rinf, &e2);
            nbt_phase_free(q);
        }
        r.worst_inf = fmax(r.worst_inf, fabs(Lp - R) / Rinf);
        if (sliced)
            nbt_airlight_table_g(t[0], g, &geo, &L, &E);
        else {
            for (size_t k = 0; k <= K; k++)
                b[k] = pow(g, (double)k);
            nbt_airlight_table_e(t, nt, b, K, NULL, &geo, &L, &E);
        }
        if (sliced ? L != Lp : E < 1e-9 * fabs(L))
            fell++; /* the route did not return the lookup (sliced) / the ray quadrature's estimate */
        rel[i] = fabs(Lp - R) / fabs(R);
        ok3 += rel[i] <= 1e-3;
        if (rel[i] > r.worst_pure)
            snprintf(r.worst_ray, sizeof r.worst_ray, "g %.3f gamma %.3f u %.3f d_vp %g", g, geo.gamma,
                     geo.kappa_t * geo.dsv * sin(geo.gamma), geo.dvp);
        r.worst_pure = fmax(r.worst_pure, rel[i]);
        r.worst_route = fmax(r.worst_route, fabs(L - R) / fabs(R));
    }
    qsort(rel, (size_t)nrays, sizeof(double), cmpd);
    r.p99_pure = rel[(size_t)(0.99 * (nrays - 1))];
    r.fallback_frac = (double)fell / nrays;
    r.frac_1e3 = (double)ok3 / nrays;
    free(rel);
    free(b);
    return r;
}

static void row(const char *what, double G, const char *size, double mb, double secs, double rec, ray_stats s)
{
    printf("%-8s %4.2f %-15s %7.2f MB %6.2f s rec %.1e | lookup: worst %.1e p99 %.1e <=1e-3 %5.1f%% "
           "vs-unobstructed %.1e | route: worst %.1e fallback %5.1f%%\n", what, G, size, mb, secs, rec,
           s.worst_pure, s.p99_pure, 100.0 * s.frac_1e3, s.worst_inf, s.worst_route, 100.0 * s.fallback_frac);
    printf("#   worst lookup: %s\n", s.worst_ray);
}

/* Surface radiance from g-sliced J^1 and J^20 tables for g in [-0.95, 0.95],
 * T = kappa_t d_sp in [0, 20] (d_sp up to 20 mean free paths), theta_s and
 * theta_r in [0, pi] (below the horizon only scattered light arrives): the
 * "before" tables (commit f7542cd's method: one fixed-phase build per slice,
 * plain J, g on the cos mapping, trilinear; recorded error = largest
 * in-slice + largest g error + quadrature) rebuilt here from public calls,
 * and the "after" ones (nbt_gslice_fill: one pass for all slices, ln(e^T J),
 * atanh g axis, quadratic in g, error per g cell) on the same T/theta axes
 * and sizes, in this process. Against nbt_surface_direct (kd 0.7 Lambert +
 * ks 0.3 Phong 20, the direct term included): the pure lookup (the shader's
 * arithmetic) and the route (nbt_surface_table_g with fallback_tol, which
 * integrates where its bound exceeds 10% of the value). */
#define TMAX_J 20.0

static nbt_table *j_before(int n, const nbt_axis *a0, const nbt_axis *a1, size_t ng, double *secs)
{
    double t0 = now();
    nbt_axis a2 = {-0.95, 0.95, NBT_AXIS_COS, 0, ng};
    nbt_table *t = nbt_table_alloc3(NBT_TABLE_J, a0, a1, &a2, 1);
    size_t ns = a0->n * a1->n;
    double serr = 0, gerr = 0, qerr = 0, amax = 0;
    t->n = n;
    t->k[0] = -1;
    snprintf(t->phase, sizeof t->phase, "hg");
    for (int pass = 0; pass < 2; pass++)
        for (size_t m = 0; m + (size_t)pass < ng; m++) {
            double g = pass ? nbt_axis_from_unit(&a2, ((double)m + 0.5) / (double)(ng - 1)) : nbt_axis_node(&a2, m);
            nbt_table *s = nbt_table_alloc(NBT_TABLE_J, a0, a1, 1);
            nbt_phase *p = nbt_phase_hg(g);
            nbt_build_opts o = {1e-10, !pass, 2};
            s->n = n;
            s->k[0] = -1;
            nbt_j_table_build(s, p, &o);
            qerr = fmax(qerr, s->quad_err);
            if (!pass) {
                memcpy(t->data + m * ns, s->data, ns * sizeof(float));
                serr = fmax(serr, s->max_err[0]);
                amax = fmax(amax, s->max_abs[0]);
            } else
                for (size_t k = 0; k < ns; k++) {
                    double v;
                    nbt_table_lookup3(t, nbt_axis_node(a0, k % a0->n), nbt_axis_node(a1, k / a0->n), g, &v);
                    gerr = fmax(gerr, fabs(v - s->data[k]));
                }
            nbt_phase_free(p);
            nbt_table_free(s);
        }
    t->max_err[0] = serr + gerr + qerr;
    t->max_abs[0] = amax;
    t->quad_err = qerr;
    *secs = now() - t0;
    return t;
}

static nbt_table *j_after(int n, const nbt_axis *a0, const nbt_axis *a1, size_t ng, double *secs)
{
    double t0 = now();
    nbt_axis a2 = {-0.95, 0.95, NBT_AXIS_ATANH, 0, ng};
    nbt_table *t = nbt_table_alloc3(NBT_TABLE_J, a0, a1, &a2, 1);
    nbt_build_opts o = {1e-10, 1, 2};
    t->n = n;
    t->form = NBT_FORM_LOG_ET;
    t->interp2 = 2;
    nbt_gslice_fill(t, &o);
    *secs = now() - t0;
    return t;
}

/* the shader's arithmetic: the lookups in the tables' form, no fallback */
static double surface_lookup(const nbt_table *J1, const nbt_table *Jn, double g, const nbt_surface_geom *geo)
{
    double T = geo->kappa_t * geo->dsp, v[2];
    const nbt_table *t[2] = {J1, Jn};
    double th[2] = {geo->theta_s, geo->theta_r};
    for (int i = 0; i < 2; i++) {
        nbt_table_lookup3(t[i], T, th[i], g, &v[i]);
        if (t[i]->form == NBT_FORM_LOG_ET)
            v[i] = exp(v[i] - T);
    }
    double direct = geo->I0 * exp(-T) / (geo->dsp * geo->dsp) *
                    (geo->kd * fmax(cos(geo->theta_s), 0.0) + geo->ks * pow(fmax(cos(geo->theta_r), 0.0), geo->n));
    return direct + geo->kappa_s * geo->I0 / (4.0 * M_PI * geo->dsp) * (geo->kd * v[0] + geo->ks * v[1]);
}

static void surface_part(int n, size_t NT, size_t N, size_t ng, int with_before)
{
    nbt_axis a0 = {0, TMAX_J, NBT_AXIS_LOG1P_CBRT, TMAX_J, NT}, a1 = {0, M_PI, NBT_AXIS_LINEAR, 0, N};
    nbt_axis an = a1;
    an.map = NBT_AXIS_COS; /* the planner's theta mappings: linear for Lambert, cos for Phong */
    for (int after = !with_before; after < 2; after++) {
        double s1, sn;
        nbt_table *J1 = after ? j_after(1, &a0, &a1, ng, &s1) : j_before(1, &a0, &a1, ng, &s1);
        nbt_table *Jn = after ? j_after(20, &a0, &an, ng, &sn) : j_before(20, &a0, &an, ng, &sn);
        /* on the same tables: the per-row bound (files without nbt.theta_err)
         * and the per-cell one (files without nbt.row_err either) */
        nbt_table *R1 = strip_bounds(J1, 1), *Rn = strip_bounds(Jn, 1), *C1 = strip_bounds(J1, 0),
                  *Cn = strip_bounds(Jn, 0);
        double wl = 0, wr = 0, *rel = malloc((size_t)n * sizeof(double)), *bq = malloc((size_t)n * sizeof(double));
        double *tq = malloc((size_t)n * sizeof(double));
        /* the geometries the theta bound does not certify: their true error
         * (looseness of the bound, or the lookup's own error?) */
        double *ut = malloc((size_t)n * sizeof(double)), *ub = malloc((size_t)n * sizeof(double));
        double *ur = malloc((size_t)n * sizeof(double));
        int nu = 0, nu_true = 0;
        double tb_row = 0, tb_cell = 0, wtb_row = 0, wtb_cell = 0, wtb_th = 0;
        int ok = 0, fell = 0, cert = 0, cert_cell = 0, cert_row = 0, within = 0;
        unsigned long long seed = rs;
        rs = 0x51ed2701ull; /* the same geometries for every table */
        for (int i = 0; i < n; i++) {
            nbt_surface_geom geo = {0.3, 0.5, 1.0, 0.05 + (2.0 * TMAX_J - 0.05) * uni(), M_PI * uni(), M_PI * uni(),
                                    0.7, 0.3, 20};
            double g = -0.95 + 1.9 * uni(), R, RE, L, E, Lf, Ef;
            nbt_phase *p = nbt_phase_hg(g);
            nbt_surface_direct(p, &geo, 1e-9, &R, &RE);
            nbt_phase_free(p);
            double Lp = surface_lookup(J1, Jn, g, &geo);
            double t_b = now(), Ec, Lc, Er, Lr;
            nbt_surface_table_g(J1, Jn, g, &geo, 0, &L, &E);
            tb_row += now() - t_b;
            nbt_surface_table_g(R1, Rn, g, &geo, 0, &Lr, &Er);
            t_b = now();
            nbt_surface_table_g(C1, Cn, g, &geo, 0, &Lc, &Ec);
            tb_cell += now() - t_b;
            nbt_surface_table_g(J1, Jn, g, &geo, 1e-9, &Lf, &Ef);
            fell += Lf != L;
            cert += E <= 1e-3 * fabs(L);
            cert_row += Er <= 1e-3 * fabs(L);
            cert_cell += Ec <= 1e-3 * fabs(L);
            within += fabs(L - R) <= E + RE;
            if (!(E <= 1e-3 * fabs(L))) {
                ut[nu] = fabs(L - R) / fabs(R); /* the table route's true error, relative */
                ub[nu] = E / fabs(L);           /* its bound, relative */
                ur[nu] = fabs(L - R) / E;
                nu_true += ut[nu] > 1e-3;
                nu++;
            }
            bq[i] = Ec / Er;
            tq[i] = Er / E;
            wtb_th = fmax(wtb_th, fabs(L - R) / E);
            wtb_row = fmax(wtb_row, fabs(L - R) / Er);
            wtb_cell = fmax(wtb_cell, fabs(L - R) / Ec);
            rel[i] = fabs(Lp - R) / fabs(R);
            ok += rel[i] <= 1e-3;
            wl = fmax(wl, rel[i]);
            wr = fmax(wr, fabs(Lf - R) / fabs(R));
        }
        rs = seed;
        qsort(rel, (size_t)n, sizeof(double), cmpd);
        qsort(bq, (size_t)n, sizeof(double), cmpd);
        qsort(tq, (size_t)n, sizeof(double), cmpd);
        printf("%-6s J1+J20 %3zux%3zux%2zu x2 %5.2f MB build %5.2f s (J1 %.2f, J20 %.2f) rec J1 %.1e J20 %.1e | "
               "lookup: worst %.1e median %.1e <=1e-3 %3.0f%% | bound <=1e-3 %3.0f%% | route: worst %.1e fallback %3.0f%%\n",
               after ? "after" : "before", NT, N, ng, 8e-6 * (double)nbt_table_size(J1), s1 + sn, s1, sn,
               after ? J1->max_err[0] : J1->max_err[0] / J1->max_abs[0],
               after ? Jn->max_err[0] : Jn->max_err[0] / Jn->max_abs[0], wl, rel[n / 2], 100.0 * ok / n,
               100.0 * cert / n, wr, 100.0 * fell / n);
        if (after)
            printf("       bound per (T row, theta band, g cell) | (T row, g cell) | g cell: <=1e-3 %3.0f%% | %3.0f%% | "
                   "%3.0f%%; true/bound worst %.2f | %.2f | %.2f (true within the theta bound at %d of %d); "
                   "row/theta bound median %.1f (min %.2f, max %.1f); cell/row median %.1f (min %.2f, max %.1f); "
                   "%.2f | %.2f us per route call (theta | cell)\n",
                   100.0 * cert / n, 100.0 * cert_row / n, 100.0 * cert_cell / n, wtb_th, wtb_row, wtb_cell, within, n,
                   tq[n / 2], tq[0], tq[n - 1], bq[n / 2], bq[0], bq[n - 1], 1e6 * tb_row / n, 1e6 * tb_cell / n);
        if (after && nu) {
            qsort(ut, (size_t)nu, sizeof(double), cmpd);
            qsort(ub, (size_t)nu, sizeof(double), cmpd);
            qsort(ur, (size_t)nu, sizeof(double), cmpd);
            printf("       not certified by the theta bound: %d of %d; their true error > 1e-3 at %d; true error "
                   "median %.1e p90 %.1e max %.1e; bound median %.1e p90 %.1e max %.1e; true/bound median %.2f "
                   "p90 %.2f max %.2f\n",
                   nu, n, nu_true, ut[nu / 2], ut[nu * 9 / 10], ut[nu - 1], ub[nu / 2], ub[nu * 9 / 10], ub[nu - 1],
                   ur[nu / 2], ur[nu * 9 / 10], ur[nu - 1]);
        }
        free(ut);
        free(ub);
        free(ur);
        free(rel);
        free(bq);
        free(tq);
        nbt_table_free(R1);
        nbt_table_free(Rn);
        nbt_table_free(C1);
        nbt_table_free(Cn);
        nbt_table_free(J1);
        nbt_table_free(Jn);
        fflush(stdout);
    }
}

int main(int argc, char **argv)
{
    double tol = argc > 1 ? atof(argv[1]) : 1e-2;
    int nrays = argc > 2 ? atoi(argv[2]) : 200;
    double legmax = argc > 3 ? atof(argv[3]) : 30.0;
    /* the surface part alone; jlast: its planner's size (65x257x33) alone */
    int jlast = argc > 4 && !strcmp(argv[4], "jlast"), only_j = jlast || (argc > 4 && !strcmp(argv[4], "j"));
    static const double Gs[] = {0.5, 0.8, 0.9, 0.95};
    printf("# H tables for HG g in [-G, G], u in [0, %g], tol %g (max_err / max |value|), 2 threads;\n"
           "# airlight over %d random rays (d_vp finite and infinite, gamma in (0.02, pi-0.02)) and g,\n"
           "# relative to nbt_airlight_direct. 'lookup': the shader's arithmetic; 'route': the library\n"
           "# call with its fallback to the ray integral where the bound exceeds 10%% of the value\n"
           "# (tail form: 1e-3). 'plain': the former g-sliced H (plain values, trilinear, cos g axis,\n"
           "# the former planner's sizes for tol 1e-2, fill time only); 'tail': the tail form as planned\n"
           "# (its rec is relative to the value: the error map's largest entry, at u -> 0, v -> pi/2).\n"
           "# Arguments: TOL NRAYS LEGMAX (< 0: no Legendre rows) [nosurface | j (surface only) | jlast (its 65x257x33 only)].\n"
           "# 'vs-unobstructed': the lookup's error relative to the airlight of the same ray with\n"
           "# d_vp = inf (equal to 'worst' when the worst rays are unobstructed ones: sideways and\n"
           "# backward rays far from the source, whose airlight is a difference of two nearly\n"
           "# equal lookups). 'rec': the recorded error, relative to max |value|\n"
           "# (Legendre: the tables' times the amplification plus the truncation).\n",
           XMAX, tol, nrays);
    for (size_t gi = 0; gi < sizeof Gs / sizeof Gs[0] && !only_j; gi++) {
        double G = Gs[gi];
        /* Legendre packs, as nbt-gen airlight --g -G:G --basis legendre */
        nbt_plan_legendre leg;
        nbt_status st = legmax < 0 ? NBT_EINVAL : nbt_plan_legendre_terms(G, XMAX, tol, 512, &leg);
        if (st == NBT_OK) {
            nbt_plan_request q = {NBT_TABLE_H, 0, leg.nterms, NULL, XMAX, leg.table_tol, {0, 0}, 0, 0};
            nbt_plan *plan = NULL;
            char err[256];
            double t0 = now();
            nbt_plan_tables(&q, 1, 2, &plan, err, sizeof err);
            const nbt_plan_set *ps = nbt_plan_get(plan, 0);
            char size[64];
            snprintf(size, sizeof size, "%zux%zu x%zu", ps->axis[0].n, ps->axis[1].n, leg.nterms);
            double mb = 16e-6 * (double)ps->axis[0].n * (double)ps->axis[1].n * (double)ps->npacks;
            if (ps->pred_seconds > legmax) {
                printf("legendre  %4.2f  %-16s %8.2f MB  predicted %.0f s: not built (limit %g s)\n", G, size, mb,
                       ps->pred_seconds, legmax);
            } else {
                nbt_tableset ts;
                if (nbt_plan_execute(plan, 0, &ts, err, sizeof err) == NBT_OK) {
                    double secs = now() - t0;
                    ray_stats s = rays((const nbt_table *const *)ts.t, ts.count, 0, G, nrays);
                    row("legendre", G, size, mb, secs, ts.rel_err * leg.amp + leg.trunc_err, s);
                    nbt_tableset_free(&ts);
                }
            }
            nbt_plan_free(plan);
        } else if (legmax >= 0)
            printf("legendre  %4.2f  needs more than %d orders at tol %g\n", G, 512, tol);
        /* before (in this process): plain H slices, trilinear on a cos g axis, at the sizes the
         * former error-driven planner chose for tol 1e-2 (doc/tables.md), fill time only */
        {
            static const size_t old_n[4][2] = {{33, 25}, {65, 49}, {97, 65}, {129, 65}};
            nbt_axis a0 = {0, XMAX, NBT_AXIS_LOG1P_CBRT, 10, old_n[gi][0]};
            nbt_axis a1 = {-M_PI_2, M_PI_2, NBT_AXIS_COS, 0, old_n[gi][0]}, a2 = {-G, G, NBT_AXIS_COS, 0, old_n[gi][1]};
            nbt_table *t = nbt_table_alloc3(NBT_TABLE_H, &a0, &a1, &a2, 1);
            nbt_build_opts o = {1e-10, 1, 2};
            double t0 = now();
            if (t && nbt_gslice_fill_form(t, NBT_FORM_PLAIN, &o) == NBT_OK) {
                double secs = now() - t0;
                char size[64];
                snprintf(size, sizeof size, "%zux%zux%zu", t->axis[0].n, t->axis[1].n, t->axis[2].n);
                ray_stats s = rays((const nbt_table *const *)&t, 1, 1, G, nrays);
                row("plain", G, size, 4e-6 * (double)nbt_table_size(t), secs, t->max_err[0] / t->max_abs[0], s);
            }
            nbt_table_free(t);
        }
        /* after: g slices as planned (H: the tail form, atanh g, quadratic) */
        nbt_gslice_request r = {NBT_TABLE_H, 0, XMAX, {-G, G}, tol, {0, 0, 0}, 0};
        nbt_table *t = NULL;
        char err[256];
        double secs;
        st = nbt_gslice_build(&r, 2, &t, &secs, err, sizeof err);
        if (st != NBT_OK) {
            printf("slices    %4.2f  %s\n", G, err);
            continue;
        }
        char size[64];
        snprintf(size, sizeof size, "%zux%zux%zu", t->axis[0].n, t->axis[1].n, t->axis[2].n);
        ray_stats s = rays((const nbt_table *const *)&t, 1, 1, G, nrays);
        row(t->form == NBT_FORM_TAIL ? "tail" : "slices", G, size, 4e-6 * (double)nbt_table_size(t), secs,
            t->form == NBT_FORM_TAIL ? t->max_err[0] : t->max_err[0] / t->max_abs[0], s);
        nbt_table_free(t);
        fflush(stdout);
    }
    if (!(argc > 4 && !strcmp(argv[4], "nosurface"))) {
        printf("# surface: g-sliced J^1 (theta linear) and J^20 (theta cos), g in [-0.95, 0.95], T in [0, %g]\n"
               "# (log1p_cbrt), 2 threads; %d random geometries (d_sp <= 40, kappa_t 0.5, theta_s, theta_r in [0, pi]) and g;\n"
               "# relative to nbt_surface_direct (direct term included). 'rec': recorded error (before: relative to max\n"
               "# |J|; after: in ln J, i.e. relative). 'bound <=1e-3': the route's bound certifies 1e-3.\n",
               TMAX_J, nrays / 2);
        /* T x theta x g: before and after at two sizes, then after only (before costs ~5x) */
        static const size_t JN[][4] = {{33, 33, 33, 1}, {65, 65, 33, 1}, {49, 193, 17, 0}, {65, 193, 33, 0}, {65, 257, 33, 0}};
        for (size_t k = jlast ? sizeof JN / sizeof JN[0] - 1 : 0; k < sizeof JN / sizeof JN[0]; k++)
            surface_part(nrays / 2, JN[k][0], JN[k][1], JN[k][2], (int)JN[k][3]);
        /* the planner's J^1 + J^20 at 1e-3: each alone, then as one set
         * sharing G's quadrature (nbt_gslice_build_set) */
        nbt_gslice_request rq[2] = {{NBT_TABLE_J, 1, TMAX_J, {-0.95, 0.95}, 1e-3, {0, 0, 0}, 0},
                                    {NBT_TABLE_J, 20, TMAX_J, {-0.95, 0.95}, 1e-3, {0, 0, 0}, 0}};
        nbt_table *ts[2];
        double sa[2], ss[2];
        char err[256];
        for (int i = 0; i < 2; i++) {
            if (nbt_gslice_build(&rq[i], 2, &ts[i], &sa[i], err, sizeof err) != NBT_OK) {
                fprintf(stderr, "bench_gslice: %s\n", err);
                return 1;
            }
            nbt_table_free(ts[i]);
        }
        if (nbt_gslice_build_set(rq, 2, 2, ts, ss, err, sizeof err) != NBT_OK) {
            fprintf(stderr, "bench_gslice: %s\n", err);
            return 1;
        }
        printf("planned J^1 + J^20 at 1e-3 (%zux%zux%zu): alone %.2f + %.2f = %.2f s; as a set %.2f + %.2f = %.2f s\n",
               ts[0]->axis[0].n, ts[0]->axis[1].n, ts[0]->axis[2].n, sa[0], sa[1], sa[0] + sa[1], ss[0], ss[1],
               ss[0] + ss[1]);
        nbt_table_free(ts[0]);
        nbt_table_free(ts[1]);
    }
    return 0;
}
