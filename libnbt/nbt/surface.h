/* nbt/surface.h: surface radiance from a point source in a medium (Hong, ch. 4).
 *
 *   J_k^n(T, theta) = int_{cos theta_i > 0} e^{-T cos g}/sin g
 *                     [H_k(T sin g, pi/2) - H_k(T sin g, g - pi/2)] cos^n theta_i dw_i
 * theta_i measured from the axis (the normal for n = 1, the mirror direction
 * for a Phong lobe), g the angle between w_i and the source direction, which
 * makes angle theta with the axis; T >= 0, theta in [0, pi], integer n >= 1.
 *
 * Computed in coordinates centred on the source direction, where the solid
 * angle element sin g dg dphi cancels the 1/sin g:
 *   J_k^n(T, theta) = int_0^pi G_k(T, g) K_n(theta, g) dg,
 *   G_k(T, g) = int_{g-pi/2}^{pi/2} exp(-T [cos g + sin g tan(pi/4 + t/2)]) P_k(-sin t) dt,
 *   K_n(theta, g) = int_0^{2pi} max(0, cos theta cos g + sin theta sin g cos phi)^n dphi.
 *
 * Surface radiance (BRDF = kd for Lambert, ks cos^n for Phong about the
 * mirror direction, as in the thesis):
 *   L_p = I0 e^{-kappa_t d_sp}/d_sp^2 (kd cos theta_s + ks cos^n theta_s')
 *       + kappa_s I0/d_sp (1/4pi) sum_k (2k+1) b_k [kd J_k^1(T, theta_s) + ks J_k^n(T, theta_s')]
 * with T = kappa_t d_sp; the cosine factors of the direct term are clamped at 0. */
#ifndef NBT_SURFACE_H
#define NBT_SURFACE_H

#include <stddef.h>
#include <nbt/error.h>
#include <nbt/phase.h>
#include <nbt/table.h>
#include <nbt/airlight.h>

#ifdef __cplusplus
extern "C" {
#endif

/* J_0^n..J_kmax^n at (T, theta), relative tolerance tol. */
nbt_status nbt_jk(size_t kmax, int n, double T, double theta, double tol, double *J, double *abserr);
/* Fixed-phase J_p^n (4 pi p in place of P_k). */
nbt_status nbt_j_phase(const nbt_phase *p, int n, double T, double theta, double tol,
                       double *J, double *abserr);

/* The azimuthal kernel K_n(theta, g) (exact for the full cone, Gauss-Legendre
 * to ~1e-15 relative for a cone cut by the horizon). */
double nbt_surface_kernel(int n, double theta, double g);

typedef struct {
    double kappa_s, kappa_t, I0;
    double dsp;       /* source-surface distance, > 0 */
    double theta_s;   /* angle between normal and source direction, [0, pi] */
    double theta_r;   /* angle between mirror direction and source direction, [0, pi] */
    double kd, ks;    /* diffuse and specular BRDF constants, >= 0 */
    int n;            /* Phong exponent, >= 1 */
} nbt_surface_geom;

nbt_status nbt_surface_check(const nbt_surface_geom *g);

/* Reference: the physical integral, i.e. Nishita's airlight integral along
 * every incident ray (in distance, not through H), integrated over incident
 * directions around the source direction, clamped cosine lobe evaluated
 * pointwise in azimuth. Slow (nested adaptive quadrature). */
nbt_status nbt_surface_direct(const nbt_phase *p, const nbt_surface_geom *g, double tol,
                              double *Lp, double *abserr);
/* Legendre series over exactly computed J_k^n. */
nbt_status nbt_surface_series(const double *b, size_t nterms, const nbt_surface_geom *g,
                              double tol, double *Lp, double *abserr);
/* Table lookup. diffuse: tables with n = 1; specular: tables with n = g->n
 * (either set may be empty when kd or ks is 0). Fixed-phase tables: b unused. */
nbt_status nbt_surface_table(const nbt_table *const *diffuse, size_t ndiffuse,
                             const nbt_table *const *specular, size_t nspecular,
                             const double *b, size_t nterms, const nbt_surface_geom *g,
                             double *Lp);

/* Fill a J table (axes, nch, k[] or fixed phase, n set): G on shared
 * Gauss-Legendre nodes in g, product-integration weights of K_n that respect
 * each theta's kinks, J = G M^T. max_err measured at midpoints as for H. */
nbt_status nbt_j_table_build(nbt_table *t, const nbt_phase *fixed, const nbt_build_opts *o);
/* Several J tables with the same axes and n (at most 64) in one pass. */
nbt_status nbt_j_table_build_set(nbt_table *const *ts, size_t nt, const nbt_phase *fixed,
                                 const nbt_build_opts *o);

#ifdef __cplusplus
}
#endif
#endif
