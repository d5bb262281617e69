/* bench/bench_jset.c: the planner's J^1 + J^20 g-sliced pair at tol 1e-3
 * (65x257x33, g in [-0.95, 0.95], T <= 20) built as one set
 * (nbt_gslice_build_set, as nbt-gen scene does): wall and CPU time (the
 * machine is shared: CPU time moves far less with the load), and with a
 * file argument every value and recorded bound written out, so that two
 * builds of the library can be compared bit for bit (bench/jset_compare.py).
 * Usage: bench_jset [threads] [repeats] [out.bin]   (make bench) */
#include <stdio.h>
#include <stdlib.h>
#include <time.h>
#include <nbt/nbt.h>

static double clk(clockid_t id)
{
    struct timespec t;
    clock_gettime(id, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

static void dump(FILE *f, const nbt_table *t)
{
    size_t n = t->axis[0].n * t->axis[1].n * t->axis[2].n;
    size_t nc = t->axis[2].n - 1, nr = nbt_table_row_err_len(t), nb = nbt_table_theta_err_len(t);
    double hd[4] = {t->max_err[0], t->max_abs[0], t->quad_err, (double)n};
    fwrite(hd, sizeof hd, 1, f);
    fwrite(t->data, sizeof(float), n, f);
    fwrite(t->cell_err, sizeof(double), nc, f);
    if (t->row_err)
        fwrite(t->row_err, sizeof(double), nr, f);
    if (t->theta_err)
        fwrite(t->theta_err, sizeof(double), nb, f);
}

int main(int argc, char **argv)
{
    unsigned nt = argc > 1 ? (unsigned)atoi(argv[1]) : 2;
    int rep = argc > 2 ? atoi(argv[2]) : 1;
    const char *out = argc > 3 ? argv[3] : NULL;
    nbt_gslice_request rq[2] = {{NBT_TABLE_J, 1, 20.0, {-0.95, 0.95}, 1e-3, {0, 0, 0}, 0},
                                {NBT_TABLE_J, 20, 20.0, {-0.95, 0.95}, 1e-3, {0, 0, 0}, 0}};
    for (int r = 0; r < rep; r++) {
        nbt_table *ts[2];
        double secs[2];
        char err[256];
        double w0 = clk(CLOCK_MONOTONIC), c0 = clk(CLOCK_PROCESS_CPUTIME_ID);
        if (nbt_gslice_build_set(rq, 2, nt, ts, secs, err, sizeof err) != NBT_OK) {
            fprintf(stderr, "bench_jset: %s\n", err);
            return 1;
        }
        double w = clk(CLOCK_MONOTONIC) - w0, c = clk(CLOCK_PROCESS_CPUTIME_ID) - c0;
        printf("J^1 + J^20 %zux%zux%zu, %u threads: wall %.3f s (%.3f + %.3f), cpu %.3f s; rec %.3e %.3e\n",
               ts[0]->axis[0].n, ts[0]->axis[1].n, ts[0]->axis[2].n, nt, w, secs[0], secs[1], c, ts[0]->max_err[0],
               ts[1]->max_err[0]);
        fflush(stdout);
        if (out && r == 0) {
            FILE *f = fopen(out, "wb");
            if (!f) {
                perror(out);
                return 1;
            }
            dump(f, ts[0]);
            dump(f, ts[1]);
            if (fclose(f) != 0) {
                perror(out);
                return 1;
            }
        }
        nbt_table_free(ts[0]);
        nbt_table_free(ts[1]);
    }
    return 0;
}
