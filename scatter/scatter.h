/* scatter/scatter.h: nbt-scatter's parts (scenes, tone-mapped previews). */
#ifndef NBT_SCATTER_H
#define NBT_SCATTER_H

#include <stddef.h>
#include <nbt/image.h>

/* Generated renders for tests and the quick start: index by name or -1. */
int scene_parse(const char *name);
const char *scene_names(void);
nbt_image *scene_make(int kind, size_t w, size_t h);

/* A tone-mapped sRGB PNG of a linear HDR image (exposure from the median
 * luminance, Reinhard curve). 0 or -1. */
int scatter_preview_png(const nbt_image *im, const char *path);

#endif
