/* libnbt/gslice_j.h: the J side of g-sliced tables (gslice_j.c) for
 * gslice.c; not installed. */
#ifndef NBT_GSLICE_J_H
#define NBT_GSLICE_J_H

#include <nbt/table.h>
#include <nbt/surface.h>
#include "internal.h"

/* The J^n slices at g[0..m-1] over t's axes 0 and 1 (t->n), in t's value
 * form (PLAIN or LOG_ET), as 2-D one-channel tables with quad_err,
 * max_abs and (o->measure_error) max_err in that form. */
nbt_status nbt__gslice_j_slices(const nbt_table *t, const double *g, size_t m, const nbt_build_opts *o,
                                nbt__jcache *gc, nbt_table **out);

/* J_p^n at (T, theta, g) from a g-sliced J table in either form, and its
 * bound from the recorded error (nbt_table_err_at): LOG_ET: J e^{v - T}
 * with bound J (e^err - 1); PLAIN: the lookup and err itself. */
double nbt__gslice_j_at(const nbt_table *t, double T, double theta, double g, double *err);

/* J tables (surface.c) for HG at g[0..m-1], one one-channel table each
 * (same axes, n and form), in one pass: each quadrature node's exponential
 * and the kernel matrix shared by all of them, panels graded for the most
 * peaked g. */
nbt_status nbt__j_table_build_hg(nbt_table *const *ts, size_t m, const double *g, const nbt_build_opts *o,
                                 nbt__jcache *gc);

#endif
