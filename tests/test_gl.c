/* tests/test_gl.c: nbt's GLSL on a real GL (Mesa llvmpipe through EGL
 * surfaceless): every assembled variant validates with glslangValidator and
 * compiles; rendered airlight, surface radiance and beam kernel match libnbt's
 * CPU evaluation of the same float tables pixel by pixel, and stay within the
 * tables' recorded error of the exact series; singular places give finite
 * values. Fails with a clear message when no GL context can be created. */
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#define GL_GLEXT_PROTOTYPES 1
#include <GL/gl.h>
#include <GL/glext.h>
#include <nbt/nbt.h>
#include <nbt/gl.h>
#include "../examples/egl_headless.h"
#include "testutil.h"

/* the GL driver leaks at eglTerminate: no leak report for this program */
const char *__asan_default_options(void);
const char *__asan_default_options(void)
{
    return "detect_leaks=0";
}

#define W 64
#define H 48
static const double G0 = 0.05, G1 = 3.09, D0 = 0.5, D1 = 40, KT = 0.2, KS = 0.15, I0 = 2.385, DVP = 25;
static const double KD = 0.7, KSP = 0.3, NPH = 20, ALB = 0.9, BB = 0.0685;

static const char *MAIN =
    "uniform vec2 res;\n"
    "out vec4 color;\n"
    "void main() {\n"
    "  vec2 f = (gl_FragCoord.xy - 0.5) / (res - 1.0);\n"
    "  float gam = mix(0.05, 3.09, f.x), d = mix(0.5, 40.0, f.y);\n"
    "  color.r = nbt_airlight(0.15, 0.2, 2.385, d, gam, 25.0);\n"
    "  color.g = nbt_surface(0.15, 0.2, 2.385, d, f.x * 3.14159265358979, (1.0 - f.x) * 1.5, 0.7, 0.3, 20.0);\n"
    "  float z = d / 4.0;\n"
    "  color.b = nbt_beam_psi(nbt_beam_kernel_params(1.0, 0.9, 0.0685, z), (0.02 + 0.8 * f.x) * z);\n"
    "  color.a = 1.0;\n"
    "}\n";

static nbt_table *build(nbt_table_kind kind, int n, int pack, size_t N)
{
    /* H on log1p_cbrt (the planner's mapping), J on log1p: the shaders'
     * mapping codes 4 and 2 both checked against the CPU lookup */
    nbt_axis a0 = kind == NBT_TABLE_H ? (nbt_axis){0, 10, NBT_AXIS_LOG1P_CBRT, 10, N} : (nbt_axis){0, 10, NBT_AXIS_LOG1P, 1000, N};
    nbt_axis a1 = kind == NBT_TABLE_H ? (nbt_axis){-M_PI_2, M_PI_2, NBT_AXIS_COS, 0, N} : (nbt_axis){0, M_PI, NBT_AXIS_COS, 0, N};
    nbt_table *t = nbt_table_alloc(kind, &a0, &a1, 4);
    for (int c = 0; c < 4; c++)
        t->k[c] = 4 * pack + c;
    t->n = n;
    nbt_build_opts o = {1e-10, 1, 0};
    nbt_status st = kind == NBT_TABLE_H ? nbt_h_table_build(t, NULL, &o) : nbt_j_table_build(t, NULL, &o);
    return st == NBT_OK ? t : NULL;
}

/* validate one variant with glslangValidator (and the GL compiler) */
/* What the shader computes (nbt_airlight.glsl), in double: two lookups per
 * channel, weighted, times the prefactor. nbt_airlight_table is not this
 * near the source axis, where it integrates along the ray instead. */
static double lookup_airlight(nbt_table *const *T, size_t nt, const double *b, const nbt_airlight_geom *g)
{
    double h = g->dsv * sin(g->gamma), t = g->dsv * cos(g->gamma), u = g->kappa_t * h;
    double th0 = g->gamma - M_PI_2, thd = atan2(g->dvp - t, h), s = 0;
    for (size_t i = 0; i < nt; i++) {
        double a[NBT_TABLE_MAX_CH], c[NBT_TABLE_MAX_CH];
        nbt_table_lookup(T[i], u, thd, a);
        nbt_table_lookup(T[i], u, th0, c);
        for (size_t ch = 0; ch < T[i]->nch; ch++)
            s += (2.0 * T[i]->k[ch] + 1.0) * b[T[i]->k[ch]] * (a[ch] - c[ch]);
    }
    double lp = -g->kappa_t * t + log(g->kappa_s * g->I0 / (4.0 * M_PI * h));
    return s == 0.0 ? 0.0 : copysign(exp(lp + log(fabs(s))), s);
}

/* glslangValidator on an assembled source: 0 when it accepts it */
static int glslang(const char *src, const char *flags)
{
    char path[] = "/tmp/nbt-test-glsl-XXXXXX";
    int fd = mkstemp(path);
    FILE *f = fdopen(fd, "w");
    fputs(src, f);
    fclose(f);
    char cmd[512];
    snprintf(cmd, sizeof cmd, "glslangValidator %s -S frag %s >/dev/null 2>&1", flags, path);
    int rc = system(cmd);
    unlink(path);
    return rc;
}

/* one variant for every target: desktop GL 3.30 (validated and compiled by the
 * driver), GLSL ES 3.00 (validated) and Vulkan (compiled to SPIR-V, -V) */
static void validate(const nbt_gl_config *c0, const char *main_src)
{
    static const char *const tname[3] = {"GL 3.30", "GLSL ES 3.00", "Vulkan SPIR-V"};
    static const char *const tflags[3] = {"", "", "-V -o /dev/null"};
    for (int target = 0; target < 3; target++) {
        nbt_gl_config c = *c0;
        char *src = nbt_gl_shader_source_target(&c, target, main_src);
        if (!src) {
            t_true(0, "%s source assembled", tname[target]);
            continue;
        }
        int rc = glslang(src, tflags[target]);
        t_true(rc == 0, "glslangValidator accepts the %s variant h=%d j1=%d jn=%d fixed=%d beam=%d g-sliced=%d%s",
               tname[target], c.h_packs, c.j1_packs, c.jn_packs, c.fixed_phase, c.beam, c.g_sliced,
               rc == 0 ? "" : " (is glslang-tools installed?)");
        if (target == NBT_GL_TARGET_GL330) {
            char err[4096];
            unsigned p = gl_fullscreen_program(src, err, sizeof err);
            t_true(p != 0, "GL compiles and links the variant h=%d j1=%d jn=%d fixed=%d g-sliced=%d: %s", c.h_packs,
                   c.j1_packs, c.jn_packs, c.fixed_phase, c.g_sliced, p ? "ok" : err);
            if (p)
                glDeleteProgram(p);
        }
        free(src);
    }
}

/* the validators can say no: ES without default precision and Vulkan with a
 * loose uniform are errors (what the targets' headers exist to avoid) */
static void validators_can_fail(const char *main_src)
{
    nbt_gl_config c = {1, 0, 0, 0, 0, 0, 0};
    char *src = nbt_gl_shader_source_target(&c, NBT_GL_TARGET_ES300, main_src);
    char *p = strstr(src, "precision highp float;");
    memset(p, ' ', strlen("precision highp float;"));
    t_true(glslang(src, "") != 0, "GLSL ES 3.00 without a default float precision is rejected");
    free(src);
    src = nbt_gl_shader_source_target(&c, NBT_GL_TARGET_VULKAN, "uniform float loose;\nlayout(location = 0) out vec4 color;\nvoid main() { color = vec4(loose); }\n");
    t_true(glslang(src, "-V -o /dev/null") != 0, "a loose uniform is rejected for Vulkan");
    free(src);
    t_true(nbt_gl_shader_source_target(&c, 3, NULL) == NULL, "target 3 rejected");
}

/* ---- g-sliced tables (sampler3D, run-time g) ---- */

/* A g-sliced HG table H_p(u, v; g) or J_p^n(T, theta; g) on the given
 * axes, built by libnbt (nbt_gslice_fill; its error is test_gslice's). */
static nbt_table *assemble_gsliced(nbt_table_kind kind, int n, const nbt_axis *a0, const nbt_axis *a1,
                                   const nbt_axis *a2)
{
    nbt_table *t = nbt_table_alloc3(kind, a0, a1, a2, 1);
    nbt_build_opts o = {1e-10, 0, 0};
    if (t) {
        t->n = n;
        if (kind == NBT_TABLE_J) { /* J as libnbt builds it: ln(e^T J), quadratic in g */
            t->form = NBT_FORM_LOG_ET;
            t->interp2 = 2;
            o.measure_error = 1; /* for the check against nbt_surface_direct */
        }
        if (nbt_gslice_fill(t, &o) != NBT_OK) {
            nbt_table_free(t);
            t = NULL;
        }
    }
    return t;
}

/* What the g-sliced shaders compute, in double, from the same float tables:
 * the airlight is libnbt's pure lookup of the tail form
 * (nbt_airlight_table_g_lookup: the exponentials, the short-segment Gauss
 * rule); surface radiance the fixed-phase formula with every lookup
 * trilinear at g (nbt_table_lookup3). (libnbt's nbt_airlight_table_g also
 * falls back to the ray integral where its bound is poor; a shader cannot,
 * so the lookup alone is compared.) */
static double gs_airlight(const nbt_table *Ht, double gph, const nbt_airlight_geom *g)
{
    nbt_airlight_geom q = *g;
    double L, E, lo = Ht->axis[2].lo, hi = Ht->axis[2].hi;
    q.gamma = fmin(fmax(q.gamma, 1e-3), M_PI - 1e-3);
    nbt_airlight_table_g_lookup(Ht, fmin(fmax(gph, lo), hi), &q, &L, &E);
    return L;
}

/* J from a g-sliced table in its form (log_et: e^{v - T}); *scale: how float
 * coordinate noise in v turns into J (plain: max |v|; log_et: J max |v|) */
static double gs_j(const nbt_table *J, double T, double th, double gph, double *scale)
{
    double v;
    nbt_table_lookup3(J, T, th, gph, &v);
    if (J->form != NBT_FORM_LOG_ET) {
        *scale = J->max_abs[0];
        return v;
    }
    v = exp(v - T);
    *scale = v * J->max_abs[0];
    return v;
}

static double gs_surface(const nbt_table *J1, const nbt_table *Jn, double gph, const nbt_surface_geom *g, double *sj)
{
    double T = g->kappa_t * g->dsp, s1, sn;
    double j1 = gs_j(J1, T, g->theta_s, gph, &s1), jn = gs_j(Jn, T, g->theta_r, gph, &sn);
    *sj = g->kd * s1 + g->ks * sn;
    double direct = g->I0 * exp(-T) / (g->dsp * g->dsp) *
                    (g->kd * fmax(cos(g->theta_s), 0.0) + g->ks * pow(fmax(cos(g->theta_r), 0.0), g->n));
    return direct + g->kappa_s * g->I0 / (4.0 * M_PI * g->dsp) * (g->kd * j1 + g->ks * jn);
}

/* How far float shading can move a point's unit coordinate on axis a: r =
 * (x - lo)/(hi - lo) rounded (a few ulps relative, and ~eps absolute where
 * the mapping forms 1 - 2r or 1 + c r in float) carried through the
 * mapping's slope (steep for cos and cbrt near the ends), plus a few ulps of
 * the mapping's own arithmetic. r exactly 0 or 1 (the ends, and clamped
 * points) is exact in float. */
static double unit_noise(const nbt_axis *a, double x)
{
    double r = (x - a->lo) / (a->hi - a->lo), s = nbt_axis_to_unit(a, x), e = 4 * FLT_EPSILON;
    if (r <= 0 || r >= 1)
        return e;
    double dr = 4 * FLT_EPSILON * r + FLT_EPSILON, xs[2] = {fmax(r - dr, 0), fmin(r + dr, 1)};
    for (int i = 0; i < 2; i++)
        e = fmax(e, 4 * FLT_EPSILON + fabs(nbt_axis_to_unit(a, a->lo + xs[i] * (a->hi - a->lo)) - s));
    return e;
}

static double data_maxabs(const nbt_table *t)
{
    double m = 0;
    for (size_t i = 0; i < nbt_table_size(t); i++)
        m = fmax(m, fabs(t->data[i]));
    return m;
}

/* the largest difference between neighbouring values along each axis (any channel) */
static void table_steps(const nbt_table *t, double step[3])
{
    size_t n[3] = {t->axis[0].n, t->axis[1].n, t->axis[2].n}, str[3] = {t->nch, t->nch * n[0], t->nch * n[0] * n[1]};
    step[0] = step[1] = step[2] = 0;
    for (size_t i = 0; i < nbt_table_size(t); i++) {
        size_t idx[3] = {(i / str[0]) % n[0], (i / str[1]) % n[1], i / str[2]};
        for (int a = 0; a < 3; a++)
            if (idx[a] + 1 < n[a])
                step[a] = fmax(step[a], fabs((double)t->data[i + str[a]] - t->data[i]));
    }
}

/* A full-screen program from libnbt-gl's modules for cfg and main_src;
 * asserts that it links (what names it in the test line). */
static GLuint config_program(const nbt_gl_config *cfg, const char *main_src, const char *what)
{
    char err[4096] = "no shader source";
    char *src = nbt_gl_shader_source(cfg, main_src);
    GLuint p = src ? gl_fullscreen_program(src, err, sizeof err) : 0;
    free(src);
    t_true(p != 0, "%s: %s", what, p ? "ok" : err);
    return p;
}

/* The raw nbt_lookup3 against nbt_table_lookup3 at W x H points read from a
 * texture: x0, x1 uniform over their ranges widened by 5% (clamping), x2 in
 * turn a slice node, a midpoint between slices (unit coordinate), a random
 * value, an end exactly, and beyond an end. */
static void check_lookup3(nbt_table *t, const char *what)
{
    static const char *LK =
        "uniform sampler2D pts;\nuniform sampler3D tab;\nuniform vec4 a0, a1, a2;\nuniform int m0, m1, m2;\n"
        "out vec4 color;\nvoid main() {\n  vec4 p = texelFetch(pts, ivec2(gl_FragCoord.xy), 0);\n"
        "  color = nbt_lookup3(tab, a0, m0, a1, m1, a2, m2, p.x, p.y, p.z);\n}\n";
    static const char *LKQ =
        "uniform sampler2D pts;\nuniform sampler3D tab;\nuniform vec4 a0, a1, a2;\nuniform int m0, m1, m2;\n"
        "out vec4 color;\nvoid main() {\n  vec4 p = texelFetch(pts, ivec2(gl_FragCoord.xy), 0);\n"
        "  color = nbt_lookup3q(tab, a0, m0, a1, m1, a2, m2, p.x, p.y, p.z);\n}\n";
    static const char *LKC =
        "uniform sampler2D pts;\nuniform sampler3D tab;\nuniform vec4 a0, a1, a2;\nuniform int m0, m1, m2;\n"
        "out vec4 color;\nvoid main() {\n  vec4 p = texelFetch(pts, ivec2(gl_FragCoord.xy), 0);\n"
        "  color = nbt_lookup3c(tab, a0, m0, a1, m1, a2, m2, p.x, p.y, p.z);\n}\n";
    GLuint p = config_program(&(nbt_gl_config){0, 0, 0, 0, 0, 0, 0}, t->interp2 == 3 ? LKC : t->interp2 == 2 ? LKQ : LK,
                              "lookup3 shader");
    if (!p)
        return;
    float *pt = malloc(W * H * 4 * sizeof(float)), *px = malloc(W * H * 4 * sizeof(float));
    for (int i = 0; i < W * H; i++) {
        float *q = pt + 4 * i;
        for (int a = 0; a < 2; a++) {
            const nbt_axis *ax = &t->axis[a];
            q[a] = (float)(ax->lo + (ax->hi - ax->lo) * (1.1 * t_uniform() - 0.05));
        }
        const nbt_axis *g = &t->axis[2];
        size_t m = (size_t)(t_uniform() * (double)(g->n - 1));
        double span = g->hi - g->lo;
        switch (i % 5) {
        case 0: q[2] = (float)nbt_axis_node(g, m + (i % 2)); break;
        /* quadratic in g switches its three slices at midpoints (a jump of
         * the order of its error; random data make it O(1)): a quarter off */
        case 1: q[2] = (float)nbt_axis_from_unit(g, (m + (t->interp2 == 2 ? 0.25 : 0.5)) / (double)(g->n - 1)); break;
        case 2: q[2] = (float)(g->lo + span * t_uniform()); break;
        case 3: q[2] = (float)(i % 2 ? g->hi : g->lo); break;
        default: q[2] = (float)(i % 2 ? g->hi + 0.5 * span * t_uniform() : g->lo - 0.5 * span * t_uniform()); break;
        }
        q[3] = 0;
    }
    GLuint tex[2];
    glUseProgram(p);
    tex[0] = nbt_gl_bind_table(p, "tab", t, 12);
    t_true(tex[0] != 0 && nbt_gl_table_target(t) == GL_TEXTURE_3D, "%s: uploaded as a 3-D texture", what);
    glActiveTexture(GL_TEXTURE13);
    glGenTextures(1, &tex[1]);
    glBindTexture(GL_TEXTURE_2D, tex[1]);
    glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA32F, W, H, 0, GL_RGBA, GL_FLOAT, pt);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    glUniform1i(glGetUniformLocation(p, "pts"), 13);
    float a[3][4];
    int map[3];
    static const char *an[3] = {"a0", "a1", "a2"}, *mn[3] = {"m0", "m1", "m2"};
    for (int i = 0; i < 3; i++) {
        nbt_gl_axis(&t->axis[i], a[i], &map[i]);
        glUniform4fv(glGetUniformLocation(p, an[i]), 1, a[i]);
        glUniform1i(glGetUniformLocation(p, mn[i]), map[i]);
    }
    gl_draw_fullscreen();
    glReadPixels(0, 0, W, H, GL_RGBA, GL_FLOAT, px);
    t_true(glGetError() == GL_NO_ERROR, "%s: render and read back", what);
    /* llvmpipe weights float textures in float (DESIGN.md): ~1e-7 of the
     * scale per product, 8 of them (quadratic in g: 3 bilinear fetches and
     * weights, 1.5x that; cubic: 4 fetches, weights summing to |w| <= 1.63,
     * 2x); the rest is the float unit coordinate (unit_noise)
     * times the texel count and the largest texel step (quadratic: the
     * weights' slope in g, up to 3 steps; cubic 4) */
    double step[3], scale = data_maxabs(t), worst = 0, wcls[5] = {0};
    double q2 = t->interp2 == 3 ? 2.0 : t->interp2 == 2 ? 1.5 : 1.0;
    table_steps(t, step);
    for (int i = 0; i < W * H; i++) {
        const float *q = pt + 4 * i;
        double ref[NBT_TABLE_MAX_CH], tol = 2e-6 * q2 * scale;
        nbt_table_lookup3(t, q[0], q[1], q[2], ref);
        for (int ax = 0; ax < 3; ax++)
            tol += unit_noise(&t->axis[ax], q[ax]) * (double)(t->axis[ax].n - 1) * step[ax] * (ax == 2 ? 2 * q2 : 1);
        for (size_t c = 0; c < t->nch; c++) {
            double e = fabs(px[4 * i + c] - ref[c]) / tol;
            worst = fmax(worst, e);
            wcls[i % 5] = fmax(wcls[i % 5], e);
        }
    }
    t_true(worst <= 1, "%s: nbt_lookup3 = nbt_table_lookup3 within 2e-6 of the scale + float coordinate noise "
           "(worst %.2f of it; g at nodes %.2f, midpoints %.2f, random %.2f, ends %.2f, beyond %.2f)",
           what, worst, wcls[0], wcls[1], wcls[2], wcls[3], wcls[4]);
    glDeleteTextures(2, tex);
    glDeleteProgram(p);
    free(pt);
    free(px);
}

/* random values: every texel independent, so a misplaced coordinate on any axis shows */
static nbt_table *random_table3(const nbt_axis *a0, const nbt_axis *a1, const nbt_axis *a2, size_t nch)
{
    nbt_table *t = nbt_table_alloc3(NBT_TABLE_H, a0, a1, a2, nch);
    for (size_t i = 0; i < nbt_table_size(t); i++)
        t->data[i] = (float)(2 * t_uniform() - 1);
    for (size_t c = 0; c < nch; c++)
        t->k[c] = -1;
    return t;
}

static void test_gsliced(void)
{
    /* the raw lookup: RGBA32F on (log1p_cbrt, cos, cos) and R16F on (linear, sqrt, log1p clustered at hi),
     * sizes that differ per axis */
    nbt_axis r0 = {0, 10, NBT_AXIS_LOG1P_CBRT, 10, 7}, r1 = {-M_PI_2, M_PI_2, NBT_AXIS_COS, 0, 5};
    nbt_axis r2 = {-0.95, 0.95, NBT_AXIS_COS, 0, 6};
    nbt_table *rt = random_table3(&r0, &r1, &r2, 4);
    check_lookup3(rt, "RGBA32F 7x5x6");
    nbt_table_free(rt);
    nbt_axis q0 = {0.5, 3.5, NBT_AXIS_LINEAR, 0, 9}, q1 = {0, M_PI, NBT_AXIS_SQRT, 0, 4};
    nbt_axis q2 = {-0.9, 0.97, NBT_AXIS_LOG1P, -0.9, 5};
    rt = random_table3(&q0, &q1, &q2, 1);
    nbt_table_round_half(rt);
    check_lookup3(rt, "R16F 9x4x5");
    nbt_table_free(rt);
    /* quadratic in g on an atanh g axis (nbt_lookup3q, map code 5) */
    nbt_axis w2 = {-0.95, 0.9, NBT_AXIS_ATANH, 0, 7};
    rt = random_table3(&r0, &q1, &w2, 2);
    rt->interp2 = 2;
    check_lookup3(rt, "RG32F 7x4x7 atanh, quadratic in g");
    /* cubic in g (nbt_lookup3c, what the tail-form H holds): the same table,
     * and the fewest slices it takes (4: every cell an end cell or the
     * middle one) on the ends map with an asymmetric range */
    rt->interp2 = 3;
    check_lookup3(rt, "RG32F 7x4x7 atanh, cubic in g");
    nbt_table_free(rt);
    nbt_axis c2 = {-0.7, 0.9, NBT_AXIS_ENDS, 5, 4};
    rt = random_table3(&q0, &r1, &c2, 1);
    rt->interp2 = 3;
    check_lookup3(rt, "R32F 9x5x4 ends, cubic in g");
    nbt_table_free(rt);
    /* asinh (map code 6): theta of J^1 as the planner writes it (c = 1), and
     * strongly clustered (c = 20) on the slice axis */
    nbt_axis s1 = {0, M_PI, NBT_AXIS_ASINH, 1, 9}, s2 = {-1, 2, NBT_AXIS_ASINH, 20, 6};
    rt = random_table3(&r0, &s1, &s2, 3);
    check_lookup3(rt, "RGB32F 7x9x6 asinh (c = 1, 20)");
    nbt_table_free(rt);
    /* ends (map code 7): v of the g-sliced H as the planner writes it (c = 16),
     * and on the slice axis with another c and range (halves c/2 and c apart) */
    nbt_axis e1 = {-M_PI_2, M_PI_2, NBT_AXIS_ENDS, 16, 11}, e2 = {-0.5, 2.0, NBT_AXIS_ENDS, 3, 6};
    rt = random_table3(&r0, &e1, &e2, 2);
    check_lookup3(rt, "RG32F 7x11x6 ends (c = 16, 3)");
    nbt_table_free(rt);

    /* the slice axis' uniforms from nbt_gl_set_table_axes, down to two slices
     * (a random mutant treating a 2-slice table as 2-D survived every test) */
    {
        static const char *AX = "uniform vec4 nbt_T_ax2;\nuniform int nbt_T_map2;\nout vec4 color;\n"
                                "void main() { color = vec4(nbt_T_ax2.x, nbt_T_ax2.y, nbt_T_ax2.w, float(nbt_T_map2)); }\n";
        nbt_axis t2 = {-0.5, 0.7, NBT_AXIS_COS, 0, 2};
        rt = random_table3(&q0, &q1, &t2, 1);
        GLuint p = config_program(&(nbt_gl_config){0, 0, 0, 0, 0, 0, 0}, AX, "slice-axis uniforms shader");
        if (p) {
            glUseProgram(p);
            nbt_gl_set_table_axes(p, "nbt_T", rt);
            gl_draw_fullscreen();
            float px[4];
            glReadPixels(0, 0, 1, 1, GL_RGBA, GL_FLOAT, px);
            t_true(fabsf(px[0] - -0.5f) < 1e-7f && fabsf(px[1] - 0.7f) < 1e-7f && px[2] == 2.0f && px[3] == 3.0f,
                   "a 2-slice table's g axis reaches its uniforms: lo %g hi %g n %g map %g", px[0], px[1], px[2], px[3]);
            glDeleteProgram(p);
        }
        nbt_table_free(rt);
    }

    /* airlight and surface radiance from g-sliced H, J^1, J^20 (HG, g nodes clustered at +-0.95) */
    nbt_axis g2 = {-0.95, 0.95, NBT_AXIS_COS, 0, 9};
    nbt_axis h0 = {0, 10, NBT_AXIS_LOG1P_CBRT, 10, 33}, h1 = {-M_PI_2, M_PI_2, NBT_AXIS_COS, 0, 33};
    nbt_axis j0 = {0, 10, NBT_AXIS_LOG1P, 1000, 25}, j1 = {0, M_PI, NBT_AXIS_COS, 0, 25};
    nbt_table *Hg = assemble_gsliced(NBT_TABLE_H, 0, &h0, &h1, &g2);
    nbt_axis gj2 = {-0.95, 0.95, NBT_AXIS_ATANH, 0, 9};
    nbt_table *J1g = assemble_gsliced(NBT_TABLE_J, 1, &j0, &j1, &gj2);
    nbt_table *Jng = assemble_gsliced(NBT_TABLE_J, (int)NPH, &j0, &j1, &gj2);
    t_true(Hg && J1g && Jng, "g-sliced tables assembled");
    if (!Hg || !J1g || !Jng)
        return;
    /* r, g: nbt_airlight / nbt_surface at the uniform nbt_g; b, a: nbt_airlight_g / nbt_surface_g
     * at a g per row from -0.99 to 0.99 (both ends clamp) */
    static const char *GS =
        "uniform vec2 res;\n"
        "out vec4 color;\n"
        "void main() {\n"
        "  vec2 f = (gl_FragCoord.xy - 0.5) / (res - 1.0);\n"
        "  float gam = mix(0.05, 3.09, f.x), d = mix(0.5, 40.0, f.y), gr = mix(-0.99, 0.99, f.y);\n"
        "  float ths = f.x * 3.14159265358979, thr = (1.0 - f.x) * 1.5;\n"
        "  color.r = nbt_airlight(0.15, 0.2, 2.385, d, gam, 25.0);\n"
        "  color.g = nbt_surface(0.15, 0.2, 2.385, d, ths, thr, 0.7, 0.3, 20.0);\n"
        "  color.b = nbt_airlight_g(0.15, 0.2, 2.385, 6.0, gam, 25.0, gr);\n"
        "  color.a = nbt_surface_g(0.15, 0.2, 2.385, 6.0, ths, thr, 0.7, 0.3, 20.0, gr);\n"
        "}\n";
    nbt_gl_config gc = {1, 1, 1, 0, 0, 0, 1};
    GLuint p = config_program(&gc, GS, "g-sliced shader");
    const nbt_table *tabs[3] = {Hg, J1g, Jng};
    static const char *names[3] = {"nbt_H0", "nbt_J1_0", "nbt_Jn_0"};
    GLuint tex[3];
    glUseProgram(p);
    for (int i = 0; i < 3; i++)
        tex[i] = nbt_gl_bind_table(p, names[i], tabs[i], 8 + (unsigned)i);
    nbt_gl_set_table_axes(p, "nbt_H", Hg);
    nbt_gl_set_table_axes(p, "nbt_J", J1g);
    glUniform2f(glGetUniformLocation(p, "res"), W, H);
    /* the uniform g: a slice node, the midpoint of the top cell (unit coordinate), 0.9, the range end
     * 0.95, beyond it (0.99 reads the 0.95 slice), a negative node */
    double gu[6] = {nbt_axis_node(&g2, 6), nbt_axis_from_unit(&g2, 7.5 / 8), 0.9, 0.95, 0.99, nbt_axis_node(&g2, 1)};
    float *px = malloc(W * H * 4 * sizeof(float));
    /* the float-coordinate noise of one lookup, as in the 2-D test: ~4 eps (N - 1) texels per axis
     * times the table's scale */
    /* the tail form: log values, so the noise is relative (slopes of log R up to ~10 per unit) */
    double noise_h = 4 * FLT_EPSILON * (double)(h0.n + h1.n + g2.n - 3) * 10.0;
    double noise_j = 4 * FLT_EPSILON * (double)(j0.n + j1.n + gj2.n - 3);
    double worst_dir = 0, bound_max = 0;
    int ndir = 0;
    for (int gi = 0; gi < 6; gi++) {
        glUniform1f(glGetUniformLocation(p, "nbt_g"), (float)gu[gi]);
        gl_draw_fullscreen();
        glReadPixels(0, 0, W, H, GL_RGBA, GL_FLOAT, px);
        double gf = (float)gu[gi], worst[4] = {0};
        int fin = 1;
        for (int j = 0; j < H; j++)
            for (int i = 0; i < W; i++) {
                double fx = (double)i / (W - 1), fy = (double)j / (H - 1);
                double gam = G0 + (G1 - G0) * fx, d = D0 + (D1 - D0) * fy, gr = (float)(-0.99 + 1.98 * fy);
                const float *q = px + (j * W + i) * 4;
                fin &= isfinite(q[0]) && isfinite(q[1]) && isfinite(q[2]) && isfinite(q[3]);
                nbt_airlight_geom ag = {KS, KT, I0, d, gam, DVP}, ag6 = {KS, KT, I0, 6.0, gam, DVP};
                nbt_surface_geom sg = {KS, KT, I0, d, fx * M_PI, (1 - fx) * 1.5, KD, KSP, (int)NPH};
                nbt_surface_geom sg6 = {KS, KT, I0, 6.0, fx * M_PI, (1 - fx) * 1.5, KD, KSP, (int)NPH};
                /* as test 1: 1e-4 relative + the noise of two lookups times the prefactor (airlight),
                 * of the weighted lookups (surface) */
                double La = gs_airlight(Hg, gf, &ag), La6 = gs_airlight(Hg, gr, &ag6);
                double sj, sj6, Lp = gs_surface(J1g, Jng, gf, &sg, &sj), Lp6 = gs_surface(J1g, Jng, gr, &sg6, &sj6);
                double pre = KS * I0 * exp(-KT * d * cos(gam)) / (4 * M_PI * d * sin(gam));
                double pre6 = KS * I0 * exp(-KT * 6.0 * cos(gam)) / (4 * M_PI * 6.0 * sin(gam));
                double tol6 = 1e-4 * fabs(Lp6) + noise_j * KS * I0 / (4 * M_PI * 6.0) * sj6;
                (void)pre;
                (void)pre6;
                worst[0] = fmax(worst[0], fabs(q[0] - La) / ((1e-4 + 2 * noise_h) * fabs(La)));
                worst[1] = fmax(worst[1], fabs(q[1] - Lp) / (1e-4 * fabs(Lp) + noise_j * KS * I0 / (4 * M_PI * d) * sj));
                worst[2] = fmax(worst[2], fabs(q[2] - La6) / ((1e-4 + 2 * noise_h) * fabs(La6)));
                worst[3] = fmax(worst[3], fabs(q[3] - Lp6) / tol6);
                /* the shader's surface radiance against the direct integral, within the
                 * bound libnbt records for the same lookup (nbt_surface_table_g, no fallback)
                 * + the shader-vs-CPU tolerance + the reference's error: a few pixels of the
                 * first frame with |g| <= 0.95 (the direct integral takes ~0.1 s) */
                if (gi == 0 && fabs(gr) <= 0.95 && i % 16 == 5 && j % 12 == 3) {
                    double L, E, R, RE;
                    nbt_phase *ph = nbt_phase_hg(gr);
                    nbt_surface_direct(ph, &sg6, 1e-8, &R, &RE);
                    nbt_phase_free(ph);
                    nbt_surface_table_g(J1g, Jng, gr, &sg6, 0, &L, &E);
                    worst_dir = fmax(worst_dir, fabs(q[3] - R) / (E + RE + tol6));
                    bound_max = fmax(bound_max, E / fabs(R));
                    ndir++;
                }
            }
        t_true(fin, "g-sliced, nbt_g = %.6g: every pixel finite", gf);
        t_true(worst[0] <= 1 && worst[1] <= 1,
               "g-sliced, nbt_g = %.6g: airlight and surface = CPU lookup within 1e-4 relative + float "
               "lookup noise (worst %.2f, %.2f of it)", gf, worst[0], worst[1]);
        if (gi == 0)
            t_true(worst[2] <= 1 && worst[3] <= 1,
                   "g-sliced, g per row -0.99..0.99 (nbt_airlight_g, nbt_surface_g): = CPU lookup within the same "
                   "bound (worst %.2f, %.2f of it)", worst[2], worst[3]);
    }
    t_true(ndir >= 8 && worst_dir <= 1,
           "g-sliced surface (log_et J): shader = nbt_surface_direct within the recorded bound at %d pixels "
           "(worst %.2f of it; bound up to %.1e relative on these 25^2 x 9 tables)", ndir, worst_dir, bound_max);
    /* issue 10's goal, 1e-3 relative from the shader alone: J^1, J^20 log_et tables sized for the
     * alpha column's T = 1.2 (T in [0, 2.5]: 33 x 129 x 33, g in [-0.95, 0.95]) bound in place of the
     * small ones; at the same pixels the shader is within 1e-3 of nbt_surface_direct (+ its error
     * estimate). This asserts the goal as measured (7.2e-4 here), not a bound: libnbt's recorded
     * bound for these tables is the largest over each g cell's whole (T, theta) slice (8.4e-3). */
    nbt_axis f0 = {0, 2.5, NBT_AXIS_LOG1P_CBRT, 10, 33}, f1 = {0, M_PI, NBT_AXIS_LINEAR, 0, 129};
    nbt_axis fg = {-0.95, 0.95, NBT_AXIS_ATANH, 0, 33}; /* the shader's J tables share their axes */
    nbt_table *J1f = assemble_gsliced(NBT_TABLE_J, 1, &f0, &f1, &fg), *Jnf = assemble_gsliced(NBT_TABLE_J, (int)NPH, &f0, &f1, &fg);
    t_true(J1f && Jnf, "g-sliced J 33x129x33 built");
    if (J1f && Jnf) {
        GLuint t1 = nbt_gl_bind_table(p, "nbt_J1_0", J1f, 9), t2 = nbt_gl_bind_table(p, "nbt_Jn_0", Jnf, 10);
        nbt_gl_set_table_axes(p, "nbt_J", J1f);
        glUniform1f(glGetUniformLocation(p, "nbt_g"), 0.0f);
        gl_draw_fullscreen();
        glReadPixels(0, 0, W, H, GL_RGBA, GL_FLOAT, px);
        double worst = 0, wb = 0;
        int np = 0;
        for (int j = 3; j < H; j += 12)
            for (int i = 5; i < W; i += 16) {
                double fx = (double)i / (W - 1), gr = (float)(-0.99 + 1.98 * (double)j / (H - 1)), L, E, R, RE;
                if (fabs(gr) > 0.95)
                    continue;
                nbt_surface_geom sg6 = {KS, KT, I0, 6.0, fx * M_PI, (1 - fx) * 1.5, KD, KSP, (int)NPH};
                nbt_phase *ph = nbt_phase_hg(gr);
                nbt_surface_direct(ph, &sg6, 1e-9, &R, &RE);
                nbt_phase_free(ph);
                nbt_surface_table_g(J1f, Jnf, gr, &sg6, 0, &L, &E);
                worst = fmax(worst, (fabs(px[(j * W + i) * 4 + 3] - R) - RE) / fabs(R));
                wb = fmax(wb, E / fabs(L));
                np++;
            }
        t_true(np >= 8 && worst <= 1e-3,
               "g-sliced surface (log_et J 33x129x33): shader within 1e-3 of nbt_surface_direct at %d pixels "
               "(worst %.1e; libnbt's recorded bound there up to %.1e)", np, worst, wb);
        glDeleteTextures(1, &t1);
        glDeleteTextures(1, &t2);
    }
    nbt_table_free(J1f);
    nbt_table_free(Jnf);
    free(px);
    glDeleteTextures(3, tex);
    glDeleteProgram(p);
    nbt_table_free(Hg);
    nbt_table_free(J1g);
    nbt_table_free(Jng);
}

/* The g-sliced airlight shader against the direct integral: the table the
 * planner writes for g in [-0.95, 0.95] at tol 1e-3 (97x193x33, v on ends
 * c = 16, cubic in g: bench/gslice_accuracy had 0 of 1e5 random rays above
 * 1e-3 on it, worst 7.9e-4), one random ray and g per
 * pixel (kappa_t 0.5, d_sv <= 19, gamma in (0.02, pi - 0.02), d_vp finite
 * or infinite: bench_gslice's distribution), nbt_airlight_g on llvmpipe
 * against nbt_airlight_direct with HG(g). Asserted: every pixel within
 * libnbt's bound for the lookup (the error map, float noise 1e-4 and the
 * reference's estimate added), and every pixel within 1e-3 relative (the
 * shader's float arithmetic adds ~1e-5 to the CPU lookup's worst 7.9e-4). */
static void test_gsliced_direct(void)
{
    nbt_gslice_request rq = {NBT_TABLE_H, 0, 10.0, {-0.95, 0.95}, 1e-3, {0, 0, 0}, 0};
    nbt_gslice_plan_t pl;
    memset(&pl, 0, sizeof pl);
    char perr[256] = "";
    nbt_status pst = nbt_gslice_plan(&rq, 2, &pl, perr, sizeof perr);
    t_true(pst == NBT_OK && pl.axis[1].map == NBT_AXIS_ENDS, "planned g-sliced H %zux%zux%zu (v %s) for the direct "
           "check: %s", pl.axis[0].n, pl.axis[1].n, pl.axis[2].n, nbt_axis_map_name(pl.axis[1].map), perr);
    if (pst != NBT_OK)
        return;
    nbt_table *Hg = nbt_table_alloc3(NBT_TABLE_H, &pl.axis[0], &pl.axis[1], &pl.axis[2], 1);
    nbt_build_opts o = {1e-10, 1, 0};
    t_true(Hg && nbt_gslice_fill(Hg, &o) == NBT_OK && Hg->interp2 == 3, "g-sliced H for the direct check filled, "
           "cubic in g");
    enum { NW = 32, NH = 24 };
    static float prm[4][NW * NH];
    unsigned long long r = 0x5eedull;
    for (int i = 0; i < NW * NH; i++) {
        double x[4];
        for (int k = 0; k < 4; k++) {
            r = r * 6364136223846793005ull + 1442695040888963407ull;
            x[k] = (double)(r >> 11) / 9007199254740992.0;
        }
        prm[0][i] = (float)(0.5 + 18.5 * x[0]);
        prm[1][i] = (float)(0.02 + (M_PI - 0.04) * x[1]);
        prm[2][i] = i % 3 == 0 ? 1e30f : (float)(0.1 + 25.0 * x[2]);
        prm[3][i] = (float)(-0.95 + 1.9 * x[3]);
    }
    static const char *GD =
        "uniform sampler2D prm;\n"
        "out vec4 color;\n"
        "void main() {\n"
        "  vec4 q = texelFetch(prm, ivec2(gl_FragCoord.xy), 0);\n"
        "  color = vec4(nbt_airlight_g(0.3, 0.5, 1.0, q.x, q.y, q.z, q.w), 0.0, 0.0, 1.0);\n"
        "}\n";
    nbt_gl_config gc = {1, 0, 0, 0, 0, 0, 1};
    GLuint p = config_program(&gc, GD, "g-sliced direct-check shader");
    if (!p || !Hg) {
        nbt_table_free(Hg);
        return;
    }
    float *px = malloc(NW * NH * 4 * sizeof(float));
    for (int i = 0; i < NW * NH; i++)
        for (int k = 0; k < 4; k++)
            px[i * 4 + k] = prm[k][i];
    glUseProgram(p);
    GLuint ptex;
    glGenTextures(1, &ptex);
    glActiveTexture(GL_TEXTURE0 + 12);
    glBindTexture(GL_TEXTURE_2D, ptex);
    glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA32F, NW, NH, 0, GL_RGBA, GL_FLOAT, px);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    glUniform1i(glGetUniformLocation(p, "prm"), 12);
    GLuint tex = nbt_gl_bind_table(p, "nbt_H0", Hg, 8);
    nbt_gl_set_table_axes(p, "nbt_H", Hg);
    glViewport(0, 0, NW, NH);
    gl_draw_fullscreen();
    glReadPixels(0, 0, NW, NH, GL_RGBA, GL_FLOAT, px);
    glViewport(0, 0, W, H);
    int ok3 = 0, inb = 0;
    double worst = 0, wb = 0;
    for (int i = 0; i < NW * NH; i++) {
        nbt_airlight_geom geo = {0.3, 0.5, 1.0, prm[0][i], prm[1][i], prm[2][i] > 1e29f ? INFINITY : prm[2][i]};
        double g = prm[3][i], R, RE, L, E;
        nbt_phase *ph = nbt_phase_hg(g);
        nbt_airlight_direct(ph, &geo, 1e-10, &R, &RE);
        nbt_phase_free(ph);
        nbt_airlight_table_g_lookup(Hg, g, &geo, &L, &E);
        double d = fabs(px[i * 4] - R);
        ok3 += d <= 1e-3 * R;
        inb += d <= E + 1e-4 * R + RE;
        if (!(d <= E + 1e-4 * R + RE) && getenv("NBT_TEST_VERBOSE"))
            printf("  ray %d: g %.4f gamma %.5f dsv %.3f dvp %g: shader %.8g C %.8g direct %.8g bound %.2e\n", i, g,
                   geo.gamma, geo.dsv, geo.dvp, px[i * 4], L, R, E);
        worst = fmax(worst, d / R);
        if (E > 0)
            wb = fmax(wb, d / (E + 1e-4 * R + RE));
    }
    t_true(inb == NW * NH, "g-sliced shader vs nbt_airlight_direct: %d of %d rays within the lookup's bound "
           "+ 1e-4 (worst %.2f of it)", inb, NW * NH, wb);
    t_true(ok3 == NW * NH, "g-sliced shader vs nbt_airlight_direct: %.1f%% of %d random rays within 1e-3 "
           "relative (worst %.2e)", 100.0 * ok3 / (NW * NH), NW * NH, worst);
    free(px);
    glDeleteTextures(1, &ptex);
    glDeleteTextures(1, &tex);
    glDeleteProgram(p);
    nbt_table_free(Hg);
}

/* ---- form sub (issue 21): the shaders add the closed form back ---- */

/* S's float scale of channel c: sum_q |c_q| max|b_q| (y <= pi, 1/sqrt <= 1/w; d <= 1) */
static double sub_scale(const nbt_table *t, size_t c)
{
    double s = 0;
    for (int q = 0; q < NBT_SUB_TERMS; q++)
        s += fabs(t->sub_c[c][q]) * (q == 1 ? M_PI : q == 9 ? (t->sub_w > 0 ? 1 / t->sub_w : 0) : 1);
    return s;
}

/* a coordinate on axis a for point i (k picks the case): a quarter in the last cell, an eighth
 * beyond either end when `beyond` (clamped by the lookup), the rest uniform in the unit coordinate */
static double sub_coord(const nbt_axis *a, int k, int beyond)
{
    double n1 = (double)(a->n - 1), span = a->hi - a->lo;
    if (beyond && k % 8 == 2)
        return a->hi + 0.3 * span * t_uniform();
    if (beyond && k % 8 == 3)
        return a->lo - 0.3 * span * t_uniform();
    return nbt_axis_from_unit(a, k % 8 < 2 ? (n1 - 1 + t_uniform()) / n1 : t_uniform());
}

/* A pack lookup's float noise (channel c at (x0, x1)): llvmpipe's float bilinear weights
 * (2e-6 of the texels' scale, as for nbt_lookup3), the float unit coordinate (unit_noise)
 * times the texel count and the largest texel step, and S in float: ten products of
 * coefficients with terms each a few ulps off (the angle-addition recurrences carry the
 * one sin/cos pair's ulps up to 4y), 16 eps of sum |c_q| max|b_q| */
static double sub_noise(const nbt_table *t, const double step[3], double scale, size_t c, double x0, double x1)
{
    return 2e-6 * scale + unit_noise(&t->axis[0], x0) * (double)(t->axis[0].n - 1) * step[0] +
           unit_noise(&t->axis[1], x1) * (double)(t->axis[1].n - 1) * step[1] + 16 * FLT_EPSILON * sub_scale(t, c);
}

/* nbt_airlight (H packs in nbt_H0..) or nbt_surface (J packs in both the J^1 and J^n slots) of the
 * program in use at W x H random geometries (u or T: a quarter in the last cell, an eighth beyond
 * the axis; d_vp infinite for a third: v1 = pi/2, the last node) against the CPU formula on
 * nbt_table_lookup (1e-5 relative for the float exponentials plus each lookup's sub_noise) and the
 * exact series of the same npk x 4 orders within 1.25x the tables' recorded error */
static void sub_shade(GLuint p, nbt_table *const *tp, size_t npk, int n, const double *b, const float *w, float *pt,
                      float *px, const char *what)
{
    const nbt_table *t = tp[0];
    int isH = t->kind == NBT_TABLE_H;
    size_t K = 4 * npk;
    double step[2][3], scale[2], wsum = 0, tscale = 0;
    for (size_t pk = 0; pk < npk; pk++) {
        table_steps(tp[pk], step[pk]);
        scale[pk] = data_maxabs(tp[pk]);
    }
    for (size_t k = 0; k < K; k++)
        wsum += fabs(w[k]);
    for (size_t c = 0; c < 4; c++)
        tscale = fmax(tscale, t->max_abs[c]);
    double worst = 0, wex = 0, wabs = 0, wexabs = 0;
    for (int i = 0; i < W * H; i++) {
        double x = fmax(sub_coord(&t->axis[0], i, 0), 1e-3);
        if (i % 8 == 2)
            x = t->axis[0].hi * (1 + 0.3 * t_uniform());
        float *q = pt + 4 * i;
        if (isH) {
            /* d_sv <= 65 (as the plain test's 40): airlight within float range */
            double gam = 0.05 + (M_PI - 0.1) * t_uniform(), dsv = x / (KT * sin(gam));
            if (dsv > 60) {
                double sg = fmin(x / (KT * 60), 1);
                gam = gam < M_PI_2 ? asin(sg) : M_PI - asin(sg);
                dsv = x / (KT * sin(gam));
            }
            q[0] = (float)dsv;
            q[1] = (float)gam;
            q[2] = (float)(i % 3 == 0 ? 1e30 : q[0] * (0.05 + 3 * t_uniform()));
            q[3] = 0;
        } else {
            q[0] = (float)(x / KT);
            q[1] = (float)sub_coord(&t->axis[1], i / 8, 0);
            q[2] = (float)sub_coord(&t->axis[1], i / 64 + 1, 0);
            q[3] = (float)n;
        }
    }
    glActiveTexture(GL_TEXTURE5);
    glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA32F, W, H, 0, GL_RGBA, GL_FLOAT, pt);
    glUniform1i(glGetUniformLocation(p, "which"), isH ? 3 : 4);
    gl_draw_fullscreen();
    glReadPixels(0, 0, W, H, GL_RGBA, GL_FLOAT, px);
    for (int i = 0; i < W * H; i++) {
        const float *q = pt + 4 * i;
        double cpu, ex, pre, xa[2], ya[2], sa[2] = {1, 1}, ee[8], exv[8], e = 0;
        if (isH) {
            nbt_airlight_geom ag = {KS, KT, I0, q[0], q[1], q[2]};
            double h = ag.dsv * sin(ag.gamma), tt = ag.dsv * cos(ag.gamma);
            cpu = lookup_airlight(tp, npk, b, &ag);
            nbt_airlight_series(b, K, &ag, 1e-10, &ex, &e);
            pre = KS * I0 * exp(-KT * tt) / (4 * M_PI * h);
            xa[0] = xa[1] = KT * h;
            ya[0] = ag.gamma - M_PI_2;
            ya[1] = atan2(ag.dvp - tt, h);
        } else {
            double T = KT * q[0], lk[4], js[2] = {0, 0}, jx[2] = {0, 0};
            xa[0] = xa[1] = T;
            ya[0] = q[1];
            ya[1] = q[2];
            sa[0] = KD;
            sa[1] = KSP;
            pre = KS * I0 / (4 * M_PI * q[0]);
            for (int s = 0; s < 2; s++) {
                nbt_jk(K - 1, n, T, ya[s], 1e-10, exv, ee);
                for (size_t pk = 0; pk < npk; pk++) {
                    nbt_table_lookup(tp[pk], T, ya[s], lk);
                    for (size_t c = 0; c < 4; c++)
                        js[s] += w[4 * pk + c] * lk[c];
                }
                for (size_t k = 0; k < K; k++) {
                    jx[s] += w[k] * exv[k];
                    e += pre * sa[s] * fabs(w[k]) * ee[k];
                }
            }
            double direct = I0 * exp(-T) / (q[0] * q[0]) *
                            (KD * fmax(cos(q[1]), 0.0) + KSP * pow(fmax(cos(q[2]), 0.0), q[3]));
            cpu = direct + pre * (KD * js[0] + KSP * js[1]);
            ex = direct + pre * (KD * jx[0] + KSP * jx[1]);
        }
        /* H: two lookups subtracted (sa = 1 each); J: kd and ks times one lookup each */
        double tol = 1e-5 * fabs(cpu), bound = e;
        for (int s = 0; s < 2; s++)
            for (size_t pk = 0; pk < npk; pk++)
                for (size_t c = 0; c < 4; c++) {
                    double wk = pre * sa[s] * fabs(w[4 * pk + c]);
                    tol += wk * sub_noise(tp[pk], step[pk], scale[pk], c, xa[s], ya[s]);
                    bound += wk * tp[pk]->max_err[c];
                }
        double v = px[4 * i];
        worst = fmax(worst, fabs(v - cpu) / tol);
        wex = fmax(wex, (fabs(v - ex) - tol) / bound);
        wabs = fmax(wabs, fabs(v - cpu) / (pre * wsum * tscale));
        wexabs = fmax(wexabs, fabs(v - ex) / (pre * wsum * tscale));
    }
    t_true(worst <= 1, "%s: %s = the CPU formula on nbt_table_lookup within 1e-5 + float lookup noise "
           "(worst %.2f of it; largest difference %.2e of the scattered term's scale)", what,
           isH ? "nbt_airlight" : "nbt_surface", worst, wabs);
    /* the recorded bilinear maxima bound cell midpoints; 1.25 as in test_plan */
    t_true(wex <= 1.25, "%s: %s within 1.25x the tables' recorded error of the exact series "
           "(worst %.2f of the bound; largest difference %.2e of the scattered term's scale)", what,
           isH ? "nbt_airlight" : "nbt_surface", wex, wexabs);
}

/* The default scene's three sets (H, J^1, J^20, 4 orders each, tol 1e-3) built with sub = 1: 33^2
 * (tests/test_plan.c). For each set, at W x H points (a quarter in the last cell of each axis,
 * some beyond the ends): the raw pack lookup nbt_lookup_sub (through nbt_J1_0 and nbt_Jn_0 for
 * the J sets) against nbt_table_lookup per channel; nbt_airlight / nbt_surface against the CPU
 * formula on nbt_table_lookup (the same float tables and coefficients); and against the exact
 * series within the tables' recorded error. */
static void test_sub(void)
{
    static const char *SUBM =
        "uniform sampler2D pts;\nuniform int which;\nout vec4 color;\nvoid main() {\n"
        "  vec4 p = texelFetch(pts, ivec2(gl_FragCoord.xy), 0);\n"
        "  if (which == 0)\n"
        "    color = nbt_lookup_sub(nbt_H0, nbt_H_ax0, nbt_H_map0, nbt_H_ax1, nbt_H_map1, nbt_H0_sub, nbt_H0_sub_w,\n"
        "                           nbt_H0_sub_c, p.x, p.y);\n"
        "  else if (which == 1)\n"
        "    color = nbt_lookup_sub(nbt_J1_0, nbt_J_ax0, nbt_J_map0, nbt_J_ax1, nbt_J_map1, nbt_J1_0_sub,\n"
        "                           nbt_J1_0_sub_w, nbt_J1_0_sub_c, p.x, p.y);\n"
        "  else if (which == 2)\n"
        "    color = nbt_lookup_sub(nbt_Jn_0, nbt_J_ax0, nbt_J_map0, nbt_J_ax1, nbt_J_map1, nbt_Jn_0_sub,\n"
        "                           nbt_Jn_0_sub_w, nbt_Jn_0_sub_c, p.x, p.y);\n"
        "  else if (which == 3)\n"
        "    color = vec4(nbt_airlight(0.15, 0.2, 2.385, p.x, p.y, p.z), 0.0, 0.0, 1.0);\n"

        "  else\n"
        "    color = vec4(nbt_surface(0.15, 0.2, 2.385, p.x, p.y, p.z, 0.7, 0.3, p.w), 0.0, 0.0, 1.0);\n}\n";
    nbt_plan_request rq[3] = NBT_TEST_DEFAULT_SUB_REQUESTS;
    nbt_plan *plan = NULL;
    char err[512];
    nbt_status st = nbt_plan_tables(rq, 3, 0, &plan, err, sizeof err);
    t_true(st == NBT_OK, "form sub: the default scene's sets planned (%s)", st ? err : "ok");
    GLuint p = st == NBT_OK ? config_program(&(nbt_gl_config){1, 1, 1, 0, 0, 0, 0}, SUBM, "form-sub shader") : 0;
    if (!p) {
        nbt_plan_free(plan);
        return;
    }
    glUseProgram(p);
    nbt_phase *hg = nbt_phase_hg(0.5);
    double b[4];
    float w[4];
    nbt_phase_moments(hg, 3, b);
    nbt_gl_weights(b, 4, 1, w);
    glUniform4fv(glGetUniformLocation(p, "nbt_hw"), 1, w);
    float *pt = malloc(W * H * 4 * sizeof(float)), *px = malloc(W * H * 4 * sizeof(float));
    GLuint ptex;
    glActiveTexture(GL_TEXTURE5);
    glGenTextures(1, &ptex);
    glBindTexture(GL_TEXTURE_2D, ptex);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    glUniform1i(glGetUniformLocation(p, "pts"), 5);
    for (size_t si = 0; si < 3; si++) {
        nbt_tableset ts;
        memset(&ts, 0, sizeof ts);
        st = nbt_plan_execute(plan, si, &ts, err, sizeof err);
        const nbt_table *t = st == NBT_OK ? ts.t[0] : NULL;
        int isH = rq[si].kind == NBT_TABLE_H;
        t_true(t && t->form == NBT_FORM_SUB && t->axis[0].n == 33 && t->axis[1].n == 33 && ts.rel_err <= 1e-3,
               "set %zu (%s, n %d): form sub at 33x33, recorded %.3g <= 1e-3", si, nbt_table_kind_name(rq[si].kind),
               rq[si].n, t ? ts.rel_err : 0.0);
        if (!t)
            continue;
        /* H in nbt_H0; a J set in both J slots (they share nbt_J_ax*): the diffuse and Phong paths */
        GLuint tex[2] = {0, 0};
        tex[0] = nbt_gl_bind_table(p, isH ? "nbt_H0" : "nbt_J1_0", t, isH ? 0 : 1);
        if (!isH)
            tex[1] = nbt_gl_bind_table(p, "nbt_Jn_0", t, 2);
        nbt_gl_set_table_axes(p, isH ? "nbt_H" : "nbt_J", t);
        t_true(tex[0] && (isH || tex[1]), "set %zu: form-sub table uploaded", si);
        double step[3], scale = data_maxabs(t);
        table_steps(t, step);
        /* raw pack lookups: H through nbt_H0, J through nbt_J1_0 and nbt_Jn_0 */
        for (int which = isH ? 0 : 1; which <= (isH ? 0 : 2); which++) {
            for (int i = 0; i < W * H; i++) {
                pt[4 * i] = (float)sub_coord(&t->axis[0], i, 1);
                pt[4 * i + 1] = (float)sub_coord(&t->axis[1], i / 8, 1);
                pt[4 * i + 2] = pt[4 * i + 3] = 0;
            }
            glActiveTexture(GL_TEXTURE5);
            glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA32F, W, H, 0, GL_RGBA, GL_FLOAT, pt);
            glUniform1i(glGetUniformLocation(p, "which"), which);
            gl_draw_fullscreen();
            glReadPixels(0, 0, W, H, GL_RGBA, GL_FLOAT, px);
            double worst = 0, wabs = 0, wlast = 0;
            for (int i = 0; i < W * H; i++) {
                double x0 = pt[4 * i], x1 = pt[4 * i + 1], ref[4];
                nbt_table_lookup(t, x0, x1, ref);
                for (size_t c = 0; c < 4; c++) {
                    double e = fabs(px[4 * i + c] - ref[c]);
                    double r = e / sub_noise(t, step, scale, c, x0, x1);
                    worst = fmax(worst, r);
                    wabs = fmax(wabs, e / ts.scale);
                    if (i % 8 < 2 || (i / 8) % 8 < 2)
                        wlast = fmax(wlast, r);
                }
            }
            t_true(worst <= 1, "set %zu: nbt_lookup_sub through %s = nbt_table_lookup within float noise "
                   "(worst %.2f of it, %.2e of the scale; last cells %.2f)", si,
                   which == 0 ? "nbt_H0" : which == 1 ? "nbt_J1_0" : "nbt_Jn_0", worst, wabs, wlast);
        }
        char label[64];
        snprintf(label, sizeof label, "set %zu", si);
        sub_shade(p, ts.t, 1, rq[si].n, b, w, pt, px, label);
        glDeleteTextures(2, tex);
        nbt_tableset_free(&ts);
    }
    /* packs 1 too: the same sets with 8 orders (two packs each, on the planned axes) in a program
     * with two packs per kind */
    GLuint p2 = config_program(&(nbt_gl_config){2, 2, 2, 0, 0, 0, 0}, SUBM, "form-sub shader, two packs");
    double b8[8];
    float w8[8];
    nbt_phase_moments(hg, 7, b8);
    nbt_gl_weights(b8, 8, 2, w8);
    for (size_t si = 0; p2 && si < 3; si++) {
        const nbt_plan_set *ps = nbt_plan_get(plan, si);
        nbt_table *tp[2];
        int isH = rq[si].kind == NBT_TABLE_H;
        for (int pk = 0; pk < 2; pk++) {
            tp[pk] = nbt_table_alloc(rq[si].kind, &ps->axis[0], &ps->axis[1], 4);
            for (int c = 0; c < 4; c++)
                tp[pk]->k[c] = 4 * pk + c;
            tp[pk]->n = isH ? 0 : rq[si].n;
            tp[pk]->form = NBT_FORM_SUB;
        }
        nbt_build_opts o = {1e-10, 1, 0};
        st = isH ? nbt_h_table_build_set(tp, 2, NULL, &o) : nbt_j_table_build_set(tp, 2, NULL, &o);
        t_true(st == NBT_OK, "set %zu, 8 orders: two form-sub packs built at %zux%zu", si, ps->axis[0].n, ps->axis[1].n);
        if (st == NBT_OK) {
            static const char *const nh[2] = {"nbt_H0", "nbt_H1"}, *const n1[2] = {"nbt_J1_0", "nbt_J1_1"},
                                     *const nn[2] = {"nbt_Jn_0", "nbt_Jn_1"};
            GLuint tex[4] = {0, 0, 0, 0};
            glUseProgram(p2);
            glUniform4fv(glGetUniformLocation(p2, "nbt_hw"), 2, w8);
            glUniform1i(glGetUniformLocation(p2, "pts"), 5);
            for (int pk = 0; pk < 2; pk++) {
                tex[pk] = nbt_gl_bind_table(p2, isH ? nh[pk] : n1[pk], tp[pk], (unsigned)pk);
                if (!isH)
                    tex[2 + pk] = nbt_gl_bind_table(p2, nn[pk], tp[pk], 2 + (unsigned)pk);
            }
            nbt_gl_set_table_axes(p2, isH ? "nbt_H" : "nbt_J", tp[0]);
            char label[64];
            snprintf(label, sizeof label, "set %zu, two packs", si);
            sub_shade(p2, tp, 2, rq[si].n, b8, w8, pt, px, label);
            glDeleteTextures(4, tex);
        }
        nbt_table_free(tp[0]);
        nbt_table_free(tp[1]);
    }
    if (p2)
        glDeleteProgram(p2);
    glDeleteTextures(1, &ptex);
    glDeleteProgram(p);
    free(pt);
    free(px);
    nbt_phase_free(hg);
    nbt_plan_free(plan);
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
    /* variants */
    const char *just_airlight = "layout(location = 0) out vec4 color;\nvoid main() { color = vec4(nbt_airlight(0.1, 0.2, 1.0, 3.0, 0.5, 1e30)); }\n";
    const char *just_surface = "layout(location = 0) out vec4 color;\nvoid main() { color = vec4(nbt_surface(0.1, 0.2, 1.0, 3.0, 0.5, 0.3, 0.7, 0.3, 20.0)); }\n";
    const char *just_beam = "layout(location = 0) out vec4 color;\nvoid main() { color = vec4(nbt_beam_psi(nbt_beam_kernel_params(1.0, 0.9, 0.1, 2.0), 0.3)); }\n";
    validators_can_fail(just_airlight);
    for (int h = 1; h <= 4; h++)
        validate(&(nbt_gl_config){h, 0, 0, 0, 0, 0, 0}, just_airlight);
    for (int j = 1; j <= 4; j++)
        validate(&(nbt_gl_config){0, j, j - 1, 0, 0, 0, 0}, just_surface);
    validate(&(nbt_gl_config){1, 1, 1, 1, 0, 0, 0}, just_airlight);
    validate(&(nbt_gl_config){0, 0, 0, 0, 1, 0, 0}, just_beam);
    const char *just_all = "layout(location = 0) out vec4 color;\nvoid main() { color = vec4(nbt_airlight(0.1, 0.2, 1.0, 3.0, 0.5, 1e30), "
                           "nbt_surface(0.1, 0.2, 1.0, 3.0, 0.5, 0.3, 0.7, 0.3, 20.0), "
                           "nbt_beam_psi(nbt_beam_kernel_params(1.0, 0.9, 0.1, 2.0), 0.3), 1.0); }\n";
    validate(&(nbt_gl_config){2, 2, 2, 0, 1, 0, 0}, just_all);
    t_true(nbt_gl_shader_source(&(nbt_gl_config){5, 0, 0, 0, 0, 0, 0}, NULL) == NULL, "5 packs rejected");
    t_true(nbt_gl_shader_source(&(nbt_gl_config){2, 0, 0, 1, 0, 0, 0}, NULL) == NULL, "fixed phase with 2 packs rejected");
    /* g-sliced (sampler3D tables, uniform nbt_g and the explicit-g functions) */
    const char *just_g = "layout(location = 0) out vec4 color;\nvoid main() { color = vec4(nbt_airlight(0.1, 0.2, 1.0, 3.0, 0.5, 1e30), "
                         "nbt_airlight_g(0.1, 0.2, 1.0, 3.0, 0.5, 1e30, 0.9), nbt_surface(0.1, 0.2, 1.0, 3.0, 0.5, 0.3, 0.7, 0.3, 20.0), "
                         "nbt_surface_g(0.1, 0.2, 1.0, 3.0, 0.5, 0.3, 0.7, 0.3, 20.0, 0.95)); }\n";
    validate(&(nbt_gl_config){1, 1, 1, 0, 0, 0, 1}, just_g);
    validate(&(nbt_gl_config){1, 0, 0, 0, 0, 0, 1}, just_airlight);
    validate(&(nbt_gl_config){0, 1, 0, 1, 0, 0, 1}, just_surface);
    t_true(nbt_gl_shader_source(&(nbt_gl_config){1, 2, 0, 0, 0, 0, 1}, NULL) == NULL, "g-sliced with 2 packs rejected");

    /* tables: orders 0..7 of H, J^1, J^20 */
    nbt_table *Ht[2], *J1t[2], *Jnt[2];
    for (int p = 0; p < 2; p++) {
        Ht[p] = build(NBT_TABLE_H, 0, p, 65);
        J1t[p] = build(NBT_TABLE_J, 1, p, 49);
        Jnt[p] = build(NBT_TABLE_J, 20, p, 49);
    }
    t_true(Ht[0] && Ht[1] && J1t[0] && J1t[1] && Jnt[0] && Jnt[1], "tables built");
    nbt_gl_config cfg = {2, 2, 2, 0, 1, 0, 0};
    GLuint prog = config_program(&cfg, MAIN, "test shader");
    GLuint fbo = gl_float_target(W, H);
    t_true(fbo != 0, "RGBA32F render target");
    /* create every texture on unit 0 first, then bind them to their units */
    const nbt_table *all[6] = {Ht[0], Ht[1], J1t[0], J1t[1], Jnt[0], Jnt[1]};
    static const char *names[6] = {"nbt_H0", "nbt_H1", "nbt_J1_0", "nbt_J1_1", "nbt_Jn_0", "nbt_Jn_1"};
    GLuint tex[6];
    glActiveTexture(GL_TEXTURE0);
    for (int i = 0; i < 6; i++)
        tex[i] = nbt_gl_upload_table(all[i]);
    glUseProgram(prog);
    for (int i = 0; i < 6; i++) {
        glActiveTexture(GL_TEXTURE0 + (GLenum)i);
        glBindTexture(GL_TEXTURE_2D, tex[i]);
        glUniform1i(glGetUniformLocation(prog, names[i]), i);
    }
    nbt_phase *hg = nbt_phase_hg(0.5);
    double b[8];
    nbt_phase_moments(hg, 7, b);
    float w[8];
    nbt_gl_weights(b, 8, 2, w);
    glUniform4fv(glGetUniformLocation(prog, "nbt_hw"), 2, w);
    nbt_gl_set_table_axes(prog, "nbt_H", Ht[0]);
    nbt_gl_set_table_axes(prog, "nbt_J", J1t[0]);
    glUniform2f(glGetUniformLocation(prog, "res"), W, H);
    gl_draw_fullscreen();
    float *px = malloc(W * H * 4 * sizeof(float));
    glReadPixels(0, 0, W, H, GL_RGBA, GL_FLOAT, px);
    t_true(glGetError() == GL_NO_ERROR, "render and read back");

    /* sum_k |w_k| max|table_k|: the scale of each weighted lookup */
    double wscale_h = 0, wscale_j1 = 0, wscale_jn = 0;
    for (int k = 0; k < 8; k++) {
        double wk = fabs((2 * k + 1) * b[k]);
        wscale_h += wk * Ht[k / 4]->max_abs[k % 4];
        wscale_j1 += wk * J1t[k / 4]->max_abs[k % 4];
        wscale_jn += wk * Jnt[k / 4]->max_abs[k % 4];
    }
    double noise_h = 4 * FLT_EPSILON * (double)(Ht[0]->axis[0].n - 1), noise_j = 4 * FLT_EPSILON * (double)(J1t[0]->axis[0].n - 1);
    /* CPU: the same geometries, the same float tables, double arithmetic */
    double worst[3] = {0}, worst_exact = 0;
    int finite = 1, within = 1;
    for (int j = 0; j < H; j++)
        for (int i = 0; i < W; i++) {
            double fx = (double)i / (W - 1), fy = (double)j / (H - 1);
            double gam = G0 + (G1 - G0) * fx, d = D0 + (D1 - D0) * fy;
            const float *p = px + (j * W + i) * 4;
            finite &= isfinite(p[0]) && isfinite(p[1]) && isfinite(p[2]);
            nbt_airlight_geom ag = {KS, KT, I0, d, gam, DVP};
            double La, Lp, ref, e;
            La = lookup_airlight(Ht, 2, b, &ag);
            /* Float shading: the unit coordinate carries a few ulps of relative
             * error (log, acos), i.e. ~4 eps (N - 1) texels, and one texel can
             * span the table's whole scale: per lookup the absolute noise is
             * ~4 FLT_EPSILON (N - 1) x scale, times the prefactor. Where the
             * airlight is the small difference of two lookups (gamma near pi)
             * this, not a relative error, is the honest bound. */
            double pre_a = KS * I0 * exp(-KT * d * cos(gam)) / (4 * M_PI * d * sin(gam));
            double tol_a = 1e-4 * fabs(La) + 2 * noise_h * pre_a * wscale_h;
            worst[0] = fmax(worst[0], fabs(p[0] - La) / tol_a);
            /* the exact 8-term series, within the tables' recorded error (as in test_airlight) */
            nbt_airlight_series(b, 8, &ag, 1e-10, &ref, &e);
            double bound = 0, h = d * sin(gam);
            for (int k = 0; k < 8; k++)
                bound += 2 * fabs((2 * k + 1) * b[k]) * Ht[k / 4]->max_err[k % 4];
            bound *= KS * I0 * exp(-KT * d * cos(gam)) / (4 * M_PI * h);
            within &= fabs(p[0] - ref) <= 1.25 * bound + 1e-4 * fabs(ref);
            worst_exact = fmax(worst_exact, fabs(p[0] - ref) / bound);
            nbt_surface_geom sg = {KS, KT, I0, d, fx * M_PI, (1 - fx) * 1.5, KD, KSP, (int)NPH};
            nbt_surface_table((const nbt_table *const *)J1t, 2, (const nbt_table *const *)Jnt, 2, b, 8, &sg, &Lp);
            double tol_p = 1e-4 * fabs(Lp) + noise_j * KS * I0 / (4 * M_PI * d) * (KD * wscale_j1 + KSP * wscale_jn);
            worst[1] = fmax(worst[1], fabs(p[1] - Lp) / tol_p);
            double z = d / 4, r = (0.02 + 0.8 * fx) * z, M0, M2, al, be;
            nbt_beam_medium m = nbt_beam_homogeneous(1.0, ALB, BB);
            nbt_beam_moments(&m, NBT_BEAM_ISHIMARU, z, &M0, &M2, NULL);
            nbt_beam_kernel_params(M0, M2, &al, &be);
            double psi = nbt_beam_kernel(al, be, r);
            worst[2] = fmax(worst[2], fabs(p[2] - psi) / fabs(psi));
        }
    t_true(finite, "every pixel finite");
    t_true(worst[0] <= 1, "airlight: shader = CPU table lookup within 1e-4 relative + float lookup noise (worst %.2f of it)",
           worst[0]);
    t_true(worst[1] <= 1, "surface: shader = CPU table lookup within 1e-4 relative + float lookup noise (worst %.2f of it)",
           worst[1]);
    /* G by A&S 7.1.26 (<= 7.5e-8 abs) and float moments */
    t_abs(worst[2], 0, 1e-4, "beam kernel: shader = libnbt (worst rel %.2e)", worst[2]);
    t_true(within, "airlight within 1.25x the tables' recorded error of the exact series (worst %.2f of the bound)",
           worst_exact);

    /* the fitted kernel model (nbt_beam_fit_psi) against libnbt's double evaluation, both geometries:
     * R over albedo and depth, G over B and radius, B over depth from far below to far above the
     * fitted range (its clamped monomials), A over radius deep in the medium */
    {
        const char *FIT =
            "uniform vec2 res;\nout vec4 color;\nvoid main() {\n"
            "  vec2 f = (gl_FragCoord.xy - 0.5) / (res - 1.0);\n"
            "  float z = mix(0.3, 6.0, f.y);\n"
            "  color.r = nbt_beam_fit_psi(1.7, mix(0.1, 0.99, f.x), 0.0685, z, 0.3 * z);\n"
            "  color.g = nbt_beam_fit_psi(1.0, 0.9, mix(0.0076, 0.274, f.y), 3.0, mix(0.02, 4.5, f.x));\n"
            "  color.b = nbt_beam_fit_psi(1.0, 0.5, 0.03, mix(0.05, 25.0, f.x), mix(0.05, 1.5, f.y) * mix(0.05, 25.0, f.x));\n"
            "  color.a = nbt_beam_fit_psi(0.8, 0.97, 0.2, 12.5, mix(0.01, 12.5, f.x) * mix(0.1, 1.5, f.y));\n"
            "}\n";
        nbt_gl_config bc = {0, 0, 0, 0, 1, 0, 0};
        /* the validators see a main without the test's loose uniform (Vulkan takes none) */
        validate(&bc, "layout(location = 0) out vec4 color;\n"
                      "void main() { color = vec4(nbt_beam_fit_psi(1.7, 0.9, 0.0685, 3.0, 0.9)); }\n");
        GLuint pf = config_program(&bc, FIT, "fitted-model shader");
        const nbt_beam_fit *fit = nbt_beam_fit_default();
        for (int inf = 0; inf < 2 && pf; inf++) {
            glUseProgram(pf);
            t_true(nbt_gl_set_beam_fit(pf, fit, inf) == 0, "nbt_gl_set_beam_fit (%s)", inf ? "infinite" : "half-space");
            glUniform2f(glGetUniformLocation(pf, "res"), W, H);
            gl_draw_fullscreen();
            glReadPixels(0, 0, W, H, GL_RGBA, GL_FLOAT, px);
            double wf[4] = {0};
            int fin = 1;
            for (int j = 0; j < H; j++)
                for (int i = 0; i < W; i++) {
                    double fx = (double)i / (W - 1), fy = (double)j / (H - 1), z = 0.3 + 5.7 * fy, ref[4];
                    nbt_beam_medium m0 = nbt_beam_homogeneous(1.7, 0.1 + 0.89 * fx, 0.0685);
                    nbt_beam_medium m1 = nbt_beam_homogeneous(1.0, 0.9, 0.0076 + (0.274 - 0.0076) * fy);
                    nbt_beam_medium m2 = nbt_beam_homogeneous(1.0, 0.5, 0.03);
                    nbt_beam_medium m3 = nbt_beam_homogeneous(0.8, 0.97, 0.2);
                    nbt_beam_fit_psi(fit, inf, &m0, z, 0.3 * z, &ref[0]);
                    nbt_beam_fit_psi(fit, inf, &m1, 3.0, 0.02 + 4.48 * fx, &ref[1]);
                    nbt_beam_fit_psi(fit, inf, &m2, 0.05 + 24.95 * fx, (0.05 + 1.45 * fy) * (0.05 + 24.95 * fx), &ref[2]);
                    nbt_beam_fit_psi(fit, inf, &m3, 12.5, (0.01 + 12.49 * fx) * (0.1 + 1.4 * fy), &ref[3]);
                    for (int c = 0; c < 4; c++) {
                        const float v = px[(j * W + i) * 4 + c];
                        fin &= isfinite(v) && v > 0;
                        wf[c] = fmax(wf[c], fabs(v - ref[c]) / ref[c]);
                    }
                }
            t_true(fin, "fitted model (%s): every pixel finite and > 0", inf ? "infinite" : "half-space");
            /* float arithmetic: the polynomials' sums (|P| <~ 15, ~1e-6 absolute), exp of them and of the
             * Gaussian exponent, erfc to 1.2e-7 relative: a few 1e-6 relative at most */
            for (int c = 0; c < 4; c++)
                t_abs(wf[c], 0, 1e-5, "fitted model (%s) channel %d: shader = libnbt within 1e-5 relative (worst %.2e)",
                      inf ? "infinite" : "half-space", c, wf[c]);
        }
        if (pf)
            glDeleteProgram(pf);
    }

    /* singular places: gamma = 0 through the source, gamma = pi, u far beyond the table, no surface */
    const char *SING =
        "out vec4 color;\nvoid main() {\n"
        "  color.r = nbt_airlight(0.15, 0.2, 2.385, 5.0, 0.0, 25.0);\n"
        "  color.g = nbt_airlight(0.15, 0.2, 2.385, 5.0, 3.14159265358979, 25.0);\n"
        "  color.b = nbt_airlight(0.15, 20.0, 2.385, 5.0, 1.0, 1e30);\n"
        "  color.a = nbt_surface(0.15, 20.0, 2.385, 50.0, 0.0, 0.0, 0.7, 0.3, 20.0);\n}\n";
    GLuint ps = config_program(&cfg, SING, "singular-places shader");
    glUseProgram(ps);
    for (int i = 0; i < 6; i++)
        glUniform1i(glGetUniformLocation(ps, names[i]), i);
    glUniform4fv(glGetUniformLocation(ps, "nbt_hw"), 2, w);
    nbt_gl_set_table_axes(ps, "nbt_H", Ht[0]);
    nbt_gl_set_table_axes(ps, "nbt_J", J1t[0]);
    gl_draw_fullscreen();
    float s[4];
    glReadPixels(0, 0, 1, 1, GL_RGBA, GL_FLOAT, s);
    t_true(isfinite(s[0]) && s[0] > 0, "ray through the source: finite (%g, the value at gamma = 1e-3)", s[0]);
    nbt_airlight_geom g0 = {KS, KT, I0, 5.0, 1e-3, 25.0};
    double L0;
    L0 = lookup_airlight(Ht, 2, b, &g0);
    t_rel(s[0], L0, 1e-3, "gamma = 0 gives the gamma = 1e-3 value");
    t_true(isfinite(s[1]) && s[1] >= 0, "source behind the viewer (gamma = pi): finite (%g)", s[1]);
    t_true(isfinite(s[2]) && isfinite(s[3]), "u and T beyond the tables: finite, edge values (%g, %g)", s[2], s[3]);
    free(px);
    for (int p = 0; p < 2; p++) {
        nbt_table_free(Ht[p]);
        nbt_table_free(J1t[p]);
        nbt_table_free(Jnt[p]);
    }
    nbt_phase_free(hg);
    test_gsliced();
    test_gsliced_direct();
    test_sub();
    egl_headless_close();
    return t_done();
}
