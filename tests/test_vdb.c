/* tests/test_vdb.c: the OpenVDB shim from C. Grids written with
 * nbt_vdb_write / nbt_vdb_write_test and read back with nbt_vdb_read:
 * exact round trips (distinct values, tiles expanded), an active box that
 * does not start at index 0 (zero borders; an index offset with negative
 * coordinates) moving the origin by whole voxels, grid selection by name
 * and by default, and every refusal: missing, directory and non-VDB files,
 * missing grid names (listed), non-float grids, non-uniform and rotated
 * transforms, empty grids, max_voxels, negative and NaN voxels. */
#define _POSIX_C_SOURCE 200809L
#include <dirent.h>
#include <errno.h>
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include "../scatter/vdb_shim.h"
#include "testutil.h"

static char dir[64];

static void path_of(char *buf, size_t n, const char *name)
{
    snprintf(buf, n, "%s/%s", dir, name);
}

/* a grid with distinct, non-zero, high-entropy values */
static nbt_vdb_grid make_grid(size_t nx, size_t ny, size_t nz, double o0, double o1, double o2, double voxel)
{
    nbt_vdb_grid g = {nx, ny, nz, {o0, o1, o2}, voxel, malloc(nx * ny * nz * sizeof(float))};
    for (size_t q = 0; q < nx * ny * nz; q++)
        g.data[q] = (float)(0.2385 + 1.3 * (double)q + 0.5 * t_uniform());
    return g;
}

static int one_line(const char *s)
{
    return s[0] != 0 && strchr(s, '\n') == NULL;
}

/* got == want voxel by voxel (got's voxel (i,j,k) is want's (i+di, j+dj, k+dk)) */
static size_t mismatches(const nbt_vdb_grid *got, const nbt_vdb_grid *want, size_t di, size_t dj, size_t dk)
{
    size_t bad = 0;
    for (size_t k = 0; k < got->nz; k++)
        for (size_t j = 0; j < got->ny; j++)
            for (size_t i = 0; i < got->nx; i++)
                if (got->data[(k * got->ny + j) * got->nx + i] !=
                    want->data[((k + dk) * want->ny + j + dj) * want->nx + i + di])
                    bad++;
    return bad;
}

static void test_roundtrip(void)
{
    char p[128], err[512];
    path_of(p, sizeof p, "rt.vdb");
    nbt_vdb_grid g = make_grid(7, 5, 3, -1.2385, 2.71, 0.3, 0.137), r;
    int s = nbt_vdb_write(p, "density", &g, err, sizeof err);
    t_true(s == 0, "write 7x5x3 (%s)", s ? err : "ok");
    s = nbt_vdb_read(p, "density", 105, &r, err, sizeof err);
    t_true(s == 0, "read 7x5x3 with max_voxels = 105 (%s)", s ? err : "ok");
    if (s == 0) {
        t_true(r.nx == 7 && r.ny == 5 && r.nz == 3, "round trip: size %zux%zux%zu", r.nx, r.ny, r.nz);
        for (int a = 0; a < 3; a++)
            t_abs(r.origin[a], g.origin[a], 0, "round trip: origin[%d] exact", a);
        t_abs(r.voxel, g.voxel, 0, "round trip: voxel exact");
        size_t bad = mismatches(&r, &g, 0, 0, 0);
        t_true(bad == 0, "round trip: all 105 values exact (%zu differ)", bad);
    }
    nbt_vdb_grid_free(&r);
    t_true(r.data == NULL && r.nx == 0, "nbt_vdb_grid_free zeroes the grid");
    nbt_vdb_grid_free(&r); /* twice: harmless */
    nbt_vdb_grid_free(NULL);

    /* max_voxels one short of the box */
    s = nbt_vdb_read(p, NULL, 104, &r, err, sizeof err);
    t_true(s == -1 && r.data == NULL && strstr(err, "7 x 5 x 3 = 105") && strstr(err, "104") && one_line(err),
           "max_voxels = 104 refused: %s", err);
    unlink(p);
    free(g.data);
}

/* a 24x16x16 grid whose first 16x16x16 block is constant: stored as tiles, read back voxel by voxel */
static void test_tiles(void)
{
    char p[128], err[512];
    path_of(p, sizeof p, "tiles.vdb");
    nbt_vdb_grid g = make_grid(24, 16, 16, 0.5, -3.25, 8, 0.25), r;
    for (size_t k = 0; k < 16; k++)
        for (size_t j = 0; j < 16; j++)
            for (size_t i = 0; i < 16; i++)
                g.data[(k * 16 + j) * 24 + i] = 0.7311f;
    int s = nbt_vdb_write(p, "density", &g, err, sizeof err);
    t_true(s == 0, "write tiled grid (%s)", s ? err : "ok");
    long tiles = nbt_vdb_test_active_tiles(p, "density");
    t_true(tiles == 8, "the constant 16^3 block is stored as 8 active tiles (%ld)", tiles);
    s = nbt_vdb_read(p, NULL, (size_t)-1, &r, err, sizeof err);
    t_true(s == 0 && r.nx == 24 && r.ny == 16 && r.nz == 16, "read tiled grid (%s)", s ? err : "ok");
    if (s == 0) {
        size_t bad = mismatches(&r, &g, 0, 0, 0);
        t_true(bad == 0, "tiles expanded: all values exact (%zu differ)", bad);
    }
    nbt_vdb_grid_free(&r);
    unlink(p);
    free(g.data);
}

/* zero borders: the active box starts at (3,1,5) and the origin moves by whole voxels */
static void test_zero_border(void)
{
    char p[128], err[512];
    path_of(p, sizeof p, "border.vdb");
    nbt_vdb_grid g = make_grid(10, 6, 9, 4.1, -0.37, 12.5, 0.0921), r;
    for (size_t k = 0; k < 9; k++)
        for (size_t j = 0; j < 6; j++)
            for (size_t i = 0; i < 10; i++)
                if (i < 3 || j < 1 || k < 5 || i == 9)
                    g.data[(k * 6 + j) * 10 + i] = 0;
    int s = nbt_vdb_write(p, "density", &g, err, sizeof err);
    t_true(s == 0, "write zero-bordered grid (%s)", s ? err : "ok");
    s = nbt_vdb_read(p, NULL, 1000, &r, err, sizeof err);
    t_true(s == 0, "read zero-bordered grid (%s)", s ? err : "ok");
    if (s == 0) {
        t_true(r.nx == 6 && r.ny == 5 && r.nz == 4, "zero border: box 6x5x4 (%zux%zux%zu)", r.nx, r.ny, r.nz);
        const int lo[3] = {3, 1, 5};
        for (int a = 0; a < 3; a++)
            t_rel(r.origin[a], g.origin[a] + lo[a] * g.voxel, 4 * DBL_EPSILON, "zero border: origin[%d] moved by %d voxels",
                  a, lo[a]);
        t_abs(r.voxel, g.voxel, 0, "zero border: voxel exact");
        if (r.nx == 6 && r.ny == 5 && r.nz == 4) {
            size_t bad = mismatches(&r, &g, 3, 1, 5);
            t_true(bad == 0, "zero border: values exact (%zu differ)", bad);
        }
    }
    nbt_vdb_grid_free(&r);
    unlink(p);
    free(g.data);
}

/* the grid stored from index (3,-2,5): the read origin is still the centre of its first voxel */
static void test_index_offset(void)
{
    char p[128], err[512];
    path_of(p, sizeof p, "offset.vdb");
    /* binary-exact origin and voxel: the origin must come back bit for bit */
    nbt_vdb_grid g = make_grid(5, 4, 6, 1.5, -0.75, 2.25, 0.125), r;
    nbt_vdb_test_grid e = {"density", &g, {3, -2, 5}, 0, NBT_VDB_TEST_UNIFORM};
    int s = nbt_vdb_write_test(p, &e, 1, err, sizeof err);
    t_true(s == 0, "write at index (3,-2,5) (%s)", s ? err : "ok");
    s = nbt_vdb_read(p, NULL, 120, &r, err, sizeof err);
    t_true(s == 0 && r.nx == 5 && r.ny == 4 && r.nz == 6, "read offset grid (%s)", s ? err : "ok");
    if (s == 0) {
        for (int a = 0; a < 3; a++)
            t_abs(r.origin[a], g.origin[a], 0, "index offset, exact numbers: origin[%d] exact", a);
        t_abs(r.voxel, 0.125, 0, "index offset: voxel exact");
        size_t bad = mismatches(&r, &g, 0, 0, 0);
        t_true(bad == 0, "index offset: values exact (%zu differ)", bad);
    }
    nbt_vdb_grid_free(&r);
    free(g.data);

    /* any numbers: the origin to rounding (s*i0 + (o - s*i0)) */
    g = make_grid(3, 2, 2, -7.31, 0.0042, 1e3 / 3, 0.0137);
    s = nbt_vdb_write_test(p, &e, 1, err, sizeof err);
    s = s ? s : nbt_vdb_read(p, NULL, 12, &r, err, sizeof err);
    t_true(s == 0, "offset grid, inexact numbers (%s)", s ? err : "ok");
    if (s == 0)
        for (int a = 0; a < 3; a++)
            t_rel(r.origin[a], g.origin[a], 8 * DBL_EPSILON, "index offset, inexact numbers: origin[%d]", a);
    nbt_vdb_grid_free(&r);
    unlink(p);
    free(g.data);
}

static void test_names(void)
{
    char p[128], err[512];
    nbt_vdb_grid a = make_grid(4, 3, 2, 0, 0, 0, 0.5), b = make_grid(2, 3, 4, 1, 1, 1, 0.25), r;
    b.data[0] = 42.5f;

    path_of(p, sizeof p, "two.vdb");
    nbt_vdb_test_grid two[2] = {{"temperature", &a, {0, 0, 0}, 0, NBT_VDB_TEST_UNIFORM},
                                {"density", &b, {0, 0, 0}, 0, NBT_VDB_TEST_UNIFORM}};
    int s = nbt_vdb_write_test(p, two, 2, err, sizeof err);
    t_true(s == 0, "write two float grids (%s)", s ? err : "ok");
    s = nbt_vdb_read(p, NULL, 100, &r, err, sizeof err);
    t_true(s == 0 && r.nx == 2 && r.ny == 3 && r.nz == 4 && r.data[0] == 42.5f, "NULL name picks \"density\" (%s)",
           s ? err : "ok");
    nbt_vdb_grid_free(&r);
    s = nbt_vdb_read(p, "temperature", 100, &r, err, sizeof err);
    t_true(s == 0 && r.nx == 4 && r.ny == 3 && r.nz == 2 && mismatches(&r, &a, 0, 0, 0) == 0,
           "\"temperature\" by name (%s)", s ? err : "ok");
    nbt_vdb_grid_free(&r);
    s = nbt_vdb_read(p, "smoke", 100, &r, err, sizeof err);
    t_true(s == -1 && r.data == NULL && strstr(err, "\"smoke\"") && strstr(err, "temperature (float)") &&
               strstr(err, "density (float)") && one_line(err),
           "missing name refused, grids listed: %s", err);
    unlink(p);

    /* no "density": the only float grid is picked; a double grid is listed but refused */
    path_of(p, sizeof p, "mixed.vdb");
    nbt_vdb_test_grid mixed[2] = {{"heat", &a, {0, 0, 0}, 1, NBT_VDB_TEST_UNIFORM},
                                  {"smoke", &b, {0, 0, 0}, 0, NBT_VDB_TEST_UNIFORM}};
    s = nbt_vdb_write_test(p, mixed, 2, err, sizeof err);
    t_true(s == 0, "write a double and a float grid (%s)", s ? err : "ok");
    s = nbt_vdb_read(p, NULL, 100, &r, err, sizeof err);
    t_true(s == 0 && r.nx == 2 && r.data[0] == 42.5f, "no \"density\": NULL picks the only float grid (%s)",
           s ? err : "ok");
    nbt_vdb_grid_free(&r);
    s = nbt_vdb_read(p, "heat", 100, &r, err, sizeof err);
    t_true(s == -1 && r.data == NULL && strstr(err, "\"heat\"") && strstr(err, "double") && strstr(err, "not float") &&
               one_line(err),
           "double grid refused: %s", err);
    unlink(p);

    /* no "density" and two float grids: ambiguous */
    path_of(p, sizeof p, "ambiguous.vdb");
    nbt_vdb_test_grid amb[2] = {{"smoke", &a, {0, 0, 0}, 0, NBT_VDB_TEST_UNIFORM},
                                {"fog", &b, {0, 0, 0}, 0, NBT_VDB_TEST_UNIFORM}};
    s = nbt_vdb_write_test(p, amb, 2, err, sizeof err);
    s = s ? s : nbt_vdb_read(p, NULL, 100, &r, err, sizeof err);
    t_true(s == -1 && strstr(err, "2 float grids") && strstr(err, "smoke (float)") && strstr(err, "fog (float)") &&
               one_line(err),
           "two float grids, none \"density\": refused: %s", err);
    unlink(p);

    /* a file with no grids at all */
    path_of(p, sizeof p, "nogrids.vdb");
    s = nbt_vdb_write_test(p, NULL, 0, err, sizeof err);
    s = s ? s : nbt_vdb_read(p, NULL, 100, &r, err, sizeof err);
    t_true(s == -1 && strstr(err, "no grids") && one_line(err), "file without grids refused: %s", err);
    unlink(p);
    free(a.data);
    free(b.data);
}

static void test_refusals(void)
{
    char p[128], err[512];
    nbt_vdb_grid g = make_grid(4, 5, 3, 0.1, 0.2, 0.3, 0.3), r;

    path_of(p, sizeof p, "missing.vdb");
    int s = nbt_vdb_read(p, NULL, 100, &r, err, sizeof err);
    t_true(s == -1 && r.data == NULL && strstr(err, strerror(ENOENT)) && strstr(err, "missing.vdb") && one_line(err),
           "missing file refused: %s", err);
    s = nbt_vdb_read(dir, NULL, 100, &r, err, sizeof err);
    t_true(s == -1 && strstr(err, strerror(EISDIR)) && one_line(err), "directory refused: %s", err);

    path_of(p, sizeof p, "text.vdb");
    FILE *f = fopen(p, "w");
    fputs("not a VDB file\n", f);
    fclose(f);
    s = nbt_vdb_read(p, NULL, 100, &r, err, sizeof err);
    t_true(s == -1 && r.data == NULL && strstr(err, "text.vdb") && one_line(err), "non-VDB file refused: %s", err);
    unlink(p);

    path_of(p, sizeof p, "neg.vdb");
    g.data[(1 * 5 + 3) * 4 + 2] = -0.5f; /* voxel (2,3,1) */
    s = nbt_vdb_write(p, "density", &g, err, sizeof err);
    s = s ? s : nbt_vdb_read(p, NULL, 100, &r, err, sizeof err);
    t_true(s == -1 && r.data == NULL && strstr(err, "(2,3,1)") && strstr(err, "-0.5") && one_line(err),
           "negative voxel refused: %s", err);
    g.data[(1 * 5 + 3) * 4 + 2] = 1;
    g.data[(2 * 5 + 0) * 4 + 3] = NAN; /* voxel (3,0,2) */
    s = nbt_vdb_write(p, "density", &g, err, sizeof err);
    s = s ? s : nbt_vdb_read(p, NULL, 100, &r, err, sizeof err);
    t_true(s == -1 && strstr(err, "(3,0,2)") && strstr(err, "nan") && one_line(err), "NaN voxel refused: %s", err);
    g.data[(2 * 5 + 0) * 4 + 3] = 2;
    unlink(p);

    path_of(p, sizeof p, "xf.vdb");
    nbt_vdb_test_grid e = {"density", &g, {0, 0, 0}, 0, NBT_VDB_TEST_NONUNIFORM};
    s = nbt_vdb_write_test(p, &e, 1, err, sizeof err);
    s = s ? s : nbt_vdb_read(p, NULL, 100, &r, err, sizeof err);
    t_true(s == -1 && r.data == NULL && strstr(err, "non-uniform") && one_line(err),
           "non-uniform transform refused: %s", err);
    e.transform = NBT_VDB_TEST_ROTATED;
    s = nbt_vdb_write_test(p, &e, 1, err, sizeof err);
    s = s ? s : nbt_vdb_read(p, NULL, 100, &r, err, sizeof err);
    t_true(s == -1 && strstr(err, "rotated") && one_line(err), "rotated transform refused: %s", err);
    e.transform = NBT_VDB_TEST_UNIFORM; /* the same grid, uniform: accepted (the refusals above are the transform's) */
    s = nbt_vdb_write_test(p, &e, 1, err, sizeof err);
    s = s ? s : nbt_vdb_read(p, NULL, 100, &r, err, sizeof err);
    t_true(s == 0, "control: the same grid with a uniform transform reads (%s)", s ? err : "ok");
    nbt_vdb_grid_free(&r);
    unlink(p);

    path_of(p, sizeof p, "empty.vdb");
    for (size_t q = 0; q < 60; q++)
        g.data[q] = 0;
    s = nbt_vdb_write(p, "density", &g, err, sizeof err);
    s = s ? s : nbt_vdb_read(p, NULL, 100, &r, err, sizeof err);
    t_true(s == -1 && r.data == NULL && strstr(err, "empty") && one_line(err), "all-zero (empty) grid refused: %s",
           err);
    unlink(p);

    /* the writer's own checks */
    g.voxel = -0.3;
    s = nbt_vdb_write(p, "density", &g, err, sizeof err);
    t_true(s == -1 && access(p, F_OK) != 0 && one_line(err), "write: negative voxel size refused: %s", err);
    free(g.data);
}

static int count_entries(const char *d)
{
    DIR *dp = opendir(d);
    int n = 0;
    if (!dp)
        return -1;
    for (struct dirent *e; (e = readdir(dp));)
        if (strcmp(e->d_name, ".") && strcmp(e->d_name, ".."))
            n++;
    closedir(dp);
    return n;
}

int main(void)
{
    snprintf(dir, sizeof dir, "/tmp/nbt-test-vdbXXXXXX");
    if (!mkdtemp(dir)) {
        perror("mkdtemp");
        return 1;
    }
    test_roundtrip();
    test_tiles();
    test_zero_border();
    test_index_offset();
    test_names();
    test_refusals();
    int left = count_entries(dir);
    t_true(left == 0, "temporary directory empty at the end (%d entries)", left);
    rmdir(dir);
    return t_done();
}
