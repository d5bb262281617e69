/* bench/bench_screen.c: the screen-space references' run time beside their
 * agreement. Brute force and layered FFT on the same layered scene (small),
 * then the layered FFT alone at 1920x1080 with 8 layers (operator A). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>
#include <nbt/nbt.h>

static double now(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

/* 8 layers: vertical bands at increasing depth, a textured colour */
static void scene(size_t w, size_t h, float *rgb, float *D)
{
    for (size_t y = 0; y < h; y++)
        for (size_t x = 0; x < w; x++) {
            size_t i = y * w + x, band = (x * 8 / w + y * 3 / h) % 8;
            D[i] = (float)(2.0 + 1.7 * (double)band);
            rgb[3 * i] = (float)(0.2 + 0.8 * (((x / 16) + (y / 16)) % 2));
            rgb[3 * i + 1] = 0.5f;
            rgb[3 * i + 2] = (float)(0.3 + 0.1 * (double)band);
        }
    rgb[3 * (h / 2 * w + w / 2)] = 500.0f; /* an HDR lamp */
}

int main(int argc, char **argv)
{
    nbt_beam_medium m = nbt_beam_homogeneous(0.15, 0.9, 0.0076); /* dtheta = 10 deg */
    nbt_screen_kernel *k = nbt_screen_kernel_alloc(NBT_SKERNEL_MOMENT, &m, NULL);
    const double tail = 1e-7;
    printf("# screen-space references, operator A, moment kernel, sigma_t 0.15, albedo 0.9, dtheta 10 deg\n");
    printf("# %-10s %-12s %9s %9s %12s\n", "size", "method", "fov_y", "time_s", "max_rel_diff");
    (void)argv;
    for (int pass = argc > 1; pass < 2; pass++) {
        size_t w = pass ? 1920 : 160, h = pass ? 1080 : 120, np = w * h;
        float *rgb = malloc(np * 3 * sizeof *rgb), *D = malloc(np * sizeof *D);
        double *S1 = malloc(np * 3 * sizeof *S1), *S2 = malloc(np * 3 * sizeof *S2);
        if (!rgb || !D || !S1 || !S2)
            return 1;
        scene(w, h, rgb, D);
        double fov = 40.0, dth = 2 * tan(fov * M_PI / 360) / (double)h;
        nbt_screen_input in = {w, h, rgb, D, dth, NULL};
        double t0 = now();
        nbt_screen_layered(&in, k, NBT_SCREEN_NEAR, tail, 8, 0, S1, NULL);
        double t1 = now();
        char sz[32];
        snprintf(sz, sizeof sz, "%zux%zu", w, h);
        printf("  %-10s %-12s %9.1f %9.3f %12s\n", sz, "layered-fft", fov, t1 - t0, "-");
        if (!pass) {
            nbt_screen_brute(&in, k, NBT_SCREEN_NEAR, tail, 0, S2, NULL);
            double t2 = now(), d = 0, mx = 0;
            for (size_t i = 0; i < np * 3; i++) {
                d = fmax(d, fabs(S1[i] - S2[i]));
                mx = fmax(mx, fabs(S2[i]));
            }
            printf("  %-10s %-12s %9.1f %9.3f %12.2e\n", sz, "brute", fov, t2 - t1, d / mx);
        }
        free(rgb);
        free(D);
        free(S1);
        free(S2);
    }
    nbt_screen_kernel_free(k);
    return 0;
}
