/* fit/ceres_shim.h: a small C interface to Ceres' bounded nonlinear least
 * squares, the only C++ in nbt. Nothing is printed; C++ exceptions are
 * caught at the boundary and reported in the summary. */
#ifndef NBT_CERES_SHIM_H
#define NBT_CERES_SHIM_H

#ifdef __cplusplus
extern "C" {
#endif

/* Residuals r[0..nres-1] at params p[0..np-1]; when jac != NULL also the
 * Jacobian, row-major nres x np (jac[i*np + j] = dr_i/dp_j). Return 0 on
 * success, non-zero to stop the solve (reported as a failure). */
typedef int (*nbt_fit_residual_fn)(const double *p, double *r, double *jac, void *data);

typedef enum { NBT_FIT_LOSS_NONE, NBT_FIT_LOSS_HUBER, NBT_FIT_LOSS_CAUCHY, NBT_FIT_LOSS_SOFT_L1 } nbt_fit_loss;

typedef struct {
    int max_iterations;         /* default 200 */
    double function_tolerance;  /* default 1e-12 */
    double gradient_tolerance;  /* default 1e-12 */
    double parameter_tolerance; /* default 1e-12 */
    int threads;                /* default 1 */
    nbt_fit_loss loss;          /* default none */
    double loss_scale;          /* default 1 */
    int analytic_jacobian;      /* 1: f fills jac; 0: central differences (default) */
    int covariance;             /* 1: fill summary.covariance ((J^T J)^-1 at the solution) when J^T J has full rank */
    /* optional per-iteration callback (iteration, cost), e.g. for a log on stderr */
    void (*progress)(int iteration, double cost, void *data);
    void *progress_data;
} nbt_fit_options;

#define NBT_FIT_MAX_PARAMS 96

typedef struct {
    int usable;                 /* 1: converged, or stopped at a usable point */
    int converged;
    int iterations;
    double initial_cost, final_cost;  /* 1/2 sum r^2 */
    char termination[32];       /* CONVERGENCE, NO_CONVERGENCE, FAILURE, USER_FAILURE, EXCEPTION, BAD_INPUT */
    char message[256];
    /* At a usable solution (else rcond NaN, rank 0): J^T J (J with the loss
     * applied, as Ceres evaluates it) with its columns scaled to unit norm,
     * which makes it independent of the parameters' units: the reciprocal
     * of its 2-norm condition number (1: orthogonal columns, 0: singular; a
     * zero column gives 0) and its numerical rank (eigenvalues above
     * np * DBL_EPSILON times the largest). */
    double rcond;
    int rank;
    /* Parameters on a bound: -1 at the lower, +1 at the upper, 0 inside;
     * "on" means within 1e-8 max(|bound|, |start value|). nbound counts them. */
    signed char at_bound[NBT_FIT_MAX_PARAMS];
    int nbound;
    /* With options.covariance: (J^T J)^-1, row-major np x np, when J^T J
     * has full rank (covariance_ok 1); otherwise covariance_ok 0 and NaNs:
     * never a pseudo-inverse, which would report 0 variance along the
     * directions the data do not constrain. */
    int covariance_ok;
    double covariance[NBT_FIT_MAX_PARAMS * NBT_FIT_MAX_PARAMS];
} nbt_fit_summary;

void nbt_fit_options_default(nbt_fit_options *o);

/* Minimise 1/2 sum rho(r_i^2) over p (np <= NBT_FIT_MAX_PARAMS, in/out),
 * with optional bounds lower/upper (NULL: none; +-HUGE_VAL entries: none).
 * Returns 0 when the summary is usable, non-zero otherwise. */
int nbt_fit_solve(int np, double *p, const double *lower, const double *upper, int nres, nbt_fit_residual_fn f,
                  void *data, const nbt_fit_options *o, nbt_fit_summary *s);

#ifdef __cplusplus
}
#endif
#endif
