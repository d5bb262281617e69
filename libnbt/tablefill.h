/* libnbt/tablefill.h: the shared fill step of table builders; not installed. */
#ifndef NBT_TABLEFILL_H
#define NBT_TABLEFILL_H

#include <nbt/table.h>

/* Compute exact values at every (xs[i], ys[j]) into F[(i*ny + j)*nch + c]
 * (column-major: a builder's unit of work is one x row) for the nch
 * channels of all tables together, and the largest quadrature error
 * estimate into *quad_err. */
typedef nbt_status (*nbt__grid_fill)(void *ctx, const double *xs, size_t nx, const double *ys,
                                     size_t ny, double *F, double *quad_err);

/* Fill the tables (same axes; channels taken in order, table by table) at
 * their nodes via one call of fill() (with measure: at the y midpoints too),
 * and with measure a second call at the x midpoints of the first 8, every
 * 4th and the last x interval (same y); max_err is the
 * largest |bilinear - exact| there, and on the other x intervals the
 * second differences in x of the exact node rows / 8 (the bilinear error at
 * a midpoint of a smooth f) plus the error next to them; plus the
 * quadrature error. Sets max_abs and quad_err. */
/* measure: 0 none; NBT__MEASURE_SPARSE the scheme above (H and J, whose
 * smoothness on the planner's mappings was measured); NBT__MEASURE_FULL every
 * x midpoint exact (nbt_table_tabulate's arbitrary functions). */
enum { NBT__MEASURE_SPARSE = 1, NBT__MEASURE_FULL = 2 };
nbt_status nbt__table_fill(nbt_table *const *ts, size_t nt, int measure, nbt__grid_fill fill, void *ctx);

/* Validate a set of tables to be filled together (nt >= 1; same kind, n and
 * axes; Legendre channels k >= 0, or all marked k = -1 when fixed != NULL)
 * and return the channel -> k map of all of them (malloc'd, free it), the
 * total number of channels and the highest order. */
#include <nbt/phase.h>
nbt_status nbt__table_set_prepare(nbt_table *const *ts, size_t nt, const nbt_phase *fixed, int **kmap,
                                  size_t *nch, size_t *kmax);

#endif
