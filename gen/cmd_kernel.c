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
#include "outputs.h"
#include "preview.h"

typedef struct {
    const nbt_kernel_correction *corr;
    double B;
    const nbt_beam_fit *fit; /* --model fitted: channels P0..P3 (part 0) or P4 (part 1) */
    int infinite, part;
} kctx;

/* the fitted model's log-parameters P_i at (tau, albedo): smooth in ln tau, so they interpolate well */
/* the files written through the registry of outputs.h: removed if the run
 * fails later or is interrupted */
static int write_exr(const nbt_table *t, const char *path)
{
    outputs_file *r = outputs_add(path);
    if (!r || outputs_begin(r))
        return 1;
    int ok = nbt_table_write_exr(t, path, NBT_EXR_ZIP) == NBT_OK;
    outputs_end(r, ok);
    return !ok;
}

static int write_png(const nbt_table *t, const char *path)
{
    outputs_file *r = outputs_add(path);
    if (!r || outputs_begin(r))
        return 1;
    int ok = preview_write_png(t, path) == 0;
    outputs_end(r, ok);
    return !ok;
}

static int fitted_fn(double tau, double albedo, double *out, void *vp)
{
    const kctx *c = vp;
    int g = c->infinite ? 1 : 0;
    double t[NBT_BEAM_FIT_TERMS];
    nbt_beam_fit_terms(c->fit, tau, albedo, c->B, t);
    for (int i = 0; i < (c->part ? 1 : 4); i++) {
        int q = c->part ? 4 : i;
        out[i] = 0;
        for (int k = 0; k < NBT_BEAM_FIT_TERMS; k++)
            out[i] += c->fit->c[g][q][k] * t[k];
    }
    return 0;
}

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

static int write_fitted(const char *out, const nbt_beam_fit *fit, int infinite, double B, double t0, double t1,
                        double a0, double a1, size_t W, size_t H)
{
    size_t n = strlen(out);
    char p4[1024];
    snprintf(p4, sizeof p4, "%.*s-P4.exr", (int)(n - 4), out);
    check_writable("-o", p4);
    nbt_axis ax0 = {t0, t1, NBT_AXIS_LOG1P, 1000, W}, ax1 = {a0, a1, NBT_AXIS_LINEAR, 0, H};
    nbt_table *t[2] = {nbt_table_alloc(NBT_TABLE_KERNEL, &ax0, &ax1, 4), nbt_table_alloc(NBT_TABLE_KERNEL, &ax0, &ax1, 1)};
    if (!t[0] || !t[1])
        die("out of memory");
    double t0s = now_seconds();
    for (int part = 0; part < 2; part++) {
        for (int c = 0; c < 4; c++)
            t[part]->k[c] = -1;
        snprintf(t[part]->phase, sizeof t[part]->phase, "gauss:B=%g fitted %s %s", B, infinite ? "infinite" : "half",
                 part ? "P4" : "P0-P3");
        kctx c = {NULL, B, fit, infinite, part};
        if (nbt_table_tabulate(t[part], fitted_fn, &c, 1) != NBT_OK)
            die("tabulating the kernel model failed");
    }
    /* both files or neither */
    if (write_exr(t[0], out) != 0)
        die("cannot write '%s'", out);
    if (write_exr(t[1], p4) != 0) {
        remove(out);
        die("cannot write '%s'", p4);
    }
    printf("%s + %s %zux%zu tau:log1p(c=1000)[%g,%g] albedo:linear[%g,%g]  max interp err P0..P4", out, p4, W, H, t0, t1,
           a0, a1);
    for (int c = 0; c < 4; c++)
        printf(" %.2e", t[0]->max_err[c]);
    printf(" %.2e (absolute, in ln of the parameters)\n", t[1]->max_err[0]);
    fprintf(stderr, "nbt-gen: kernel model tables in %.3f s\n", now_seconds() - t0s);
    nbt_table_free(t[0]);
    nbt_table_free(t[1]);
    return 0;
}

int cmd_kernel(int argc, char **argv)
{
    static const struct option opts[] = {
        {"B", required_argument, 0, 'B'},      {"correction", required_argument, 0, 'c'},
        {"tau", required_argument, 0, 't'},    {"albedo", required_argument, 0, 'a'},
        {"size", required_argument, 0, 's'},   {"output", required_argument, 0, 'o'},
        {"model", required_argument, 0, 'm'},  {"infinite", no_argument, 0, 'I'},
        {"beam-model", required_argument, 0, 'M'},
        {"help", no_argument, 0, 'h'},         {0, 0, 0, 0}};
    int fitted = 0, infinite = 0;
    const char *fit_path = NULL;
    double B = 0, t0 = 0.01, t1 = 20, a0 = 0.01, a1 = 1;
    size_t W = 129, H = 65;
    const char *corr_path = NULL, *out = "kernel.exr", *tau_arg = NULL, *alb_arg = NULL;
    int o;
    optind = 1;
    while ((o = getopt_long_only(argc, argv, ":o:h", opts, NULL)) != -1) {
        switch (o) {
        case 'B': B = opt_double("--B", optarg, 0, 1, 1e3, 0); break;
        case 'c': corr_path = optarg; break;
        case 't': opt_range("--tau", optarg, 1e-6, 1e4, &t0, &t1); tau_arg = optarg; break;
        case 'a': opt_range("--albedo", optarg, 1e-6, 1, &a0, &a1); alb_arg = optarg; break;
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
        case 'm':
            if (!strcmp(optarg, "fitted"))
                fitted = 1;
            else if (strcmp(optarg, "moments"))
                die_usage("--model: '%s' is not accepted: moments (the moment kernel, optionally --correction) or "
                          "fitted (nbt_beam_fit)", optarg);
            break;
        case 'I': infinite = 1; break;
        case 'M': fit_path = optarg; break;
        case 'h':
            puts("Usage: nbt-gen kernel --B B [--correction CORR.txt | --model fitted [--infinite] [--beam-model FILE]]\n"
                 "                      [--tau LO:HI] [--albedo LO:HI]\n"
                 "                      [--size WxH] [-o FILE.exr]\n\n"
                 "Tabulates the narrow-beam kernel Psi = alpha/r G(r/beta) of a homogeneous medium with the\n"
                 "Gaussian phase of spread B (dtheta^2 = 4B): channel R = alpha/sigma_t, G = beta sigma_t over\n"
                 "tau = sigma_t z (log1p axis, default 0.01:20) and albedo (default 0.01:1), from the moments\n"
                 "(eq. 25/26) or, with --correction, corrected as nbt-fit kernel --correction fitted it.\n"
                 "Default size 129x65; the measured interpolation error is recorded and printed.\n"
                 "--model fitted [--infinite] [--beam-model FILE]: the fitted kernel model instead (nbt/beam.h\n"
                 "nbt_beam_fit; libnbt's default or FILE from nbt-fit model): FILE.exr gets its log-parameters\n"
                 "P0..P3 (RGBA) and FILE-P4.exr P4 (R) over the same axes; a shader turns them into\n"
                 "(a, b, M, s, h) with nbt_beam_fit_from_P (shaders/nbt_beam.glsl). --infinite: a source inside\n"
                 "the medium; default a beam entering a half-space from vacuum.\n"
                 "  -o FILE.exr    output (default ./kernel.exr), with a PNG preview FILE.png beside it");
            return 0;
        default: die_bad_option(o, argv, "nbt-gen kernel");
        }
    }
    if (optind < argc)
        die_usage("kernel: unexpected argument '%s'", argv[optind]);
    if (!(B > 0))
        die_usage("kernel: --B B (the phase function's spread, > 0) is required");
    if (!(t1 > t0))
        die_usage("--tau: '%s' is not accepted: the table's axis needs a range LO:HI with LO < HI", tau_arg);
    if (!(a1 > a0))
        die_usage("--albedo: '%s' is not accepted: the table's axis needs a range LO:HI with LO < HI", alb_arg);
    size_t n = strlen(out);
    if (n < 5 || strcmp(out + n - 4, ".exr"))
        die_usage("-o: '%s' is not accepted: the output must end in .exr", out);
    nbt_kernel_correction corr;
    char err[512];
    if (corr_path && nbt_kernel_correction_read(corr_path, &corr, err, sizeof err) != NBT_OK)
        die_usage("--correction: %s", err);
    if (!fitted && (infinite || fit_path))
        die_usage("kernel: --infinite and --beam-model apply to --model fitted only");
    if (fitted && corr_path)
        die_usage("kernel: --correction applies to the moment kernel, not to --model fitted");
    nbt_beam_fit own;
    const nbt_beam_fit *fit = nbt_beam_fit_default();
    if (fit_path) {
        if (nbt_beam_fit_read(fit_path, &own, err, sizeof err) != NBT_OK)
            die_usage("--beam-model: %s", err);
        fit = &own;
    }
    if (fitted && !fit->have[infinite])
        die_usage("--beam-model: '%s' holds no coefficients for the %s geometry", fit_path ? fit_path : "default",
                  infinite ? "infinite" : "half-space");
    check_writable("-o", out);
    if (fitted)
        return write_fitted(out, fit, infinite, B, t0, t1, a0, a1, W, H);
    nbt_axis ax0 = {t0, t1, NBT_AXIS_LOG1P, 1000, W}, ax1 = {a0, a1, NBT_AXIS_LINEAR, 0, H};
    nbt_table *t = nbt_table_alloc(NBT_TABLE_KERNEL, &ax0, &ax1, 2);
    if (!t)
        die("out of memory");
    t->k[0] = t->k[1] = -1;
    snprintf(t->phase, sizeof t->phase, "gauss:B=%g%s", B, corr_path ? " corrected" : " moments");
    kctx c = {corr_path ? &corr : NULL, B, NULL, 0, 0};
    double t0s = now_seconds();
    if (nbt_table_tabulate(t, kernel_fn, &c, 1) != NBT_OK)
        die("tabulating the kernel failed");
    char png[1024];
    snprintf(png, sizeof png, "%.*s.png", (int)(n - 4), out);
    if (write_exr(t, out) != 0)
        die("cannot write '%s'", out);
    if (write_png(t, png) != 0)
        die("cannot write '%s'", png);
    printf("%s %zux%zu tau:log1p(c=1000)[%g,%g] albedo:linear[%g,%g]  max interp err alpha %.2e (rel %.2e) "
           "beta %.2e (rel %.2e)\n", out, W, H, t0, t1, a0, a1, t->max_err[0], t->max_err[0] / t->max_abs[0],
           t->max_err[1], t->max_err[1] / t->max_abs[1]);
    fprintf(stderr, "nbt-gen: kernel table in %.3f s\n", now_seconds() - t0s);
    nbt_table_free(t);
    return 0;
}
