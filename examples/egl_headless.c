/* examples/egl_headless.c: EGL surfaceless + desktop GL 4.5 core (Mesa's
 * llvmpipe works this way on a machine without a GPU). */
#ifdef HAVE_CONFIG_H
#include <config.h>
#endif
#include <stdio.h>
#include <string.h>
#define GL_GLEXT_PROTOTYPES 1
#include <EGL/egl.h>
#include <EGL/eglext.h>
#include <GL/gl.h>
#include <GL/glext.h>
#include "egl_headless.h"

static EGLDisplay dpy = EGL_NO_DISPLAY;
static EGLContext ctx = EGL_NO_CONTEXT;
static GLuint vao;

int egl_headless_open(char *err, unsigned long errlen)
{
    PFNEGLGETPLATFORMDISPLAYEXTPROC get_display =
        (PFNEGLGETPLATFORMDISPLAYEXTPROC)eglGetProcAddress("eglGetPlatformDisplayEXT");
    if (get_display)
        dpy = get_display(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, NULL);
    if (dpy == EGL_NO_DISPLAY) {
        snprintf(err, errlen, "no EGL surfaceless display: install libegl-mesa0 and libgl1-mesa-dri (Mesa)");
        return 1;
    }
    EGLint major, minor;
    if (!eglInitialize(dpy, &major, &minor)) {
        snprintf(err, errlen, "eglInitialize failed: install libegl-mesa0 and libgl1-mesa-dri (Mesa)");
        return 1;
    }
    if (!eglBindAPI(EGL_OPENGL_API)) {
        snprintf(err, errlen, "EGL cannot bind desktop OpenGL: install libopengl0 / libgl1-mesa-dri");
        return 1;
    }
    static const EGLint cfg_attr[] = {EGL_SURFACE_TYPE, EGL_PBUFFER_BIT, EGL_RENDERABLE_TYPE, EGL_OPENGL_BIT, EGL_NONE};
    EGLConfig cfg;
    EGLint n = 0;
    eglChooseConfig(dpy, cfg_attr, &cfg, 1, &n);
    static const EGLint ctx_attr[] = {EGL_CONTEXT_MAJOR_VERSION, 3, EGL_CONTEXT_MINOR_VERSION, 3,
                                      EGL_CONTEXT_OPENGL_PROFILE_MASK, EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT, EGL_NONE};
    ctx = eglCreateContext(dpy, n > 0 ? cfg : EGL_NO_CONFIG_KHR, EGL_NO_CONTEXT, ctx_attr);
    if (ctx == EGL_NO_CONTEXT || !eglMakeCurrent(dpy, EGL_NO_SURFACE, EGL_NO_SURFACE, ctx)) {
        snprintf(err, errlen, "no OpenGL 3.3 core context: install libgl1-mesa-dri (Mesa's llvmpipe)");
        return 1;
    }
    glGenVertexArrays(1, &vao);
    glBindVertexArray(vao);
    return 0;
}

void egl_headless_close(void)
{
    if (dpy != EGL_NO_DISPLAY) {
        eglMakeCurrent(dpy, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
        if (ctx != EGL_NO_CONTEXT)
            eglDestroyContext(dpy, ctx);
        eglTerminate(dpy);
    }
    dpy = EGL_NO_DISPLAY;
    ctx = EGL_NO_CONTEXT;
}

static GLuint compile(GLenum type, const char *src, char *err, unsigned long errlen)
{
    GLuint s = glCreateShader(type);
    glShaderSource(s, 1, &src, NULL);
    glCompileShader(s);
    GLint ok = 0;
    glGetShaderiv(s, GL_COMPILE_STATUS, &ok);
    if (!ok) {
        glGetShaderInfoLog(s, (GLsizei)errlen, NULL, err);
        glDeleteShader(s);
        return 0;
    }
    return s;
}

unsigned gl_fullscreen_program(const char *frag_src, char *err, unsigned long errlen)
{
    static const char *vs = "#version 330 core\n"
                            "void main() { vec2 p = vec2((gl_VertexID << 1) & 2, gl_VertexID & 2);\n"
                            "  gl_Position = vec4(p * 2.0 - 1.0, 0.0, 1.0); }\n";
    GLuint v = compile(GL_VERTEX_SHADER, vs, err, errlen), f = v ? compile(GL_FRAGMENT_SHADER, frag_src, err, errlen) : 0;
    if (!v || !f)
        return 0;
    GLuint p = glCreateProgram();
    glAttachShader(p, v);
    glAttachShader(p, f);
    glLinkProgram(p);
    glDeleteShader(v);
    glDeleteShader(f);
    GLint ok = 0;
    glGetProgramiv(p, GL_LINK_STATUS, &ok);
    if (!ok) {
        glGetProgramInfoLog(p, (GLsizei)errlen, NULL, err);
        glDeleteProgram(p);
        return 0;
    }
    return p;
}

unsigned gl_float_target(int w, int h)
{
    GLuint fbo, tex;
    glGenTextures(1, &tex);
    glBindTexture(GL_TEXTURE_2D, tex);
    glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA32F, w, h, 0, GL_RGBA, GL_FLOAT, NULL);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    glGenFramebuffers(1, &fbo);
    glBindFramebuffer(GL_FRAMEBUFFER, fbo);
    glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, tex, 0);
    if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
        return 0;
    glViewport(0, 0, w, h);
    return fbo;
}

void gl_draw_fullscreen(void)
{
    glDrawArrays(GL_TRIANGLES, 0, 3);
}
