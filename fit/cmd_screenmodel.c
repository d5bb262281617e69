/* fit/cmd_screenmodel.c: "nbt-fit screenmodel": the model of a screen
 * kernel's higher scattering orders (nbt_screen_model, nbt/screen.h) fitted
 * to photon counts of first wall crossings (nbt_mc_kernel_run), over the
 * HG family's g or for one phase, the albedo, the optical depth and both
 * geometries; --check measures a model against fresh counts. */
#include <config.h>
#include <getopt.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <nbt/nbt.h>
#include "../gen/cli.h"
#include "../gen/progress.h"
#include "commands.h"

#define MAXL 64

static void help(void)
{
    puts("Usage: nbt-fit screenmodel -o MODEL.txt [--phase SPEC | --g LIST] [--albedo LIST] [--tau LIST]\n"
         "                           [--geometry inside,entering] [--photons N] [--seed S] [--threads N] [--quiet]\n"
         "       nbt-fit screenmodel --check MODEL.txt|default [--phase SPEC | --g LIST] [--albedo LIST]\n"
         "                           [--tau LIST] [--geometry ...] [--photons N] [--seed S]\n\n"
         "Fits the model of the higher scattering orders (2, 3, ...) of nbt-scatter's kernels: for each\n"
         "phase (the HG family at each g of --g, default 0,0.3,0.5,0.65,0.75,0.82,0.87,0.9,0.93,0.95; or\n"
         "one phase, --phase SPEC, e.g. hg2:g1=0.9,g2=-0.3,w=0.8 or sog:FILE) and geometry (inside: the\n"
         "camera in the medium; entering: the medium begins at the camera), one photon count\n"
         "(nbt_mc_kernel_run: first crossings of walls at the optical depths --tau, default\n"
         "0.125,0.25,...,64, in radial bins of 1/4 octave, weighted to every albedo of --albedo, default\n"
         "0.2,0.5,0.75,0.9,0.95,0.98,0.99,0.995,0.999); each (albedo, depth) is fitted as a non-negative\n"
         "mixture of atoms on whole octaves (nbt_screen_shape_fit). The first order is not in the model:\n"
         "libnbt computes it exactly. stderr: per run the time and the largest and mean misfit.\n"
         "This takes minutes per g (--photons, default 1e6; paths at albedo 0.999 are long).\n\n"
         "--check: fresh counts (--seed, default 101) at the given points, compared with the model's\n"
         "higher orders and with the whole kernel (exact first order + model): one line per point,\n"
         "'geometry g albedo tau mc_mass model_mass bias relL1 relL1_total mc_noise' (relL1: sum over\n"
         "radial bins of |model - counts| / counts' mass).");
}

static size_t parse_list(const char *opt, const char *arg, double *v, double lo, double hi)
{
    size_t n = 0;
    const char *p = arg;
    char buf[64];
    for (;;) {
        size_t k = strcspn(p, ",");
        if (k == 0 || k >= sizeof buf || n == MAXL)
            die_usage("%s: '%s' is not accepted: expected a comma-separated list of at most %d numbers", opt, arg, MAXL);
        memcpy(buf, p, k);
        buf[k] = '\0';
        double x;
        if (parse_double(buf, lo, 1, hi, 1, &x) != 0 || (n && !(x > v[n - 1])))
            die_usage("%s: '%s' is not accepted: expected increasing numbers in (%g, %g)", opt, arg, lo, hi);
        v[n++] = x;
        if (!p[k])
            break;
        p += k + 1;
    }
    return n;
}

/* radial bin edges, in units of the depth: 2^(i/4), i = -56 .. 40 */
#define E_LO (-56)
#define E_HI 40
#define NE (E_HI - E_LO + 1)

static void progress_cb(double f, void *data)
{
    progress_fraction(data, f);
}

static nbt_mc_kernel_result *count(const nbt_phase *p, int geo, const double *tau, size_t nt, const double *alb,
                                   size_t na, double photons, long seed, long threads, progress *pr)
{
    static double e[NE];
    for (int i = 0; i < NE; i++)
        e[i] = exp2(0.25 * (double)(E_LO + i));
    nbt_mc_kernel_config c = {.phase = p,
                              .infinite = geo == NBT_SCREEN_INSIDE,
                              .nplanes = nt,
                              .z_planes = tau,
                              .nedges = NE,
                              .edges = e,
                              .nalbedo = na,
                              .albedo = alb,
                              .photons = (uint64_t)photons,
                              .seed = (uint64_t)seed,
                              .threads = (unsigned)threads,
                              .progress = progress_cb,
                              .progress_data = pr};
    nbt_mc_kernel_result *r;
    if (nbt_mc_kernel_run(&c, &r) != NBT_OK)
        die("photon counting failed for %s", nbt_phase_name(p));
    return r;
}

static const double *bins(const nbt_mc_kernel_result *r, size_t it, size_t ia, int order2, int se)
{
    return (se ? r->mass_se : r->mass) + ((it * r->nalbedo + ia) * 2 + (size_t)order2) * r->nbins;
}

int cmd_screenmodel(int argc, char **argv)
{
    static const struct option lo[] = {{"output", 1, 0, 'o'}, {"phase", 1, 0, 'p'},   {"g", 1, 0, 'g'},
                                       {"albedo", 1, 0, 'a'}, {"tau", 1, 0, 't'},     {"geometry", 1, 0, 'G'},
                                       {"photons", 1, 0, 'n'}, {"seed", 1, 0, 's'},   {"threads", 1, 0, 'j'},
                                       {"check", 1, 0, 'c'},  {"quiet", 0, 0, 'q'},   {"help", 0, 0, 'h'},
                                       {0, 0, 0, 0}};
    const char *out = NULL, *spec = NULL, *check = NULL, *tau_arg = NULL;
    double g[MAXL] = {0, 0.3, 0.5, 0.65, 0.75, 0.82, 0.87, 0.9, 0.93, 0.95};
    double alb[MAXL] = {0.2, 0.5, 0.75, 0.9, 0.95, 0.98, 0.99, 0.995, 0.999};
    double tau[MAXL] = {0.125, 0.25, 0.5, 1, 2, 4, 8, 16, 32, 64};
    size_t ng = 10, na = 9, nt = 10;
    int geos[2] = {1, 1}, quiet = 0, gset = 0;
    double photons = 1e6;
    long seed = -1, threads = 0;
    int c;
    while ((c = getopt_long(argc, argv, ":o:h", lo, NULL)) != -1) {
        switch (c) {
        case 'o': out = optarg; break;
        case 'p': spec = optarg; break;
        case 'g': ng = parse_list("--g", optarg, g, -1, 1); gset = 1; break;
        case 'a': na = parse_list("--albedo", optarg, alb, 0, 1); break;
        case 't': nt = parse_list("--tau", optarg, tau, 0, 1e4); tau_arg = optarg; break;
        case 'G':
            /* exactly the listed words: a substring test took 'inside,tide' for inside */
            geos[0] = !strcmp(optarg, "inside") || !strcmp(optarg, "inside,entering");
            geos[1] = !strcmp(optarg, "entering") || !strcmp(optarg, "inside,entering");
            if (!geos[0] && !geos[1])
                die_usage("--geometry: '%s' is not accepted: expected inside, entering or inside,entering", optarg);
            break;
        case 'n': photons = opt_double("--photons", optarg, 16, 0, 1e12, 0); break;
        case 's': seed = opt_long("--seed", optarg, 0, 2147483647L); break;
        case 'j': threads = opt_long("--threads", optarg, 0, 64); break;
        case 'c': check = optarg; break;
        case 'q': quiet = 1; break;
        case 'h': help(); return 0;
        default: die_bad_option(c, argv, "nbt-fit screenmodel");
        }
    }
    if (optind != argc)
        die_usage("screenmodel: unexpected argument '%s'", argv[optind]);
    if (spec && gset)
        die_usage("--phase and --g exclude each other: one phase, or the HG family at each g");
    if (!check && !out)
        die_usage("screenmodel: -o MODEL.txt is required (or --check MODEL.txt)");
    if (check && out)
        die_usage("screenmodel: --check writes nothing; drop -o");
    if (nt < 2 && !check)
        die_usage("--tau: '%s' is not accepted: a model needs two or more depths", tau_arg);
    if (seed < 0)
        seed = check ? 101 : 1;
    char err[512];
    nbt_phase *fixed = NULL;
    if (spec && nbt_phase_parse(spec, &fixed, err, sizeof err) != NBT_OK)
        die_usage("--phase: %s", err);
    if (out)
        check_writable("-o", out);
    nbt_screen_model *own = NULL;
    const nbt_screen_model *model = NULL;
    if (check) {
        if (!strcmp(check, "default"))
            model = nbt_screen_model_default();
        else if (nbt_screen_model_read(check, &own, err, sizeof err) == NBT_OK)
            model = own;
        else
            die_usage("--check: %s", err);
        if (!model)
            die("the compiled-in model could not be read");
    } else {
        own = nbt_screen_model_alloc(fixed, ng, g, na, alb, nt, tau);
        if (!own)
            die_usage("screenmodel: the grid is not accepted: --g in (-1, 1), --albedo in (0, 1), increasing");
    }
    progress pr;
    progress_init(&pr, "screenmodel", quiet);
    size_t np = fixed ? 1 : ng;
    double worst = 0, sum = 0;
    size_t nfit = 0;
    if (check)
        printf("# geometry g albedo tau mc_mass model_mass bias relL1 relL1_total mc_noise\n");
    for (int geo = 0; geo < 2; geo++) {
        if (!geos[geo])
            continue;
        for (size_t ip = 0; ip < np; ip++) {
            nbt_phase *p = fixed ? fixed : nbt_phase_hg(g[ip]);
            if (!p)
                die("out of memory");
            double t0 = progress_clock();
            progress_note(&pr, "%s %s: counting %.3g photons", geo ? "entering" : "inside", nbt_phase_name(p), photons);
            nbt_mc_kernel_result *r = count(p, geo, tau, nt, alb, na, photons, seed + (long)(ip * 2 + (size_t)geo),
                                            threads, &pr);
            double rw = 0, rs = 0;
            size_t rn = 0;
            for (size_t ia = 0; ia < na; ia++)
                for (size_t it = 0; it < nt; it++) {
                    const double *m2 = bins(r, it, ia, 1, 0), *s2 = bins(r, it, ia, 1, 1);
                    double e[NE];
                    for (int i = 0; i < NE; i++)
                        e[i] = exp2(0.25 * (double)(E_LO + i));
                    double M = 0;
                    for (size_t b = 0; b < r->nbins; b++)
                        M += m2[b];
                    if (check) {
                        nbt_screen_shape sh;
                        if (nbt_screen_model_eval(model, p, (nbt_screen_geometry)geo, alb[ia], tau[it], &sh, NULL) !=
                            NBT_OK)
                            die("the model does not cover %s (%s)", nbt_phase_name(p), geo ? "entering" : "inside");
                        /* the whole kernel: counts of every order against the exact first order plus the model */
                        nbt_screen_kernel *k = nbt_screen_kernel_phase(NBT_SKERNEL_FIRST, 1.0, alb[ia], p,
                                                                       (nbt_screen_geometry)geo, NULL);
                        nbt_screen_kern kn;
                        if (!k || nbt_screen_kernel_eval(k, tau[it], &kn) != NBT_OK)
                            die("the first order at tau %g could not be evaluated", tau[it]);
                        const double *m1 = bins(r, it, ia, 0, 0), *s1 = bins(r, it, ia, 0, 1);
                        double l1 = 0, l1t = 0, Mm = 0, Mt = 0, noise = 0;
                        for (size_t b = 0; b < r->nbins; b++) {
                            double blo = b ? e[b - 1] : 0, bhi = b < NE ? e[b] : INFINITY;
                            double fm = nbt_screen_shape_mass(&sh, blo, bhi), f1 = 0;
                            for (size_t a = 0; a < kn.n; a++)
                                f1 += kn.mass[a] * nbt_screen_atom_mass(kn.shape[a], blo / (kn.scale[a] / tau[it]),
                                                                         bhi / (kn.scale[a] / tau[it]));
                            l1 += fabs(fm - m2[b]);
                            l1t += fabs(fm + f1 - m2[b] - m1[b]);
                            Mm += fm;
                            Mt += m1[b] + m2[b];
                            noise += sqrt(s1[b] * s1[b] + s2[b] * s2[b]);
                        }
                        nbt_screen_kernel_free(k);
                        printf("%s %g %g %g %.6g %.6g %+.4f %.4f %.4f %.4f\n", geo ? "entering" : "inside",
                               fixed ? NAN : g[ip], alb[ia], tau[it], M, Mm, M > 0 ? Mm / M - 1 : 0,
                               M > 0 ? l1 / M : 0, Mt > 0 ? l1t / Mt : 0, Mt > 0 ? noise * sqrt(2 / 3.14159265358979323846) / Mt : 0);
                        continue;
                    }
                    nbt_screen_shape sh;
                    double mis = 0;
                    if (M > 0 && nbt_screen_shape_fit(NE, e, m2, s2, 2, &sh, &mis) != NBT_OK)
                        die("the shape fit failed at %s albedo %g tau %g", nbt_phase_name(p), alb[ia], tau[it]);
                    if (!(M > 0))
                        continue; /* no light counted: the node stays empty (the model gives 0 there) */
                    if (nbt_screen_model_set(own, (nbt_screen_geometry)geo, ip, ia, it, &sh) != NBT_OK)
                        die("the model could not hold the fit");
                    /* the misfit of bins with real mass; counts far down the tail are noise */
                    if (M > 1e-4) {
                        rw = fmax(rw, mis);
                        rs += mis;
                        rn++;
                    }
                }
            if (!check) {
                progress_note(&pr, "%s %s: %.1f s, misfit max %.4f mean %.4f (relative L1 of the radial masses, "
                              "nodes with mass > 1e-4)", geo ? "entering" : "inside", nbt_phase_name(p),
                              progress_clock() - t0, rw, rn ? rs / (double)rn : 0);
                worst = fmax(worst, rw);
                sum += rs;
                nfit += rn;
            }
            nbt_mc_kernel_result_free(r);
            if (!fixed)
                nbt_phase_free(p);
        }
    }
    progress_end(&pr);
    int rc = 0;
    if (!check) {
        char comment[1024];
        snprintf(comment, sizeof comment,
                 "fitted by nbt-fit screenmodel (nbt %s): %.3g photons per phase and geometry, seed %ld;\n"
                 "radial bins of 1/4 octave, atoms on whole octaves; misfit (relative L1 of the radial masses)\n"
                 "max %.4f, mean %.4f over %zu nodes with mass > 1e-4",
                 nbt_version(), photons, seed, worst, nfit ? sum / (double)nfit : 0, nfit);
        if (nbt_screen_model_write(own, out, comment, err, sizeof err) != NBT_OK)
            die("%s", err);
    }
    nbt_screen_model_free(own);
    nbt_phase_free(fixed);
    return rc;
}
