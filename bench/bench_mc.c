/* bench/bench_mc.c: photon-counting throughput on the van de Hulst slab
 * (albedo 0.9, tau 2, HG g 0.75; R = 0.09739, T = 0.66096), nbt_mc_run on
 * 1 and 2 threads side by side with a baseline in the same process: the
 * MCML algorithm as its paper describes it (weighted photons, implicit
 * capture, Russian roulette below weight 1e-4 with survival 1/10,
 * drand48), one thread. Usage: bench_mc [photons] */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <nbt/nbt.h>

static double now(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

/* MCML-style weighted transport in a matched slab [0, d], HG phase. */
static void mcml_like(long n, double mua, double mus, double g, double d, double *R, double *T, double *Rse)
{
    double rs = 0, ts = 0, rs2 = 0, mut = mua + mus;
    srand48(1);
    for (long i = 0; i < n; i++) {
        double z = 0, ux = 0, uy = 0, uz = 1, w = 1, rr = 0;
        for (;;) {
            double s = -log(drand48()) / mut;
            double zn = z + s * uz;
            if (zn < 0) {
                rr += w;
                break;
            }
            if (zn > d) {
                ts += w;
                break;
            }
            z = zn;
            w *= mus / mut; /* implicit capture: absorb the fraction mua/mut */
            double xi = drand48(), ct;
            if (g != 0) {
                double f = (1 - g * g) / (1 - g + 2 * g * xi);
                ct = (1 + g * g - f * f) / (2 * g);
            } else
                ct = 2 * xi - 1;
            double st = sqrt(1 - ct * ct), ph = 2 * M_PI * drand48(), cp = cos(ph), sp = sin(ph);
            if (fabs(uz) > 0.99999) {
                ux = st * cp;
                uy = st * sp;
                uz = uz > 0 ? ct : -ct;
            } else {
                double tmp = sqrt(1 - uz * uz), nx = st * (ux * uz * cp - uy * sp) / tmp + ux * ct;
                double ny = st * (uy * uz * cp + ux * sp) / tmp + uy * ct, nz = -st * cp * tmp + uz * ct;
                ux = nx;
                uy = ny;
                uz = nz;
            }
            if (w < 1e-4) { /* roulette */
                if (drand48() < 0.1)
                    w *= 10;
                else
                    break;
            }
        }
        rs += rr;
        rs2 += rr * rr;
    }
    *R = rs / n;
    *T = ts / n;
    *Rse = sqrt((rs2 / n - *R * *R) / n);
}

int main(int argc, char **argv)
{
    long n = argc > 1 ? atol(argv[1]) : 4000000;
    nbt_phase *hg = nbt_phase_hg(0.75);
    printf("# slab albedo 0.9, tau 2, HG g 0.75; van de Hulst R = 0.09739, T = 0.66096; %ld photons\n", n);
    printf("%-34s %8s %10s %10s %10s %14s\n", "method", "threads", "R", "R se", "T", "photons/s");
    double t0 = now(), R, T, Rse;
    mcml_like(n, 0.1, 0.9, 0.75, 2.0, &R, &T, &Rse);
    double tb = now() - t0;
    printf("%-34s %8d %10.5f %10.1e %10.5f %14.3g\n", "baseline: MCML algorithm (weighted)", 1, R, Rse, T, n / tb);
    for (unsigned th = 1; th <= 2; th++) {
        nbt_mc_config c;
        memset(&c, 0, sizeof c);
        c.sigma_t = 1;
        c.albedo = 0.9;
        c.phase = hg;
        c.slab = 2;
        c.photons = (uint64_t)n;
        c.seed = 1;
        c.threads = th;
        nbt_mc_result *r;
        nbt_mc_run(&c, &r);
        printf("%-34s %8u %10.5f %10.1e %10.5f %14.3g\n", "nbt_mc_run (analog, exact counts)", th, r->R, r->R_se, r->T,
               n / r->seconds);
        nbt_mc_result_free(r);
    }
    nbt_phase_free(hg);
    return 0;
}
