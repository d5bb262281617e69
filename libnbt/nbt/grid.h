/* nbt/grid.h: dense 3-D density grids (smoke, fog banks) for heterogeneous
 * media, and nbt's raw grid file.
 *
 * Voxel (i, j, k) holds the density at its centre, world position
 * origin + voxel * (i, j, k); between centres the density is trilinear,
 * outside the grid's box (half a voxel beyond the outer centres) it is 0.
 *
 * Raw file: one text line "NBTGRID 1 nx ny nz ox oy oz voxel\n" followed by
 * nx*ny*nz float32 values, little-endian, x fastest, then y, then z. */
#ifndef NBT_GRID_H
#define NBT_GRID_H

#include <stddef.h>
#include <nbt/error.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef struct {
    size_t nx, ny, nz;
    double origin[3]; /* centre of voxel (0, 0, 0) */
    double voxel;     /* edge length, > 0 */
    float *data;      /* data[(k*ny + j)*nx + i], >= 0 and finite */
} nbt_grid;

/* A grid of the given size, zero-filled (NULL on bad size or no memory). */
nbt_grid *nbt_grid_alloc(size_t nx, size_t ny, size_t nz, const double origin[3], double voxel);
void nbt_grid_free(nbt_grid *g);

/* Checks sizes, voxel > 0, finite origin, every value finite and >= 0
 * (err names the first bad voxel). */
nbt_status nbt_grid_check(const nbt_grid *g, char *err, size_t errlen);

/* Read / write the raw format (write: via a temporary file). On failure
 * *out is NULL and err holds one line naming the file and the problem. */
nbt_status nbt_grid_read_raw(const char *path, nbt_grid **out, char *err, size_t errlen);
nbt_status nbt_grid_write_raw(const nbt_grid *g, const char *path, char *err, size_t errlen);

/* Trilinear density at p (an nbt_density_fn: ctx is the grid). */
double nbt_grid_density(const double p[3], void *grid);

/* The box the density lives in: lo = origin - voxel/2, hi = lo + n voxel. */
void nbt_grid_box(const nbt_grid *g, double lo[3], double hi[3]);
/* The farthest distance t >= 0 at which o + t d (d unit) is inside the box; 0 if never. */
double nbt_grid_exit(const nbt_grid *g, const double o[3], const double d[3]);

#ifdef __cplusplus
}
#endif
#endif
