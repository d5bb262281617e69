/* gen/cmd_info.c: "nbt-gen info FILE [--at X,Y]": a table's metadata and
 * interpolated values. */
#include <config.h>
#include <getopt.h>
#include <math.h>
#include <stdio.h>
#include <string.h>
#include "cli.h"
#include "commands.h"

int cmd_info(int argc, char **argv)
{
    static const struct option opts[] = {{"at", required_argument, 0, 'a'}, {"help", no_argument, 0, 'h'}, {0, 0, 0, 0}};
    const char *at = NULL;
    int c;
    optind = 1;
    while ((c = getopt_long(argc, argv, ":h", opts, NULL)) != -1) {
        if (c == 'a')
            at = optarg;
        else if (c == 'h') {
            puts("Usage: nbt-gen info FILE.exr [--at X,Y[,G]]\n"
                 "Prints the table's metadata; with --at, the bilinear (GPU-equivalent) values at\n"
                 "physical coordinates X (u or T) and Y (v or theta); on a 3-D (g-sliced) table the\n"
                 "value at X,Y,G as libnbt and the shaders look it up (trilinear, or quadratic in g for\n"
                 "interp2 = 2, cubic for 3; G: the slice axis, e.g. g; default its low end), in the table's\n"
                 "value form.");
            return 0;
        } else
            die_bad_option(c, argv, "nbt-gen info");
    }
    if (optind != argc - 1)
        die_usage("info: expected exactly one table file");
    const char *path = argv[optind];
    double x = 0, y = 0, z = NAN;
    if (at) {
        char extra;
        int got = sscanf(at, "%lf,%lf,%lf%c", &x, &y, &z, &extra);
        if ((got != 2 && got != 3) || !isfinite(x) || !isfinite(y) || (got == 3 && !isfinite(z)))
            die_usage("--at: '%s' is not accepted: expected X,Y or X,Y,G (finite numbers)", at);
    }
    nbt_table *t;
    char err[512];
    nbt_status st = nbt_table_read_exr(path, &t, err, sizeof err);
    if (st != NBT_OK) /* missing, unreadable or not a table: bad input */
        die_usage("%s", err);
    const char *n0 = nbt_table_axis_name(t->kind, 0), *n1 = nbt_table_axis_name(t->kind, 1);
    printf("file        %s\n", path);
    printf("kind        %s\n", nbt_table_kind_name(t->kind));
    if (t->kind == NBT_TABLE_J)
        printf("n           %d\n", t->n);
    for (int a = 0; a < 2; a++) { /* each mapping with its own parameter, as nbt-gen's summary line prints it */
        nbt_axis_map m = t->axis[a].map;
        char cs[40] = "";
        if (axis_map_has_c(m))
            snprintf(cs, sizeof cs, "(c=%.17g)", t->axis[a].c);
        printf("axis%d       %s %s%s [%.17g, %.17g] %zu nodes\n", a, a ? n1 : n0, nbt_axis_map_name(m), cs,
               t->axis[a].lo, t->axis[a].hi, t->axis[a].n);
    }
    if (t->axis[2].n >= 2)
        printf("axis2       %s %s [%.17g, %.17g] %zu slices (3-D: a sampler3D)\n",
               nbt_table_axis_name(t->kind, 2), nbt_axis_map_name(t->axis[2].map), t->axis[2].lo, t->axis[2].hi,
               t->axis[2].n);
    printf("storage     %s\n", t->half ? "half" : "float");
    if (t->form != NBT_FORM_PLAIN || t->axis[2].n >= 2)
        printf("form        %s%s\n", nbt_table_form_name(t->form),
               t->form == NBT_FORM_TAIL ? ": R = log(C W), C the scaled tail integral, W = 1 + s/2 + u s^2/2 "
                                          "(doc/tables.md); errors relative"
               : t->form == NBT_FORM_SUB ? ": values minus S = d(x0) sum_q c_q b_q(x1) (nbt/table.h); the lookup "
                                           "adds S back, errors are the quantity's" : "");
    if (t->form == NBT_FORM_SUB) {
        printf("sub         d(x) = %s, w %.9g\n", t->sub_decay == NBT_SUB_EXP ? "exp(-x)" : "1/(1 + x)", t->sub_w);
        for (size_t ch = 0; ch < t->nch; ch++) {
            printf("sub c[%zu]   ", ch);
            for (int q = 0; q < NBT_SUB_TERMS; q++)
                printf(" %.9g", t->sub_c[ch][q]);
            printf("\n");
        }
    }
    if (t->axis[2].n >= 2)
        printf("g interp    %s\n", t->interp2 == 3   ? "cubic (the cell's two slices and one on either side)"
                                   : t->interp2 == 2 ? "quadratic (three nearest slices)"
                                                     : "linear");
    printf("%s %s\n", t->kind == NBT_TABLE_PSI ? "run        " : "phase      ", t->phase[0] ? t->phase : "legendre");
    int fitted = t->kind == NBT_TABLE_KERNEL && strstr(t->phase, " fitted ") != NULL;
    if (fitted)
        printf("use         the fitted kernel model's log-parameters at (sigma_t z, albedo): nbt_beam_fit_from_P\n");
    else if (t->kind == NBT_TABLE_KERNEL)
        printf("use         Psi(z, r) = alpha/r G(r/beta), alpha = sigma_t R, beta = G/sigma_t at (sigma_t z, albedo)\n");
    static const char *CH = "RGBA";
    for (size_t ch = 0; ch < t->nch; ch++) {
        char what[32];
        if (t->kind == NBT_TABLE_PSI)
            snprintf(what, sizeof what, ch == 0 ? "psi" : "psi_stderr");
        else if (fitted)
            snprintf(what, sizeof what, "P%d", strstr(t->phase, " P4") ? 4 : (int)ch);
        else if (t->kind == NBT_TABLE_KERNEL)
            snprintf(what, sizeof what, ch == 0 ? "alpha/sig_t" : "beta*sig_t");
        else if (t->form == NBT_FORM_TAIL)
            snprintf(what, sizeof what, ch == 0 ? "log(C W)(g)" : "error map");
        else if (t->k[ch] < 0 && t->axis[2].n >= 2)
            snprintf(what, sizeof what, "phase(g)");
        else if (t->k[ch] < 0)
            snprintf(what, sizeof what, "fixed phase");
        else
            snprintf(what, sizeof what, "k=%d", t->k[ch]);
        if (t->kind == NBT_TABLE_PSI)
            printf("channel %c   %-11s max |value| %.6g\n", CH[ch], what, t->max_abs[ch]);
        else
            printf("channel %c   %-11s max |value| %.6g  max interp err %.3e\n", CH[ch], what, t->max_abs[ch],
                   t->max_err[ch]);
    }
    if (t->kind == NBT_TABLE_H || t->kind == NBT_TABLE_J)
        printf("quad tol    %.3g (largest node error estimate %.3g)\n", t->quad_tol, t->quad_err);
    if (at) {
        double v[NBT_TABLE_MAX_CH];
        if (t->axis[2].n >= 2 && !isnan(z)) {
            nbt_table_lookup3(t, x, y, z, v);
            printf("at %s=%.17g %s=%.17g %s=%.17g:", n0, x, n1, y, nbt_table_axis_name(t->kind, 2), z);
            if (z < t->axis[2].lo || z > t->axis[2].hi)
                fprintf(stderr, "nbt-gen: warning: %s = %g lies outside the table; clamped to its edge\n",
                        nbt_table_axis_name(t->kind, 2), z);
        } else {
            nbt_table_lookup(t, x, y, v);
            printf("at %s=%.17g %s=%.17g%s:", n0, x, n1, y, t->axis[2].n >= 2 ? " (slice 0)" : "");
        }
        for (size_t ch = 0; ch < t->nch; ch++)
            printf(" %.9g", v[ch]);
        printf("\n");
        if (x < t->axis[0].lo || x > t->axis[0].hi || y < t->axis[1].lo || y > t->axis[1].hi)
            fprintf(stderr, "nbt-gen: warning: (%g, %g) lies outside the table; values are clamped to its edge\n", x, y);
    }
    nbt_table_free(t);
    return 0;
}
