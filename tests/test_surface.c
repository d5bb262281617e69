/* tests/test_surface.c: J_k^n against mpmath references and closed forms,
 * the azimuthal kernel, surface radiance series vs the direct integral,
 * J tables against pointwise J within their recorded error. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <nbt/nbt.h>
#include "testutil.h"

typedef struct {
    int n;
    double a, b;
} lobe;
static int lobe_f(double phi, void *vp, unsigned fdim, double *f)
{
    (void)fdim;
    const lobe *l = vp;
    double v = l->a + l->b * cos(phi);
    f[0] = v > 0 ? pow(v, l->n) : 0;
    return 0;
}
typedef struct {
    int n;
    double theta;
} kint;
static int ksin_f(double g, void *vp, unsigned fdim, double *f)
{
    (void)fdim;
    const kint *c = vp;
    f[0] = nbt_surface_kernel(c->n, c->theta, g) * sin(g);
    return 0;
}

/* J tables built without the error measurement, so that both theta rows
 * of each pair the product J = G M^T takes together are node rows (with
 * it, every second row is a midpoint): every node against nbt_jk /
 * nbt_j_phase at 1e-12 (their estimates added), within float rounding
 * (6e-8) plus the recorded quadrature error, itself <= 1e-9 (Legendre) or
 * 1e-6 (HG) as in test_table. Orders 0..11 (12 channels:
 * the product's blocks of eight and two) and a fixed HG phase (one
 * channel: its scalar loop); 7 theta nodes on [0.15, 3] (three pairs and
 * a last row alone), whose kernels' supports [theta - pi/2, theta + pi/2]
 * end at different g within a pair. */
static void test_j_nodes_unmeasured(void)
{
    nbt_axis ax = {0, 8, NBT_AXIS_LINEAR, 0, 4}, ay = {0.15, 3.0, NBT_AXIS_LINEAR, 0, 7};
    for (int n = 1; n <= 20; n += 19)
        for (int ph = 0; ph < 2; ph++) {
            nbt_phase *p = ph ? nbt_phase_hg(0.6) : NULL;
            size_t np = ph ? 1 : 3;
            nbt_table *js[3];
            for (size_t q = 0; q < np; q++) {
                js[q] = nbt_table_alloc(NBT_TABLE_J, &ax, &ay, ph ? 1 : 4);
                js[q]->n = n;
                for (size_t c = 0; c < js[q]->nch; c++)
                    js[q]->k[c] = ph ? -1 : (int)(4 * q + c);
            }
            nbt_build_opts o = {1e-10, 0, 2};
            t_true(nbt_j_table_build_set(js, np, p, &o) == NBT_OK, "unmeasured J^%d %s builds", n,
                   ph ? "HG 0.6" : "orders 0..11");
            double worst = 0;
            for (size_t i = 0; i < ax.n; i++)
                for (size_t j = 0; j < ay.n; j++) {
                    double T = nbt_axis_node(&ax, i), th = nbt_axis_node(&ay, j), ex[12], ee[12];
                    if (ph)
                        nbt_j_phase(p, n, T, th, 1e-12, ex, ee);
                    else
                        nbt_jk(11, n, T, th, 1e-12, ex, ee);
                    for (size_t q = 0; q < np; q++)
                        for (size_t c = 0; c < js[q]->nch; c++) {
                            size_t k = 4 * q + c;
                            double d = fabs(js[q]->data[(j * ax.n + i) * js[q]->nch + c] - ex[k]);
                            worst = fmax(worst, d / (ee[k] + 6e-8 * fabs(ex[k]) + js[q]->quad_err));
                        }
                }
            /* and that error small (test_table's limits at quad_tol 1e-10): a
             * wrong product inflates it too, through the halved-panel check */
            t_true(worst <= 1.0 && js[0]->quad_err <= (ph ? 1e-6 : 1e-9),
                   "unmeasured J^%d %s: every node within float rounding + quad_err %.1e (worst %.2g of it)", n,
                   ph ? "HG 0.6" : "orders 0..11", js[0]->quad_err, worst);
            for (size_t q = 0; q < np; q++)
                nbt_table_free(js[q]);
            nbt_phase_free(p);
        }
}

int main(void)
{
    test_j_nodes_unmeasured();
    double J[16], E[16];
    /* ---- mpmath references ---- */
    const char *refdir = getenv("NBT_REF") ? getenv("NBT_REF") : "tests/ref";
    char path[1024], line[256];
    snprintf(path, sizeof path, "%s/jk.txt", refdir);
    FILE *f = fopen(path, "r");
    t_true(f != NULL, "reference file %s opens", path);
    int nref = 0, honest = 1;
    while (f && fgets(line, sizeof line, f)) {
        int k, n;
        double T, th, ref;
        if (line[0] == '#' || sscanf(line, "%d %d %lf %lf %lf", &k, &n, &T, &th, &ref) != 5)
            continue;
        nbt_status st = nbt_jk((size_t)k, n, T, th, 1e-10, J, E);
        double d = fabs(J[k] - ref);
        t_true(st == NBT_OK && d <= 1e-9 * fabs(ref), "J_%d^%d(%g, %g) vs mpmath: rel diff %.2e", k, n, T, th, d / fabs(ref));
        honest &= d <= E[k];
        nref++;
    }
    if (f)
        fclose(f);
    t_true(nref >= 40, "read %d J references", nref);
    t_true(honest, "every J error estimate bounds its true error");
    /* closed form: J_0^1(0, 0) = 2 pi int_0^{pi/2} (pi - g) cos g dg = pi^2 + 2 pi */
    nbt_jk(0, 1, 0, 0, 1e-12, J, E);
    t_rel(J[0], M_PI * M_PI + 2 * M_PI, 1e-12, "J_0^1(0, 0) = pi^2 + 2 pi");

    /* ---- kernel ---- */
    nbt_quad_ws *ws = nbt_quad_ws_alloc(1, 500);
    int nk[] = {1, 2, 7, 20, 200};
    for (int i = 0; i < 5; i++) {
        int n = nk[i];
        double worst = 0;
        for (int j = 0; j < 40; j++) {
            double th = M_PI * t_uniform(), g = M_PI * t_uniform(), r, e;
            lobe l = {n, cos(th) * cos(g), sin(th) * sin(g)};
            double ph0 = (l.b > 0 && fabs(l.a) < l.b) ? acos(-l.a / l.b) : M_PI;
            nbt_quad_gk_pts(ws, lobe_f, &l, 1, 0, M_PI, &ph0, ph0 < M_PI, 1e-300, 1e-13, &r, &e);
            double K = nbt_surface_kernel(n, th, g);
            worst = fmax(worst, fabs(K - 2 * r) / fmax(2 * r, 1e-300 + (r == 0)));
        }
        t_abs(worst, 0, 1e-11, "K_%d matches pointwise azimuthal quadrature at 40 random (theta, g)", n);
        t_rel(nbt_surface_kernel(n, 0, 0.7), 2 * M_PI * pow(cos(0.7), n), 1e-13, "K_%d(0, g) = 2 pi cos^n g", n);
        /* int K sin g dg = int over the sphere of cos^n_+ = 2 pi/(n+1), whatever theta */
        for (double th = 0.1; th < M_PI; th += 0.9) {
            kint c = {n, th};
            double r, e;
            double pts[4] = {fabs(M_PI_2 - th), th + M_PI_2 < M_PI ? th + M_PI_2 : M_PI - 1e-9};
            nbt_quad_gk_pts(ws, ksin_f, &c, 1, 0, M_PI, pts, pts[0] < pts[1] ? 2 : 1, 0, 1e-12, &r, &e);
            t_rel(r, 2 * M_PI / (n + 1), 1e-9, "int K_%d(%g, g) sin g dg = 2 pi/(n+1)", n, th);
        }
    }
    nbt_quad_ws_free(ws);

    /* ---- surface radiance: series vs direct ---- */
    nbt_phase *hg = nbt_phase_hg(0.6);
    double b[200];
    nbt_phase_moments(hg, 199, b);
    int agree = 0;
    double worst = 0;
    for (int i = 0; i < 12; i++) {
        nbt_surface_geom g = {0, 0, 2.385, 0, 0, 0, 0.7, 0.3, i % 2 ? 20 : 5};
        g.kappa_t = 0.01 * pow(300.0, t_uniform());
        g.kappa_s = g.kappa_t * 0.9;
        g.dsp = 0.3 * pow(30.0, t_uniform());
        g.theta_s = M_PI * t_uniform();
        g.theta_r = M_PI * t_uniform();
        double Ld, Ed, Ls, Es;
        nbt_status s1 = nbt_surface_direct(hg, &g, 1e-8, &Ld, &Ed);
        nbt_status s2 = nbt_surface_series(b, 120, &g, 1e-9, &Ls, &Es);
        double rel = fabs(Ls - Ld) / Ld;
        worst = fmax(worst, rel);
        int ok = s1 == NBT_OK && s2 == NBT_OK && rel <= 1e-6;
        if (!ok)
            printf("kt=%g dsp=%g ts=%g tr=%g n=%d: direct %.12g series %.12g (%d %d)\n", g.kappa_t, g.dsp, g.theta_s,
                   g.theta_r, g.n, Ld, Ls, s1, s2);
        agree += ok;
    }
    t_true(agree == 12, "surface series = direct within 1e-6 on %d/12 random geometries (worst %.2e)", agree, worst);

    /* ---- no scattering (kappa_s = 0): only the unscattered light, in closed
     * form I0 e^{-kappa_t d}/d^2 (kd cos theta_s + ks cos^n theta_r), with the
     * source and mirror angles different (both methods share this term) ---- */
    {
        nbt_surface_geom g = {0, 0.3, 2.385, 3.1, 0.4, 1.1, 0.6, 0.35, 20};
        double want = 2.385 * exp(-0.3 * 3.1) / (3.1 * 3.1) * (0.6 * cos(0.4) + 0.35 * pow(cos(1.1), 20));
        double Ld, Ed, Ls, Es;
        t_true(nbt_surface_direct(hg, &g, 1e-10, &Ld, &Ed) == NBT_OK, "kappa_s = 0: direct");
        t_rel(Ld, want, 1e-12, "kappa_s = 0: direct = the unscattered closed form");
        t_true(nbt_surface_series(b, 40, &g, 1e-10, &Ls, &Es) == NBT_OK, "kappa_s = 0: series");
        t_rel(Ls, want, 1e-12, "kappa_s = 0: series = the unscattered closed form");
        g.theta_r = 2.0; /* mirror direction below the surface: no specular light */
        want = 2.385 * exp(-0.3 * 3.1) / (3.1 * 3.1) * 0.6 * cos(0.4);
        nbt_surface_direct(hg, &g, 1e-10, &Ld, &Ed);
        t_rel(Ld, want, 1e-12, "kappa_s = 0, theta_r > pi/2: diffuse only");
    }

    /* the series takes exactly b[0..nterms-1]: a moment past them (a
     * sentinel of 1e3) changes nothing (a random mutant reading one more
     * order survived every test) */
    {
        const double b4[2][4] = {{1, 0.5, 0.25, 0}, {1, 0.5, 0.25, 1e3}};
        nbt_surface_geom gs = {0.15, 0.2, 2.385, 3.1, 0.4, 1.1, 0.6, 0.35, 20};
        double L[2], E2[2];
        for (int i = 0; i < 2; i++)
            nbt_surface_series(b4[i], 3, &gs, 1e-10, &L[i], &E2[i]);
        t_true(L[0] > 0 && L[0] == L[1], "surface series of 3 terms ignores b_3: %.17g vs %.17g", L[0], L[1]);
    }

    /* ---- edges ---- */
    nbt_status st = nbt_jk(3, 1, 1e3, 0.3, 1e-10, J, E);
    t_true(st == NBT_OK && isfinite(J[0]) && J[0] >= 0 && J[0] < 1e-300, "T = 1000: finite, tiny, >= 0 (%.3g)", J[0]);
    st = nbt_jk(3, 1000, 2.385, M_PI, 1e-10, J, E);
    t_true(st == NBT_OK && isfinite(J[0]) && J[0] >= 0, "n = 1000, theta = pi: finite (%.3g)", J[0]);
    t_true(nbt_jk(0, 0, 1, 1, 1e-10, J, E) == NBT_EDOM, "n = 0 rejected");
    t_true(nbt_jk(0, 1, -1, 1, 1e-10, J, E) == NBT_EDOM, "T < 0 rejected");
    t_true(nbt_jk(0, 1, 1, 3.2, 1e-10, J, E) == NBT_EDOM, "theta > pi rejected");

    /* ---- J table: pointwise truth within the recorded error ---- */
    int ns[2] = {1, 20};
    nbt_table *jt[2];
    for (int i = 0; i < 2; i++) {
        nbt_axis a0 = {0, 10, NBT_AXIS_SQRT, 0, 65}, a1 = {0, M_PI, NBT_AXIS_COS, 0, 65};
        nbt_table *t = nbt_table_alloc(NBT_TABLE_J, &a0, &a1, 4);
        for (int c = 0; c < 4; c++)
            t->k[c] = c;
        t->n = ns[i];
        nbt_build_opts o = {1e-10, 1, 0};
        t_true(nbt_j_table_build(t, NULL, &o) == NBT_OK, "J^%d table builds", ns[i]);
        int in = 0;
        double ratio = 0;
        for (int j = 0; j < 60; j++) {
            double T = 10 * t_uniform(), th = M_PI * t_uniform(), v[4];
            nbt_table_lookup(t, T, th, v);
            nbt_jk(3, ns[i], T, th, 1e-10, J, E);
            int ok = 1;
            for (int c = 0; c < 4; c++) {
                ratio = fmax(ratio, fabs(v[c] - J[c]) / t->max_err[c]);
                ok &= fabs(v[c] - J[c]) <= 1.25 * t->max_err[c];
            }
            in += ok;
        }
        t_true(in == 60, "J^%d table: %d/60 random points within 1.25x the recorded error (worst ratio %.2f)", ns[i], in, ratio);
        /* nodes carry the exact values (to float) */
        nbt_jk(3, ns[i], nbt_axis_node(&a0, 7), nbt_axis_node(&a1, 50), 1e-11, J, E);
        t_rel(t->data[(50 * 65 + 7) * 4], J[0], 1e-7, "J^%d table node (7, 50) = J to float precision", ns[i]);
        jt[i] = t;
    }
    /* the table route against the direct integral, Rayleigh scattering (b_k = 0
     * beyond k = 2, so orders 0..3 are the whole series): within the bound the
     * tables' recorded errors give, kappa_s I0/(4 pi d) sum_k (2k+1) |b_k|
     * (kd err_k(J^1) + ks err_k(J^20)) */
    {
        nbt_phase *ray = nbt_phase_rayleigh();
        double rb[4] = {1, 0, 0.1, 0};
        int in = 0;
        for (int j = 0; j < 8; j++) {
            nbt_surface_geom g = {0.15, 0.2, 2.385, 0.5 + 4 * t_uniform(), M_PI * t_uniform(), M_PI * t_uniform(), 0.7, 0.3, 20};
            double Lt, Ld, Ed, bound = 0;
            nbt_status s1 = nbt_surface_table((const nbt_table *const *)&jt[0], 1, (const nbt_table *const *)&jt[1], 1, rb, 4,
                                              &g, &Lt);
            nbt_status s2 = nbt_surface_direct(ray, &g, 1e-8, &Ld, &Ed);
            for (int k = 0; k < 4; k++)
                bound += (2 * k + 1) * fabs(rb[k]) * (g.kd * jt[0]->max_err[k] + g.ks * jt[1]->max_err[k]);
            bound *= g.kappa_s * g.I0 / (4 * M_PI * g.dsp);
            int ok = s1 == NBT_OK && s2 == NBT_OK && fabs(Lt - Ld) <= bound + Ed;
            if (!ok)
                printf("dsp=%g ts=%g tr=%g: table %.10g direct %.10g bound %.3g (%d %d)\n", g.dsp, g.theta_s, g.theta_r, Lt,
                       Ld, bound, s1, s2);
            in += ok;
        }
        t_true(in == 8, "surface table route within its recorded bound of direct on %d/8 geometries", in);
        nbt_phase_free(ray);
    }
    /* the tables swapped (J^20 as the diffuse one, J^1 as the specular): refused, not summed */
    {
        nbt_surface_geom g = {0.15, 0.2, 2.385, 2.0, 0.7, 1.1, 0.7, 0.3, 20};
        double rb[4] = {1, 0, 0.1, 0}, Lt;
        t_true(nbt_surface_table((const nbt_table *const *)&jt[1], 1, (const nbt_table *const *)&jt[1], 1, rb, 4, &g,
                                 &Lt) == NBT_EINVAL,
               "surface table: a diffuse table with n = 20 is refused");
        t_true(nbt_surface_table((const nbt_table *const *)&jt[0], 1, (const nbt_table *const *)&jt[0], 1, rb, 4, &g,
                                 &Lt) == NBT_EINVAL,
               "surface table: a specular table with n = 1 for the geometry's 20 is refused");
    }
    nbt_table_free(jt[0]);
    nbt_table_free(jt[1]);
    nbt_phase_free(hg);
    return t_done();
}
