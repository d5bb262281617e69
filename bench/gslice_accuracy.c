/* bench/gslice_accuracy.c: how close the g-sliced airlight shader
 * (nbt_airlight_g on a tail-form H table, doc/tables.md) comes to
 * Nishita's integral along the ray (nbt_airlight_direct with HG(g)) over
 * random rays and g in [-0.95, 0.95], on the GL at hand (Mesa llvmpipe
 * here) and, beside it, the same formula evaluated on the CPU from the same
 * float table (nbt_airlight_table_g_lookup). A second pass snaps every g to
 * the nearest slice, which leaves only the table's (u, v) error: the
 * difference between the passes is the interpolation in g (quadratic).
 *
 * Usage: bench/gslice_accuracy [N_UV [N_G [RAYS [MAP [misses|- [VMAP[:c] [INTERP]]]]]]]
 *   N_UV nodes on u (log1p_cbrt, c = 10, [0, 10]) and v (cos), default 257;
 *   NUxNV (65x257, say) sets the two apart;
 *   N_G slices on g in [-0.95, 0.95], default 33; RAYS default 2000;
 *   MAP the g mapping (atanh, linear, sqrt, cos, ...; default atanh);
 *   misses: print every ray above 1e-3 (CPU lookup, g anywhere) with its
 *   table coordinates (u, theta_0, theta_d, g) ('-': do not);
 *   VMAP[:c] the v mapping and its strength (ends:16, the planner's), default cos;
 *   INTERP the g interpolation the lookups use, 2 quadratic (the tail form
 *   before issue 21) or 3 cubic (what nbt_gslice_fill writes now), default
 *   the table's; the error map is the one measured for the table's own.
 * Rays: kappa_t = 0.2, kappa_s = 0.18, d_sv log-uniform in [0.5, 40], gamma
 * uniform in [0.02, pi - 0.02], d_vp infinite for 30%, else d_sv times a
 * log-uniform factor in [0.05, 3]; g uniform in [-0.95, 0.95] for half the
 * rays, |g| uniform in [0.8, 0.95] for the others. Prints quantiles of
 * |L - L_direct| / L_direct per group. */
#include <config.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#define GL_GLEXT_PROTOTYPES 1
#include <GL/gl.h>
#include <GL/glext.h>
#include <nbt/nbt.h>
#include <nbt/gl.h>
#include "../examples/egl_headless.h"

static const double KT = 0.2, KS = 0.18, I0 = 1.0;

static double now(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

/* A g-sliced HG table H_p(u, v; g) on the given axes, built by libnbt. */
static nbt_table *assemble_gsliced(const nbt_axis *a0, const nbt_axis *a1, const nbt_axis *a2)
{
    nbt_table *t = nbt_table_alloc3(NBT_TABLE_H, a0, a1, a2, 1);
    nbt_build_opts o = {1e-10, 0, 0};
    if (t && nbt_gslice_fill(t, &o) != NBT_OK) {
        nbt_table_free(t);
        t = NULL;
    }
    return t;
}

/* the shader's formula in double from the same table (as tests/test_gl.c):
 * libnbt's lookup alone (tail form), without nbt_airlight_table_g's
 * fallback */
static double cpu_airlight(const nbt_table *Ht, double gph, const nbt_airlight_geom *g)
{
    double L, E;
    nbt_airlight_table_g_lookup(Ht, gph, g, &L, &E);
    return L;
}

static int cmp(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

/* quantiles of e[i] over the rays with sel[i] */
static void report(const char *what, const double *e, const int *sel, int n)
{
    double *s = malloc((size_t)n * sizeof *s);
    int m = 0, ok = 0;
    for (int i = 0; i < n; i++)
        if (sel[i]) {
            s[m++] = e[i];
            ok += e[i] <= 1e-3;
        }
    if (m) {
        qsort(s, (size_t)m, sizeof *s, cmp);
        printf("  %-34s %5d rays  median %.2e  p90 %.2e  p99 %.2e  max %.2e  <= 1e-3: %5.1f%% (%d above)\n", what, m,
               s[m / 2], s[(int)(0.9 * m)], s[(int)(0.99 * m)], s[m - 1], 100.0 * ok / m, m - ok);
    }
    free(s);
}

static unsigned long long rng = 0x2385;
static double uni(void)
{
    rng = rng * 6364136223846793005ULL + 1442695040888963407ULL;
    return (double)(rng >> 11) / 9007199254740992.0;
}

int main(int argc, char **argv)
{
    char *end = NULL;
    size_t N = argc > 1 ? strtoul(argv[1], &end, 10) : 257, NG = argc > 2 ? strtoul(argv[2], NULL, 10) : 33;
    size_t NV = end && *end == 'x' ? strtoul(end + 1, NULL, 10) : N;
    int R = argc > 3 ? atoi(argv[3]) : 2000, nmiss = argc > 5 && !strcmp(argv[5], "misses");
    nbt_axis_map gmap = NBT_AXIS_ATANH;
    if ((argc > 4 && nbt_axis_map_parse(argv[4], &gmap) != NBT_OK) || N < 2 || N > 2049 || NV < 2 || NV > 2049 || NG < 3 || NG > 513 ||
        R < 1 || R > 1000000 || gmap == NBT_AXIS_LOG1P || gmap == NBT_AXIS_LOG1P_CBRT) {
        fprintf(stderr, "gslice_accuracy: usage: [N_UV|NUxNV 2..2049 [N_G 3..513 [RAYS 1..1e6 [MAP atanh|linear|sqrt|cos]]]]\n");
        return 2;
    }
    char err[4096];
    if (egl_headless_open(err, sizeof err)) {
        fprintf(stderr, "gslice_accuracy: %s\n", err);
        return 1;
    }
    nbt_axis a0 = {0, 10, NBT_AXIS_LOG1P_CBRT, 10, N}, a1 = {-M_PI_2, M_PI_2, NBT_AXIS_COS, 0, NV};
    if (argc > 6) { /* VMAP[:c] */
        char name[32];
        snprintf(name, sizeof name, "%s", argv[6]);
        char *colon = strchr(name, ':');
        if (colon) {
            *colon = 0;
            a1.c = atof(colon + 1);
        }
        if (nbt_axis_map_parse(name, &a1.map) != NBT_OK) {
            fprintf(stderr, "gslice_accuracy: v mapping '%s' unknown\n", argv[6]);
            return 2;
        }
    }
    nbt_axis a2 = {-0.95, 0.95, gmap, 0, NG};
    double t0 = now();
    nbt_table *Ht = assemble_gsliced(&a0, &a1, &a2);
    double tb = now() - t0;
    if (!Ht) {
        fprintf(stderr, "gslice_accuracy: building the table failed\n");
        return 1;
    }
    if (argc > 7) {
        int ip = atoi(argv[7]);
        if (ip != 2 && ip != 3) {
            fprintf(stderr, "gslice_accuracy: INTERP '%s' must be 2 or 3\n", argv[7]);
            return 2;
        }
        Ht->interp2 = ip;
    }
    const char *MAIN = "uniform sampler2D rays;\nout vec4 color;\nvoid main() {\n"
                       "  vec4 r = texelFetch(rays, ivec2(gl_FragCoord.xy), 0);\n"
                       "  color = vec4(nbt_airlight_g(0.18, 0.2, 1.0, r.x, r.y, r.z, r.w), 0.0, 0.0, 1.0);\n}\n";
    char *src = nbt_gl_shader_source(&(nbt_gl_config){1, 0, 0, 0, 0, 0, 1}, MAIN);
    GLuint prog = gl_fullscreen_program(src, err, sizeof err);
    free(src);
    int W = 64, H = (R + W - 1) / W;
    GLuint fbo = prog ? gl_float_target(W, H) : 0;
    if (!fbo) {
        fprintf(stderr, "gslice_accuracy: %s\n", prog ? "no RGBA32F render target" : err);
        return 1;
    }
    float *in = calloc((size_t)W * H * 4, sizeof(float)), *px = malloc((size_t)W * H * 4 * sizeof(float));
    double *eg = malloc((size_t)R * sizeof(double)), *ec = malloc((size_t)R * sizeof(double));
    int *sel = malloc((size_t)R * sizeof(int));
    nbt_airlight_geom *geo = malloc((size_t)R * sizeof *geo);
    double *gr = malloc((size_t)R * sizeof(double));
    for (int i = 0; i < R; i++) {
        double dsv = 0.5 * pow(80.0, uni()), gam = 0.02 + (M_PI - 0.04) * uni();
        int inf = uni() < 0.3;
        double dvp = inf ? INFINITY : dsv * 0.05 * pow(60.0, uni());
        gr[i] = i % 2 ? -0.95 + 1.9 * uni() : (uni() < 0.5 ? -1 : 1) * (0.8 + 0.15 * uni());
        geo[i] = (nbt_airlight_geom){KS, KT, I0, (float)dsv, (float)gam, inf ? INFINITY : (float)dvp};
        gr[i] = (float)gr[i];
    }
    GLuint tex[2];
    glUseProgram(prog);
    tex[0] = nbt_gl_bind_table(prog, "nbt_H0", Ht, 1);
    glActiveTexture(GL_TEXTURE2);
    glGenTextures(1, &tex[1]);
    glBindTexture(GL_TEXTURE_2D, tex[1]);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    glUniform1i(glGetUniformLocation(prog, "rays"), 2);
    nbt_gl_set_table_axes(prog, "nbt_H", Ht);
    printf("g-sliced H %zu x %zu x %zu (u log1p_cbrt [0, 10], v %s c %g, g %s [-0.95, 0.95], %s in g), %.1f MB as float, "
           "assembled from 2-D builds in %.2f s (2-core machine shared with other jobs); %s\n",
           N, NV, NG, nbt_axis_map_name(a1.map), a1.c, nbt_axis_map_name(gmap),
           Ht->interp2 == 3 ? "cubic" : "quadratic", (double)nbt_table_size(Ht) * 4 / 1e6, tb,
           (const char *)glGetString(GL_RENDERER));
    for (int pass = 0; pass < 2; pass++) {
        int bad = 0;
        for (int i = 0; i < R; i++) {
            double g = gr[i];
            if (pass) /* nearest slice (in the mapped coordinate) */
                g = nbt_axis_node(&a2, (size_t)lround(nbt_axis_to_unit(&a2, g) * (double)(NG - 1)));
            float *q = in + 4 * i;
            q[0] = (float)geo[i].dsv;
            q[1] = (float)geo[i].gamma;
            q[2] = isinf(geo[i].dvp) ? 1e30f : (float)geo[i].dvp;
            q[3] = (float)g;
            gr[i] = q[3]; /* both sides see the float g */
        }
        glBindTexture(GL_TEXTURE_2D, tex[1]);
        glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA32F, W, H, 0, GL_RGBA, GL_FLOAT, in);
        gl_draw_fullscreen();
        glReadPixels(0, 0, W, H, GL_RGBA, GL_FLOAT, px);
        double td = 0;
        for (int i = 0; i < R; i++) {
            nbt_phase *hg = nbt_phase_hg(gr[i]);
            double ref, abserr, t1 = now();
            if (nbt_airlight_direct(hg, &geo[i], 1e-10, &ref, &abserr) != NBT_OK || !(fabs(ref) > 0)) {
                bad++;
                ref = NAN;
            }
            td += now() - t1;
            nbt_phase_free(hg);
            eg[i] = fabs(px[4 * i] - ref) / fabs(ref);
            ec[i] = fabs(cpu_airlight(Ht, gr[i], &geo[i]) - ref) / fabs(ref);
            if (isnan(eg[i]))
                eg[i] = ec[i] = INFINITY;
        }
        int iw = 0;
        for (int i = 1; i < R; i++)
            iw = ec[i] > ec[iw] ? i : iw;
        printf("worst ray (CPU lookup): g %.4f gamma %.4f d_sv %.3g d_vp %.3g (u = kappa_t h %.3g, theta_0 %.4f): %.2e\n",
               gr[iw], geo[iw].gamma, geo[iw].dsv, geo[iw].dvp, KT * geo[iw].dsv * sin(geo[iw].gamma),
               geo[iw].gamma - M_PI_2, ec[iw]);
        /* MISSES: every ray above 1e-3 (CPU lookup) with its lookup points */
        for (int i = 0; i < R && nmiss && !pass; i++)
            if (ec[i] > 1e-3) {
                double h = geo[i].dsv * sin(geo[i].gamma), tf = geo[i].dsv * cos(geo[i].gamma);
                printf("miss: g %+.4f u %.4g theta_0 %+.4f theta_d %+.4f d_vp %s: %.2e\n", gr[i], KT * h,
                       geo[i].gamma - M_PI_2, isinf(geo[i].dvp) ? M_PI_2 : atan2(geo[i].dvp - tf, h),
                       isinf(geo[i].dvp) ? "inf" : "finite", ec[i]);
            }
        printf("%s (%d rays without a reference value, counted as failures):\n",
               pass ? "g snapped to the nearest slice: the (u, v) error alone" : "g anywhere in [-0.95, 0.95]", bad);
        static const char *grp[4] = {"all", "d_vp infinite", "d_vp finite", "|g| >= 0.8"};
        for (int k = 0; k < 4; k++) {
            for (int i = 0; i < R; i++)
                sel[i] = k == 0 || (k == 1 && isinf(geo[i].dvp)) || (k == 2 && !isinf(geo[i].dvp)) ||
                         (k == 3 && fabs(gr[i]) >= 0.8);
            char w[64];
            snprintf(w, sizeof w, "shader, %s", grp[k]);
            report(w, eg, sel, R);
            snprintf(w, sizeof w, "CPU lookup3, %s", grp[k]);
            report(w, ec, sel, R);
        }
    }
    glDeleteTextures(2, tex);
    nbt_table_free(Ht);
    free(in);
    free(px);
    free(eg);
    free(ec);
    free(sel);
    free(geo);
    free(gr);
    egl_headless_close();
    return 0;
}
