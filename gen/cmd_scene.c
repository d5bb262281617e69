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
    char perr[1024];
    if (scene_parse(argv[optind], &s, perr, sizeof perr))
        die_usage("%s", perr);
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
