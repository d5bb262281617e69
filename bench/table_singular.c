/* bench/table_singular.c: what limits the default scene's tables (H_0..3,
 * J_0..3^1, J_0..3^20 over [0, 10]) at 33^2, and whether subtracting or
 * dividing out a closed form helps (issue 21; doc/tables.md, "33^2 at 1e-3").
 *
 * Exact values at every cell and edge midpoint of an N^2 table come from one
 * build at (2N-1)^2 on the same mappings: in unit coordinates its odd nodes
 * are the N^2 table's midpoints, where the bilinear error of a smooth function
 * peaks. A remedy tabulates f - S (or f / S) at the even nodes, interpolates,
 * and adds S back (or multiplies) at the midpoint: the error printed is that
 * of the reconstructed f, relative to max |channel 0| (nbt-gen's "rel").
 *
 * Usage: table_singular [m<mode>] [r<points>] [a<a>[,<p>]] [M<m>[,<w>]] [N ...]
 *   (options in this order; default N: 17 33 65 129). m: the remedy (modes at S() below); r: also
 *   that many random points against nbt_hk/nbt_jk; a: the decay in x of
 *   mode 6, e^-ax, or (1 + a x/p)^-p for p > 0; M: J's row 0 by a least
 *   squares fit of cos(q y), q = 0..m, the last (q = m) replaced when w is
 *   given: w < 0 the peak
 *   1/sqrt(y^2 + w^2) (w = -0: w chosen by the smallest fit residual),
 *   w = 99 the horizon (y - pi/2)^2 log|y - pi/2|. H's row 0 is always exact.
 *   Each run treats all three tables alike; read the lines of the table the
 *   options are meant for. doc/tables.md's numbers ("33^2 at 1e-3: what
 *   limits it"):
 *     table_singular r2000 17 33 65 129            plain: where the error sits
 *     table_singular m6 r2000 a1,1 17 33 65 129    H: H_k(0, v)/(1 + u) subtracted
 *     table_singular m6 r2000 a1 M4 17 33 65 129   J1: e^-T (1, cos y .. cos 4y)
 *     table_singular m6 r2000 a1 M3,-0 17 33 65 129   J20: e^-T (1, cos y, cos 2y, peak)
 *     table_singular m1 33 65 129                  e^-x f(0, y) exact (the bound of this family) */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <nbt/nbt.h>

typedef struct {
    const char *name;
    nbt_table_kind kind;
    int n;
} spec;

static const spec specs[3] = {{"H", NBT_TABLE_H, 0}, {"J1", NBT_TABLE_J, 1}, {"J20", NBT_TABLE_J, 20}};

/* the planner's rule for the default scene (doc/tables.md) */
static nbt_table *build(const spec *s, size_t N)
{
    nbt_axis a0 = {0, 10, NBT_AXIS_LOG1P_CBRT, 10, N};
    nbt_axis a1 = s->kind == NBT_TABLE_H ? (nbt_axis){-M_PI_2, M_PI_2, NBT_AXIS_COS, 0, N}
                  : s->n == 1            ? (nbt_axis){0, M_PI, NBT_AXIS_ASINH, 1, N}
                                         : (nbt_axis){0, M_PI, NBT_AXIS_LOG1P, 20, N};
    nbt_table *t = nbt_table_alloc(s->kind, &a0, &a1, 4);
    for (int c = 0; c < 4; c++)
        t->k[c] = c;
    t->n = s->kind == NBT_TABLE_J ? s->n : 0;
    nbt_build_opts o = {1e-11, 0, 0};
    nbt_status st = s->kind == NBT_TABLE_H ? nbt_h_table_build(t, NULL, &o) : nbt_j_table_build(t, NULL, &o);
    if (st != NBT_OK) {
        fprintf(stderr, "build failed: %s\n", nbt_strerror(st));
        exit(1);
    }
    return t;
}

static double val(const nbt_table *t, size_t i, size_t j, int c)
{
    return t->data[(j * t->axis[0].n + i) * 4 + c];
}

/* Remedies: S(i, j, c) from the table's own exact row x = 0 and column
 * y = 0 (profiles; the study of which shape limits the error, before any
 * closed form): 0 none; 1 subtract e^-x f(0, y); 2 divide by f(0, y);
 * 3 subtract f(x, 0) cos y; 4 subtract f(x, 0) f(0, y)/f(0, 0);
 * 5 divide by f(x, 0) f(0, y)/f(0, 0) */
static int mode, fitM = -1, nrand = 0;
static double decay_a = 1, decay_p = 0;
static double fitc[4][16], fitw = 0;
static int autow; /* M<m>,-0: w chosen by the smallest fit residual */
/* basis of the row-0 fit: cos(q y) for q < M (fitw = 0), or with fitw > 0
 * the first M - 2 of those and the smoothed cones sqrt(y^2 + w^2),
 * sqrt((pi - y)^2 + w^2) (the T = 0 profile of a Phong lobe of width ~w
 * over G(0, gamma) = pi - gamma, whose cones at the poles it rounds off) */
static double basis(int q, int M, double y)
{
    if (fitw >= 99 && q == M - 1) { /* the Lambert horizon, x^2 log|x| (w = 99) */
        double x = y - M_PI_2;
        return x == 0 ? 0 : x * x * log(fabs(x));
    }
    if (fitw < 0 && q == M - 1) /* a peak 1/gamma towards the source, rounded off by a lobe of width |w| */
        return 1 / sqrt(y * y + fitw * fitw);
    if (fitw > 0 && fitw < 99 && q == M - 1)
        return sqrt(y * y + fitw * fitw);
    if (fitw > 0 && fitw < 99 && q == M - 2)
        return sqrt((M_PI - y) * (M_PI - y) + fitw * fitw);
    return cos(q * y);
}
/* least squares cosine series sum_m fitc[c][m] cos(m y) of the row x = 0 (J) */
static double fit_row0_w(const nbt_table *t);
static void fit_row0(const nbt_table *t)
{
    if (autow) { /* auto: w in [0.05, 1] with the smallest fit residual */
        double best = INFINITY, bw = 0.3;
        for (double w = 0.05; w <= 1.0001; w += 0.01) {
            fitw = -w;
            double r = fit_row0_w(t);
            if (r < best)
                best = r, bw = w;
        }
        fitw = -bw;
        fit_row0_w(t);
        fprintf(stderr, "%s: auto w = %.2f\n", nbt_table_kind_name(t->kind), bw);
        return;
    }
    fit_row0_w(t);
}
/* the fit; returns the largest residual over channels relative to each row's largest value */
static double fit_row0_w(const nbt_table *t)
{
    double worst_res = 0;
    size_t m = t->axis[1].n;
    int M = fitM + 1;
    for (int c = 0; c < 4; c++) {
        double A[16][17] = {{0}};
        for (size_t j = 0; j < m; j++) {
            double y = nbt_axis_node(&t->axis[1], j), b[16];
            for (int q = 0; q < M; q++)
                b[q] = basis(q, M, y);
            for (int p = 0; p < M; p++) {
                for (int q = 0; q < M; q++)
                    A[p][q] += b[p] * b[q];
                A[p][M] += b[p] * val(t, 0, j, c);
            }
        }
        for (int p = 0; p < M; p++) /* Gauss-Jordan, SPD */
            for (int r = 0; r < M; r++)
                if (r != p) {
                    double f = A[r][p] / A[p][p];
                    for (int q = 0; q <= M; q++)
                        A[r][q] -= f * A[p][q];
                }
        for (int p = 0; p < M; p++)
            fitc[c][p] = A[p][M] / A[p][p];
        {
            double r = 0, mx = 0;
            for (size_t j = 0; j < m; j++) {
                double y = nbt_axis_node(&t->axis[1], j), s = 0;
                for (int q = 0; q < M; q++)
                    s += fitc[c][q] * basis(q, M, y);
                r = fmax(r, fabs(s - val(t, 0, j, c)));
                mx = fmax(mx, fabs(val(t, 0, j, c)));
            }
            worst_res = fmax(worst_res, r / mx);
            if (getenv("FITRES")) /* the fit's largest residual, relative to the row's largest value */
                fprintf(stderr, "fit ch %d: max residual %.3e of %.3e\n", c, r, mx);
        }
    }
    return worst_res;
}
static double row0(const nbt_table *t, size_t j, int c)
{
    if (fitM < 0 || t->kind == NBT_TABLE_H)
        return val(t, 0, j, c);
    double y = nbt_axis_node(&t->axis[1], j), s = 0;
    for (int q = 0; q <= fitM; q++)
        s += fitc[c][q] * basis(q, fitM + 1, y);
    return s;
}
static double decay(double x)
{
    return decay_p > 0 ? pow(1 + decay_a * x / decay_p, -decay_p) : exp(-decay_a * x);
}
static double S(const nbt_table *t, size_t i, size_t j, int c)
{
    double x = nbt_axis_node(&t->axis[0], i), y = nbt_axis_node(&t->axis[1], j);
    switch (mode) {
    case 6: return decay(x) * row0(t, j, c);
    case 1: return exp(-x) * val(t, 0, j, c);
    case 2: return val(t, 0, j, c);
    case 3: return val(t, i, 0, c) * cos(y);
    case 4:
    case 5: return val(t, i, 0, c) * val(t, 0, j, c) / val(t, 0, 0, c);
    default: return 0;
    }
}
static int divides(void) { return mode == 2 || mode == 5; }
static double fwd(const nbt_table *t, size_t i, size_t j, int c)
{
    double s = S(t, i, j, c);
    return divides() ? val(t, i, j, c) / s : val(t, i, j, c) - s;
}

typedef struct {
    double err, x, y;
    size_t i, j;
    int c;
} worst;

/* error of the N^2 table (even nodes of fine) at every odd node of fine;
 * also the largest error per region: rows (x) in 4 bands of unit coordinate
 * and columns (y) in 8 bands */
static void measure(const nbt_table *f, worst *w, double reg[4][8])
{
    size_t n = f->axis[0].n, m = f->axis[1].n;
    memset(w, 0, sizeof *w);
    for (int a = 0; a < 4; a++)
        for (int b = 0; b < 8; b++)
            reg[a][b] = 0;
    for (size_t j = 0; j < m; j++)
        for (size_t i = 0; i < n; i++) {
            if (i % 2 == 0 && j % 2 == 0)
                continue;
            size_t i0 = i & ~(size_t)1, j0 = j & ~(size_t)1;
            size_t i1 = i % 2 ? i0 + 2 : i0, j1 = j % 2 ? j0 + 2 : j0;
            for (int c = 0; c < 4; c++) {
                double b = 0.25 * (fwd(f, i0, j0, c) + fwd(f, i1, j0, c) + fwd(f, i0, j1, c) + fwd(f, i1, j1, c));
                b = divides() ? b * S(f, i, j, c) : b + S(f, i, j, c);
                double e = fabs(b - val(f, i, j, c));
                int ra = (int)(4 * i / n), rb = (int)(8 * j / m);
                if (e > reg[ra][rb])
                    reg[ra][rb] = e;
                if (e > w->err)
                    *w = (worst){e, nbt_axis_node(&f->axis[0], i), nbt_axis_node(&f->axis[1], j), i, j, c};
            }
        }
}

/* the same reconstruction at random points (unit coordinates uniform, so
 * that u, T -> 0 is sampled as densely as the nodes), against nbt_hk /
 * nbt_jk at tol 1e-10: the largest error over npts points */
static double random_err(const nbt_table *f, const spec *sp, int npts)
{
    size_t n = (f->axis[0].n + 1) / 2, m = (f->axis[1].n + 1) / 2;
    double wmax = 0;
    unsigned long long st = 0x9e3779b97f4a7c15ull;
    for (int r = 0; r < npts; r++) {
        double su, sv;
        st = st * 6364136223846793005ull + 1442695040888963407ull;
        su = (double)(st >> 11) / 9007199254740992.0;
        st = st * 6364136223846793005ull + 1442695040888963407ull;
        sv = (double)(st >> 11) / 9007199254740992.0;
        double x = nbt_axis_from_unit(&f->axis[0], su), y = nbt_axis_from_unit(&f->axis[1], sv);
        double px = su * (double)(n - 1), py = sv * (double)(m - 1);
        size_t i = (size_t)px, j = (size_t)py;
        if (i > n - 2)
            i = n - 2;
        if (j > m - 2)
            j = m - 2;
        double tx = px - (double)i, ty = py - (double)j, ex[4], ee[4];
        nbt_status s = sp->kind == NBT_TABLE_H ? nbt_hk(3, x, y, 1e-10, ex, ee) : nbt_jk(3, sp->n, x, y, 1e-10, ex, ee);
        if (s != NBT_OK)
            exit(2);
        for (int c = 0; c < 4; c++) {
            double g00 = fwd(f, 2 * i, 2 * j, c), g10 = fwd(f, 2 * i + 2, 2 * j, c);
            double g01 = fwd(f, 2 * i, 2 * j + 2, c), g11 = fwd(f, 2 * i + 2, 2 * j + 2, c);
            double b = (1 - ty) * ((1 - tx) * g00 + tx * g10) + ty * ((1 - tx) * g01 + tx * g11);
            /* S at the point: the modes' profiles are at nodes only; evaluate
             * the closed forms (modes 0, 6) at (x, y) directly */
            double sxy = 0;
            if (mode == 6) {
                double rw = 0;
                if (f->kind == NBT_TABLE_H) { /* H_k(0, y) by the closed form's own quadrature */
                    double h0[4], e0[4];
                    nbt_hk(3, 0, y, 1e-12, h0, e0);
                    rw = h0[c];
                } else {
                    for (int q = 0; q <= fitM; q++)
                        rw += fitc[c][q] * basis(q, fitM + 1, y);
                }
                sxy = decay(x) * rw;
            }
            b += sxy;
            wmax = fmax(wmax, fabs(b - ex[c]));
        }
    }
    return wmax;
}

static double scale0(const nbt_table *f)
{
    double s = 0;
    for (size_t q = 0; q < f->axis[0].n * f->axis[1].n; q++)
        s = fmax(s, fabs(f->data[q * 4]));
    return s;
}

int main(int argc, char **argv)
{
    size_t Ns[8] = {17, 33, 65, 129};
    int nN = 4;
    if (argc > 1 && argv[1][0] == 'm') {
        mode = atoi(argv[1] + 1);
        argc--, argv++;
    }
    if (argc > 1 && argv[1][0] == 'r') { /* random points per table */
        nrand = atoi(argv[1] + 1);
        argc--, argv++;
    }
    if (argc > 1 && argv[1][0] == 'a') { /* decay e^-a x, or (1 + a x/p)^-p with p > 0: a<a>,<p> */
        sscanf(argv[1] + 1, "%lf,%lf", &decay_a, &decay_p);
        argc--, argv++;
    }
    if (argc > 1 && argv[1][0] == 'M') { /* J: row 0 by a cosine series of order M */
        sscanf(argv[1] + 1, "%d,%lf", &fitM, &fitw);
        autow = fitw == 0 && signbit(fitw);
        argc--, argv++;
    }
    if (argc > 1) {
        nN = 0;
        for (int a = 1; a < argc && nN < 8; a++) {
            char *end;
            long v = strtol(argv[a], &end, 10);
            if (*end || v < 2 || v > 1025) {
                fprintf(stderr, "table_singular: '%s' is not a size 2 .. 1025 (options come first, in the order "
                                "m, r, a, M)\n", argv[a]);
                return 2;
            }
            Ns[nN++] = (size_t)v;
        }
    }
    for (int s = 0; s < 3; s++) {
        double prev = 0, regprev[4][8];
        for (int k = 0; k < nN; k++) {
            size_t N = Ns[k];
            nbt_table *f = build(&specs[s], 2 * N - 1);
            if (fitM >= 0 && f->kind == NBT_TABLE_J)
                fit_row0(f);
            double sc = scale0(f), reg[4][8];
            worst w;
            measure(f, &w, reg);
            printf("%-3s %4zu^2: rel %.3e", specs[s].name, N, w.err / sc);
            if (prev > 0)
                printf(" (ratio %.2f)", prev / w.err);
            printf("  worst: ch %d at %s %.4g, %s %.4g (fine node %zu,%zu of %zu: %s)\n", w.c,
                   nbt_table_axis_name(f->kind, 0), w.x, nbt_table_axis_name(f->kind, 1), w.y, w.i, w.j,
                   f->axis[0].n, w.i % 2 && w.j % 2 ? "cell centre" : w.i % 2 ? "edge, mid x" : "edge, mid y");
            if (nrand > 0 && (mode == 0 || mode == 6))
                printf("     random points (%d): rel %.3e\n", nrand, random_err(f, &specs[s], nrand) / sc);
            printf("     regions (rows: x quarter in unit coordinate; columns: y eighth), rel error");
            if (prev > 0)
                printf(" / ratio to previous N");
            printf("\n");
            for (int a = 0; a < 4; a++) {
                printf("     ");
                for (int b = 0; b < 8; b++) {
                    printf(" %.2e", reg[a][b] / sc);
                    if (prev > 0)
                        printf("/%4.2f", regprev[a][b] / reg[a][b]);
                }
                printf("\n");
            }
            memcpy(regprev, reg, sizeof reg);
            prev = w.err;
            nbt_table_free(f);
        }
    }
    return 0;
}
