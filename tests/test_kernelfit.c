/* tests/test_kernelfit.c: the fitted shapes' annulus means (against direct
 * quadrature of the shape), their analytic derivatives (against central
 * differences), exact recovery of known parameters through the shim, and
 * the judgement of fits (fit_status): a good fit is ok with standard errors
 * that match the scatter of a parametric bootstrap; a shape that cannot
 * follow the data is a misfit, and the misfit limit's false-alarm rate is
 * measured by Monte Carlo; an unidentifiable width or an empty plane is
 * flagged; the statuses' precedence. */
#include <gsl/gsl_cdf.h>
#include <gsl/gsl_randist.h>
#include <gsl/gsl_rng.h>
#include <math.h>
#include <string.h>
#include <nbt/nbt.h>
#include "../fit/ceres_shim.h"
#include "../fit/fit_status.h"
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

/* the annulus mean of the shape by quadrature, to make synthetic data that do
 * not come from the model's own closed form (kernel_annulus, gauss_annulus) */
static double ann_ref(double alpha, double beta, double M, double s, double lo, double hi)
{
    nbt_quad_ws *ws = nbt_quad_ws_alloc(1, 500);
    shp c = {alpha, beta, M, s};
    double v = NAN, e;
    nbt_quad_gk(ws, integrand, &c, 1, lo, hi, 0, 1e-14, &v, &e);
    nbt_quad_ws_free(ws);
    return v / (M_PI * (hi * hi - lo * lo));
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

/* one plane as nbt-fit kernel fits it: erfc annulus means, residuals (m - y)/sigma */
#define NP 20
typedef struct {
    double lo[NP], hi[NP], y[NP], sig[NP];
} plane;
static int plane_res(const double *p, double *r, double *jac, void *vp)
{
    const plane *d = vp;
    for (int k = 0; k < NP; k++) {
        double da, db;
        r[k] = (kernel_annulus(p[0], p[1], d->lo[k], d->hi[k], &da, &db) - d->y[k]) / d->sig[k];
        if (jac) {
            jac[2 * k] = da / d->sig[k];
            jac[2 * k + 1] = db / d->sig[k];
        }
    }
    return 0;
}

static double t_normal(void)
{
    double u1 = t_uniform(), u2 = t_uniform();
    return sqrt(-2 * log(1 - u1)) * cos(2 * M_PI * u2);
}

/* fit one plane with cmd_kernel's bounds (widths <= 100 x the largest radius); standard errors
 * (J^T J)^-1 (the noise is known here: no weights to estimate); the status from fit_judge, then
 * fit_misfit on chi^2 (known sigma: the residuals are the fit's own) */
static fit_status fit_plane(const plane *d, double a0, double b0, double *p, double *se, char *why)
{
    static const char *const names[2] = {"alpha", "beta"};
    double lo[2] = {0, 1e-9}, hi[2] = {HUGE_VAL, 100 * d->hi[NP - 1]};
    nbt_fit_options o;
    nbt_fit_options_default(&o);
    o.analytic_jacobian = 1;
    o.covariance = 1;
    nbt_fit_summary s;
    p[0] = a0;
    p[1] = b0;
    if (nbt_fit_solve(2, p, lo, hi, NP, plane_res, (void *)d, &o, &s) != 0)
        return FIT_NOCONV;
    for (int e = 0; e < 2; e++)
        se[e] = s.covariance_ok ? sqrt(s.covariance[3 * e]) : NAN;
    fit_status st = fit_judge(&s, 2, names, p, lo, hi, se, NULL, NAN, NAN, "the start", why, 512);
    return fit_misfit(st, 2 * s.final_cost, NP - 2, NAN, why, 512);
}

static void judge_checks(void)
{
    /* a good plane: alpha/r G(r/beta) within r < 2, 3% Gaussian noise per annulus (known sigma) */
    const double A = 0.37, Bt = 0.61;
    plane d;
    double truth[NP];
    for (int k = 0; k < NP; k++) {
        d.lo[k] = 0.1 * k;
        d.hi[k] = 0.1 * (k + 1);
        truth[k] = ann_ref(A, Bt, 0, 1, d.lo[k], d.hi[k]);
        d.sig[k] = 0.03 * truth[k];
    }
    /* parametric bootstrap: 400 noisy copies; the spread of the fitted values
     * against the mean reported standard error (sampling error of an SD from
     * 400 draws: 3.5%; the chi^2/dof >= 1 scaling adds a few % upwards) */
    enum { R = 400 };
    double sa = 0, sa2 = 0, sb = 0, sb2 = 0, ea = 0, eb = 0;
    int nok = 0, nmis = 0;
    char why[512];
    for (int rep = 0; rep < R; rep++) {
        for (int k = 0; k < NP; k++)
            d.y[k] = truth[k] + d.sig[k] * t_normal();
        double p[2], se[2];
        fit_status st = fit_plane(&d, 0.5 * A, 2 * Bt, p, se, why);
        nmis += st == FIT_MISFIT;
        if (st != FIT_OK || !isfinite(se[0]) || !isfinite(se[1]))
            continue;
        nok++;
        sa += p[0];
        sa2 += p[0] * p[0];
        sb += p[1];
        sb2 += p[1] * p[1];
        ea += se[0];
        eb += se[1];
    }
    /* the shape that made the data fits them: chi^2(18) exceeds the misfit limit with probability
     * below 1e-3 (the limit allows for estimated errors), so of 400 fits at most 0.4 are expected
     * misfits; 3 or more would happen with probability < 0.008 */
    t_true(nok + nmis == R && nmis <= 2, "a good plane: all %d bootstrap fits ok with finite standard errors "
           "(%d ok, %d misfit)", R, nok, nmis);
    double sda = sqrt((sa2 - sa * sa / nok) / (nok - 1)), sdb = sqrt((sb2 - sb * sb / nok) / (nok - 1));
    t_rel(sda / (ea / nok), 1, 0.15, "alpha: bootstrap spread %.4g vs mean standard error %.4g", sda, ea / nok);
    t_rel(sdb / (eb / nok), 1, 0.15, "beta: bootstrap spread %.4g vs mean standard error %.4g", sdb, eb / nok);
    t_rel(sa / nok, A, 3 * sda / sqrt(nok) / A, "alpha unbiased");
    t_rel(sb / nok, Bt, 3 * sdb / sqrt(nok) / Bt + 0.002, "beta unbiased within 0.2%%");

    /* a shape that cannot follow the data: erfc fitted to erfc plus a diffuse Gaussian carrying 40% of the
     * light (s = 0.5), 3% noise: misfit, with chi^2/dof in the reason, every time (20 noise draws) */
    {
        int nm = 0;
        for (int rep = 0; rep < 20; rep++) {
            for (int k = 0; k < NP; k++) {
                double t = ann_ref(A, Bt, 0.4 * sqrt(2 * M_PI) * A * Bt, 0.5, d.lo[k], d.hi[k]);
                d.sig[k] = 0.03 * t;
                d.y[k] = t + d.sig[k] * t_normal();
            }
            double p[2], se[2];
            fit_status st = fit_plane(&d, A, Bt, p, se, why);
            nm += st == FIT_MISFIT && strstr(why, "chi^2/dof = ") && strstr(why, "(dof 18) is above 2.47");
        }
        t_true(nm == 20, "erfc fitted to erfc + Gaussian: 20 of 20 misfit (%d; the last: %s)", nm, why);
    }
    /* the misfit limit against Monte Carlo: with standard errors from 64 batch means each squared
     * residual of a fitting shape is t(63)^2; sums of dof of them exceed fit_chi2_limit(dof) with
     * probability FIT_MISFIT_P = 1e-3 up to the moment-matching approximation (measured 0.8-1.3e-3 for
     * dof 2-48), accepted within [0.7, 1.5] x 1e-3; the plain chi^2(dof) 0.1% point, which forgets that
     * the errors are estimates, is exceeded 2.0e-3 (dof 10) and 2.5e-3 (dof 48) of the time. Draws:
     * 2e5 each (expected about 200-260 exceedances: Poisson error 6-7%). */
    {
        gsl_rng *g = gsl_rng_alloc(gsl_rng_mt19937);
        gsl_rng_set(g, 2385);
        static const int dofs[2] = {10, 48};
        static const long ndraw[2] = {200000, 200000};
        for (int q = 0; q < 2; q++) {
            double lim = fit_chi2_limit(dofs[q]);
            long hit = 0;
            for (long n = 0; n < ndraw[q]; n++) {
                double sum = 0;
                for (int k = 0; k < dofs[q]; k++) {
                    double z = gsl_ran_ugaussian(g);
                    sum += z * z / (gsl_ran_chisq(g, FIT_BATCHES - 1) / (FIT_BATCHES - 1));
                }
                hit += sum > lim;
            }
            double rate = (double)hit / (double)ndraw[q];
            t_true(rate >= 0.7e-3 && rate <= 1.5e-3, "dof %d: sums of t(63)^2 above the misfit limit %.4g at rate %.3g "
                   "(want 1e-3; the plain chi^2 point is %.4g)", dofs[q], lim, rate, gsl_cdf_chisq_Qinv(1e-3, dofs[q]));
        }
        gsl_rng_free(g);
        t_true(isnan(fit_chi2_limit(0.5)), "no misfit limit below 1 dof");
    }
    /* beta not identifiable: the data are alpha/(2r) (beta = infinity), the fit runs to the width bound */
    for (int k = 0; k < NP; k++) {
        d.y[k] = ann_ref(A, 1e12, 0, 1, d.lo[k], d.hi[k]);
        d.sig[k] = 0.03 * d.y[k];
        d.y[k] += d.sig[k] * t_normal();
    }
    double p[2], se[2];
    fit_status st = fit_plane(&d, A, Bt, p, se, why);
    t_true(st == FIT_BOUND && strstr(why, "beta") && strstr(why, "upper"), "Psi ~ 1/r: flagged bound (%s: %s)",
           fit_status_word(st), why);
    /* an almost empty plane: a handful of counts in one annulus, the rest zero with the floor error */
    for (int k = 0; k < NP; k++) {
        d.y[k] = k == 13 ? 0.02 : 0;
        d.sig[k] = 0.02;
    }
    st = fit_plane(&d, A, Bt, p, se, why);
    t_true(st != FIT_OK, "an almost empty plane: flagged (%s: %s)", fit_status_word(st), why);

    /* precedence: noconv > bound > illcond > worse > misfit > ok */
    static const char *const nm[2] = {"a", "b"};
    double lo[2] = {0, 0}, hi[2] = {1, 1}, q[2] = {0.5, 1}, ok_se[2] = {0.1, 0.1}, nan_se[2] = {0.1, NAN};
    nbt_fit_summary s;
    memset(&s, 0, sizeof s);
    s.converged = 1;
    s.rcond = 0.3;
    s.rank = 2;
    t_true(fit_judge(&s, 2, nm, q, lo, hi, ok_se, NULL, 0.2, 0.1, "x", why, sizeof why) == FIT_OK, "judge: ok");
    t_true(fit_judge(&s, 2, nm, q, lo, hi, ok_se, NULL, NAN, 0.1, "x", why, sizeof why) == FIT_OK, "judge: no start error: ok");
    t_true(fit_judge(&s, 2, nm, q, lo, hi, ok_se, NULL, 0.1, 0.2, "x", why, sizeof why) == FIT_WORSE, "judge: worse");
    t_true(fit_misfit(FIT_WORSE, 1e6, 10, NAN, why, sizeof why) == FIT_WORSE && fit_misfit(FIT_BOUND, 1e6, 10, NAN, why, sizeof why) == FIT_BOUND,
           "judge: worse and bound beat misfit");
    {
        double l10 = fit_chi2_limit(10);
        t_true(fit_misfit(FIT_OK, 0.999 * l10, 10, NAN, why, sizeof why) == FIT_OK &&
                   fit_misfit(FIT_OK, 1.001 * l10, 10, 0.123, why, sizeof why) == FIT_MISFIT && strstr(why, "RMS 0.123") &&
                   fit_misfit(FIT_OK, 1e9, 0, NAN, why, sizeof why) == FIT_OK && fit_misfit(FIT_OK, NAN, 10, NAN, why, sizeof why) == FIT_OK,
               "judge: misfit just above the limit only, not without dof or chi^2 (%s)", why);
        /* a misfit is reported but is not a flag: --strict passes it */
        fit_report r;
        fit_report_init(&r, 1);
        fit_report_fit(&r, "here", FIT_MISFIT, "why");
        fit_report_fit(&r, "there", FIT_OK, "");
        t_true(r.nmisfit == 1 && r.nflagged == 0 && r.log.len > 0 && fit_report_finish(&r) == 0, "--strict passes a misfit");
        fit_report_init(&r, 1);
        fit_report_fit(&r, "here", FIT_MISFIT, "why");
        fit_report_fit(&r, "there", FIT_WORSE, "why");
        t_true(r.nflagged == 1 && !strncmp(r.first, "there: worse", 12) && fit_report_finish(&r) == 1, "--strict fails on worse");
    }
    double se_max[2] = {1, 0.05};
    t_true(fit_judge(&s, 2, nm, q, lo, hi, ok_se, se_max, 0.2, 0.1, "x", why, sizeof why) == FIT_ILLCOND,
           "judge: a standard error above its limit: illcond (%s)", why);
    t_true(fit_judge(&s, 2, nm, q, lo, hi, nan_se, NULL, 0.1, 0.2, "x", why, sizeof why) == FIT_ILLCOND,
           "judge: NaN standard error beats worse: illcond");
    s.rcond = 1e-12;
    t_true(fit_judge(&s, 2, nm, q, lo, hi, ok_se, NULL, 0.1, 0.2, "x", why, sizeof why) == FIT_ILLCOND,
           "judge: rcond 1e-12: illcond");
    s.rcond = 0.3;
    s.rank = 1;
    t_true(fit_judge(&s, 2, nm, q, lo, hi, ok_se, NULL, 0.1, 0.2, "x", why, sizeof why) == FIT_ILLCOND, "judge: rank 1: illcond");
    s.at_bound[1] = 1;
    s.nbound = 1;
    t_true(fit_judge(&s, 2, nm, q, lo, hi, nan_se, NULL, 0.1, 0.2, "x", why, sizeof why) == FIT_BOUND && strstr(why, "b = 1"),
           "judge: bound beats illcond and worse (%s)", why);
    s.converged = 0;
    t_true(fit_judge(&s, 2, nm, q, lo, hi, nan_se, NULL, 0.1, 0.2, "x", why, sizeof why) == FIT_NOCONV, "judge: noconv first");
    t_true(!strcmp(fit_status_word(FIT_OK), "ok") && !strcmp(fit_status_word(FIT_BOUND), "bound") &&
               !strcmp(fit_status_word(FIT_NOCONV), "noconv") && !strcmp(fit_status_word(FIT_ILLCOND), "illcond") &&
               !strcmp(fit_status_word(FIT_WORSE), "worse") && !strcmp(fit_status_word(FIT_MISFIT), "misfit"),
           "status words");
}

typedef struct {
    const double *p;
} pctx;
/* 2 pi r Psi_hat(r) of the fitted model's point evaluation */
static int pexp_f(double r, void *vp, unsigned fdim, double *f)
{
    (void)fdim;
    f[0] = 2 * M_PI * r * nbt_beam_fit_eval(((const pctx *)vp)->p, r);
    return 0;
}

int main(void)
{
    judge_checks();
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
    /* the fitted model's diffuse part (nbt-fit model): the annulus formula equals the quadrature of
     * libnbt's point evaluation (nbt_beam_fit_eval, core switched off), and its derivatives the
     * central differences, from nearly exponential (h << s) to nearly Gaussian (h >> s) */
    {
        static const double sh[3][2] = {{0.8, 0.01}, {0.8, 0.9}, {0.3, 40}};
        nbt_quad_ws *w2 = nbt_quad_ws_alloc(1, 500);
        for (int i = 0; i < 3; i++) {
            double p[NBT_BEAM_FIT_PARTS] = {0, 0, 0.43, sh[i][0], sh[i][1]}, dM, dS, dH, q, qe;
            pctx pc = {p};
            for (int j = 0; j < 2; j++) {
                double a = j ? 0.0 : 0.35, b = j ? 0.2 : 1.7;
                nbt_quad_gk(w2, pexp_f, &pc, 1, a, b, 0, 1e-13, &q, &qe);
                t_rel(pexp_annulus(p[2], p[3], p[4], a, b, NULL, NULL, NULL), q / (M_PI * (b * b - a * a)), 1e-10,
                      "diffuse part s %g h %g on [%g, %g]: annulus mean = quadrature of nbt_beam_fit_eval", p[3], p[4], a, b);
            }
            pexp_annulus(p[2], p[3], p[4], lo, hi, &dM, &dS, &dH);
            double hs = 1e-5 * p[3], hh = 1e-4 * p[4]; /* steps where roundoff and truncation are both below 1e-7 */
            t_rel(dM, (pexp_annulus(p[2] + h, p[3], p[4], lo, hi, NULL, NULL, NULL) - pexp_annulus(p[2] - h, p[3], p[4], lo, hi, NULL, NULL, NULL)) / (2 * h), 1e-7, "  d/dM");
            t_rel(dS, (pexp_annulus(p[2], p[3] + hs, p[4], lo, hi, NULL, NULL, NULL) - pexp_annulus(p[2], p[3] - hs, p[4], lo, hi, NULL, NULL, NULL)) / (2 * hs), 1e-6, "  d/ds");
            t_rel(dH, (pexp_annulus(p[2], p[3], p[4] + hh, lo, hi, NULL, NULL, NULL) - pexp_annulus(p[2], p[3], p[4] - hh, lo, hi, NULL, NULL, NULL)) / (2 * hh), 1e-6, "  d/dh");
        }
        nbt_quad_ws_free(w2);
    }
    /* noise-free synthetic data: the parameters come back to 1e-8 */
    syn d;
    for (int k = 0; k < NB; k++) {
        d.lo[k] = 0.25 * k;
        d.hi[k] = 0.25 * (k + 1);
        d.y[k] = ann_ref(c.alpha, c.beta, c.M, c.s, d.lo[k], d.hi[k]);
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
