/* gen/cmd_scene.c: "nbt-gen scene FILE [-o DIR]": only the tables a scene
 * needs, each with the smallest size and number of Legendre terms that meet
 * the scene's error target. Format: doc/scene-format.md. */
#include <config.h>
#include <errno.h>
#include <getopt.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include "cli.h"
#include "commands.h"

/* libnbt-gl's airlight and surface shaders take at most 4 RGBA packs per
 * kind (GLSL 3.30 indexes sampler arrays with constants only): 16 orders. */
#define NBT_SCENE_GL_ORDERS 16

typedef struct {
    double kt_lo, kt_hi, ks_lo, ks_hi, d_lo, d_hi, g_lo, g_hi, tol;
    int have_kt, have_ks, have_d, have_g, airlight, diffuse, half;
    char phase[256];
    int phong[16];
    long orders_max;  /* Legendre orders the tables may hold (default: what libnbt-gl takes) */
    size_t nphong;
} scene_t;

static char *trim(char *s)
{
    while (*s == ' ' || *s == '\t')
        s++;
    char *e = s + strlen(s);
    while (e > s && (e[-1] == ' ' || e[-1] == '\t' || e[-1] == '\n' || e[-1] == '\r'))
        *--e = '\0';
    return s;
}

static int yesno(const char *file, int line, const char *key, const char *v)
{
    if (!strcmp(v, "yes"))
        return 1;
    if (!strcmp(v, "no"))
        return 0;
    die_usage("%s:%d: %s = '%s' is not accepted: yes or no", file, line, key, v);
}

static void parse_scene(const char *path, scene_t *s)
{
    FILE *f = fopen(path, "r");
    if (!f)
        die_usage("scene: cannot open '%s': %s", path, strerror(errno));
    memset(s, 0, sizeof *s);
    s->airlight = s->diffuse = 1;
    s->tol = 1e-3;
    s->orders_max = NBT_SCENE_GL_ORDERS;
    char buf[1024], opt[160];
    int line = 0;
    while (fgets(buf, sizeof buf, f)) {
        line++;
        char *h = strchr(buf, '#');
        if (h)
            *h = '\0';
        char *l = trim(buf);
        if (!*l)
            continue;
        char *eq = strchr(l, '=');
        if (!eq)
            die_usage("%s:%d: expected 'key = value', got '%s'", path, line, l);
        *eq = '\0';
        char *key = trim(l), *val = trim(eq + 1);
        snprintf(opt, sizeof opt, "%s:%d: %s", path, line, key);
        if (!strcmp(key, "kappa_t")) {
            opt_range(opt, val, 0, 1e3, &s->kt_lo, &s->kt_hi);
            if (!(s->kt_hi > 0))
                die_usage("%s = '%s' is not accepted: extinction must be > 0", opt, val);
            s->have_kt = 1;
        } else if (!strcmp(key, "kappa_s")) {
            opt_range(opt, val, 0, 1e3, &s->ks_lo, &s->ks_hi);
            s->have_ks = 1;
        } else if (!strcmp(key, "distance")) {
            opt_range(opt, val, 0, 1e9, &s->d_lo, &s->d_hi);
            if (!(s->d_hi > 0))
                die_usage("%s = '%s' is not accepted: the largest distance must be > 0", opt, val);
            s->have_d = 1;
        } else if (!strcmp(key, "g")) {
            opt_range(opt, val, -0.99, 0.99, &s->g_lo, &s->g_hi);
            s->have_g = 1;
        } else if (!strcmp(key, "phase")) {
            snprintf(s->phase, sizeof s->phase, "%s", val);
        } else if (!strcmp(key, "airlight")) {
            s->airlight = yesno(path, line, key, val);
        } else if (!strcmp(key, "diffuse")) {
            s->diffuse = yesno(path, line, key, val);
        } else if (!strcmp(key, "half")) {
            s->half = yesno(path, line, key, val);
        } else if (!strcmp(key, "orders_max")) {
            s->orders_max = opt_long(opt, val, 1, 512);
        } else if (!strcmp(key, "tol")) {
            s->tol = opt_double(opt, val, 1e-7, 0, 0.5, 0);
        } else if (!strcmp(key, "phong")) {
            for (char *tok = strtok(val, " ,"); tok; tok = strtok(NULL, " ,")) {
                if (s->nphong == sizeof s->phong / sizeof s->phong[0])
                    die_usage("%s: at most 16 Phong exponents", opt);
                s->phong[s->nphong++] = (int)opt_long(opt, tok, 2, 10000);
            }
        } else
            die_usage("%s:%d: unknown key '%s': accepted are kappa_t, kappa_s, distance, g, phase, airlight, "
                      "diffuse, phong, tol, half, orders_max", path, line, key);
    }
    fclose(f);
    if (!s->have_kt || !s->have_d)
        die_usage("%s: kappa_t and distance are required", path);
    if (s->have_g == !!s->phase[0])
        die_usage("%s: give exactly one of g (a value or range: Legendre tables) and phase (fixed phase)", path);
    if (s->have_ks && s->ks_hi > s->kt_hi)
        die_usage("%s: kappa_s (%g) must not exceed kappa_t (%g)", path, s->ks_hi, s->kt_hi);
    if (!s->airlight && !s->diffuse && s->nphong == 0)
        die_usage("%s: the scene needs no tables (airlight = no, diffuse = no, no phong)", path);
}

int cmd_scene(int argc, char **argv)
{
    static const struct option opts[] = {{"output", required_argument, 0, 'o'},
                                         {"threads", required_argument, 0, 'j'},
                                         {"help", no_argument, 0, 'h'},
                                         {0, 0, 0, 0}};
    const char *dir = "nbt-tables";
    unsigned threads = 0;
    int c;
    optind = 1;
    while ((c = getopt_long(argc, argv, "o:h", opts, NULL)) != -1) {
        if (c == 'o')
            dir = optarg;
        else if (c == 'j')
            threads = (unsigned)opt_long("--threads", optarg, 1, 64);
        else if (c == 'h') {
            puts("Usage: nbt-gen scene FILE [-o DIR] [--threads T]\n"
                 "Builds only the tables the scene in FILE needs (format: doc/scene-format.md),\n"
                 "each with the smallest size and Legendre order count meeting its tol.");
            return 0;
        } else
            die_usage("see 'nbt-gen scene --help'");
    }
    if (optind != argc - 1)
        die_usage("scene: expected exactly one scene file");
    scene_t s;
    parse_scene(argv[optind], &s);
    nbt_phase *ph = NULL;
    if (s.phase[0]) {
        char err[256];
        if (nbt_phase_parse(s.phase, &ph, err, sizeof err) != NBT_OK)
            die_usage("%s: phase: %s", argv[optind], err);
    }
    double xmax = s.kt_hi * s.d_hi;
    if (xmax > 1e6)
        die_usage("%s: kappa_t * distance = %g exceeds 1e6 (the medium is opaque long before)", argv[optind], xmax);
    check_writable_dir("-o", dir);
    size_t nterms = 1;
    double ttol = s.tol;
    if (!ph && legendre_budget(fmax(fabs(s.g_lo), fabs(s.g_hi)), xmax, s.tol, (size_t)s.orders_max, &nterms, &ttol) != 0) {
        if (nterms > 512)
            die("%s: |g| up to %g needs more than 512 Legendre orders at tol %g: use a fixed phase "
                "(phase = hg:g=...) or a larger tol", argv[optind], fmax(fabs(s.g_lo), fabs(s.g_hi)), s.tol);
        die("%s: |g| up to %g needs %zu Legendre orders at tol %g, more than orders_max = %ld%s: use a fixed phase "
            "(phase = hg:g=...), a larger tol or a smaller |g|%s", argv[optind], fmax(fabs(s.g_lo), fabs(s.g_hi)),
            nterms, s.tol, s.orders_max,
            s.orders_max == NBT_SCENE_GL_ORDERS ? " (libnbt-gl's shaders take at most 16: 4 packs of 4)" : "",
            s.orders_max == NBT_SCENE_GL_ORDERS ? ", or raise orders_max (up to 512) for tables used off the GPU" : "");
    }
    if (mkdir(dir, 0777) != 0 && errno != EEXIST)
        die("cannot create the directory '%s': %s", dir, strerror(errno));
    tableset_spec specs[18];
    size_t ns = 0;
    tableset_spec base = {NBT_TABLE_H, 0, nterms, ph, xmax, ttol, {0, 0}, s.half, threads};
    if (s.airlight)
        specs[ns++] = base;
    base.kind = NBT_TABLE_J;
    if (s.diffuse) {
        base.n = 1;
        specs[ns++] = base;
    }
    for (size_t i = 0; i < s.nphong; i++) {
        base.n = s.phong[i];
        specs[ns++] = base;
    }
    int rc = 0;
    double t0 = now_seconds();
    for (size_t i = 0; i < ns && rc == 0; i++) {
        tableset ts;
        rc = tableset_build(&specs[i], &ts);
        if (rc == 0) {
            char stem[1024], name[128];
            tableset_stem(&specs[i], name, sizeof name);
            snprintf(stem, sizeof stem, "%s/%s", dir, name);
            rc = tableset_write(&ts, stem, 1);
            tableset_free(&ts);
        }
    }
    if (rc == 0)
        fprintf(stderr, "nbt-gen: scene: %zu table set(s) in %s/ in %.3f s\n", ns, dir, now_seconds() - t0);
    nbt_phase_free(ph);
    return rc;
}
