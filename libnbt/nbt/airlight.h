/* nbt/airlight.h: the airlight integrals of Hong's thesis (ch. 4).
 *
 *   H_k(u, v) = int_{-pi/2}^{v} exp(-u tan(pi/4 + t/2)) P_k(-sin t) dt,
 *               u >= 0, v in [-pi/2, pi/2]                    (thesis eq. 4.17)
 *   H_p(u, v) = same with 4 pi p(-sin t) in place of P_k  = sum_k (2k+1) b_k H_k
 *               (fixed-phase mode, the thesis' eq. 4.7 up to the 4 pi)
 *
 * Airlight of an isotropic point source (intensity I0) seen along a ray:
 *   L_a = kappa_s I0 e^{-kappa_t t}/h (1/4pi) sum_k (2k+1) b_k [H_k(kappa_t h, theta_d) - H_k(kappa_t h, theta_0)]
 * with t = d_sv cos(gamma), h = d_sv sin(gamma), theta_0 = gamma - pi/2,
 * theta_d = atan((d_vp - t)/h). Reference: Nishita's integral along the ray
 *   L_a = int_0^{d_vp} kappa_s p(cos alpha(x)) I0 e^{-kappa_t d(x)}/d(x)^2 e^{-kappa_t x} dx. */
#ifndef NBT_AIRLIGHT_H
#define NBT_AIRLIGHT_H

#include <stddef.h>
#include <nbt/error.h>
#include <nbt/phase.h>
#include <nbt/table.h>

#ifdef __cplusplus
extern "C" {
#endif

/* H_0..H_kmax at (u, v), relative tolerance tol (absolute where H_k is small
 * through cancellation: relative to int |integrand|). H and abserr hold
 * kmax+1 values. NBT_EDOM for u < 0, v outside [-pi/2, pi/2], NaN. */
nbt_status nbt_hk(size_t kmax, double u, double v, double tol, double *H, double *abserr);

/* Fixed-phase H_p(u, v). */
nbt_status nbt_h_phase(const nbt_phase *p, double u, double v, double tol, double *H, double *abserr);

typedef struct {
    double kappa_s;  /* scattering coefficient, >= 0 */
    double kappa_t;  /* extinction coefficient, >= kappa_s */
    double I0;       /* source intensity */
    double dsv;      /* viewer-source distance, > 0 */
    double gamma;    /* angle between view ray and source direction, [0, pi] */
    double dvp;      /* distance to the surface along the ray, > 0 (INFINITY allowed) */
} nbt_airlight_geom;

/* Checks ranges; NBT_EDOM for a ray that runs through the source itself
 * (gamma = 0 and dvp >= dsv): the airlight is infinite there. The handler
 * gets one line naming the bad value and what is accepted. */
nbt_status nbt_airlight_check(const nbt_airlight_geom *g);

/* Reference: Nishita's integral along the ray by adaptive quadrature. */
nbt_status nbt_airlight_direct(const nbt_phase *p, const nbt_airlight_geom *g, double tol,
                               double *La, double *abserr);
/* Legendre series with moments b[0..nterms-1] over exactly computed H_k
 * (one channel: the weighted sum of the H_k differences is integrated
 * directly, never formed by subtracting H values). */
nbt_status nbt_airlight_series(const double *b, size_t nterms, const nbt_airlight_geom *g,
                               double tol, double *La, double *abserr);
/* Table route: Legendre tables (any number, channels give k; b indexed by k,
 * orders without a channel are left out) or one fixed-phase table (b unused).
 * The lookup is L_a above with two lookups per channel; its bound is the
 * tables' recorded max_err, twice per channel, weighted by |w_k| and the
 * prefactor, so it grows as 1/h towards the source axis (gamma -> 0 with the
 * surface before the source, gamma -> pi) while L_a stays finite. Wherever
 * that bound exceeds 10% of the looked-up value (and on the axis itself,
 * gamma = 0 or pi, where the lookup is undefined) the same phase function
 * is integrated along the ray instead (as nbt_airlight_direct does): the
 * channels' truncated series for Legendre tables; for a fixed-phase table
 * the phase `fixed`, or, when NULL, the table's phase name parsed with
 * nbt_phase_parse (file phases, e.g. "sog:2 terms", cannot be: the lookup is
 * then returned with its bound; on the axis NBT_EDOM). abserr: the lookup's
 * bound (NaN where max_err was not measured) or the ray quadrature's error
 * estimate. The series' truncation is the caller's (as in nbt_airlight_series).
 * NBT_ETOL: u = kappa_t h beyond the table's u range (the lookup clamps to
 * the edge; the bound does not cover that). The GLSL shaders do only the
 * lookup, with gamma clamped (doc/shaders.md). */
nbt_status nbt_airlight_table_e(const nbt_table *const *tables, size_t ntables, const double *b,
                                size_t nterms, const nbt_phase *fixed, const nbt_airlight_geom *g,
                                double *La, double *abserr);
/* The same, without the bound and with fixed = NULL. */
nbt_status nbt_airlight_table(const nbt_table *const *tables, size_t ntables, const double *b,
                              size_t nterms, const nbt_airlight_geom *g, double *La);

/* Fill a table whose axes, nch and k[] (or phase, with fixed != NULL) are set:
 * node values by cumulative quadrature in v (Legendre channels: fixed
 * Gauss-Legendre rules per cell, prefix-summed), and (if measure_error)
 * max_err: |bilinear - exact| at every midpoint between v nodes, at every
 * cell and edge midpoint of the first 8 and every 4th u interval, and from
 * second differences in u of the exact values on the others. */
typedef struct {
    double quad_tol;     /* relative quadrature tolerance at nodes (e.g. 1e-10) */
    int measure_error;   /* fill max_err (H: about 2-3x the build time) */
    unsigned nthreads;   /* 0: all online CPUs */
} nbt_build_opts;

nbt_status nbt_h_table_build(nbt_table *t, const nbt_phase *fixed, const nbt_build_opts *o);
/* Several tables with the same axes (e.g. packs of four orders) in one pass:
 * every order is integrated once. */
nbt_status nbt_h_table_build_set(nbt_table *const *ts, size_t nt, const nbt_phase *fixed,
                                 const nbt_build_opts *o);

#ifdef __cplusplus
}
#endif
#endif
