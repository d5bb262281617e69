/* fit/cmd_mc.c: "nbt-fit mc": photon counting to CSV (z,r_lo,r_hi,psi,psi_stderr),
 * slab reflectance and transmittance to stdout. */
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
#include "../gen/progress.h"
#include "commands.h"
#ifdef HAVE_MPI
#include "mc_mpi.h"
#endif
#ifdef HAVE_GL
#include <nbt/gl_mc.h>
#include "../examples/egl_headless.h"
#endif

/* Launched by mpirun (or srun)? Rank and size from the launcher's
 * environment, read before MPI starts, so that usage errors need no MPI. */
static int launcher_env(int *rank, int *size)
{
    static const char *sizes[] = {"OMPI_COMM_WORLD_SIZE", "PMI_SIZE"};
    static const char *ranks[] = {"OMPI_COMM_WORLD_RANK", "PMI_RANK"};
    *rank = 0;
    *size = 1;
    for (int i = 0; i < 2; i++) {
        const char *s = getenv(sizes[i]), *r = getenv(ranks[i]);
        if (s && r && atoi(s) >= 1 && atoi(r) >= 0) {
            *size = atoi(s);
            *rank = atoi(r);
            return 1;
        }
    }
    return 0;
}

static void help(void)
{
    puts("Usage: nbt-fit mc --albedo W --sigma-t ST (--B B | --phase SPEC) --photons N -o OUT.csv|OUT.exr\n"
         "                  [--seed S] [--threads T] [--z-planes FROM:TO:COUNT] [--r-bins N]\n"
         "                  [--r-max-scale F] [--density FILE] [--z-cut Z] [--infinite] [--order-max N]\n"
         "                  [--estimator analog|weighted] [--gpu] [--quiet]\n"
         "       nbt-fit mc --albedo W --sigma-t ST (--B B | --phase SPEC) --photons N --slab TAU [-o OUT.csv]\n\n"
         "A pencil beam enters at the origin along +z; every forward crossing of a plane z by a\n"
         "scattered photon is counted, per unit area per launched photon, in radial bins over\n"
         "[0, F z) (default F = 1, 50 bins, planes 1:10:10). OUT.csv has the columns\n"
         "z,r_lo,r_hi,psi,psi_stderr; OUT.exr is a PSI table (axis 0 r/z at the bin centres,\n"
         "axis 1 z; R = psi, G = psi_stderr; see nbt-gen info). stdout gets\n"
         "'M z M0 M0_stderr M2 M2_stderr' per plane.\n"
         "--B B is the Gaussian phase of Shinya et al. eq. 13 (dtheta^2 = 4B); --phase takes\n"
         "iso, rayleigh, hg:g=G, gauss:B=B, table:FILE. --density FILE: lines 'z rho'.\n"
         "--slab TAU: a slab of optical thickness TAU (at density 1); stdout gets\n"
         "'R value stderr' and 'T value stderr' (T includes unscattered light).\n"
         "--infinite: the medium fills all space (a source inside fog): photons going to z < 0\n"
         "keep scattering (at the density of z = 0+) and may come back; they are dropped below\n"
         "-z_cut. The default is a beam entering a half-space from vacuum. Not with --slab.\n"
         "--order-max N: count only photons scattered at most N times (1: single scattering).\n"
         "--estimator weighted: survival biasing with Russian roulette (MCML's rule): photons are\n"
         "never absorbed but lose weight; the same expectations, other variances and costs (see\n"
         "doc/beam.md). The default, analog, counts photons.\n"
         "--gpu: the GLSL compute counter (OpenGL 4.3 through EGL; Mesa's llvmpipe on a machine\n"
         "without a GPU): a homogeneous slab or half-space, HG/iso/Gaussian phase, analog; its own\n"
         "random numbers (Philox), identical on every run; one process.\n"
         "Results are identical for any --threads; standard errors from 64 batches.\n"
         "Progress goes to stderr as batches finish: percent done, elapsed time and ETA (a line\n"
         "rewritten in place on a terminal; otherwise one line at most every 2 s,\n"
         "NBT_PROGRESS_SECONDS changes that), with one warning line as soon as the first\n"
         "batches predict more than 60 s. --quiet: no progress and no timing line.\n\n"
         "mpirun -np N nbt-fit mc ... splits the 64 photon batches over N processes (on one or\n"
         "many machines; --threads counts per process) and writes, from rank 0, output identical\n"
         "byte for byte to a one-process run with the same seed (ranks beyond 64 get no photons).\n"
         "This needs a build configured --with-mpi.");
}

#ifdef HAVE_GL
/* the reason libnbt-gl gives for a refusal, for the message */
static char gpu_reason[256];
static void on_gpu_error(const char *reason, nbt_status st)
{
    (void)st;
    snprintf(gpu_reason, sizeof gpu_reason, "%s", reason);
}
#endif

/* the library calls this from the calling thread as batches finish */
static void on_progress(double f, void *data)
{
    progress_fraction(data, f);
}

static int write_csv(const char *out, const nbt_mc_config *c, const nbt_mc_result *r)
{
    char *tmp;
    FILE *f = out_open(out, &tmp);
    if (!f) {
        fprintf(stderr, "%s: cannot write '%s': %s\n", cli_prog, out, strerror(errno));
        return 1;
    }
    fprintf(f, "z,r_lo,r_hi,psi,psi_stderr\n");
    for (size_t j = 0; j < c->nplanes; j++) {
        double dr = c->r_max_scale * c->z_planes[j] / (double)c->r_bins;
        for (size_t k = 0; k < c->r_bins; k++)
            fprintf(f, "%.17g,%.17g,%.17g,%.17g,%.17g\n", c->z_planes[j], dr * (double)k, dr * (double)(k + 1),
                    r->psi[j * c->r_bins + k], r->psi_se[j * c->r_bins + k]);
    }
    if (out_close(f, tmp, out, 1)) {
        fprintf(stderr, "%s: cannot write '%s': %s\n", cli_prog, out, strerror(errno));
        return 1;
    }
    return 0;
}

/* A PSI table: axis 0 = r/z at the bin centres, axis 1 = z at the planes
 * (evenly spaced), channels R = psi, G = its standard error. */
static int write_exr(const char *out, const nbt_mc_config *c, const nbt_mc_result *r, const char *phase, double B,
                     double tau, int gpu)
{
    size_t nb = c->r_bins, np = c->nplanes;
    double h = c->r_max_scale / (double)nb;
    nbt_axis a0 = {0.5 * h, c->r_max_scale - 0.5 * h, NBT_AXIS_LINEAR, 0, nb};
    nbt_axis a1 = {c->z_planes[0], c->z_planes[np - 1], NBT_AXIS_LINEAR, 0, np};
    nbt_table *t = nbt_table_alloc(NBT_TABLE_PSI, &a0, &a1, 2);
    if (!t)
        die("out of memory");
    t->k[0] = t->k[1] = -1;
    char ph[64];
    if (phase)
        snprintf(ph, sizeof ph, "%s", phase);
    else
        snprintf(ph, sizeof ph, "gauss:B=%g", B);
    char run[512];
    char ord[32] = "";
    if (c->order_max)
        snprintf(ord, sizeof ord, " order_max=%u", c->order_max);
    snprintf(run, sizeof run, "mc albedo=%g sigma_t=%g phase=%s photons=%llu seed=%llu%s%s%s%s%s", c->albedo,
             c->sigma_t, ph, (unsigned long long)c->photons, (unsigned long long)c->seed, tau > 0 ? " slab" : "",
             c->infinite ? " infinite" : "", ord, c->estimator == NBT_MC_WEIGHTED ? " weighted" : "",
             gpu ? " gpu" : "");
    size_t n = strlen(run) < sizeof t->phase ? strlen(run) : sizeof t->phase - 1; /* a long table path is cut */
    memcpy(t->phase, run, n);
    t->phase[n] = '\0';
    for (size_t j = 0; j < np; j++)
        for (size_t k = 0; k < nb; k++) {
            t->data[(j * nb + k) * 2] = (float)r->psi[j * nb + k];
            t->data[(j * nb + k) * 2 + 1] = (float)r->psi_se[j * nb + k];
            t->max_abs[0] = fmax(t->max_abs[0], r->psi[j * nb + k]);
            t->max_abs[1] = fmax(t->max_abs[1], r->psi_se[j * nb + k]);
        }
    t->max_err[0] = t->max_err[1] = NAN; /* data, not an interpolated function: see the G channel */
    nbt_status st = nbt_table_write_exr(t, out, NBT_EXR_ZIP);
    nbt_table_free(t);
    if (st != NBT_OK) {
        fprintf(stderr, "%s: cannot write '%s'\n", cli_prog, out);
        return 1;
    }
    return 0;
}

int cmd_mc(int argc, char **argv)
{
    static const struct option opts[] = {
        {"albedo", required_argument, 0, 'a'},  {"sigma-t", required_argument, 0, 's'},
        {"B", required_argument, 0, 'B'},       {"phase", required_argument, 0, 'p'},
        {"photons", required_argument, 0, 'n'}, {"seed", required_argument, 0, 'S'},
        {"threads", required_argument, 0, 'j'}, {"z-planes", required_argument, 0, 'z'},
        {"r-bins", required_argument, 0, 'r'},  {"r-max-scale", required_argument, 0, 'F'},
        {"slab", required_argument, 0, 'L'},    {"density", required_argument, 0, 'd'},
        {"z-cut", required_argument, 0, 'c'},   {"output", required_argument, 0, 'o'},
        {"infinite", no_argument, 0, 'I'},      {"order-max", required_argument, 0, 'O'},
        {"estimator", required_argument, 0, 'E'}, {"gpu", no_argument, 0, 'G'},
        {"quiet", no_argument, 0, 'q'},
        {"help", no_argument, 0, 'h'},          {0, 0, 0, 0}};
    int rank, size, launched = launcher_env(&rank, &size);
    if (rank != 0 && !freopen("/dev/null", "w", stderr)) /* one message per run: rank 0 speaks */
        return 1;
#ifndef HAVE_MPI
    if (launched && size > 1)
        die_usage("mc: started as %d MPI ranks, but this nbt-fit was built without MPI (install libopenmpi-dev "
                  "openmpi-bin and configure --with-mpi); every rank would run the whole job", size);
#endif
    nbt_mc_config c;
    memset(&c, 0, sizeof c);
    c.r_bins = 50;
    c.r_max_scale = 1;
    c.seed = 1;
    const char *out = NULL, *phase = NULL, *density = NULL, *planes = "1:10:10";
    double B = 0, tau = 0;
    int have[4] = {0}, gpu = 0, quiet = 0;
    int o;
    optind = 1;
    while ((o = getopt_long_only(argc, argv, ":o:h", opts, NULL)) != -1) {
        switch (o) {
        case 'a': c.albedo = opt_double("--albedo", optarg, 0, 0, 1, 0); have[0] = 1; break;
        case 's': c.sigma_t = opt_double("--sigma-t", optarg, 0, 1, 1e12, 0); have[1] = 1; break;
        case 'B': B = opt_double("--B", optarg, 0, 1, NBT_PHASE_GAUSS_BMAX, 0); break;
        case 'p': phase = optarg; break;
        case 'n': c.photons = (uint64_t)opt_double("--photons", optarg, 64, 0, 1e15, 0); have[2] = 1; break;
        case 'S': c.seed = (uint64_t)opt_long("--seed", optarg, 0, 0x7fffffffL); break;
        case 'j': c.threads = (unsigned)opt_long("--threads", optarg, 0, 64); break;
        case 'z': planes = optarg; break;
        case 'r': c.r_bins = (size_t)opt_long("--r-bins", optarg, 1, 100000); break;
        case 'F': c.r_max_scale = opt_double("--r-max-scale", optarg, 0, 1, 1e6, 0); break;
        case 'L': tau = opt_double("--slab", optarg, 0, 1, 1e6, 0); break;
        case 'd': density = optarg; break;
        case 'c': c.z_cut = opt_double("--z-cut", optarg, 0, 1, 1e15, 0); break;
        case 'I': c.infinite = 1; break;
        case 'O': c.order_max = (unsigned)opt_long("--order-max", optarg, 1, 1000000); break;
        case 'E':
            if (!strcmp(optarg, "analog"))
                c.estimator = NBT_MC_ANALOG;
            else if (!strcmp(optarg, "weighted"))
                c.estimator = NBT_MC_WEIGHTED;
            else
                die_usage("--estimator: '%s' is not accepted: analog or weighted", optarg);
            break;
        case 'G': gpu = 1; break;
        case 'q': quiet = 1; break;
        case 'o': out = optarg; break;
        case 'h': help(); return 0;
        default: die_bad_option(o, argv, "nbt-fit mc");
        }
    }
    if (optind < argc)
        die_usage("mc: unexpected argument '%s'", argv[optind]);
    static const char *const need[3] = {"--albedo A", "--sigma-t S", "--photons N"};
    for (int i = 0; i < 3; i++)
        if (!have[i])
            die_usage("mc: %s is required (--albedo, --sigma-t and --photons are)", need[i]);
    if ((B > 0) == (phase != NULL))
        die_usage("mc: give the phase function with exactly one of --B B and --phase SPEC");
    if (tau > 0 && density)
        die_usage("--slab and --density exclude each other");
    if (tau > 0 && c.infinite)
        die_usage("--infinite and --slab exclude each other: a slab has vacuum on both sides");
    if (!out && tau == 0)
        die_usage("mc: -o OUT.csv is required (except for a --slab run)");
    if (gpu && launched && size > 1)
        die_usage("--gpu runs in one process: start it without mpirun");
#ifndef HAVE_GL
    if (gpu)
        die_usage("--gpu: this nbt-fit was built without OpenGL (install libegl-dev libopengl-dev libegl-mesa0 "
                  "libgl1-mesa-dri and configure --with-gl)");
#endif
    int exr = 0;
    if (out) {
        size_t n = strlen(out);
        exr = n >= 5 && !strcmp(out + n - 4, ".exr");
        if (n < 5 || (strcmp(out + n - 4, ".csv") && !exr))
            die_usage("-o: '%s' is not accepted: the output must end in .csv or .exr", out);
    }
    nbt_phase *ph = NULL;
    char err[512];
    if (phase) {
        if (nbt_phase_parse(phase, &ph, err, sizeof err) != NBT_OK)
            die_usage("--phase: %s", err);
    } else if (!(ph = nbt_phase_gauss(B)))
        die("out of memory");
    c.phase = ph;
    double *zp = NULL, *zl = NULL, *rl = NULL;
    if (out) {
        double from, to;
        long count;
        char extra;
        if (sscanf(planes, "%lf:%lf:%ld%c", &from, &to, &count, &extra) != 3 || !(from > 0) || !(to >= from) ||
            !isfinite(to) || count < 1 || count > 10000 || (count > 1 && !(to > from)))
            die_usage("--z-planes: '%s' is not accepted: expected FROM:TO:COUNT with 0 < FROM <= TO, "
                      "1 <= COUNT <= 10000 (FROM < TO when COUNT > 1)", planes);
        if (exr && (count < 2 || c.r_bins < 2))
            die_usage("-o %s: an EXR table needs at least 2 planes and 2 r bins", out);
        zp = malloc((size_t)count * sizeof(double));
        if (!zp)
            die("out of memory");
        for (long i = 0; i < count; i++)
            zp[i] = count == 1 ? from : from + (to - from) * (double)i / (double)(count - 1);
        c.nplanes = (size_t)count;
        c.z_planes = zp;
    }
    if (out && rank == 0)
        check_writable("-o", out);
    if (density) {
        if (nbt_density_read(density, &zl, &rl, &c.nlayers, err, sizeof err) != NBT_OK)
            die_usage("--density: %s", err);
        c.z = zl;
        c.rho = rl;
    }
    if (tau > 0)
        c.slab = tau / c.sigma_t;
    progress prog;
    progress_init(&prog, "mc", quiet || rank != 0);
    c.progress = on_progress;
    c.progress_data = &prog;
    nbt_mc_result *r = NULL;
    nbt_status st;
#ifdef HAVE_GL
    if (gpu) {
        char gerr[256];
        if (egl_headless_open(gerr, sizeof gerr))
            die_usage("--gpu: no OpenGL context: %s", gerr);
        nbt_error_handler *prev = nbt_set_error_handler(on_gpu_error);
        st = nbt_gl_mc_run(&c, 0, 0, &r);
        nbt_set_error_handler(prev);
        egl_headless_close();
        if (st == NBT_EINVAL)
            die_usage("--gpu: %s", gpu_reason);
        if (st != NBT_OK)
            die("photon counting on the GPU failed: %s", gpu_reason[0] ? gpu_reason : nbt_strerror(st));
    } else
#endif
#ifdef HAVE_MPI
    if (launched) {
        char merr[256];
        if (mc_mpi_start(&rank, &size))
            die("mc: MPI_Init failed");
        st = mc_mpi_run(&c, rank, size, &r, merr, sizeof merr);
        mc_mpi_stop();
        if (st != NBT_OK)
            die("photon counting failed: %s", merr);
        if (rank != 0) { /* rank 0 writes */
            nbt_phase_free(ph);
            free(zp);
            free(zl);
            free(rl);
            return 0;
        }
    } else
#endif
    {
        st = nbt_mc_run(&c, &r);
        if (st != NBT_OK)
            die("photon counting failed: %s", nbt_strerror(st));
    }
    progress_end(&prog);
    int rc = 0;
    if (out && exr)
        rc = write_exr(out, &c, r, phase ? phase : NULL, B, tau, gpu);
    else if (out)
        rc = write_csv(out, &c, r);
    for (size_t j = 0; j < c.nplanes && out && rc == 0; j++)
        printf("M %.17g %.17g %.17g %.17g %.17g\n", zp[j], r->M0[j], r->M0_se[j], r->M2[j], r->M2_se[j]);
    if (tau > 0 && rc == 0) {
        printf("R %.17g %.17g\n", r->R, r->R_se);
        printf("T %.17g %.17g\n", r->T, r->T_se);
    }
    if (!quiet)
        fprintf(stderr, "%s: %llu photons in %.3f s (%.3g photons/s%s)\n", cli_prog, (unsigned long long)c.photons,
            r->seconds, (double)c.photons / r->seconds, size > 1 ? ", all ranks" : "");
    nbt_mc_result_free(r);
    nbt_phase_free(ph);
    free(zp);
    free(zl);
    free(rl);
    return rc;
}
