/* gen/cmd_kernel.c: "nbt-gen kernel": the narrow-beam kernel as a table a
 * shader reads: alpha/sigma_t and beta sigma_t over optical depth and
 * albedo, for one phase width, optionally corrected (nbt-fit kernel
 * --correction). Psi(z, r) = alpha/r G(r/beta) with alpha = sigma_t R,
 * beta = G/sigma_t read at (tau = sigma_t z, albedo). */
#include <config.h>
#include <getopt.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "cli.h"
#include "commands.h"
#include "preview.h"

typedef struct {
    const nbt_kernel_correction *corr;
    double B;
} kctx;

static int kernel_fn(double tau, double albedo, double *out, void *vp)
{
    const kctx *c = vp;
    nbt_beam_medium m = nbt_beam_homogeneous(1.0, albedo, c->B); /* sigma_t = 1: z = tau */
    double a, b;
    if (nbt_kernel_corrected(c->corr, &m, tau, &a, &b) != NBT_OK)
        return 1;
    out[0] = a;
    out[1] = b;
    return 0;
}

int cmd_kernel(int argc, char **argv)
{
    static const struct option opts[] = {
        {"B", required_argument, 0, 'B'},      {"correction", required_argument, 0, 'c'},
        {"tau", required_argument, 0, 't'},    {"albedo", required_argument, 0, 'a'},
        {"size", required_argument, 0, 's'},   {"output", required_argument, 0, 'o'},
        {"help", no_argument, 0, 'h'},         {0, 0, 0, 0}};
    double B = 0, t0 = 0.01, t1 = 20, a0 = 0.01, a1 = 1;
    size_t W = 129, H = 65;
    const char *corr_path = NULL, *out = "kernel.exr";
    int o;
    optind = 1;
    while ((o = getopt_long_only(argc, argv, "o:h", opts, NULL)) != -1) {
        switch (o) {
        case 'B': B = opt_double("--B", optarg, 0, 1, 1e3, 0); break;
        case 'c': corr_path = optarg; break;
        case 't': opt_range("--tau", optarg, 1e-6, 1e4, &t0, &t1); break;
        case 'a': opt_range("--albedo", optarg, 1e-6, 1, &a0, &a1); break;
        case 's': {
            char extra;
            long w, h;
            if (sscanf(optarg, "%ldx%ld%c", &w, &h, &extra) != 2 || w < 2 || h < 2 || w > 4096 || h > 4096)
                die_usage("--size: '%s' is not accepted: expected WxH with 2 <= W, H <= 4096", optarg);
            W = (size_t)w;
            H = (size_t)h;
            break;
        }
        case 'o': out = optarg; break;
        case 'h':
            puts("Usage: nbt-gen kernel --B B [--correction CORR.txt] [--tau LO:HI] [--albedo LO:HI]\n"
                 "                      [--size WxH] [-o FILE.exr]\n\n"
                 "Tabulates the narrow-beam kernel Psi = alpha/r G(r/beta) of a homogeneous medium with the\n"
                 "Gaussian phase of spread B (dtheta^2 = 4B): channel R = alpha/sigma_t, G = beta sigma_t over\n"
                 "tau = sigma_t z (log1p axis, default 0.01:20) and albedo (default 0.01:1), from the moments\n"
                 "(eq. 25/26) or, with --correction, corrected as nbt-fit kernel --correction fitted it.\n"
                 "Default size 129x65; the measured interpolation error is recorded and printed.\n"
                 "  -o FILE.exr    output (default ./kernel.exr), with a PNG preview FILE.png beside it");
            return 0;
        default: die_usage("see 'nbt-gen kernel --help'");
        }
    }
    if (optind < argc)
        die_usage("kernel: unexpected argument '%s'", argv[optind]);
    if (!(B > 0))
        die_usage("kernel: --B B (the phase function's spread, > 0) is required");
    if (!(t1 > t0) || !(a1 > a0))
        die_usage("kernel: --tau and --albedo need LO < HI");
    size_t n = strlen(out);
    if (n < 5 || strcmp(out + n - 4, ".exr"))
        die_usage("-o: '%s' is not accepted: the output must end in .exr", out);
    nbt_kernel_correction corr;
    char err[512];
    if (corr_path && nbt_kernel_correction_read(corr_path, &corr, err, sizeof err) != NBT_OK)
        die_usage("--correction: %s", err);
    check_writable("-o", out);
    nbt_axis ax0 = {t0, t1, NBT_AXIS_LOG1P, 1000, W}, ax1 = {a0, a1, NBT_AXIS_LINEAR, 0, H};
    nbt_table *t = nbt_table_alloc(NBT_TABLE_KERNEL, &ax0, &ax1, 2);
    if (!t)
        die("out of memory");
    t->k[0] = t->k[1] = -1;
    snprintf(t->phase, sizeof t->phase, "gauss:B=%g%s", B, corr_path ? " corrected" : " moments");
    kctx c = {corr_path ? &corr : NULL, B};
    double t0s = now_seconds();
    if (nbt_table_tabulate(t, kernel_fn, &c, 1) != NBT_OK)
        die("tabulating the kernel failed");
    char png[1024];
    snprintf(png, sizeof png, "%.*s.png", (int)(n - 4), out);
    if (nbt_table_write_exr(t, out, NBT_EXR_ZIP) != NBT_OK)
        die("cannot write '%s'", out);
    if (preview_write_png(t, png) != 0)
        die("cannot write '%s'", png);
    printf("%s %zux%zu tau:log1p(c=1000)[%g,%g] albedo:linear[%g,%g]  max interp err alpha %.2e (rel %.2e) "
           "beta %.2e (rel %.2e)\n", out, W, H, t0, t1, a0, a1, t->max_err[0], t->max_err[0] / t->max_abs[0],
           t->max_err[1], t->max_err[1] / t->max_abs[1]);
    fprintf(stderr, "nbt-gen: kernel table in %.3f s\n", now_seconds() - t0s);
    nbt_table_free(t);
    return 0;
}
