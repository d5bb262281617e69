/* bench/bench_path.c: time and 4x4-binned noise of the path-traced screen
 * reference (nbt_screen_path) at 160x120 on a wall with HDR lamps, HG g 0.9,
 * albedo 0.95, optical depth 2 to the wall, 2 threads; then the time to 1%
 * binned noise. Usage: bench_path [threads] [target] [maxspp] [run] (defaults
 * 2, 0.01, 64, 1; maxspp: the largest of 4, 16, 64 measured; run 0: predict
 * the time to the target only). */
#include <config.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>
#include <nbt/nbt.h>

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

int main(int argc, char **argv)
{
    unsigned threads = argc > 1 ? (unsigned)atoi(argv[1]) : 2;
    double target = argc > 2 ? atof(argv[2]) : 0.01;
    unsigned long maxspp = argc > 3 ? strtoul(argv[3], NULL, 10) : 64;
    int run = argc > 4 ? atoi(argv[4]) : 1;
    const size_t w = 160, h = 120;
    const double Zw = 4.0, sigma = 0.5; /* tau 2 to the wall */
    float *rgb = malloc(w * h * 3 * sizeof *rgb), *Z = malloc(w * h * sizeof *Z);
    /* a dim wall; four 3x3 lamps of radiance 50 (one warm, one in front of the wall) */
    const size_t lamps[4][2] = {{40, 30}, {110, 45}, {75, 80}, {130, 95}};
    for (size_t y = 0; y < h; y++)
        for (size_t x = 0; x < w; x++) {
            size_t i = y * w + x;
            Z[i] = (float)Zw;
            rgb[3 * i] = 0.3f;
            rgb[3 * i + 1] = 0.3f;
            rgb[3 * i + 2] = 0.35f;
            for (int k = 0; k < 4; k++)
                if (x >= lamps[k][0] && x < lamps[k][0] + 3 && y >= lamps[k][1] && y < lamps[k][1] + 3) {
                    rgb[3 * i] = 50.0f;
                    rgb[3 * i + 1] = k == 1 ? 30.0f : 50.0f;
                    rgb[3 * i + 2] = k == 1 ? 15.0f : 50.0f;
                    if (k == 2)
                        Z[i] = 2.5f;
                }
        }
    double dth = 2.0 * tan(0.5 * 40.0 * M_PI / 180.0) / (double)h; /* 40 degrees vertical */
    nbt_screen_world W = {.w = w, .h = h, .rgb = rgb, .Z = Z, .dtheta = dth, .cx = 0.5 * w, .cy = 0.5 * h,
                          .x0 = 0, .y0 = 0, .ow = w, .oh = h};
    nbt_phase *p = nbt_phase_hg(0.9);
    nbt_screen_path_medium m = {.sigma_t = {sigma, sigma, sigma}, .albedo = {0.95, 0.95, 0.95}, .phase = p,
                                .radius = INFINITY};
    double *S = malloc(w * h * 3 * sizeof *S), *se = malloc(w * h * 3 * sizeof *se);
    printf("# 160x120, wall tau 2, 4 HDR lamps, HG g 0.9, albedo 0.95, %u threads\n", threads);
    printf("# spp  seconds  binned_noise(4x4)  predicted_spp_for_%g  predicted_seconds\n", target);
    double rate = 0, noise1 = 0;
    unsigned long spp_list[3] = {4, 16, 64};
    for (int k = 0; k < 3 && spp_list[k] <= maxspp; k++) {
        nbt_screen_path_opts o = {.spp = spp_list[k], .seed = 1, .nthreads = threads};
        double t0 = now();
        if (nbt_screen_path(&W, &m, &o, S, se, NULL) != NBT_OK)
            return 1;
        double dt = now() - t0, n = nbt_screen_binned_noise(w, h, S, se, 4);
        double need = spp_list[k] * (n / target) * (n / target);
        rate = dt / spp_list[k];
        noise1 = n * sqrt((double)spp_list[k]);
        printf("%5lu  %7.2f  %.4f  %.0f  %.1f\n", spp_list[k], dt, n, need, need * rate);
        fflush(stdout);
    }
    double pred = (noise1 / target) * (noise1 / target) * rate;
    if (run && pred < 600) {
        nbt_screen_path_opts o = {.spp = 32, .seed = 2, .nthreads = threads, .target_noise = target,
                                  .max_spp = 100000, .progress = 1};
        unsigned long done = 0;
        double t0 = now();
        nbt_screen_path(&W, &m, &o, S, se, &done);
        printf("# to %.3g binned noise: %.1f s, %lu spp (noise %.4f)\n", target, now() - t0, done,
               nbt_screen_binned_noise(w, h, S, se, 4));
    } else
        printf("# to %.3g binned noise: predicted %.0f s, not run\n", target, pred);
    nbt_phase_free(p);
    free(rgb);
    free(Z);
    free(S);
    free(se);
    return 0;
}
