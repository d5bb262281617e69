/* fit/fit_status.c: status words, the judgement of a fit, held-back output. */
#include <config.h>
#include <gsl/gsl_cdf.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "../gen/cli.h"
#include "fit_status.h"

const char *fit_status_word(fit_status s)
{
    switch (s) {
    case FIT_OK: return "ok";
    case FIT_MISFIT: return "misfit";
    case FIT_WORSE: return "worse";
    case FIT_ILLCOND: return "illcond";
    case FIT_BOUND: return "bound";
    case FIT_NOCONV: return "noconv";
    }
    return "?";
}

fit_status fit_judge(const nbt_fit_summary *s, int np, const char *const *names, const double *p, const double *lo,
                     const double *hi, const double *se, const double *se_max, double before, double after,
                     const char *start, char *why, size_t whylen)
{
    if (!s->converged) {
        snprintf(why, whylen, "did not converge (%s after %d iterations)", s->termination, s->iterations);
        return FIT_NOCONV;
    }
    if (s->nbound > 0) {
        size_t n = 0;
        why[0] = 0;
        for (int i = 0; i < np && n < whylen; i++)
            if (s->at_bound[i]) {
                double b = s->at_bound[i] < 0 ? lo[i] : hi[i];
                n += (size_t)snprintf(why + n, whylen - n, "%s%s = %.6g is on its %s bound %.6g", n ? "; " : "",
                                      names[i], p[i], s->at_bound[i] < 0 ? "lower" : "upper", b);
            }
        return FIT_BOUND;
    }
    if (!(s->rcond >= FIT_RCOND_MIN) || s->rank < np) {
        snprintf(why, whylen, "J^T J is %s (rank %d of %d, scaled rcond %.3g < %g): the data do not determine the "
                 "parameters", s->rank < np ? "singular" : "ill-conditioned", s->rank, np, s->rcond, FIT_RCOND_MIN);
        return FIT_ILLCOND;
    }
    for (int i = 0; se && i < np; i++) {
        if (!isfinite(se[i])) {
            snprintf(why, whylen, "the standard error of %s cannot be computed", names[i]);
            return FIT_ILLCOND;
        }
        if (se_max && se[i] > se_max[i]) {
            snprintf(why, whylen, "%s = %.6g has standard error %.3g > %g: the data do not determine it", names[i], p[i],
                     se[i], se_max[i]);
            return FIT_ILLCOND;
        }
    }
    if (after > before) { /* false when either is NaN */
        snprintf(why, whylen, "RMS %.4g is above the RMS %.4g of %s it started from", after, before, start);
        return FIT_WORSE;
    }
    why[0] = 0;
    return FIT_OK;
}

double fit_chi2_limit(double dof)
{
    if (!(dof >= 1))
        return NAN;
    /* one squared residual ~ F(1, d): mean d/(d - 2), variance 2 d^2 (d - 1)/((d - 2)^2 (d - 4)) */
    const double d = FIT_BATCHES - 1, m = d / (d - 2), v = 2 * d * d * (d - 1) / ((d - 2) * (d - 2) * (d - 4));
    const double c = v / (2 * m), nu = m / c; /* c chi^2(nu) has mean c nu = m and variance 2 c^2 nu = v */
    return c * gsl_cdf_chisq_Qinv(FIT_MISFIT_P, nu * dof);
}

fit_status fit_misfit(fit_status st, double chi2, double dof, double rms, char *why, size_t whylen)
{
    double lim = fit_chi2_limit(dof);
    if (st != FIT_OK || !(chi2 > lim)) /* NaN limit or chi^2: not judged */
        return st;
    int n = snprintf(why, whylen, "chi^2/dof = %.3g (dof %.0f) is above %.3g, which a shape that fits exceeds with "
                     "probability %g: the shape does not fit within the counting noise", chi2 / dof, dof, lim / dof,
                     FIT_MISFIT_P);
    if (isfinite(rms) && n > 0 && (size_t)n < whylen)
        snprintf(why + n, whylen - (size_t)n, " (RMS %.4g)", rms);
    return FIT_MISFIT;
}

static void text_vadd(fit_text *t, const char *fmt, va_list ap)
{
    va_list aq;
    va_copy(aq, ap);
    int n = vsnprintf(NULL, 0, fmt, aq);
    va_end(aq);
    if (n < 0)
        return;
    if (t->len + (size_t)n + 1 > t->cap) {
        size_t cap = 2 * (t->len + (size_t)n + 1);
        char *s = realloc(t->s, cap);
        if (!s)
            die("out of memory");
        t->s = s;
        t->cap = cap;
    }
    vsnprintf(t->s + t->len, t->cap - t->len, fmt, ap);
    t->len += (size_t)n;
}

void fit_text_add(fit_text *t, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    text_vadd(t, fmt, ap);
    va_end(ap);
}

void fit_text_write(const fit_text *t, FILE *f)
{
    if (t->len)
        fwrite(t->s, 1, t->len, f);
}

void fit_text_free(fit_text *t)
{
    free(t->s);
    memset(t, 0, sizeof *t);
}

void fit_report_init(fit_report *r, int strict)
{
    memset(r, 0, sizeof *r);
    r->strict = strict;
}

void fit_report_fit(fit_report *r, const char *where, fit_status st, const char *why)
{
    r->nfits++;
    if (st == FIT_OK)
        return;
    if (st == FIT_MISFIT)
        r->nmisfit++;
    else if (r->nflagged++ == 0)
        snprintf(r->first, sizeof r->first, "%s: %s: %s", where, fit_status_word(st), why);
    fit_text_add(&r->log, "%s: %s: %s: %s\n", cli_prog, where, fit_status_word(st), why);
}

void fit_report_note(fit_report *r, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    text_vadd(&r->log, fmt, ap);
    va_end(ap);
}

int fit_report_finish(fit_report *r)
{
    int fail = r->strict && r->nflagged > 0;
    if (fail)
        fprintf(stderr, "%s: --strict: %d of %d fits flagged, nothing written; the first: %s\n", cli_prog, r->nflagged,
                r->nfits, r->first);
    else
        fit_text_write(&r->log, stderr);
    fit_text_free(&r->log);
    return fail;
}
