/* scatter/scatter.h: nbt-scatter's parts (scenes, tone-mapped previews). */
#ifndef NBT_SCATTER_H
#define NBT_SCATTER_H

#include <stddef.h>
#include <nbt/image.h>
#include <nbt/nbt.h>

/* Generated renders for tests and the quick start: index by name or -1. */
int scene_parse(const char *name);
const char *scene_names(void);
/* A w x h frame; ox, oy > 0: an overscanned render, the data window larger by
 * ox, oy pixels on each side (origin (-ox, -oy), display window (0, 0)-(w-1, h-1)). */
nbt_image *scene_make(int kind, size_t w, size_t h, size_t ox, size_t oy);

/* A tone-mapped sRGB PNG of a linear HDR image (exposure from the median
 * luminance, Reinhard curve). 0 or -1. */
int scatter_preview_png(const nbt_image *im, const char *path);

/* The medium: sigma_t and albedo per channel (one value or R,G,B), the
 * Gaussian phase width B (the moment kernels) or a phase per channel (one,
 * or three for R, G, B), the geometry and the model of the fitted kernels. */
typedef struct {
    double sigma_t[3], albedo[3], B;
    int nst, nalb, nphase;
    nbt_phase *phase[3];
    nbt_screen_geometry geometry;
    const nbt_screen_model *model; /* NULL: the shipped one */
    nbt_screen_model *owned_model;
} scatter_medium;

/* ARG is one value or R,G,B, each in [lo, hi] ((lo, hi] when lo_open);
 * v gets three values (one repeated); returns how many were given. Bad: exit 2. */
int parse_triple(const char *opt, const char *arg, double lo, int lo_open, double hi, double v[3]);
void medium_add_phase(scatter_medium *m, const char *spec);
void medium_finish(scatter_medium *m);
/* 3 when any of sigma_t, albedo or the phase differs per channel, else 1 */
int medium_channels(const scatter_medium *m);
const nbt_phase *medium_phase(const scatter_medium *m, int c);
/* the kernel family (an RGB kernel for an RGB medium); a refusal exits 2 */
nbt_screen_kernel *medium_kernel(const scatter_medium *m, nbt_skernel_kind kind, const nbt_kernel_correction *corr);
void medium_free(scatter_medium *m);
void medium_triple_str(const double v[3], int n, char *buf, size_t len);

#endif
