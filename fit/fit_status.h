/* fit/fit_status.h: judging a finished fit honestly. Every fit nbt-fit
 * reports gets one status word; a fit that is not "ok" gets one line on
 * stderr naming the fit and the reason. "misfit" (the solver found a sound
 * minimum, but the shape does not fit within the data's noise) keeps its
 * numbers, with standard errors scaled by sqrt(chi^2/dof); every other
 * status is a flag: its standard errors are not printed as numbers, and
 * --strict turns it into an error (exit 2, one message, nothing written).
 * A misfit is not an error, with or without --strict. See doc/fit.md. */
#ifndef NBT_FIT_STATUS_H
#define NBT_FIT_STATUS_H

#include <stddef.h>
#include <stdio.h>
#include "ceres_shim.h"

/* In ascending precedence: when several apply, the larger one is reported. */
typedef enum {
    FIT_OK = 0,  /* converged, inside its bounds, well-conditioned, no worse than its start, fits within the noise */
    FIT_MISFIT,  /* all of that but the last: chi^2 above fit_chi2_limit (or, without noise, error above a tolerance) */
    FIT_WORSE,   /* ends with a larger error (RMS) than the model it started from */
    FIT_ILLCOND, /* J^T J singular or ill-conditioned (rcond < FIT_RCOND_MIN), or a standard error not finite */
    FIT_BOUND,   /* a parameter ended on one of the bounds the fit was given */
    FIT_NOCONV   /* the solver stopped without converging (iteration limit) */
} fit_status;

/* The column-scaled J^T J's reciprocal condition number below which the
 * covariance is not trusted: a correlation between parameters within
 * ~1e-10 of +-1, or a parameter the data barely move. */
#define FIT_RCOND_MIN 1e-10

const char *fit_status_word(fit_status s);

/* The misfit test. A fit's chi^2 = sum ((model - data)/se)^2 over n data with
 * np parameters (dof = n - np) is compared with the point that a shape which
 * does fit exceeds with probability FIT_MISFIT_P. The standard errors of
 * photon counts (nbt-fit mc) come from the spread of 64 batch means, so for
 * a shape that fits each squared residual is F(1, 63)- rather than
 * chi^2(1)-distributed (mean 63/61, variance 2.242 instead of 1 and 2); the
 * sum is taken as c chi^2(nu) with the same mean and variance (c = 1.0853,
 * nu = 0.9516 dof) and the limit is c times chi^2(nu)'s upper
 * FIT_MISFIT_P point. Per fit of a shape that fits, 1 chance in 1000 of a
 * false "misfit"; chi^2/dof at the limit: 3.12 at dof 10, 1.83 at dof 48,
 * 1.21 at dof 784. NaN when dof < 1. */
#define FIT_MISFIT_P 1e-3
#define FIT_BATCHES 64
double fit_chi2_limit(double dof);

/* FIT_MISFIT with the reason in why when st is FIT_OK and chi2 is above
 * fit_chi2_limit(dof) (rms, when finite, is quoted in the reason); else st,
 * why unchanged. */
fit_status fit_misfit(fit_status st, double chi2, double dof, double rms, char *why, size_t whylen);

/* The status of a usable fit with np parameters named names[] (for the
 * reason), solution p, the bounds it was given (NULL: none), standard errors
 * se (NULL: not computed, else NaN where they could not be; illcond also
 * where se[i] > se_max[i], se_max NULL: no limit), and its error 'after'
 * against the error 'before' of the model named start it began from (NaN:
 * not compared). The winning status's reason goes into why. */
fit_status fit_judge(const nbt_fit_summary *s, int np, const char *const *names, const double *p, const double *lo,
                     const double *hi, const double *se, const double *se_max, double before, double after,
                     const char *start, char *why, size_t whylen);

/* A growing text buffer (output held back until every fit is judged). */
typedef struct {
    char *s;
    size_t len, cap;
} fit_text;
void fit_text_add(fit_text *t, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
void fit_text_write(const fit_text *t, FILE *f);
void fit_text_free(fit_text *t);

/* The stderr report of one command: notes and flag lines, held back. */
typedef struct {
    int strict, nfits, nflagged, nmisfit; /* nflagged: neither ok nor misfit */
    char first[512]; /* the first flag line, for --strict's one message */
    fit_text log;
} fit_report;
void fit_report_init(fit_report *r, int strict);
/* Count a fit; a status other than FIT_OK adds "PROG: WHERE: WORD: WHY"
 * (FIT_MISFIT is counted in nmisfit, not as a flag). */
void fit_report_fit(fit_report *r, const char *where, fit_status st, const char *why);
void fit_report_note(fit_report *r, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
/* 1 when --strict and something was flagged (a misfit is not a flag): then one line on stderr says
 * so and the caller writes nothing and exits 2. Otherwise prints the held-back
 * lines to stderr and returns 0. Frees the log either way. */
int fit_report_finish(fit_report *r);

#endif
