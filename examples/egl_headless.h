/* examples/egl_headless.h: an offscreen desktop-GL context (EGL surfaceless,
 * Mesa), for the shader tests and the demo. Render into FBOs only. */
#ifndef NBT_EGL_HEADLESS_H
#define NBT_EGL_HEADLESS_H

/* 0 on success; otherwise a one-line reason (naming the missing piece) in err. */
int egl_headless_open(char *err, unsigned long errlen);
void egl_headless_close(void);

/* Compile and link a vertex shader drawing one full-screen triangle with the
 * given fragment shader; 0 on failure with the compiler's log in err. */
unsigned gl_fullscreen_program(const char *frag_src, char *err, unsigned long errlen);
/* An RGBA32F framebuffer of w x h (bound); 0 on failure. */
unsigned gl_float_target(int w, int h);
/* Draw the full-screen triangle with the current program. */
void gl_draw_fullscreen(void);

#endif
