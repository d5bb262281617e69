/* shaders/nbt_gl.c: assembling nbt's GLSL and uploading tables. */
#include <config.h>
#define GL_GLEXT_PROTOTYPES 1
#include <GL/gl.h>
#include <GL/glext.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <nbt/beam.h>
#include "nbt/gl.h"
#include "gl_internal.h"

/* generated from the GLSL modules at build time (nbt_glsl.c) */
extern const char nbt_glsl_nbt_table[], nbt_glsl_nbt_weights[], nbt_glsl_nbt_airlight[], nbt_glsl_nbt_surface[],
    nbt_glsl_nbt_beam[];

char *nbt_gl_shader_source(const nbt_gl_config *c, const char *user_src)
{
    return nbt_gl_shader_source_target(c, NBT_GL_TARGET_GL330, user_src);
}

char *nbt_gl_shader_source_target(const nbt_gl_config *c, int target, const char *user_src)
{
    if (c->h_packs < 0 || c->h_packs > 4 || c->j1_packs < 0 || c->j1_packs > 4 || c->jn_packs < 0 ||
        c->jn_packs > 4 || (c->jn_packs > 0 && c->j1_packs == 0) ||
        ((c->fixed_phase || c->g_sliced) && (c->h_packs > 1 || c->j1_packs > 1 || c->jn_packs > 1)))
        return NULL;
    int w = c->h_packs > c->j1_packs ? c->h_packs : c->j1_packs;
    if (c->jn_packs > w)
        w = c->jn_packs;
    /* the version line and how the modules declare their uniforms: loose
     * uniforms for OpenGL and OpenGL ES (ES also needs default precisions, and
     * highp: the tables' values and axes need 32-bit floats); Vulkan allows
     * only blocks and samplers with explicit set/binding (bindings in gl.h) */
    /* (ES has no default precision for sampler3D: nbt_lookup3 needs one) */
    static const char *const target_head[3] = {
        "#version 330 core\n#define NBT_U uniform\n#define NBT_BLOCK_BEGIN(name, b)\n#define NBT_BLOCK_END\n"
        "#define NBT_SAMPLER(name, b) uniform sampler2D name;\n#define NBT_SAMPLER3D(name, b) uniform sampler3D name;\n",
        "#version 300 es\nprecision highp float;\nprecision highp int;\nprecision highp sampler2D;\n"
        "precision highp sampler3D;\n#define NBT_U uniform\n#define NBT_BLOCK_BEGIN(name, b)\n#define NBT_BLOCK_END\n"
        "#define NBT_SAMPLER(name, b) uniform sampler2D name;\n#define NBT_SAMPLER3D(name, b) uniform sampler3D name;\n",
        "#version 450\n#define NBT_VULKAN 1\n#define NBT_U\n"
        "#define NBT_BLOCK_BEGIN(name, b) layout(std140, set = 0, binding = b) uniform name {\n"
        "#define NBT_BLOCK_END };\n#define NBT_SAMPLER(name, b) layout(set = 0, binding = b) uniform sampler2D name;\n"
        "#define NBT_SAMPLER3D(name, b) layout(set = 0, binding = b) uniform sampler3D name;\n"};
    if (target < NBT_GL_TARGET_GL330 || target > NBT_GL_TARGET_VULKAN)
        return NULL;
    char head[1024];
    int n = snprintf(head, sizeof head, "%s%s%s#define NBT_W_PACKS %d\n#define NBT_GAMMA_EPS %.9g\n",
                     target_head[target], c->fixed_phase ? "#define NBT_FIXED_PHASE 1\n" : "",
                     c->g_sliced ? "#define NBT_G_SLICED 1\n" : "", w > 0 ? w : 1, c->gamma_eps > 0 ? c->gamma_eps : 1e-3);
    if (c->h_packs)
        n += snprintf(head + n, sizeof head - (size_t)n, "#define NBT_H_PACKS %d\n", c->h_packs);
    if (c->j1_packs)
        n += snprintf(head + n, sizeof head - (size_t)n, "#define NBT_J1_PACKS %d\n#define NBT_JN_PACKS %d\n",
                      c->j1_packs, c->jn_packs);
    const char *parts[6] = {head, nbt_glsl_nbt_table, nbt_glsl_nbt_weights,
                            c->h_packs ? nbt_glsl_nbt_airlight : "", c->j1_packs ? nbt_glsl_nbt_surface : "",
                            c->beam ? nbt_glsl_nbt_beam : ""};
    size_t len = (user_src ? strlen(user_src) : 0) + 1;
    for (int i = 0; i < 6; i++)
        len += strlen(parts[i]) + 1;
    char *s = malloc(len);
    if (!s)
        return NULL;
    s[0] = '\0';
    for (int i = 0; i < 6; i++) {
        strcat(s, parts[i]);
        strcat(s, "\n");
    }
    if (user_src)
        strcat(s, user_src);
    return s;
}

void nbt_gl_weights(const double *b, size_t nterms, int packs, float *w)
{
    for (size_t k = 0; k < (size_t)packs * 4; k++)
        w[k] = k < nterms ? (float)((2.0 * (double)k + 1.0) * b[k]) : 0.0f;
}

void nbt_gl_axis(const nbt_axis *a, float v[4], int *map)
{
    v[0] = (float)a->lo;
    v[1] = (float)a->hi;
    v[2] = (float)a->c;
    v[3] = (float)a->n;
    *map = a->map == NBT_AXIS_SQRT ? 1 : a->map == NBT_AXIS_LOG1P ? 2 : a->map == NBT_AXIS_COS ? 3
         : a->map == NBT_AXIS_LOG1P_CBRT ? 4 : a->map == NBT_AXIS_ATANH ? 5 : a->map == NBT_AXIS_ASINH ? 6 : a->map == NBT_AXIS_ENDS ? 7 : 0;
}

void nbt_gl_table_axes(const nbt_table *t, float ax0[4], float ax1[4], int *map0, int *map1)
{
    nbt_gl_axis(&t->axis[0], ax0, map0);
    nbt_gl_axis(&t->axis[1], ax1, map1);
}

void nbt_gl_set_table_axes(unsigned program, const char *prefix, const nbt_table *t)
{
    float a[3][4];
    int m[3];
    char name[128];
    int na = t->axis[2].n > 1 ? 3 : 2;
    for (int i = 0; i < na; i++)
        nbt_gl_axis(&t->axis[i], a[i], &m[i]);
    for (int i = 0; i < na; i++) {
        snprintf(name, sizeof name, "%s_ax%d", prefix, i);
        glUniform4fv(glGetUniformLocation(program, name), 1, a[i]);
        snprintf(name, sizeof name, "%s_map%d", prefix, i);
        glUniform1i(glGetUniformLocation(program, name), m[i]);
    }
    if (na == 3) { /* g-sliced: value form and g interpolation (absent uniforms: location -1, ignored) */
        snprintf(name, sizeof name, "%s_form", prefix);
        glUniform1i(glGetUniformLocation(program, name), t->form == NBT_FORM_LOG_ET ? 1 : 0);
        snprintf(name, sizeof name, "%s_interp2", prefix);
        glUniform1i(glGetUniformLocation(program, name), t->interp2);
    }
}

void nbt_gl_set_table_sub(unsigned program, const char *sampler, const nbt_table *t)
{
    /* term q of the four channels in one vec4 (nbt_sub in nbt_table.glsl); zeros for a plain table */
    float c[NBT_SUB_TERMS][4] = {{0}};
    int sub = t->form == NBT_FORM_SUB && t->axis[2].n <= 1;
    for (size_t ch = 0; sub && ch < t->nch && ch < 4; ch++)
        for (int q = 0; q < NBT_SUB_TERMS; q++)
            c[q][ch] = (float)t->sub_c[ch][q];
    char name[128];
    snprintf(name, sizeof name, "%s_sub", sampler);
    glUniform1i(glGetUniformLocation(program, name), sub ? (t->sub_decay == NBT_SUB_EXP ? 2 : 1) : 0);
    snprintf(name, sizeof name, "%s_sub_w", sampler);
    glUniform1f(glGetUniformLocation(program, name), sub ? (float)t->sub_w : 0.0f);
    snprintf(name, sizeof name, "%s_sub_c", sampler);
    glUniform4fv(glGetUniformLocation(program, name), NBT_SUB_TERMS, &c[0][0]);
}

unsigned nbt_gl_table_target(const nbt_table *t)
{
    return t->axis[2].n > 1 ? GL_TEXTURE_3D : GL_TEXTURE_2D;
}

unsigned nbt_gl_upload_table(const nbt_table *t)
{
    size_t nx = t->axis[0].n, ny = t->axis[1].n, nz = t->axis[2].n, nv = nx * ny * nz;
    GLenum target = nbt_gl_table_target(t);
    /* 2-D tables stay RGBA (the Legendre shaders dot all four channels);
     * a one-channel 3-D table needs only R (its shaders read .r), and so
     * does a tail-form one (channel 1 is libnbt's error map) */
    int red = target == GL_TEXTURE_3D && (t->nch == 1 || t->form == NBT_FORM_TAIL);
    size_t nc = red ? 1 : 4;
    float *px = calloc(nv * nc, sizeof(float));
    if (!px)
        return 0;
    for (size_t i = 0; i < nv; i++)
        for (size_t c = 0; c < t->nch && c < nc; c++)
            px[i * nc + c] = t->data[i * t->nch + c];
    GLuint tex = 0;
    glGenTextures(1, &tex);
    glBindTexture(target, tex);
    glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
    if (target == GL_TEXTURE_3D) {
        GLint fmt = red ? (t->half ? GL_R16F : GL_R32F) : (t->half ? GL_RGBA16F : GL_RGBA32F);
        glTexImage3D(GL_TEXTURE_3D, 0, fmt, (GLsizei)nx, (GLsizei)ny, (GLsizei)nz, 0, red ? GL_RED : GL_RGBA, GL_FLOAT, px);
        glTexParameteri(GL_TEXTURE_3D, GL_TEXTURE_WRAP_R, GL_CLAMP_TO_EDGE);
    } else
        glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA32F, (GLsizei)nx, (GLsizei)ny, 0, GL_RGBA, GL_FLOAT, px);
    glTexParameteri(target, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
    glTexParameteri(target, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    glTexParameteri(target, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    glTexParameteri(target, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
    free(px);
    if (glGetError() != GL_NO_ERROR) {
        glDeleteTextures(1, &tex);
        return 0;
    }
    return tex;
}

unsigned nbt_gl_bind_table(unsigned program, const char *sampler, const nbt_table *t, unsigned unit)
{
    glActiveTexture(GL_TEXTURE0 + unit);
    GLuint tex = nbt_gl_upload_table(t);
    if (tex) {
        glUniform1i(glGetUniformLocation(program, sampler), (GLint)unit);
        nbt_gl_set_table_sub(program, sampler, t);
    }
    return tex;
}

int nbt_gl_set_beam_fit(unsigned program, const nbt_beam_fit *f, int infinite)
{
    int g = infinite ? 1 : 0;
    if (!f || !f->have[g])
        return 1;
    float c[NBT_BEAM_FIT_PARTS * NBT_BEAM_FIT_TERMS], lo[3], hi[3];
    for (int i = 0; i < NBT_BEAM_FIT_PARTS; i++)
        for (int k = 0; k < NBT_BEAM_FIT_TERMS; k++)
            c[i * NBT_BEAM_FIT_TERMS + k] = (float)f->c[g][i][k];
    for (int i = 0; i < 3; i++) {
        lo[i] = (float)f->range[i][0];
        hi[i] = (float)f->range[i][1];
    }
    glUniform4fv(glGetUniformLocation(program, "nbt_beam_fit_c"), NBT_BEAM_FIT_PARTS * NBT_BEAM_FIT_TERMS / 4, c);
    glUniform3fv(glGetUniformLocation(program, "nbt_beam_fit_lo"), 1, lo);
    glUniform3fv(glGetUniformLocation(program, "nbt_beam_fit_hi"), 1, hi);
    return 0;
}

GLuint nbt__gl_compute_program(const char *src, const char *what)
{
    GLuint sh = glCreateShader(GL_COMPUTE_SHADER);
    glShaderSource(sh, 1, &src, NULL);
    glCompileShader(sh);
    GLint ok = 0;
    glGetShaderiv(sh, GL_COMPILE_STATUS, &ok);
    char log[1024], msg[1200];
    if (!ok) {
        glGetShaderInfoLog(sh, sizeof log, NULL, log);
        glDeleteShader(sh);
        snprintf(msg, sizeof msg, "%s does not compile: %s", what, log);
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
        snprintf(msg, sizeof msg, "%s does not link: %s", what, log);
        nbt__fail(NBT_EIO, msg);
        return 0;
    }
    return p;
}
