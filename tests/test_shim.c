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

/* y = a + b t (+ 0 c: a parameter the residuals ignore when np = 3), sigma 1 */
static int line(const double *p, double *r, double *jac, void *vp)
{
    const data *d = vp;
    int np = d->sigma > 1 ? 3 : 2; /* sigma doubles as the switch; residuals unweighted */
    for (int i = 0; i < N; i++) {
        r[i] = p[0] + p[1] * d->t[i] - d->y[i];
        if (jac) {
            jac[np * i] = 1;
            jac[np * i + 1] = d->t[i];
            if (np == 3)
                jac[np * i + 2] = 0;
        }
    }
    return 0;
}

/* y = (a + b) t: only a + b is identified */
static int sum2(const double *p, double *r, double *jac, void *vp)
{
    const data *d = vp;
    for (int i = 0; i < N; i++) {
        r[i] = (p[0] + p[1]) * d->t[i] - d->y[i];
        if (jac)
            jac[2 * i] = jac[2 * i + 1] = d->t[i];
    }
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
    t_true(s.at_bound[1] == 1 && s.at_bound[0] == 0 && s.at_bound[2] == 0 && s.nbound == 1,
           "the upper bound is reported (at_bound %d %d %d)", s.at_bound[0], s.at_bound[1], s.at_bound[2]);
    double lo2[3] = {-HUGE_VAL, 1.0, -HUGE_VAL}, pl[3] = {1, 2, 0};
    nbt_fit_solve(3, pl, lo2, NULL, N, decay, &d, &o, &s);
    t_true(s.usable && pl[1] == 1.0 && s.at_bound[1] == -1 && s.nbound == 1, "the lower bound is reported (k = %.12g)", pl[1]);
    double pin[3] = {1, 1, 0}, hi5[3] = {HUGE_VAL, 5, HUGE_VAL};
    nbt_fit_solve(3, pin, lo, hi5, N, decay, &dn, &o, &s);
    t_true(s.usable && s.nbound == 0 && fabs(pin[1] - k) < 0.05, "bounds that do not bind are not reported (k = %.6g, %d)",
           pin[1], s.nbound);
    /* conditioning: y = a + b t is linear, its column-scaled J^T J is
     * [[1, rho], [rho, 1]], rho = sum t / sqrt(N sum t^2): rcond = (1 - rho)/(1 + rho) */
    data dl = d;
    double st = 0, st2 = 0;
    for (int i = 0; i < N; i++) {
        dl.t[i] = 2.385 + 0.1 * i;
        dl.y[i] = 0.7 + 0.3 * dl.t[i] + 0.01 * (t_uniform() - 0.5);
        st += dl.t[i];
        st2 += dl.t[i] * dl.t[i];
    }
    double rho = st / sqrt(N * st2), det = N * st2 - st * st;
    nbt_fit_options_default(&o);
    o.analytic_jacobian = 1;
    o.covariance = 1;
    double pl2[2] = {0, 0};
    nbt_fit_solve(2, pl2, NULL, NULL, N, line, &dl, &o, &s);
    t_rel(s.rcond, (1 - rho) / (1 + rho), 1e-10, "rcond of a straight line fit (closed form)");
    t_true(s.rank == 2 && s.covariance_ok, "full rank, covariance computed");
    t_rel(s.covariance[0], st2 / det, 1e-10, "covariance aa = sum t^2 / det");
    t_rel(s.covariance[1], -st / det, 1e-10, "covariance ab = -sum t / det");
    t_rel(s.covariance[3], N / det, 1e-10, "covariance bb = N / det");
    /* the same fit in other units (b in units of 1e-6): rcond does not change */
    data du = dl;
    for (int i = 0; i < N; i++)
        du.t[i] = dl.t[i] * 1e-6;
    double pu[2] = {0, 0};
    double rc_lin = s.rcond;
    nbt_fit_solve(2, pu, NULL, NULL, N, line, &du, &o, &s);
    t_rel(s.rcond, rc_lin, 1e-8, "rcond is independent of the parameters' units");
    /* a parameter the residuals ignore: singular, no covariance (NaN, not a pseudo-inverse) */
    du = dl;
    du.sigma = 2;
    double p3[3] = {0, 0, 0.5};
    nbt_fit_solve(3, p3, NULL, NULL, N, line, &du, &o, &s);
    t_true(s.usable && s.rcond == 0 && s.rank == 2 && !s.covariance_ok && isnan(s.covariance[8]) && isnan(s.covariance[0]),
           "an unused parameter: rcond %g, rank %d, covariance_ok %d", s.rcond, s.rank, s.covariance_ok);
    /* two parameters entering only as their sum */
    double p2[2] = {0.1, 0.2};
    nbt_fit_solve(2, p2, NULL, NULL, N, sum2, &dl, &o, &s);
    t_true(s.usable && s.rcond < 1e-15 && s.rank == 1 && !s.covariance_ok,
           "a + b only: rcond %g, rank %d, covariance_ok %d", s.rcond, s.rank, s.covariance_ok);
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
