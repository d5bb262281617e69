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
#include "scene.h"

int cmd_scene(int argc, char **argv)
{
    static const struct option opts[] = {{"output", required_argument, 0, 'o'},
                                         {"threads", required_argument, 0, 'j'},
                                         {"quiet", no_argument, 0, 'q'},
                                         {"help", no_argument, 0, 'h'},
                                         {0, 0, 0, 0}};
    const char *dir = "nbt-tables";
    unsigned threads = 0;
    int c, quiet = 0;
    optind = 1;
    while ((c = getopt_long(argc, argv, "o:h", opts, NULL)) != -1) {
        if (c == 'o')
            dir = optarg;
        else if (c == 'q')
            quiet = 1;
        else if (c == 'j')
            threads = (unsigned)opt_long("--threads", optarg, 1, 64);
        else if (c == 'h') {
            puts("Usage: nbt-gen scene FILE [-o DIR] [--threads T] [--quiet]\n"
                 "Builds only the tables the scene in FILE needs (format: doc/scene-format.md),\n"
                 "each with the smallest size and Legendre order count meeting its tol.\n"
                 "Progress on stderr: each set's start with its predicted time, its end with the\n"
                 "actual time, one warning line when the plan predicts more than 60 s; --quiet: none.");
            return 0;
        } else
            die_usage("see 'nbt-gen scene --help'");
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
    if (mkdir(dir, 0777) != 0 && errno != EEXIST)
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
        rc = tableset_write(&ts, stem, 1);
        nbt_tableset_free(&ts);
    }
    if (rc == 0 && !quiet)
        fprintf(stderr, "nbt-gen: scene: %zu table set(s) in %s/ in %.3f s\n", ns, dir, now_seconds() - t0);
    nbt_plan_free(plan);
    nbt_phase_free(ph);
    return rc;
}
