/* gen/cmd_tables.c: the "airlight", "surface" and default (no arguments)
 * commands: parse, let libnbt's planner (nbt/plan.h) plan and build, write. */
#include <config.h>
#include <errno.h>
#include <getopt.h>
#include <math.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>
#include "cli.h"
#include "commands.h"
#include "outputs.h"
#include "preview.h"
#include "progress.h"

double now_seconds(void)
{
    return progress_clock();
}

static double tables_write_seconds(double bytes, size_t nfiles, const progress *p);
static double plan_bytes(const nbt_plan *plan, size_t *nfiles);

double plan_announce(const nbt_plan *plan, progress *p)
{
    double total = 0;
    size_t n = nbt_plan_count(plan), nfiles;
    for (size_t i = 0; i < n; i++)
        total += nbt_plan_get(plan, i)->pred_seconds;
    double bytes = plan_bytes(plan, &nfiles), wr = tables_write_seconds(bytes, nfiles, p);
    progress_note(p, "planned %zu table set(s) in %.2g s, predicted build time %.2g s, writing %.0f MB %.2g s", n,
                  now_seconds() - p->t0, total, 1e-6 * bytes, wr);
    progress_warn_long(p, total + wr, "the planner's prediction, writing included");
    return total;
}

nbt_status build_set(const nbt_plan *plan, size_t i, progress *p, double *pred_left, nbt_tableset *ts, char *err,
                     size_t errlen)
{
    const nbt_plan_set *ps = nbt_plan_get(plan, i);
    char name[128];
    nbt_plan_stem(&ps->req, name, sizeof name);
    progress_note(p, "set %zu/%zu %s: building %zux%zu, %zu pack(s), predicted %.2g s (ETA all sets %.2g s)", i + 1,
                  nbt_plan_count(plan), name, ps->axis[0].n, ps->axis[1].n, ps->npacks, ps->pred_seconds,
                  *pred_left);
    double t0 = now_seconds();
    nbt_status st = nbt_plan_execute(plan, i, ts, err, errlen);
    *pred_left -= ps->pred_seconds;
    if (*pred_left < 0)
        *pred_left = 0;
    if (st == NBT_OK)
        progress_note(p, "set %zu/%zu %s: built %zux%zu in %.2f s (predicted %.2g s), %.1f s elapsed", i + 1,
                      nbt_plan_count(plan), name, ts->t[0]->axis[0].n, ts->t[0]->axis[1].n, now_seconds() - t0,
                      ps->pred_seconds, now_seconds() - p->t0);
    return st;
}

int axis_map_has_c(nbt_axis_map m)
{
    return m == NBT_AXIS_LOG1P || m == NBT_AXIS_LOG1P_CBRT || m == NBT_AXIS_ASINH || m == NBT_AXIS_ENDS;
}

static void axis_desc(const nbt_axis *a, const char *name, char *buf, size_t n)
{
    if (axis_map_has_c(a->map))
        snprintf(buf, n, "%s:%s(c=%g)[%g,%g]", name, nbt_axis_map_name(a->map), a->c, a->lo, a->hi);
    else
        snprintf(buf, n, "%s:%s[%g,%g]", name, nbt_axis_map_name(a->map), a->lo, a->hi);
}

/* The fraction of a tail-form table's nodes whose error map is <= e. */
static double tail_coverage(const nbt_table *t, double e)
{
    size_t n = nbt_table_size(t) / t->nch, k = 0;
    for (size_t i = 0; i < n; i++)
        k += t->data[i * t->nch + 1] <= e;
    return (double)k / (double)n;
}

/* the tail form's error map: how much of the table meets a relative error
 * (max_err is set by the corner u -> 0, v -> pi/2 alone) */
static void print_tail_map(const nbt_table *t)
{
    printf("# tail form: the error map (relative, per node) is <= 1e-3 at %.1f%% and <= 1e-2 at %.1f%% of the "
           "nodes; the route integrates along the ray where its bound exceeds 1e-3\n", 100.0 * tail_coverage(t, 1e-3),
           100.0 * tail_coverage(t, 1e-2));
}

double gslice_lookup_err(const nbt_table *t)
{
    return t->form == NBT_FORM_TAIL || t->form == NBT_FORM_LOG_ET ? t->max_err[0] : t->max_err[0] / t->max_abs[0];
}

int gslice_tol_check(const nbt_table *t, const char *name, double tol, int allow)
{
    double e = gslice_lookup_err(t);
    if (!(tol > 0) || e <= tol)
        return 0;
    char cover[160] = "";
    if (t->form == NBT_FORM_TAIL)
        snprintf(cover, sizeof cover, " (its error map is <= tol at %.1f%% of the nodes; libnbt's airlight route "
                 "integrates along the ray where it is not)", 100.0 * tail_coverage(t, tol));
    fprintf(stderr, "nbt-gen: %s: %s: the g-sliced %s table's recorded lookup error is %.2e, above tol %.2e%s%s\n",
            name, allow ? "warning" : "error", nbt_table_kind_name(t->kind), e, tol, cover,
            allow ? "; written anyway (--allow-tol-miss)" : ": nothing written; pass --allow-tol-miss to write it anyway,"
                                                           " or ask for a larger tol or a smaller g range");
    return !allow;
}

/* One output file: table t of a set as EXR (png == 0) or as its PNG preview. */
typedef struct {
    const nbt_table *t;
    char *path;
    int png, ok, skip; /* skip: a preview not asked for */
    outputs_file *reg; /* removed on a signal or a later failure (outputs.h) */
    double weight;     /* its share of the writing: the table's bytes (EXR), a tenth of them (preview) */
    atomic_uint_fast32_t ppm; /* written so far, parts per million (the progress lines) */
} out_job;

typedef struct {
    out_job *job;
    size_t n;
    atomic_size_t next;
    atomic_size_t running; /* writer threads still busy */
} out_queue;

static void on_chunk(double f, void *vj)
{
    atomic_store(&((out_job *)vj)->ppm, (uint_fast32_t)(1e6 * f));
}

static void *out_worker(void *vq)
{
    out_queue *q = vq;
    for (size_t i; (i = atomic_fetch_add(&q->next, 1)) < q->n;) {
        out_job *j = &q->job[i];
        if (j->skip || outputs_begin(j->reg))
            continue;
        j->ok = j->png ? preview_write_png(j->t, j->path) == 0
                       : nbt_table_write_exr_progress(j->t, j->path, NBT_EXR_ZIP, on_chunk, j) == NBT_OK;
        atomic_store(&j->ppm, 1000000);
        outputs_end(j->reg, j->ok);
    }
    atomic_fetch_sub(&q->running, 1);
    return NULL;
}

/* Up to one writer per CPU (the previews' sampling and deflate were a third of the default scene's
 * run time on one core), the same number that tables_write_seconds assumes */
static size_t out_threads(size_t nfiles)
{
    long ncpu = sysconf(_SC_NPROCESSORS_ONLN);
    size_t nt = ncpu < 1 ? 1 : (size_t)ncpu;
    if (nt > nfiles)
        nt = nfiles;
    return nt > 16 ? 16 : nt < 1 ? 1 : nt;
}

/* The files are independent (each written via a temporary file and renamed),
 * so they are written in parallel. With w (not NULL) the calling thread
 * only watches: the share written, every 0.25 s (or half w's interval, at
 * least 1 ms), as w's progress lines. */
static void out_run(out_job *job, size_t n, progress *w)
{
    out_queue q = {job, n, 0, 0};
    size_t nt = out_threads(n);
    pthread_t th[16];
    size_t started = 0;
    for (; started + (w ? 0 : 1) < nt; started++) {
        atomic_fetch_add(&q.running, 1);
        if (pthread_create(&th[started], NULL, out_worker, &q) != 0) {
            atomic_fetch_sub(&q.running, 1);
            break;
        }
    }
    if (!w || started == 0) {
        atomic_fetch_add(&q.running, 1);
        out_worker(&q);
    } else {
        double total = 0;
        for (size_t i = 0; i < n; i++)
            total += job[i].skip ? 0 : job[i].weight;
        /* every 0.25 s, or faster where lines are wanted more often (NBT_PROGRESS_SECONDS) */
        double per = fmax(0.001, fmin(0.25, 0.5 * w->interval));
        struct timespec ts = {0, (long)(1e9 * per)};
        while (atomic_load(&q.running) > 0) {
            double done = 0;
            for (size_t i = 0; i < n; i++)
                done += job[i].skip ? 0 : job[i].weight * 1e-6 * (double)atomic_load(&job[i].ppm);
            if (total > 0 && done < total)
                progress_fraction(w, done / total);
            nanosleep(&ts, NULL);
        }
    }
    for (size_t i = 0; i < started; i++)
        pthread_join(th[i], NULL);
}

/* The deflate of nbt's float tables (ZIP, as nbt_table_write_exr writes them) ran at 32-40 MB of
 * raw table data per CPU second (16.8 MB packs of H and J, 1025^2 x 4 channels). */
#define WRITE_MB_PER_CPU_SECOND 35.0

/* CPU time of the calling thread */
static double thread_cpu_seconds(void)
{
    struct timespec t;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

/* Predicted wall time of writing `bytes` of tables as nfiles EXR files: their deflate's CPU time
 * shared by the writers, times how much slower than its CPU time the calling thread has run so far
 * (it plans and builds alongside the other threads, so this is the machine's other load; p's start
 * is about the thread's) */
static double tables_write_seconds(double bytes, size_t nfiles, const progress *p)
{
    double cpu = thread_cpu_seconds(), wall = progress_clock() - p->t0;
    double slow = cpu > 0.01 && wall > 0 ? fmax(1.0, wall / cpu) : 1.0;
    return bytes / (1e6 * WRITE_MB_PER_CPU_SECOND) / (double)out_threads(nfiles) * slow;
}

/* the raw bytes of a plan's tables and their number of EXR files */
static double plan_bytes(const nbt_plan *plan, size_t *nfiles)
{
    double b = 0;
    *nfiles = 0;
    for (size_t i = 0; i < nbt_plan_count(plan); i++) {
        const nbt_plan_set *ps = nbt_plan_get(plan, i);
        double ch = ps->req.phase ? 1.0 : (double)ps->req.nterms;
        b += (double)ps->axis[0].n * (double)ps->axis[1].n * ch * (ps->req.half ? 2.0 : 4.0);
        *nfiles += ps->npacks;
    }
    return b;
}

static void print_table_line(const nbt_tableset *ts, const nbt_table *t, const char *path)
{
    char d0[96], d1[96];
    axis_desc(&t->axis[0], nbt_table_axis_name(t->kind, 0), d0, sizeof d0);
    axis_desc(&t->axis[1], nbt_table_axis_name(t->kind, 1), d1, sizeof d1);
    double e = nbt_table_max_err(t);
    char d2[96] = "";
    if (t->axis[2].n >= 2) {
        axis_desc(&t->axis[2], nbt_table_axis_name(t->kind, 2), d2 + 1, sizeof d2 - 1);
        d2[0] = ' ';
    }
    /* form sub says so: a shader of its own that reads the texels as values would miss the closed form */
    printf("%-22s %4zux%-4zu%s%.0zu %s %s%s  max interp err %.2e (rel %.2e)  quad err %.1e%s\n", path, t->axis[0].n,
           t->axis[1].n, t->axis[2].n >= 2 ? "x" : "", t->axis[2].n >= 2 ? t->axis[2].n : 0, d0, d1, d2, e,
           t->form == NBT_FORM_TAIL || t->form == NBT_FORM_LOG_ET ? e : ts->scale > 0 ? e / ts->scale : e, t->quad_err,
           t->form == NBT_FORM_SUB ? "  form sub (lookups add a closed form back: doc/shaders.md)" : "");
    if (t->form == NBT_FORM_TAIL)
        print_tail_map(t);
}

int tablesets_write(const nbt_tableset *ts, size_t nsets, const char *const *stems, int preview, progress *p)
{
    size_t n = 0;
    for (size_t s = 0; s < nsets; s++)
        n += 2 * ts[s].count;
    out_job *job = calloc(n ? n : 1, sizeof *job);
    int rc = job ? 0 : 1;
    for (size_t s = 0, i = 0; s < nsets && rc == 0; s++)
        for (size_t k = 0; k < ts[s].count && rc == 0; k++, i += 2) {
            const nbt_table *t = ts[s].t[k];
            size_t len = strlen(stems[s]) + 32;
            for (int png = 0; png < 2; png++) {
                char *path = malloc(len);
                job[i + (size_t)png] = (out_job){t, path, png, 0, png && !preview, NULL, 0, 0};
                job[i + (size_t)png].weight = (double)nbt_table_size(t) * (t->half ? 2.0 : 4.0) * (png ? 0.1 : 1.0);
                if (!path) {
                    rc = 1;
                    break;
                }
                if (ts[s].count == 1 || t->k[0] < 0)
                    snprintf(path, len, "%s.%s", stems[s], png ? "png" : "exr");
                else
                    snprintf(path, len, "%s_k%d-%d.%s", stems[s], t->k[0], t->k[t->nch - 1], png ? "png" : "exr");
                if (!job[i + (size_t)png].skip && !(job[i + (size_t)png].reg = outputs_add(path))) {
                    rc = 1;
                    break;
                }
            }
        }
    if (rc != 0)
        fprintf(stderr, "nbt-gen: out of memory writing the tables\n");
    else {
        /* progress: the EXR files' raw bytes, predicted and measured time */
        double bytes = 0, t0 = now_seconds(), pred = 0;
        size_t nexr = 0, nfiles = 0;
        for (size_t i = 0; i < n; i++) {
            nfiles += !job[i].skip;
            if (!job[i].png) {
                bytes += job[i].weight;
                nexr++;
            }
        }
        char label[96];
        progress w;
        if (p) {
            pred = tables_write_seconds(bytes, nexr, p);
            progress_note(p, "writing %zu file(s), %.1f MB of tables, predicted %.2g s", nfiles, 1e-6 * bytes, pred);
            snprintf(label, sizeof label, "%s: writing", p->what);
            progress_init(&w, label, p->quiet);
            w.warned = p->warned; /* one long-run warning per run */
        }
        out_run(job, n, p ? &w : NULL);
        if (p) {
            progress_end(&w);
            p->warned |= w.warned;
        }
        for (size_t i = 0; i < n; i++)
            if (!job[i].skip && !job[i].ok) {
                fprintf(stderr, "nbt-gen: cannot write '%s'\n", job[i].path);
                rc = 1;
                break;
            }
        if (rc != 0) { /* all or nothing */
            for (size_t i = 0; i < n; i++)
                if (job[i].ok)
                    unlink(job[i].path);
        } else if (p)
            progress_note(p, "wrote %zu file(s) in %.2f s (predicted %.2g s), %.1f s elapsed", nfiles,
                          now_seconds() - t0, pred, now_seconds() - p->t0);
    }
    if (rc == 0)
        for (size_t s = 0, i = 0; s < nsets; s++)
            for (size_t k = 0; k < ts[s].count; k++, i += 2)
                print_table_line(&ts[s], ts[s].t[k], job[i].path);
    for (size_t i = 0; job && i < n; i++)
        free(job[i].path);
    free(job);
    return rc;
}

int tableset_write(const nbt_tableset *ts, const char *stem, int preview, progress *p)
{
    return tablesets_write(ts, 1, &stem, preview, p);
}

void print_legendre(const nbt_plan_legendre *l, double gmax)
{
    printf("# Legendre terms: %zu (airlight truncation error <= %.2e relative for |g| <= %g)\n", l->nterms,
           l->trunc_err, gmax);
    printf("# per-table interpolation target: %.2e relative to H_0/J_0 (error amplification %.3g)\n", l->table_tol,
           l->amp);
}

/* Plan the requests, build and write each set under stems[i]; 0 or 1. */
static int plan_build_write(const nbt_plan_request *rq, size_t n, unsigned threads, char stems[][1024], int preview,
                            progress *prog)
{
    char err[512];
    nbt_plan *plan = NULL;
    nbt_status st = nbt_plan_tables(rq, n, threads, &plan, err, sizeof err);
    int rc = 0;
    if (st != NBT_OK) {
        fprintf(stderr, "nbt-gen: %s\n", err);
        return 1;
    }
    double left = plan_announce(plan, prog);
    for (size_t i = 0; i < n && rc == 0; i++) {
        nbt_tableset ts;
        st = build_set(plan, i, prog, &left, &ts, err, sizeof err);
        if (st != NBT_OK) {
            fprintf(stderr, "nbt-gen: %s\n", err);
            rc = 1;
            break;
        }
        rc = tableset_write(&ts, stems[i], preview, prog);
        nbt_tableset_free(&ts);
    }
    nbt_plan_free(plan);
    return rc;
}

/* ---- nbt-gen airlight|surface ---- */

static void tables_help(const char *cmd)
{
    printf("Usage: nbt-gen %s [-o FILE.exr] [--size WxH | --tol EPS] [--kmax K | --g LO:HI | --phase SPEC]\n"
           "       %*s [--basis legendre|slices|auto] [--max X] [--half] [--threads T] [--no-preview] [--quiet]%s\n"
           "       %*s [--allow-tol-miss]\n\n"
           "Tabulates %s on a node-aligned grid and writes OpenEXR (+ PNG preview).\n"
           "  -o FILE.exr    output (default ./%s.exr; more than 4 orders: FILE_k0-3.exr, ...)\n"
           "  --size WxH     nodes per axis (2..4096); mappings by the planner's rule: log1p_cbrt (u/T),\n"
           "                 cos (v/theta; asinh(c=1) for J^1)\n"
           "  --tol EPS      target max interpolation error relative to the largest value of the\n"
           "                 first pack (H_0/J_0), default 1e-3; mappings and size are chosen to meet it,\n"
           "                 measured at all cell and edge midpoints\n"
           "  --kmax K       Legendre orders 0..K (default 3), packed 4 per file (RGBA)\n"
           "  --g LO:HI      HG asymmetry range to serve: the number of orders is chosen so the\n"
           "                 airlight series truncation stays below tol/2, and the tables' error\n"
           "                 target is tol/2 over the error amplification sum (2k+1)|g|^k\n"
           "  --basis B      with --g: legendre (the orders above), slices (one 3-D table of HG\n"
           "                 slices on an atanh g axis, cubic in g for H: nbt/gslice.h) or auto (default:\n"
           "                 the smaller predicted build time; prints why); slices need --tol, and a\n"
           "                 g-sliced table whose recorded lookup error misses tol is an error (exit 1,\n"
           "                 nothing written) unless --allow-tol-miss\n"
           "  --phase SPEC   fixed phase instead: iso, rayleigh, hg:g=G, gauss:B=B, table:FILE\n"
           "  --max X        upper end of %s (default 10), 0 < X <= 1e6\n"
           "%s"
           "  --half         store half floats\n"
           "  --threads T    worker threads, 0..64 (default 0: all CPUs)\n"
           "  --no-preview   no PNG preview\n"
           "  --quiet        no progress lines on stderr (by default: the plan's predicted time, each set's\n"
           "                 start with its predicted time and its end with the actual time, and\n"
           "                 one warning line when the plan predicts more than 60 s)\n",
           cmd, (int)strlen(cmd), "", strcmp(cmd, "surface") ? "" : " [--n N]", (int)strlen(cmd), "",
           strcmp(cmd, "surface") ? "H_k(u, v), u in [0, X], v in [-pi/2, pi/2]"
                                  : "J_k^n(T, theta), T in [0, X], theta in [0, pi]",
           strcmp(cmd, "surface") ? "H" : "J<n>", strcmp(cmd, "surface") ? "u" : "T",
           strcmp(cmd, "surface") ? "" : "  --n N          cosine exponent: 1 Lambert, > 1 Phong (default 1), <= 10000\n");
}

static void parse_size(const char *arg, size_t *w, size_t *h)
{
    char extra;
    long a, b;
    if (sscanf(arg, "%ldx%ld%c", &a, &b, &extra) != 2 || a < 2 || b < 2 || a > 4096 || b > 4096)
        die_usage("--size: '%s' is not accepted: expected WxH with 2 <= W, H <= 4096", arg);
    *w = (size_t)a;
    *h = (size_t)b;
}

/* --basis auto|slices: choose (printing why) and, for slices, build and
 * write the g-sliced table. Returns the exit status, or -1 when the
 * Legendre tables were chosen (the caller builds them). */
static int slices_or_legendre(const nbt_plan_request *s, double g_lo, double g_hi, nbt_basis basis, unsigned threads,
                              const char *out, int preview, int quiet, int allow_miss)
{
    nbt_gslice_request r = {s->kind, s->n, s->xmax, {g_lo, g_hi}, s->tol, {0, 0, 0}, s->half};
    if (!(g_lo < g_hi)) {
        if (basis == NBT_BASIS_SLICES)
            die_usage("--basis slices: --g %g:%g is one value: give a range LO < HI (or --phase hg:g=%g)", g_lo, g_hi,
                      g_lo);
        return -1;
    }
    if (fmax(fabs(g_lo), fabs(g_hi)) > NBT_GSLICE_GMAX)
        die_usage("--g: %g:%g is not accepted for slices: |g| <= %g", g_lo, g_hi, NBT_GSLICE_GMAX);
    nbt_basis_choice ch;
    char err[512];
    progress prog;
    progress_init(&prog, s->kind == NBT_TABLE_H ? "airlight" : "surface", quiet);
    if (nbt_basis_choose(&r, 512, basis, threads, &ch, err, sizeof err) != NBT_OK)
        die("%s", err);
    printf("# basis %s\n", ch.reason);
    if (ch.basis == NBT_BASIS_LEGENDRE)
        return -1;
    progress_note(&prog, "g-sliced %zux%zux%zu: predicted %.2g s", ch.sl_plan.axis[0].n, ch.sl_plan.axis[1].n,
                  ch.sl_plan.axis[2].n, ch.sl_plan.pred_seconds);
    nbt_table *t = NULL;
    double t0 = now_seconds();
    if (nbt_gslice_execute(&ch.sl_plan, threads, &t, err, sizeof err) != NBT_OK)
        die("%s", err);
    char stem[1024];
    if (out) {
        size_t n = strlen(out);
        memcpy(stem, out, n - 4);
        stem[n - 4] = '\0';
    } else if (s->kind == NBT_TABLE_H)
        snprintf(stem, sizeof stem, "H_hg_slices");
    else
        snprintf(stem, sizeof stem, "J%d_hg_slices", s->n);
    nbt_tableset ts = {{t}, 1, t->max_abs[0], gslice_lookup_err(t), now_seconds() - t0};
    int rc = gslice_tol_check(t, stem, s->tol, allow_miss);
    if (rc == 0)
        rc = tableset_write(&ts, stem, preview, &prog);
    if (rc == 0)
        printf("# g-sliced: %zu slices, g %s [%g, %g], %.1f MB as %s, built in %.2f s (planning %.2f s)\n",
               t->axis[2].n, nbt_axis_map_name(t->axis[2].map), t->axis[2].lo, t->axis[2].hi,
               1e-6 * (double)nbt_table_size(t) * (t->half ? 2.0 : 4.0), t->half ? "half" : "float", ts.seconds,
               ch.sl_plan.plan_seconds);
    nbt_table_free(t);
    return rc;
}

/* --kmax accepts orders 0..KMAX_CLI (64 packs of four) */
#define KMAX_CLI 255

int cmd_tables(int argc, char **argv)
{
    const char *cmd = argv[0];
    char cmdline[32];
    snprintf(cmdline, sizeof cmdline, "nbt-gen %s", cmd);
    int surface = !strcmp(cmd, "surface");
    nbt_plan_request s = {surface ? NBT_TABLE_J : NBT_TABLE_H, surface ? 1 : 0, 4, NULL, 10.0, 0, {0, 0}, 0, 0};
    unsigned threads = 0;
    const char *out = NULL, *phase_spec = NULL, *basis_arg = NULL;
    nbt_basis basis = NBT_BASIS_AUTO;
    int have_size = 0, have_tol = 0, have_k = 0, have_g = 0, preview = 1, quiet = 0, allow_miss = 0;
    double g_lo = 0, g_hi = 0;
    static const struct option opts[] = {
        {"output", required_argument, 0, 'o'}, {"size", required_argument, 0, 's'},
        {"tol", required_argument, 0, 't'},    {"kmax", required_argument, 0, 'k'},
        {"phase", required_argument, 0, 'p'},  {"n", required_argument, 0, 'n'},
        {"g", required_argument, 0, 'g'},      {"basis", required_argument, 0, 'b'},
        {"max", required_argument, 0, 'm'},    {"half", no_argument, 0, 'H'},
        {"threads", required_argument, 0, 'j'}, {"no-preview", no_argument, 0, 'P'},
        {"quiet", no_argument, 0, 'q'},         {"allow-tol-miss", no_argument, 0, 'A'},
        {"help", no_argument, 0, 'h'},          {0, 0, 0, 0}};
    int c;
    optind = 1;
    while ((c = getopt_long(argc, argv, ":o:h", opts, NULL)) != -1) {
        switch (c) {
        case 'o': out = optarg; break;
        case 's': parse_size(optarg, &s.size[0], &s.size[1]); have_size = 1; break;
        case 't': s.tol = opt_double("--tol", optarg, 0, 1, 1, 1); have_tol = 1; break;
        case 'k': s.nterms = (size_t)opt_long("--kmax", optarg, 0, KMAX_CLI) + 1; have_k = 1; break;
        case 'p': phase_spec = optarg; break;
        case 'b':
            if (nbt_basis_parse(optarg, &basis) != NBT_OK)
                die_usage("--basis: '%s' is not accepted: legendre, slices or auto", optarg);
            basis_arg = optarg;
            break;
        case 'g': opt_range("--g", optarg, -0.99, 0.99, &g_lo, &g_hi); have_g = 1; break;
        case 'n':
            if (!surface)
                die_usage("--n applies to 'surface' tables only");
            s.n = (int)opt_long("--n", optarg, 1, 10000);
            break;
        case 'm': s.xmax = opt_double("--max", optarg, 0, 1, 1e6, 0); break;
        case 'H': s.half = 1; break;
        case 'j': threads = (unsigned)opt_long("--threads", optarg, 0, 64); break;
        case 'P': preview = 0; break;
        case 'q': quiet = 1; break;
        case 'A': allow_miss = 1; break;
        case 'h': tables_help(cmd); return 0;
        default: die_bad_option(c, argv, cmdline);
        }
    }
    if (optind < argc)
        die_usage("%s: unexpected argument '%s'", cmd, argv[optind]);
    if (have_size && have_tol)
        die_usage("--size and --tol exclude each other: give one");
    if (phase_spec && have_k)
        die_usage("--kmax and --phase exclude each other: Legendre orders or one fixed phase");
    if (have_g && (phase_spec || have_k))
        die_usage("--g chooses the Legendre orders itself: it excludes --kmax and --phase");
    if (basis_arg && !have_g)
        die_usage("--basis applies to a g range (--g LO:HI) only");
    if (have_g && basis == NBT_BASIS_SLICES && have_size)
        die_usage("--basis slices sizes its table by --tol: --size is not accepted with it");
    if (have_g && have_size)
        basis = NBT_BASIS_LEGENDRE; /* auto with --size: the Legendre tables of that size */
    if (!have_size && !have_tol)
        s.tol = 1e-3;
    if (out) {
        size_t n = strlen(out);
        if (n < 5 || strcmp(out + n - 4, ".exr") || n >= 512)
            die_usage("-o: '%s' is not accepted: the output must be a file name ending in .exr", out);
    }
    nbt_phase *ph = NULL;
    if (phase_spec) {
        char err[256];
        if (nbt_phase_parse(phase_spec, &ph, err, sizeof err) != NBT_OK)
            die_usage("--phase: %s", err);
        s.phase = ph;
    }
    if (out)
        check_writable("-o", out);
    else
        check_writable_dir(cmd, ".");
    if (have_g && basis != NBT_BASIS_LEGENDRE) {
        int rc = slices_or_legendre(&s, g_lo, g_hi, basis, threads, out, preview, quiet, allow_miss);
        if (rc >= 0) {
            nbt_phase_free(ph);
            return rc;
        }
    }
    if (have_g) {
        nbt_plan_legendre leg;
        double gmax = fmax(fabs(g_lo), fabs(g_hi));
        if (nbt_plan_legendre_terms(gmax, s.xmax, have_tol ? s.tol : 1e-3, 512, &leg) != NBT_OK)
            die("--g: |g| up to %g needs more than 512 Legendre terms at this tolerance: use --phase hg:g=G", gmax);
        print_legendre(&leg, gmax);
        s.nterms = leg.nterms;
        if (!have_size)
            s.tol = leg.table_tol;
    }
    char stem[1][1024];
    if (out) {
        size_t n = strlen(out);
        memcpy(stem[0], out, n - 4);
        stem[0][n - 4] = '\0';
    } else
        nbt_plan_stem(&s, stem[0], sizeof stem[0]);
    progress prog;
    progress_init(&prog, cmd, quiet);
    int rc = plan_build_write(&s, 1, threads, stem, preview, &prog);
    if (rc == 0 && !quiet)
        fprintf(stderr, "nbt-gen: %zu table(s) in %.3f s\n", s.phase ? (size_t)1 : (s.nterms + 3) / 4,
                now_seconds() - prog.t0);
    nbt_phase_free(ph);
    return rc;
}

/* ---- nbt-gen (no arguments): the default scene ---- */

int cmd_default(int argc, char **argv)
{
    /* only --quiet (-q) is taken; the message names the first other argument */
    int quiet = argc > 1;
    for (int i = 1; i < argc; i++)
        if (strcmp(argv[i], "--quiet") && strcmp(argv[i], "-q"))
            die_usage("unknown option '%s' (see 'nbt-gen --help')", argv[i]);
    const char *dir = "nbt-tables";
    check_writable_dir("nbt-gen", dir);
    if (mkdir(dir, 0777) == 0)
        outputs_dir(dir); /* removed again if the run fails or is interrupted */
    else if (errno != EEXIST)
        die("cannot create the directory '%s': %s", dir, strerror(errno));
    /* the thesis' set: H_0..3, J_0..3^1, J_0..3^20, u and T in [0, 10],
     * theta over [0, pi]; resolution planned for 1e-3 relative error, in
     * form sub (the value minus its closed form, which the CPU lookups and
     * libnbt-gl's shaders add back): 33^2 where plain tables need 49^2
     * (issue 21, doc/tables.md "33^2 at 1e-3") */
    nbt_plan_request rq[3] = {
        {NBT_TABLE_H, 0, 4, NULL, 10.0, 1e-3, {0, 0}, 0, 1},
        {NBT_TABLE_J, 1, 4, NULL, 10.0, 1e-3, {0, 0}, 0, 1},
        {NBT_TABLE_J, 20, 4, NULL, 10.0, 1e-3, {0, 0}, 0, 1},
    };
    char stems[3][1024], err[512];
    const char *stemp[3] = {stems[0], stems[1], stems[2]};
    for (int i = 0; i < 3; i++) {
        char name[64];
        nbt_plan_stem(&rq[i], name, sizeof name);
        snprintf(stems[i], sizeof stems[i], "%s/%s", dir, name);
    }
    progress prog;
    progress_init(&prog, "default scene", quiet);
    double t0 = prog.t0;
    nbt_plan *plan = NULL;
    nbt_tableset ts[3];
    nbt_status st = nbt_plan_tables(rq, 3, 0, &plan, err, sizeof err);
    size_t built = 0;
    if (st == NBT_OK) { /* all sets built before any is written: all or nothing */
        double left = plan_announce(plan, &prog);
        for (; built < 3 && st == NBT_OK; built++)
            if ((st = build_set(plan, built, &prog, &left, &ts[built], err, sizeof err)) != NBT_OK)
                break;
    }
    nbt_plan_free(plan);
    if (st != NBT_OK) {
        for (size_t i = 0; i < built; i++)
            nbt_tableset_free(&ts[i]);
        die("%s", err);
    }
    double tb = now_seconds() - t0;
    int rc = tablesets_write(ts, 3, stemp, 1, &prog);
    for (int i = 0; i < 3; i++)
        nbt_tableset_free(&ts[i]);
    if (rc == 0 && !quiet)
        fprintf(stderr, "nbt-gen: default scene: 3 tables in %s/, built in %.3f s (incl. planning "
                "and error measurement)\n", dir, tb);
    return rc;
}
