/* gen/scene.h: the scene file of nbt-gen scene (doc/scene-format.md). */
#ifndef NBT_GEN_SCENE_H
#define NBT_GEN_SCENE_H

#include <stddef.h>

/* libnbt-gl's airlight and surface shaders take at most 4 RGBA packs per
 * kind (GLSL 3.30 indexes sampler arrays with constants only): 16 orders. */
#define NBT_SCENE_GL_ORDERS 16

typedef struct {
    double kt_lo, kt_hi, ks_lo, ks_hi, d_lo, d_hi, g_lo, g_hi, tol;
    int have_kt, have_ks, have_d, have_g, airlight, diffuse, half;
    char phase[256];
    int phong[16];
    long orders_max;  /* Legendre orders the tables may hold (default: what libnbt-gl takes) */
    size_t nphong;
} scene_t;

/* Read and check the scene in PATH: 0, or -1 with one line in err naming
 * file:line, the key and what is accepted (what nbt-gen prints, exit 2). */
int scene_parse(const char *path, scene_t *s, char *err, size_t errlen);

#endif
