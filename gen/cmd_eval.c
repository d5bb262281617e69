/* gen/cmd_eval.c: "nbt-gen eval H|J|airlight|surface": one value and its
 * estimated absolute error on one line, 17 significant digits. */
#include <config.h>
#include <getopt.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "cli.h"
#include "commands.h"

enum {
    O_K, O_U, O_V, O_N, O_T, O_THETA, O_G, O_PHASE, O_KS, O_KT, O_I0, O_DSV, O_GAMMA, O_DVP,
    O_DSP, O_THS, O_THR, O_KD, O_KSPEC, O_METHOD, O_TERMS, O_TOL, O_ALBEDO, O_SIGMAT, O_BSPREAD, O_Z, O_R,
    O_MODEL, O_DENSITY, O_INFINITE, O_BEAMMODEL, O_TABLES, O_COUNT
};
static const struct option opts[] = {
    {"k", required_argument, 0, O_K},         {"u", required_argument, 0, O_U},
    {"v", required_argument, 0, O_V},         {"n", required_argument, 0, O_N},
    {"T", required_argument, 0, O_T},         {"theta", required_argument, 0, O_THETA},
    {"g", required_argument, 0, O_G},         {"phase", required_argument, 0, O_PHASE},
    {"kappa-s", required_argument, 0, O_KS},  {"kappa-t", required_argument, 0, O_KT},
    {"I0", required_argument, 0, O_I0},       {"dsv", required_argument, 0, O_DSV},
    {"gamma", required_argument, 0, O_GAMMA}, {"dvp", required_argument, 0, O_DVP},
    {"dsp", required_argument, 0, O_DSP},     {"theta-s", required_argument, 0, O_THS},
    {"theta-r", required_argument, 0, O_THR}, {"kd", required_argument, 0, O_KD},
    {"ks", required_argument, 0, O_KSPEC},    {"method", required_argument, 0, O_METHOD},
    {"terms", required_argument, 0, O_TERMS}, {"tol", required_argument, 0, O_TOL},
    {"albedo", required_argument, 0, O_ALBEDO}, {"sigma-t", required_argument, 0, O_SIGMAT},
    {"B", required_argument, 0, O_BSPREAD},   {"z", required_argument, 0, O_Z},
    {"r", required_argument, 0, O_R},         {"model", required_argument, 0, O_MODEL},
    {"density", required_argument, 0, O_DENSITY}, {"infinite", no_argument, 0, O_INFINITE},
    {"beam-model", required_argument, 0, O_BEAMMODEL}, {"tables", required_argument, 0, O_TABLES},
    {"help", no_argument, 0, 'h'},            {0, 0, 0, 0}};

static void eval_help(void)
{
    puts("Usage: nbt-gen eval H --k K --u U --v V [--tol EPS]\n"
         "       nbt-gen eval H --phase SPEC --u U --v V            (fixed phase, 4 pi p)\n"
         "       nbt-gen eval J --k K --n N --T T --theta TH [--tol EPS]   (or --phase SPEC)\n"
         "       nbt-gen eval airlight (--g G | --phase SPEC) --kappa-s KS --kappa-t KT --I0 I\n"
         "                --dsv D --gamma GA --dvp DV|inf [--method direct|series|table] [--terms N] [--tol EPS]\n"
         "       nbt-gen eval surface (--g G | --phase SPEC) --kappa-s KS --kappa-t KT --I0 I\n"
         "                --dsp D --theta-s TS --theta-r TR --kd KD --ks KS --n N [--method ...] [--terms N] [--tol EPS]\n"
         "       nbt-gen eval airlight|surface ... --method table --tables FILE.exr [FILE.exr ...]\n"
         "                from given tables instead of building them: Legendre packs (with --g G or\n"
         "                --phase SPEC; the bound adds the series truncation beyond their orders), one\n"
         "                fixed-phase table per lobe (no --g/--phase), or g-sliced tables (--g G at run\n"
         "                time); prints the value and the bound the tables record\n\n"
         "       nbt-gen eval moments --albedo W --sigma-t ST --B B --z Z [--model ishimaru|smallangle]\n"
         "                [--density FILE]           prints M0 M2 alpha beta (narrow beam, pencil at z = 0)\n"
         "       nbt-gen eval psi --albedo W --sigma-t ST --B B --z Z --r R\n"
         "                [--model ishimaru|smallangle|lineint|single|elek] [--density FILE]\n"
         "       nbt-gen eval psi --albedo W --sigma-t ST --B B --z Z --r R --model fitted [--infinite]\n"
         "                [--beam-model FILE]   the fitted kernel model (nbt/beam.h nbt_beam_fit): libnbt's\n"
         "                default or FILE (nbt-fit model -o FILE); --infinite: a source inside the medium\n"
         "                (as nbt-fit mc --infinite), default a beam entering a half-space from vacuum;\n"
         "                with --density through zeta and the second moments (nbt_beam_fit_psi); the\n"
         "                error column is nan (no per-point bound; measured errors: doc/fit.md)\n\n"
         "Prints the value and its estimated absolute error, 17 significant digits.\n"
         "A density FILE has lines 'z rho': layers from z (first 0) with density rho >= 0.\n"
         "--tol (default 1e-8; 1e-15..0.1, for J and surface 1e-12..0.1) bounds the quadrature\n"
         "error; 'series' adds Legendre terms until the series changes by less than tol\n"
         "relative (unless --terms); 'table' builds tables at 1e-3 relative interpolation\n"
         "error and reports their recorded error.\n"
         "Angles in radians, distances in scene units, coefficients in 1/length.");
}

typedef struct {
    const char *arg[O_COUNT];
} args_t;

static double need(const args_t *a, int o, const char *name, double lo, int lo_open, double hi, int hi_open)
{
    if (!a->arg[o])
        die_usage("eval: %s is required here", name);
    return opt_double(name, a->arg[o], lo, lo_open, hi, hi_open);
}

static void only(const args_t *a, const char *what, const int *allowed, size_t n)
{
    for (int o = 0; o < O_COUNT; o++) {
        if (!a->arg[o])
            continue;
        int ok = 0;
        for (size_t i = 0; i < n; i++)
            ok |= allowed[i] == o;
        if (!ok)
            die_usage("eval %s: --%s does not apply here", what, opts[o].name);
    }
}

static nbt_phase *get_phase(const args_t *a)
{
    nbt_phase *p = NULL;
    if (a->arg[O_G] && a->arg[O_PHASE])
        die_usage("eval: --g and --phase exclude each other");
    if (a->arg[O_G])
        p = nbt_phase_hg(opt_double("--g", a->arg[O_G], -1, 1, 1, 1));
    else if (a->arg[O_PHASE]) {
        char err[256];
        if (nbt_phase_parse(a->arg[O_PHASE], &p, err, sizeof err) != NBT_OK)
            die_usage("--phase: %s", err);
    } else
        die_usage("eval: give the phase function with --g G or --phase SPEC");
    if (!p)
        die("out of memory");
    return p;
}

static void print_result(nbt_status st, double v, double e)
{
    if (st != NBT_OK && st != NBT_ETOL)
        die("evaluation failed: %s", nbt_strerror(st));
    printf("%.17g %.17g\n", v, e);
    if (st == NBT_ETOL)
        fprintf(stderr, "nbt-gen: warning: the requested tolerance was not reached; the error estimate is honest\n");
}

/* The physical evaluations share method handling. */
typedef struct {
    int surface;
    nbt_airlight_geom ag;
    nbt_surface_geom sg;
} phys_t;

static nbt_status series_eval(const phys_t *ph, const double *b, size_t N, double tol, double *v, double *e)
{
    return ph->surface ? nbt_surface_series(b, N, &ph->sg, tol, v, e) : nbt_airlight_series(b, N, &ph->ag, tol, v, e);
}

/* Series with terms added (doubling) until it changes by < tol relative. */
static nbt_status series_auto(const phys_t *ph, const nbt_phase *p, size_t fixed, double tol, double *v,
                              double *e, size_t *used)
{
    const size_t cap = 2048;
    double *b = malloc((cap + 1) * sizeof(double));
    if (!b || nbt_phase_moments(p, cap, b) != NBT_OK)
        die("cannot compute the Legendre moments of the phase function");
    nbt_status st;
    if (fixed) {
        st = series_eval(ph, b, fixed, tol, v, e);
        *used = fixed;
    } else {
        double prev = NAN, pe = 0;
        size_t N = 4;
        int short_quad = 0; /* a quadrature short of tol (NBT_ETOL): more terms still help; said at the end */
        st = series_eval(ph, b, N, tol, &prev, &pe);
        for (;;) {
            if (st == NBT_ETOL) {
                short_quad = 1;
                st = NBT_OK;
            }
            size_t M = 2 * N;
            if (st != NBT_OK || M > cap) {
                *v = prev;
                *e = pe;
                *used = N;
                if (st == NBT_OK)
                    st = NBT_ETOL;
                break;
            }
            double cur, ce;
            st = series_eval(ph, b, M, tol, &cur, &ce);
            double d = fabs(cur - prev);
            prev = cur;
            pe = ce + d; /* the last change bounds the rest of a decaying tail */
            N = M;
            if ((st == NBT_OK || st == NBT_ETOL) && d <= tol * fabs(cur)) {
                *v = cur;
                *e = pe;
                *used = N;
                break;
            }
        }
        if (short_quad && st == NBT_OK)
            st = NBT_ETOL;
    }
    free(b);
    return st;
}

/* --tol (default 1e-8). J and the surface integral are nested quadratures:
 * below 1e-12 their inner integrals run into the double-precision floor and
 * the outer one subdivides for minutes without reaching tol (J at 1e-13:
 * over a minute; 1e-12: 0.1 s), so they accept 1e-12 and up. */
static double eval_tol(const args_t *a, const char *what)
{
    if (!a->arg[O_TOL])
        return 1e-8;
    int nested = !strcmp(what, "J") || !strcmp(what, "surface");
    double lo = nested ? 1e-12 : 1e-15, t;
    char msg[256];
    if (msg_double(msg, sizeof msg, "--tol", a->arg[O_TOL], lo, 0, 0.1, 0, &t) != 0) {
        if (nested && parse_double(a->arg[O_TOL], 1e-15, 0, 0.1, 0, &t) == 0)
            die_usage("eval %s: --tol %s is not accepted: 1e-12 .. 0.1 (a nested quadrature: below 1e-12 it "
                      "runs for minutes at the double-precision floor)", what, a->arg[O_TOL]);
        die_usage("%s", msg);
    }
    return t;
}

static int eval_phys(const args_t *a, phys_t *ph)
{
    nbt_phase *p = get_phase(a);
    double tol = eval_tol(a, ph->surface ? "surface" : "airlight");
    const char *method = a->arg[O_METHOD] ? a->arg[O_METHOD] : "direct";
    size_t terms = a->arg[O_TERMS] ? (size_t)opt_long("--terms", a->arg[O_TERMS], 1, 2048) : 0;
    nbt_status st = ph->surface ? nbt_surface_check(&ph->sg) : nbt_airlight_check(&ph->ag);
    if (st != NBT_OK)
        die_usage("eval: the geometry is outside the domain (%s)",
                  ph->surface ? "kappa_t >= kappa_s >= 0, dsp > 0, angles in [0, pi]"
                              : "kappa_t >= kappa_s >= 0, dsv > 0, gamma in [0, pi], dvp > 0, and the ray must not run through the source");
    double v = NAN, e = NAN;
    if (!strcmp(method, "direct")) {
        if (terms)
            die_usage("--terms applies to --method series|table only");
        st = ph->surface ? nbt_surface_direct(p, &ph->sg, tol, &v, &e) : nbt_airlight_direct(p, &ph->ag, tol, &v, &e);
    } else if (!strcmp(method, "series")) {
        size_t used;
        st = series_auto(ph, p, terms, tol, &v, &e, &used);
        fprintf(stderr, "nbt-gen: %zu Legendre terms\n", used);
    } else if (!strcmp(method, "table")) {
        size_t used = 1;
        double sv = 0, se = 0;
        int fixed = a->arg[O_PHASE] && !terms;
        /* as many terms as the tables' own accuracy (1e-3) warrants */
        if (!fixed)
            st = series_auto(ph, p, terms, 1e-3, &sv, &se, &used);
        double x = ph->surface ? ph->sg.kappa_t * ph->sg.dsp : ph->ag.kappa_t * ph->ag.dsv * sin(ph->ag.gamma);
        nbt_plan_request rq[2] = {{ph->surface ? NBT_TABLE_J : NBT_TABLE_H, 1, used, fixed ? p : NULL,
                                   fmax(10.0, 1.01 * x), 1e-3, {0, 0}, 0, 0}};
        nbt_tableset sets[2];
        memset(sets, 0, sizeof sets);
        int nsets = ph->surface ? 2 : 1;
        rq[1] = rq[0];
        rq[1].n = ph->surface ? ph->sg.n : 1;
        /* plan only the sets the geometry uses: J^1 when kd > 0 (or the
         * specular lobe has n = 1), J^n when ks > 0 and n > 1 */
        size_t use[2], nuse = 0;
        int same1 = ph->surface && ph->sg.n == 1 && ph->sg.ks > 0;
        if (!ph->surface || ph->sg.kd > 0 || same1)
            use[nuse++] = 0;
        if (nsets == 2 && ph->sg.ks > 0 && ph->sg.n > 1)
            use[nuse++] = 1;
        if (nuse > 0) {
            nbt_plan_request r2[2];
            for (size_t q = 0; q < nuse; q++)
                r2[q] = rq[use[q]];
            nbt_plan *plan = NULL;
            char err[512];
            if (nbt_plan_tables(r2, nuse, 0, &plan, err, sizeof err) != NBT_OK)
                die("building the tables failed: %s", err);
            for (size_t q = 0; q < nuse; q++)
                if (nbt_plan_execute(plan, q, &sets[use[q]], err, sizeof err) != NBT_OK)
                    die("building the tables failed: %s", err);
            nbt_plan_free(plan);
        }
        if (same1)
            sets[1] = sets[0];
        double *b = malloc((used + 1) * sizeof(double));
        if (!b || nbt_phase_moments(p, used, b) != NBT_OK)
            die("cannot compute the Legendre moments");
        if (ph->surface) {
            st = nbt_surface_table((const nbt_table *const *)sets[0].t, sets[0].count,
                                   (const nbt_table *const *)sets[1].t, sets[1].count, b, used, &ph->sg, &v);
            /* error: each channel's recorded interpolation error, weighted as
             * in the series, plus truncation */
            double w = 0;
            for (int i = 0; i < nsets; i++) {
                double coef = i == 0 ? ph->sg.kd : ph->sg.ks;
                for (size_t t = 0; t < sets[i].count; t++)
                    for (size_t c = 0; c < sets[i].t[t]->nch; c++) {
                        int k = sets[i].t[t]->k[c];
                        w += coef * fabs(k < 0 ? 1.0 : (2.0 * k + 1.0) * b[k]) * sets[i].t[t]->max_err[c];
                    }
            }
            e = ph->sg.kappa_s * ph->sg.I0 / (4 * M_PI * ph->sg.dsp) * w;
        } else {
            /* the library's bound: the recorded errors of the lookups, or near
             * the source axis the ray integral's own error */
            st = nbt_airlight_table_e((const nbt_table *const *)sets[0].t, sets[0].count, b, used,
                                      fixed ? p : NULL, &ph->ag, &v, &e);
        }
        e += fixed ? 0.0 : se; /* se: the series' own error at that many terms */
        if (st == NBT_ETOL)
            fprintf(stderr, "nbt-gen: warning: outside the table's range, clamped\n");
        if (st == NBT_ETOL)
            st = NBT_OK;
        free(b);
        int same = ph->surface && sets[1].t[0] == sets[0].t[0];
        nbt_tableset_free(&sets[0]);
        if (!same)
            nbt_tableset_free(&sets[1]);
        fprintf(stderr, "nbt-gen: %zu Legendre terms, %s tables\n", used, fixed ? "fixed-phase" : "Legendre");
    } else
        die_usage("--method: '%s' is not accepted: direct, series or table", method);
    nbt_phase_free(p);
    print_result(st, v, e);
    return 0;
}

/* eval moments | psi: the narrow-beam models of nbt/beam.h */
static int eval_beam(const args_t *a, const char *what)
{
    int psi = !strcmp(what, "psi");
    static const int ok[] = {O_ALBEDO, O_SIGMAT, O_BSPREAD, O_Z, O_MODEL, O_DENSITY, O_R, O_INFINITE, O_BEAMMODEL};
    int fitted = psi && a->arg[O_MODEL] && !strcmp(a->arg[O_MODEL], "fitted");
    only(a, what, ok, fitted ? 9 : psi ? 7 : 6);
    double W = need(a, O_ALBEDO, "--albedo", 0, 0, 1, 0);
    double st_ = need(a, O_SIGMAT, "--sigma-t", 0, 1, INFINITY, 1);
    double B = need(a, O_BSPREAD, "--B", 0, 1, INFINITY, 1);
    double z = need(a, O_Z, "--z", 0, psi, INFINITY, 1);
    double r = psi ? need(a, O_R, "--r", 0, 1, INFINITY, 1) : 0;
    nbt_beam_medium m = nbt_beam_homogeneous(st_, W, B);
    double *zl = NULL, *rl = NULL;
    if (a->arg[O_DENSITY]) {
        char err[512];
        if (nbt_density_read(a->arg[O_DENSITY], &zl, &rl, &m.nlayers, err, sizeof err) != NBT_OK)
            die_usage("--density: %s", err);
        m.z = zl;
        m.rho = rl;
    }
    const char *model = a->arg[O_MODEL] ? a->arg[O_MODEL] : "ishimaru";
    nbt_status st;
    if (!psi) {
        nbt_beam_model bm;
        if (!strcmp(model, "ishimaru"))
            bm = NBT_BEAM_ISHIMARU;
        else if (!strcmp(model, "smallangle"))
            bm = NBT_BEAM_SMALLANGLE;
        else
            die_usage("--model: '%s' is not accepted for moments: ishimaru or smallangle", model);
        double M0, M2, al, be, e;
        st = nbt_beam_moments(&m, bm, z, &M0, &M2, &e);
        if (st != NBT_OK && st != NBT_ETOL)
            die("evaluation failed: %s", nbt_strerror(st));
        nbt_beam_kernel_params(M0, M2, &al, &be);
        printf("%.17g %.17g %.17g %.17g\n", M0, M2, al, be);
    } else if (fitted) {
        nbt_beam_fit own;
        const nbt_beam_fit *f = nbt_beam_fit_default();
        char err[512];
        if (a->arg[O_BEAMMODEL]) {
            if (nbt_beam_fit_read(a->arg[O_BEAMMODEL], &own, err, sizeof err) != NBT_OK)
                die_usage("--beam-model: %s", err);
            f = &own;
        }
        int inf = a->arg[O_INFINITE] != NULL;
        if (!f->have[inf])
            die_usage("--beam-model: '%s' holds no coefficients for the %s geometry", a->arg[O_BEAMMODEL],
                      inf ? "infinite (--infinite)" : "half-space");
        double v;
        st = nbt_beam_fit_psi(f, inf, &m, z, r, &v);
        if (st != NBT_OK)
            die("evaluation failed: %s", nbt_strerror(st));
        /* The model carries no per-point bound (its measured error is in
         * doc/fit.md): the error column is nan, never a false 0. Outside
         * the fitted range of tau, albedo or B its P_i are held at their
         * edge values: an extrapolation, said on stderr. */
        double zeta, lam, Bmix = 0;
        for (size_t i = 0; i < m.nlobes; i++)
            Bmix += m.w[i] * m.B[i];
        if (nbt_beam_fit_equivalent(&m, z, &zeta, &lam) != NBT_OK)
            zeta = z;
        const double q[3] = {m.sigma_t * zeta, m.albedo, Bmix};
        static const char *const qn[3] = {"tau = sigma_t z", "albedo", "B"};
        printf("%.17g nan\n", v);
        int outside = 0;
        for (int i = 0; i < 3; i++)
            if (f->range[i][0] < f->range[i][1] && (q[i] < f->range[i][0] || q[i] > f->range[i][1])) {
                fprintf(stderr, "nbt-gen: warning: %s = %g is outside the fitted range [%g, %g]: the value is an "
                        "extrapolation (the model's parameters held at the range's edge), with no error bound\n",
                        qn[i], q[i], f->range[i][0], f->range[i][1]);
                outside = 1;
            }
        if (!outside)
            fprintf(stderr, "nbt-gen: note: the fitted model gives no per-point error bound (error column nan); its "
                    "measured error against photon counts is in doc/fit.md\n");
    } else {
        static const char *names[] = {"ishimaru", "smallangle", "lineint", "single", "elek"};
        static const nbt_psi_model models[] = {NBT_PSI_ISHIMARU, NBT_PSI_SMALLANGLE, NBT_PSI_LINEINT, NBT_PSI_SINGLE,
                                               NBT_PSI_ELEK};
        int k = -1;
        for (int i = 0; i < 5; i++)
            if (!strcmp(model, names[i]))
                k = i;
        if (!strcmp(model, "pi"))
            die_usage("--model pi: the path-integral width of Shinya et al.'s supplement (eq. 14-16) is not "
                      "available here; accepted are ishimaru, smallangle, lineint, single, elek");
        if (k < 0)
            die_usage("--model: '%s' is not accepted: ishimaru, smallangle, lineint, single, elek or fitted", model);
        double v, e;
        st = nbt_beam_psi(&m, models[k], z, r, &v, &e);
        print_result(st, v, e);
    }
    free(zl);
    free(rl);
    return 0;
}

int cmd_eval(int argc, char **argv)
{
    if (argc < 2 || !strcmp(argv[1], "--help") || !strcmp(argv[1], "-h")) {
        if (argc < 2)
            die_usage("eval: say what to evaluate: H, J, airlight, surface, moments or psi (see 'nbt-gen eval --help')");
        eval_help();
        return 0;
    }
    const char *what = argv[1];
    args_t a = {{0}};
    int c;
    optind = 2;
    while ((c = getopt_long_only(argc, argv, ":", opts, NULL)) != -1) {
        if (c == 'h') {
            eval_help();
            return 0;
        }
        if (c < 0 || c >= O_COUNT)
            die_bad_option(c, argv, "nbt-gen eval");
        a.arg[c] = optarg ? optarg : ""; /* a flag without argument is present as "" */
    }
    /* --tables FILE [FILE ...]: the files after the first are left as operands */
    const char *files[65];
    size_t nfiles = 0;
    if (a.arg[O_TABLES]) {
        if (!a.arg[O_METHOD] || strcmp(a.arg[O_METHOD], "table"))
            die_usage("--tables applies to --method table only");
        if (a.arg[O_TERMS] || a.arg[O_TOL])
            die_usage("--tables: --terms and --tol do not apply (the files fix both)");
        files[nfiles++] = a.arg[O_TABLES];
        for (; optind < argc && nfiles < 65; optind++)
            files[nfiles++] = argv[optind];
    }
    if (optind < argc)
        die_usage("eval: unexpected argument '%s'", argv[optind]);
    double tol = eval_tol(&a, what);
    if (!strcmp(what, "H") || !strcmp(what, "J")) {
        int isJ = what[0] == 'J';
        static const int okH[] = {O_K, O_U, O_V, O_TOL, O_PHASE}, okJ[] = {O_K, O_N, O_T, O_THETA, O_TOL, O_PHASE};
        only(&a, what, isJ ? okJ : okH, isJ ? 6 : 5);
        nbt_phase *p = NULL;
        long k = 0;
        if (a.arg[O_PHASE] && a.arg[O_K])
            die_usage("eval %s: --k and --phase exclude each other", what);
        if (a.arg[O_PHASE])
            p = get_phase(&a);
        else if (a.arg[O_K])
            k = opt_long("--k", a.arg[O_K], 0, 10000);
        else
            die_usage("eval %s: --k K (Legendre order) or --phase SPEC is required", what);
        double *v = malloc(2 * (size_t)(k + 1) * sizeof(double));
        if (!v)
            die("out of memory");
        nbt_status st;
        if (!isJ) {
            double u = need(&a, O_U, "--u", 0, 0, INFINITY, 1);
            double vv = need(&a, O_V, "--v", -M_PI_2, 0, M_PI_2, 0);
            st = p ? nbt_h_phase(p, u, vv, tol, v, v + 1) : nbt_hk((size_t)k, u, vv, tol, v, v + k + 1);
        } else {
            int n = (int)opt_long("--n", a.arg[O_N] ? a.arg[O_N] : "", 1, 10000);
            double T = need(&a, O_T, "--T", 0, 0, INFINITY, 1);
            double th = need(&a, O_THETA, "--theta", 0, 0, M_PI, 0);
            st = p ? nbt_j_phase(p, n, T, th, tol, v, v + 1) : nbt_jk((size_t)k, n, T, th, tol, v, v + k + 1);
        }
        if (p)
            print_result(st, v[0], v[1]);
        else
            print_result(st, v[k], v[2 * k + 1]);
        free(v);
        nbt_phase_free(p);
        return 0;
    }
    if (!strcmp(what, "moments") || !strcmp(what, "psi"))
        return eval_beam(&a, what);
    phys_t ph;
    memset(&ph, 0, sizeof ph);
    if (!strcmp(what, "airlight")) {
        static const int ok[] = {O_G, O_PHASE, O_KS, O_KT, O_I0, O_DSV, O_GAMMA, O_DVP, O_METHOD, O_TERMS, O_TOL,
                                 O_TABLES};
        only(&a, what, ok, sizeof ok / sizeof ok[0]);
        ph.ag.kappa_s = need(&a, O_KS, "--kappa-s", 0, 0, INFINITY, 1);
        ph.ag.kappa_t = need(&a, O_KT, "--kappa-t", 0, 0, INFINITY, 1);
        ph.ag.I0 = need(&a, O_I0, "--I0", 0, 0, INFINITY, 1);
        ph.ag.dsv = need(&a, O_DSV, "--dsv", 0, 1, INFINITY, 1);
        ph.ag.gamma = need(&a, O_GAMMA, "--gamma", 0, 0, M_PI, 0);
        if (a.arg[O_DVP] && !strcmp(a.arg[O_DVP], "inf"))
            ph.ag.dvp = INFINITY;
        else
            ph.ag.dvp = need(&a, O_DVP, "--dvp", 0, 1, INFINITY, 1);
        if (ph.ag.kappa_t < ph.ag.kappa_s)
            die_usage("--kappa-t: %g is not accepted: extinction must be >= scattering (%g)", ph.ag.kappa_t, ph.ag.kappa_s);
        /* the one geometry libnbt refuses beyond the bounds above (nbt_airlight_check) */
        if (ph.ag.gamma == 0 && ph.ag.dvp >= ph.ag.dsv)
            die_usage("--dvp: '%s' is not accepted with --gamma 0: the ray would run through the source (dvp >= "
                      "dsv = %g); give dvp < dsv or gamma > 0", a.arg[O_DVP], ph.ag.dsv);
        if (nfiles)
            return eval_from_tables(0, &ph.ag, files, nfiles, a.arg[O_G], a.arg[O_PHASE]);
        return eval_phys(&a, &ph);
    }
    if (!strcmp(what, "surface")) {
        static const int ok[] = {O_G, O_PHASE, O_KS, O_KT, O_I0, O_DSP, O_THS, O_THR, O_KD, O_KSPEC, O_N, O_METHOD, O_TERMS, O_TOL,
                                 O_TABLES};
        only(&a, what, ok, sizeof ok / sizeof ok[0]);
        ph.surface = 1;
        ph.sg.kappa_s = need(&a, O_KS, "--kappa-s", 0, 0, INFINITY, 1);
        ph.sg.kappa_t = need(&a, O_KT, "--kappa-t", 0, 0, INFINITY, 1);
        ph.sg.I0 = need(&a, O_I0, "--I0", 0, 0, INFINITY, 1);
        ph.sg.dsp = need(&a, O_DSP, "--dsp", 0, 1, INFINITY, 1);
        ph.sg.theta_s = need(&a, O_THS, "--theta-s", 0, 0, M_PI, 0);
        ph.sg.theta_r = need(&a, O_THR, "--theta-r", 0, 0, M_PI, 0);
        ph.sg.kd = need(&a, O_KD, "--kd", 0, 0, INFINITY, 1);
        ph.sg.ks = need(&a, O_KSPEC, "--ks", 0, 0, INFINITY, 1);
        ph.sg.n = (int)opt_long("--n", a.arg[O_N] ? a.arg[O_N] : "", 1, 10000);
        if (ph.sg.kappa_t < ph.sg.kappa_s)
            die_usage("--kappa-t: %g is not accepted: extinction must be >= scattering (%g)", ph.sg.kappa_t, ph.sg.kappa_s);
        if (nfiles)
            return eval_from_tables(1, &ph.sg, files, nfiles, a.arg[O_G], a.arg[O_PHASE]);
        return eval_phys(&a, &ph);
    }
    die_usage("eval: '%s' is not accepted: H, J, airlight, surface, moments or psi", what);
}
