/* nbt/image.h: HDR images (linear RGB radiance plus optional depth) and
 * their OpenEXR I/O, for programs that post-process renders (e.g. from
 * Blender).
 *
 * Layout: row y = 0 is the top scan line, i.e. the first line of the EXR
 * data window (EXR's y axis points down); pixel x = 0 is the data window's
 * left column. Values are stored as float32 exactly as in the file (no
 * colour-space conversion, no clamping: negative values, Inf and NaN are
 * kept). Depth is in whatever unit and convention the renderer wrote
 * (Blender: scene units; background pixels hold a very large value).
 *
 * Errors: the I/O functions return a status from nbt/error.h, write one
 * line without a trailing newline naming the file and the problem to err
 * (when err != NULL and errlen > 0; truncated to errlen), and pass the same
 * line to the error handler set with nbt_set_error_handler. */
#ifndef NBT_IMAGE_H
#define NBT_IMAGE_H

#include <stddef.h>
#include <nbt/error.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef struct {
    size_t w, h;     /* pixels; row y = 0 is the top scan line (EXR's first line of the data window) */
    float *rgb;      /* rgb[(y*w + x)*3 + c], c = 0, 1, 2 for R, G, B: linear HDR radiance */
    float *z;        /* depth per pixel, z[y*w + x], or NULL when the image has none */
} nbt_image;

/* A w x h image, every value 0, with a depth plane when with_z != 0.
 * Returns NULL when w or h is 0, when w*h*3 floats overflow size_t, or when
 * memory runs out. Free with nbt_image_free. */
nbt_image *nbt_image_alloc(size_t w, size_t h, int with_z);
/* Frees the image and its planes; NULL is allowed. */
void nbt_image_free(nbt_image *im);

/* Reads RGB and (when present) depth from an OpenEXR file.
 *
 * Files: scan-line or tiled parts (tiled: level 0 of one-level, mipmap or
 * ripmap files), any compression the OpenEXR core library decodes; HALF,
 * FLOAT and UINT channels are converted to float. In a multi-part file the
 * first part (deep parts skipped) that has the channels below is read; a
 * part whose channels are ambiguous or unsupported stops the search.
 *
 * Window: the image is the data window alone. Its origin may be anywhere
 * (negative too); the display window is ignored, so a border render comes
 * back cropped to its data window, with row 0 at the data window's top.
 *
 * Channels:
 *   RGB: exactly "R", "G", "B"; failing that, one layer P with channels
 *        "P.R", "P.G", "P.B" (e.g. Blender multilayer "ViewLayer.Combined.R").
 *        Several such layers: the one whose last name component is
 *        "Combined" when that is unique, else NBT_EFORMAT ("ambiguous").
 *        Failing both, a single luminance channel "Y" (without "RY"/"BY"
 *        chroma) is read as grey, R = G = B = Y. No RGB: NBT_EFORMAT.
 *   Z:   "Z"; failing that, with an RGB layer "L.Pass" the channel
 *        "L.Depth.Z" or "L.Pass.Z"; failing that, the only channel named
 *        "Depth.Z" or ending in ".Depth.Z"; failing that, the only channel
 *        "P.Z" that is neither a vector component (no "P.X"/"P.Y" beside
 *        it, e.g. Blender's Normal.Z) nor Blender's normalized "Mist.Z".
 *        Several candidates at the first level that has any: NBT_EFORMAT.
 *        None: im->z = NULL.
 *   Other channels are ignored. A chosen channel that is subsampled
 *   (x/y sampling != 1): NBT_EFORMAT.
 *
 * Returns NBT_OK and *out (free with nbt_image_free); on failure *out is
 * NULL and the status is NBT_EIO (the file cannot be opened or is a
 * directory; err includes strerror(errno)), NBT_EFORMAT (not OpenEXR, bad
 * header, missing, ambiguous or unsupported channels, truncated or corrupt
 * pixel data), NBT_ENOMEM, or NBT_EINVAL (path or out NULL). */
nbt_status nbt_image_read_exr(const char *path, nbt_image **out, char *err, size_t errlen);

/* Writes a single-part scan-line OpenEXR file with float32 channels R, G, B
 * (and Z when im->z != NULL), ZIP compression, data window = display window
 * = (0, 0) - (w-1, h-1). attrs holds nattrs pairs attrs[2i] (name) and
 * attrs[2i+1] (value) stored as string attributes; attrs may be NULL when
 * nattrs == 0. A name that the library refuses (e.g. a standard attribute
 * of another type, such as "compression") gives NBT_EINVAL.
 *
 * The file is written to a temporary file next to path and renamed over
 * path at the end, so on failure path is untouched and nothing is left
 * behind. Returns NBT_OK, or:
 *   NBT_EINVAL: no image or no pixels, w or h 0, w >= 2^31/12 or h >= 2^31,
 *               a NULL or empty attribute name, a NULL value, a refused name;
 *   NBT_EIO:    the file cannot be created, written or renamed (err says why:
 *               strerror(errno) or the library's message);
 *   NBT_ENOMEM. */
nbt_status nbt_image_write_exr(const nbt_image *im, const char *path, const char *const *attrs, size_t nattrs,
                               char *err, size_t errlen);

#ifdef __cplusplus
}
#endif
#endif
