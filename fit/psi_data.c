/* fit/psi_data.c: reading photon-counting data for the fits. */
#include <config.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <nbt/nbt.h>
#include "psi_data.h"

void psi_data_free(psi_data *d)
{
    free(d->z);
    free(d->lo);
    free(d->hi);
    free(d->psi);
    free(d->se);
    memset(d, 0, sizeof *d);
}

static int alloc(psi_data *d, size_t np, size_t nb)
{
    d->nplanes = np;
    d->nbins = nb;
    d->z = calloc(np, sizeof(double));
    d->lo = calloc(np * nb, sizeof(double));
    d->hi = calloc(np * nb, sizeof(double));
    d->psi = calloc(np * nb, sizeof(double));
    d->se = calloc(np * nb, sizeof(double));
    return d->z && d->lo && d->hi && d->psi && d->se;
}

static int read_exr(const char *path, psi_data *d, char *err, size_t errlen)
{
    nbt_table *t;
    if (nbt_table_read_exr(path, &t, err, errlen) != NBT_OK)
        return 1;
    if (t->kind != NBT_TABLE_PSI || t->nch != 2) {
        snprintf(err, errlen, "%s: not a PSI table (nbt-fit mc -o FILE.exr)", path);
        nbt_table_free(t);
        return 1;
    }
    size_t nb = t->axis[0].n, np = t->axis[1].n;
    if (!alloc(d, np, nb)) {
        nbt_table_free(t);
        snprintf(err, errlen, "out of memory");
        return 1;
    }
    double h = (t->axis[0].hi - t->axis[0].lo) / (double)(nb - 1); /* bin width in r/z */
    for (size_t j = 0; j < np; j++) {
        d->z[j] = nbt_axis_node(&t->axis[1], j);
        for (size_t k = 0; k < nb; k++) {
            double c = nbt_axis_node(&t->axis[0], k);
            d->lo[j * nb + k] = (c - 0.5 * h) * d->z[j];
            d->hi[j * nb + k] = (c + 0.5 * h) * d->z[j];
            d->psi[j * nb + k] = t->data[(j * nb + k) * 2];
            d->se[j * nb + k] = t->data[(j * nb + k) * 2 + 1];
        }
    }
    /* "mc albedo=A sigma_t=S phase=gauss:B=B ..." */
    const char *a = strstr(t->phase, "albedo="), *s = strstr(t->phase, "sigma_t="), *b = strstr(t->phase, "gauss:B=");
    if (a)
        d->albedo = atof(a + 7);
    if (s)
        d->sigma_t = atof(s + 8);
    if (b)
        d->B = atof(b + 8);
    d->infinite = strstr(t->phase, " infinite") != NULL;
    nbt_table_free(t);
    return 0;
}

static int read_csv(const char *path, psi_data *d, char *err, size_t errlen)
{
    FILE *f = fopen(path, "r");
    if (!f) {
        snprintf(err, errlen, "%s: cannot open: %s", path, strerror(errno));
        return 1;
    }
    char line[512];
    if (!fgets(line, sizeof line, f) || strncmp(line, "z,r_lo,r_hi,psi,psi_stderr", 26)) {
        fclose(f);
        snprintf(err, errlen, "%s: expected the header z,r_lo,r_hi,psi,psi_stderr", path);
        return 1;
    }
    size_t n = 0, cap = 1024, np = 0;
    double *v = malloc(cap * 5 * sizeof(double));
    int ln = 1, bad = 0;
    while (v && fgets(line, sizeof line, f)) {
        ln++;
        double r[5];
        char extra;
        if (sscanf(line, "%lf,%lf,%lf,%lf,%lf %c", &r[0], &r[1], &r[2], &r[3], &r[4], &extra) != 5 ||
            !isfinite(r[0]) || !isfinite(r[1]) || !isfinite(r[2]) || !isfinite(r[3]) || !isfinite(r[4]) ||
            !(r[0] > 0) || !(r[1] >= 0) || !(r[2] > r[1]) || r[3] < 0 || r[4] < 0) {
            bad = ln;
            break;
        }
        if (n == cap) {
            cap *= 2;
            double *v2 = realloc(v, cap * 5 * sizeof(double));
            if (!v2) {
                free(v);
                v = NULL;
                break;
            }
            v = v2;
        }
        if (n == 0 || r[0] != v[(n - 1) * 5])
            np++;
        memcpy(v + n * 5, r, sizeof r);
        n++;
    }
    fclose(f);
    if (!v) {
        snprintf(err, errlen, "out of memory");
        return 1;
    }
    if (bad || n == 0 || n % np) {
        if (bad) {
            line[strcspn(line, "\r\n")] = '\0'; /* the refused row, quoted */
            snprintf(err, errlen, "%s line %d: '%.60s' is not accepted: expected z > 0, 0 <= r_lo < r_hi, psi >= 0, "
                     "psi_stderr >= 0 (finite)", path, bad, line);
        }
        else if (n == 0)
            snprintf(err, errlen, "%s: no data rows", path);
        else
            snprintf(err, errlen, "%s: every plane must have the same number of bins", path);
        free(v);
        return 1;
    }
    size_t nb = n / np;
    if (!alloc(d, np, nb)) {
        free(v);
        snprintf(err, errlen, "out of memory");
        return 1;
    }
    for (size_t i = 0; i < n; i++) {
        size_t j = i / nb;
        if (v[i * 5] != v[j * nb * 5]) {
            snprintf(err, errlen, "%s: every plane must have the same number of bins", path);
            free(v);
            return 1;
        }
        d->z[j] = v[i * 5];
        d->lo[i] = v[i * 5 + 1];
        d->hi[i] = v[i * 5 + 2];
        d->psi[i] = v[i * 5 + 3];
        d->se[i] = v[i * 5 + 4];
    }
    free(v);
    return 0;
}

int psi_data_read(const char *path, psi_data *d, char *err, size_t errlen)
{
    memset(d, 0, sizeof *d);
    d->albedo = d->sigma_t = d->B = NAN;
    snprintf(d->name, sizeof d->name, "%s", path);
    size_t n = strlen(path);
    int rc = n > 4 && !strcmp(path + n - 4, ".exr") ? read_exr(path, d, err, errlen) : read_csv(path, d, err, errlen);
    if (rc)
        psi_data_free(d);
    return rc;
}

int psi_data_read_medium(const char *path, psi_data *d, double albedo, double sigma_t, double B, char *err,
                         size_t errlen)
{
    if (psi_data_read(path, d, err, errlen))
        return 1;
    if (!isnan(albedo))
        d->albedo = albedo;
    if (!isnan(sigma_t))
        d->sigma_t = sigma_t;
    if (!isnan(B))
        d->B = B;
    if (isnan(d->albedo) || isnan(d->sigma_t) || isnan(d->B)) {
        snprintf(err, errlen, "%s: the medium is unknown: give --albedo, --sigma-t and --B", d->name);
        psi_data_free(d);
        return 1;
    }
    return 0;
}

double psi_floor_se(const psi_data *d, size_t j)
{
    double f = INFINITY;
    for (size_t k = 0; k < d->nbins; k++)
        if (d->se[j * d->nbins + k] > 0)
            f = fmin(f, d->se[j * d->nbins + k]);
    return f;
}

double psi_chi2_term(const psi_data *d, size_t i, double floor, double m)
{
    double se = d->se[i] > 0 ? d->se[i] : floor, r = (m - d->psi[i]) / se;
    return r * r;
}
