/* gen/preview.h: false-colour PNG previews of tables. */
#ifndef NBT_GEN_PREVIEW_H
#define NBT_GEN_PREVIEW_H

#include <nbt/table.h>

/* One panel per channel, side by side, PREVIEW_PANEL_W x PREVIEW_PANEL_H
 * pixels each, axis 0 to the right and axis 1 upwards, both linear in the
 * physical values (ticks and labels), sampled with the table's bilinear
 * lookup; one colour scale for all channels (min..max of the samples) with
 * a colour bar to the right; a two-line caption: kind, size, the recorded
 * interpolation error, the node mappings and phase. The image is
 * PREVIEW_W(nch) x PREVIEW_H. Written via a temporary file. 0 or -1. */
#define PREVIEW_PANEL_W 384
#define PREVIEW_PANEL_H 288
#define PREVIEW_LEFT 124
#define PREVIEW_TOP 96
#define PREVIEW_GAP 40
#define PREVIEW_BAR_GAP 24
#define PREVIEW_BAR_W 24
#define PREVIEW_RIGHT 176
#define PREVIEW_BOTTOM 56
#define PREVIEW_W(nch) (PREVIEW_LEFT + (int)(nch) * PREVIEW_PANEL_W + ((int)(nch) - 1) * PREVIEW_GAP + PREVIEW_RIGHT)
#define PREVIEW_H (PREVIEW_TOP + PREVIEW_PANEL_H + PREVIEW_BOTTOM)
int preview_write_png(const nbt_table *t, const char *path);

/* An 8-bit RGB image (rows top to bottom) as PNG, via a temporary file. 0 or -1. */
#include <stddef.h>
int preview_write_rgb8(const char *path, const unsigned char *img, size_t W, size_t H);

#endif
