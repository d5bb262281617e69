/* fit/cmd_phase.c: "nbt-fit phase": a sum of K Gaussian lobes (the phase
 * function of Shinya et al. eq. 13 on the sphere) fitted to a phase function. */
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

#define MAXK 16
#define NPANEL 8
#define PNODES 16
#define NNODE (NPANEL * PNODES)

static void help(void)
{
    puts("Usage: nbt-fit phase --target SPEC --terms K [-o SOG.txt] [--against MC.exr] [--tol EPS] [--strict]\n\n"
         "Fits w_1..w_K >= 0 (sum 1) and B_1..B_K > 0 of p = sum w_i p_G(B_i), p_G the Gaussian\n"
         "phase function of Shinya et al. eq. 13 on the sphere (as nbt's photon counter samples it),\n"
         "to the target (iso, rayleigh, hg:g=G, gauss:B=B, table:FILE, sog:FILE), 1e-6 <= B <= 1e3,\n"
         "minimising the L2\n"
         "error over the sphere relative to the target's norm, ||p_K - p|| / ||p||. Prints that error\n"
         "for every K' = 1..K (each fit starts from the previous one). SOG.txt has lines 'w B' and is\n"
         "accepted wherever a phase SPEC is, as sog:SOG.txt.\n"
         "--against MC.exr (photon counts from nbt-fit mc, whose metadata names the medium): the\n"
         "narrow-beam moment kernel depends on the lobes only through B_mix = sum w_i B_i, so all\n"
         "widths are scaled by one factor to make it match the counts best (RMS of 2 pi r Psi);\n"
         "the RMS before and after is printed and the scaled lobes are written.\n"
         "Each fit is judged (status on its line, and in SOG.txt; a line on stderr when not ok): noconv\n"
         "(did not converge), bound (a weight or width on its bound), illcond (J^T J singular or\n"
         "ill-conditioned: redundant lobes), worse (error above its start's), misfit (a sound fit whose\n"
         "error is above --tol EPS, default 0.01: a target without noise has no chi^2, so the tolerance\n"
         "stands in for it; --against: the moment kernel outside the counts' noise, chi^2/dof above its\n"
         "0.1% point), else ok; the first that applies, in this order. --strict: any flagged fit but a\n"
         "misfit is an error (exit 2, nothing written); a misfit is reported and exits 0.");
}

typedef struct {
    int K;
    double th[NNODE], w[NNODE], target[NNODE], norm;
} phase_ctx;

static double lobe(double B, double th)
{
    double ratio = th < 1e-4 ? 1 + th * th / 6 : th / sin(th);
    return ratio * exp(-th * th / (4 * B)) / (4 * M_PI * B * -expm1(-M_PI * M_PI / (4 * B)));
}

/* p = (u_1..u_{K-1}, v_1..v_K): w = softmax(0, u), B = exp(v) */
static void params_to_sog(int K, const double *p, double *w, double *B)
{
    double m = 0, s = 0;
    for (int i = 1; i < K; i++)
        m = fmax(m, p[i - 1]);
    for (int i = 0; i < K; i++) {
        w[i] = exp((i == 0 ? 0 : p[i - 1]) - m);
        s += w[i];
        B[i] = exp(p[K - 1 + i]);
    }
    for (int i = 0; i < K; i++)
        w[i] /= s;
}

static int phase_res(const double *p, double *r, double *jac, void *vp)
{
    (void)jac;
    const phase_ctx *c = vp;
    double w[MAXK], B[MAXK];
    params_to_sog(c->K, p, w, B);
    for (int n = 0; n < NNODE; n++) {
        double v = 0;
        for (int i = 0; i < c->K; i++)
            v += w[i] * lobe(B[i], c->th[n]);
        r[n] = (v - c->target[n]) * c->w[n] / c->norm;
    }
    return 0;
}

static double fit_error(phase_ctx *c, const double *p)
{
    double r[NNODE], s = 0;
    phase_res(p, r, NULL, c);
    for (int n = 0; n < NNODE; n++)
        s += r[n] * r[n];
    return sqrt(s);
}

/* --against MC: the moment kernel depends on the lobes only through
 * B_mix = sum w_i B_i (eq. 26 is linear in B), so the narrow-beam prediction
 * is matched to photon counts by scaling every width by one factor c. */
typedef struct {
    const psi_data *d;
    int K;
    const double *w, *B;
    double scale;
} against_ctx;

static double against_rms(const against_ctx *c, double factor, double *num_out)
{
    nbt_beam_medium m = nbt_beam_homogeneous(c->d->sigma_t, c->d->albedo, 1.0);
    m.nlobes = (size_t)c->K;
    for (int i = 0; i < c->K; i++) {
        m.w[i] = c->w[i];
        m.B[i] = factor * c->B[i];
    }
    double num = 0, den = 0;
    for (size_t j = 0; j < c->d->nplanes; j++) {
        double M0, M2, a, b;
        nbt_beam_moments(&m, NBT_BEAM_ISHIMARU, c->d->z[j], &M0, &M2, NULL);
        nbt_beam_kernel_params(M0, M2, &a, &b);
        kernel_rms_parts(c->d, j, a, b, &num, &den);
    }
    if (num_out)
        *num_out = num;
    return sqrt(num / den);
}

/* sum ((Psi - mc)/se)^2 over the counts for widths scaled by factor */
static double against_chi2(const against_ctx *c, double factor)
{
    nbt_beam_medium m = nbt_beam_homogeneous(c->d->sigma_t, c->d->albedo, 1.0);
    m.nlobes = (size_t)c->K;
    for (int i = 0; i < c->K; i++) {
        m.w[i] = c->w[i];
        m.B[i] = factor * c->B[i];
    }
    double chi2 = 0;
    for (size_t j = 0; j < c->d->nplanes; j++) {
        double M0, M2, a, b, fl = psi_floor_se(c->d, j);
        nbt_beam_moments(&m, NBT_BEAM_ISHIMARU, c->d->z[j], &M0, &M2, NULL);
        nbt_beam_kernel_params(M0, M2, &a, &b);
        for (size_t k = 0; k < c->d->nbins; k++) {
            size_t i = j * c->d->nbins + k;
            chi2 += psi_chi2_term(c->d, i, fl, a > 0 && b > 0 ? kernel_annulus(a, b, c->d->lo[i], c->d->hi[i], NULL, NULL) : 0);
        }
    }
    return chi2;
}

static int against_res(const double *p, double *r, double *jac, void *vp)
{
    (void)jac;
    const against_ctx *c = vp;
    double num;
    against_rms(c, exp(p[0]), &num);
    r[0] = sqrt(num) * c->scale;
    return 0;
}

/* the photon counts of --against, read (and judged) before any fit */
static void read_against(const char *path, psi_data *d)
{
    char err[512];
    if (psi_data_read(path, d, err, sizeof err))
        die_usage("--against: %s", err);
    if (isnan(d->albedo) || isnan(d->sigma_t))
        die_usage("--against: %s does not name its medium (use an EXR written by nbt-fit mc)", path);
}

static int refit_against(const char *path, psi_data *dp, int K, double *w, double *B, fit_report *rep, fit_text *txt,
                         char *status, size_t statuslen)
{
    against_ctx c = {dp, K, w, B, 1};
    double before = against_rms(&c, 1, NULL), num;
    against_rms(&c, 1, &num);
    c.scale = 1 / sqrt(num);
    double p[1] = {0}, lo[1] = {log(1e-3)}, hi[1] = {log(1e3)};
    nbt_fit_options fo;
    nbt_fit_options_default(&fo);
    nbt_fit_summary s;
    /* a 1-D problem: bracket the factor on a log grid, then refine */
    double bestf = 0, bestr = before;
    for (double lf = -3; lf <= 3.0001; lf += 0.25) {
        double rr = against_rms(&c, exp(lf), NULL);
        if (rr < bestr) {
            bestr = rr;
            bestf = lf;
        }
    }
    p[0] = bestf;
    if (nbt_fit_solve(1, p, lo, hi, 1, against_res, &c, &fo, &s) != 0) {
        fprintf(stderr, "%s: --against: the refit failed: %s (%s)\n", cli_prog, s.termination, s.message);
        return 1;
    }
    double f = exp(p[0]), after = against_rms(&c, f, NULL);
    /* judged against the moment kernel with the fitted lobes (factor 1); a factor on
     * its bound (1e-3 or 1e3) means the counts want widths beyond what is allowed */
    static const char *const names[1] = {"ln(factor)"};
    char why[512];
    fit_status st = fit_judge(&s, 1, names, p, lo, hi, NULL, NULL, before, after, "the moment kernel with the fitted lobes", why,
                              sizeof why);
    if (after > bestr) { /* keep the grid's best if the local refinement wandered */
        f = exp(bestf);
        after = bestr;
    }
    /* the moment kernel with these lobes against the counts' noise (one parameter fitted) */
    double dof = (double)(dp->nplanes * dp->nbins) - 1;
    st = fit_misfit(st, against_chi2(&c, f), dof, after, why, sizeof why);
    char where[600];
    snprintf(where, sizeof where, "phase --against %s", path);
    fit_report_fit(rep, where, st, why);
    snprintf(status, statuslen, "%s", fit_status_word(st));
    fit_text_add(txt, "against %s: moment-kernel RMS %.4f with the fitted lobes, %.4f with widths x %.4g status %s\n", path,
                 before, after, f, fit_status_word(st));
    for (int i = 0; i < K; i++)
        B[i] *= f;
    return 0;
}

int cmd_phase(int argc, char **argv)
{
    static const struct option opts[] = {{"target", required_argument, 0, 't'}, {"terms", required_argument, 0, 'k'},
                                         {"output", required_argument, 0, 'o'}, {"against", required_argument, 0, 'a'},
                                         {"strict", no_argument, 0, 'T'},       {"tol", required_argument, 0, 'e'},
                                         {"help", no_argument, 0, 'h'},         {0, 0, 0, 0}};
    const char *target = NULL, *out = NULL, *against = NULL;
    int K = 0, o, strict = 0;
    double tol = 0.01;
    optind = 1;
    while ((o = getopt_long_only(argc, argv, ":o:h", opts, NULL)) != -1) {
        switch (o) {
        case 't': target = optarg; break;
        case 'k': K = (int)opt_long("--terms", optarg, 1, MAXK); break;
        case 'o': out = optarg; break;
        case 'a': against = optarg; break;
        case 'T': strict = 1; break;
        case 'e': tol = opt_double("--tol", optarg, 0, 1, 1, 1); break;
        case 'h': help(); return 0;
        default: die_bad_option(o, argv, "nbt-fit phase");
        }
    }
    if (optind < argc)
        die_usage("phase: unexpected argument '%s'", argv[optind]);
    if (!target || K == 0)
        die_usage("phase: --target SPEC and --terms K are required");
    nbt_phase *tp = NULL;
    char err[512];
    if (nbt_phase_parse(target, &tp, err, sizeof err) != NBT_OK)
        die_usage("--target: %s", err);
    psi_data ad;
    memset(&ad, 0, sizeof ad);
    if (against)
        read_against(against, &ad);
    if (out)
        check_writable("-o", out);
    /* Gauss-Legendre panels graded towards the forward peak */
    static const double edges[NPANEL + 1] = {0, 0.02, 0.05, 0.1, 0.2, 0.4, 0.8, 1.6, M_PI};
    nbt_gl_rule *gl = nbt_gl_rule_alloc(PNODES);
    if (!gl)
        die("out of memory");
    phase_ctx c;
    memset(&c, 0, sizeof c);
    double nn = 0;
    for (int q = 0; q < NPANEL; q++)
        for (int i = 0; i < PNODES; i++) {
            int n = q * PNODES + i;
            double a = edges[q], b = edges[q + 1];
            c.th[n] = 0.5 * (a + b) + 0.5 * (b - a) * gl->x[i];
            double dw = 0.5 * (b - a) * gl->w[i] * 2 * M_PI * sin(c.th[n]); /* d omega */
            c.w[n] = sqrt(dw);
            c.target[n] = nbt_phase_eval(tp, cos(c.th[n]));
            nn += c.target[n] * c.target[n] * dw;
        }
    nbt_gl_rule_free(gl);
    c.norm = sqrt(nn);
    double g = nbt_phase_mean_cosine(tp);
    double best[2 * MAXK] = {0};
    best[0] = log(fmax(1e-4, fmin(5.0, (1 - g) / 2))); /* K = 1: one lobe, B ~ (1-g)/2 */
    nbt_fit_options fo;
    nbt_fit_options_default(&fo);
    fo.max_iterations = 500;
    fo.covariance = 1;
    double werr = 0, w[MAXK], B[MAXK];
    /* output is held back until every fit is judged (--strict writes nothing when one is flagged) */
    fit_report rep;
    fit_report_init(&rep, strict);
    fit_text txt = {0};
    char kstatus[600] = "ok", astatus[32] = "";
    double prev_err = INFINITY;
    for (int k = 1; k <= K; k++) {
        c.K = k;
        double p[2 * MAXK], cand[2][2 * MAXK];
        int ncand = k == 1 ? 1 : 2;
        /* start: the previous fit plus a broad or a narrow new lobe of small weight */
        for (int t = 0; t < ncand; t++) {
            double *s = cand[t];
            if (k == 1) {
                s[0] = best[0];
                continue;
            }
            int km = k - 1;
            for (int i = 0; i < km - 1; i++)
                s[i] = best[i];
            s[km - 1] = -3;
            double vmax = -INFINITY, vmin = INFINITY;
            for (int i = 0; i < km; i++) {
                s[k - 1 + i] = best[km - 1 + i];
                vmax = fmax(vmax, best[km - 1 + i]);
                vmin = fmin(vmin, best[km - 1 + i]);
            }
            s[2 * k - 2] = t == 0 ? vmax + log(4.0) : vmin - log(4.0);
        }
        /* bounds keep lobes physical: weights' logits within +-30, 1e-6 <= B <= 1e3 */
        double lo[2 * MAXK], hi[2 * MAXK];
        char nbuf[2 * MAXK][24];
        const char *names[2 * MAXK];
        for (int i = 0; i < 2 * k - 1; i++) {
            lo[i] = i < k - 1 ? -30 : log(1e-6);
            hi[i] = i < k - 1 ? 30 : log(1e3);
            if (i < k - 1)
                snprintf(nbuf[i], sizeof nbuf[i], "logit(w_%d/w_1)", i + 2);
            else
                snprintf(nbuf[i], sizeof nbuf[i], "ln B_%d", i - (k - 1) + 1);
            names[i] = nbuf[i];
        }
        double berr = INFINITY, bstart = NAN;
        nbt_fit_summary bs;
        memset(&bs, 0, sizeof bs);
        for (int t = 0; t < ncand; t++) {
            memcpy(p, cand[t], sizeof p);
            for (int i = 0; i < 2 * k - 1; i++)
                p[i] = fmin(hi[i], fmax(lo[i], p[i]));
            double e0 = fit_error(&c, p);
            nbt_fit_summary s;
            nbt_fit_solve(2 * k - 1, p, lo, hi, NNODE, phase_res, &c, &fo, &s);
            double e = fit_error(&c, p);
            if (s.usable && e < berr) {
                berr = e;
                bstart = e0;
                bs = s;
                memcpy(best, p, sizeof best);
            }
        }
        if (!isfinite(berr))
            die("the fit with %d terms failed", k);
        /* standard errors of the logits and ln B, the fit's own error per node taken as the noise: a
         * lobe the target does not determine to a factor e (a redundant lobe) is not a result */
        int np = 2 * k - 1;
        double se[2 * MAXK], se_max[2 * MAXK], sig2 = berr * berr / (NNODE - np);
        for (int i = 0; i < np; i++) {
            se[i] = bs.covariance_ok ? sqrt(bs.covariance[i * np + i] * sig2) : NAN;
            se_max[i] = 1;
        }
        /* worse: above the error of K - 1 lobes (which K lobes contain, with a zero weight), or of the start */
        char why[512], where[64], sname[64];
        double before = k == 1 ? bstart : prev_err;
        snprintf(sname, sizeof sname, k == 1 ? "its start" : "the %d-lobe fit", k - 1);
        fit_status st = fit_judge(&bs, np, names, best, lo, hi, se, se_max, before, berr, sname, why, sizeof why);
        if (st == FIT_OK && berr > tol) {
            snprintf(why, sizeof why, "relative L2 error %.3g is above --tol %g: the lobes do not follow the target "
                     "(it has no noise, so the tolerance stands in for a chi^2 test)", berr, tol);
            st = FIT_MISFIT;
        }
        prev_err = berr;
        snprintf(where, sizeof where, "phase K = %d", k);
        fit_report_fit(&rep, where, st, why);
        if (k == K)
            snprintf(kstatus, sizeof kstatus, "%s%s%s", fit_status_word(st), st == FIT_OK ? "" : ": ", why);
        werr = berr;
        fit_text_add(&txt, "K %d error %.6g status %s\n", k, berr, fit_status_word(st));
    }
    params_to_sog(K, best, w, B);
    int arc = against ? refit_against(against, &ad, K, w, B, &rep, &txt, astatus, sizeof astatus) : 0;
    psi_data_free(&ad);
    if (arc != 0) {
        fit_report_finish(&rep);
        fit_text_free(&txt);
        nbt_phase_free(tp);
        return 1;
    }
    int rc = 0;
    if (fit_report_finish(&rep)) {
        fit_text_free(&txt);
        nbt_phase_free(tp);
        return EXIT_USAGE;
    }
    fit_text_write(&txt, stdout);
    fit_text_free(&txt);
    if (out) {
        char *tmp;
        FILE *f = out_open(out, &tmp);
        if (!f)
            die("cannot write '%s': %s", out, strerror(errno));
        fprintf(f, "# sum of %d Gaussian lobes fitted to %s by nbt-fit phase; L2 error %.6g relative\n", K, target, werr);
        fprintf(f, "# fit status: %s\n", kstatus);
        if (against)
            fprintf(f, "# widths scaled to match %s, refit status: %s\n", against, astatus);
        fprintf(f, "# w B\n");
        for (int i = 0; i < K; i++)
            fprintf(f, "%.17g %.17g\n", w[i], B[i]);
        if (out_close(f, tmp, out, 1)) {
            fprintf(stderr, "%s: cannot write '%s': %s\n", cli_prog, out, strerror(errno));
            rc = 1;
        }
    } else
        for (int i = 0; i < K; i++)
            printf("w %.17g B %.17g\n", w[i], B[i]);
    nbt_phase_free(tp);
    return rc;
}
