/* shaders/nbt_gl_scatter.c: screen-space scattering by GLSL compute shaders
 * (nbt/gl_scatter.h): programs, textures, dispatches, read-back. */
#include <config.h>
#define GL_GLEXT_PROTOTYPES 1
#include <GL/gl.h>
#include <GL/glext.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <nbt/screen.h>
#include "nbt/gl_scatter.h"

/* libnbt's error reporting (libnbt/internal.h): the reason goes to the
 * caller's handler (nbt_set_error_handler) */
nbt_status nbt__fail(nbt_status s, const char *reason);

/* generated from the GLSL modules at build time (nbt_glsl.c) */
extern const char nbt_glsl_nbt_beam[], nbt_glsl_nbt_scatter_common[], nbt_glsl_nbt_scatter_near[],
    nbt_glsl_nbt_scatter_shinya[], nbt_glsl_nbt_scatter_literal[], nbt_glsl_nbt_scatter_pyr0[],
    nbt_glsl_nbt_scatter_down[], nbt_glsl_nbt_scatter_naive[], nbt_glsl_nbt_scatter_elek[];

enum { P_NEAR, P_SHINYA, P_LITERAL, P_PYR0, P_DOWN, P_NAIVE, P_ELEK, NPASS };

static const struct {
    const char *name;
    const char *src;
} PASSES[NPASS] = {
    {"near", nbt_glsl_nbt_scatter_near},       {"shinya", nbt_glsl_nbt_scatter_shinya},
    {"literal", nbt_glsl_nbt_scatter_literal}, {"pyr0", nbt_glsl_nbt_scatter_pyr0},
    {"down", nbt_glsl_nbt_scatter_down},       {"naive", nbt_glsl_nbt_scatter_naive},
    {"elek", nbt_glsl_nbt_scatter_elek},
};

static const char *const MNAMES[NBT_GLS_NMETHODS] = {"shinya", "shinya-literal", "naive", "elek"};

struct nbt_gls {
    size_t w, h, pw, ph; /* image and padded (pyramid) size */
    GLuint prog[NPASS];
    GLuint tc, tp, tn0, tn1, tlut, tout, tpyr, twb;
    GLuint stamp[2]; /* GL_TIMESTAMP before and after the passes */
    float *buf; /* staging, w*h*4 */
};

const char *nbt_gls_method_name(nbt_gls_method m)
{
    return (unsigned)m < NBT_GLS_NMETHODS ? MNAMES[m] : "?";
}

nbt_status nbt_gls_method_parse(const char *name, nbt_gls_method *m)
{
    for (unsigned i = 0; i < NBT_GLS_NMETHODS; i++)
        if (!strcmp(name, MNAMES[i])) {
            *m = (nbt_gls_method)i;
            return NBT_OK;
        }
    return NBT_EINVAL;
}

unsigned nbt_gls_npasses(void)
{
    return NPASS;
}

const char *nbt_gls_pass_name(unsigned i)
{
    return i < NPASS ? PASSES[i].name : NULL;
}

char *nbt_gls_pass_source(unsigned i)
{
    if (i >= NPASS)
        return NULL;
    char head[512];
    int n = snprintf(head, sizeof head,
                     "#version 430 core\n#define NBT_SC_LUT_LO %d\n#define NBT_SC_LUT_PER %d\n#define NBT_SC_LUT_N %d\n"
                     "#define NBT_SC_NAIVE_C %.9g\n#define NBT_SC_ELEK_C %.9g\n",
                     NBT_GLS_LUT_LO, NBT_GLS_LUT_PER, NBT_GLS_LUT_N, NBT_GLS_NAIVE_C, NBT_GLS_ELEK_C);
    const char *parts[4] = {head, nbt_glsl_nbt_beam, nbt_glsl_nbt_scatter_common, PASSES[i].src};
    size_t len = 1;
    for (int k = 0; k < 4; k++)
        len += strlen(parts[k]) + 1;
    char *s = malloc(len);
    if (!s || n < 0)
        return free(s), NULL;
    s[0] = '\0';
    for (int k = 0; k < 4; k++) {
        strcat(s, parts[k]);
        strcat(s, "\n");
    }
    return s;
}

void nbt_gls_near_table(float *lut)
{
    static const long off[6][2] = {{0, 0}, {1, 0}, {1, 1}, {2, 0}, {2, 1}, {2, 2}};
    for (int i = 0; i < NBT_GLS_LUT_N; i++) {
        double b = exp2(NBT_GLS_LUT_LO + (double)i / NBT_GLS_LUT_PER);
        for (int k = 0; k < 6; k++)
            lut[8 * i + k] = (float)nbt_screen_atom_pixel(NBT_ATOM_ERFC, b, off[k][0], off[k][1]);
        lut[8 * i + 6] = lut[8 * i + 7] = 0.0f;
    }
}

static GLuint compile_pass(unsigned i)
{
    char *src = nbt_gls_pass_source(i);
    if (!src) {
        nbt__fail(NBT_ENOMEM, "gl_scatter: out of memory");
        return 0;
    }
    GLuint sh = glCreateShader(GL_COMPUTE_SHADER);
    const char *s = src;
    glShaderSource(sh, 1, &s, NULL);
    glCompileShader(sh);
    free(src);
    GLint ok = 0;
    glGetShaderiv(sh, GL_COMPILE_STATUS, &ok);
    char log[1024], msg[1200];
    if (!ok) {
        glGetShaderInfoLog(sh, sizeof log, NULL, log);
        glDeleteShader(sh);
        snprintf(msg, sizeof msg, "gl_scatter: pass %s does not compile: %s", PASSES[i].name, log);
        nbt__fail(NBT_EIO, msg);
        return 0;
    }
    GLuint p = glCreateProgram();
    glAttachShader(p, sh);
    glLinkProgram(p);
    glDeleteShader(sh);
    glGetProgramiv(p, GL_LINK_STATUS, &ok);
    if (!ok) {
        glGetProgramInfoLog(p, sizeof log, NULL, log);
        glDeleteProgram(p);
        snprintf(msg, sizeof msg, "gl_scatter: pass %s does not link: %s", PASSES[i].name, log);
        nbt__fail(NBT_EIO, msg);
        return 0;
    }
    return p;
}

static GLuint make_tex(GLsizei levels, GLenum fmt, size_t w, size_t h, int pyramid)
{
    GLuint t = 0;
    glGenTextures(1, &t);
    glBindTexture(GL_TEXTURE_2D, t);
    glTexStorage2D(GL_TEXTURE_2D, levels, fmt, (GLsizei)w, (GLsizei)h);
    if (pyramid) {
        static const float zero[4] = {0, 0, 0, 0};
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR_MIPMAP_NEAREST);
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_BORDER);
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_BORDER);
        glTexParameterfv(GL_TEXTURE_2D, GL_TEXTURE_BORDER_COLOR, zero);
    } else {
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
    }
    return t;
}

void nbt_gls_free(nbt_gls *g)
{
    if (!g)
        return;
    for (int i = 0; i < NPASS; i++)
        if (g->prog[i])
            glDeleteProgram(g->prog[i]);
    GLuint t[8] = {g->tc, g->tp, g->tn0, g->tn1, g->tlut, g->tout, g->tpyr, g->twb};
    for (int i = 0; i < 8; i++)
        if (t[i])
            glDeleteTextures(1, &t[i]);
    if (g->stamp[0])
        glDeleteQueries(2, g->stamp);
    free(g->buf);
    free(g);
}

nbt_gls *nbt_gls_alloc(size_t w, size_t h)
{
    GLint major = 0, minor = 0;
    glGetIntegerv(GL_MAJOR_VERSION, &major);
    glGetIntegerv(GL_MINOR_VERSION, &minor);
    if (major * 10 + minor < 43) {
        nbt__fail(NBT_EINVAL, "gl_scatter: needs a current OpenGL >= 4.3 context (compute shaders)");
        return NULL;
    }
    GLint maxsz = 0;
    glGetIntegerv(GL_MAX_TEXTURE_SIZE, &maxsz);
    size_t pad = (size_t)1 << NBT_GLS_K;
    if (w == 0 || h == 0 || w > (size_t)maxsz - pad || h > (size_t)maxsz - pad) {
        nbt__fail(NBT_EDOM, "gl_scatter: image size outside 1 .. GL_MAX_TEXTURE_SIZE - 64");
        return NULL;
    }
    nbt_gls *g = calloc(1, sizeof *g);
    if (!g || !(g->buf = malloc(w * h * 4 * sizeof *g->buf))) {
        free(g);
        nbt__fail(NBT_ENOMEM, "gl_scatter: out of memory");
        return NULL;
    }
    g->w = w;
    g->h = h;
    g->pw = (w + pad - 1) / pad * pad;
    g->ph = (h + pad - 1) / pad * pad;
    while (glGetError() != GL_NO_ERROR)
        ;
    for (unsigned i = 0; i < NPASS; i++)
        if (!(g->prog[i] = compile_pass(i))) {
            nbt_gls_free(g);
            return NULL;
        }
    glActiveTexture(GL_TEXTURE0);
    g->tc = make_tex(1, GL_RGBA32F, w, h, 0);
    g->tp = make_tex(1, GL_RGBA32F, w, h, 0);
    g->tn0 = make_tex(1, GL_RGBA32F, w, h, 0);
    g->tn1 = make_tex(1, GL_RGBA32F, w, h, 0);
    g->tout = make_tex(1, GL_RGBA32F, w, h, 0);
    g->tlut = make_tex(1, GL_RGBA32F, NBT_GLS_LUT_N, 2, 0);
    g->tpyr = make_tex(NBT_GLS_K + 1, GL_RGBA32F, g->pw, g->ph, 1);
    g->twb = make_tex(NBT_GLS_K + 1, GL_RG32F, g->pw, g->ph, 1);
    float *lut = malloc(NBT_GLS_LUT_N * 8 * sizeof *lut);
    if (!lut) {
        nbt_gls_free(g);
        nbt__fail(NBT_ENOMEM, "gl_scatter: out of memory");
        return NULL;
    }
    nbt_gls_near_table(lut);
    /* rows: texel (i, 0) = entries 0..3 of i, (i, 1) = entries 4..7 */
    float *rows = malloc(NBT_GLS_LUT_N * 8 * sizeof *rows);
    if (rows) {
        for (int i = 0; i < NBT_GLS_LUT_N; i++)
            for (int k = 0; k < 4; k++) {
                rows[4 * i + k] = lut[8 * i + k];
                rows[4 * (NBT_GLS_LUT_N + i) + k] = lut[8 * i + 4 + k];
            }
        glBindTexture(GL_TEXTURE_2D, g->tlut);
        glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
        glTexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, NBT_GLS_LUT_N, 2, GL_RGBA, GL_FLOAT, rows);
    }
    free(lut);
    glGenQueries(2, g->stamp);
    if (!rows || glGetError() != GL_NO_ERROR) {
        free(rows);
        nbt_gls_free(g);
        nbt__fail(rows ? NBT_EIO : NBT_ENOMEM, "gl_scatter: creating the textures failed");
        return NULL;
    }
    free(rows);
    return g;
}

static int is_sky(float D)
{
    return !(D < (float)NBT_SCREEN_SKY);
}

static nbt_status check_input(nbt_gls_method m, const nbt_gls_input *in)
{
    if ((unsigned)m >= NBT_GLS_NMETHODS)
        return nbt__fail(NBT_EINVAL, "gl_scatter: unknown method");
    if (!in->rgb || !in->D || !in->M0 || !in->beta_px)
        return nbt__fail(NBT_EINVAL, "gl_scatter: rgb, D, M0 and beta_px are required");
    if (m == NBT_GLS_SHINYA_LITERAL && !(in->dtheta > 0 && isfinite(in->dtheta)))
        return nbt__fail(NBT_EDOM, "gl_scatter: dtheta must be finite and > 0");
    if (m == NBT_GLS_SHINYA && !(in->cut > 0 && isfinite(in->cut)))
        return nbt__fail(NBT_EDOM, "gl_scatter: cut must be finite and > 0");
    if (m == NBT_GLS_ELEK && !(in->eps >= 0 && isfinite(in->eps)))
        return nbt__fail(NBT_EDOM, "gl_scatter: eps must be finite and >= 0");
    for (size_t i = 0; i < in->w * in->h; i++) {
        if (!(in->D[i] >= 0))
            return nbt__fail(NBT_EDOM, "gl_scatter: a depth is negative or NaN");
        if (!(in->M0[i] >= 0 && isfinite(in->M0[i])) || !(in->beta_px[i] >= 0 && isfinite(in->beta_px[i])) ||
            (in->sigma_px && !(in->sigma_px[i] >= 0 && isfinite(in->sigma_px[i]))))
            return nbt__fail(NBT_EDOM, "gl_scatter: M0, beta_px and sigma_px must be finite and >= 0");
        for (int c = 0; c < 3; c++)
            if (!isfinite(in->rgb[3 * i + c]))
                return nbt__fail(NBT_EDOM, "gl_scatter: a colour is not finite");
    }
    return NBT_OK;
}

long nbt_gls_window(nbt_gls_method m, const nbt_gls_input *in)
{
    double r = 0, cap = (double)(in->w > in->h ? in->w : in->h);
    for (size_t i = 0; i < in->w * in->h; i++) {
        if (!(in->M0[i] > 0) || is_sky(in->D[i]))
            continue;
        double b = in->beta_px[i];
        if (m == NBT_GLS_SHINYA)
            r = fmax(r, ceil(in->cut * b));
        else if (m == NBT_GLS_SHINYA_LITERAL) /* half-size beta[] / (D dtheta) = 2 beta_px^2 D dtheta */
            r = fmax(r, floor(2.0 * b * b * in->D[i] * in->dtheta) + 1);
    }
    if (m == NBT_GLS_SHINYA)
        r = fmax(r, 2); /* the near taps */
    else if (m != NBT_GLS_SHINYA_LITERAL)
        return 0;
    return (long)fmin(r, cap);
}

static void bind_tex(GLuint unit, GLuint tex)
{
    glActiveTexture(GL_TEXTURE0 + unit);
    glBindTexture(GL_TEXTURE_2D, tex);
}

static void dispatch(size_t w, size_t h)
{
    glDispatchCompute((GLuint)((w + 7) / 8), (GLuint)((h + 7) / 8), 1);
    glMemoryBarrier(GL_SHADER_IMAGE_ACCESS_BARRIER_BIT | GL_TEXTURE_FETCH_BARRIER_BIT);
}

static void use(const nbt_gls *g, int pass)
{
    GLuint p = g->prog[pass];
    glUseProgram(p);
    glUniform2i(glGetUniformLocation(p, "nbt_sc_size"), (GLint)g->w, (GLint)g->h);
    glUniform2i(glGetUniformLocation(p, "nbt_sc_psize"), (GLint)g->pw, (GLint)g->ph);
    glUniform1i(glGetUniformLocation(p, "nbt_sc_K"), NBT_GLS_K);
}

/* the pyramid: level 0, then K levels (masked for Elek) */
static void build_pyramid(const nbt_gls *g, int masked, float eps)
{
    use(g, P_PYR0);
    glBindImageTexture(0, g->tpyr, 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
    glBindImageTexture(1, g->twb, 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RG32F);
    dispatch(g->pw, g->ph);
    use(g, P_DOWN);
    GLuint p = g->prog[P_DOWN];
    glUniform1i(glGetUniformLocation(p, "nbt_sc_masked"), masked);
    glUniform1f(glGetUniformLocation(p, "nbt_sc_eps"), eps);
    for (int k = 1; k <= NBT_GLS_K; k++) {
        size_t sw = g->pw >> (k - 1), sh = g->ph >> (k - 1);
        glUniform2i(glGetUniformLocation(p, "nbt_sc_srcsize"), (GLint)sw, (GLint)sh);
        glUniform2i(glGetUniformLocation(p, "nbt_sc_dstsize"), (GLint)(sw / 2), (GLint)(sh / 2));
        glUniform1f(glGetUniformLocation(p, "nbt_sc_T"), (float)(NBT_GLS_ELEK_C * ldexp(1.0, k - 1)));
        glBindImageTexture(0, g->tpyr, k - 1, GL_FALSE, 0, GL_READ_ONLY, GL_RGBA32F);
        glBindImageTexture(1, g->tpyr, k, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
        glBindImageTexture(2, g->twb, k - 1, GL_FALSE, 0, GL_READ_ONLY, GL_RG32F);
        glBindImageTexture(3, g->twb, k, GL_FALSE, 0, GL_WRITE_ONLY, GL_RG32F);
        dispatch(sw / 2, sh / 2);
    }
}

nbt_status nbt_gls_exec(nbt_gls *g, nbt_gls_method m, const nbt_gls_input *in, float *S, double *gpu_ms)
{
    if (!g || in->w != g->w || in->h != g->h)
        return nbt__fail(NBT_EINVAL, "gl_scatter: the input's size is not the context's");
    nbt_status st = check_input(m, in);
    if (st != NBT_OK)
        return st;
    size_t w = g->w, h = g->h, np = w * h;
    while (glGetError() != GL_NO_ERROR)
        ;
    /* upload: (r, g, b, depth key) and (M0, beta_px, sigma_px, 0) */
    glActiveTexture(GL_TEXTURE0);
    glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
    for (size_t i = 0; i < np; i++) {
        for (int c = 0; c < 3; c++)
            g->buf[4 * i + c] = in->rgb[3 * i + c];
        g->buf[4 * i + 3] = is_sky(in->D[i]) ? 1e30f : in->D[i];
    }
    glBindTexture(GL_TEXTURE_2D, g->tc);
    glTexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, (GLsizei)w, (GLsizei)h, GL_RGBA, GL_FLOAT, g->buf);
    for (size_t i = 0; i < np; i++) {
        g->buf[4 * i] = in->M0[i];
        g->buf[4 * i + 1] = in->beta_px[i];
        g->buf[4 * i + 2] = in->sigma_px ? in->sigma_px[i] : (float)(in->beta_px[i] / sqrt(3.0));
        g->buf[4 * i + 3] = 0.0f;
    }
    glBindTexture(GL_TEXTURE_2D, g->tp);
    glTexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, (GLsizei)w, (GLsizei)h, GL_RGBA, GL_FLOAT, g->buf);
    bind_tex(0, g->tc);
    bind_tex(1, g->tp);
    bind_tex(2, g->tlut);
    long R = nbt_gls_window(m, in);

    /* timestamps, not GL_TIME_ELAPSED: llvmpipe reports 1 ns elapsed for
     * compute-only work, while its timestamps (and a GPU's) bracket it */
    glQueryCounter(g->stamp[0], GL_TIMESTAMP);
    switch (m) {
    case NBT_GLS_SHINYA:
        use(g, P_NEAR);
        glBindImageTexture(0, g->tn0, 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
        glBindImageTexture(1, g->tn1, 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
        dispatch(w, h);
        use(g, P_SHINYA);
        bind_tex(3, g->tn0);
        bind_tex(4, g->tn1);
        glUniform1i(glGetUniformLocation(g->prog[P_SHINYA], "nbt_sc_R"), (GLint)R);
        glUniform1f(glGetUniformLocation(g->prog[P_SHINYA], "nbt_sc_cut"), (float)in->cut);
        glBindImageTexture(0, g->tout, 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
        dispatch(w, h);
        break;
    case NBT_GLS_SHINYA_LITERAL:
        use(g, P_LITERAL);
        glUniform1i(glGetUniformLocation(g->prog[P_LITERAL], "nbt_sc_R"), (GLint)R);
        glUniform1f(glGetUniformLocation(g->prog[P_LITERAL], "nbt_sc_dtheta"), (float)in->dtheta);
        glBindImageTexture(0, g->tout, 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
        dispatch(w, h);
        break;
    case NBT_GLS_NAIVE:
    case NBT_GLS_ELEK: {
        int elek = m == NBT_GLS_ELEK;
        build_pyramid(g, elek, (float)in->eps);
        int pass = elek ? P_ELEK : P_NAIVE;
        use(g, pass);
        bind_tex(2, g->tpyr);
        bind_tex(3, g->twb);
        glBindImageTexture(0, g->tout, 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
        dispatch(w, h);
        break;
    }
    }
    glQueryCounter(g->stamp[1], GL_TIMESTAMP);
    glMemoryBarrier(GL_TEXTURE_UPDATE_BARRIER_BIT);
    glActiveTexture(GL_TEXTURE0);
    glBindTexture(GL_TEXTURE_2D, g->tout);
    glPixelStorei(GL_PACK_ALIGNMENT, 4);
    glGetTexImage(GL_TEXTURE_2D, 0, GL_RGBA, GL_FLOAT, g->buf);
    for (size_t i = 0; i < np; i++)
        for (int c = 0; c < 3; c++)
            S[3 * i + c] = g->buf[4 * i + c];
    if (gpu_ms) {
        GLuint64 t0 = 0, t1 = 0;
        glGetQueryObjectui64v(g->stamp[0], GL_QUERY_RESULT, &t0);
        glGetQueryObjectui64v(g->stamp[1], GL_QUERY_RESULT, &t1);
        *gpu_ms = t1 > t0 ? (double)(t1 - t0) * 1e-6 : 0.0;
    }
    glUseProgram(0);
    if (glGetError() != GL_NO_ERROR)
        return nbt__fail(NBT_EIO, "gl_scatter: a GL call failed");
    return NBT_OK;
}

nbt_status nbt_gls_run(nbt_gls_method m, const nbt_gls_input *in, float *S, double *gpu_ms)
{
    nbt_gls *g = nbt_gls_alloc(in->w, in->h);
    if (!g)
        return NBT_EINVAL;
    nbt_status st = nbt_gls_exec(g, m, in, S, gpu_ms);
    nbt_gls_free(g);
    return st;
}
