/* tests/test_shim.c: the Ceres shim from C: known parameters recovered
 * (noise-free to 1e-8, noisy within their standard errors), bounds, robust
 * loss, analytic vs numeric Jacobians, bad input, determinism. */
#include <math.h>
#include <string.h>
#include "../fit/ceres_shim.h"
#include "testutil.h"

#define N 40
typedef struct {
    double t[N], y[N], sigma;
} data;

/* y = A exp(-k t) + c, residuals (model - y)/sigma */
static int decay(const double *p, double *r, double *jac, void *vp)
{
    const data *d = vp;
    for (int i = 0; i < N; i++) {
        double e = exp(-p[1] * d->t[i]);
        r[i] = (p[0] * e + p[2] - d->y[i]) / d->sigma;
        if (jac) {
            jac[3 * i] = e / d->sigma;
            jac[3 * i + 1] = -p[0] * d->t[i] * e / d->sigma;
            jac[3 * i + 2] = 1 / d->sigma;
        }
    }
    return 0;
}

static int rosen(const double *p, double *r, double *jac, void *vp)
{
    (void)vp;
    (void)jac;
    r[0] = 10 * (p[1] - p[0] * p[0]);
    r[1] = 1 - p[0];
    return 0;
}

static int fails(const double *p, double *r, double *jac, void *vp)
{
    (void)p;
    (void)r;
    (void)jac;
    (void)vp;
    return 1;
}

int main(void)
{
    data d;
    d.sigma = 1;
    const double A = 2.385, k = 0.73, c = 0.41;
    for (int i = 0; i < N; i++) {
        d.t[i] = 0.1 * i;
        d.y[i] = A * exp(-k * d.t[i]) + c;
    }
    nbt_fit_options o;
    nbt_fit_summary s;
    for (int an = 0; an < 2; an++) {
        nbt_fit_options_default(&o);
        o.analytic_jacobian = an;
        double p[3] = {1, 1, 0};
        int rc = nbt_fit_solve(3, p, NULL, NULL, N, decay, &d, &o, &s);
        t_true(rc == 0 && s.converged, "noise-free fit converges (%s Jacobian): %s", an ? "analytic" : "numeric",
               s.termination);
        t_abs(p[0], A, 1e-8, "A recovered");
        t_abs(p[1], k, 1e-8, "k recovered");
        t_abs(p[2], c, 1e-8, "c recovered");
        t_true(s.final_cost < 1e-16 && s.initial_cost > s.final_cost && s.iterations > 0, "costs and iterations reported");
    }
    /* noisy data (deterministic noise, sigma 0.01): within 3 standard errors from the covariance */
    data dn = d;
    dn.sigma = 0.01;
    for (int i = 0; i < N; i++) {
        double u1 = t_uniform(), u2 = t_uniform();
        dn.y[i] += dn.sigma * sqrt(-2 * log(1 - u1)) * cos(2 * M_PI * u2);
    }
    nbt_fit_options_default(&o);
    o.analytic_jacobian = 1;
    o.covariance = 1;
    double p[3] = {1, 1, 0};
    nbt_fit_solve(3, p, NULL, NULL, N, decay, &dn, &o, &s);
    t_true(s.covariance_ok, "covariance computed");
    const double truth[3] = {A, k, c};
    for (int i = 0; i < 3; i++)
        t_abs(p[i], truth[i], 3 * sqrt(s.covariance[i * 3 + i]), "noisy: parameter %d within 3 se (se %.2g)", i,
              sqrt(s.covariance[i * 3 + i]));
    /* determinism */
    double q[3] = {1, 1, 0};
    nbt_fit_summary s2;
    nbt_fit_solve(3, q, NULL, NULL, N, decay, &dn, &o, &s2);
    t_true(!memcmp(p, q, sizeof p) && s.final_cost == s2.final_cost, "the same fit twice: identical");
    /* bounds: k <= 0.5 binds */
    double lo[3] = {-HUGE_VAL, 0, -HUGE_VAL}, hi[3] = {HUGE_VAL, 0.5, HUGE_VAL}, pb[3] = {1, 0.2, 0};
    nbt_fit_solve(3, pb, lo, hi, N, decay, &d, &o, &s);
    t_true(s.usable && pb[1] <= 0.5 && fabs(pb[1] - 0.5) < 1e-9, "upper bound respected and active (k = %.12g)", pb[1]);
    /* Rosenbrock */
    nbt_fit_options_default(&o);
    double pr[2] = {-1.2, 1};
    nbt_fit_solve(2, pr, NULL, NULL, 2, rosen, NULL, &o, &s);
    t_abs(pr[0], 1, 1e-8, "Rosenbrock x");
    t_abs(pr[1], 1, 1e-8, "Rosenbrock y");
    /* robust loss: one gross outlier moves the plain fit, much less the Cauchy one */
    data dout = d;
    dout.y[5] += 5;
    double pp[3] = {1, 1, 0}, pc[3] = {1, 1, 0};
    nbt_fit_options_default(&o);
    o.analytic_jacobian = 1;
    nbt_fit_solve(3, pp, NULL, NULL, N, decay, &dout, &o, &s);
    o.loss = NBT_FIT_LOSS_CAUCHY;
    o.loss_scale = 0.1;
    nbt_fit_solve(3, pc, NULL, NULL, N, decay, &dout, &o, &s);
    t_true(fabs(pc[0] - A) < 0.1 * fabs(pp[0] - A) && fabs(pc[0] - A) < 1e-3, "Cauchy loss resists the outlier (A %.4g vs %.4g)",
           pc[0], pp[0]);
    /* bad input */
    nbt_fit_options_default(&o);
    double bad[3] = {NAN, 1, 0};
    t_true(nbt_fit_solve(3, bad, NULL, NULL, N, decay, &d, &o, &s) != 0 && !strcmp(s.termination, "BAD_INPUT"),
           "NaN start rejected: %s", s.message);
    double outb[3] = {1, 0.9, 0};
    t_true(nbt_fit_solve(3, outb, lo, hi, N, decay, &d, &o, &s) != 0 && !strcmp(s.termination, "BAD_INPUT"),
           "start outside its bounds rejected");
    t_true(nbt_fit_solve(3, p, NULL, NULL, 2, decay, &d, &o, &s) != 0, "fewer residuals than parameters rejected");
    double pf[2] = {1, 1};
    t_true(nbt_fit_solve(2, pf, NULL, NULL, 2, fails, NULL, &o, &s) != 0 && !s.usable, "a failing residual is reported (%s)",
           s.termination);
    return t_done();
}
