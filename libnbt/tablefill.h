/* libnbt/tablefill.h: the shared fill step of table builders; not installed. */
#ifndef NBT_TABLEFILL_H
#define NBT_TABLEFILL_H

#include <nbt/table.h>

/* Compute exact values at every (xs[i], ys[j]) into F[(j*nx + i)*nch + c]
 * for the nch channels of all tables together, and the largest quadrature
 * error estimate into *quad_err. */
typedef nbt_status (*nbt__grid_fill)(void *ctx, const double *xs, size_t nx, const double *ys,
                                     size_t ny, double *F, double *quad_err);

/* Fill the tables (same axes; channels taken in order, table by table) at
 * their nodes via one call of fill(); with measure, evaluate on the grid
 * refined by 2 in each axis (in unit coordinates) and set max_err to the
 * largest |bilinear - exact| over all cell and edge midpoints, plus the
 * quadrature error. Sets max_abs and quad_err. */
nbt_status nbt__table_fill(nbt_table *const *ts, size_t nt, int measure, nbt__grid_fill fill, void *ctx);

/* Check that the tables share kind and axes; the channel -> k map of all of
 * them (k = -1 for fixed phase) into kmap (size >= total channels). Returns
 * the total number of channels, 0 on mismatch. */
size_t nbt__table_set_channels(nbt_table *const *ts, size_t nt, int *kmap);

#endif
