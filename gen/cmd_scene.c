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
#include "outputs.h"
#include "scene.h"

/* The scene's sets as g-sliced tables (basis slices): H, J^1, J^n at the
 * scene's tol, written to DIR/H_hg_slices.exr, J1_hg_slices.exr, ... All
 * built before any is written. */
static int scene_slices(const nbt_scene *s, const char *dir, unsigned threads, int quiet, int allow_miss)
{
    nbt_gslice_request rq[2 + NBT_SCENE_MAX_PHONG];
    size_t n = 0;
    double xmax = s->kappa_t[1] * s->distance[1];
    if (s->airlight)
        rq[n++] = (nbt_gslice_request){NBT_TABLE_H, 0, xmax, {s->g[0], s->g[1]}, s->tol, {0, 0, 0}, s->half};
    if (s->diffuse)
        rq[n++] = (nbt_gslice_request){NBT_TABLE_J, 1, xmax, {s->g[0], s->g[1]}, s->tol, {0, 0, 0}, s->half};
    for (size_t i = 0; i < s->nphong; i++)
        rq[n++] = (nbt_gslice_request){NBT_TABLE_J, s->phong[i], xmax, {s->g[0], s->g[1]}, s->tol, {0, 0, 0}, s->half};
    nbt_table *t[2 + NBT_SCENE_MAX_PHONG] = {0};
    char err[512];
    double secs[2 + NBT_SCENE_MAX_PHONG];
    progress prog;
    progress_init(&prog, "scene", quiet);
    /* one set: the J builds share G's quadrature (it depends on neither n nor theta) */
    if (nbt_gslice_build_set(rq, n, threads, t, secs, err, sizeof err) != NBT_OK)
        die("%s", err);
    for (size_t i = 0; i < n; i++)
        progress_note(&prog, "set %zu/%zu: g-sliced %s%s %zux%zux%zu in %.2f s", i + 1, n,
                      nbt_table_kind_name(rq[i].kind), rq[i].kind == NBT_TABLE_J ? "^n" : "", t[i]->axis[0].n,
                      t[i]->axis[1].n, t[i]->axis[2].n, secs[i]);
    /* every set checked before anything is written */
    int miss = 0;
    for (size_t i = 0; i < n; i++) {
        char name[64];
        snprintf(name, sizeof name, "scene: set %zu/%zu", i + 1, n);
        miss |= gslice_tol_check(t[i], name, s->tol, allow_miss);
    }
    if (miss) {
        for (size_t i = 0; i < n; i++)
            nbt_table_free(t[i]);
        return 1;
    }
    if (mkdir(dir, 0777) == 0)
        outputs_dir(dir); /* removed again if the run fails or is interrupted */
    else if (errno != EEXIST)
        die("cannot create the directory '%s': %s", dir, strerror(errno));
    int rc = 0;
    for (size_t i = 0; i < n; i++) {
        char stem[1024];
        if (rq[i].kind == NBT_TABLE_H)
            snprintf(stem, sizeof stem, "%s/H_hg_slices", dir);
        else
            snprintf(stem, sizeof stem, "%s/J%d_hg_slices", dir, rq[i].n);
        nbt_tableset ts = {{t[i]}, 1, t[i]->max_abs[0], gslice_lookup_err(t[i]), 0};
        if (rc == 0)
            rc = tableset_write(&ts, stem, 1, &prog);
        nbt_table_free(t[i]);
    }
    if (rc == 0 && !quiet)
        fprintf(stderr, "nbt-gen: scene: %zu g-sliced table(s) in %s/ in %.3f s\n", n, dir, now_seconds() - prog.t0);
    return rc;
}

int cmd_scene(int argc, char **argv)
{
    static const struct option opts[] = {{"output", required_argument, 0, 'o'},
                                         {"threads", required_argument, 0, 'j'},
                                         {"quiet", no_argument, 0, 'q'},
                                         {"allow-tol-miss", no_argument, 0, 'A'},
                                         {"help", no_argument, 0, 'h'},
                                         {0, 0, 0, 0}};
    const char *dir = "nbt-tables";
    unsigned threads = 0;
    int c, quiet = 0, allow_miss = 0;
    optind = 1;
    while ((c = getopt_long(argc, argv, ":o:h", opts, NULL)) != -1) {
        if (c == 'o')
            dir = optarg;
        else if (c == 'q')
            quiet = 1;
        else if (c == 'A')
            allow_miss = 1;
        else if (c == 'j')
            threads = (unsigned)opt_long("--threads", optarg, 0, 64);
        else if (c == 'h') {
            puts("Usage: nbt-gen scene FILE [-o DIR] [--threads T] [--quiet] [--allow-tol-miss]\n"
                 "Builds only the tables the scene in FILE needs (format: doc/scene-format.md),\n"
                 "each with the smallest size and Legendre order count meeting its tol; with a g\n"
                 "range, Legendre packs or g-sliced tables by the scene's basis key (default auto:\n"
                 "the smaller predicted build time, slices only when 1.5x faster; printed with the\n"
                 "reason). A g-sliced table whose recorded lookup error misses tol is an error\n"
                 "(exit 1, nothing written) unless --allow-tol-miss.\n"
                 "Progress on stderr: each set's start with its predicted time, its end with the\n"
                 "actual time, one warning line when the plan predicts more than 60 s; --quiet: none.");
            return 0;
        } else
            die_bad_option(c, argv, "nbt-gen scene");
    }
    if (optind != argc - 1)
        die_usage("scene: expected exactly one scene file");
    nbt_scene s;
    nbt_phase *ph = NULL;
    char perr[1024];
    if (scene_parse(argv[optind], &s, &ph, perr, sizeof perr))
        die_usage("%s", perr);
    check_writable_dir("-o", dir);
    char err[1024];
    if (s.have_g && s.basis != NBT_BASIS_LEGENDRE) {
        nbt_basis_choice ch;
        if (nbt_scene_basis(&s, threads, &ch, err, sizeof err) != NBT_OK)
            die("%s: %s", argv[optind], err);
        printf("# basis %s\n", ch.reason);
        if (ch.basis == NBT_BASIS_SLICES)
            return scene_slices(&s, dir, threads, quiet, allow_miss);
    }
    nbt_plan *plan = NULL;
    progress prog;
    progress_init(&prog, "scene", quiet);
    double t0 = prog.t0;
    nbt_status st = nbt_plan_scene(&s, threads, &plan, NULL, err, sizeof err);
    if (st != NBT_OK) {
        nbt_phase_free(ph);
        die("%s: %s", argv[optind], err);
    }
    if (s.have_g) {
        nbt_plan_legendre leg = nbt_plan_legendre_budget(plan);
        print_legendre(&leg, fmax(fabs(s.g[0]), fabs(s.g[1])));
    }
    if (mkdir(dir, 0777) == 0)
        outputs_dir(dir); /* removed again if the run fails or is interrupted */
    else if (errno != EEXIST)
        die("cannot create the directory '%s': %s", dir, strerror(errno));
    int rc = 0;
    size_t ns = nbt_plan_count(plan);
    double left = plan_announce(plan, &prog);
    for (size_t i = 0; i < ns && rc == 0; i++) {
        nbt_tableset ts;
        const nbt_plan_set *ps = nbt_plan_get(plan, i);
        if (build_set(plan, i, &prog, &left, &ts, err, sizeof err) != NBT_OK) {
            fprintf(stderr, "nbt-gen: %s\n", err);
            rc = 1;
            break;
        }
        char stem[1024], name[128];
        nbt_plan_stem(&ps->req, name, sizeof name);
        snprintf(stem, sizeof stem, "%s/%s", dir, name);
        rc = tableset_write(&ts, stem, 1, &prog);
        nbt_tableset_free(&ts);
    }
    if (rc == 0 && !quiet)
        fprintf(stderr, "nbt-gen: scene: %zu table set(s) in %s/ in %.3f s\n", ns, dir, now_seconds() - t0);
    nbt_plan_free(plan);
    nbt_phase_free(ph);
    return rc;
}
