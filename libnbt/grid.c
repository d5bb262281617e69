/* libnbt/grid.c: dense density grids, trilinear lookup, raw files (nbt/grid.h). */
#include <config.h>
#include <errno.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include <nbt/grid.h>
#include "internal.h"

nbt_grid *nbt_grid_alloc(size_t nx, size_t ny, size_t nz, const double origin[3], double voxel)
{
    if (nx == 0 || ny == 0 || nz == 0 || nx > SIZE_MAX / ny || nx * ny > SIZE_MAX / nz / sizeof(float))
        return NULL;
    nbt_grid *g = calloc(1, sizeof *g);
    if (!g)
        return NULL;
    g->data = calloc(nx * ny * nz, sizeof *g->data);
    if (!g->data) {
        free(g);
        return NULL;
    }
    g->nx = nx, g->ny = ny, g->nz = nz;
    memcpy(g->origin, origin, sizeof g->origin);
    g->voxel = voxel;
    return g;
}

void nbt_grid_free(nbt_grid *g)
{
    if (g)
        free(g->data);
    free(g);
}

nbt_status nbt_grid_check(const nbt_grid *g, char *err, size_t errlen)
{
    if (!g || !g->data) {
        snprintf(err, errlen, "empty grid: no data");
        return NBT_EDOM;
    }
    if (g->nx == 0 || g->ny == 0 || g->nz == 0) {
        snprintf(err, errlen, "empty grid: size %zu x %zu x %zu, each must be >= 1", g->nx, g->ny, g->nz);
        return NBT_EDOM;
    }
    if (!(g->voxel > 0) || !isfinite(g->voxel)) {
        snprintf(err, errlen, "voxel size %g is not accepted: finite and > 0", g->voxel);
        return NBT_EDOM;
    }
    if (!isfinite(g->origin[0]) || !isfinite(g->origin[1]) || !isfinite(g->origin[2])) {
        snprintf(err, errlen, "origin (%g, %g, %g) is not accepted: finite", g->origin[0], g->origin[1], g->origin[2]);
        return NBT_EDOM;
    }
    for (size_t k = 0; k < g->nz; k++)
        for (size_t j = 0; j < g->ny; j++)
            for (size_t i = 0; i < g->nx; i++) {
                float v = g->data[(k * g->ny + j) * g->nx + i];
                if (!(v >= 0) || !isfinite(v)) {
                    snprintf(err, errlen, "density %g at voxel (%zu, %zu, %zu): expected finite and >= 0", v, i, j, k);
                    return NBT_EDOM;
                }
            }
    return NBT_OK;
}

static int little_endian(void)
{
    const uint16_t one = 1;
    return *(const unsigned char *)&one == 1;
}

static void swap4(float *v, size_t n)
{
    for (size_t i = 0; i < n; i++) {
        unsigned char *b = (unsigned char *)&v[i], t;
        t = b[0], b[0] = b[3], b[3] = t;
        t = b[1], b[1] = b[2], b[2] = t;
    }
}

nbt_status nbt_grid_read_raw(const char *path, nbt_grid **out, char *err, size_t errlen)
{
    *out = NULL;
    FILE *f = fopen(path, "rb");
    if (!f) {
        int e = errno;
        snprintf(err, errlen, "%s: cannot open: %s", path, strerror(e));
        return nbt__io_status(e);
    }
    char line[512];
    unsigned long long nx, ny, nz;
    double o[3], vox;
    int ver;
    char extra;
    if (!fgets(line, sizeof line, f) || !strchr(line, '\n') ||
        sscanf(line, "NBTGRID %d %llu %llu %llu %lf %lf %lf %lf %c", &ver, &nx, &ny, &nz, &o[0], &o[1], &o[2], &vox,
               &extra) != 8 ||
        ver != 1) {
        fclose(f);
        snprintf(err, errlen,
                 "%s: not an nbt raw grid (expected a first line 'NBTGRID 1 nx ny nz ox oy oz voxel', then float32 "
                 "little-endian data)",
                 path);
        return NBT_EFORMAT;
    }
    errno = 0;
    nbt_grid *g = nbt_grid_alloc((size_t)nx, (size_t)ny, (size_t)nz, o, vox);
    if (!g) {
        /* NULL for a size that is 0 or overflows (no allocation tried: errno stays 0) or no memory */
        int nomem = errno == ENOMEM;
        fclose(f);
        snprintf(err, errlen, "%s: grid size %llux%llux%llu: %s", path, nx, ny, nz,
                 nomem ? "out of memory" : "a size is 0 or the grid exceeds the address space");
        return nomem ? NBT_ENOMEM : NBT_EFORMAT;
    }
    size_t n = g->nx * g->ny * g->nz, got = fread(g->data, sizeof(float), n, f);
    int more = fgetc(f) != EOF;
    fclose(f);
    if (got != n || more) {
        snprintf(err, errlen, "%s: expected %zu float32 values after the header, found %s", path, n,
                 got != n ? "fewer" : "more");
        nbt_grid_free(g);
        return NBT_EFORMAT;
    }
    if (!little_endian())
        swap4(g->data, n);
    char why[256];
    if (nbt_grid_check(g, why, sizeof why) != NBT_OK) {
        snprintf(err, errlen, "%s: %s", path, why);
        nbt_grid_free(g);
        return NBT_EFORMAT;
    }
    *out = g;
    return NBT_OK;
}

nbt_status nbt_grid_write_raw(const nbt_grid *g, const char *path, char *err, size_t errlen)
{
    size_t len = strlen(path) + 32, n = g->nx * g->ny * g->nz;
    char *tmp = malloc(len);
    if (!tmp) {
        snprintf(err, errlen, "out of memory");
        return NBT_ENOMEM;
    }
    snprintf(tmp, len, "%s.tmp%ld", path, (long)getpid());
    FILE *f = fopen(tmp, "wb");
    if (!f) {
        int e = errno;
        snprintf(err, errlen, "%s: cannot write: %s", path, strerror(e));
        free(tmp);
        return nbt__io_status(e);
    }
    int ok = fprintf(f, "NBTGRID 1 %zu %zu %zu %.17g %.17g %.17g %.17g\n", g->nx, g->ny, g->nz, g->origin[0],
                     g->origin[1], g->origin[2], g->voxel) > 0;
    if (little_endian())
        ok = ok && fwrite(g->data, sizeof(float), n, f) == n;
    else {
        for (size_t i = 0; i < n && ok; i++) {
            float v = g->data[i];
            swap4(&v, 1);
            ok = fwrite(&v, sizeof v, 1, f) == 1;
        }
    }
    int e = ok ? 0 : errno; /* the first failure's reason (ENOMEM: the stream's buffer) */
    if (fclose(f) != 0 && ok)
        ok = 0, e = errno;
    if (ok && rename(tmp, path) != 0)
        ok = 0, e = errno;
    if (!ok) {
        snprintf(err, errlen, "%s: cannot write: %s", path, strerror(e));
        unlink(tmp);
    }
    free(tmp);
    return ok ? NBT_OK : nbt__io_status(e);
}

double nbt_grid_density(const double p[3], void *grid)
{
    const nbt_grid *g = grid;
    const size_t n[3] = {g->nx, g->ny, g->nz};
    size_t i0[3];
    double f[3];
    for (int a = 0; a < 3; a++) {
        double u = (p[a] - g->origin[a]) / g->voxel; /* voxel-centre coordinates */
        if (!(u >= -0.5 && u <= (double)n[a] - 0.5))
            return 0.0;
        /* constant in the half voxels at the border */
        if (u < 0)
            u = 0;
        if (u > (double)n[a] - 1)
            u = (double)n[a] - 1;
        double fl = floor(u);
        i0[a] = (size_t)fl;
        f[a] = u - fl;
        if (i0[a] + 1 >= n[a]) {
            i0[a] = n[a] > 1 ? n[a] - 2 : 0;
            f[a] = n[a] > 1 ? 1.0 : 0.0;
        }
    }
    double v = 0;
    for (int c = 0; c < 8; c++) {
        size_t ix = i0[0] + (c & 1), iy = i0[1] + ((c >> 1) & 1), iz = i0[2] + ((c >> 2) & 1);
        double wgt = ((c & 1) ? f[0] : 1 - f[0]) * (((c >> 1) & 1) ? f[1] : 1 - f[1]) * (((c >> 2) & 1) ? f[2] : 1 - f[2]);
        if (wgt == 0)
            continue;
        if (ix >= n[0] || iy >= n[1] || iz >= n[2])
            continue;
        v += wgt * g->data[(iz * g->ny + iy) * g->nx + ix];
    }
    return v;
}

void nbt_grid_box(const nbt_grid *g, double lo[3], double hi[3])
{
    const size_t n[3] = {g->nx, g->ny, g->nz};
    for (int a = 0; a < 3; a++) {
        lo[a] = g->origin[a] - 0.5 * g->voxel;
        hi[a] = lo[a] + (double)n[a] * g->voxel;
    }
}

double nbt_grid_exit(const nbt_grid *g, const double o[3], const double d[3])
{
    double lo[3], hi[3], t0 = 0, t1 = INFINITY;
    nbt_grid_box(g, lo, hi);
    for (int a = 0; a < 3; a++) {
        if (d[a] == 0) {
            if (o[a] < lo[a] || o[a] > hi[a])
                return 0;
            continue;
        }
        double ta = (lo[a] - o[a]) / d[a], tb = (hi[a] - o[a]) / d[a];
        if (ta > tb) {
            double t = ta;
            ta = tb, tb = t;
        }
        t0 = fmax(t0, ta);
        t1 = fmin(t1, tb);
    }
    return t1 >= t0 && isfinite(t1) ? t1 : 0;
}
