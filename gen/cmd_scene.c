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

/* Parse FILE into an nbt_scene; fixed phase parsed into *ph (caller frees). */
static void parse_scene(const char *path, nbt_scene *s, nbt_phase **ph)
{
    char phase[256] = "";
    long orders_max = NBT_PLAN_GL_ORDERS;
    FILE *f = fopen(path, "r");
    if (!f)
        die_usage("scene: cannot open '%s': %s", path, strerror(errno));
    nbt_scene_init(s);
    int have_kt = 0, have_d = 0;
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
            opt_range(opt, val, 0, 1e3, &s->kappa_t[0], &s->kappa_t[1]);
            if (!(s->kappa_t[1] > 0))
                die_usage("%s = '%s' is not accepted: extinction must be > 0", opt, val);
            have_kt = 1;
        } else if (!strcmp(key, "kappa_s")) {
            opt_range(opt, val, 0, 1e3, &s->kappa_s[0], &s->kappa_s[1]);
        } else if (!strcmp(key, "distance")) {
            opt_range(opt, val, 0, 1e9, &s->distance[0], &s->distance[1]);
            if (!(s->distance[1] > 0))
                die_usage("%s = '%s' is not accepted: the largest distance must be > 0", opt, val);
            have_d = 1;
        } else if (!strcmp(key, "g")) {
            opt_range(opt, val, -0.99, 0.99, &s->g[0], &s->g[1]);
            s->have_g = 1;
        } else if (!strcmp(key, "phase")) {
            snprintf(phase, sizeof phase, "%s", val);
        } else if (!strcmp(key, "airlight")) {
            s->airlight = yesno(path, line, key, val);
        } else if (!strcmp(key, "diffuse")) {
            s->diffuse = yesno(path, line, key, val);
        } else if (!strcmp(key, "half")) {
            s->half = yesno(path, line, key, val);
        } else if (!strcmp(key, "orders_max")) {
            orders_max = opt_long(opt, val, 1, 512);
        } else if (!strcmp(key, "tol")) {
            s->tol = opt_double(opt, val, 1e-7, 0, 0.5, 0);
        } else if (!strcmp(key, "phong")) {
            for (char *tok = strtok(val, " ,"); tok; tok = strtok(NULL, " ,")) {
                if (s->nphong == NBT_SCENE_MAX_PHONG)
                    die_usage("%s: at most 16 Phong exponents", opt);
                s->phong[s->nphong++] = (int)opt_long(opt, tok, 2, 10000);
            }
        } else
            die_usage("%s:%d: unknown key '%s': accepted are kappa_t, kappa_s, distance, g, phase, airlight, "
                      "diffuse, phong, tol, half, orders_max", path, line, key);
    }
    fclose(f);
    s->orders_max = (size_t)orders_max;
    if (!have_kt || !have_d)
        die_usage("%s: kappa_t and distance are required", path);
    *ph = NULL;
    if (phase[0]) {
        char err[256];
        if (nbt_phase_parse(phase, ph, err, sizeof err) != NBT_OK)
            die_usage("%s: phase: %s", path, err);
        s->phase = *ph;
    }
    char err[512];
    if (nbt_scene_check(s, err, sizeof err) != NBT_OK) {
        nbt_phase_free(*ph);
        die_usage("%s: %s", path, err);
    }
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
    nbt_scene s;
    nbt_phase *ph = NULL;
    parse_scene(argv[optind], &s, &ph);
    check_writable_dir("-o", dir);
    char err[1024];
    nbt_plan *plan = NULL;
    double t0 = now_seconds();
    nbt_status st = nbt_plan_scene(&s, threads, &plan, NULL, err, sizeof err);
    if (st != NBT_OK) {
        nbt_phase_free(ph);
        die("%s: %s", argv[optind], err);
    }
    if (s.have_g) {
        nbt_plan_legendre leg = nbt_plan_legendre_budget(plan);
        print_legendre(&leg, fmax(fabs(s.g[0]), fabs(s.g[1])));
    }
    if (mkdir(dir, 0777) != 0 && errno != EEXIST)
        die("cannot create the directory '%s': %s", dir, strerror(errno));
    int rc = 0;
    size_t ns = nbt_plan_count(plan);
    for (size_t i = 0; i < ns && rc == 0; i++) {
        nbt_tableset ts;
        const nbt_plan_set *ps = nbt_plan_get(plan, i);
        if (nbt_plan_execute(plan, i, &ts, err, sizeof err) != NBT_OK) {
            fprintf(stderr, "nbt-gen: %s\n", err);
            rc = 1;
            break;
        }
        char stem[1024], name[128];
        nbt_plan_stem(&ps->req, name, sizeof name);
        snprintf(stem, sizeof stem, "%s/%s", dir, name);
        rc = tableset_write(&ts, stem, 1);
        nbt_tableset_free(&ts);
    }
    if (rc == 0)
        fprintf(stderr, "nbt-gen: scene: %zu table set(s) in %s/ in %.3f s\n", ns, dir, now_seconds() - t0);
    nbt_plan_free(plan);
    nbt_phase_free(ph);
    return rc;
}
