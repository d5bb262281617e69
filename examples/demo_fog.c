/* examples/demo_fog.c: a point light in fog over a ground plane with a
 * sphere, rendered offscreen with nbt's shaders and tables only: airlight
 * glow and surface radiance (Lambert + Phong n = 20) for g = 0, 0.5, 0.9 and
 * kappa = 0.05, 0.2 (as the thesis' Fig. 5.1-5.3), written as one PNG strip.
 * A fourth column repeats g = 0.9 with multiple scattering of the surfaces'
 * light on the way to the camera (nbt/screen.h, operator A with the moment
 * kernel of a Gaussian lobe of the same mean cosine, depth in 64 layers).
 * Columns five and six are g = 0.9 and 0.95 drawn from one set of g-sliced
 * tables (HG g on a third axis, sampler3D) at the run-time uniform nbt_g.
 * Usage: nbt-demo [OUT.png] [--width W]   (default nbt-demo.png, 320 per panel; unknown
 * options are refused, the output is opened before the work and renamed into place)
 * Installed with egl_headless.c/h, font5x7.h and a Makefile in PREFIX/share/nbt/examples:
 *   make -f PREFIX/share/nbt/examples/Makefile demo_fog   (pkg-config nbt-gl egl opengl libpng) */
#ifdef HAVE_CONFIG_H
#include <config.h>
#endif
#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <png.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>
#include <sys/stat.h>
#define GL_GLEXT_PROTOTYPES 1
#include <GL/gl.h>
#include <GL/glext.h>
#include <nbt/nbt.h>
#include <nbt/gl.h>
#include "egl_headless.h"
#include "font5x7.h"

static const char *SCENE =
    "uniform vec2 res;\n"
    "uniform vec3 light;\n"
    "uniform float kappa, albedo, I0, exposure;\n"
    "uniform int raw; // 1: (airlight, surface radiance before the medium, distance) for nbt-scatter's operator\n"
    "out vec4 color;\n"
    "void main() {\n"
    "  vec2 q = (gl_FragCoord.xy / res) * 2.0 - 1.0;\n"
    "  vec3 o = vec3(0.0, 1.2, 0.0);\n"
    "  vec3 d = normalize(vec3(q.x * res.x / res.y * 0.6, q.y * 0.6 - 0.12, -1.0));\n"
    "  float t = 1e30; vec3 n = vec3(0.0, 1.0, 0.0);\n"
    "  if (d.y < 0.0) t = -o.y / d.y;                       // ground plane y = 0\n"
    "  vec3 c = vec3(0.0, 1.0, -6.0); vec3 oc = o - c;       // sphere, radius 1\n"
    "  float b = dot(oc, d), disc = b * b - dot(oc, oc) + 1.0;\n"
    "  if (disc > 0.0) { float ts = -b - sqrt(disc); if (ts > 0.0 && ts < t) { t = ts; n = normalize(o + ts * d - c); } }\n"
    "  vec3 ls = light - o;\n"
    "  float ks = albedo * kappa;\n"
    "  float L = nbt_airlight(ks, kappa, I0, length(ls), acos(clamp(dot(d, normalize(ls)), -1.0, 1.0)), t);\n"
    "  float Ls = 0.0;\n"
    "  if (t < 1e29) {\n"
    "    vec3 p = o + t * d, lp = light - p, ldir = normalize(lp);\n"
    "    float ths = acos(clamp(dot(n, ldir), -1.0, 1.0));\n"
    "    float thr = acos(clamp(dot(reflect(d, n), ldir), -1.0, 1.0));\n"
    "    float kd = t < 1e29 && n.y > 0.999 ? 0.6 : 0.5, ksp = n.y > 0.999 ? 0.0 : 0.4;\n"
    "    Ls = nbt_surface(ks, kappa, I0, length(lp), ths, thr, kd, ksp, 20.0);\n"
    "    L += exp(-kappa * t) * Ls;\n"
    "  }\n"
    "  if (raw != 0) { color = vec4(L - (t < 1e29 ? exp(-kappa * t) * Ls : 0.0), Ls, min(t, 1e10), 1.0); return; }\n"
    "  vec3 rgb = vec3(1.0, 0.93, 0.8) * (1.0 - exp(-exposure * L));\n"
    "  color = vec4(pow(rgb, vec3(1.0 / 2.2)), 1.0);\n"
    "}\n";

static nbt_table *table(nbt_table_kind kind, int n, const nbt_phase *ph, size_t N)
{
    nbt_axis a0 = {0, 12, NBT_AXIS_LOG1P, 1000, N};
    nbt_axis a1 = kind == NBT_TABLE_H ? (nbt_axis){-M_PI_2, M_PI_2, NBT_AXIS_COS, 0, N} : (nbt_axis){0, M_PI, NBT_AXIS_COS, 0, N};
    nbt_table *t = nbt_table_alloc(kind, &a0, &a1, 1);
    t->n = n;
    nbt_build_opts o = {1e-9, 0, 0};
    nbt_status st = kind == NBT_TABLE_H ? nbt_h_table_build(t, ph, &o) : nbt_j_table_build(t, ph, &o);
    if (st != NBT_OK) {
        nbt_table_free(t);
        return NULL;
    }
    return t;
}

/* A g-sliced table over gax on the axes of table() above, built by libnbt
 * (nbt_gslice_fill). */
static nbt_table *assemble_gsliced(nbt_table_kind kind, int n, size_t N, const nbt_axis *gax)
{
    nbt_axis a0 = {0, 12, NBT_AXIS_LOG1P, 1000, N};
    nbt_axis a1 = kind == NBT_TABLE_H ? (nbt_axis){-M_PI_2, M_PI_2, NBT_AXIS_COS, 0, N} : (nbt_axis){0, M_PI, NBT_AXIS_COS, 0, N};
    nbt_table *t = nbt_table_alloc3(kind, &a0, &a1, gax, 1);
    nbt_build_opts o = {1e-9, 0, 0};
    if (t) {
        t->n = n;
        if (nbt_gslice_fill(t, &o) != NBT_OK) {
            nbt_table_free(t);
            t = NULL;
        }
    }
    return t;
}

/* the output's temporary, removed at exit unless renamed into place */
static char tmp_path[4096];
static void remove_tmp(void)
{
    if (tmp_path[0])
        unlink(tmp_path);
}

/* 0 on success; f stays open (the caller closes it) */
static int write_png(FILE *f, const unsigned char *rgb, int w, int h)
{
    png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, NULL, NULL, NULL);
    png_infop info = png ? png_create_info_struct(png) : NULL;
    if (!png || !info || setjmp(png_jmpbuf(png))) {
        png_destroy_write_struct(&png, info ? &info : NULL);
        return 1;
    }
    png_init_io(png, f);
    png_set_IHDR(png, info, (png_uint_32)w, (png_uint_32)h, 8, PNG_COLOR_TYPE_RGB, PNG_INTERLACE_NONE,
                 PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
    png_write_info(png, info);
    for (int y = 0; y < h; y++)
        png_write_row(png, (png_const_bytep)(rgb + (size_t)(h - 1 - y) * (size_t)w * 3)); /* GL rows are bottom-up */
    png_write_end(png, NULL);
    png_destroy_write_struct(&png, &info);
    return ferror(f) != 0;
}

/* px holds (airlight, surface radiance, distance) per pixel; replace it by
 * the tone-mapped colour of airlight + T c + S, S the surfaces' light
 * scattered on its way (operator A; the kernel built for the HG phase of
 * g = 0.9 the shaders use: its first order exact, the higher orders from
 * libnbt's fitted model, the camera inside the fog). */
static int multiple_scattering(float *px, int pw, int ph, double kappa, double albedo, double exposure)
{
    size_t n = (size_t)pw * (size_t)ph;
    float *rgb = malloc(n * 3 * sizeof *rgb), *D = malloc(n * sizeof *D), *Dq = malloc(n * sizeof *Dq);
    double *S = malloc(n * 3 * sizeof *S), *T = malloc(n * sizeof *T);
    nbt_phase *hg = nbt_phase_hg(0.9);
    nbt_screen_kernel *k = hg ? nbt_screen_kernel_phase(NBT_SKERNEL_FITTED, kappa, albedo, hg, NBT_SCREEN_INSIDE, NULL)
                              : NULL;
    int rc = !rgb || !D || !Dq || !S || !T || !k;
    for (size_t i = 0; !rc && i < n; i++) {
        rgb[3 * i] = rgb[3 * i + 1] = rgb[3 * i + 2] = px[4 * i + 1];
        D[i] = px[4 * i + 2];
    }
    if (!rc) {
        nbt_screen_quantize(D, n, 64, Dq);
        nbt_screen_input in = {(size_t)pw, (size_t)ph, rgb, Dq, 1.2 / ph, NULL}; /* the shader's tangent half-height 0.6 */
        rc = nbt_screen_layered(&in, k, NBT_SCREEN_NEAR, 1e-6, 66, 0, S, NULL) != NBT_OK;
    }
    for (size_t i = 0; !rc && i < n; i++) {
        nbt_screen_kern kn;
        nbt_screen_kernel_eval(k, D[i], &kn); /* the direct part at the true distance */
        double L = px[4 * i] + kn.T * px[4 * i + 1] + S[3 * i];
        static const double tint[3] = {1.0, 0.93, 0.8};
        for (int c = 0; c < 3; c++)
            px[4 * i + c] = (float)pow(tint[c] * (1.0 - exp(-exposure * L)), 1.0 / 2.2);
    }
    nbt_screen_kernel_free(k);
    nbt_phase_free(hg);
    free(rgb);
    free(D);
    free(Dq);
    free(S);
    free(T);
    return rc;
}

/* A panel label at the top-left of panel (col, row) of the strip, white on
 * a black box, in the 5x7 font of nbt-gen's previews (scaled by fs). img
 * holds GL rows (bottom-up) of an image H rows high. */
static void label(unsigned char *img, int W, int H, int pw, int ph, int col, int row, int fs, const char *s)
{
    int n = (int)strlen(s), bw = (6 * n + 3) * fs, bh = 11 * fs;
    for (int ry = 0; ry < bh && ry < ph; ry++)
        for (int rx = 0; rx < bw && rx < pw; rx++) {
            int tx = rx / fs - 2, ty = ry / fs - 2, on = 0;
            if (ty >= 0 && ty < 7 && tx >= 0 && tx / 6 < n && tx % 6 < 5) {
                char ch = (char)toupper((unsigned char)s[tx / 6]);
                for (size_t g = 0; g < sizeof font5x7 / sizeof font5x7[0]; g++)
                    if (font5x7[g].c == ch)
                        on = (font5x7[g].row[ty] >> (4 - tx % 6)) & 1;
            }
            int X = col * pw + rx, Y = H - 1 - (row * ph + ry);
            memset(img + ((size_t)Y * (size_t)W + (size_t)X) * 3, on ? 255 : 0, 3);
        }
}

/* the scene's uniforms shared by every panel */
static void scene_uniforms(GLuint prog, int pw, int ph)
{
    glUniform2f(glGetUniformLocation(prog, "res"), (float)pw, (float)ph);
    glUniform3f(glGetUniformLocation(prog, "light"), 1.6f, 2.6f, -4.5f);
    glUniform1f(glGetUniformLocation(prog, "albedo"), 0.9f);
    glUniform1f(glGetUniformLocation(prog, "I0"), 10.0f);
    glUniform1f(glGetUniformLocation(prog, "exposure"), 1.5f);
}

/* H, J^1 and J^20 (2-D or g-sliced 3-D) on texture units 0-2 of prog (in use) */
static int bind_tables(GLuint prog, nbt_table *const *t, GLuint *tex)
{
    static const char *names[3] = {"nbt_H0", "nbt_J1_0", "nbt_Jn_0"};
    for (int i = 0; i < 3; i++)
        tex[i] = nbt_gl_bind_table(prog, names[i], t[i], (unsigned)i);
    nbt_gl_set_table_axes(prog, "nbt_H", t[0]);
    nbt_gl_set_table_axes(prog, "nbt_J", t[1]);
    return !tex[0] || !tex[1] || !tex[2];
}

/* draw the current program into px (RGBA floats); returns the CPU seconds */
static double draw(float *px, int pw, int ph)
{
    double r0 = (double)clock() / CLOCKS_PER_SEC;
    gl_draw_fullscreen();
    glReadPixels(0, 0, pw, ph, GL_RGBA, GL_FLOAT, px);
    return (double)clock() / CLOCKS_PER_SEC - r0;
}

/* panel (col, row) of the strip from px; row 0 is kappa 0.05 (top) */
static void put_panel(unsigned char *img, int W, const float *px, int pw, int ph, int col, int row)
{
    for (int y = 0; y < ph; y++)
        for (int x = 0; x < pw; x++)
            for (int c = 0; c < 3; c++) {
                float v = px[((size_t)y * pw + x) * 4 + c];
                int X = col * pw + x, Y = (1 - row) * ph + y;
                img[((size_t)Y * W + X) * 3 + c] = (unsigned char)lrintf(255.0f * fminf(fmaxf(v, 0.0f), 1.0f));
            }
}

int main(int argc, char **argv)
{
    const char *out = "nbt-demo.png";
    int pw = 320;
    int have_out = 0;
    for (int i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "--width")) {
            char *end = NULL;
            long v = i + 1 < argc ? strtol(argv[i + 1], &end, 10) : 0;
            if (i + 1 >= argc || end == argv[i + 1] || *end || v < 16 || v > 4096) {
                fprintf(stderr, "nbt-demo: --width %s is not accepted: an integer 16..4096\n",
                        i + 1 < argc ? argv[i + 1] : "(missing)");
                return 2;
            }
            pw = (int)v;
            i++;
        } else if (!strcmp(argv[i], "--version")) {
            printf("nbt-demo (nbt) %s\n", nbt_version());
            return 0;
        } else if (!strcmp(argv[i], "--help")) {
            puts("Usage: nbt-demo [OUT.png] [--width W]\nRenders g = 0, 0.5, 0.9, 0.9 with multiple scattering, and g = 0.9, 0.95\n"
                 "from g-sliced tables at a run-time g (columns) x kappa = 0.05, 0.2 (rows); each panel labelled\n"
                 "with its g and kappa.");
            return 0;
        } else if (argv[i][0] == '-' && argv[i][1]) {
            /* an option taken for a file name wrote a PNG called "--foo" */
            fprintf(stderr, "nbt-demo: unknown option '%s': accepted are OUT.png, --width W, --help, --version\n",
                    argv[i]);
            return 2;
        } else if (have_out) {
            fprintf(stderr, "nbt-demo: one output only: '%s' and '%s'\n", out, argv[i]);
            return 2;
        } else {
            out = argv[i];
            have_out = 1;
        }
    }
    size_t olen = strlen(out);
    if (olen < 5 || strcmp(out + olen - 4, ".png")) {
        fprintf(stderr, "nbt-demo: '%s' is not accepted: the output must be a file name ending in .png\n", out);
        return 2;
    }
    /* the output is opened (as a temporary, renamed at the end) before the
     * tables and rendering, seconds of work, not after them */
    struct stat sb;
    if (stat(out, &sb) == 0 && S_ISDIR(sb.st_mode)) {
        fprintf(stderr, "nbt-demo: cannot write '%s': %s\n", out, strerror(EISDIR));
        return 1;
    }
    snprintf(tmp_path, sizeof tmp_path, "%s.tmp%ld", out, (long)getpid());
    FILE *fo = strlen(out) + 32 < sizeof tmp_path ? fopen(tmp_path, "wb") : NULL;
    if (!fo) {
        fprintf(stderr, "nbt-demo: cannot write '%s': %s\n", out, strerror(errno ? errno : ENAMETOOLONG));
        return 1;
    }
    atexit(remove_tmp);
    enum { NCOL = 6 };
    int ph = pw * 3 / 4, W = NCOL * pw, H = 2 * ph;
    char err[4096];
    if (egl_headless_open(err, sizeof err)) {
        fprintf(stderr, "nbt-demo: %s\n", err);
        return 1;
    }
    /* fixed-phase tables (one g per set) and g-sliced ones (g read from the uniform nbt_g) */
    nbt_gl_config cfg = {1, 1, 1, 1, 0, 0, 0}, cfg_g = {1, 1, 1, 0, 0, 0, 1};
    char *src = nbt_gl_shader_source(&cfg, SCENE);
    GLuint prog = gl_fullscreen_program(src, err, sizeof err);
    free(src);
    src = prog ? nbt_gl_shader_source(&cfg_g, SCENE) : NULL;
    GLuint prog_g = src ? gl_fullscreen_program(src, err, sizeof err) : 0;
    free(src);
    GLuint fbo = prog_g ? gl_float_target(pw, ph) : 0;
    if (!prog || !prog_g || !fbo) {
        fprintf(stderr, "nbt-demo: %s\n", prog_g ? "no RGBA32F render target" : err);
        return 1;
    }
    unsigned char *img = malloc((size_t)W * H * 3);
    float *px = malloc((size_t)pw * ph * 4 * sizeof(float));
    double gs[3] = {0.0, 0.5, 0.9}, ks[2] = {0.05, 0.2}, t_render = 0;
    double t0 = (double)clock() / CLOCKS_PER_SEC;
    for (int gi = 0; gi < 3; gi++) {
        nbt_phase *hp = gs[gi] == 0 ? nbt_phase_iso() : nbt_phase_hg(gs[gi]);
        nbt_table *t[3] = {table(NBT_TABLE_H, 0, hp, 129), table(NBT_TABLE_J, 1, hp, 65), table(NBT_TABLE_J, 20, hp, 65)};
        GLuint tex[3];
        glUseProgram(prog);
        if (!t[0] || !t[1] || !t[2] || bind_tables(prog, t, tex)) {
            fprintf(stderr, "nbt-demo: building the tables failed\n");
            return 1;
        }
        float w[4] = {1, 0, 0, 0};
        glUniform4fv(glGetUniformLocation(prog, "nbt_hw"), 1, w);
        scene_uniforms(prog, pw, ph);
        for (int ki = 0; ki < 2; ki++) {
            glUniform1f(glGetUniformLocation(prog, "kappa"), (float)ks[ki]);
            for (int ms = 0; ms < 1 + (gi == 2); ms++) {
                glUniform1i(glGetUniformLocation(prog, "raw"), ms);
                t_render += draw(px, pw, ph);
                if (ms && multiple_scattering(px, pw, ph, ks[ki], 0.9, 1.5) != 0) {
                    fprintf(stderr, "nbt-demo: multiple scattering failed\n");
                    return 1;
                }
                put_panel(img, W, px, pw, ph, gi + ms, ki);
                char lab[64];
                snprintf(lab, sizeof lab, "g=%g kappa=%g%s", gs[gi], ks[ki], ms ? " +multiple" : "");
                label(img, W, H, pw, ph, gi + ms, ki, pw >= 400 ? 2 : 1, lab);
            }
        }
        glDeleteTextures(3, tex);
        for (int i = 0; i < 3; i++)
            nbt_table_free(t[i]);
        nbt_phase_free(hp);
    }
    /* g-sliced: one set of tables over g in [0.8, 0.95] (4 slices, clustered at the ends), drawn at
     * nbt_g = 0.9 (between slices) and 0.95 (the last one); the g = 0.9 panel is compared with the
     * fixed-phase one (column 2) pixel by pixel */
    nbt_axis gax = {0.8, 0.95, NBT_AXIS_COS, 0, 4};
    /* H in the tail form: quadratic in g on an atanh axis (5 slices) */
    nbt_axis hgax = {0.8, 0.95, NBT_AXIS_ATANH, 0, 5};
    nbt_table *t[3] = {assemble_gsliced(NBT_TABLE_H, 0, 129, &hgax), assemble_gsliced(NBT_TABLE_J, 1, 65, &gax),
                       assemble_gsliced(NBT_TABLE_J, 20, 65, &gax)};
    GLuint tex[3];
    glUseProgram(prog_g);
    if (!t[0] || !t[1] || !t[2] || bind_tables(prog_g, t, tex)) {
        fprintf(stderr, "nbt-demo: building the g-sliced tables failed\n");
        return 1;
    }
    scene_uniforms(prog_g, pw, ph);
    glUniform1i(glGetUniformLocation(prog_g, "raw"), 0);
    double gsl[2] = {0.9, 0.95};
    int dmax = 0;
    for (int gi = 0; gi < 2; gi++) {
        glUniform1f(glGetUniformLocation(prog_g, "nbt_g"), (float)gsl[gi]);
        for (int ki = 0; ki < 2; ki++) {
            glUniform1f(glGetUniformLocation(prog_g, "kappa"), (float)ks[ki]);
            t_render += draw(px, pw, ph);
            put_panel(img, W, px, pw, ph, 4 + gi, ki);
            for (int y = 0; gi == 0 && y < ph; y++) /* against column 2 (fixed phase, g = 0.9), below the labels */
                for (int x = 0; x < pw * 3; x++) {
                    size_t row = (size_t)((1 - ki) * ph + y) * (size_t)W * 3;
                    if (ph - 1 - y >= 11 * (pw >= 400 ? 2 : 1)) {
                        int d = abs((int)img[row + (size_t)(4 * pw) * 3 + x] - (int)img[row + (size_t)(2 * pw) * 3 + x]);
                        dmax = d > dmax ? d : dmax;
                    }
                }
            char lab[64];
            snprintf(lab, sizeof lab, "g=%g kappa=%g sliced", gsl[gi], ks[ki]);
            label(img, W, H, pw, ph, 4 + gi, ki, pw >= 400 ? 2 : 1, lab);
        }
    }
    glDeleteTextures(3, tex);
    for (int i = 0; i < 3; i++)
        nbt_table_free(t[i]);
    /* written to the temporary and renamed: never a half-written picture */
    errno = 0;
    int rc = write_png(fo, img, W, H), e = 0;
    if (fclose(fo) != 0 || rc != 0)
        e = errno ? errno : EIO;
    else if (rename(tmp_path, out) != 0)
        e = errno;
    rc = e != 0;
    if (rc == 0) { /* the report only for a picture that was written */
        tmp_path[0] = '\0';
        fprintf(stderr, "nbt-demo: %s (%dx%d): %d panels; tables and rendering %.2f s CPU, of which drawing %.3f s "
                "(%s, CPU figures are for relative comparisons only); g = 0.9 from g-sliced tables differs from the "
                "fixed-phase panel by at most %d/255\n", out, W, H, 2 * NCOL,
                (double)clock() / CLOCKS_PER_SEC - t0, t_render, (const char *)glGetString(GL_RENDERER), dmax);
    }
    free(img);
    free(px);
    egl_headless_close();
    if (rc)
        fprintf(stderr, "nbt-demo: cannot write '%s': %s\n", out, strerror(e));
    return rc;
}
