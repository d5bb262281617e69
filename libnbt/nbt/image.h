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
#include <stdint.h>
#include <nbt/error.h>

#ifdef __cplusplus
extern "C" {
#endif

/* An EXR box2i: the pixels min_x..max_x, min_y..max_y inclusive, in the
 * file's pixel coordinates (y down; negative values allowed). */
typedef struct {
    int32_t min_x, min_y, max_x, max_y;
} nbt_box2i;

/* EXR pixel types, with OpenEXR's codes. */
typedef enum { NBT_PIXEL_UINT = 0, NBT_PIXEL_HALF = 1, NBT_PIXEL_FLOAT = 2 } nbt_pixel_type;

/* A channel of the file kept as it was (see nbt_image_read_exr). */
typedef struct {
    char *name;                 /* full channel name, e.g. "A" or "ViewLayer.Combined.A" */
    nbt_pixel_type type;        /* its type in the file; data holds it unconverted */
    int x_sampling, y_sampling; /* 1, 1; other values: a subsampled channel, not kept (data NULL) */
    int linear;                 /* the file's pLinear flag */
    void *data;                 /* w*h values, data[y*w + x] like z: uint16_t (HALF: IEEE binary16
                                   bits), float (FLOAT) or uint32_t (UINT); NULL when not kept */
} nbt_image_channel;

typedef struct nbt_image_attrs nbt_image_attrs; /* header attributes kept from a file (opaque) */

typedef struct {
    size_t w, h;     /* pixels; row y = 0 is the top scan line (EXR's first line of the data window) */
    float *rgb;      /* rgb[(y*w + x)*3 + c], c = 0, 1, 2 for R, G, B: linear HDR radiance */
    float *z;        /* depth per pixel, z[y*w + x], or NULL when the image has none */
    /* Where the pixels lie (nbt_image_alloc: x0 = y0 = 0, display = (0, 0) - (w-1, h-1)): */
    int32_t x0, y0;      /* EXR coordinates of pixel (0, 0): the data window's min corner */
    nbt_box2i display;   /* the display window (the frame); may be smaller than, larger than
                            or offset from the data window (x0, y0) - (x0+w-1, y0+h-1) */
    /* What a file had besides RGB and Z (nbt_image_alloc: all NULL / 0): */
    char *rgb_layer;     /* layer P of the RGB channels P.R, P.G, P.B (e.g. "ViewLayer.Combined");
                            NULL: plain R, G, B (or a grey Y read as R = G = B) */
    char *z_name;        /* name of the depth channel in the file (e.g. "ViewLayer.Depth.Z"); NULL: "Z" */
    size_t nchannels;    /* the file's other channels of the part read, in file order */
    nbt_image_channel *channels;
    nbt_image_attrs *attrs; /* its other header attributes; NULL when none */
} nbt_image;

/* A w x h image, every value 0, with a depth plane when with_z != 0, origin
 * (0, 0), display window = data window, no kept channels or attributes.
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
 * Window: the pixels are the data window, with row 0 at its top; its origin
 * may be anywhere (negative too) and is returned in im->x0, im->y0. The
 * display window goes to im->display; it may be smaller (an overscanned
 * render), larger (a border render) or offset; nothing is cropped here.
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
 *   A chosen channel that is subsampled (x/y sampling != 1): NBT_EFORMAT.
 *   The layer of R, G, B goes to im->rgb_layer ("ViewLayer.Combined", NULL
 *   for plain names or Y) and a depth channel's name other than "Z" to
 *   im->z_name, so that nbt_image_write_exr_ex writes them back where the
 *   file had them.
 *   Every other channel of the part (alpha "A", "ViewLayer.Combined.A",
 *   Blender's other passes, ...) is kept in im->channels, in file order,
 *   unconverted (HALF as its 16 bits, FLOAT, UINT). Subsampled ones are
 *   listed there with their sampling but not kept (data NULL).
 *
 * Attributes: every header attribute of the part except the layout ones
 * (channels, compression, dataWindow, displayWindow, lineOrder, tiles,
 * type, name, version, chunkCount, maxSamplesPerPixel) is kept in im->attrs
 * with its type and value (strings, numbers, vectors, matrices, preview,
 * unknown types as raw bytes), to be written back by nbt_image_write_exr_ex;
 * see nbt_image_attr_count.
 *
 * Returns NBT_OK and *out (free with nbt_image_free); on failure *out is
 * NULL and the status is NBT_EIO (the file cannot be opened or is a
 * directory; err includes strerror(errno)), NBT_EFORMAT (not OpenEXR, bad
 * header, missing, ambiguous or unsupported channels, truncated or corrupt
 * pixel data), NBT_ENOMEM, or NBT_EINVAL (path or out NULL). */
nbt_status nbt_image_read_exr(const char *path, nbt_image **out, char *err, size_t errlen);

/* Writes a single-part scan-line OpenEXR file with float32 channels R, G, B
 * (and Z when im->z != NULL), ZIP compression, data window = display window
 * = (0, 0) - (w-1, h-1), whatever im's origin, display window, kept
 * channels and attributes (nbt_image_write_exr_ex writes those). attrs holds nattrs pairs attrs[2i] (name) and
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

/* A layer of float32 channels that nbt_image_write_exr_ex adds, e.g. the
 * scattered part {"S", 3, {"R", "G", "B"}, s}, the transmittance
 * {"T", 3, {"R", "G", "B"}, t} or the off-screen fraction
 * {"offscreen", 1, {"X"}, f}. Blender's multilayer reader takes only
 * one-letter channel names (and red/green/blue/alpha); use R, G, B (A) for
 * colours and X (as Blender's own one-value passes IndexOB/IndexMA) or Z
 * for one value. */
typedef struct {
    const char *name;         /* layer (pass) name, non-empty */
    size_t nchan;             /* 1 to 64 */
    const char *const *chan;  /* nchan channel names */
    const float *data;        /* data[(y*w + x)*nchan + c] over the image's whole data window (im->w x im->h) */
} nbt_image_layer;

/* Options of nbt_image_write_exr_ex; all zero / NULL: the whole data window
 * with every kept channel and attribute, no layers. */
typedef struct {
    const nbt_box2i *window;   /* pixels written, in the image's EXR coordinates (it becomes the file's
                                  data window); must lie inside the data window (x0, y0) - (x0+w-1,
                                  y0+h-1). NULL: the whole data window. &im->display: the frame only. */
    const nbt_box2i *display;  /* the file's display window; NULL: im->display */
    int drop_channels;         /* != 0: do not write im->channels */
    int drop_attrs;            /* != 0: do not write im->attrs */
    const char *layer_prefix;  /* put before each layer's name; NULL: the view layer of im->rgb_layer */
    const nbt_image_layer *layers;
    size_t nlayers;
    const char *const *attrs;  /* nattrs string attributes, name attrs[2i], value attrs[2i+1] (e.g.
                                  "nbt.method"); they replace kept attributes of the same name */
    size_t nattrs;
} nbt_exr_write_opts;

/* Writes a single-part scan-line OpenEXR file (ZIP) of the pixels in
 * opts->window, keeping what nbt_image_read_exr kept.
 *
 * Channel names (the convention of OpenImageIO, Nuke and Blender: dots
 * separate layer, pass and channel):
 *   RGB: "P.R", "P.G", "P.B" with P = im->rgb_layer; plain "R", "G", "B"
 *        when it is NULL. float32.
 *   Z:   im->z_name, or "Z" when it is NULL (only when im->z != NULL). float32.
 *   Layers: "<prefix><name>.<chan>", float32. prefix = opts->layer_prefix
 *        when given (verbatim, e.g. "" or "nbt."), else the view layer of
 *        im->rgb_layer: its text up to and including the last '.'
 *        ("ViewLayer.Combined" -> "ViewLayer.", so "ViewLayer.S.R" beside
 *        Blender's passes), "" when it has no '.' or is NULL ("S.R").
 *   Kept channels: their own names and types, cropped like the rest. One
 *        whose name equals a channel above is replaced by it (so a file
 *        written by nbt-scatter can be its input again); subsampled ones
 *        (data NULL) are left out.
 * Two channels above with the same name: NBT_EINVAL.
 * Seen from the tools: `oiiotool --info -v` lists "R, G, B, A, S.R, S.G,
 * S.B, ..."; Blender 3.4 opens a file with any layered channel as a
 * multilayer image: view layer "" (plain) or "ViewLayer", passes
 * "Combined" (R, G, B and A), "Depth" (Z), "S", "T", "offscreen", each an
 * output of the compositor's Image node.
 *
 * Header: data window = the window; display window = opts->display or
 * im->display (so cropping to im->display gives data = display window);
 * pixelAspectRatio, screenWindowCenter and screenWindowWidth from im->attrs
 * when kept (else 1, (0, 0), 1); then opts->attrs as strings; then every
 * other kept attribute unchanged (not when opts->drop_attrs).
 *
 * Written to a temporary file next to path and renamed over it at the end,
 * so on failure path is untouched and nothing is left behind. Returns
 * NBT_OK, or:
 *   NBT_EINVAL: no image or no pixels, a window that is empty or not inside
 *               the data window (err names both), an empty display window,
 *               a layer without name, channels or data, two channels of
 *               one name, a NULL or empty attribute name, a NULL value, a
 *               refused attribute name (a layout attribute such as
 *               "compression");
 *   NBT_EFORMAT: a kept attribute that the library refuses to write;
 *   NBT_EIO:    the file cannot be created, written or renamed;
 *   NBT_ENOMEM. */
nbt_status nbt_image_write_exr_ex(const nbt_image *im, const char *path, const nbt_exr_write_opts *opts, char *err,
                                  size_t errlen);

/* Gives dst (same w and h) src's window origin, display window, RGB layer,
 * depth name, kept channels and attributes (deep copies, replacing dst's),
 * for writing a new image with what its input had. Returns NBT_OK,
 * NBT_EINVAL (NULL, the same image or a different size) or NBT_ENOMEM (dst
 * unchanged). */
nbt_status nbt_image_copy_meta(nbt_image *dst, const nbt_image *src);

/* The kept header attributes: how many, the i-th's name (and its EXR type
 * name, e.g. "string", "m44f", when type_name != NULL; NULL when i is out
 * of range), and the value of a string attribute (NULL when there is no
 * string attribute of that name). */
size_t nbt_image_attr_count(const nbt_image *im);
const char *nbt_image_attr_name(const nbt_image *im, size_t i, const char **type_name);
const char *nbt_image_attr_string(const nbt_image *im, const char *name);

#ifdef __cplusplus
}
#endif
#endif
