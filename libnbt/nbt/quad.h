/* nbt/quad.h: the quadrature rules the rest of libnbt is built on.
 *
 * Integrands are vector-valued (cubature style): one call evaluates fdim
 * components at one point, so that e.g. all Legendre orders k share one
 * exponential. All state goes through `params`; nothing is global. */
#ifndef NBT_QUAD_H
#define NBT_QUAD_H

#include <stddef.h>
#include <nbt/error.h>

#ifdef __cplusplus
extern "C" {
#endif

/* f(x) -> fval[0..fdim-1]. Return 0 on success, non-zero to abort. */
typedef int (*nbt_integrand)(double x, void *params, unsigned fdim, double *fval);

/* Gauss-Legendre rule with n nodes on [-1, 1] (n >= 1). */
typedef struct {
    size_t n;
    double *x;
    double *w;
} nbt_gl_rule;

nbt_gl_rule *nbt_gl_rule_alloc(size_t n);
void nbt_gl_rule_free(nbt_gl_rule *rule);

/* Workspace for adaptive Gauss-Kronrod (7/15) integration of a vector
 * integrand with up to fdim components, using at most max_intervals
 * subintervals. One workspace per thread. */
typedef struct nbt_quad_ws nbt_quad_ws;

nbt_quad_ws *nbt_quad_ws_alloc(unsigned fdim, size_t max_intervals);
void nbt_quad_ws_free(nbt_quad_ws *ws);

/* Adaptive integral of f over [a, b] (finite, a <= b or a > b).
 *
 * Component i is converged when its error estimate is below
 * max(epsabs, epsrel * L1_i), L1_i the estimate of the integral of |f_i|:
 * relative accuracy where a component is large, absolute where it is near
 * zero through cancellation. The error estimate is |K15 - G7| per interval,
 * summed (conservative: it does not use QUADPACK's power-law rescaling).
 *
 * result and abserr hold fdim values each. Returns NBT_ETOL (results still
 * set) when the interval budget is spent before convergence, NBT_EDOM for
 * non-finite limits or an integrand that returned non-zero or non-finite
 * values, NBT_EINVAL for fdim larger than the workspace. */
nbt_status nbt_quad_gk(nbt_quad_ws *ws, nbt_integrand f, void *params, unsigned fdim,
                       double a, double b, double epsabs, double epsrel,
                       double *result, double *abserr);

/* As nbt_quad_gk, with interior breakpoints pts[0..npts-1] (sorted, inside
 * (a, b)) where the integrand has kinks or narrow features. */
nbt_status nbt_quad_gk_pts(nbt_quad_ws *ws, nbt_integrand f, void *params, unsigned fdim,
                           double a, double b, const double *pts, size_t npts,
                           double epsabs, double epsrel, double *result, double *abserr);

#ifdef __cplusplus
}
#endif
#endif
