/* tests/test_gl_scatter.c: the GPU screen-space scattering methods
 * (nbt/gl_scatter.h) on Mesa llvmpipe through EGL surfaceless:
 *   (a) every pass validates with glslangValidator; each method's GL output
 *       equals its CPU emulation (tests/scatter_emul.c) to 1e-5 of max S on
 *       five generated scenes;
 *   (b) invariants: a constant wall receives M0 c (shinya within its window
 *       error, naive exactly); D = 0, sky and albedo 0 give S = 0; bad input
 *       is refused;
 *   (c) accuracy against libnbt's brute-force operators (A for every method,
 *       B for the pyramid methods), printed for the docs; shinya's relative
 *       L1 against A is asserted, and nbt's relative L1, edge band and bias
 *       against A, also at dtheta / 4 (beta_px to ~30), with its convergence
 *       in the slab count and its kernel's misplaced mass per beta; naive's
 *       (vs A) and elek's (vs A and B) relative L1 and edge band are gated
 *       against regressions;
 *   (d) time per method at 320x240 (after a first, compiling run).
 * Fails with a clear message when no GL context can be created. */
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>
#define GL_GLEXT_PROTOTYPES 1
#include <GL/gl.h>
#include <GL/glext.h>
#include <nbt/nbt.h>
#include <nbt/gl_scatter.h>
#include "../examples/egl_headless.h"
#include "scatter_emul.h"
#include "testutil.h"

/* the GL driver leaks at eglTerminate: no leak report for this program */
const char *__asan_default_options(void);
const char *__asan_default_options(void)
{
    return "detect_leaks=0";
}

#define W 64
#define H 48
#define NP (W * H)

/* shinya against operator A, relative L1 (measured: see the table printed by
 * this test; the tolerance is about 3x the worst scene) */
#define SHINYA_L1_TOL 3e-3

/* nbt against operator A on the five scenes (measured, 4 slabs: relative L1
 * 0.6 .. 2.9% (mean 1.4%), edge band <= 4.4%, bias +0.03 .. +0.15%; at
 * dtheta / 4 (beta_px to ~30) relative L1 0.65 .. 3.2%, bias -0.10 ..
 * +0.53% (blocks): see the printed table). Tolerances about 1.5x the worst
 * measured value of either setting; the goals are 3% mean, 5% worst, 5%
 * edge, 0.5% bias (the bias gate was 1.8% before nbt subtracted its
 * in-slab excess: +1.1% on the slanted plane; test_nbt_slope_bias holds
 * the 0.5% goal on continuous depth). */
#define NBT_L1_TOL 4.5e-2
#define NBT_MEAN_TOL 3e-2
#define NBT_EDGE_TOL 7e-2
#define NBT_BIAS_TOL 8e-3
/* the same beyond the screen (test_nbt_beyond_screen; measured relative L1
 * 0.06-0.75% for beta_px 0.3-30 (2.6-3.0% at 3-30 on the step), 1.2-3.1% for
 * beta_px 300-30000, where it is mostly bias (+1.2 .. +2.7%): the fitted
 * 1/r profile seen within 64 px; before the wide kernels 2.9-4.4%, bias
 * up to +4.4%), 1.5x */
#define NBT_WIDE_L1_TOL 4.7e-2
#define NBT_WIDE_BIAS_TOL 4.1e-2

/* regression gates for the other pyramid methods on the five scenes of (c),
 * about 1.5x the worst measured value (relative L1 / edge band):
 *   naive vs A (erfc kernel):  0.307 (step+lamp) / 0.592 (blocks)
 *   elek vs A (erfc kernel):   0.241 (step+lamp) / 0.616 (blocks)
 *   elek vs B (Elek's kernel): 0.163 (step+lamp) / 0.492 (blocks) */
#define NAIVE_A_L1_TOL 0.46
#define NAIVE_A_EDGE_TOL 0.89
#define ELEK_A_L1_TOL 0.36
#define ELEK_A_EDGE_TOL 0.92
#define ELEK_B_L1_TOL 0.25
#define ELEK_B_EDGE_TOL 0.74

typedef struct {
    const char *name;
    size_t w, h;
    float *rgb, *D, *M0, *beta, *sigma; /* beta: moment kernel; sigma: Elek kernel */
} scene;

static scene scene_new(const char *name, size_t w, size_t h)
{
    size_t n = w * h;
    scene s = {name, w, h, calloc(n * 3, sizeof(float)), calloc(n, sizeof(float)), calloc(n, sizeof(float)),
               calloc(n, sizeof(float)), calloc(n, sizeof(float))};
    return s;
}

static void scene_free(scene *s)
{
    free(s->rgb);
    free(s->D);
    free(s->M0);
    free(s->beta);
    free(s->sigma);
}

/* the per-pixel kernels libnbt computes for this medium */
static void scene_kernels(scene *s, const nbt_screen_kernel *km, const nbt_screen_kernel *ke, double dtheta)
{
    for (size_t i = 0; i < s->w * s->h; i++) {
        nbt_screen_kern a, b;
        nbt_screen_kernel_eval(km, s->D[i], &a);
        nbt_screen_kernel_eval(ke, s->D[i], &b);
        double px = s->D[i] * dtheta;
        s->M0[i] = a.n ? (float)a.mass[0] : 0.0f;
        s->beta[i] = a.n ? (float)(a.scale[0] / px) : 0.0f;
        s->sigma[i] = b.n ? (float)(b.scale[0] / px) : 0.0f;
    }
}

static double q(double v) /* multiples of 1/1024 */
{
    return floor(v * 1024) / 1024;
}

static void random_rgb(scene *s)
{
    for (size_t i = 0; i < s->w * s->h * 3; i++)
        s->rgb[i] = (float)q(t_uniform());
}

/* the five scenes of (a) and (c) */
static scene make_scene(int which)
{
    scene s;
    switch (which) {
    case 0: /* a textured plane facing the camera */
        s = scene_new("plane", W, H);
        random_rgb(&s);
        for (size_t i = 0; i < NP; i++)
            s.D[i] = 6.3f;
        break;
    case 1: /* a step edge, a far wall on the left, a near one with an HDR lamp beside the edge; sky on top */
        s = scene_new("step+lamp", W, H);
        random_rgb(&s);
        for (size_t y = 0; y < H; y++)
            for (size_t x = 0; x < W; x++)
                s.D[y * W + x] = y < 5 ? 1e10f : x < 30 ? 11.7f : 3.9f;
        for (size_t y = 22; y < 25; y++)
            for (size_t x = 31; x < 34; x++)
                for (int c = 0; c < 3; c++)
                    s.rgb[3 * (y * W + x) + c] = c == 1 ? 350.0f : 240.0f;
        break;
    case 2: /* three layers and sky */
        s = scene_new("3 layers", W, H);
        random_rgb(&s);
        for (size_t y = 0; y < H; y++)
            for (size_t x = 0; x < W; x++) {
                float D = y < 8 ? INFINITY : 15.2f;
                if (x >= 12 && x < 44 && y >= 14 && y < 40)
                    D = 7.3f;
                if ((x - 30) * (x - 30) + (y - 28) * (y - 28) < 64)
                    D = 2.9f;
                s.D[y * W + x] = D;
            }
        s.rgb[3 * (28 * W + 30) + 0] = 500.0f; /* a lamp on the nearest layer */
        break;
    case 3: /* a plane slanted in depth */
        s = scene_new("slanted", W, H);
        random_rgb(&s);
        for (size_t y = 0; y < H; y++)
            for (size_t x = 0; x < W; x++)
                s.D[y * W + x] = (float)(2.6 + 0.19 * x + 0.02 * y);
        break;
    default: /* random 8 x 8 blocks, some sky, a few HDR pixels */
        s = scene_new("blocks", W, H);
        random_rgb(&s);
        for (size_t by = 0; by < H / 8; by++)
            for (size_t bx = 0; bx < W / 8; bx++) {
                double u = t_uniform();
                float D = u < 0.12 ? 1e10f : (float)(2.0 + 18.0 * t_uniform());
                for (size_t y = 0; y < 8; y++)
                    for (size_t x = 0; x < 8; x++)
                        s.D[(by * 8 + y) * W + bx * 8 + x] = D;
            }
        for (int k = 0; k < 6; k++)
            s.rgb[3 * (size_t)(t_uniform() * NP) + (size_t)(t_uniform() * 3)] = 200.0f;
        break;
    }
    return s;
}

static nbt_gls_input gls_input(const scene *s, int elek_sigma, double dtheta)
{
    nbt_gls_input in = {s->w, s->h, s->rgb, s->D, s->M0, s->beta, elek_sigma ? s->sigma : NULL, dtheta,
                        NBT_GLS_CUT, NBT_GLS_EPS};
    return in;
}

/* max |S_gl - S_emul| / max |S_emul| */
static double gl_vs_emul(const float *Sg, const double *Se, size_t n)
{
    double d = 0, m = t_maxabs(Se, n);
    for (size_t i = 0; i < n; i++)
        d = fmax(d, isfinite(Sg[i]) ? fabs(Sg[i] - Se[i]) : INFINITY);
    return m > 0 ? d / m : d;
}

static void validate_passes(void)
{
    for (unsigned i = 0; i < nbt_gls_npasses(); i++) {
        char *src = nbt_gls_pass_source(i);
        char path[] = "/tmp/nbt-test-scatter-XXXXXX";
        int fd = mkstemp(path);
        FILE *f = fd >= 0 ? fdopen(fd, "w") : NULL;
        if (f) {
            fputs(src, f);
            fclose(f);
        }
        char cmd[256];
        snprintf(cmd, sizeof cmd, "glslangValidator -S comp %s >/dev/null 2>&1", path);
        int rc = f ? system(cmd) : -1;
        t_true(rc == 0, "glslangValidator accepts pass %s%s", nbt_gls_pass_name(i),
               rc == 0 ? "" : " (is glslang-tools installed?)");
        unlink(path);
        free(src);
    }
    t_true(nbt_gls_pass_source(nbt_gls_npasses()) == NULL, "no pass past the last");
    nbt_gls_method m;
    int names_ok = 1;
    for (int k = 0; k < NBT_GLS_NMETHODS; k++)
        names_ok &= nbt_gls_method_parse(nbt_gls_method_name((nbt_gls_method)k), &m) == NBT_OK && m == (nbt_gls_method)k;
    t_true(names_ok && nbt_gls_method_parse("bogus", &m) == NBT_EINVAL, "method names parse");
}

/* nbt's gates against operator A */
static void nbt_gate(const char *name, const nbt_screen_metrics *m)
{
    t_true(m->rel_l1 <= NBT_L1_TOL && m->edge <= NBT_EDGE_TOL && fabs(m->bias) <= NBT_BIAS_TOL,
           "%s: nbt against operator A, relative L1 %.3g <= %.2g, edge %.3g <= %.2g, |bias| %.3g <= %.2g", name,
           m->rel_l1, NBT_L1_TOL, m->edge, NBT_EDGE_TOL, fabs(m->bias), NBT_BIAS_TOL);
}

/* llvmpipe compiles a program at its first dispatch: run every method once */
static void warm_up(nbt_gls *g, const nbt_screen_kernel *km, const nbt_screen_kernel *ke, double dth)
{
    scene s = scene_new("warm", W, H); /* no random numbers: the scenes stay as they were */
    for (size_t i = 0; i < NP; i++) {
        s.D[i] = i % 7 ? 5.0f : 9.0f;
        s.rgb[3 * i] = s.rgb[3 * i + 1] = s.rgb[3 * i + 2] = 0.5f;
    }
    scene_kernels(&s, km, ke, dth);
    float *S = malloc(s.w * s.h * 3 * sizeof *S);
    for (int m = 0; m < NBT_GLS_NMETHODS; m++) {
        nbt_gls_input in = gls_input(&s, 0, dth);
        nbt_gls_exec(g, (nbt_gls_method)m, &in, S, NULL);
    }
    free(S);
    scene_free(&s);
}

/* (a) GL = emulation, and (c) accuracy, on the five scenes */
static void test_scenes(nbt_gls *g, const nbt_screen_kernel *km, const nbt_screen_kernel *ke, double dth)
{
    float *Sg = malloc(NP * 3 * sizeof *Sg);
    double *Se = malloc(NP * 3 * sizeof *Se), *SA = malloc(NP * 3 * sizeof *SA), *SB = malloc(NP * 3 * sizeof *SB),
           *Sd = malloc(NP * 3 * sizeof *Sd);
    double worst_l1 = 0, nbt_sum = 0;
    warm_up(g, km, ke, dth);
    printf("# method vs operator: relL1 relRMS edge bias max (64x48, dtheta %g)\n", dth);
    for (int sc = 0; sc < 5; sc++) {
        scene s = make_scene(sc);
        scene_kernels(&s, km, ke, dth);
        nbt_screen_input sin = {.w = s.w, .h = s.h, .rgb = s.rgb, .D = s.D, .dtheta = dth};
        t_true(nbt_screen_brute(&sin, km, NBT_SCREEN_NEAR, 1e-7, 2, SA, NULL) == NBT_OK, "%s: operator A", s.name);
        t_true(nbt_screen_brute(&sin, ke, NBT_SCREEN_SOURCE, 1e-7, 2, SB, NULL) == NBT_OK, "%s: operator B", s.name);
        for (int m = 0; m < NBT_GLS_NMETHODS; m++)
            for (int es = 0; es < 2; es++) {
                /* the pyramid methods run with both kernels; shinya only with the erfc kernel */
                if (es && (m == NBT_GLS_SHINYA || m == NBT_GLS_SHINYA_LITERAL || m == NBT_GLS_NBT))
                    continue;
                nbt_gls_input in = gls_input(&s, es, dth);
                double ms = 0;
                nbt_status st = nbt_gls_exec(g, (nbt_gls_method)m, &in, Sg, &ms);
                scatter_emul((nbt_gls_method)m, &in, Se);
                double d = gl_vs_emul(Sg, Se, NP * 3);
                t_true(st == NBT_OK && d <= 1e-5, "%s, %s%s: GL = CPU emulation (max diff %.2g of max S, window %ld)",
                       s.name, nbt_gls_method_name((nbt_gls_method)m), es ? " (Elek kernel)" : "", d,
                       nbt_gls_window((nbt_gls_method)m, &in));
                for (size_t i = 0; i < NP * 3; i++)
                    Sd[i] = Sg[i];
                nbt_screen_metrics mA;
                nbt_screen_compare(&sin, es ? ke : km, Sd, es ? SB : SA, &mA);
                printf("%-10s %-15s vs %s: %8.4f %8.4f %8.4f %+8.4f %8.4f  (%.1f ms)\n", s.name,
                       nbt_gls_method_name((nbt_gls_method)m), es ? "B" : "A", mA.rel_l1, mA.rel_rms, mA.edge, mA.bias,
                       mA.max, ms);
                if (m == NBT_GLS_NBT) {
                    nbt_sum += mA.rel_l1;
                    nbt_gate(s.name, &mA);
                }
                if ((m == NBT_GLS_NAIVE && !es) || m == NBT_GLS_ELEK) {
                    double tl = m == NBT_GLS_NAIVE ? NAIVE_A_L1_TOL : es ? ELEK_B_L1_TOL : ELEK_A_L1_TOL;
                    double te = m == NBT_GLS_NAIVE ? NAIVE_A_EDGE_TOL : es ? ELEK_B_EDGE_TOL : ELEK_A_EDGE_TOL;
                    t_true(mA.rel_l1 <= tl && mA.edge <= te,
                           "%s: %s against operator %s, relative L1 %.3g <= %.2g, edge %.3g <= %.2g", s.name,
                           nbt_gls_method_name((nbt_gls_method)m), es ? "B" : "A", mA.rel_l1, tl, mA.edge, te);
                }
                if (m == NBT_GLS_SHINYA) {
                    worst_l1 = fmax(worst_l1, mA.rel_l1);
                    t_true(mA.rel_l1 <= SHINYA_L1_TOL, "%s: shinya against operator A, relative L1 %.2g <= %.1g",
                           s.name, mA.rel_l1, SHINYA_L1_TOL);
                }
            }
        scene_free(&s);
    }
    printf("# shinya vs A: worst relative L1 %.3g\n", worst_l1);
    t_true(nbt_sum / 5 <= NBT_MEAN_TOL, "nbt against operator A: mean relative L1 %.3g <= %.2g", nbt_sum / 5, NBT_MEAN_TOL);
    free(Sg);
    free(Se);
    free(SA);
    free(SB);
    free(Sd);
}

/* nbt at wider kernels (dtheta / 4: beta_px up to ~30) against operator A,
 * next to the other pyramid methods, and its convergence in the slab count
 * at both settings (the scenes are regenerated: same seeds, not the same
 * random textures as test_scenes) */
static void test_nbt_wide(nbt_gls *g, const nbt_screen_kernel *km, const nbt_screen_kernel *ke, double dth)
{
    float *Sg = malloc(NP * 3 * sizeof *Sg);
    double *SA = malloc(NP * 3 * sizeof *SA), *Sd = malloc(NP * 3 * sizeof *Sd);
    const double dths[2] = {dth, dth / 4};
    for (int set = 0; set < 2; set++) {
        double sum = 0, bmax = 0;
        printf("# dtheta %g: method vs A: relL1 edge bias (beta_px range); nbt by slab count 1..%d: relL1/edge/bias\n",
               dths[set], NBT_GLS_NBT_MAXSLABS);
        for (int sc = 0; sc < 5; sc++) {
            scene s = make_scene(sc);
            scene_kernels(&s, km, ke, dths[set]);
            double b0 = INFINITY, b1 = 0;
            for (size_t i = 0; i < NP; i++)
                if (s.M0[i] > 0)
                    b0 = fmin(b0, s.beta[i]), b1 = fmax(b1, s.beta[i]);
            bmax = fmax(bmax, b1);
            nbt_screen_input sin = {.w = s.w, .h = s.h, .rgb = s.rgb, .D = s.D, .dtheta = dths[set]};
            nbt_screen_brute(&sin, km, NBT_SCREEN_NEAR, 1e-7, 2, SA, NULL);
            const nbt_gls_method ms[3] = {NBT_GLS_NBT, NBT_GLS_ELEK, NBT_GLS_NAIVE};
            for (int k = 0; k < 3; k++) {
                nbt_gls_input in = gls_input(&s, 0, dths[set]);
                nbt_gls_exec(g, ms[k], &in, Sg, NULL);
                for (size_t i = 0; i < NP * 3; i++)
                    Sd[i] = Sg[i];
                nbt_screen_metrics mA;
                nbt_screen_compare(&sin, km, Sd, SA, &mA);
                printf("%-10s %-6s vs A: %8.4f %8.4f %+8.4f  (beta_px %.1f .. %.1f)\n", s.name,
                       nbt_gls_method_name(ms[k]), mA.rel_l1, mA.edge, mA.bias, b0, b1);
                if (ms[k] == NBT_GLS_NBT && set == 1) {
                    sum += mA.rel_l1;
                    nbt_gate(s.name, &mA);
                }
            }
            printf("%-10s slabs:", s.name);
            for (unsigned n = 1; n <= NBT_GLS_NBT_MAXSLABS; n++) {
                nbt_gls_input in = gls_input(&s, 0, dths[set]);
                nbt_gls_set_slabs(g, n);
                nbt_gls_exec(g, NBT_GLS_NBT, &in, Sg, NULL);
                for (size_t i = 0; i < NP * 3; i++)
                    Sd[i] = Sg[i];
                nbt_screen_metrics mA;
                nbt_screen_compare(&sin, km, Sd, SA, &mA);
                printf(" %.4f/%.4f/%+.4f", mA.rel_l1, mA.edge, mA.bias);
            }
            printf("\n");
            nbt_gls_set_slabs(g, NBT_GLS_NBT_SLABS);
            scene_free(&s);
        }
        if (set == 1) {
            t_true(bmax >= 25, "the wide setting reaches beta_px %.1f >= 25", bmax);
            t_true(sum / 5 <= NBT_MEAN_TOL, "nbt at dtheta %g: mean relative L1 %.3g <= %.2g", dths[set], sum / 5,
                   NBT_MEAN_TOL);
        }
    }
    t_true(nbt_gls_set_slabs(g, 0) == NBT_EDOM && nbt_gls_set_slabs(g, NBT_GLS_NBT_MAXSLABS + 1) == NBT_EDOM,
           "nbt: slab counts outside 1 .. %d refused", NBT_GLS_NBT_MAXSLABS);
    free(Sg);
    free(SA);
    free(Sd);
}

/* nbt when the kernel is far wider than the screen (issue 21): beta_px from
 * 0.3 px to 100x the image width and beyond the fitted table (8192 px), on the plane and the step scene (64x48),
 * against operator A by brute force. Light a kernel sends off the screen is
 * lost in A; before the fitted weights were extended past beta 128 px (and
 * scaled by 1/beta beyond the table) nbt held them at 128 px and was
 * +180% at beta ~ 500 px, +600% at ~5000. */
static void test_nbt_beyond_screen(nbt_gls *g, const nbt_screen_kernel *km, const nbt_screen_kernel *ke, double dth)
{
    float *Sg = malloc(NP * 3 * sizeof *Sg);
    double *SA = malloc(NP * 3 * sizeof *SA), *Sd = malloc(NP * 3 * sizeof *Sd);
    const double target[7] = {0.3, 3, 30, 300, 3000, 100.0 * W, 30000};
    double worst_l1 = 0, worst_bias = 0;
    printf("# nbt vs A beyond the screen: beta_px (median), relative L1, bias\n");
    for (int sc = 0; sc < 2; sc++)
        for (int k = 0; k < 7; k++) {
            scene s = make_scene(sc);
            scene_kernels(&s, km, ke, dth);
            double b0 = s.beta[NP / 2 + W / 4], d = dth * b0 / target[k];
            scene_kernels(&s, km, ke, d);
            nbt_screen_input sin = {.w = s.w, .h = s.h, .rgb = s.rgb, .D = s.D, .dtheta = d};
            nbt_screen_brute(&sin, km, NBT_SCREEN_NEAR, 1e-7, 2, SA, NULL);
            nbt_gls_input in = gls_input(&s, 0, d);
            nbt_gls_exec(g, NBT_GLS_NBT, &in, Sg, NULL);
            for (size_t i = 0; i < NP * 3; i++)
                Sd[i] = Sg[i];
            nbt_screen_metrics mA;
            nbt_screen_compare(&sin, km, Sd, SA, &mA);
            printf("%-8s beta_px %8.1f: %.4f %+.4f\n", s.name, (double)s.beta[NP / 2 + W / 4], mA.rel_l1, mA.bias);
            worst_l1 = fmax(worst_l1, mA.rel_l1);
            worst_bias = fmax(worst_bias, fabs(mA.bias));
            scene_free(&s);
        }
    t_true(worst_l1 <= NBT_WIDE_L1_TOL && worst_bias <= NBT_WIDE_BIAS_TOL,
           "nbt vs A for beta_px 0.3 .. 30000: worst relative L1 %.3g <= %.2g, |bias| %.3g <= %.2g", worst_l1,
           NBT_WIDE_L1_TOL, worst_bias, NBT_WIDE_BIAS_TOL);
    free(Sg);
    free(SA);
    free(Sd);
}

/* nbt's own kernel: the impulse response (CPU emulation, = GL above) on a
 * constant-depth plane against the pixel-integrated erfc kernel, at three
 * sub-pixel phases of the 2^K pyramid grid; misplaced mass = L1 / mass */
/* a floor tilted across the image (depth 1.2/(fy - 0.15), 25% deeper to the
 * right) under sky in the top fifth: every slab and the in-slab march busy */
static void floor_depth(scene *s)
{
    for (size_t y = 0; y < H; y++)
        for (size_t x = 0; x < W; x++) {
            double fy = (y + 0.5) / H, fx = (x + 0.5) / W;
            s->D[y * W + x] = fy < 0.2 ? 1e10f : (float)(1.2 / (fy - 0.15) * (1 + 0.25 * fx));
        }
}

/* nbt's energy bias on continuous depth (issue 21). Within a depth slab the
 * pyramid sends every pair through the source's kernel where operator A
 * takes the nearer pixel's; nbt subtracts an estimate of that excess
 * (nbt_scatter_nbt.glsl). A floor receding to a horizon with sky above,
 * tilted across (depth varies along both axes), random colours, 64x48,
 * against operator A by brute force in the same test, at dtheta 0.06 and
 * 0.015 (beta_px 2.7-8 and 11-32): measured bias +0.19% and -0.10%,
 * relative L1 0.78% and 0.75% (without the correction, mutation
 * gls-nbt-excess-off: +1.51% and +1.87%, 1.92% and 2.20%). Tolerances: |bias| <= 0.5%, the goal (what is
 * left is second order in the kernel's change across a slab, the sparse
 * taps, and the light the correction's strips assume beyond the screen's
 * sides, about -0.6% for a 26 px kernel on this 48 px high image); relative
 * L1 <= 1.2%, 1.5x the worse measured value. */
#define NBT_SLOPE_BIAS_TOL 5e-3
#define NBT_SLOPE_L1_TOL 1.2e-2

static void test_nbt_slope_bias(nbt_gls *g, const nbt_screen_kernel *km, const nbt_screen_kernel *ke, double dth)
{
    float *Sg = malloc(NP * 3 * sizeof *Sg);
    double *SA = malloc(NP * 3 * sizeof *SA), *Sd = malloc(NP * 3 * sizeof *Sd), *Se = malloc(NP * 3 * sizeof *Se);
    for (int k = 0; k < 2; k++) {
        double d = k ? dth / 4 : dth;
        scene s = scene_new("floor", W, H);
        random_rgb(&s);
        floor_depth(&s);
        scene_kernels(&s, km, ke, d);
        nbt_screen_input sin = {.w = s.w, .h = s.h, .rgb = s.rgb, .D = s.D, .dtheta = d};
        t_true(nbt_screen_brute(&sin, km, NBT_SCREEN_NEAR, 1e-7, 2, SA, NULL) == NBT_OK, "floor: operator A");
        nbt_gls_input in = gls_input(&s, 0, d);
        nbt_status st = nbt_gls_exec(g, NBT_GLS_NBT, &in, Sg, NULL);
        scatter_emul(NBT_GLS_NBT, &in, Se);
        double e = gl_vs_emul(Sg, Se, NP * 3);
        t_true(st == NBT_OK && e <= 1e-5, "floor, dtheta %g: nbt GL = CPU emulation (max diff %.2g of max S)", d, e);
        for (size_t i = 0; i < NP * 3; i++)
            Sd[i] = Sg[i];
        nbt_screen_metrics m;
        nbt_screen_compare(&sin, km, Sd, SA, &m);
        t_true(fabs(m.bias) <= NBT_SLOPE_BIAS_TOL && m.rel_l1 <= NBT_SLOPE_L1_TOL,
               "floor, dtheta %g: nbt against operator A, bias %+.3g within +-%.2g, relative L1 %.3g <= %.2g", d,
               m.bias, NBT_SLOPE_BIAS_TOL, m.rel_l1, NBT_SLOPE_L1_TOL);
        scene_free(&s);
    }
    free(Sg);
    free(SA);
    free(Sd);
    free(Se);
}

/* nbt's energy bias with kernels of 60-140 px on a 320x240 screen and of
 * 600 px on 640x480 (issue 21). The pyramid's own kernels (levels 1-6) stop
 * at about 150 px, where an erfc kernel of beta = 100 px still has 7% of its
 * mass (140 px: 20%); the wide kernels (Gaussian blurs at level 6) reach
 * that light, the first two to about 600 px, the third (sigma 6 texels) to
 * about 1300. A far wall
 * with beta_px = target, a box in front at half the distance, sky on top,
 * random colours, against operator A by layered FFT (exact for these three
 * depths): measured bias +0.15% (target 70) and -0.02% (140), relative L1
 * 0.43% and 0.30%; before the wide kernels +0.05% and -5.6%, relative L1
 * 0.47% and 5.6% (the bench's 320x240 scenes: -0.9% on layers and
 * blocks). 640x480 at beta 600 px (pairs up to 800 px apart): bias +0.13%,
 * relative L1 0.13%; with two wide kernels (fit window 640 px) -2.1% and
 * 2.5% (1920x1080 bench: -4.9%). Tolerances: |bias| <= 0.5%, the issue's
 * goal (the old kernels miss it 11x at 140, two wide ones 4x at 600);
 * relative L1 <= 0.6%, 1.4x the worse measured. GL =
 * its emulation here too (the wide blurs run only where their weights are
 * not 0: not in the five 64x48 scenes of (a)). */
#define NBT_WIDEK_BIAS_TOL 5e-3
#define NBT_WIDEK_L1_TOL 6e-3

static void test_nbt_wide_kernels(const nbt_screen_kernel *km, const nbt_screen_kernel *ke, double dth)
{
    /* 320x240 at beta 70 and 140, 640x480 at 600 (the third wide kernel) */
    const size_t ws[3] = {320, 320, 640};
    const double target[3] = {70, 140, 600};
    for (int k = 0; k < 3; k++) {
        const size_t w = ws[k], h = w * 3 / 4, n = w * h;
        nbt_gls *g = nbt_gls_alloc(w, h);
        float *Sg = malloc(n * 3 * sizeof *Sg);
        double *SA = malloc(n * 3 * sizeof *SA), *Sd = malloc(n * 3 * sizeof *Sd), *Se = malloc(n * 3 * sizeof *Se);
        t_true(g && Sg && SA && Sd && Se, "context and buffers for %zux%zu", w, h);
        if (!(g && Sg && SA && Sd && Se)) {
            if (g)
                nbt_gls_free(g);
            free(Sg), free(SA), free(Sd), free(Se);
            continue;
        }
        scene s = scene_new("wall+box", w, h);
        random_rgb(&s);
        for (size_t y = 0; y < h; y++)
            for (size_t x = 0; x < w; x++)
                s.D[y * w + x] = y < h / 10 ? INFINITY : x >= 9 * w / 32 && x < 23 * w / 32 && y >= h / 4 && y < 3 * h / 4 ? 6.0f : 12.0f;
        const size_t far = (h - 1) * w + w - 1; /* the last pixel: the far wall */
        scene_kernels(&s, km, ke, dth);
        double d = dth * s.beta[far] / target[k];
        scene_kernels(&s, km, ke, d);
        nbt_screen_input sin = {.w = w, .h = h, .rgb = s.rgb, .D = s.D, .dtheta = d};
        t_true(nbt_screen_layered(&sin, km, NBT_SCREEN_NEAR, 1e-7, 4, 2, SA, NULL) == NBT_OK, "wall+box: operator A");
        nbt_gls_input in = gls_input(&s, 0, d);
        nbt_status st = nbt_gls_exec(g, NBT_GLS_NBT, &in, Sg, NULL);
        scatter_emul(NBT_GLS_NBT, &in, Se);
        double e = gl_vs_emul(Sg, Se, n * 3);
        t_true(st == NBT_OK && e <= 1e-5, "wall+box, beta_px %.0f: nbt GL = CPU emulation (max diff %.2g of max S)",
               (double)s.beta[far], e);
        for (size_t i = 0; i < n * 3; i++)
            Sd[i] = Sg[i];
        nbt_screen_metrics m;
        nbt_screen_compare(&sin, km, Sd, SA, &m);
        printf("# wall+box %zux%zu, beta_px %.1f (box %.1f): nbt vs A relative L1 %.4f bias %+.4f\n", w, h,
               (double)s.beta[far], (double)s.beta[(h / 2) * w + w / 2], m.rel_l1, m.bias);
        t_true(fabs(m.bias) <= NBT_WIDEK_BIAS_TOL && m.rel_l1 <= NBT_WIDEK_L1_TOL,
               "wall+box %zux%zu, beta_px %.0f: nbt against operator A, bias %+.3g within +-%.2g, relative L1 %.3g <= %.2g",
               w, h, (double)s.beta[far], m.bias, NBT_WIDEK_BIAS_TOL, m.rel_l1, NBT_WIDEK_L1_TOL);
        scene_free(&s);
        nbt_gls_free(g);
        free(Sg);
        free(SA);
        free(Sd);
        free(Se);
    }
}

/* nbt stores its pyramid levels a band of rows at a time when a level
 * exceeds one shader storage block (large images); forced here on a small
 * one: 6 slabs (all 19 source layers), 1, 5 and 7 rows per band (level 1
 * is 34 rows, level 6 three), on a floor with sky (every layer and the
 * in-slab march busy). Each row is computed by the same code whichever
 * band holds it, so S must equal the unbanded run's bit for bit; and both
 * the CPU emulation to 1e-5 of max S. */
static void test_nbt_bands(nbt_gls *g, const nbt_screen_kernel *km, const nbt_screen_kernel *ke, double dth)
{
    float *S0 = malloc(NP * 3 * sizeof *S0), *S1 = malloc(NP * 3 * sizeof *S1);
    double *Se = malloc(NP * 3 * sizeof *Se);
    scene s = scene_new("bands", W, H);
    random_rgb(&s);
    floor_depth(&s);
    scene_kernels(&s, km, ke, dth);
    nbt_gls_input in = gls_input(&s, 0, dth);
    nbt_gls_set_slabs(g, NBT_GLS_NBT_MAXSLABS);
    nbt_status st = nbt_gls_exec(g, NBT_GLS_NBT, &in, S0, NULL);
    scatter_emul_nbt(&in, NBT_GLS_NBT_MAXSLABS, Se);
    const unsigned rows[3] = {1, 5, 7};
    for (int r = 0; r < 3; r++) {
        nbt_gls_set_band_rows(g, rows[r]);
        nbt_status st1 = nbt_gls_exec(g, NBT_GLS_NBT, &in, S1, NULL);
        size_t diff = 0;
        for (size_t i = 0; i < NP * 3; i++)
            diff += S1[i] != S0[i];
        double e = gl_vs_emul(S1, Se, NP * 3);
        t_true(st == NBT_OK && st1 == NBT_OK && diff == 0 && e <= 1e-5,
               "nbt, %d slabs, %u rows per band: S equals the unbanded run's (%zu of %d values differ), the CPU "
               "emulation to %.2g of max S",
               NBT_GLS_NBT_MAXSLABS, rows[r], diff, NP * 3, e);
    }
    nbt_gls_set_band_rows(g, 0);
    nbt_gls_set_slabs(g, NBT_GLS_NBT_SLABS);
    scene_free(&s);
    free(S0);
    free(S1);
    free(Se);
}

static void test_nbt_kernel(void)
{
    const size_t w = 384, h = 384, n = w * h;
    float *rgb = calloc(n * 3, sizeof *rgb), *D = malloc(n * sizeof *D), *M0 = malloc(n * sizeof *M0),
          *b = malloc(n * sizeof *b);
    double *S = malloc(n * 3 * sizeof *S);
    const double betas[7] = {1, 2, 3, 4, 8, 16, 30};
    const long ph[3][2] = {{192, 192}, {177, 203}, {161, 190}};
    printf("# nbt kernel: misplaced mass (L1 of impulse response - erfc kernel, / mass) per beta_px, 3 phases\n");
    double worst = 0;
    for (int k = 0; k < 7; k++) {
        for (size_t i = 0; i < n; i++)
            D[i] = 5.0f, M0[i] = 1.0f, b[i] = (float)betas[k];
        double mean = 0, wk = 0;
        for (int p = 0; p < 3; p++) {
            size_t c = (size_t)ph[p][1] * w + (size_t)ph[p][0];
            rgb[3 * c] = 1.0f;
            nbt_gls_input in = {w, h, rgb, D, M0, b, NULL, 0.01, NBT_GLS_CUT, NBT_GLS_EPS};
            scatter_emul(NBT_GLS_NBT, &in, S);
            rgb[3 * c] = 0.0f;
            double l1 = 0;
            for (long y = 0; y < (long)h; y++)
                for (long x = 0; x < (long)w; x++)
                    l1 += fabs(S[3 * ((size_t)y * w + (size_t)x)] -
                               nbt_screen_atom_pixel(NBT_ATOM_ERFC, betas[k], x - ph[p][0], y - ph[p][1]));
            mean += l1 / 3;
            wk = fmax(wk, l1);
        }
        printf("#   beta_px %5.1f: mean %.4f worst %.4f\n", betas[k], mean, wk);
        worst = fmax(worst, wk);
    }
    /* measured worst 0.088 (beta 2-3): tolerance 1.5x */
    t_true(worst <= 0.13, "nbt kernel: misplaced mass %.3g <= 0.13 for beta_px 1 .. 30", worst);
    free(rgb);
    free(D);
    free(M0);
    free(b);
    free(S);
}

/* an odd size (padding, partial work groups): every method = its emulation */
static void test_odd_size(const nbt_screen_kernel *km, const nbt_screen_kernel *ke, double dth)
{
    const size_t w = 37, h = 29, n = w * h;
    scene s = scene_new("odd", w, h);
    random_rgb(&s);
    for (size_t y = 0; y < h; y++)
        for (size_t x = 0; x < w; x++)
            s.D[y * w + x] = y < 3 ? INFINITY : x < 3 ? 0.0f : (float)(2.0 + 0.3 * x + (x > 20) * 6.0);
    s.rgb[3 * (15 * w + 20) + 2] = 300.0f;
    scene_kernels(&s, km, ke, dth);
    nbt_gls *g = nbt_gls_alloc(w, h);
    float *Sg = malloc(n * 3 * sizeof *Sg);
    double *Se = malloc(n * 3 * sizeof *Se);
    for (int m = 0; m < NBT_GLS_NMETHODS; m++) {
        nbt_gls_input in = gls_input(&s, m == NBT_GLS_ELEK, dth);
        nbt_status st = g ? nbt_gls_exec(g, (nbt_gls_method)m, &in, Sg, NULL) : NBT_EINVAL;
        scatter_emul((nbt_gls_method)m, &in, Se);
        double d = gl_vs_emul(Sg, Se, n * 3);
        t_true(st == NBT_OK && d <= 1e-5, "37x29 with D = 0 and sky, %s: GL = CPU emulation (%.2g)",
               nbt_gls_method_name((nbt_gls_method)m), d);
    }
    nbt_gls_free(g);
    free(Sg);
    free(Se);
    scene_free(&s);
}

/* (b) invariants and bad input */
static void test_invariants(nbt_gls *g, const nbt_screen_kernel *km, const nbt_screen_kernel *ke, double dth)
{
    float *S = malloc(NP * 3 * sizeof *S);
    scene s = scene_new("wall", W, H);
    const float c[3] = {1.25f, 0.5f, 2.0f};
    for (size_t i = 0; i < NP; i++) {
        s.D[i] = 4.1f;
        for (int k = 0; k < 3; k++)
            s.rgb[3 * i + k] = c[k];
    }
    scene_kernels(&s, km, ke, dth);
    size_t ctr = (H / 2) * W + W / 2;
    double M0 = s.M0[ctr];
    t_true(s.beta[ctr] * 5 < H / 2, "wall kernel fits (beta %.2f px)", s.beta[ctr]);
    /* shinya: interior = M0 c but for the mass beyond cut beta (1e-3 at 3, 1e-6 at 5),
     * the near table and the far field (1e-4 together) */
    const double cuts[2] = {3.0, 5.0}, tol[2] = {1.5e-3, 2e-4};
    for (int k = 0; k < 2; k++) {
        nbt_gls_input in = gls_input(&s, 0, dth);
        in.cut = cuts[k];
        nbt_gls_exec(g, NBT_GLS_SHINYA, &in, S, NULL);
        double worst = 0;
        for (int ch = 0; ch < 3; ch++)
            worst = fmax(worst, fabs(S[3 * ctr + ch] / (M0 * c[ch]) - 1));
        t_true(worst <= tol[k], "constant wall, shinya cut %g: interior S = M0 c within %.1g (%.2g)", cuts[k], tol[k],
               worst);
    }
    /* naive, and Elek with a step mask: the pyramid filters have unit sum */
    for (int m = NBT_GLS_NAIVE; m <= NBT_GLS_ELEK; m++) {
        nbt_gls_input in = gls_input(&s, 1, dth);
        in.eps = 0;
        nbt_gls_exec(g, (nbt_gls_method)m, &in, S, NULL);
        double worst = 0;
        for (int ch = 0; ch < 3; ch++)
            worst = fmax(worst, fabs(S[3 * ctr + ch] / (M0 * c[ch]) - 1));
        t_true(worst <= 1e-5, "constant wall, %s%s: interior S = M0 c (%.2g)", nbt_gls_method_name((nbt_gls_method)m),
               m == NBT_GLS_ELEK ? " (eps 0)" : "", worst);
    }
    /* nbt: the fit's mass (Sum of the weights' mass + centre taps) within 0.5% for beta <= 45 px */
    {
        nbt_gls_input in = gls_input(&s, 0, dth);
        nbt_gls_exec(g, NBT_GLS_NBT, &in, S, NULL);
        double worst = 0;
        for (int ch = 0; ch < 3; ch++)
            worst = fmax(worst, fabs(S[3 * ctr + ch] / (M0 * c[ch]) - 1));
        t_true(worst <= 2e-3, "constant wall, nbt: interior S = M0 c within 2e-3 (%.2g)", worst);
    }
    /* beta_px = 0: a kernel without spread keeps M0 on the own pixel */
    float *beta0 = calloc(NP, sizeof *beta0);
    nbt_gls_input in0 = gls_input(&s, 0, dth);
    in0.beta_px = beta0;
    nbt_gls_exec(g, NBT_GLS_SHINYA, &in0, S, NULL);
    t_rel(S[3 * ctr + 2], M0 * c[2], 1e-6, "beta_px = 0: shinya keeps M0 c on the own pixel");
    free(beta0);
    /* the literal algorithm: equal depths exchange nothing (error 3) */
    nbt_gls_input in = gls_input(&s, 0, dth);
    nbt_gls_exec(g, NBT_GLS_SHINYA_LITERAL, &in, S, NULL);
    t_true(S[3 * ctr] == 0, "constant wall, shinya-literal: receives nothing (strict '>')");

    /* D = 0 everywhere, sky everywhere, albedo 0: S = 0 for every method */
    nbt_beam_medium m0 = nbt_beam_homogeneous(0.2385, 0.0, 0.0085);
    nbt_screen_kernel *k0 = nbt_screen_kernel_alloc(NBT_SKERNEL_MOMENT, &m0, NULL);
    const char *what[3] = {"D = 0", "sky (1e10 and inf)", "albedo 0"};
    for (int cs = 0; cs < 3; cs++) {
        for (size_t i = 0; i < NP; i++)
            s.D[i] = cs == 0 ? 0.0f : cs == 1 ? (i % 2 ? 1e10f : INFINITY) : 5.5f;
        s.rgb[3 * ctr + 1] = 900.0f;
        scene_kernels(&s, cs == 2 ? k0 : km, ke, dth);
        for (int m = 0; m < NBT_GLS_NMETHODS; m++) {
            nbt_gls_input in2 = gls_input(&s, 0, dth);
            nbt_status st = nbt_gls_exec(g, (nbt_gls_method)m, &in2, S, NULL);
            double mx = 0;
            for (size_t i = 0; i < NP * 3; i++)
                mx = fmax(mx, isfinite(S[i]) ? fabs(S[i]) : INFINITY);
            t_true(st == NBT_OK && mx == 0, "%s: %s gives S = 0 (max %.2g)", what[cs],
                   nbt_gls_method_name((nbt_gls_method)m), mx);
        }
    }
    nbt_screen_kernel_free(k0);

    /* bad input */
    for (size_t i = 0; i < NP; i++)
        s.D[i] = 3.3f;
    scene_kernels(&s, km, ke, dth);
    nbt_gls_input b = gls_input(&s, 0, dth);
    unsigned ran = nbt_gls_pass_times(g, NULL, NULL, NULL, 0);
    s.D[17] = -1.0f;
    t_true(nbt_gls_exec(g, NBT_GLS_SHINYA, &b, S, NULL) == NBT_EDOM, "negative depth refused");
    t_true(ran > 0 && nbt_gls_pass_times(g, NULL, NULL, NULL, 0) == 0,
           "a refused input leaves no pass times behind (%u groups from the run before)", ran);
    s.D[17] = NAN;
    t_true(nbt_gls_exec(g, NBT_GLS_NAIVE, &b, S, NULL) == NBT_EDOM, "NaN depth refused");
    s.D[17] = 3.3f;
    s.rgb[5] = INFINITY;
    t_true(nbt_gls_exec(g, NBT_GLS_ELEK, &b, S, NULL) == NBT_EDOM, "infinite colour refused");
    s.rgb[5] = 0.5f;
    s.M0[9] = -0.1f;
    t_true(nbt_gls_exec(g, NBT_GLS_SHINYA, &b, S, NULL) == NBT_EDOM, "negative M0 refused");
    s.M0[9] = 0.1f;
    b.cut = 0;
    t_true(nbt_gls_exec(g, NBT_GLS_SHINYA, &b, S, NULL) == NBT_EDOM, "cut 0 refused");
    b.cut = NBT_GLS_CUT;
    b.eps = -0.5;
    t_true(nbt_gls_exec(g, NBT_GLS_ELEK, &b, S, NULL) == NBT_EDOM, "eps < 0 refused");
    b.eps = NBT_GLS_EPS;
    b.dtheta = 0;
    t_true(nbt_gls_exec(g, NBT_GLS_SHINYA_LITERAL, &b, S, NULL) == NBT_EDOM, "dtheta 0 refused (literal)");
    b.dtheta = dth;
    b.w = W - 1;
    t_true(nbt_gls_exec(g, NBT_GLS_SHINYA, &b, S, NULL) == NBT_EINVAL, "a size other than the context's refused");
    b.w = W;
    t_true(nbt_gls_exec(g, (nbt_gls_method)7, &b, S, NULL) == NBT_EINVAL, "unknown method refused");
    t_true(nbt_gls_exec(g, NBT_GLS_SHINYA, &b, S, NULL) == NBT_OK, "the context still runs after refusals");
    t_true(nbt_gls_alloc(0, 5) == NULL, "empty image refused");
    scene_free(&s);
    free(S);
}

/* time per pass at 320x240 (the three-layer scene scaled, same kernels in pixels) */
static double clock_s(clockid_t c)
{
    struct timespec t;
    clock_gettime(c, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

/* nbt_gls_pass_times after one more exec: the method's groups by name in
 * order, each time >= 0, their GPU sum (timestamps inside exec) at most
 * exec's wall time and above 0, their CPU sum at most the process's CPU
 * time over exec (a unit or a misplaced stamp breaks one of these) */
static void check_pass_times(nbt_gls *g, nbt_gls_method m, const nbt_gls_input *in, float *S)
{
    static const char *const want[NBT_GLS_NMETHODS][6] = {{"near", "shinya"},
                                                         {"literal"},
                                                         {"pyr0", "down", "naive"},
                                                         {"pyr0", "down", "elek"},
                                                         {"nbt0", "nbtdown", "nbtup", "near", "nbt"}};
    const char *nm[NBT_GLS_MAXPASSES];
    double ms[NBT_GLS_MAXPASSES], cpu[NBT_GLS_MAXPASSES], gpu = 0;
    double w0 = clock_s(CLOCK_MONOTONIC), c0 = clock_s(CLOCK_PROCESS_CPUTIME_ID);
    nbt_status st = nbt_gls_exec(g, m, in, S, &gpu);
    double wall = 1e3 * (clock_s(CLOCK_MONOTONIC) - w0), pcpu = 1e3 * (clock_s(CLOCK_PROCESS_CPUTIME_ID) - c0);
    unsigned n = nbt_gls_pass_times(g, nm, ms, cpu, NBT_GLS_MAXPASSES), nw = 0;
    while (nw < 6 && want[m][nw])
        nw++;
    int names = n == nw, pos = 1;
    double sg = 0, sc = 0;
    for (unsigned k = 0; k < n && k < NBT_GLS_MAXPASSES; k++) {
        names = names && k < nw && !strcmp(nm[k], want[m][k]);
        pos = pos && ms[k] >= 0 && cpu[k] >= 0;
        sg += ms[k], sc += cpu[k];
    }
    t_true(st == NBT_OK && names && pos && sg > 0 && sg <= wall && fabs(sg - gpu) <= 1e-9 * gpu && sc <= pcpu,
           "%s: %u pass groups named as documented (%s ...), GPU sum %.3g ms in (0, exec's wall %.3g ms], = gpu_ms "
           "%.3g, CPU sum %.3g ms <= the process's %.3g ms",
           nbt_gls_method_name(m), n, n ? nm[0] : "-", sg, wall, gpu, sc, pcpu);
}

static void time_large(const nbt_screen_kernel *km, const nbt_screen_kernel *ke, double dth)
{
    const size_t w = 320, h = 240, n = w * h;
    scene s = scene_new("320x240", w, h);
    random_rgb(&s);
    for (size_t y = 0; y < h; y++)
        for (size_t x = 0; x < w; x++) {
            float D = y < 40 ? INFINITY : 15.2f;
            if (x >= 60 && x < 220 && y >= 70 && y < 200)
                D = 7.3f;
            if ((x - 150) * (x - 150) + (y - 140) * (y - 140) < 1600)
                D = 2.9f;
            s.D[y * w + x] = D;
        }
    scene_kernels(&s, km, ke, dth);
    nbt_gls *g = nbt_gls_alloc(w, h);
    float *S = malloc(n * 3 * sizeof *S);
    for (int m = 0; m < NBT_GLS_NMETHODS && g; m++) {
        nbt_gls_input in = gls_input(&s, m == NBT_GLS_ELEK, dth);
        long R = nbt_gls_window((nbt_gls_method)m, &in);
        if (R > 32) {
            printf("# %s at %zux%zu: skipped (window %ld px)\n", nbt_gls_method_name((nbt_gls_method)m), w, h, R);
            continue;
        }
        double ms = 0, best = INFINITY;
        nbt_status st = nbt_gls_exec(g, (nbt_gls_method)m, &in, S, &ms); /* the first run compiles (llvmpipe) */
        for (int r = 0; r < 3 && st == NBT_OK && m != NBT_GLS_SHINYA; r++) {
            st = nbt_gls_exec(g, (nbt_gls_method)m, &in, S, &ms);
            best = fmin(best, ms);
        }
        if (m == NBT_GLS_SHINYA)
            best = ms;
        t_true(st == NBT_OK, "%s runs at %zux%zu", nbt_gls_method_name((nbt_gls_method)m), w, h);
        check_pass_times(g, (nbt_gls_method)m, &in, S);
        printf("# %s at %zux%zu: %.1f ms (best of 3 after a first run; window %ld px)\n",
               nbt_gls_method_name((nbt_gls_method)m), w, h, best, R);
    }
    nbt_gls_free(g);
    free(S);
    scene_free(&s);
}

/* NBT_GLS_NBT's weights are linear in log2 beta_px between table entries (1/PER
 * apart): their slope da must equal a central difference of a(lb) inside each
 * segment (exact for a linear function, up to rounding ~1e-16/h), be 0
 * where the weights are held (below the table) and follow their 1/beta
 * scaling above it. A CPU check: no GL. */
/* at lb: the largest |da - central difference| into *worst, the largest
 * |central difference| into *big */
static void slope_vs_difference(double lb, double *worst, double *big)
{
    enum { NB = NBT_GLS_NBT_NB };
    const double h = 1e-4;
    double a[NB], da[NB], ap[NB], am[NB];
    nbt_gls_nbt_weights(lb, a, da);
    nbt_gls_nbt_weights(lb + h, ap, NULL);
    nbt_gls_nbt_weights(lb - h, am, NULL);
    for (int b = 0; b < NB; b++) {
        double cd = (ap[b] - am[b]) / (2 * h);
        *worst = fmax(*worst, fabs(da[b] - cd));
        *big = fmax(*big, fabs(cd));
    }
}

static void test_nbt_weights_slope(void)
{
    enum { NB = NBT_GLS_NBT_NB };
    const double f[3] = {0.21, 0.5, 0.83};
    double a[NB], da[NB], worst = 0, big = 0, held = 0;
    for (int i = 0; i + 1 < NBT_GLS_NBT_N; i++)
        for (int q = 0; q < 3; q++)
            slope_vs_difference(NBT_GLS_NBT_LO + ((double)i + f[q]) / NBT_GLS_NBT_PER, &worst, &big);
    /* below the table the weights are held: slope 0; above it they scale as
     * 2^(HI - lb), whose slope -ln 2 a is checked by the same difference */
    nbt_gls_nbt_weights(NBT_GLS_NBT_LO - 0.37, a, da);
    for (int b = 0; b < NB; b++)
        held = fmax(held, fabs(da[b]));
    double above = 0, abig = 0;
    for (int q = 0; q < 3; q++)
        slope_vs_difference(NBT_GLS_NBT_HI + 0.41 + 3.0 * q, &above, &abig);
    t_true(big > 0 && worst <= 1e-9 * big, "nbt weights: slope = central difference in log2 beta_px (worst difference %.2g, "
           "largest slope %.3g) at %d points", worst, big, 3 * (NBT_GLS_NBT_N - 1));
    t_abs(held, 0, 0, "nbt weights: slope 0 below the table");
    /* exp2 is not linear: the central difference's error is (ln 2)^2 h^2/6 of the slope */
    t_true(abig > 0 && above <= 1e-7 * abig, "nbt weights above the table: slope = central difference (worst %.2g of "
           "%.3g)", above, abig);
}

int main(void)
{
    char err[4096];
    if (egl_headless_open(err, sizeof err)) {
        printf("FAIL: cannot create a GL context: %s\n", err);
        t_true(0, "GL context");
        return t_done();
    }
    t_true(1, "GL context: %s", (const char *)glGetString(GL_RENDERER));
    test_nbt_weights_slope();
    validate_passes();
    nbt_gls *g = nbt_gls_alloc(W, H);
    t_true(g != NULL, "context for %dx%d", W, H);
    if (!g)
        return t_done();
    const double dth = 0.06;
    nbt_beam_medium med = nbt_beam_homogeneous(0.2385, 0.93, 0.0085);
    nbt_screen_kernel *km = nbt_screen_kernel_alloc(NBT_SKERNEL_MOMENT, &med, NULL);
    nbt_screen_kernel *ke = nbt_screen_kernel_alloc(NBT_SKERNEL_ELEK, &med, NULL);
    test_scenes(g, km, ke, dth);
    test_nbt_wide(g, km, ke, dth);
    test_nbt_beyond_screen(g, km, ke, dth);
    test_nbt_slope_bias(g, km, ke, dth);
    test_nbt_wide_kernels(km, ke, dth);
    test_nbt_bands(g, km, ke, dth);
    test_nbt_kernel();
    test_odd_size(km, ke, dth);
    test_invariants(g, km, ke, dth);
    time_large(km, ke, dth);
    nbt_screen_kernel_free(km);
    nbt_screen_kernel_free(ke);
    nbt_gls_free(g);
    egl_headless_close();
    return t_done();
}
