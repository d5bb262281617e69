/* tests/test_kernelfit.c: the fitted shapes' annulus means (against direct
 * quadrature of the shape), their analytic derivatives (against central
 * differences), and exact recovery of known parameters through the shim. */
#include <math.h>
#include <string.h>
#include <nbt/nbt.h>
#include "../fit/ceres_shim.h"
#include "../fit/kernel_model.h"
#include "testutil.h"

typedef struct {
    double alpha, beta, M, s;
} shp;
static int integrand(double r, void *vp, unsigned fdim, double *f)
{
    (void)fdim;
    const shp *c = vp;
    f[0] = 2 * M_PI * r * (nbt_beam_kernel(c->alpha, c->beta, r) + c->M * exp(-r * r / (2 * c->s * c->s)) / (2 * M_PI * c->s * c->s));
    return 0;
}

#define NB 24
typedef struct {
    double lo[NB], hi[NB], y[NB];
} syn;
static int res(const double *p, double *r, double *jac, void *vp)
{
    const syn *d = vp;
    for (int k = 0; k < NB; k++) {
        double da, db, dm, ds;
        r[k] = kernel_annulus(p[0], p[1], d->lo[k], d->hi[k], &da, &db) + gauss_annulus(p[2], p[3], d->lo[k], d->hi[k], &dm, &ds)
               - d->y[k];
        r[k] /= 1e-3 * d->y[k];
        if (jac) {
            double w = 1 / (1e-3 * d->y[k]);
            jac[4 * k] = da * w;
            jac[4 * k + 1] = db * w;
            jac[4 * k + 2] = dm * w;
            jac[4 * k + 3] = ds * w;
        }
    }
    return 0;
}

int main(void)
{
    nbt_quad_ws *ws = nbt_quad_ws_alloc(1, 500);
    shp c = {0.37, 1.3, 0.21, 0.9};
    double lo = 0.3, hi = 0.55, v, e;
    nbt_quad_gk(ws, integrand, &c, 1, lo, hi, 0, 1e-13, &v, &e);
    double area = M_PI * (hi * hi - lo * lo);
    t_rel(kernel_annulus(c.alpha, c.beta, lo, hi, NULL, NULL) + gauss_annulus(c.M, c.s, lo, hi, NULL, NULL), v / area, 1e-12,
          "annulus mean = quadrature of the shape");
    nbt_quad_gk(ws, integrand, &c, 1, 1e-12, 0.1, 0, 1e-12, &v, &e);
    t_rel(kernel_annulus(c.alpha, c.beta, 0, 0.1, NULL, NULL) + gauss_annulus(c.M, c.s, 0, 0.1, NULL, NULL),
          v / (M_PI * 0.01), 1e-9, "annulus mean at the axis (the 1/r core)");
    nbt_quad_ws_free(ws);
    /* analytic derivatives */
    double da, db, dm, ds, h = 1e-6;
    kernel_annulus(c.alpha, c.beta, lo, hi, &da, &db);
    gauss_annulus(c.M, c.s, lo, hi, &dm, &ds);
    t_rel(da, (kernel_annulus(c.alpha + h, c.beta, lo, hi, NULL, NULL) - kernel_annulus(c.alpha - h, c.beta, lo, hi, NULL, NULL)) / (2 * h), 1e-8, "d/dalpha");
    t_rel(db, (kernel_annulus(c.alpha, c.beta + h, lo, hi, NULL, NULL) - kernel_annulus(c.alpha, c.beta - h, lo, hi, NULL, NULL)) / (2 * h), 1e-8, "d/dbeta");
    t_rel(dm, (gauss_annulus(c.M + h, c.s, lo, hi, NULL, NULL) - gauss_annulus(c.M - h, c.s, lo, hi, NULL, NULL)) / (2 * h), 1e-8, "d/dM");
    t_rel(ds, (gauss_annulus(c.M, c.s + h, lo, hi, NULL, NULL) - gauss_annulus(c.M, c.s - h, lo, hi, NULL, NULL)) / (2 * h), 1e-8, "d/ds");
    /* noise-free synthetic data: the parameters come back to 1e-8 */
    syn d;
    for (int k = 0; k < NB; k++) {
        d.lo[k] = 0.25 * k;
        d.hi[k] = 0.25 * (k + 1);
        d.y[k] = kernel_annulus(c.alpha, c.beta, d.lo[k], d.hi[k], NULL, NULL) + gauss_annulus(c.M, c.s, d.lo[k], d.hi[k], NULL, NULL);
    }
    nbt_fit_options o;
    nbt_fit_options_default(&o);
    o.analytic_jacobian = 1;
    nbt_fit_summary s;
    double p[4] = {0.2, 2.0, 0.4, 0.5}, plo[4] = {0, 1e-6, 0, 1e-6};
    t_true(nbt_fit_solve(4, p, plo, NULL, NB, res, &d, &o, &s) == 0 && s.converged, "synthetic fit converges: %s", s.termination);
    t_rel(p[0], c.alpha, 1e-8, "alpha recovered");
    t_rel(p[1], c.beta, 1e-8, "beta recovered");
    t_rel(p[2], c.M, 1e-8, "M recovered");
    t_rel(p[3], c.s, 1e-8, "s recovered");
    return t_done();
}
