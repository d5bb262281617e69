/* libnbt/beam_fit.c: the fitted narrow-beam kernel model (core + diffuse
 * part, parameters as smooth functions of depth, albedo and phase width),
 * its coefficient file and the compiled-in default (beam_fit_data.h,
 * written by doc/kernelmodel.sh from nbt-fit model's output). */
#include <config.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <nbt/beam.h>
#include "internal.h"

static const nbt_beam_fit default_fit = {
#include "beam_fit_data.h"
};

const nbt_beam_fit *nbt_beam_fit_default(void)
{
    return &default_fit;
}

static double clampr(const nbt_beam_fit *f, int i, double v)
{
    if (!f || !(f->range[i][0] < f->range[i][1]))
        return v;
    return v < f->range[i][0] ? f->range[i][0] : v > f->range[i][1] ? f->range[i][1] : v;
}

void nbt_beam_fit_terms(const nbt_beam_fit *f, double tau, double albedo, double B, double *t)
{
    tau = clampr(f, 0, tau);
    albedo = clampr(f, 1, albedo);
    B = clampr(f, 2, B);
    double x = log(tau) - 1.15, w = albedo - 0.5, v = log(B / 0.05);
    double m[NBT_BEAM_FIT_TERMS] = {1, x, w, v, x * x, x * w, x * v, w * w, w * v, v * v,
                                    x * x * x, x * x * w, x * x * v, x * w * w, x * w * v, x * v * v};
    memcpy(t, m, sizeof m);
}

nbt_status nbt_beam_fit_params(const nbt_beam_fit *f, int infinite, double tau, double albedo, double B, double *p)
{
    int g = infinite ? 1 : 0;
    if (!f || !f->have[g])
        NBT_FAIL(NBT_EDOM, "beam fit: the model holds no coefficients for this geometry");
    if (!(tau > 0) || !isfinite(tau) || !(albedo >= 0 && albedo <= 1) || !(B > 0) || !isfinite(B))
        NBT_FAIL(NBT_EDOM, "beam fit: needs tau > 0 finite, albedo in [0, 1], B > 0 finite");
    double t[NBT_BEAM_FIT_TERMS], P[NBT_BEAM_FIT_PARTS] = {0};
    nbt_beam_fit_terms(f, tau, albedo, B, t);
    for (int i = 0; i < NBT_BEAM_FIT_PARTS; i++)
        for (int k = 0; k < NBT_BEAM_FIT_TERMS; k++)
            P[i] += f->c[g][i][k] * t[k];
    nbt_beam_fit_from_P(P, tau, albedo, B, p);
    return NBT_OK;
}

void nbt_beam_fit_from_P(const double *P, double tau, double albedo, double B, double *p)
{
    /* T: the scattered light that goes on forward in small-angle theory;
     * L: the single-scattering width */
    double T = exp(-(1 - albedo) * tau) * -expm1(-albedo * tau), L = tau * sqrt(2 * B);
    p[1] = L * exp(P[1]);
    p[0] = T * exp(P[0]) / (sqrt(2 * NBT_PI) * p[1]);
    p[2] = T * exp(P[2]);
    p[3] = L * exp(P[3]);
    p[4] = p[3] * exp(P[4]);
}

double nbt_beam_fit_eval(const double *p, double rh)
{
    if (!(rh > 0))
        return 0;
    double core = p[1] > 0 ? p[0] / rh * 0.5 * erfc(rh / (sqrt(2.0) * p[1])) : 0;
    double s = p[3], h = p[4], q = sqrt(rh * rh + h * h);
    /* q - h without cancellation when rh << h */
    return core + p[2] * exp(-rh * rh / ((q + h) * s)) / (2 * NBT_PI * s * (h + s));
}

nbt_status nbt_beam_fit_psi(const nbt_beam_fit *f, int infinite, const nbt_beam_medium *m, double z, double r,
                            double *psi)
{
    if (!(r >= 0) || !isfinite(r))
        NBT_FAIL(NBT_EDOM, "beam fit: needs r >= 0, finite");
    double zeta, lam;
    nbt_status st = nbt_beam_fit_equivalent(m, z, &zeta, &lam);
    if (st != NBT_OK)
        return st;
    if (!(zeta > 0)) { /* no medium crossed: no scattered light */
        *psi = 0;
        return NBT_OK;
    }
    double B = 0, p[NBT_BEAM_FIT_PARTS];
    for (size_t i = 0; i < m->nlobes; i++)
        B += m->w[i] * m->B[i];
    if ((st = nbt_beam_fit_params(f, infinite, m->sigma_t * zeta, m->albedo, B, p)) != NBT_OK)
        return st;
    *psi = m->sigma_t * m->sigma_t / (lam * lam) * nbt_beam_fit_eval(p, m->sigma_t * r / lam);
    return NBT_OK;
}

nbt_status nbt_beam_fit_equivalent(const nbt_beam_medium *m, double z, double *zeta, double *lambda)
{
    nbt_status st = nbt_beam_check(m);
    if (st != NBT_OK)
        return st;
    if (!(z > 0) || !isfinite(z))
        NBT_FAIL(NBT_EDOM, "beam fit: needs z > 0, finite");
    *zeta = z;
    *lambda = 1;
    if (m->nlayers == 0 && !m->rho_fn)
        return NBT_OK;
    *zeta = nbt_beam_zeta(m, z);
    if (!(*zeta > 0))
        return NBT_OK;
    /* the homogeneous medium at density 1 and depth zeta has the layered M0 (eq. 25 = eq. 28);
     * the widths scale by the ratio of the layered and homogeneous second moments, those of the
     * small-angle random walk: measured against layered photon counts they do better than eq. 29 / 26
     * (doc/fit.md: 2-11% against 3-15% relative RMS) */
    nbt_beam_medium h = *m;
    h.nlayers = 0;
    h.z = h.rho = NULL;
    h.rho_fn = NULL;
    double M0l, M2l, M0h, M2h;
    if ((st = nbt_beam_moments(m, NBT_BEAM_SMALLANGLE, z, &M0l, &M2l, NULL)) != NBT_OK && st != NBT_ETOL)
        return st;
    if ((st = nbt_beam_moments(&h, NBT_BEAM_SMALLANGLE, *zeta, &M0h, &M2h, NULL)) != NBT_OK && st != NBT_ETOL)
        return st;
    if (M2l > 0 && M2h > 0 && isfinite(M2l / M2h))
        *lambda = sqrt(M2l / M2h);
    return NBT_OK;
}

static const char *const geo_name[2] = {"half", "infinite"};

nbt_status nbt_beam_fit_read(const char *path, nbt_beam_fit *f, char *err, size_t errlen)
{
    FILE *fp = fopen(path, "r");
    if (!fp) {
        int e = errno;
        snprintf(err, errlen, "beam model '%s' cannot be opened: %s", path, strerror(e));
        return nbt__io_status(e);
    }
    memset(f, 0, sizeof *f);
    char line[4096];
    int ln = 0, got[2] = {0};
    nbt_status st = NBT_OK;
    while (st == NBT_OK && fgets(line, sizeof line, fp)) {
        ln++;
        char *p = line + strspn(line, " \t");
        if (*p == '#' || *p == '\n' || *p == '\0')
            continue;
        char gname[16], pname[8];
        int off = 0, g = -1, i = -1;
        if (!strncmp(p, "range ", 6)) {
            double lo, hi;
            char extra;
            int ri = -1;
            if (sscanf(p, "range %15s %lf %lf %c", gname, &lo, &hi, &extra) == 3)
                ri = !strcmp(gname, "tau") ? 0 : !strcmp(gname, "albedo") ? 1 : !strcmp(gname, "B") ? 2 : -1;
            if (ri < 0 || !isfinite(lo) || !isfinite(hi) || !(lo <= hi)) {
                snprintf(err, errlen, "beam model '%s' line %d: expected 'range tau|albedo|B LO HI' with LO <= HI",
                         path, ln);
                st = NBT_EFORMAT;
                break;
            }
            f->range[ri][0] = lo;
            f->range[ri][1] = hi;
            continue;
        }
        if (sscanf(p, "%15s %7s %n", gname, pname, &off) == 2) {
            g = !strcmp(gname, "half") ? 0 : !strcmp(gname, "infinite") ? 1 : -1;
            if (pname[0] == 'P' && pname[1] >= '0' && pname[1] < '0' + NBT_BEAM_FIT_PARTS && pname[2] == '\0')
                i = pname[1] - '0';
        }
        if (g < 0 || i < 0) {
            snprintf(err, errlen, "beam model '%s' line %d: expected 'half|infinite P0..P4' and %d numbers", path, ln,
                     NBT_BEAM_FIT_TERMS);
            st = NBT_EFORMAT;
            break;
        }
        p += off;
        for (int k = 0; k < NBT_BEAM_FIT_TERMS && st == NBT_OK; k++) {
            char *end;
            f->c[g][i][k] = strtod(p, &end);
            if (end == p || !isfinite(f->c[g][i][k])) {
                snprintf(err, errlen, "beam model '%s' line %d: expected %d finite numbers after '%s %s'", path, ln,
                         NBT_BEAM_FIT_TERMS, gname, pname);
                st = NBT_EFORMAT;
            }
            p = end;
        }
        if (st == NBT_OK && strspn(p, " \t\r\n") != strlen(p)) {
            snprintf(err, errlen, "beam model '%s' line %d: more than %d numbers", path, ln, NBT_BEAM_FIT_TERMS);
            st = NBT_EFORMAT;
        }
        got[g] |= 1 << i;
    }
    if (st == NBT_OK && ferror(fp)) {
        snprintf(err, errlen, "beam model '%s' cannot be read: %s", path, strerror(errno));
        st = NBT_EIO;
    }
    fclose(fp);
    for (int g = 0; g < 2 && st == NBT_OK; g++) {
        int all = (1 << NBT_BEAM_FIT_PARTS) - 1;
        if (got[g] != 0 && got[g] != all) {
            snprintf(err, errlen, "beam model '%s': geometry '%s' needs all of P0 .. P%d", path, geo_name[g],
                     NBT_BEAM_FIT_PARTS - 1);
            st = NBT_EFORMAT;
        }
        f->have[g] = got[g] == all;
    }
    if (st == NBT_OK && !f->have[0] && !f->have[1]) {
        snprintf(err, errlen, "beam model '%s': no coefficients (lines 'half P0 ...' or 'infinite P0 ...')", path);
        st = NBT_EFORMAT;
    }
    return st;
}

nbt_status nbt_beam_fit_fprint(FILE *fp, const nbt_beam_fit *f, const char *comment)
{
    fprintf(fp, "# nbt beam kernel model (see nbt/beam.h, doc/fit.md)\n");
    if (comment)
        fputs(comment, fp);
    static const char *const rn[3] = {"tau", "albedo", "B"};
    for (int i = 0; i < 3; i++)
        if (f->range[i][0] < f->range[i][1])
            fprintf(fp, "range %s %.17g %.17g\n", rn[i], f->range[i][0], f->range[i][1]);
    for (int g = 0; g < 2; g++)
        for (int i = 0; f->have[g] && i < NBT_BEAM_FIT_PARTS; i++) {
            fprintf(fp, "%s P%d", geo_name[g], i);
            for (int k = 0; k < NBT_BEAM_FIT_TERMS; k++)
                fprintf(fp, " %.17g", f->c[g][i][k]);
            fputc('\n', fp);
        }
    if (ferror(fp))
        NBT_FAIL(NBT_EIO, "beam fit: writing the model failed");
    return NBT_OK;
}
