/* fit/cmd_model.c: "nbt-fit model": the kernel model of nbt/beam.h
 * (nbt_beam_fit: core + diffuse part with smooth parameters) fitted jointly
 * to photon-counting runs over depth, albedo and phase width, directly on
 * the relative RMS of 2 pi r Psi; --apply measures a model on other runs. */
#include <config.h>
#include <errno.h>
#include <getopt.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <nbt/nbt.h>
#include "../gen/cli.h"
#include "ceres_shim.h"
#include "commands.h"
#include "fit_status.h"
#include "kernel_model.h"
#include "psi_data.h"

static void help(void)
{
    puts("Usage: nbt-fit model MC.exr|MC.csv [MORE ...] -o MODEL.txt [--albedo W --sigma-t ST --B B]\n"
         "                     [--infinite] [--ridge L] [--strict]\n"
         "       nbt-fit model --apply MODEL.txt|default MC.exr [MORE ...] [--density FILE]\n\n"
         "Fits the kernel model of nbt/beam.h (nbt_beam_fit): Psi = a/r G(r/b) + M e^{-(q-h)/s}/(2 pi s (h+s)),\n"
         "q = sqrt(r^2 + h^2) (sigma_t = 1 units), with log-parameters P0..P4 as polynomials in\n"
         "ln(sigma_t z), albedo and ln B (the terms in albedo and B only where the runs differ in them),\n"
         "one set per geometry, to all runs at once: it\n"
         "minimises the sum over runs of the squared relative RMS of 2 pi r Psi (annulus means, as\n"
         "counted), plus L^2 sum (c - c_start)^2 over the coefficients (--ridge, default 1e-3; the start is\n"
         "0 but for the constants), which keeps the fit well-posed. The medium and geometry come from\n"
         "an EXR's metadata (nbt-fit mc -o X.exr) or --albedo/--sigma-t/--B and --infinite (the source\n"
         "inside the medium) for CSV files.\n"
         "stderr gets 'RMS FILE model X moment Y' per run and the fit's status (see nbt-fit kernel --help;\n"
         "misfit: chi^2/dof over all bins of all runs against the counts' standard errors is above its\n"
         "0.1% point); --strict: a flagged fit but a misfit is an error (exit 2, nothing written).\n"
         "--apply: for each run, 'geometry dtheta albedo mc_se model moment' (relative RMS of 2 pi r Psi;\n"
         "mc_se the counts' own noise on that scale; dtheta = 2 sqrt(B) in degrees) on stdout.\n"
         "--apply --density FILE: the runs were counted in that layered density (nbt-fit mc --density);\n"
         "the model is evaluated as nbt_beam_fit_psi does there (equivalent depth zeta, widths scaled by\n"
         "the eq. 29 / eq. 26 second moments), the moment kernel from eq. 28/29.");
}

typedef struct {
    psi_data *runs;
    size_t nruns;
    int geo;
    int active[NBT_BEAM_FIT_TERMS]; /* terms the runs can determine */
    int free_[NBT_BEAM_FIT_PARTS][NBT_BEAM_FIT_TERMS]; /* parameters free in this stage */
    double c[NBT_BEAM_FIT_PARTS][NBT_BEAM_FIT_TERMS]; /* current coefficients (fixed ones keep their value) */
    double *scale;                    /* per run: 1/sqrt(sum (2 pi r mc)^2) */
    double ridge;
    size_t nres; /* data residuals over all runs */
    int np;
} model_ctx;

static void model_fill(nbt_beam_fit *f, int geo, const double c[NBT_BEAM_FIT_PARTS][NBT_BEAM_FIT_TERMS])
{
    memset(f, 0, sizeof *f);
    memcpy(f->c[geo], c, sizeof f->c[geo]);
    f->have[geo] = 1;
}

/* the annulus mean of the model on run d's annulus i, with d mean / d P_q in D[q] */
static double model_annulus(const psi_data *d, const double *p, size_t i, double *D)
{
    double st2 = d->sigma_t * d->sigma_t, lo = d->sigma_t * d->lo[i], hi = d->sigma_t * d->hi[i], g[5];
    double m = kernel_annulus(p[0], p[1], lo, hi, &g[0], &g[1]) + pexp_annulus(p[2], p[3], p[4], lo, hi, &g[2], &g[3], &g[4]);
    if (D) { /* a ~ e^{P0 - P1}, b ~ e^{P1}, M ~ e^{P2}, s ~ e^{P3}, h ~ e^{P3 + P4} */
        D[0] = st2 * g[0] * p[0];
        D[1] = st2 * (g[1] * p[1] - g[0] * p[0]);
        D[2] = st2 * g[2] * p[2];
        D[3] = st2 * (g[3] * p[3] + g[4] * p[4]);
        D[4] = st2 * g[4] * p[4];
    }
    return st2 * m;
}

/* start: the core carrying half the light at single scattering's width, the diffuse half three times as
 * wide, between exponential and Gaussian (h = s) */
static const double start_c[NBT_BEAM_FIT_PARTS] = {-0.69314718055994531, 0, -0.69314718055994531, 1.0986122886681098, 0};

static void unpack(model_ctx *c, const double *x)
{
    int n = 0;
    for (int q = 0; q < NBT_BEAM_FIT_PARTS; q++)
        for (int k = 0; k < NBT_BEAM_FIT_TERMS; k++)
            if (c->free_[q][k])
                c->c[q][k] = x[n++];
}

static int model_res(const double *x, double *r, double *jac, void *vp)
{
    model_ctx *c = vp;
    unpack(c, x);
    nbt_beam_fit f;
    model_fill(&f, c->geo, c->c);
    size_t n = 0;
    int np = c->np;
    for (size_t q = 0; q < c->nruns; q++) {
        const psi_data *d = &c->runs[q];
        for (size_t j = 0; j < d->nplanes; j++) {
            double p[NBT_BEAM_FIT_PARTS], t[NBT_BEAM_FIT_TERMS];
            if (nbt_beam_fit_params(&f, c->geo, d->sigma_t * d->z[j], d->albedo, d->B, p) != NBT_OK)
                return 1;
            nbt_beam_fit_terms(NULL, d->sigma_t * d->z[j], d->albedo, d->B, t);
            for (size_t k = 0; k < d->nbins; k++) {
                size_t i = j * d->nbins + k;
                double w = c->scale[q] * M_PI * (d->lo[i] + d->hi[i]), D[NBT_BEAM_FIT_PARTS];
                r[n] = w * (model_annulus(d, p, i, jac ? D : NULL) - d->psi[i]);
                if (jac) {
                    int e = 0;
                    for (int qq = 0; qq < NBT_BEAM_FIT_PARTS; qq++)
                        for (int kk = 0; kk < NBT_BEAM_FIT_TERMS; kk++)
                            if (c->free_[qq][kk])
                                jac[n * (size_t)np + (size_t)e++] = w * D[qq] * t[kk];
                }
                n++;
            }
        }
    }
    /* the ridge: L (c - c_start) for every free coefficient (the start is 0 but for the constants),
     * so that a part the data do not need cannot run away to e^P = 0 (where its gradient vanishes) */
    int e = 0;
    for (int qq = 0; qq < NBT_BEAM_FIT_PARTS; qq++)
        for (int kk = 0; kk < NBT_BEAM_FIT_TERMS; kk++)
            if (c->free_[qq][kk]) {
                r[n] = c->ridge * (c->c[qq][kk] - (kk == 0 ? start_c[qq] : 0));
                if (jac) {
                    memset(jac + n * (size_t)np, 0, (size_t)np * sizeof *jac);
                    jac[n * (size_t)np + (size_t)e] = c->ridge;
                }
                n++;
                e++;
            }
    return 0;
}

/* relative RMS of 2 pi r Psi over a whole run: model (f, geometry) or, f == NULL, the moment kernel;
 * *noise (may be NULL) gets the counts' standard errors on the same scale */
/* the layered density of --apply --density (NULL: homogeneous) */
typedef struct {
    size_t n;
    const double *z, *rho;
} layers;

static double run_rms_in(const psi_data *d, const nbt_beam_fit *f, int geo, const layers *ly, double *noise,
                         double *chi2)
{
    double num = 0, den = 0, se2 = 0, c2 = 0, st = d->sigma_t;
    nbt_beam_medium m = nbt_beam_homogeneous(d->sigma_t, d->albedo, d->B);
    if (ly) {
        m.nlayers = ly->n;
        m.z = ly->z;
        m.rho = ly->rho;
    }
    for (size_t j = 0; j < d->nplanes; j++) {
        double p[NBT_BEAM_FIT_PARTS] = {0}, a = 0, b = 0, zeta = d->z[j], lam = 1;
        if (f) { /* layers: the homogeneous model at zeta(z), widths scaled by lambda (nbt_beam_fit_psi) */
            if (nbt_beam_fit_equivalent(&m, d->z[j], &zeta, &lam) != NBT_OK ||
                (zeta > 0 && nbt_beam_fit_params(f, geo, st * zeta, d->albedo, d->B, p) != NBT_OK))
                return NAN;
        } else {
            double M0, M2;
            nbt_beam_moments(&m, NBT_BEAM_ISHIMARU, d->z[j], &M0, &M2, NULL);
            nbt_beam_kernel_params(M0, M2, &a, &b);
        }
        for (size_t k = 0; k < d->nbins; k++) {
            size_t i = j * d->nbins + k;
            double w = M_PI * (d->lo[i] + d->hi[i]), v = 0;
            if (f && zeta > 0) {
                double lo = st * d->lo[i] / lam, hi = st * d->hi[i] / lam;
                v = st * st / (lam * lam) *
                    (kernel_annulus(p[0], p[1], lo, hi, NULL, NULL) + pexp_annulus(p[2], p[3], p[4], lo, hi, NULL, NULL, NULL));
            } else if (!f && b > 0)
                v = kernel_annulus(a, b, d->lo[i], d->hi[i], NULL, NULL);
            num += w * w * (v - d->psi[i]) * (v - d->psi[i]);
            den += w * w * d->psi[i] * d->psi[i];
            se2 += w * w * d->se[i] * d->se[i];
            if (chi2)
                c2 += psi_chi2_term(d, i, psi_floor_se(d, j), v);
        }
    }
    if (noise)
        *noise = sqrt(se2 / den);
    if (chi2)
        *chi2 = c2;
    return sqrt(num / den);
}

/* *chi2 (may be NULL): sum ((model - mc)/se)^2 over the run's bins (the plane's floor where se is 0) */
static double run_rms(const psi_data *d, const nbt_beam_fit *f, int geo, double *noise, double *chi2)
{
    return run_rms_in(d, f, geo, NULL, noise, chi2);
}

/* terms of monomial k: powers of (x, w, v) */
static const int pw[NBT_BEAM_FIT_TERMS][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {2, 0, 0}, {1, 1, 0},
                                              {1, 0, 1}, {0, 2, 0}, {0, 1, 1}, {0, 0, 2}, {3, 0, 0}, {2, 1, 0},
                                              {2, 0, 1}, {1, 2, 0}, {1, 1, 1}, {1, 0, 2}};

static size_t distinct(const psi_data *runs, size_t n, int which)
{
    double v[4096];
    size_t m = 0;
    for (size_t q = 0; q < n && m < 4096; q++) {
        double x = which ? runs[q].B : runs[q].albedo;
        size_t i = 0;
        while (i < m && fabs(v[i] - x) > 1e-9 * fabs(x))
            i++;
        if (i == m)
            v[m++] = x;
    }
    return m;
}

static const char *const geo_word[2] = {"half", "infinite"};

/* one continuation stage: the coefficients of total degree <= deg free (the diffuse shape P4 stays at
 * h = s while only constants are free: alone it runs to h -> 0, the exponential, where its gradient
 * vanishes and the later stages could not move it back); 0, or 1 after a message */
static int fit_stage(model_ctx *c, int deg, nbt_fit_summary *s, fit_text *flog)
{
    int np = 0;
    for (int q = 0; q < NBT_BEAM_FIT_PARTS; q++)
        for (int k = 0; k < NBT_BEAM_FIT_TERMS; k++) {
            c->free_[q][k] = c->active[k] && pw[k][0] + pw[k][1] + pw[k][2] <= deg && (q < 4 || deg >= 1);
            np += c->free_[q][k];
        }
    if (np > NBT_FIT_MAX_PARAMS)
        die("model: %d coefficients exceed the solver's %d", np, NBT_FIT_MAX_PARAMS);
    c->np = np;
    double x[NBT_FIT_MAX_PARAMS];
    int n = 0;
    for (int q = 0; q < NBT_BEAM_FIT_PARTS; q++)
        for (int k = 0; k < NBT_BEAM_FIT_TERMS; k++)
            if (c->free_[q][k])
                x[n++] = c->c[q][k];
    nbt_fit_options o;
    nbt_fit_options_default(&o);
    o.analytic_jacobian = 1;
    o.max_iterations = 2000;
    size_t nr = c->nres + (size_t)np; /* the data, then one ridge residual per coefficient */
    if (nbt_fit_solve(np, x, NULL, NULL, (int)nr, model_res, c, &o, s)) {
        fprintf(stderr, "%s: model (%s): the fit failed at degree %d: %s (%s)\n", cli_prog, geo_word[c->geo], deg,
                s->termination, s->message);
        return 1;
    }
    unpack(c, x);
    fit_text_add(flog, "model %s: degree %d, %d coefficients, cost %.6g -> %.6g in %d iterations\n", geo_word[c->geo],
                 deg, np, s->initial_cost, s->final_cost, s->iterations);
    return 0;
}

/* fit one geometry's coefficients; returns 0 and fills c, or 1 (hard failure) */
static int fit_geometry(psi_data *runs, size_t nruns, int geo, double ridge, double c_out[NBT_BEAM_FIT_PARTS][NBT_BEAM_FIT_TERMS],
                        fit_report *rep, fit_text *flog)
{
    model_ctx c;
    memset(&c, 0, sizeof c);
    c.runs = runs;
    c.nruns = nruns;
    c.geo = geo;
    c.ridge = ridge;
    size_t na = distinct(runs, nruns, 0), nb = distinct(runs, nruns, 1), nplanes_max = 0;
    for (size_t q = 0; q < nruns; q++)
        nplanes_max = runs[q].nplanes > nplanes_max ? runs[q].nplanes : nplanes_max;
    for (int k = 0; k < NBT_BEAM_FIT_TERMS; k++) /* a power needs more distinct values than its degree */
        c.active[k] = (size_t)pw[k][0] < nplanes_max && (size_t)pw[k][1] < na && (size_t)pw[k][2] < nb;
    c.scale = malloc(nruns * sizeof(double));
    if (!c.scale)
        die("out of memory");
    size_t nres = 0;
    for (size_t q = 0; q < nruns; q++) {
        double den = run_rms_den(&runs[q]);
        if (!(den > 0))
            die_usage("%s: no photons counted: cannot fit", runs[q].name);
        c.scale[q] = 1 / sqrt(den);
        nres += runs[q].nplanes * runs[q].nbins;
    }
    c.nres = nres;
    /* continuation: constants, then total degree <= 1, 2, 3. Stages 0 and 1 have local minima (the
     * diffuse part settling near the core's width or far out: on 9 runs of 2e4 photons, 3 of 4 seeds
     * ended at chi^2/dof 12 from one start, against 1.9 from the best): they run from three diffuse
     * widths and the lowest cost goes on to degrees 2 and 3 */
    static const double diffuse_start[3] = {1.0986122886681098, 0.0, -1.0986122886681098}; /* s = 3, 1, 1/3 */
    double best[NBT_BEAM_FIT_PARTS][NBT_BEAM_FIT_TERMS], best_cost = INFINITY;
    nbt_fit_summary s;
    memset(&s, 0, sizeof s);
    for (int t = 0; t < 3; t++) {
        memset(c.c, 0, sizeof c.c);
        for (int q = 0; q < NBT_BEAM_FIT_PARTS; q++)
            c.c[q][0] = start_c[q];
        c.c[3][0] = diffuse_start[t];
        for (int deg = 0; deg <= 1; deg++)
            if (fit_stage(&c, deg, &s, flog)) {
                free(c.scale);
                return 1;
            }
        fit_text_add(flog, "model %s: start %d (diffuse width %g): cost %.6g at degree 1\n", geo_word[geo], t,
                     exp(diffuse_start[t]), s.final_cost);
        if (s.final_cost < best_cost) {
            best_cost = s.final_cost;
            memcpy(best, c.c, sizeof best);
        }
    }
    memcpy(c.c, best, sizeof best);
    for (int deg = 2; deg <= 3; deg++)
        if (fit_stage(&c, deg, &s, flog)) {
            free(c.scale);
            return 1;
        }
    int np = c.np;
    /* judged: converged, well-conditioned (the ridge keeps J^T J regular), no run worse than the moment kernel */
    nbt_beam_fit f;
    model_fill(&f, geo, c.c);
    double before = NAN, after = NAN, worst = -INFINITY, chi2 = 0;
    for (size_t q = 0; q < nruns; q++) {
        double c2, r0 = run_rms(&runs[q], NULL, geo, NULL, NULL), r1 = run_rms(&runs[q], &f, geo, NULL, &c2);
        chi2 += c2;
        fit_report_note(rep, "RMS %s model %.4f moment %.4f\n", runs[q].name, r1, r0);
        if (r1 - r0 > worst) {
            worst = r1 - r0;
            before = r0;
            after = r1;
        }
    }
    char why[512], where[64];
    const char *names[NBT_FIT_MAX_PARAMS];
    for (int e = 0; e < np; e++)
        names[e] = "a coefficient";
    fit_status st = fit_judge(&s, np, names, NULL, NULL, NULL, NULL, NULL, before, after, "the moment kernel", why,
                              sizeof why);
    /* within the counting noise? (the ridge's residuals are not data) */
    st = fit_misfit(st, chi2, (double)nres - np, NAN, why, sizeof why);
    snprintf(where, sizeof where, "model (%s)", geo_word[geo]);
    fit_report_fit(rep, where, st, why);
    fit_text_add(flog, "# %s: %zu runs, %d coefficients, rcond %.3g, chi^2/dof %.4g, fit status %s\n", geo_word[geo],
                 nruns, np, s.rcond, chi2 / ((double)nres - np), fit_status_word(st));
    memcpy(c_out, c.c, sizeof c.c);
    free(c.scale);
    return 0;
}

int cmd_model(int argc, char **argv)
{
    static const struct option opts[] = {
        {"output", required_argument, 0, 'o'}, {"albedo", required_argument, 0, 'a'},
        {"sigma-t", required_argument, 0, 's'}, {"B", required_argument, 0, 'B'},
        {"infinite", no_argument, 0, 'I'},     {"ridge", required_argument, 0, 'r'},
        {"apply", required_argument, 0, 'A'},  {"strict", no_argument, 0, 'T'},
        {"density", required_argument, 0, 'd'},
        {"help", no_argument, 0, 'h'},         {0, 0, 0, 0}};
    const char *out = NULL, *apply = NULL, *density = NULL;
    double albedo = NAN, sigma_t = NAN, B = NAN, ridge = 1e-3;
    int infinite = 0, strict = 0, o;
    optind = 1;
    while ((o = getopt_long_only(argc, argv, ":o:h", opts, NULL)) != -1) {
        switch (o) {
        case 'o': out = optarg; break;
        case 'a': albedo = opt_double("--albedo", optarg, 0, 0, 1, 0); break;
        case 's': sigma_t = opt_double("--sigma-t", optarg, 0, 1, 1e12, 0); break;
        case 'B': B = opt_double("--B", optarg, 0, 1, 1e6, 0); break;
        case 'I': infinite = 1; break;
        case 'r': ridge = opt_double("--ridge", optarg, 0, 0, 1e3, 0); break;
        case 'A': apply = optarg; break;
        case 'T': strict = 1; break;
        case 'd': density = optarg; break;
        case 'h': help(); return 0;
        default: die_bad_option(o, argv, "nbt-fit model");
        }
    }
    size_t nruns = (size_t)(argc - optind);
    if (nruns == 0)
        die_usage("model: give at least one photon-counting file (nbt-fit mc -o FILE)");
    if (!apply && !out)
        die_usage("model: -o MODEL.txt is required (or --apply MODEL.txt to measure one)");
    if (apply && out)
        die_usage("model: --apply and -o exclude each other");
    if (density && !apply)
        die_usage("model: --density applies to --apply only (the model is fitted to homogeneous runs)");
    nbt_beam_fit applied;
    char err[512];
    if (apply) {
        if (!strcmp(apply, "default"))
            applied = *nbt_beam_fit_default();
        else if (nbt_beam_fit_read(apply, &applied, err, sizeof err) != NBT_OK)
            die_usage("--apply: %s", err);
    }
    psi_data *runs = calloc(nruns, sizeof *runs);
    if (!runs)
        die("out of memory");
    for (size_t q = 0; q < nruns; q++) {
        psi_data *d = &runs[q];
        if (psi_data_read_medium(argv[optind + q], d, albedo, sigma_t, B, err, sizeof err))
            die_usage("%s", err);
        if (infinite)
            d->infinite = 1;
        if (apply && !applied.have[d->infinite])
            die_usage("%s: the model '%s' holds no coefficients for the %s geometry", d->name, apply,
                      geo_word[d->infinite]);
    }
    if (apply) {
        layers ly = {0, NULL, NULL};
        double *lz = NULL, *lr = NULL;
        if (density) {
            if (nbt_density_read(density, &lz, &lr, &ly.n, err, sizeof err) != NBT_OK)
                die_usage("--density: %s", err);
            ly.z = lz;
            ly.rho = lr;
        }
        printf("# relative RMS of 2 pi r Psi vs photon counting, model %s%s%s; mc_se: the counts' own noise\n"
               "geometry dtheta albedo   mc_se    model   moment  file\n", apply, density ? ", density " : "",
               density ? density : "");
        for (size_t q = 0; q < nruns; q++) {
            const psi_data *d = &runs[q];
            double se, r1 = run_rms_in(d, &applied, d->infinite, density ? &ly : NULL, &se, NULL),
                       r0 = run_rms_in(d, NULL, 0, density ? &ly : NULL, NULL, NULL);
            printf("%-8s %6.1f %6.3f %7.4f %8.4f %8.4f  %s\n", geo_word[d->infinite], 2 * sqrt(d->B) * 180 / M_PI,
                   d->albedo, se, r1, r0, d->name);
        }
        for (size_t q = 0; q < nruns; q++)
            psi_data_free(&runs[q]);
        free(runs);
        free(lz);
        free(lr);
        return 0;
    }
    check_writable("-o", out);
    nbt_beam_fit f;
    memset(&f, 0, sizeof f);
    fit_report rep;
    fit_report_init(&rep, strict);
    fit_text log = {0};
    int rc = 0;
    for (int g = 0; g < 2 && rc == 0; g++) {
        /* the runs of this geometry, gathered in front */
        psi_data *sel = malloc(nruns * sizeof *sel);
        if (!sel)
            die("out of memory");
        size_t n = 0;
        for (size_t q = 0; q < nruns; q++)
            if (runs[q].infinite == g)
                sel[n++] = runs[q];
        if (n > 0) {
            rc = fit_geometry(sel, n, g, ridge, f.c[g], &rep, &log);
            f.have[g] = rc == 0;
        }
        free(sel);
    }
    if (rc == 0 && fit_report_finish(&rep))
        rc = EXIT_USAGE;
    else if (rc != 0)
        fit_report_finish(&rep);
    for (size_t q = 0; q < nruns; q++) { /* the data's range: the model clamps its monomials' arguments to it */
        const psi_data *d = &runs[q];
        double v[3][2] = {{d->sigma_t * d->z[0], d->sigma_t * d->z[d->nplanes - 1]}, {d->albedo, d->albedo}, {d->B, d->B}};
        for (int i = 0; i < 3; i++) {
            f.range[i][0] = q == 0 ? v[i][0] : fmin(f.range[i][0], v[i][0]);
            f.range[i][1] = q == 0 ? v[i][1] : fmax(f.range[i][1], v[i][1]);
        }
    }
    if (rc == 0) {
        fit_text_add(&log, "# ridge %g; fitted by nbt-fit model to %zu runs:\n", ridge, nruns);
        for (size_t q = 0; q < nruns; q++)
            fit_text_add(&log, "#   %s albedo=%g sigma_t=%g B=%g %s\n", runs[q].name, runs[q].albedo, runs[q].sigma_t,
                         runs[q].B, geo_word[runs[q].infinite]);
        char *tmp;
        FILE *fp = out_open(out, &tmp);
        int ok = fp != NULL;
        if (ok) {
            for (char *p = log.s; p && *p;) { /* every log line as a comment */
                char *e = strchr(p, '\n');
                size_t len = e ? (size_t)(e - p) : strlen(p);
                fprintf(fp, "%s%.*s\n", *p == '#' ? "" : "# ", (int)len, p);
                p = e ? e + 1 : p + len;
            }
            ok = nbt_beam_fit_fprint(fp, &f, NULL) == NBT_OK;
        }
        if (!fp || out_close(fp, tmp, out, ok)) {
            fprintf(stderr, "%s: cannot write '%s': %s\n", cli_prog, out, strerror(errno));
            rc = 1;
        }
    }
    fit_text_free(&log);
    for (size_t q = 0; q < nruns; q++)
        psi_data_free(&runs[q]);
    free(runs);
    return rc;
}
