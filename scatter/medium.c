/* scatter/medium.c: nbt-scatter's medium options (a value or an R,G,B
 * triple; a phase per channel) and the screen kernel they build. */
#include <config.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "../gen/cli.h"
#include "scatter.h"

int parse_triple(const char *opt, const char *arg, double lo, int lo_open, double hi, double v[3])
{
    char buf[256];
    if (strlen(arg) >= sizeof buf)
        die_usage("%s: '%.40s...' is too long", opt, arg);
    strcpy(buf, arg);
    int n = 0;
    for (char *p = buf, *q;; p = q + 1) {
        q = strchr(p, ',');
        if (q)
            *q = '\0';
        if (n == 3)
            die_usage("%s: '%s' is not accepted: expected one value or three (R,G,B)", opt, arg);
        if (parse_double(p, lo, lo_open, hi, 0, &v[n]) != 0)
            die_usage("%s: '%s' is not accepted: expected one value or R,G,B, each in %c%g, %g]", opt, arg,
                      lo_open ? '(' : '[', lo, hi);
        n++;
        if (!q)
            break;
    }
    if (n == 2)
        die_usage("%s: '%s' is not accepted: expected one value or three (R,G,B), not two", opt, arg);
    if (n == 1)
        v[1] = v[2] = v[0];
    return n;
}

void medium_add_phase(scatter_medium *m, const char *spec)
{
    if (m->nphase == 3)
        die_usage("--phase: give one phase, or three (R, G, B in that order)");
    char err[512];
    if (nbt_phase_parse(spec, &m->phase[m->nphase], err, sizeof err) != NBT_OK)
        die_usage("--phase: %s", err);
    m->nphase++;
}

int medium_channels(const scatter_medium *m)
{
    return m->nst == 3 || m->nalb == 3 || m->nphase == 3 ? 3 : 1;
}

void medium_finish(scatter_medium *m)
{
    if (m->nphase == 2)
        die_usage("--phase: give one phase, or three (R, G, B in that order), not two");
}

const nbt_phase *medium_phase(const scatter_medium *m, int c)
{
    return m->nphase == 3 ? m->phase[c] : m->phase[0];
}

/* one channel's kernel */
static nbt_screen_kernel *channel_kernel(const scatter_medium *m, int c, nbt_skernel_kind kind,
                                         const nbt_kernel_correction *corr)
{
    if (m->nphase) {
        const nbt_screen_model *model = m->model ? m->model : nbt_screen_model_default();
        char err[512];
        if (kind != NBT_SKERNEL_FIRST && model &&
            nbt_screen_model_covers(model, medium_phase(m, c), m->geometry, err, sizeof err) != NBT_OK)
            die_usage("--phase: %s: --kernel first for single scattering alone, or --model FILE", err);
        nbt_screen_kernel *k =
            nbt_screen_kernel_phase(kind, m->sigma_t[c], m->albedo[c], medium_phase(m, c), m->geometry, m->model);
        if (!k)
            die_usage("--kernel %s for --phase %s: see the line above (a phase outside the shipped model: "
                      "--kernel first, or fit one with 'nbt-fit screenmodel --phase SPEC' and give it with --model)",
                      nbt_skernel_name(kind), nbt_phase_name(medium_phase(m, c)));
        return k;
    }
    nbt_beam_medium bm = nbt_beam_homogeneous(m->sigma_t[c], m->albedo[c], m->B);
    nbt_screen_kernel *k = nbt_screen_kernel_alloc(kind, &bm, corr);
    if (!k)
        die("the kernel could not be set up");
    return k;
}

nbt_screen_kernel *medium_kernel(const scatter_medium *m, nbt_skernel_kind kind, const nbt_kernel_correction *corr)
{
    if (medium_channels(m) == 1)
        return channel_kernel(m, 0, kind, corr);
    nbt_screen_kernel *r = channel_kernel(m, 0, kind, corr), *g = channel_kernel(m, 1, kind, corr),
                      *b = channel_kernel(m, 2, kind, corr);
    nbt_screen_kernel *k = nbt_screen_kernel_rgb(r, g, b);
    if (!k)
        die("the RGB kernel could not be set up");
    return k;
}

void medium_free(scatter_medium *m)
{
    for (int c = 0; c < 3; c++)
        nbt_phase_free(m->phase[c]);
    nbt_screen_model_free(m->owned_model);
}

/* "%.17g" or "R,G,B" */
void medium_triple_str(const double v[3], int n, char *buf, size_t len)
{
    if (n == 3)
        snprintf(buf, len, "%.17g,%.17g,%.17g", v[0], v[1], v[2]);
    else
        snprintf(buf, len, "%.17g", v[0]);
}
