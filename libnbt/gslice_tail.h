/* libnbt/gslice_tail.h (internal): the tail form of g-sliced H tables. */
#ifndef NBT_GSLICE_TAIL_H
#define NBT_GSLICE_TAIL_H
#include <nbt/airlight.h>

/* The tail form of g-sliced H tables (libnbt/gslice_tail.c, doc/tables.md).
 * fill: node values R = C W, the relative error per g cell (cell_err) and
 * max_err, form, interp2 = 2. phi: HG's Moebius angle 2 atan(s (1+g)/(1-g)).
 * weight: W(u, v) = 1 + s/2 + u s^2/2 (INFINITY at v = pi/2, where C = 0).
 * gauss: int_{phi_0}^{phi_d} exp(-e0 - u (s(phi) - s0)) 4 pi p dt/dphi dphi by
 * the NBT_TAIL_GAUSS_N-point Gauss-Legendre rule (fine: twice the nodes), s0 = s(theta_0), ds = s(theta_d) - s0,
 * written without cancellation (float shaders evaluate it too). airlight_tail: the lookup (or, where the two terms
 * nearly cancel, the Gauss rule) and its bound; geometry with h > 0. */
#define NBT_TAIL_SHORT 0.25
#define NBT_TAIL_GAUSS_N 16
/* the tail route integrates along the ray where its bound exceeds this
 * fraction of the value (the goal, 1e-3) */
#define NBT_TAIL_RAY_TOL 1e-3
nbt_status nbt__tail_fill(nbt_table *t, const nbt_build_opts *o);
double nbt__tail_phi(double s, double g);
double nbt__tail_weight(double u, double v);
double nbt__tail_gauss(double g, double u, double e0, double s0, double ds, int fine);
/* the relative error bound of a lookup at (u, v, g): the error map (channel
 * 1) at the 8 nodes of its cell; cell_err without a map */
double nbt__tail_err_at(const nbt_table *t, double u, double v, double g);
/* Half precision for a tail-form table: log values rounded, their largest
 * rounding change (relative: expm1 of it) added to the error map, cell_err
 * and max_err, the map rounded up. */
nbt_status nbt__tail_round_half(nbt_table *t);
nbt_status nbt__airlight_tail(const nbt_table *t, double g, const void *geo, double *La, double *abserr,
                              int *used_gauss);

#endif
