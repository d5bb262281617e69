/* shaders/gl_internal.h: what libnbt-gl's sources share and do not export. */
#ifndef NBT_GL_INTERNAL_H
#define NBT_GL_INTERNAL_H

#include <GL/gl.h>
#include <nbt/error.h>

/* from libnbt (not in its public headers) */
nbt_status nbt__fail(nbt_status s, const char *reason);
/* libnbt's Lawson-Hanson NNLS (libnbt/internal.h) */
nbt_status nbt__nnls(const double *A, size_t m, size_t n, const double *b, double *x, double *resid);

/* Compile and link one compute shader: the program, or 0 after nbt__fail
 * (NBT_EIO) with "WHAT does not compile|link: " and the driver's log. */
GLuint nbt__gl_compute_program(const char *src, const char *what);

#endif
