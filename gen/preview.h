/* gen/preview.h: false-colour PNG previews of tables. */
#ifndef NBT_GEN_PREVIEW_H
#define NBT_GEN_PREVIEW_H

#include <nbt/table.h>

/* One panel per channel, side by side, each scaled to its own min..max;
 * axis 0 to the right, axis 1 upwards. Written via a temporary file. 0 or -1. */
int preview_write_png(const nbt_table *t, const char *path);

/* An 8-bit RGB image (rows top to bottom) as PNG, via a temporary file. 0 or -1. */
#include <stddef.h>
int preview_write_rgb8(const char *path, const unsigned char *img, size_t W, size_t H);

#endif
