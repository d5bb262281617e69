/* libnbt/tablefill.h: the shared fill step of table builders; not installed. */
#ifndef NBT_TABLEFILL_H
#define NBT_TABLEFILL_H

#include <nbt/table.h>

/* Compute exact values at every (xs[i], ys[j]) into F[(j*nx + i)*nch + c]
 * and the largest quadrature error estimate into *quad_err. */
typedef nbt_status (*nbt__grid_fill)(void *ctx, const double *xs, size_t nx, const double *ys,
                                     size_t ny, double *F, double *quad_err);

/* Fill t->data at the nodes via fill(); with measure, evaluate on the grid
 * refined by 2 in each axis (in unit coordinates) and set max_err to the
 * largest |bilinear - exact| over all cell and edge midpoints, plus the
 * quadrature error. Sets max_abs and quad_err. */
nbt_status nbt__table_fill(nbt_table *t, int measure, nbt__grid_fill fill, void *ctx);

#endif
