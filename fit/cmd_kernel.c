/* fit/cmd_kernel.c: "nbt-fit kernel": per-plane alpha, beta of
 * Psi = alpha/r G(r/beta) fitted to photon counts (weighted by their
 * standard errors, from the moment solution), and a smooth correction of the
 * moment kernel over depth, albedo and phase width fitted to several runs. */
#include <config.h>
#include <errno.h>
#include <getopt.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include <nbt/nbt.h>
#include "../gen/cli.h"
#include "ceres_shim.h"
#include "commands.h"
#include "fit_status.h"
#include "kernel_model.h"
#include "psi_data.h"

static void help(void)
{
    puts("Usage: nbt-fit kernel MC.csv|MC.exr [MORE ...] [-o FIT.csv] [--albedo W --sigma-t ST --B B]\n"
         "                      [--shape erfc|erfc2] [--weight stderr|rms] [--loss none|huber|cauchy]\n"
         "                      [--correction OUT.txt | --apply CORR.txt] [--strict]\n\n"
         "Per plane z, fits alpha(z), beta(z) of Psi = alpha/r G(r/beta) to photon counts (nbt-fit mc\n"
         "output), averaged over each annulus as counted, weighted by the standard errors (or, with\n"
         "--weight rms, by the RMS metric's weights 2 pi r), starting\n"
         "from the moment solution (eq. 25/26). FIT.csv (default stdout): z,alpha,beta,alpha_stderr,\n"
         "beta_stderr,rms_before,rms_after,chi2_dof,status, one block per input (erfc2, a narrow plus a broad kernel,\n"
         "adds alpha2,beta2; erfc+gauss, plus a diffuse 2-D Gaussian M exp(-r^2/2s^2)/(2 pi s^2), adds\n"
         "M,s; with their errors). rms: sqrt(sum (model - mc)^2 / sum mc^2)\n"
         "of 2 pi r Psi over the plane; 'RMS FILE moment X fitted Y' lines on stderr cover all planes.\n"
         "The medium comes from an EXR's metadata or --albedo/--sigma-t/--B (Gaussian phase).\n"
         "--correction OUT.txt: fit log(beta/beta_moment) and log(alpha/alpha_moment) as polynomials in\n"
         "x = ln(sigma_t z) (and albedo a, b = ln B where the inputs differ in them) to all inputs;\n"
         "--apply CORR.txt: report the RMS of a correction on inputs it was not fitted to.\n"
         "chi2_dof: sum ((fit - mc)/stderr)^2 / (bins - parameters), whatever the weighting.\n"
         "status (also on stderr, one line per fit that is not ok): noconv (did not converge), bound (a\n"
         "parameter on a bound; widths are bounded by 100 x the plane's largest radius), illcond (J^T J\n"
         "singular or ill-conditioned, or a standard error that cannot be computed), worse (RMS above the\n"
         "moment kernel's), misfit (a sound fit, but the shape does not fit within the counting noise:\n"
         "chi2_dof above the point a shape that fits exceeds with probability 0.001), else ok; the first\n"
         "that applies, in this order. Standard errors are the spread a run with another seed would give\n"
         "(misfits included); the other flagged fits print nan. --strict: any flagged fit but a misfit is\n"
         "an error (exit 2, nothing written). Flags and misfits alike exit 0 otherwise.");
}

typedef struct {
    const psi_data *d;
    size_t j;
    double floor_se;
    int ncomp; /* 1: erfc; 2: erfc2 (alpha1, beta1, alpha2, beta2); 3: erfc+gauss (alpha, beta, M, s) */
    int rms;   /* weight by 2 pi r / sqrt(sum (2 pi r mc)^2), the RMS metric, instead of 1/stderr */
    double rms_scale;
} plane_ctx;

static int plane_res(const double *p, double *r, double *jac, void *vp)
{
    const plane_ctx *c = vp;
    const psi_data *d = c->d;
    size_t nb = d->nbins;
    int np = shape_params(c->ncomp);
    for (size_t k = 0; k < nb; k++) {
        size_t i = c->j * nb + k;
        double se = c->rms ? 1.0 / (M_PI * (d->lo[i] + d->hi[i]) * c->rms_scale)
                           : (d->se[i] > 0 ? d->se[i] : c->floor_se), g[4];
        double m = shape_annulus(c->ncomp, p, d->lo[i], d->hi[i], g);
        r[k] = (m - d->psi[i]) / se;
        if (jac)
            for (int q = 0; q < np; q++)
                jac[(size_t)np * k + (size_t)q] = g[q] / se;
    }
    return 0;
}

/* sum ((shape - mc)/se)^2 over plane j: the counts' standard errors, the floor where a bin counted nothing */
static double plane_chi2(const psi_data *d, size_t j, int ncomp, const double *p, double floor_se)
{
    double c = 0;
    for (size_t k = 0; k < d->nbins; k++) {
        size_t i = j * d->nbins + k;
        c += psi_chi2_term(d, i, floor_se, shape_annulus(ncomp, p, d->lo[i], d->hi[i], NULL));
    }
    return c;
}

/* The inverse of the n x n matrix a (n <= 4, row-major) into ai by Gauss-Jordan with partial
 * pivoting; 1 when a pivot is not above 1e-14 of the largest entry (singular for this purpose). */
static int invert(int n, const double *a, double *ai)
{
    double m[4][8], big = 0;
    for (int i = 0; i < n; i++)
        for (int c = 0; c < 2 * n; c++) {
            m[i][c] = c < n ? a[i * n + c] : (c - n == i);
            if (c < n)
                big = fmax(big, fabs(a[i * n + c]));
        }
    for (int c = 0; c < n; c++) {
        int piv = c;
        for (int i = c + 1; i < n; i++)
            if (fabs(m[i][c]) > fabs(m[piv][c]))
                piv = i;
        if (!(fabs(m[piv][c]) > 1e-14 * big))
            return 1;
        for (int q = 0; q < 2 * n; q++) {
            double t = m[c][q];
            m[c][q] = m[piv][q];
            m[piv][q] = t;
        }
        double f = 1 / m[c][c];
        for (int q = 0; q < 2 * n; q++)
            m[c][q] *= f;
        for (int i = 0; i < n; i++)
            if (i != c) {
                double g = m[i][c];
                for (int q = 0; q < 2 * n; q++)
                    m[i][q] -= g * m[c][q];
            }
    }
    for (int i = 0; i < n; i++)
        for (int c = 0; c < n; c++)
            ai[i * n + c] = m[i][n + c];
    return 0;
}

/* Standard errors of a plane's fitted parameters as the spread a new photon-counting run (another
 * seed) would give them: the fit minimises sum w_k^2 (m_k(p) - y_k)^2, so to first order
 * dp = H^-1 sum_k w_k^2 g_k (dy_k + (m_k - y_k) dw_k^2 / w_k^2)  (g = dm/dp, H = sum w_k^2 g g^T):
 * Cov = H^-1 [sum_k w_k^4 g_k g_k^T (se_k^2 + kappa (m_k - y_k)^2)] H^-1 (a sandwich).
 * The first term is the counts' own noise. The second enters with --weight stderr, whose weights
 * 1/se_k^2 are themselves estimates from 64 batches (relative variance kappa = 2/63): where the
 * shape misfits, the residuals m - y are many standard errors and the weights' noise moves the
 * solution. (Against the spread over 12 seeds at albedo 0.9, chi^2/dof 80-350, this gave 0.9-1.4
 * times the spread; (J^T J)^-1 scaled by chi^2/dof 2.6-4.5x too much, unscaled 2.4-6x too little:
 * doc/fit.md.) se[] NaN when H is singular. */
static void plane_stderr(const psi_data *d, size_t j, int ncomp, const double *p, double floor_se, int rmsw,
                         double rms_scale, double *se)
{
    int np = shape_params(ncomp);
    const double kappa = 2.0 / (FIT_BATCHES - 1);
    double H[16] = {0}, Bm[16] = {0}, Hi[16], T[16];
    for (size_t k = 0; k < d->nbins; k++) {
        size_t i = j * d->nbins + k;
        double sig = d->se[i] > 0 ? d->se[i] : floor_se, g[4];
        double w = rmsw ? M_PI * (d->lo[i] + d->hi[i]) * rms_scale : 1 / sig, w2 = w * w;
        double r = shape_annulus(ncomp, p, d->lo[i], d->hi[i], g) - d->psi[i];
        double v = w2 * w2 * (sig * sig + (rmsw ? 0 : kappa * r * r));
        for (int a = 0; a < np; a++)
            for (int b = 0; b < np; b++) {
                H[a * np + b] += w2 * g[a] * g[b];
                Bm[a * np + b] += v * g[a] * g[b];
            }
    }
    if (invert(np, H, Hi)) {
        for (int a = 0; a < np; a++)
            se[a] = NAN;
        return;
    }
    for (int a = 0; a < np; a++) /* T = Hi Bm */
        for (int b = 0; b < np; b++) {
            T[a * np + b] = 0;
            for (int c = 0; c < np; c++)
                T[a * np + b] += Hi[a * np + c] * Bm[c * np + b];
        }
    for (int a = 0; a < np; a++) { /* diag(T Hi) */
        double v = 0;
        for (int c = 0; c < np; c++)
            v += T[a * np + c] * Hi[c * np + a];
        se[a] = v > 0 ? sqrt(v) : NAN;
    }
}

/* the moment kernel of the medium at z */
static void moment_kernel(const psi_data *d, double z, double *alpha, double *beta)
{
    nbt_beam_medium m = nbt_beam_homogeneous(d->sigma_t, d->albedo, d->B);
    double M0, M2;
    nbt_beam_moments(&m, NBT_BEAM_ISHIMARU, z, &M0, &M2, NULL);
    nbt_beam_kernel_params(M0, M2, alpha, beta);
}

/* ---- the correction, fitted to all runs ---- */

typedef struct {
    psi_data *runs;
    size_t nruns;
    int active[NBT_KERNEL_CORR_TERMS];
    double *scale; /* per run: 1/sqrt(sum (2 pi r mc)^2) */
} corr_ctx;

static void unpack(const corr_ctx *c, const double *p, double *cb, double *ca)
{
    int n = 0;
    for (int i = 0; i < NBT_KERNEL_CORR_TERMS; i++)
        cb[i] = c->active[i] ? p[n++] : 0;
    for (int i = 0; i < NBT_KERNEL_CORR_TERMS; i++)
        ca[i] = c->active[i] ? p[n++] : 0;
}

static void corrected(const psi_data *d, double z, const double *cb, const double *ca, double *alpha, double *beta)
{
    nbt_kernel_correction c;
    memcpy(c.beta, cb, sizeof c.beta);
    memcpy(c.alpha, ca, sizeof c.alpha);
    nbt_beam_medium m = nbt_beam_homogeneous(d->sigma_t, d->albedo, d->B);
    nbt_kernel_corrected(&c, &m, z, alpha, beta);
}

static int corr_res(const double *p, double *r, double *jac, void *vp)
{
    (void)jac;
    const corr_ctx *c = vp;
    double cb[NBT_KERNEL_CORR_TERMS], ca[NBT_KERNEL_CORR_TERMS];
    unpack(c, p, cb, ca);
    size_t n = 0;
    for (size_t q = 0; q < c->nruns; q++) {
        const psi_data *d = &c->runs[q];
        for (size_t j = 0; j < d->nplanes; j++) {
            double a, b;
            corrected(d, d->z[j], cb, ca, &a, &b);
            for (size_t k = 0; k < d->nbins; k++) {
                size_t i = j * d->nbins + k;
                double w = M_PI * (d->lo[i] + d->hi[i]);
                r[n++] = c->scale[q] * w * (kernel_annulus(a, b, d->lo[i], d->hi[i], NULL, NULL) - d->psi[i]);
            }
        }
    }
    return 0;
}

static int write_correction(const char *path, const corr_ctx *c, const double *cb, const double *ca, const char *status)
{
    char *tmp;
    FILE *f = out_open(path, &tmp);
    if (!f)
        return 1;
    double alo = INFINITY, ahi = -INFINITY, blo = INFINITY, bhi = -INFINITY, tlo = INFINITY, thi = -INFINITY;
    for (size_t q = 0; q < c->nruns; q++) {
        const psi_data *d = &c->runs[q];
        alo = fmin(alo, d->albedo);
        ahi = fmax(ahi, d->albedo);
        blo = fmin(blo, d->B);
        bhi = fmax(bhi, d->B);
        tlo = fmin(tlo, d->sigma_t * d->z[0]);
        thi = fmax(thi, d->sigma_t * d->z[d->nplanes - 1]);
    }
    fprintf(f, "# nbt kernel correction (nbt-fit kernel --correction)\n"
               "# log(beta/beta_m) = sum beta_i t_i, log(alpha/alpha_m) = sum alpha_i t_i, alpha_m, beta_m from eq. 25/26\n"
               "# t = 1, x, x^2, a, a x, b, b x with x = ln(sigma_t z), a = albedo, b = ln B\n"
               "# fitted on %zu runs: albedo [%g, %g], B [%g, %g], sigma_t z [%g, %g]\n",
            c->nruns, alo, ahi, blo, bhi, tlo, thi);
    fprintf(f, "# fit status: %s\n", status);
    fprintf(f, "beta");
    for (int i = 0; i < NBT_KERNEL_CORR_TERMS; i++)
        fprintf(f, " %.17g", cb[i]);
    fprintf(f, "\nalpha");
    for (int i = 0; i < NBT_KERNEL_CORR_TERMS; i++)
        fprintf(f, " %.17g", ca[i]);
    fprintf(f, "\n");
    return out_close(f, tmp, path, 1);
}

static double run_rms(const psi_data *d, const double *cb, const double *ca, int use_corr)
{
    double num = 0, den = 0, a, b;
    for (size_t j = 0; j < d->nplanes; j++) {
        if (use_corr)
            corrected(d, d->z[j], cb, ca, &a, &b);
        else
            moment_kernel(d, d->z[j], &a, &b);
        kernel_rms_parts(d, j, a, b, &num, &den);
    }
    return sqrt(num / den);
}

int cmd_kernel(int argc, char **argv)
{
    static const struct option opts[] = {
        {"output", required_argument, 0, 'o'}, {"albedo", required_argument, 0, 'a'},
        {"sigma-t", required_argument, 0, 's'}, {"B", required_argument, 0, 'B'},
        {"shape", required_argument, 0, 'S'},  {"loss", required_argument, 0, 'l'},
        {"correction", required_argument, 0, 'c'}, {"apply", required_argument, 0, 'A'},
        {"weight", required_argument, 0, 'w'}, {"strict", no_argument, 0, 'T'},
        {"help", no_argument, 0, 'h'}, {0, 0, 0, 0}};
    const char *out = NULL, *corr_out = NULL, *apply = NULL;
    int ncomp = 1, rmsw = 0, strict = 0;
    double albedo = NAN, sigma_t = NAN, B = NAN;
    nbt_fit_options fo;
    nbt_fit_options_default(&fo);
    fo.analytic_jacobian = 1;
    fo.covariance = 1;
    int o;
    optind = 1;
    while ((o = getopt_long_only(argc, argv, ":o:h", opts, NULL)) != -1) {
        switch (o) {
        case 'o': out = optarg; break;
        case 'a': albedo = opt_double("--albedo", optarg, 0, 0, 1, 0); break;
        case 's': sigma_t = opt_double("--sigma-t", optarg, 0, 1, 1e12, 0); break;
        case 'B': B = opt_double("--B", optarg, 0, 1, 1e6, 0); break;
        case 'S':
            if (!strcmp(optarg, "erfc"))
                ncomp = 1;
            else if (!strcmp(optarg, "erfc2"))
                ncomp = 2;
            else if (!strcmp(optarg, "erfc+gauss"))
                ncomp = 3;
            else
                die_usage("--shape: '%s' is not accepted: erfc (alpha/r G(r/beta)), erfc2 (a sum of two) or "
                          "erfc+gauss (plus a 2-D Gaussian M exp(-r^2/2s^2)/(2 pi s^2))", optarg);
            break;
        case 'l':
            if (!strcmp(optarg, "none"))
                fo.loss = NBT_FIT_LOSS_NONE;
            else if (!strcmp(optarg, "huber"))
                fo.loss = NBT_FIT_LOSS_HUBER;
            else if (!strcmp(optarg, "cauchy"))
                fo.loss = NBT_FIT_LOSS_CAUCHY;
            else
                die_usage("--loss: '%s' is not accepted: none, huber or cauchy", optarg);
            break;
        case 'w':
            if (!strcmp(optarg, "stderr"))
                rmsw = 0;
            else if (!strcmp(optarg, "rms"))
                rmsw = 1;
            else
                die_usage("--weight: '%s' is not accepted: stderr (statistical) or rms (the RMS metric)", optarg);
            break;
        case 'c': corr_out = optarg; break;
        case 'A': apply = optarg; break;
        case 'T': strict = 1; break;
        case 'h': help(); return 0;
        default: die_bad_option(o, argv, "nbt-fit kernel");
        }
    }
    size_t nruns = (size_t)(argc - optind);
    if (nruns == 0)
        die_usage("kernel: give at least one photon-counting file (nbt-fit mc -o FILE)");
    if (corr_out && apply)
        die_usage("--correction and --apply exclude each other");
    psi_data *runs = calloc(nruns, sizeof *runs);
    if (!runs)
        die("out of memory");
    char err[512];
    for (size_t q = 0; q < nruns; q++) {
        psi_data *d = &runs[q];
        if (psi_data_read_medium(argv[optind + q], d, albedo, sigma_t, B, err, sizeof err))
            die_usage("%s", err);
        if (d->nbins < (size_t)(shape_params(ncomp) + 1))
            die_usage("%s: %zu bins per plane: this shape needs at least %d", d->name, d->nbins, shape_params(ncomp) + 1);
    }
    if (out)
        check_writable("-o", out);
    if (corr_out)
        check_writable("--correction", corr_out);
    if (apply) {
        nbt_kernel_correction kc;
        if (nbt_kernel_correction_read(apply, &kc, err, sizeof err) != NBT_OK)
            die_usage("--apply: %s", err);
        const double *cb = kc.beta, *ca = kc.alpha;
        for (size_t q = 0; q < nruns; q++)
            printf("RMS %s moment %.4f corrected %.4f\n", runs[q].name, run_rms(&runs[q], NULL, NULL, 0),
                   run_rms(&runs[q], cb, ca, 1));
        for (size_t q = 0; q < nruns; q++)
            psi_data_free(&runs[q]);
        free(runs);
        return 0;
    }
    /* everything is held back until every fit is judged: --strict writes nothing when one is flagged */
    fit_text rows = {0};
    fit_report rep;
    fit_report_init(&rep, strict);
    static const char *const names[4][4] = {{0}, {"alpha", "beta"}, {"alpha", "beta", "alpha2", "beta2"},
                                            {"alpha", "beta", "M", "s"}};
    if (ncomp == 1)
        fit_text_add(&rows, "z,alpha,beta,alpha_stderr,beta_stderr,rms_before,rms_after,chi2_dof,status\n");
    else if (ncomp == 2)
        fit_text_add(&rows, "z,alpha,beta,alpha_stderr,beta_stderr,alpha2,beta2,alpha2_stderr,beta2_stderr,rms_before,"
                            "rms_after,chi2_dof,status\n");
    else
        fit_text_add(&rows, "z,alpha,beta,alpha_stderr,beta_stderr,M,s,M_stderr,s_stderr,rms_before,rms_after,chi2_dof,"
                            "status\n");
    int rc = 0;
    for (size_t q = 0; q < nruns && rc == 0; q++) {
        psi_data *d = &runs[q];
        double nb_all = 0, na_all = 0, den_all = 0;
        int nflag = 0, nmis = 0;
        for (size_t j = 0; j < d->nplanes; j++) {
            double floor_se = psi_floor_se(d, j), rmax = 0;
            for (size_t k = 0; k < d->nbins; k++)
                rmax = fmax(rmax, d->hi[j * d->nbins + k]);
            if (isinf(floor_se))
                die_usage("%s: plane z = %g has no photons counted (all-zero histogram): cannot fit", d->name, d->z[j]);
            /* widths beyond 100 times the plane's largest radius look like beta = infinity (Psi ~ 1/r) on
             * it: the data cannot tell them apart, so a fit that runs there ends on this bound */
            double wmax = 100 * rmax;
            double p[4], lo[4] = {0, 1e-9 * d->z[j], 0, 1e-9 * d->z[j]}, hi[4] = {HUGE_VAL, wmax, HUGE_VAL, wmax};
            moment_kernel(d, d->z[j], &p[0], &p[1]);
            double a0 = p[0], b0 = p[1];
            if (!(p[0] > 0 && p[1] > 0)) { /* no scattering in theory: start from the data's scale */
                p[0] = d->psi[j * d->nbins] * d->hi[j * d->nbins];
                p[1] = 0.3 * d->z[j];
            }
            p[1] = fmin(p[1], 0.5 * wmax);
            plane_ctx pc = {d, j, floor_se, ncomp, rmsw, 0};
            {
                double n00 = 0, d00 = 0;
                kernel_rms_parts(d, j, 0, 0, &n00, &d00);
                pc.rms_scale = 1 / sqrt(d00);
            }
            nbt_fit_summary s;
            int np = shape_params(ncomp);
            /* two-part shapes have local minima: start from several splits of
             * the light (fraction f in the second part, width w times beta) */
            static const double fs[4] = {0.5, 0.2, 0.8, 0.5}, ws[4] = {2.0, 1.0, 1.0, 0.5};
            int nstart = ncomp == 1 ? 1 : 4, got = 0;
            double best[4] = {0}, bestcost = INFINITY, base[2] = {p[0], p[1]};
            nbt_fit_summary bs;
            memset(&bs, 0, sizeof bs);
            for (int t = 0; t < nstart; t++) {
                double x[4] = {base[0], base[1], 0, 0};
                if (ncomp == 2) { /* a second erfc part, broader or narrower */
                    x[0] = (1 - fs[t]) * base[0];
                    x[2] = fs[t] * base[0];
                    x[3] = ws[t] * base[1];
                } else if (ncomp == 3) { /* a diffuse Gaussian carrying fraction f of M0 */
                    x[0] = (1 - fs[t]) * base[0];
                    x[2] = fs[t] * sqrt(2 * M_PI) * base[0] * base[1];
                    x[3] = ws[t] * base[1];
                }
                x[3] = fmin(x[3], wmax);
                if (nbt_fit_solve(np, x, lo, hi, (int)d->nbins, plane_res, &pc, &fo, &s) == 0 && s.final_cost < bestcost) {
                    bestcost = s.final_cost;
                    memcpy(best, x, sizeof best);
                    bs = s;
                    got = 1;
                }
            }
            if (!got) {
                fprintf(stderr, "%s: %s: plane z = %g: the fit failed: %s (%s)\n", cli_prog, d->name, d->z[j],
                        s.termination, s.message);
                rc = 1;
                break;
            }
            memcpy(p, best, sizeof best);
            s = bs;
            /* chi^2 against the counts' standard errors at the solution, whatever the weighting and loss
             * the fit used: does the shape fit within the counting noise? */
            double dof = (double)d->nbins - np, chi2 = plane_chi2(d, j, ncomp, p, floor_se);
            /* standard errors: the spread over photon-counting runs (plane_stderr); with a robust loss,
             * which the sandwich does not model, Ceres' (J^T J)^-1 scaled by chi^2/dof where above 1 */
            double se_[4];
            if (fo.loss == NBT_FIT_LOSS_NONE && s.covariance_ok)
                plane_stderr(d, j, ncomp, p, floor_se, rmsw, pc.rms_scale, se_);
            else
                for (int e = 0; e < np; e++)
                    se_[e] = s.covariance_ok && dof > 0 ? sqrt(s.covariance[e * np + e] * fmax(1.0, chi2 / dof)) : NAN;
            double n0 = 0, d0 = 0, n1 = 0, d1 = 0;
            kernel_rms_parts(d, j, a0, b0, &n0, &d0);
            shape_rms_parts(d, j, ncomp, p, &n1, &d1);
            double rms0 = a0 > 0 && b0 > 0 ? sqrt(n0 / d0) : NAN, rms1 = sqrt(n1 / d1);
            char why[512], where[400];
            fit_status st = fit_judge(&s, np, names[ncomp], p, lo, hi, se_, NULL, rms0, rms1, "the moment kernel", why,
                                      sizeof why);
            st = fit_misfit(st, chi2, dof, rms1, why, sizeof why);
            snprintf(where, sizeof where, "%s: plane z = %g", d->name, d->z[j]);
            fit_report_fit(&rep, where, st, why);
            if (st == FIT_MISFIT)
                nmis++;
            else if (st != FIT_OK) { /* not a precise value: no standard errors */
                nflag++;
                for (int e = 0; e < np; e++)
                    se_[e] = NAN;
            }
            if (ncomp == 1)
                fit_text_add(&rows, "%.17g,%.17g,%.17g,%.17g,%.17g,%.6g,%.6g,%.4g,%s\n", d->z[j], p[0], p[1], se_[0],
                             se_[1], sqrt(n0 / d0), rms1, chi2 / dof, fit_status_word(st));
            else
                fit_text_add(&rows, "%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.6g,%.6g,%.4g,%s\n", d->z[j],
                             p[0], p[1], se_[0], se_[1], p[2], p[3], se_[2], se_[3], sqrt(n0 / d0), rms1, chi2 / dof,
                             fit_status_word(st));
            nb_all += n0;
            na_all += n1;
            den_all += d0;
        }
        if (rc == 0)
            fit_report_note(&rep, "RMS %s moment %.4f fitted %.4f (%d of %zu planes flagged, %d misfit)\n", d->name,
                            sqrt(nb_all / den_all), sqrt(na_all / den_all), nflag, d->nplanes, nmis);
    }
    double corr_b[NBT_KERNEL_CORR_TERMS], corr_a[NBT_KERNEL_CORR_TERMS];
    corr_ctx c = {runs, nruns, {1, 1, 1, 0, 0, 0, 0}, NULL};
    char corr_status[600] = "ok";
    if (rc == 0 && corr_out) {
        c.scale = calloc(nruns, sizeof(double));
        if (!c.scale)
            die("out of memory");
        size_t nres = 0;
        for (size_t q = 0; q < nruns; q++) {
            c.scale[q] = 1 / sqrt(run_rms_den(&runs[q]));
            nres += runs[q].nplanes * runs[q].nbins;
            /* albedo and width terms only where the runs differ in them */
            if (runs[q].albedo != runs[0].albedo)
                c.active[3] = c.active[4] = 1;
            if (runs[q].B != runs[0].B)
                c.active[5] = c.active[6] = 1;
        }
        double p[2 * NBT_KERNEL_CORR_TERMS] = {0};
        const char *pn[2 * NBT_KERNEL_CORR_TERMS];
        static const char *const bn[NBT_KERNEL_CORR_TERMS] = {"beta:1", "beta:x", "beta:x^2", "beta:a", "beta:a x", "beta:b", "beta:b x"},
                                 *const an[NBT_KERNEL_CORR_TERMS] = {"alpha:1", "alpha:x", "alpha:x^2", "alpha:a", "alpha:a x", "alpha:b", "alpha:b x"};
        int np = 0;
        for (int i = 0; i < NBT_KERNEL_CORR_TERMS; i++)
            if (c.active[i])
                pn[np++] = bn[i];
        for (int i = 0; i < NBT_KERNEL_CORR_TERMS; i++)
            if (c.active[i])
                pn[np++] = an[i];
        nbt_fit_options co;
        nbt_fit_options_default(&co);
        nbt_fit_summary s;
        /* p = 0 is the moment kernel: the fit starts from it */
        if (nbt_fit_solve(np, p, NULL, NULL, (int)nres, corr_res, &c, &co, &s)) {
            fprintf(stderr, "%s: the correction fit failed: %s (%s)\n", cli_prog, s.termination, s.message);
            rc = 1;
        } else {
            unpack(&c, p, corr_b, corr_a);
            /* worse: on any input, the corrected kernel's RMS above the moment kernel's */
            double before = 0, after = 0, worst = 0;
            for (size_t q = 0; q < nruns; q++) {
                double r0 = run_rms(&runs[q], NULL, NULL, 0), r1 = run_rms(&runs[q], corr_b, corr_a, 1);
                fit_report_note(&rep, "RMS %s moment %.4f corrected %.4f\n", runs[q].name, r0, r1);
                if (q == 0 || r1 - r0 > worst) {
                    worst = r1 - r0;
                    before = r0;
                    after = r1;
                }
            }
            char why[512];
            fit_status st = fit_judge(&s, np, pn, p, NULL, NULL, NULL, NULL, before, after, "the moment kernel", why, sizeof why);
            if (st == FIT_OK && s.final_cost > s.initial_cost) {
                snprintf(why, sizeof why, "its cost %.6g is above the moment kernel's %.6g", s.final_cost, s.initial_cost);
                st = FIT_WORSE;
            }
            /* within the counting noise of every bin of every run? */
            double chi2 = 0;
            for (size_t q = 0; q < nruns; q++) {
                const psi_data *d = &runs[q];
                for (size_t j = 0; j < d->nplanes; j++) {
                    double a, b, fl = psi_floor_se(d, j);
                    corrected(d, d->z[j], corr_b, corr_a, &a, &b);
                    for (size_t k = 0; k < d->nbins; k++) {
                        size_t i = j * d->nbins + k;
                        chi2 += psi_chi2_term(d, i, fl, kernel_annulus(a, b, d->lo[i], d->hi[i], NULL, NULL));
                    }
                }
            }
            st = fit_misfit(st, chi2, (double)nres - np, NAN, why, sizeof why);
            fit_report_fit(&rep, "correction", st, why);
            snprintf(corr_status, sizeof corr_status, "%s%s%s", fit_status_word(st), st == FIT_OK ? "" : ": ", why);
        }
    }
    if (rc != 0) { /* a hard failure: say what was judged so far, write nothing */
        fit_report_finish(&rep);
        fit_text_free(&rows);
    } else if (fit_report_finish(&rep)) {
        fit_text_free(&rows);
        rc = EXIT_USAGE;
    } else {
        if (out) {
            char *tmp;
            FILE *f = out_open(out, &tmp);
            if (f)
                fit_text_write(&rows, f);
            if (!f || out_close(f, tmp, out, 1)) {
                fprintf(stderr, "%s: cannot write '%s': %s\n", cli_prog, out, strerror(errno));
                rc = 1;
            }
        } else
            fit_text_write(&rows, stdout);
        fit_text_free(&rows);
        if (rc == 0 && corr_out && write_correction(corr_out, &c, corr_b, corr_a, corr_status)) {
            fprintf(stderr, "%s: cannot write '%s': %s\n", cli_prog, corr_out, strerror(errno));
            rc = 1;
        }
    }
    free(c.scale);
    for (size_t q = 0; q < nruns; q++)
        psi_data_free(&runs[q]);
    free(runs);
    return rc;
}
