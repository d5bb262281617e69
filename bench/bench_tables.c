/* bench/bench_tables.c: run time against error for the default tables
 * (H_0..3, J_0..3^1, J_0..3^20), side by side with the naive baseline of the
 * thesis (an independent adaptive integral per texel), in one process.
 * Usage: bench_tables [max_size]   (make bench) */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>
#include <nbt/nbt.h>

static double now(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

typedef struct {
    const char *name;
    nbt_table_kind kind;
    int n;
} spec;

static nbt_table *make(const spec *s, size_t N)
{
    nbt_axis a0 = {0, 10, NBT_AXIS_LOG1P, 1000, N};
    nbt_axis a1 = s->kind == NBT_TABLE_H ? (nbt_axis){-M_PI_2, M_PI_2, NBT_AXIS_COS, 0, N}
                                         : (nbt_axis){0, M_PI, NBT_AXIS_COS, 0, N};
    nbt_table *t = nbt_table_alloc(s->kind, &a0, &a1, 4);
    for (int c = 0; c < 4; c++)
        t->k[c] = c;
    t->n = s->kind == NBT_TABLE_J ? s->n : 0;
    return t;
}

static nbt_status build(nbt_table *t, int measure, unsigned threads)
{
    nbt_build_opts o = {1e-10, measure, threads};
    return t->kind == NBT_TABLE_H ? nbt_h_table_build(t, NULL, &o) : nbt_j_table_build(t, NULL, &o);
}

/* best of a few runs */
static double time_build(nbt_table *t, unsigned threads)
{
    double best = INFINITY;
    for (int r = 0; r < 3; r++) {
        double t0 = now();
        build(t, 0, threads);
        best = fmin(best, now() - t0);
    }
    return best;
}

/* Naive baseline: every texel its own adaptive integral (tol 1e-10), timed on
 * a sample of texels and scaled to the table. */
static double baseline(const nbt_table *t, size_t sample, double *per_texel)
{
    size_t N = t->axis[0].n, M = t->axis[1].n, total = N * M;
    double v[4], e[4], t0 = now();
    for (size_t s = 0; s < sample; s++) {
        size_t idx = (s * 7919u) % total, i = idx % N, j = idx / N;
        double x = nbt_axis_node(&t->axis[0], i), y = nbt_axis_node(&t->axis[1], j);
        if (t->kind == NBT_TABLE_H)
            nbt_hk(3, x, y, 1e-10, v, e);
        else
            nbt_jk(3, t->n, x, y, 1e-10, v, e);
    }
    *per_texel = (now() - t0) / (double)sample;
    return *per_texel * (double)total;
}

int main(int argc, char **argv)
{
    size_t maxN = argc > 1 ? (size_t)atol(argv[1]) : 513;
    spec specs[3] = {{"H_0..3", NBT_TABLE_H, 0}, {"J_0..3^1", NBT_TABLE_J, 1}, {"J_0..3^20", NBT_TABLE_J, 20}};
    printf("# nbt table bench: u, T in [0, 10] log1p(c=1000); v, theta cos-mapped; quad tol 1e-10\n");
    printf("# max rel err: measured at all cell and edge midpoints, relative to the largest value of channel 0\n");
    printf("# baseline: one adaptive integral per texel (as the thesis did, there in MATLAB: 2.5-152 s per H,\n");
    printf("#           171-432 s per J table), timed on a sample of texels and scaled to the table\n");
    printf("%-10s %6s %12s %12s %12s %14s %9s\n", "table", "size", "1 thread [s]", "2 threads[s]", "max rel err",
           "baseline [s]", "speed-up");
    for (int k = 0; k < 3; k++) {
        for (size_t N = 33; N <= maxN; N = 2 * N - 1) {
            nbt_table *t = make(&specs[k], N);
            double t1 = time_build(t, 1), t2 = time_build(t, 2);
            build(t, 1, 2);
            double err = 0;
            for (int c = 0; c < 4; c++)
                err = fmax(err, t->max_err[c]);
            err /= t->max_abs[0];
            double per, base = baseline(t, k == 0 ? 400 : 60, &per);
            printf("%-10s %6zu %12.4f %12.4f %12.2e %14.3g %9.0fx\n", specs[k].name, N, t1, t2, err, base, base / t2);
            fflush(stdout);
            nbt_table_free(t);
        }
    }
    /* the default scene's set at the sizes nbt-gen picks for 1e-3 */
    size_t sizes[3] = {49, 49, 97};
    double total = 0;
    for (int k = 0; k < 3; k++) {
        nbt_table *t = make(&specs[k], sizes[k]);
        total += time_build(t, 2);
        nbt_table_free(t);
    }
    printf("# default set as nbt-gen picks it for 1e-3 (H 49^2, J^1 49^2, J^20 97^2, 6-8e-4 relative error): "
           "%.3f s on 2 threads\n", total);
    return 0;
}
