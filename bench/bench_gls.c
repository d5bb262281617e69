/* bench/bench_gls.c: GPU time per pass of the screen-space methods nbt and
 * elek (nbt/gl_scatter.h), both on one context in one process, interleaved
 * (elek, nbt, elek, nbt, ...) so that a shared machine's load falls on
 * both alike. Inputs: nbt-scatter's generated scenes (scatter/scenes.c),
 * Z read as ray distance, the moment kernel (nbt) and Elek's (elek) of
 * bench_scatter.sh's medium: fov 40 deg, sigma_t 0.15, albedo 0.9, dtheta
 * 10 deg. Each method runs once to warm up (llvmpipe compiles a shader at
 * its first dispatch), then N times; printed per pass: the best of N
 * (GL_TIMESTAMP after each group of passes, nbt_gls_pass_times), the best
 * total, and the median over the N pairs of nbt's total over elek's in the
 * same pair; the same for the process's CPU time over each pass (on
 * llvmpipe the pass's work on all its threads: what other jobs on a shared
 * machine do not inflate). Load average before and after. Method nbt's S can be written
 * (--dump DIR: DIR/SCENE-WxH.f32, w*h*3 floats) to check that a faster
 * version computes the same image.
 * Usage: bench_gls [-n N] [--scenes a,b,...] [--dump DIR] [WxH ...]
 *        (defaults: N = 5, slant,blocks, 320x240 1920x1080) */
#include <config.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <GL/gl.h>
#include <nbt/gl_scatter.h>
#include <nbt/nbt.h>
#include "../examples/egl_headless.h"
#include "../scatter/scatter.h"

static void die(const char *msg, const char *what)
{
    fprintf(stderr, "bench_gls: %s%s\n", msg, what ? what : "");
    exit(2);
}

static int cmp_d(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

static void load(const char *when)
{
    double l[3];
    if (getloadavg(l, 3) == 3)
        printf("# load average %s: %.2f %.2f %.2f\n", when, l[0], l[1], l[2]);
}

typedef struct {
    const char *name[NBT_GLS_MAXPASSES];
    double best[NBT_GLS_MAXPASSES], cbest[NBT_GLS_MAXPASSES], total, ctotal;
    unsigned n;
} times;

/* one exec; t: keep the best per pass; returns the GPU ms, *cpu the CPU ms */
static double run(nbt_gls *g, nbt_gls_method m, const nbt_gls_input *in, float *S, times *t, double *cpu)
{
    double ms = 0, p[NBT_GLS_MAXPASSES], c[NBT_GLS_MAXPASSES], csum = 0;
    const char *nm[NBT_GLS_MAXPASSES];
    if (nbt_gls_exec(g, m, in, S, &ms) != NBT_OK)
        die("nbt_gls_exec failed for ", nbt_gls_method_name(m));
    unsigned n = nbt_gls_pass_times(g, nm, p, c, NBT_GLS_MAXPASSES);
    for (unsigned k = 0; k < n; k++)
        csum += c[k];
    if (cpu)
        *cpu = csum;
    if (t) {
        if (t->n == 0) {
            t->n = n;
            t->total = t->ctotal = INFINITY;
            for (unsigned k = 0; k < n; k++)
                t->name[k] = nm[k], t->best[k] = t->cbest[k] = INFINITY;
        }
        for (unsigned k = 0; k < n && k < t->n; k++) {
            t->best[k] = fmin(t->best[k], p[k]);
            t->cbest[k] = fmin(t->cbest[k], c[k]);
        }
        t->total = fmin(t->total, ms);
        t->ctotal = fmin(t->ctotal, csum);
    }
    return ms;
}

static void show(const char *scene, size_t w, size_t h, const char *m, const times *t)
{
    printf("%-7s %4zux%-4zu %-4s GPU %8.2f ms:", scene, w, h, m, t->total);
    for (unsigned k = 0; k < t->n; k++)
        printf(" %s %.2f", t->name[k], t->best[k]);
    printf("\n%-7s %4zux%-4zu %-4s CPU %8.2f ms:", scene, w, h, m, t->ctotal);
    for (unsigned k = 0; k < t->n; k++)
        printf(" %s %.2f", t->name[k], t->cbest[k]);
    printf("\n");
}

static void bench(const char *scene, size_t w, size_t h, int reps, const char *dump)
{
    int kind = scene_parse(scene);
    if (kind < 0)
        die("unknown scene ", scene);
    nbt_image *im = scene_make(kind, w, h, 0, 0);
    size_t np = w * h;
    float *M0 = malloc(np * sizeof *M0), *beta = malloc(np * sizeof *beta), *M0e = malloc(np * sizeof *M0e),
          *sig = malloc(np * sizeof *sig), *S = malloc(3 * np * sizeof *S);
    if (!im || !M0 || !beta || !M0e || !sig || !S)
        die("out of memory", NULL);
    double dth = 10.0 * M_PI / 180.0, dtheta = 2.0 * tan(20.0 * M_PI / 180.0) / (double)h;
    nbt_beam_medium bm = nbt_beam_homogeneous(0.15, 0.9, dth * dth / 4.0);
    nbt_screen_kernel *km = nbt_screen_kernel_alloc(NBT_SKERNEL_MOMENT, &bm, NULL),
                      *ke = nbt_screen_kernel_alloc(NBT_SKERNEL_ELEK, &bm, NULL);
    if (!km || !ke)
        die("the kernels could not be set up", NULL);
    for (size_t i = 0; i < np; i++) {
        nbt_screen_kern k;
        double D = im->z[i], px = D * dtheta;
        if (nbt_screen_kernel_eval(km, D, &k) != NBT_OK)
            die("kernel evaluation failed", NULL);
        M0[i] = k.n ? (float)k.mass[0] : 0.0f;
        beta[i] = k.n ? (float)(k.scale[0] / px) : 0.0f;
        if (nbt_screen_kernel_eval(ke, D, &k) != NBT_OK)
            die("kernel evaluation failed", NULL);
        M0e[i] = k.n ? (float)k.mass[0] : 0.0f;
        sig[i] = k.n ? (float)(k.scale[0] / px) : 0.0f;
    }
    nbt_gls_input in_n = {w, h, im->rgb, im->z, M0, beta, NULL, dtheta, NBT_GLS_CUT, NBT_GLS_EPS};
    nbt_gls_input in_e = {w, h, im->rgb, im->z, M0e, beta, sig, dtheta, NBT_GLS_CUT, NBT_GLS_EPS};
    nbt_gls *g = nbt_gls_alloc(w, h);
    if (!g)
        die("nbt_gls_alloc failed", NULL);
    run(g, NBT_GLS_ELEK, &in_e, S, NULL, NULL); /* warm-up: llvmpipe's JIT */
    run(g, NBT_GLS_NBT, &in_n, S, NULL, NULL);
    times te = {0}, tn = {0};
    double *ratio = malloc(2 * (size_t)reps * sizeof *ratio), *cratio = ratio + reps;
    if (!ratio)
        die("out of memory", NULL);
    for (int r = 0; r < reps; r++) {
        double ce, cn, e = run(g, NBT_GLS_ELEK, &in_e, S, &te, &ce);
        ratio[r] = run(g, NBT_GLS_NBT, &in_n, S, &tn, &cn) / e;
        cratio[r] = cn / ce;
    }
    qsort(ratio, (size_t)reps, sizeof *ratio, cmp_d);
    qsort(cratio, (size_t)reps, sizeof *ratio, cmp_d);
    show(scene, w, h, "elek", &te);
    show(scene, w, h, "nbt", &tn);
    printf("%-7s %4zux%-4zu nbt/elek GPU: best %.2f, pairs median %.2f (%.2f .. %.2f); CPU: best %.2f, pairs median "
           "%.2f (%.2f .. %.2f)\n",
           scene, w, h, tn.total / te.total, ratio[reps / 2], ratio[0], ratio[reps - 1], tn.ctotal / te.ctotal,
           cratio[reps / 2], cratio[0], cratio[reps - 1]);
    fflush(stdout);
    if (dump) { /* the last nbt run's S */
        char path[4096];
        snprintf(path, sizeof path, "%s/%s-%zux%zu.f32", dump, scene, w, h);
        FILE *f = fopen(path, "wb");
        if (!f || fwrite(S, sizeof *S, 3 * np, f) != 3 * np || fclose(f))
            die("cannot write ", path);
    }
    nbt_gls_free(g);
    nbt_screen_kernel_free(km);
    nbt_screen_kernel_free(ke);
    nbt_image_free(im);
    free(M0), free(beta), free(M0e), free(sig), free(S), free(ratio);
}

int main(int argc, char **argv)
{
    int reps = 5, nsz = 0;
    const char *scenes = "slant,blocks", *dump = NULL;
    size_t W[16], H[16];
    for (int a = 1; a < argc; a++) {
        unsigned long x, y;
        char c;
        if (!strcmp(argv[a], "-n") && a + 1 < argc) {
            reps = atoi(argv[++a]);
            if (reps < 1)
                die("-n: expected a count >= 1, got ", argv[a]);
        } else if (!strcmp(argv[a], "--scenes") && a + 1 < argc)
            scenes = argv[++a];
        else if (!strcmp(argv[a], "--dump") && a + 1 < argc)
            dump = argv[++a];
        else if (nsz < 16 && sscanf(argv[a], "%lux%lu%c", &x, &y, &c) == 2 && x > 0 && y > 0)
            W[nsz] = x, H[nsz++] = y;
        else
            die("expected -n N, --scenes a,b, --dump DIR or a size WxH, got ", argv[a]);
    }
    if (!nsz)
        W[0] = 320, H[0] = 240, W[1] = 1920, H[1] = 1080, nsz = 2;
    char err[4096];
    if (egl_headless_open(err, sizeof err))
        die("needs OpenGL 4.3 through EGL: ", err);
    printf("# bench_gls: GPU ms per pass, best of %d, warm; %s\n", reps, (const char *)glGetString(GL_RENDERER));
    load("before");
    for (int s = 0; s < nsz; s++) {
        char list[1024];
        snprintf(list, sizeof list, "%s", scenes);
        for (char *sc = strtok(list, ","); sc; sc = strtok(NULL, ","))
            bench(sc, W[s], H[s], reps, dump);
    }
    load("after");
    egl_headless_close();
    return 0;
}
