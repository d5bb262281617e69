/* shaders/nbt_gl_mc.c: host side of the GLSL compute photon counter (nbt/gl_mc.h). */
#include <config.h>
#define GL_GLEXT_PROTOTYPES 1
#include <GL/gl.h>
#include <GL/glext.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include "nbt/gl_mc.h"
#include "gl_internal.h"

/* from libnbt (not in its public headers) */
int nbt__phase_sample_param(const nbt_phase *p, nbt_phase_kind *kind, double *param);
extern const char nbt_glsl_nbt_mc[];

/* photons per invocation: each invocation loops over this many, so that
 * SIMD lanes start new photons instead of idling (llvmpipe: 1.5x faster
 * than one photon per invocation); a batch of 1.5e7 photons (1e9 in all)
 * still has 2.4e5 invocations to fill a large GPU */
#define MC_PER_INVOCATION 64

static GLuint build(unsigned wg)
{
    size_t n = strlen(nbt_glsl_nbt_mc) + 64;
    char *src = malloc(n);
    if (!src) {
        nbt__fail(NBT_ENOMEM, "gl_mc: out of memory");
        return 0;
    }
    snprintf(src, n, "#version 430\n#define NBT_MC_WG %u\n%s", wg, nbt_glsl_nbt_mc);
    GLuint p = nbt__gl_compute_program(src, "gl_mc: the compute shader (OpenGL 4.3 needed)");
    free(src);
    return p;
}

nbt_status nbt_gl_mc_run(const nbt_mc_config *cf, unsigned wg, uint64_t max_dispatch, nbt_mc_result **out)
{
    *out = NULL;
    if (!cf || !cf->phase)
        return nbt__fail(NBT_EINVAL, "gl_mc: no configuration or phase function");
    nbt_phase_kind kind;
    double param;
    if (nbt_phase_get_kind(cf->phase) == NBT_PHASE_ISO) {
        kind = NBT_PHASE_HG;
        param = 0;
    } else if (!nbt__phase_sample_param(cf->phase, &kind, &param))
        return nbt__fail(NBT_EINVAL, "gl_mc: the GPU counter samples HG, isotropic and single-Gaussian phase functions only");
    if (cf->nlayers > 0 || cf->rho_fn)
        return nbt__fail(NBT_EINVAL, "gl_mc: the GPU counter needs a homogeneous medium (no layers, no density callback)");
    if (cf->estimator != NBT_MC_ANALOG)
        return nbt__fail(NBT_EINVAL, "gl_mc: the GPU counter is analog only");
    if (wg > 1024)
        return nbt__fail(NBT_EDOM, "gl_mc: work-group size must be 1..1024 (0: 64)");
    /* the rest (albedo, planes, photons, ...) as nbt_mc_run checks it: a
     * zero-photon part runs nothing but validates */
    double dummy = 0;
    nbt_status st = nbt_mc_run_part(cf, 0, 0, &dummy);
    if (st != NBT_OK)
        return st;
    if (wg == 0)
        wg = 64;
    if (max_dispatch == 0)
        max_dispatch = (uint64_t)1 << 20;
    struct timespec t0, t1;
    clock_gettime(CLOCK_MONOTONIC, &t0);
    size_t np = cf->nplanes, nb = cf->r_bins, stride = np * (nb + 2) + 3, len = nbt_mc_tally_len(cf);
    GLuint prog = build(wg);
    if (!prog)
        return NBT_EIO; /* the reason is set */
    double last = np ? cf->z_planes[np - 1] : 0;
    double zc = cf->z_cut > 0 ? cf->z_cut : 2.0 * last + 20.0 / cf->sigma_t;
    double top = cf->slab > 0 ? cf->slab : zc, bottom = cf->infinite ? -zc : 0.0;
    float *zpf = malloc((np ? np : 1) * sizeof(float));
    uint32_t *tb = calloc(2 * len, sizeof(uint32_t));
    double *tally = malloc(len * sizeof(double));
    if (!zpf || !tb || !tally) {
        free(zpf);
        free(tb);
        free(tally);
        glDeleteProgram(prog);
        return nbt__fail(NBT_ENOMEM, "gl_mc: out of memory");
    }
    for (size_t j = 0; j < np; j++)
        zpf[j] = (float)cf->z_planes[j];
    if (!np)
        zpf[0] = INFINITY;
    GLuint buf[2];
    glGenBuffers(2, buf);
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, buf[0]);
    glBufferData(GL_SHADER_STORAGE_BUFFER, (GLsizeiptr)(2 * len * sizeof(uint32_t)), tb, GL_DYNAMIC_COPY);
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, buf[1]);
    glBufferData(GL_SHADER_STORAGE_BUFFER, (GLsizeiptr)((np ? np : 1) * sizeof(float)), zpf, GL_STATIC_DRAW);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, buf[0]);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, buf[1]);
    glUseProgram(prog);
    glUniform2ui(glGetUniformLocation(prog, "u_seed"), (GLuint)cf->seed, (GLuint)(cf->seed >> 32));
    glUniform1f(glGetUniformLocation(prog, "u_sigma_t"), (float)cf->sigma_t);
    glUniform1f(glGetUniformLocation(prog, "u_albedo"), (float)cf->albedo);
    glUniform1f(glGetUniformLocation(prog, "u_bottom"), (float)bottom);
    glUniform1f(glGetUniformLocation(prog, "u_top"), (float)top);
    glUniform1f(glGetUniformLocation(prog, "u_param"), (float)param);
    glUniform1f(glGetUniformLocation(prog, "u_rscale"), (float)(np ? cf->r_max_scale : 1.0));
    glUniform1i(glGetUniformLocation(prog, "u_phase"), kind == NBT_PHASE_GAUSS);
    glUniform1i(glGetUniformLocation(prog, "u_slab"), cf->slab > 0);
    glUniform1i(glGetUniformLocation(prog, "u_nplanes"), (GLint)np);
    glUniform1i(glGetUniformLocation(prog, "u_nbins"), (GLint)nb);
    glUniform1ui(glGetUniformLocation(prog, "u_order_max"), cf->order_max);
    GLint lfirst = glGetUniformLocation(prog, "u_first"), lcount = glGetUniformLocation(prog, "u_count"),
          lbase = glGetUniformLocation(prog, "u_base"), lthreads = glGetUniformLocation(prog, "u_threads");
    /* batch by batch (the tallies of batch b live at b * stride), each in
     * dispatches of at most max_dispatch photons */
    for (size_t b = 0; b < NBT_MC_BATCHES; b++) {
        uint64_t p0 = cf->photons * b / NBT_MC_BATCHES, p1 = cf->photons * (b + 1) / NBT_MC_BATCHES;
        glUniform1ui(lbase, (GLuint)(b * stride));
        for (uint64_t p = p0; p < p1;) {
            uint64_t n = p1 - p < max_dispatch ? p1 - p : max_dispatch;
            uint64_t inv = (n + MC_PER_INVOCATION - 1) / MC_PER_INVOCATION, groups = (inv + wg - 1) / wg;
            glUniform2ui(lfirst, (GLuint)p, (GLuint)(p >> 32));
            glUniform1ui(lcount, (GLuint)n);
            glUniform1ui(lthreads, (GLuint)(groups * wg));
            glDispatchCompute((GLuint)groups, 1, 1);
            p += n;
        }
    }
    glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, buf[0]);
    glGetBufferSubData(GL_SHADER_STORAGE_BUFFER, 0, (GLsizeiptr)(2 * len * sizeof(uint32_t)), tb);
    GLenum e = glGetError();
    glDeleteBuffers(2, buf);
    glUseProgram(0);
    glDeleteProgram(prog);
    if (e != GL_NO_ERROR)
        st = nbt__fail(NBT_EIO, "gl_mc: a GL call failed (OpenGL 4.3 compute and storage buffers needed)");
    for (size_t i = 0; st == NBT_OK && i < len; i++) {
        double v = ldexp((double)tb[2 * i + 1], 32) + (double)tb[2 * i];
        size_t k = i % stride;
        tally[i] = k < np * (nb + 2) && k % (nb + 2) == nb + 1 ? ldexp(v, -20) : v; /* M2 slots are fixed-point */
    }
    if (st == NBT_OK)
        st = nbt_mc_finish(cf, tally, out);
    free(zpf);
    free(tb);
    free(tally);
    if (st == NBT_OK) {
        clock_gettime(CLOCK_MONOTONIC, &t1);
        (*out)->seconds = (double)(t1.tv_sec - t0.tv_sec) + 1e-9 * (double)(t1.tv_nsec - t0.tv_nsec);
    }
    return st;
}
