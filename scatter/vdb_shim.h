/* scatter/vdb_shim.h: a small C interface to OpenVDB for nbt-scatter: read a
 * float density grid (smoke, fog) from a .vdb file as a dense array, and (for
 * tests) write one. Nothing is printed; C++ exceptions are caught at the
 * boundary. Fallible calls return 0 on success and -1 on failure, with one
 * line (no trailing newline) in err[0..errlen-1] (err may be NULL).
 *
 * Convention (OpenVDB's, cell-centred): an integer index coordinate (i,j,k)
 * names the CENTRE of a voxel; the grid's transform maps it to world space,
 * world = voxel * (i,j,k) + translation. A voxel covers
 * world +- voxel/2 around its centre. `origin` below is therefore the centre
 * of voxel (0,0,0) of the dense array, not its corner; the corner of the
 * dense box is origin - voxel/2 on each axis.
 *
 * The functions may be called from several threads at once (each on its own
 * grid and file); OpenVDB is initialised once, on first use. */
#ifndef NBT_VDB_SHIM_H
#define NBT_VDB_SHIM_H

#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef struct {
    size_t nx, ny, nz;      /* voxels along x, y, z */
    double origin[3];       /* world position of the CENTRE of voxel (0,0,0) */
    double voxel;           /* edge length of a (cubic) voxel in world units */
    float *data;            /* data[(k*ny + j)*nx + i], malloc'd; free with nbt_vdb_grid_free */
} nbt_vdb_grid;

/* Read the float grid named `name` (NULL: the grid named "density", else the
 * only float grid) from a .vdb file as a dense array over its active-voxel
 * bounding box (the background value outside active voxels; tiles expanded).
 * Dense voxel (0,0,0) is the bounding box's minimum index corner, so
 * out->origin is the world centre of that index voxel (it moves with the
 * box when the active region does not start at index 0).
 * Refuse with one line in err (return -1, *out zeroed): missing/unreadable
 * file (strerror text), no such grid (list the grids found and their
 * types), not a float grid, a non-uniform or rotated/sheared/mirrored/
 * perspective transform (only uniform positive scale + translation accepted,
 * to a relative 1e-9), an empty grid (no active voxels), a dense size above
 * max_voxels, negative or non-finite values (name the voxel), out of memory.
 * 0 on success. */
int nbt_vdb_read(const char *path, const char *name, size_t max_voxels, nbt_vdb_grid *out, char *err, size_t errlen);

/* Free g->data and zero *g (NULL or an already freed grid: nothing). */
void nbt_vdb_grid_free(nbt_vdb_grid *g);

/* Tests: write a dense array as a FloatGrid named `name` with a uniform
 * transform (voxel size, translation so that voxel (0,0,0)'s centre is at
 * origin), zero background, zero voxels inactive. Dense voxel (i,j,k) is
 * stored at index (i,j,k). Constant active blocks are stored as tiles
 * (lossless). Values are written as given (negative or NaN too), and
 * read(write(g)) returns g exactly when g's outer faces hold non-zero
 * values (zero voxels are inactive, so zero borders shrink the box). */
int nbt_vdb_write(const char *path, const char *name, const nbt_vdb_grid *g, char *err, size_t errlen);

/* ---- test helpers: only tests/test_vdb.c uses these ---- */

typedef enum {
    NBT_VDB_TEST_UNIFORM,    /* voxel size g->voxel on every axis */
    NBT_VDB_TEST_NONUNIFORM, /* x voxel size 2 * g->voxel */
    NBT_VDB_TEST_ROTATED     /* uniform scale, rotated 30 degrees about z */
} nbt_vdb_test_transform;

typedef struct {
    const char *name;
    const nbt_vdb_grid *g;
    int index0[3];                     /* index coordinate of g's voxel (0,0,0); its centre stays at g->origin */
    int as_double;                     /* 1: store as a DoubleGrid (not a float grid) */
    nbt_vdb_test_transform transform;
} nbt_vdb_test_grid;

/* Test helper: write n grids into one file, each as nbt_vdb_write would
 * (zero background, zero voxels inactive, pruned) but placed at index0,
 * optionally as a DoubleGrid or with a transform the reader refuses.
 * nbt_vdb_write(p, nm, g) is nbt_vdb_write_test with one
 * {nm, g, {0,0,0}, 0, NBT_VDB_TEST_UNIFORM}. */
int nbt_vdb_write_test(const char *path, const nbt_vdb_test_grid *grids, size_t n, char *err, size_t errlen);

/* Test helper: the number of active tiles (constant blocks stored above
 * voxel level) of the grid `name` in a file, or -1 on any error. */
long nbt_vdb_test_active_tiles(const char *path, const char *name);

#ifdef __cplusplus
}
#endif
#endif
