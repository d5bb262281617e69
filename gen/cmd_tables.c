/* gen/cmd_tables.c: building and writing table sets; the "airlight",
 * "surface" and default (no arguments) commands. */
#include <config.h>
#include <errno.h>
#include <getopt.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>
#include "cli.h"
#include "commands.h"
#include "preview.h"

double now_seconds(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

void tableset_stem(const tableset_spec *s, char *buf, size_t n)
{
    char kind[16];
    if (s->kind == NBT_TABLE_H)
        snprintf(kind, sizeof kind, "H");
    else
        snprintf(kind, sizeof kind, "J%d", s->n);
    if (s->phase)
        snprintf(buf, n, "%s_%s", kind, nbt_phase_name(s->phase));
    else
        snprintf(buf, n, "%s", kind);
    for (char *p = buf; *p; p++) /* keep file names portable */
        if (*p == ':' || *p == '=' || *p == ' ' || *p == '/')
            *p = '_';
}

/* Interpolation error relative to the table set's scale: the largest value
 * of its first pack (H_0 or J_0 for Legendre sets). */
static double rel_error(const nbt_table *t, double scale)
{
    double e = 0;
    for (size_t c = 0; c < t->nch; c++)
        e = fmax(e, t->max_err[c]);
    return scale > 0 ? e / scale : e;
}

static double table_scale(const nbt_table *t)
{
    double m = 0;
    for (size_t c = 0; c < t->nch; c++)
        m = fmax(m, t->max_abs[c]);
    return m;
}

/* Allocate pack p (orders 4p..4p+3, or the fixed phase) on the given axes. */
static nbt_table *new_pack(const tableset_spec *s, size_t pack, const nbt_axis *a0, const nbt_axis *a1)
{
    size_t nch = 1;
    if (!s->phase) {
        nch = s->nterms - 4 * pack;
        if (nch > 4)
            nch = 4;
    }
    nbt_table *t = nbt_table_alloc(s->kind, a0, a1, nch);
    if (!t)
        return NULL;
    for (size_t c = 0; c < nch; c++)
        t->k[c] = s->phase ? -1 : (int)(4 * pack + c);
    t->n = s->kind == NBT_TABLE_J ? s->n : 0;
    t->half = s->half;
    if (s->phase)
        snprintf(t->phase, sizeof t->phase, "%s", nbt_phase_name(s->phase));
    return t;
}

/* Quadrature tolerance of the tables written, and of the candidates tried
 * while searching mapping and size (only their interpolation error matters). */
#define QUAD_TOL 1e-10
static double search_quad_tol(const tableset_spec *s)
{
    return s->tol > 0 ? fmin(1e-7, 0.01 * s->tol) : 1e-7;
}

/* Build packs [first, first + count) in one pass (every order integrated once). */
static nbt_status build_packs(const tableset_spec *s, size_t first, size_t count, const nbt_axis *a0,
                              const nbt_axis *a1, double qtol, nbt_table **out)
{
    for (size_t i = 0; i < count; i++)
        if (!(out[i] = new_pack(s, first + i, a0, a1))) {
            for (size_t j = 0; j < i; j++)
                nbt_table_free(out[j]);
            return NBT_ENOMEM;
        }
    nbt_build_opts o = {qtol, 1, s->threads};
    nbt_status st = s->kind == NBT_TABLE_H ? nbt_h_table_build_set(out, count, s->phase, &o)
                                           : nbt_j_table_build_set(out, count, s->phase, &o);
    if (st != NBT_OK)
        for (size_t i = 0; i < count; i++) {
            nbt_table_free(out[i]);
            out[i] = NULL;
        }
    return st;
}

/* A search candidate: the first pack only, at the search tolerance. */
static nbt_table *build_one(const tableset_spec *s, nbt_axis a0, nbt_axis a1, nbt_status *st)
{
    nbt_table *t = NULL;
    *st = build_packs(s, 0, 1, &a0, &a1, search_quad_tol(s), &t);
    return t;
}

static nbt_axis make_axis(const tableset_spec *s, int which, nbt_axis_map m, double c, size_t n)
{
    nbt_axis a = {0, 0, m, c, n};
    if (which == 0) {
        a.lo = 0;
        a.hi = s->xmax;
    } else if (s->kind == NBT_TABLE_H) {
        a.lo = -M_PI_2;
        a.hi = M_PI_2;
    } else {
        a.lo = 0;
        a.hi = M_PI;
    }
    return a;
}

/* Axis-0 mapping candidates, ordered by how strongly they cluster nodes at
 * 0 (where H and J have a log singularity in u and T): sqrt, then log1p with
 * c = 10 .. 1e6. Axis 1: cos or linear. */
#define NMAP0 7
static void map0(int i, nbt_axis_map *m, double *c)
{
    *m = i == 0 ? NBT_AXIS_SQRT : NBT_AXIS_LOG1P;
    *c = i == 0 ? 0 : pow(10.0, i);
}

/* Best mapping at N0 x N1 nodes: try (i0 +- 1, j0) and (i0, other j), keep
 * the best; repeat from the new best until nothing improves. *cur holds the
 * best table so far (or NULL) and is replaced. */
static nbt_status best_mapping(const tableset_spec *s, size_t N0, size_t N1, int *i0, int *j0, nbt_table **cur)
{
    nbt_status st = NBT_OK;
    double best = *cur ? rel_error(*cur, table_scale(*cur)) : INFINITY;
    char tried[NMAP0][2] = {{0}};
    for (int moved = 1; moved && st == NBT_OK;) {
        moved = 0;
        int cand[4][2] = {{*i0, *j0}, {*i0 - 1, *j0}, {*i0 + 1, *j0}, {*i0, 1 - *j0}};
        int bi = *i0, bj = *j0;
        for (int q = 0; q < 4 && st == NBT_OK; q++) {
            int i = cand[q][0], j = cand[q][1];
            if (i < 0 || i >= NMAP0 || tried[i][j])
                continue;
            tried[i][j] = 1;
            nbt_axis_map m;
            double c;
            map0(i, &m, &c);
            nbt_table *t = build_one(s, make_axis(s, 0, m, c, N0), make_axis(s, 1, j ? NBT_AXIS_LINEAR : NBT_AXIS_COS, 0, N1), &st);
            if (t && rel_error(t, table_scale(t)) < best) {
                best = rel_error(t, table_scale(t));
                nbt_table_free(*cur);
                *cur = t;
                bi = i;
                bj = j;
            } else
                nbt_table_free(t);
        }
        if (bi != *i0 || bj != *j0) {
            *i0 = bi;
            *j0 = bj;
            moved = 1;
        }
    }
    return st;
}

/* One status line on a terminal (overwritten in place), nothing otherwise. */
static void progress(const tableset_spec *s, const char *what, size_t N)
{
    if (!stderr_is_tty())
        return;
    if (!what) {
        fprintf(stderr, "\r\033[K");
        return;
    }
    fprintf(stderr, "\r\033[Knbt-gen: %s%s: %s %zux%zu", s->kind == NBT_TABLE_H ? "H" : "J",
            s->kind == NBT_TABLE_J ? (s->n == 1 ? "1" : "n") : "", what, N, N);
}

/* Sizes tried by the error-driven search, growing by ~1.5. */
static const size_t SIZES[] = {33, 49, 65, 97, 129, 193, 257, 385, 513, 769, 1025, 1537, 2049};
#define NSIZES (sizeof SIZES / sizeof SIZES[0])

/* The next size after N, or 0 past the last. */
static size_t grow(size_t N)
{
    for (size_t i = 0; i < NSIZES; i++)
        if (SIZES[i] > N)
            return SIZES[i];
    return 0;
}

int tableset_build(const tableset_spec *s, tableset *out)
{
    memset(out, 0, sizeof *out);
    size_t npacks = s->phase ? 1 : (s->nterms + 3) / 4;
    if (npacks > TABLESET_MAX) {
        fprintf(stderr, "nbt-gen: too many Legendre orders (%zu): at most %d\n", s->nterms, 4 * TABLESET_MAX);
        return 1;
    }
    double t0 = now_seconds();
    nbt_status st = NBT_OK;
    nbt_table *first = NULL;
    int i0 = 3, j0 = 0; /* start from log1p(c = 1000) x cos */
    if (s->tol <= 0) {
        /* fixed size: the best mapping at that size */
        st = best_mapping(s, s->size[0], s->size[1], &i0, &j0, &first);
    } else {
        /* size: grow by ~1.5 until the measured error meets tol, re-choosing
         * the mapping at every size (the best clustering grows with N) */
        for (size_t i = 0; st == NBT_OK; i++) {
            if (i == NSIZES) {
                progress(s, NULL, 0);
                fprintf(stderr, "nbt-gen: --tol %g is not reached with up to 2049x2049 nodes (best %.2g): "
                        "ask for a larger tolerance or a smaller range\n", s->tol, rel_error(first, table_scale(first)));
                nbt_table_free(first);
                return 1;
            }
            nbt_table_free(first);
            first = NULL;
            progress(s, "trying axis mappings at", SIZES[i]);
            st = best_mapping(s, SIZES[i], SIZES[i], &i0, &j0, &first);
            if (st == NBT_OK && first && rel_error(first, table_scale(first)) <= s->tol)
                break;
        }
    }
    /* the set itself: every pack, at the final quadrature tolerance, in one
     * pass; higher orders oscillate more, so grow until every pack meets tol */
    if (st == NBT_OK && first) {
        nbt_axis a0 = first->axis[0], a1 = first->axis[1];
        nbt_table_free(first);
        first = NULL;
        for (;;) {
            progress(s, "building all orders at", a0.n);
            st = build_packs(s, 0, npacks, &a0, &a1, QUAD_TOL, out->t);
            if (st != NBT_OK)
                break;
            out->count = npacks;
            double scale = table_scale(out->t[0]), worst = 0;
            for (size_t p = 0; p < npacks; p++)
                worst = fmax(worst, rel_error(out->t[p], scale));
            size_t next = grow(a0.n);
            if (s->tol <= 0 || worst <= s->tol)
                break;
            if (next == 0) {
                progress(s, NULL, 0);
                fprintf(stderr, "nbt-gen: --tol %g is not reached by every order with up to 2049x2049 nodes "
                        "(worst %.2g): ask for a larger tolerance or fewer orders\n", s->tol, worst);
                tableset_free(out);
                return 1;
            }
            tableset_free(out);
            a0.n = a1.n = next;
        }
    }
    nbt_table_free(first);
    progress(s, NULL, 0);
    if (st != NBT_OK) {
        fprintf(stderr, "nbt-gen: building the %s table failed: %s\n", s->kind == NBT_TABLE_H ? "H" : "J",
                nbt_strerror(st));
        tableset_free(out);
        return 1;
    }
    out->seconds = now_seconds() - t0;
    out->scale = table_scale(out->t[0]);
    for (size_t i = 0; i < out->count; i++)
        out->rel_err = fmax(out->rel_err, rel_error(out->t[i], out->scale));
    return 0;
}

void tableset_free(tableset *ts)
{
    for (size_t i = 0; i < ts->count; i++)
        nbt_table_free(ts->t[i]);
    ts->count = 0;
}

static void axis_desc(const nbt_axis *a, const char *name, char *buf, size_t n)
{
    if (a->map == NBT_AXIS_LOG1P)
        snprintf(buf, n, "%s:%s(c=%g)[%g,%g]", name, nbt_axis_map_name(a->map), a->c, a->lo, a->hi);
    else
        snprintf(buf, n, "%s:%s[%g,%g]", name, nbt_axis_map_name(a->map), a->lo, a->hi);
}

int tableset_write(const tableset *ts, const char *stem, int preview)
{
    size_t written = 0, len = strlen(stem) + 32;
    char **paths = calloc(2 * ts->count, sizeof(char *));
    int rc = 0;
    for (size_t i = 0; i < ts->count && rc == 0; i++) {
        const nbt_table *t = ts->t[i];
        char *exr = malloc(len), *png = malloc(len);
        paths[2 * i] = exr;
        paths[2 * i + 1] = png;
        if (!exr || !png) {
            rc = 1;
            break;
        }
        if (ts->count == 1 || t->k[0] < 0) {
            snprintf(exr, len, "%s.exr", stem);
            snprintf(png, len, "%s.png", stem);
        } else {
            snprintf(exr, len, "%s_k%d-%d.exr", stem, t->k[0], t->k[t->nch - 1]);
            snprintf(png, len, "%s_k%d-%d.png", stem, t->k[0], t->k[t->nch - 1]);
        }
        if (nbt_table_write_exr(t, exr, NBT_EXR_ZIP) != NBT_OK) {
            fprintf(stderr, "nbt-gen: cannot write '%s'\n", exr);
            rc = 1;
            break;
        }
        written = 2 * i + 1;
        if (preview && preview_write_png(t, png) != 0) {
            fprintf(stderr, "nbt-gen: cannot write '%s'\n", png);
            rc = 1;
            break;
        }
        written = 2 * i + 2;
    }
    if (rc != 0) {
        for (size_t i = 0; i < written; i++)
            if (paths[i])
                unlink(paths[i]);
    } else {
        for (size_t i = 0; i < ts->count; i++) {
            const nbt_table *t = ts->t[i];
            char d0[96], d1[96];
            axis_desc(&t->axis[0], nbt_table_axis_name(t->kind, 0), d0, sizeof d0);
            axis_desc(&t->axis[1], nbt_table_axis_name(t->kind, 1), d1, sizeof d1);
            printf("%-22s %4zux%-4zu %s %s  max interp err %.2e (rel %.2e)  quad err %.1e\n", paths[2 * i],
                   t->axis[0].n, t->axis[1].n, d0, d1, fmax(fmax(t->max_err[0], t->nch > 1 ? t->max_err[1] : 0),
                   fmax(t->nch > 2 ? t->max_err[2] : 0, t->nch > 3 ? t->max_err[3] : 0)),
                   rel_error(t, ts->scale), t->quad_err);
        }
    }
    for (size_t i = 0; i < 2 * ts->count; i++)
        free(paths[i]);
    free(paths);
    return rc;
}

/* Smallest N such that the airlight series truncated to N terms differs from
 * the converged one by at most tol relative, for HG with |g| <= gmax, over
 * sample rays (u up to umax, gamma from 0.05 to 2.5 rad, unobstructed). */
static size_t choose_terms(double gmax, double umax, double tol, double *achieved)
{
    /* orders beyond K: (2k+1) g^k below 1e-3 tol, negligible for the tail */
    size_t K = 8;
    while (K < 512 && (2.0 * K + 1.0) * pow(gmax, (double)K) > 1e-3 * tol)
        K *= 2;
    static const double gam[] = {0.05, 0.2, 0.5, 1.0, 1.5, 2.5};
    double *h1 = malloc(2 * (K + 1) * sizeof(double)), *h0 = malloc(2 * (K + 1) * sizeof(double));
    double *worst = calloc(K + 2, sizeof(double));
    if (!h1 || !h0 || !worst)
        die("out of memory");
    for (int iu = 0; iu < 6; iu++) {
        double u = umax * pow(10.0, -iu * 0.6);
        for (size_t ig = 0; ig < sizeof gam / sizeof gam[0]; ig++) {
            if (nbt_hk(K, u, M_PI_2, 1e-10, h1, h1 + K + 1) != NBT_OK ||
                nbt_hk(K, u, gam[ig] - M_PI_2, 1e-10, h0, h0 + K + 1) != NBT_OK)
                die("H_k evaluation failed");
            double total = 0, tail = 0, gk = 1;
            for (size_t k = 0; k <= K; k++, gk *= gmax)
                total += (2.0 * k + 1.0) * gk * (h1[k] - h0[k]);
            /* tail after N terms, from the top down */
            gk = pow(gmax, (double)K);
            for (size_t k = K + 1; k-- > 0; gk = gmax != 0 ? gk / gmax : (k == 1 ? 1 : 0)) {
                tail += (2.0 * k + 1.0) * gk * (h1[k] - h0[k]);
                worst[k] = fmax(worst[k], fabs(tail / total));
            }
        }
    }
    size_t N = 1;
    while (N <= K && worst[N] > tol)
        N++;
    *achieved = N <= K ? worst[N] : worst[K];
    free(h1);
    free(h0);
    free(worst);
    return N;
}

int legendre_budget(double gmax, double xmax, double tol, size_t nmax, size_t *nterms, double *table_tol)
{
    double trunc;
    *nterms = choose_terms(gmax, xmax, 0.5 * tol, &trunc);
    if (*nterms > 512 || *nterms > nmax)
        return 1;
    /* Interpolation gets the other half of tol. In the series each order's
     * error is weighted by (2k+1)|g|^k, so each table must be that much
     * better than tol/2 (relative to H_0/J_0). */
    double amp = 0;
    for (size_t k = 0; k < *nterms; k++)
        amp += (2.0 * k + 1.0) * pow(gmax, (double)k);
    *table_tol = 0.5 * tol / amp;
    printf("# Legendre terms: %zu (airlight truncation error <= %.2e relative for |g| <= %g)\n", *nterms, trunc, gmax);
    printf("# per-table interpolation target: %.2e relative to H_0/J_0 (error amplification %.3g)\n", *table_tol, amp);
    return 0;
}

/* ---- nbt-gen airlight|surface ---- */

static void tables_help(const char *cmd)
{
    printf("Usage: nbt-gen %s [-o FILE.exr] [--size WxH | --tol EPS] [--kmax K | --g LO:HI | --phase SPEC]\n"
           "       %*s [--max X] [--half] [--threads T] [--no-preview]%s\n\n"
           "Tabulates %s on a node-aligned grid and writes OpenEXR (+ PNG preview).\n"
           "  -o FILE.exr    output (default ./%s.exr; more than 4 orders: FILE_k0-3.exr, ...)\n"
           "  --size WxH     nodes per axis (2..4096); mappings sqrt (u/T) and cos (v/theta)\n"
           "  --tol EPS      target max interpolation error relative to the largest value of the\n"
           "                 first pack (H_0/J_0), default 1e-3; mappings and size are chosen to meet it,\n"
           "                 measured at all cell and edge midpoints\n"
           "  --kmax K       Legendre orders 0..K (default 3), packed 4 per file (RGBA)\n"
           "  --g LO:HI      HG asymmetry range to serve: the number of orders is chosen so the\n"
           "                 airlight series truncation stays below tol/2, and the tables' error\n"
           "                 target is tol/2 over the error amplification sum (2k+1)|g|^k\n"
           "  --phase SPEC   fixed phase instead: iso, rayleigh, hg:g=G, gauss:B=B, table:FILE\n"
           "  --max X        upper end of %s (default 10), 0 < X <= 1e6\n"
           "%s"
           "  --half         store half floats\n"
           "  --threads T    worker threads (default: all CPUs)\n",
           cmd, (int)strlen(cmd), "", strcmp(cmd, "surface") ? "" : " [--n N]",
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

int cmd_tables(int argc, char **argv)
{
    const char *cmd = argv[0];
    int surface = !strcmp(cmd, "surface");
    tableset_spec s = {surface ? NBT_TABLE_J : NBT_TABLE_H, 1, 4, NULL, 10.0, 0, {0, 0}, 0, 0};
    const char *out = NULL, *phase_spec = NULL;
    int have_size = 0, have_tol = 0, have_k = 0, have_g = 0, preview = 1;
    double g_lo = 0, g_hi = 0;
    static const struct option opts[] = {
        {"output", required_argument, 0, 'o'}, {"size", required_argument, 0, 's'},
        {"tol", required_argument, 0, 't'},    {"kmax", required_argument, 0, 'k'},
        {"phase", required_argument, 0, 'p'},  {"n", required_argument, 0, 'n'},
        {"g", required_argument, 0, 'g'},
        {"max", required_argument, 0, 'm'},    {"half", no_argument, 0, 'H'},
        {"threads", required_argument, 0, 'j'}, {"no-preview", no_argument, 0, 'P'},
        {"help", no_argument, 0, 'h'},          {0, 0, 0, 0}};
    int c;
    optind = 1;
    while ((c = getopt_long(argc, argv, "o:h", opts, NULL)) != -1) {
        switch (c) {
        case 'o': out = optarg; break;
        case 's': parse_size(optarg, &s.size[0], &s.size[1]); have_size = 1; break;
        case 't': s.tol = opt_double("--tol", optarg, 0, 1, 1, 1); have_tol = 1; break;
        case 'k': s.nterms = (size_t)opt_long("--kmax", optarg, 0, 4 * TABLESET_MAX - 1) + 1; have_k = 1; break;
        case 'p': phase_spec = optarg; break;
        case 'g': opt_range("--g", optarg, -0.99, 0.99, &g_lo, &g_hi); have_g = 1; break;
        case 'n':
            if (!surface)
                die_usage("--n applies to 'surface' tables only");
            s.n = (int)opt_long("--n", optarg, 1, 10000);
            break;
        case 'm': s.xmax = opt_double("--max", optarg, 0, 1, 1e6, 0); break;
        case 'H': s.half = 1; break;
        case 'j': s.threads = (unsigned)opt_long("--threads", optarg, 1, 64); break;
        case 'P': preview = 0; break;
        case 'h': tables_help(cmd); return 0;
        default: die_usage("see 'nbt-gen %s --help'", cmd);
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
    if (have_g) {
        double ttol;
        if (legendre_budget(fmax(fabs(g_lo), fabs(g_hi)), s.xmax, have_tol ? s.tol : 1e-3, 512, &s.nterms, &ttol) != 0)
            die("--g: |g| up to %g needs more than 512 Legendre terms at this tolerance: use --phase hg:g=G",
                fmax(fabs(g_lo), fabs(g_hi)));
        if (!have_size)
            s.tol = ttol;
    }
    char stem[512];
    if (out) {
        size_t n = strlen(out);
        memcpy(stem, out, n - 4);
        stem[n - 4] = '\0';
    } else
        tableset_stem(&s, stem, sizeof stem);
    tableset ts;
    int rc = tableset_build(&s, &ts);
    if (rc == 0) {
        rc = tableset_write(&ts, stem, preview);
        if (rc == 0)
            fprintf(stderr, "nbt-gen: %zu table(s) in %.3f s\n", ts.count, ts.seconds);
    }
    tableset_free(&ts);
    nbt_phase_free(ph);
    return rc;
}

/* ---- nbt-gen (no arguments): the default scene ---- */

int cmd_default(int argc, char **argv)
{
    (void)argc;
    (void)argv;
    const char *dir = "nbt-tables";
    check_writable_dir("nbt-gen", dir);
    if (mkdir(dir, 0777) != 0 && errno != EEXIST)
        die("cannot create the directory '%s': %s", dir, strerror(errno));
    /* the thesis' set: H_0..3, J_0..3^1, J_0..3^20, u and T in [0, 10],
     * theta over [0, pi]; resolution chosen for 1e-3 relative error */
    tableset_spec specs[3] = {
        {NBT_TABLE_H, 0, 4, NULL, 10.0, 1e-3, {0, 0}, 0, 0},
        {NBT_TABLE_J, 1, 4, NULL, 10.0, 1e-3, {0, 0}, 0, 0},
        {NBT_TABLE_J, 20, 4, NULL, 10.0, 1e-3, {0, 0}, 0, 0},
    };
    tableset ts[3];
    double t0 = now_seconds();
    int rc = 0;
    size_t built = 0;
    for (; built < 3 && rc == 0; built++)
        rc = tableset_build(&specs[built], &ts[built]);
    if (rc != 0)
        built--;
    double tb = now_seconds() - t0;
    for (size_t i = 0; i < built && rc == 0; i++) {
        char stem[256], name[64];
        tableset_stem(&specs[i], name, sizeof name);
        snprintf(stem, sizeof stem, "%s/%s", dir, name);
        rc = tableset_write(&ts[i], stem, 1);
    }
    for (size_t i = 0; i < built; i++)
        tableset_free(&ts[i]);
    if (rc == 0)
        fprintf(stderr, "nbt-gen: default scene: 3 tables in %s/, built in %.3f s (incl. size search "
                "and error measurement)\n", dir, tb);
    return rc;
}
