/* tests/test_image.c: nbt_image OpenEXR I/O. Float round trips (with and
 * without depth, odd sizes, special values, attributes, ZIP), files written
 * here with the OpenEXR core API (HALF, UINT, tiled with mipmaps, a data
 * window away from the origin, Blender multilayer names, luminance, multi
 * part) read back with known values, and failures: missing, non-EXR,
 * channel-less, ambiguous, subsampled and truncated files, and writes that
 * cannot complete (nothing left behind). nbt_image_write_exr_ex: an
 * overscanned file (data window (-7, -5) - (37, 25) around a 30 x 20 display
 * window) with HALF/FLOAT/UINT channels and string, int, float, m44f, v2f and
 * string-vector attributes, cropped to the display window and checked pixel
 * by pixel and through the core library's header; the whole data window;
 * Blender names; refused windows, layers and attributes. */
#define _POSIX_C_SOURCE 200809L
#include <dirent.h>
#include <errno.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>
#include <openexr.h>
#include <nbt/error.h>
#include <nbt/image.h>
#include "testutil.h"

static char dir[64];

static const char *in_dir(const char *name)
{
    static char buf[8][256];
    static int k;
    k = (k + 1) % 8;
    snprintf(buf[k], sizeof buf[k], "%s/%s", dir, name);
    return buf[k];
}

/* Entries in a directory other than . and .. (-1: cannot read it). */
static int count_entries(const char *path)
{
    DIR *d = opendir(path);
    if (!d)
        return -1;
    int n = 0;
    struct dirent *e;
    while ((e = readdir(d)))
        if (strcmp(e->d_name, ".") && strcmp(e->d_name, ".."))
            n++;
    closedir(d);
    return n;
}

static long file_size(const char *path)
{
    struct stat sb;
    return stat(path, &sb) == 0 ? (long)sb.st_size : -1;
}

/* ---- a small writer on the OpenEXR core API, independent of libnbt ---- */

/* f exactly representable as a normal half, or +-0 */
static uint16_t f2h(float f)
{
    uint32_t u;
    memcpy(&u, &f, 4);
    uint32_t s = (u >> 16) & 0x8000u;
    if ((u & 0x7fffffffu) == 0)
        return (uint16_t)s;
    int e = (int)((u >> 23) & 0xffu) - 127 + 15;
    return (uint16_t)(s | ((uint32_t)e << 10) | ((u & 0x7fffffu) >> 13));
}

typedef struct {
    const char *name;
    exr_pixel_type_t type;
    const float *v;  /* level-0 values of the data window, row-major (w/xs x h/ys when subsampled) */
    int xs, ys;      /* sampling; 0 means 1 */
} wch;

typedef struct {
    exr_storage_t storage;
    exr_compression_t comp;
    int x0, y0, w, h;                  /* data window */
    int disp;                          /* display window (0,0)-(w+9, h+9) instead of = data window */
    uint32_t tw, th;                   /* tile size */
    exr_tile_level_mode_t levels;
    const wch *ch;
    int nch;
    const exr_attr_box2i_t *dispbox;   /* display window when not NULL (overrides disp) */
    exr_result_t (*attrs)(exr_context_t, int); /* sets extra header attributes when not NULL */
} wpart;

/* One channel's values for a level, converted to its type (levels > 0: all 99). */
static uint8_t *chan_buf(const wch *c, size_t n, int level)
{
    size_t bpe = c->type == EXR_PIXEL_HALF ? 2 : 4;
    uint8_t *b = malloc(n * bpe);
    for (size_t i = 0; i < n; i++) {
        float f = level ? 99.0f : c->v[i];
        if (c->type == EXR_PIXEL_HALF) {
            uint16_t hv = f2h(f);
            memcpy(b + 2 * i, &hv, 2);
        } else if (c->type == EXR_PIXEL_UINT) {
            uint32_t uv = (uint32_t)f;
            memcpy(b + 4 * i, &uv, 4);
        } else
            memcpy(b + 4 * i, &f, 4);
    }
    return b;
}

/* Encodes one chunk; bufs[c] holds channel c's level image, lw pixels wide,
 * (px, py) is the chunk's first pixel within it. */
static exr_result_t put_chunk(exr_context_t ctx, int part, const wpart *wp, exr_chunk_info_t *ci, uint8_t **bufs,
                              int lw, int px, int py)
{
    exr_encode_pipeline_t enc = EXR_ENCODE_PIPELINE_INITIALIZER;
    exr_result_t rv = exr_encoding_initialize(ctx, part, ci, &enc);
    for (int16_t c = 0; c < enc.channel_count && rv == EXR_ERR_SUCCESS; c++) {
        exr_coding_channel_info_t *ch = &enc.channels[c];
        int k = 0;
        while (k < wp->nch && strcmp(wp->ch[k].name, ch->channel_name))
            k++;
        int xs = wp->ch[k].xs ? wp->ch[k].xs : 1, ys = wp->ch[k].ys ? wp->ch[k].ys : 1;
        int bpe = wp->ch[k].type == EXR_PIXEL_HALF ? 2 : 4;
        ch->user_pixel_stride = bpe;
        ch->user_line_stride = (lw / xs) * bpe;
        ch->user_bytes_per_element = (int16_t)bpe;
        ch->user_data_type = (uint16_t)wp->ch[k].type;
        ch->encode_from_ptr = bufs[k] + ((size_t)((py + ys - 1) / ys) * (size_t)(lw / xs) + (size_t)(px / xs)) * (size_t)bpe;
    }
    if (rv == EXR_ERR_SUCCESS)
        rv = exr_encoding_choose_default_routines(ctx, part, &enc);
    if (rv == EXR_ERR_SUCCESS)
        rv = exr_encoding_run(ctx, part, &enc);
    exr_encoding_destroy(ctx, &enc);
    return rv;
}

static exr_result_t write_part_data(exr_context_t ctx, int part, const wpart *wp)
{
    exr_result_t rv = EXR_ERR_SUCCESS;
    uint8_t *bufs[16];
    if (wp->storage == EXR_STORAGE_SCANLINE) {
        for (int c = 0; c < wp->nch; c++) {
            int xs = wp->ch[c].xs ? wp->ch[c].xs : 1, ys = wp->ch[c].ys ? wp->ch[c].ys : 1;
            bufs[c] = chan_buf(&wp->ch[c], (size_t)(wp->w / xs) * (size_t)(wp->h / ys), 0);
        }
        int32_t lpc = 1;
        exr_get_scanlines_per_chunk(ctx, part, &lpc);
        for (int y = 0; y < wp->h && rv == EXR_ERR_SUCCESS; y += lpc) {
            exr_chunk_info_t ci;
            rv = exr_write_scanline_chunk_info(ctx, part, wp->y0 + y, &ci);
            if (rv == EXR_ERR_SUCCESS)
                rv = put_chunk(ctx, part, wp, &ci, bufs, wp->w, 0, y);
        }
        for (int c = 0; c < wp->nch; c++)
            free(bufs[c]);
        return rv;
    }
    int32_t nlx = 1, nly = 1;
    rv = exr_get_tile_levels(ctx, part, &nlx, &nly);
    for (int32_t lx = 0; lx < nlx && rv == EXR_ERR_SUCCESS; lx++)
        for (int32_t ly = 0; ly < nly && rv == EXR_ERR_SUCCESS; ly++) {
            if (wp->levels == EXR_TILE_MIPMAP_LEVELS && lx != ly)
                continue;
            int32_t lw = 0, lh = 0, tw = 0, th = 0;
            rv = exr_get_level_sizes(ctx, part, lx, ly, &lw, &lh);
            if (rv == EXR_ERR_SUCCESS)
                rv = exr_get_tile_sizes(ctx, part, lx, ly, &tw, &th);
            if (rv != EXR_ERR_SUCCESS)
                break;
            /* OpenEXR 3.1.5 does not clip the edge tiles of levels > 0
             * (exr_write_tile_chunk_info reports whole tiles there), so
             * those levels get buffers padded to whole tiles */
            int pw = lx || ly ? (lw + tw - 1) / tw * tw : lw, ph = lx || ly ? (lh + th - 1) / th * th : lh;
            for (int c = 0; c < wp->nch; c++)
                bufs[c] = chan_buf(&wp->ch[c], (size_t)pw * (size_t)ph, lx || ly);
            for (int ty = 0; ty * th < lh && rv == EXR_ERR_SUCCESS; ty++)
                for (int tx = 0; tx * tw < lw && rv == EXR_ERR_SUCCESS; tx++) {
                    exr_chunk_info_t ci;
                    rv = exr_write_tile_chunk_info(ctx, part, tx, ty, lx, ly, &ci);
                    if (rv == EXR_ERR_SUCCESS && (!(lx || ly)) && (ci.width > lw - tx * tw || ci.height > lh - ty * th))
                        rv = EXR_ERR_INVALID_ARGUMENT; /* level 0 must be clipped */
                    if (rv == EXR_ERR_SUCCESS)
                        rv = put_chunk(ctx, part, wp, &ci, bufs, pw, tx * tw, ty * th);
                }
            for (int c = 0; c < wp->nch; c++)
                free(bufs[c]);
        }
    return rv;
}

static void quiet(exr_const_context_t c, exr_result_t code, const char *msg)
{
    (void)c;
    (void)code;
    if (getenv("NBT_TEST_VERBOSE"))
        printf("      (openexr: %s)\n", msg);
}

/* Writes the parts (names p0, p1, ... when more than one); 0 on success. */
static int write_exr(const char *path, const wpart *parts, int nparts)
{
    exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
    init.error_handler_fn = quiet;
    exr_context_t ctx = NULL;
    exr_result_t rv = exr_start_write(&ctx, path, EXR_WRITE_FILE_DIRECTLY, &init);
    for (int p = 0; p < nparts && rv == EXR_ERR_SUCCESS; p++) {
        const wpart *wp = &parts[p];
        char name[16];
        snprintf(name, sizeof name, "p%d", p);
        int idx = 0;
        rv = exr_add_part(ctx, nparts > 1 ? name : NULL, wp->storage, &idx);
        exr_attr_box2i_t dw, dispw;
        dw.min.x = wp->x0;
        dw.min.y = wp->y0;
        dw.max.x = wp->x0 + wp->w - 1;
        dw.max.y = wp->y0 + wp->h - 1;
        dispw.min.x = dispw.min.y = 0;
        dispw.max.x = wp->w + 9;
        dispw.max.y = wp->h + 9;
        exr_attr_v2f_t swc;
        swc.x = swc.y = 0.0f;
        if (rv == EXR_ERR_SUCCESS)
            rv = exr_initialize_required_attr(ctx, idx, wp->dispbox ? wp->dispbox : wp->disp ? &dispw : &dw, &dw, 1.0f,
                                              &swc, 1.0f, EXR_LINEORDER_INCREASING_Y, wp->comp);
        if (rv == EXR_ERR_SUCCESS && wp->attrs)
            rv = wp->attrs(ctx, idx);
        for (int c = 0; c < wp->nch && rv == EXR_ERR_SUCCESS; c++)
            rv = exr_add_channel(ctx, idx, wp->ch[c].name, wp->ch[c].type, EXR_PERCEPTUALLY_LOGARITHMIC,
                                 wp->ch[c].xs ? wp->ch[c].xs : 1, wp->ch[c].ys ? wp->ch[c].ys : 1);
        if (rv == EXR_ERR_SUCCESS && wp->storage == EXR_STORAGE_TILED)
            rv = exr_set_tile_descriptor(ctx, idx, wp->tw, wp->th, wp->levels, EXR_TILE_ROUND_DOWN);
    }
    if (rv == EXR_ERR_SUCCESS)
        rv = exr_write_header(ctx);
    for (int p = 0; p < nparts && rv == EXR_ERR_SUCCESS; p++)
        rv = write_part_data(ctx, p, &parts[p]);
    exr_result_t fr = ctx ? exr_finish(&ctx) : EXR_ERR_SUCCESS;
    if (rv == EXR_ERR_SUCCESS)
        rv = fr;
    if (rv != EXR_ERR_SUCCESS)
        printf("      test writer failed for %s: %s\n", path, exr_get_default_error_message(rv));
    return rv != EXR_ERR_SUCCESS;
}

static wpart scan(int w, int h, exr_compression_t comp, const wch *ch, int nch)
{
    wpart p = {EXR_STORAGE_SCANLINE, comp, 0, 0, w, h, 0, 0, 0, EXR_TILE_ONE_LEVEL, ch, nch, NULL, NULL};
    return p;
}

/* Plane of w*h values exactly representable in half: pattern + offset. */
static float *plane(int w, int h, float offset)
{
    float *v = malloc((size_t)w * (size_t)h * sizeof(float));
    for (int i = 0; i < w * h; i++)
        v[i] = (float)((i * 7 + 3) % 97) * 0.125f - 3.0f + offset;
    return v;
}

/* Mismatches between an image plane and expected values (stride 3 for RGB channel c, 1 for z). */
static size_t mismatches(const float *got, size_t stride, size_t c, const float *want, size_t n)
{
    size_t bad = 0;
    for (size_t i = 0; i < n; i++)
        if (got[i * stride + c] != want[i])
            bad++;
    return bad;
}

/* ---- error handler capture ---- */
static char handler_reason[1024];
static nbt_status handler_status;
static int handler_calls;
static void on_error(const char *reason, nbt_status s)
{
    snprintf(handler_reason, sizeof handler_reason, "%s", reason);
    handler_status = s;
    handler_calls++;
}

/* ---- tests ---- */

static void test_alloc(void)
{
    t_true(nbt_image_alloc(0, 5, 0) == NULL, "alloc: width 0 -> NULL");
    t_true(nbt_image_alloc(5, 0, 1) == NULL, "alloc: height 0 -> NULL");
    t_true(nbt_image_alloc(SIZE_MAX / 2, 3, 0) == NULL, "alloc: w*h overflows -> NULL");
    t_true(nbt_image_alloc(SIZE_MAX / 8, 1, 0) == NULL, "alloc: w*h*3 floats overflow -> NULL");
    nbt_image *im = nbt_image_alloc(7, 3, 1);
    t_true(im && im->w == 7 && im->h == 3 && im->rgb && im->z, "alloc: 7x3 with z");
    if (im) {
        size_t nz = 0;
        for (size_t i = 0; i < 7 * 3 * 3; i++)
            nz += im->rgb[i] != 0.0f;
        for (size_t i = 0; i < 7 * 3; i++)
            nz += im->z[i] != 0.0f;
        t_true(nz == 0, "alloc: zero-filled (%zu non-zero)", nz);
    }
    nbt_image_free(im);
    im = nbt_image_alloc(2, 2, 0);
    t_true(im && im->z == NULL, "alloc: without z, z == NULL");
    nbt_image_free(im);
    nbt_image_free(NULL);
}

static void fill_special(nbt_image *im)
{
    size_t n = im->w * im->h;
    for (size_t i = 0; i < 3 * n; i++)
        im->rgb[i] = (float)((t_uniform() - 0.25) * pow(10.0, 8.0 * t_uniform() - 4.0));
    const float sp[] = {-0.0f, 1e-40f, 65504.0f, 3.4e38f, INFINITY, -INFINITY, NAN, 1.0f / 3.0f};
    for (size_t k = 0; k < sizeof sp / sizeof sp[0] && k < 3 * n; k++)
        im->rgb[(k * 37) % (3 * n)] = sp[k];
    if (im->z)
        for (size_t i = 0; i < n; i++)
            im->z[i] = (float)(1.0 + 1000.0 * t_uniform());
}

static void test_roundtrip(size_t w, size_t h, int with_z)
{
    nbt_image *im = nbt_image_alloc(w, h, with_z), *back = NULL;
    fill_special(im);
    const char *path = in_dir("rt.exr");
    const char *attrs[] = {"nbt.source", "blender 4.1", "comment", "round trip"};
    char err[512] = "x";
    nbt_status s = nbt_image_write_exr(im, path, attrs, 2, err, sizeof err);
    t_true(s == NBT_OK && err[0] == '\0', "round trip %zux%zu z=%d: write OK (%s)", w, h, with_z, err);
    t_true(count_entries(dir) == 1, "round trip %zux%zu z=%d: only the file in the directory (%d entries)", w, h,
           with_z, count_entries(dir));
    s = nbt_image_read_exr(path, &back, err, sizeof err);
    t_true(s == NBT_OK && back, "round trip %zux%zu z=%d: read OK (%s)", w, h, with_z, err);
    if (back) {
        t_true(back->w == w && back->h == h, "round trip: size %zux%zu", back->w, back->h);
        t_true(!memcmp(back->rgb, im->rgb, w * h * 3 * sizeof(float)), "round trip %zux%zu: RGB bit-exact", w, h);
        t_true(with_z ? back->z && !memcmp(back->z, im->z, w * h * sizeof(float)) : back->z == NULL,
               "round trip %zux%zu: Z %s", w, h, with_z ? "bit-exact" : "absent");
        t_abs(back->rgb[(w * h - 1) * 3 + 2], im->rgb[(w * h - 1) * 3 + 2], 0.0, "round trip: last B value");
    }
    nbt_image_free(back);

    /* the file itself: channels, types, compression, attributes (read with the core API) */
    exr_context_t ctx = NULL;
    exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
    init.error_handler_fn = quiet;
    if (exr_start_read(&ctx, path, &init) == EXR_ERR_SUCCESS) {
        const exr_attr_chlist_t *cl = NULL;
        exr_compression_t comp = EXR_COMPRESSION_LAST_TYPE;
        exr_storage_t stor = EXR_STORAGE_LAST_TYPE;
        exr_get_channels(ctx, 0, &cl);
        exr_get_compression(ctx, 0, &comp);
        exr_get_storage(ctx, 0, &stor);
        int allfloat = cl != NULL;
        for (int i = 0; cl && i < cl->num_channels; i++)
            allfloat &= cl->entries[i].pixel_type == EXR_PIXEL_FLOAT;
        t_true(cl && cl->num_channels == (with_z ? 4 : 3) && !strcmp(cl->entries[0].name.str, "B") &&
                   !strcmp(cl->entries[2].name.str, "R") && (!with_z || !strcmp(cl->entries[3].name.str, "Z")),
               "written file: channels B, G, R%s", with_z ? ", Z" : "");
        t_true(allfloat, "written file: all channels FLOAT");
        t_true(comp == EXR_COMPRESSION_ZIP && stor == EXR_STORAGE_SCANLINE, "written file: scan lines, ZIP (%d)",
               (int)comp);
        const char *v = NULL, *v2 = NULL;
        int32_t len = 0;
        int ok = exr_attr_get_string(ctx, 0, "nbt.source", &len, &v) == EXR_ERR_SUCCESS && v;
        t_true(ok && !strcmp(v, "blender 4.1"), "written file: attribute nbt.source = \"%s\"", v ? v : "(none)");
        ok = exr_attr_get_string(ctx, 0, "comment", &len, &v2) == EXR_ERR_SUCCESS && v2;
        t_true(ok && !strcmp(v2, "round trip"), "written file: attribute comment = \"%s\"", v2 ? v2 : "(none)");
        exr_finish(&ctx);
    } else
        t_true(0, "written file opens with the core API");
    unlink(path);
    nbt_image_free(im);
}

static void test_half(void)
{
    const int w = 37, h = 23;
    float *r = plane(w, h, 0), *g = plane(w, h, 10), *b = plane(w, h, -20), *a = plane(w, h, 0.5f),
          *z = plane(w, h, 100);
    /* RGB only (the core library's 3-channel interleave path), ZIP */
    wch c3[] = {{"R", EXR_PIXEL_HALF, r, 0, 0}, {"G", EXR_PIXEL_HALF, g, 0, 0}, {"B", EXR_PIXEL_HALF, b, 0, 0}};
    wpart p = scan(w, h, EXR_COMPRESSION_ZIP, c3, 3);
    const char *path = in_dir("half.exr");
    nbt_image *im = NULL;
    char err[512] = "";
    t_true(write_exr(path, &p, 1) == 0, "half: test file written");
    nbt_status s = nbt_image_read_exr(path, &im, err, sizeof err);
    t_true(s == NBT_OK && im && im->w == (size_t)w && im->h == (size_t)h && !im->z, "half RGB: read %dx%d (%s)", w,
           h, err);
    if (im) {
        size_t n = (size_t)w * (size_t)h;
        t_true(mismatches(im->rgb, 3, 0, r, n) + mismatches(im->rgb, 3, 1, g, n) + mismatches(im->rgb, 3, 2, b, n) == 0,
               "half RGB: every value exact");
        t_abs(im->rgb[0], -2.625, 0, "half RGB: R(0,0)");         /* 3*0.125 - 3 */
        t_abs(im->rgb[(5 * w + 2) * 3 + 1], (double)g[5 * w + 2], 0, "half RGB: G(2,5)");
        t_abs(im->rgb[(n - 1) * 3 + 2], (double)b[n - 1], 0, "half RGB: B(last)");
    }
    nbt_image_free(im);
    im = NULL;
    /* HALF RGBA + FLOAT Z, uncompressed (generic conversion, A skipped) */
    wch c5[] = {{"A", EXR_PIXEL_HALF, a, 0, 0}, {"B", EXR_PIXEL_HALF, b, 0, 0}, {"G", EXR_PIXEL_HALF, g, 0, 0},
                {"R", EXR_PIXEL_HALF, r, 0, 0}, {"Z", EXR_PIXEL_FLOAT, z, 0, 0}};
    p = scan(w, h, EXR_COMPRESSION_NONE, c5, 5);
    t_true(write_exr(path, &p, 1) == 0, "half RGBA+Z: test file written");
    s = nbt_image_read_exr(path, &im, err, sizeof err);
    t_true(s == NBT_OK && im && im->z, "half RGBA + float Z: read (%s)", err);
    if (im && im->z) {
        size_t n = (size_t)w * (size_t)h;
        t_true(mismatches(im->rgb, 3, 0, r, n) + mismatches(im->rgb, 3, 1, g, n) + mismatches(im->rgb, 3, 2, b, n) == 0,
               "half RGBA: RGB exact, A ignored");
        t_true(mismatches(im->z, 1, 0, z, n) == 0, "half RGBA: Z exact");
        t_abs(im->z[w + 1], (double)z[w + 1], 0, "half RGBA: Z(1,1)");
    }
    nbt_image_free(im);
    unlink(path);
    free(r), free(g), free(b), free(a), free(z);
}

static void test_tiled(void)
{
    const int w = 37, h = 23;
    float *r = plane(w, h, 1), *g = plane(w, h, 2), *b = plane(w, h, 3), *z = malloc((size_t)(w * h) * sizeof(float));
    for (int i = 0; i < w * h; i++)
        z[i] = (float)(1000 + 3 * i);
    /* mipmapped, 8x5 tiles (partial edge tiles), ZIP, float RGB and UINT Z, origin (3, -4) */
    wch c4[] = {{"B", EXR_PIXEL_FLOAT, b, 0, 0}, {"G", EXR_PIXEL_FLOAT, g, 0, 0}, {"R", EXR_PIXEL_FLOAT, r, 0, 0},
                {"Z", EXR_PIXEL_UINT, z, 0, 0}};
    wpart p = {EXR_STORAGE_TILED, EXR_COMPRESSION_ZIP, 3, -4, w, h, 1, 8, 5, EXR_TILE_MIPMAP_LEVELS, c4, 4, NULL, NULL};
    const char *path = in_dir("tiled.exr");
    nbt_image *im = NULL;
    char err[512] = "";
    t_true(write_exr(path, &p, 1) == 0, "tiled: test file written");
    nbt_status s = nbt_image_read_exr(path, &im, err, sizeof err);
    t_true(s == NBT_OK && im && im->z && im->w == (size_t)w && im->h == (size_t)h, "tiled mipmap: read level 0 (%s)",
           err);
    if (im && im->z) {
        size_t n = (size_t)w * (size_t)h;
        t_true(mismatches(im->rgb, 3, 0, r, n) + mismatches(im->rgb, 3, 1, g, n) + mismatches(im->rgb, 3, 2, b, n) == 0,
               "tiled mipmap: RGB exact everywhere (no level-1 values)");
        t_true(mismatches(im->z, 1, 0, z, n) == 0, "tiled mipmap: UINT Z converted exactly");
        t_abs(im->z[n - 1], 1000.0 + 3.0 * (double)(n - 1), 0, "tiled: Z(last) from UINT");
        t_abs(im->rgb[(22 * w + 36) * 3], (double)r[22 * w + 36], 0, "tiled: R(36,22) in the corner tile");
    }
    nbt_image_free(im);
    im = NULL;
    /* one level, a 16x16 tile larger than the 13x9 image, uncompressed HALF */
    const int w2 = 13, h2 = 9;
    float *r2 = plane(w2, h2, 0), *g2 = plane(w2, h2, -1), *b2 = plane(w2, h2, 4);
    wch c3[] = {{"R", EXR_PIXEL_HALF, r2, 0, 0}, {"G", EXR_PIXEL_HALF, g2, 0, 0}, {"B", EXR_PIXEL_HALF, b2, 0, 0}};
    wpart p2 = {EXR_STORAGE_TILED, EXR_COMPRESSION_NONE, 0, 0, w2, h2, 0, 16, 16, EXR_TILE_ONE_LEVEL, c3, 3, NULL, NULL};
    t_true(write_exr(path, &p2, 1) == 0, "tiled one level: test file written");
    s = nbt_image_read_exr(path, &im, err, sizeof err);
    t_true(s == NBT_OK && im && im->w == (size_t)w2 && im->h == (size_t)h2 && !im->z, "tiled one level: read (%s)",
           err);
    if (im) {
        size_t n = (size_t)w2 * (size_t)h2;
        t_true(mismatches(im->rgb, 3, 0, r2, n) + mismatches(im->rgb, 3, 1, g2, n) + mismatches(im->rgb, 3, 2, b2, n) ==
                   0,
               "tiled one level: RGB exact");
    }
    nbt_image_free(im);
    unlink(path);
    free(r), free(g), free(b), free(z), free(r2), free(g2), free(b2);
}

static void test_origin(void)
{
    const int w = 37, h = 40;
    float *r = plane(w, h, 0), *g = plane(w, h, 1), *b = plane(w, h, 2);
    wch c3[] = {{"R", EXR_PIXEL_FLOAT, r, 0, 0}, {"G", EXR_PIXEL_FLOAT, g, 0, 0}, {"B", EXR_PIXEL_FLOAT, b, 0, 0}};
    /* data window (-5, 7) - (31, 46) inside a (0,0)-(46,49) display window: 3 ZIP chunks */
    wpart p = scan(w, h, EXR_COMPRESSION_ZIP, c3, 3);
    p.x0 = -5;
    p.y0 = 7;
    p.disp = 1;
    const char *path = in_dir("origin.exr");
    nbt_image *im = NULL;
    char err[512] = "";
    t_true(write_exr(path, &p, 1) == 0, "origin: test file written");
    nbt_status s = nbt_image_read_exr(path, &im, err, sizeof err);
    t_true(s == NBT_OK && im && im->w == (size_t)w && im->h == (size_t)h, "origin: image is the %dx%d data window (%s)",
           w, h, err);
    if (im && im->w == (size_t)w && im->h == (size_t)h) {
        size_t n = (size_t)w * (size_t)h;
        t_true(mismatches(im->rgb, 3, 0, r, n) + mismatches(im->rgb, 3, 1, g, n) + mismatches(im->rgb, 3, 2, b, n) == 0,
               "origin: RGB exact, row 0 = data window top");
        t_abs(im->rgb[0], (double)r[0], 0, "origin: R(0,0) is data window pixel (-5, 7)");
        t_abs(im->rgb[(39 * w + 36) * 3 + 1], (double)g[39 * w + 36], 0, "origin: G(36,39) is pixel (31, 46)");
    }
    nbt_image_free(im);
    unlink(path);
    free(r), free(g), free(b);
}

static void test_blender(void)
{
    const int w = 21, h = 19;
    size_t n = (size_t)w * (size_t)h;
    float *cr = plane(w, h, 0), *cg = plane(w, h, 1), *cb = plane(w, h, 2), *ca = plane(w, h, 3);
    float *dr = plane(w, h, 40), *depth = plane(w, h, 500), *nx = plane(w, h, -7), *mist = plane(w, h, 60);
    wch ch[] = {{"ViewLayer.Combined.A", EXR_PIXEL_HALF, ca, 0, 0}, {"ViewLayer.Combined.B", EXR_PIXEL_HALF, cb, 0, 0},
                {"ViewLayer.Combined.G", EXR_PIXEL_HALF, cg, 0, 0}, {"ViewLayer.Combined.R", EXR_PIXEL_HALF, cr, 0, 0},
                {"ViewLayer.Depth.Z", EXR_PIXEL_FLOAT, depth, 0, 0}, {"ViewLayer.DiffCol.B", EXR_PIXEL_HALF, dr, 0, 0},
                {"ViewLayer.DiffCol.G", EXR_PIXEL_HALF, dr, 0, 0},   {"ViewLayer.DiffCol.R", EXR_PIXEL_HALF, dr, 0, 0},
                {"ViewLayer.Mist.Z", EXR_PIXEL_FLOAT, mist, 0, 0},   {"ViewLayer.Normal.X", EXR_PIXEL_FLOAT, nx, 0, 0},
                {"ViewLayer.Normal.Y", EXR_PIXEL_FLOAT, nx, 0, 0},   {"ViewLayer.Normal.Z", EXR_PIXEL_FLOAT, nx, 0, 0}};
    wpart p = scan(w, h, EXR_COMPRESSION_ZIP, ch, 12);
    const char *path = in_dir("blender.exr");
    nbt_image *im = NULL;
    char err[512] = "";
    t_true(write_exr(path, &p, 1) == 0, "blender: test file written");
    nbt_status s = nbt_image_read_exr(path, &im, err, sizeof err);
    t_true(s == NBT_OK && im && im->z, "blender multilayer: read with depth (%s)", err);
    if (im && im->z) {
        t_true(mismatches(im->rgb, 3, 0, cr, n) + mismatches(im->rgb, 3, 1, cg, n) + mismatches(im->rgb, 3, 2, cb, n) ==
                   0,
               "blender: RGB from ViewLayer.Combined (not DiffCol)");
        t_true(mismatches(im->z, 1, 0, depth, n) == 0, "blender: Z from ViewLayer.Depth.Z (not Mist, not Normal)");
        t_abs(im->rgb[3], (double)cr[1], 0, "blender: R(1,0)");
        t_abs(im->z[n - 1], (double)depth[n - 1], 0, "blender: Z(last)");
    }
    nbt_image_free(im);
    im = NULL;

    /* one layer with a vector but no depth: no Z (Normal.Z is not depth) */
    wch ch2[] = {{"Foo.B", EXR_PIXEL_FLOAT, cb, 0, 0},        {"Foo.G", EXR_PIXEL_FLOAT, cg, 0, 0},
                 {"Foo.Normal.X", EXR_PIXEL_FLOAT, nx, 0, 0}, {"Foo.Normal.Y", EXR_PIXEL_FLOAT, nx, 0, 0},
                 {"Foo.Normal.Z", EXR_PIXEL_FLOAT, nx, 0, 0}, {"Foo.R", EXR_PIXEL_FLOAT, cr, 0, 0}};
    p = scan(w, h, EXR_COMPRESSION_NONE, ch2, 6);
    t_true(write_exr(path, &p, 1) == 0, "layer+normal: test file written");
    s = nbt_image_read_exr(path, &im, err, sizeof err);
    t_true(s == NBT_OK && im && !im->z, "layer Foo with normals: read, no Z (%s)", err);
    if (im)
        t_true(mismatches(im->rgb, 3, 0, cr, n) + mismatches(im->rgb, 3, 2, cb, n) == 0, "layer Foo: R, B exact");
    nbt_image_free(im);
    im = NULL;

    /* two Combined layers: ambiguous */
    wch ch3[] = {{"A.Combined.B", EXR_PIXEL_HALF, cb, 0, 0}, {"A.Combined.G", EXR_PIXEL_HALF, cg, 0, 0},
                 {"A.Combined.R", EXR_PIXEL_HALF, cr, 0, 0}, {"B.Combined.B", EXR_PIXEL_HALF, cb, 0, 0},
                 {"B.Combined.G", EXR_PIXEL_HALF, cg, 0, 0}, {"B.Combined.R", EXR_PIXEL_HALF, cr, 0, 0}};
    p = scan(w, h, EXR_COMPRESSION_ZIP, ch3, 6);
    t_true(write_exr(path, &p, 1) == 0, "two layers: test file written");
    s = nbt_image_read_exr(path, &im, err, sizeof err);
    t_true(s == NBT_EFORMAT && !im && strstr(err, "ambiguous") && strstr(err, "A.Combined") && strstr(err, "B.Combined"),
           "two Combined layers: EFORMAT naming both (%s)", err);
    nbt_image_free(im);
    im = NULL;

    /* plain R, G, B with "Depth.Z" and "Mist.Z": depth from Depth.Z */
    wch ch4[] = {{"B", EXR_PIXEL_HALF, cb, 0, 0},         {"Depth.Z", EXR_PIXEL_FLOAT, depth, 0, 0},
                 {"G", EXR_PIXEL_HALF, cg, 0, 0},         {"Mist.Z", EXR_PIXEL_FLOAT, mist, 0, 0},
                 {"R", EXR_PIXEL_HALF, cr, 0, 0}};
    p = scan(w, h, EXR_COMPRESSION_ZIP, ch4, 5);
    t_true(write_exr(path, &p, 1) == 0, "Depth.Z: test file written");
    s = nbt_image_read_exr(path, &im, err, sizeof err);
    t_true(s == NBT_OK && im && im->z, "R, G, B, Depth.Z, Mist.Z: read with depth (%s)", err);
    if (im && im->z)
        t_true(mismatches(im->z, 1, 0, depth, n) == 0 && mismatches(im->rgb, 3, 1, cg, n) == 0,
               "Depth.Z: Z from Depth.Z, G exact");
    nbt_image_free(im);
    im = NULL;

    /* no Depth.Z: a lone "*.Z" is depth, Mist.Z is not */
    wch ch6[] = {{"B", EXR_PIXEL_HALF, cb, 0, 0}, {"G", EXR_PIXEL_HALF, cg, 0, 0}, {"Mist.Z", EXR_PIXEL_FLOAT, mist, 0, 0},
                 {"R", EXR_PIXEL_HALF, cr, 0, 0}, {"zbuf.Z", EXR_PIXEL_FLOAT, depth, 0, 0}};
    p = scan(w, h, EXR_COMPRESSION_ZIP, ch6, 5);
    t_true(write_exr(path, &p, 1) == 0, "zbuf.Z: test file written");
    s = nbt_image_read_exr(path, &im, err, sizeof err);
    t_true(s == NBT_OK && im && im->z, "R, G, B, Mist.Z, zbuf.Z: read with depth (%s)", err);
    if (im && im->z)
        t_true(mismatches(im->z, 1, 0, depth, n) == 0, "zbuf.Z: Z from zbuf.Z, not Mist.Z");
    nbt_image_free(im);
    im = NULL;

    /* two depth passes and no way to choose: ambiguous */
    wch ch5[] = {{"B", EXR_PIXEL_HALF, cb, 0, 0}, {"G", EXR_PIXEL_HALF, cg, 0, 0}, {"R", EXR_PIXEL_HALF, cr, 0, 0},
                 {"a.Depth.Z", EXR_PIXEL_FLOAT, depth, 0, 0}, {"b.Depth.Z", EXR_PIXEL_FLOAT, mist, 0, 0}};
    p = scan(w, h, EXR_COMPRESSION_ZIP, ch5, 5);
    t_true(write_exr(path, &p, 1) == 0, "two depths: test file written");
    s = nbt_image_read_exr(path, &im, err, sizeof err);
    t_true(s == NBT_EFORMAT && !im && strstr(err, "ambiguous depth"), "two *.Depth.Z: EFORMAT (%s)", err);
    nbt_image_free(im);
    unlink(path);
    free(cr), free(cg), free(cb), free(ca), free(dr), free(depth), free(nx), free(mist);
}

static void test_grey_and_parts(void)
{
    const int w = 9, h = 17;
    size_t n = (size_t)w * (size_t)h;
    float *y = plane(w, h, 0.25f), *a = plane(w, h, 1), *r = plane(w, h, 2), *g = plane(w, h, 3), *b = plane(w, h, 4);
    wch cy[] = {{"A", EXR_PIXEL_HALF, a, 0, 0}, {"Y", EXR_PIXEL_HALF, y, 0, 0}};
    wpart p = scan(w, h, EXR_COMPRESSION_ZIP, cy, 2);
    const char *path = in_dir("grey.exr");
    nbt_image *im = NULL;
    char err[512] = "";
    t_true(write_exr(path, &p, 1) == 0, "grey: test file written");
    nbt_status s = nbt_image_read_exr(path, &im, err, sizeof err);
    t_true(s == NBT_OK && im && !im->z, "Y only: read (%s)", err);
    if (im) {
        t_true(mismatches(im->rgb, 3, 0, y, n) + mismatches(im->rgb, 3, 1, y, n) + mismatches(im->rgb, 3, 2, y, n) == 0,
               "Y only: R = G = B = Y");
        t_abs(im->rgb[3 * 4 + 1], (double)y[4], 0, "Y only: G(4,0)");
    }
    nbt_image_free(im);
    im = NULL;

    /* two parts: the first without colour, the second with R, G, B */
    wch c0[] = {{"A", EXR_PIXEL_FLOAT, a, 0, 0}};
    wch c1[] = {{"B", EXR_PIXEL_FLOAT, b, 0, 0}, {"G", EXR_PIXEL_FLOAT, g, 0, 0}, {"R", EXR_PIXEL_FLOAT, r, 0, 0}};
    wpart parts[2] = {scan(w, h, EXR_COMPRESSION_ZIP, c0, 1), scan(w, h, EXR_COMPRESSION_NONE, c1, 3)};
    t_true(write_exr(path, parts, 2) == 0, "multipart: test file written");
    s = nbt_image_read_exr(path, &im, err, sizeof err);
    t_true(s == NBT_OK && im, "multipart: read the part with R, G, B (%s)", err);
    if (im)
        t_true(mismatches(im->rgb, 3, 0, r, n) + mismatches(im->rgb, 3, 1, g, n) + mismatches(im->rgb, 3, 2, b, n) == 0,
               "multipart: RGB of part 1 exact");
    nbt_image_free(im);
    unlink(path);
    free(y), free(a), free(r), free(g), free(b);
}

static void test_errors(void)
{
    char err[512];
    nbt_image *im = (nbt_image *)&err; /* must be reset to NULL */
    const int w = 8, h = 6;
    float *a = plane(w, h, 0), *v = plane(w, h, 1);

    /* missing file */
    const char *missing = in_dir("does-not-exist.exr");
    handler_calls = 0;
    nbt_error_handler *old = nbt_set_error_handler(on_error);
    nbt_status s = nbt_image_read_exr(missing, &im, err, sizeof err);
    t_true(s == NBT_EIO && im == NULL, "missing file: NBT_EIO, *out NULL (%d)", (int)s);
    t_true(strstr(err, missing) && strstr(err, strerror(ENOENT)), "missing file: message names it and says why (%s)",
           err);
    t_true(handler_calls == 1 && handler_status == NBT_EIO && !strcmp(handler_reason, err),
           "missing file: error handler got the same line");
    nbt_set_error_handler(old);

    /* a directory */
    im = (nbt_image *)&err;
    s = nbt_image_read_exr(dir, &im, err, sizeof err);
    t_true(s == NBT_EIO && im == NULL && strstr(err, dir), "directory: NBT_EIO (%s)", err);

    /* not an EXR */
    const char *text = in_dir("text.exr");
    FILE *f = fopen(text, "w");
    fputs("this is not an OpenEXR file, just some text long enough to be read as a header\n", f);
    fclose(f);
    s = nbt_image_read_exr(text, &im, err, sizeof err);
    t_true(s == NBT_EFORMAT && im == NULL && strstr(err, text), "text file: NBT_EFORMAT (%s)", err);
    unlink(text);

    /* no R, G, B */
    const char *nocol = in_dir("nocolour.exr");
    wch cn[] = {{"A", EXR_PIXEL_HALF, a, 0, 0}, {"Y2", EXR_PIXEL_FLOAT, v, 0, 0}};
    wpart p = scan(w, h, EXR_COMPRESSION_ZIP, cn, 2);
    t_true(write_exr(nocol, &p, 1) == 0, "no colour: test file written");
    s = nbt_image_read_exr(nocol, &im, err, sizeof err);
    t_true(s == NBT_EFORMAT && im == NULL, "no R, G, B: NBT_EFORMAT (%d)", (int)s);
    t_true(strstr(err, nocol) && strstr(err, "no R, G, B channels (found: A, Y2)"),
           "no R, G, B: message names the file and the channels (%s)", err);
    unlink(nocol);

    /* R and G only */
    wch crg[] = {{"G", EXR_PIXEL_HALF, a, 0, 0}, {"R", EXR_PIXEL_HALF, v, 0, 0}};
    p = scan(w, h, EXR_COMPRESSION_NONE, crg, 2);
    t_true(write_exr(nocol, &p, 1) == 0, "R, G only: test file written");
    s = nbt_image_read_exr(nocol, &im, err, sizeof err);
    t_true(s == NBT_EFORMAT && im == NULL && strstr(err, "found: G, R"), "R, G only: NBT_EFORMAT (%s)", err);
    unlink(nocol);

    /* subsampled B */
    float *sub = plane(w / 2, h / 2, 0);
    wch cs[] = {{"B", EXR_PIXEL_HALF, sub, 2, 2}, {"G", EXR_PIXEL_HALF, a, 0, 0}, {"R", EXR_PIXEL_HALF, v, 0, 0}};
    const char *subp = in_dir("sub.exr");
    p = scan(w, h, EXR_COMPRESSION_ZIP, cs, 3);
    t_true(write_exr(subp, &p, 1) == 0, "subsampled: test file written");
    s = nbt_image_read_exr(subp, &im, err, sizeof err);
    t_true(s == NBT_EFORMAT && im == NULL && strstr(err, "channel B is subsampled"), "subsampled B: NBT_EFORMAT (%s)",
           err);
    /* luminance/chroma */
    wch cl[] = {{"BY", EXR_PIXEL_HALF, sub, 2, 2}, {"RY", EXR_PIXEL_HALF, sub, 2, 2}, {"Y", EXR_PIXEL_HALF, a, 0, 0}};
    p = scan(w, h, EXR_COMPRESSION_ZIP, cl, 3);
    t_true(write_exr(subp, &p, 1) == 0, "Y/RY/BY: test file written");
    s = nbt_image_read_exr(subp, &im, err, sizeof err);
    t_true(s == NBT_EFORMAT && im == NULL && strstr(err, "RY"), "Y, RY, BY: NBT_EFORMAT (%s)", err);
    unlink(subp);
    free(sub);

    /* truncated files: an error, never a crash */
    nbt_image *big = nbt_image_alloc(64, 48, 1);
    for (size_t i = 0; i < 64 * 48 * 3; i++)
        big->rgb[i] = (float)t_uniform();
    for (size_t i = 0; i < 64 * 48; i++)
        big->z[i] = (float)t_uniform();
    const char *tr = in_dir("trunc.exr");
    s = nbt_image_write_exr(big, tr, NULL, 0, err, sizeof err);
    long full = file_size(tr);
    t_true(s == NBT_OK && full > 20000, "truncated: full file written (%ld bytes)", full);
    const long cut[] = {full / 2, full - 1, full * 9 / 10, full / 10, 400, 100, 20, 0};
    for (size_t k = 0; k < sizeof cut / sizeof cut[0]; k++) {
        s = nbt_image_write_exr(big, tr, NULL, 0, err, sizeof err);
        if (s != NBT_OK || truncate(tr, cut[k]) != 0) {
            t_true(0, "truncated: cannot prepare %ld bytes", cut[k]);
            continue;
        }
        im = (nbt_image *)&err;
        err[0] = '\0';
        s = nbt_image_read_exr(tr, &im, err, sizeof err);
        t_true(s == NBT_EFORMAT && im == NULL && strstr(err, tr) != NULL,
               "truncated to %ld of %ld bytes: NBT_EFORMAT, no image (%s)", cut[k], full, err);
    }
    unlink(tr);

    /* writing into a directory that does not exist */
    const char *nodir = in_dir("no/such/dir/out.exr");
    int before = count_entries(dir);
    s = nbt_image_write_exr(big, nodir, NULL, 0, err, sizeof err);
    t_true(s == NBT_EIO && strstr(err, nodir) && strstr(err, strerror(ENOENT)),
           "write into a missing directory: NBT_EIO naming the path (%s)", err);
    t_true(file_size(nodir) < 0 && count_entries(dir) == before, "write into a missing directory: nothing created");

    /* the target is a directory: rename fails, the temporary file goes */
    const char *sub_dir = in_dir("adir");
    mkdir(sub_dir, 0755);
    before = count_entries(dir);
    s = nbt_image_write_exr(big, sub_dir, NULL, 0, err, sizeof err);
    t_true(s == NBT_EIO && strstr(err, sub_dir), "write over a directory: NBT_EIO (%s)", err);
    t_true(count_entries(dir) == before && count_entries(sub_dir) == 0,
           "write over a directory: no temporary file left (%d entries)", count_entries(dir));
    rmdir(sub_dir);

    /* an existing file survives a failed write untouched */
    const char *keep = in_dir("keep.exr");
    nbt_image *one = nbt_image_alloc(1, 1, 0);
    one->rgb[0] = 42.0f;
    s = nbt_image_write_exr(one, keep, NULL, 0, err, sizeof err);
    const char *bad_attrs[] = {"nbt.x", NULL};
    before = count_entries(dir);
    s = nbt_image_write_exr(big, keep, bad_attrs, 1, err, sizeof err);
    t_true(s == NBT_EINVAL && strstr(err, keep) && count_entries(dir) == before,
           "attribute without a value: NBT_EINVAL, nothing created (%s)", err);
    const char *std_attr[] = {"compression", "zip"}; /* a standard attribute of another type: the library refuses */
    s = nbt_image_write_exr(big, keep, std_attr, 1, err, sizeof err);
    t_true(s == NBT_EINVAL && strstr(err, "compression") && count_entries(dir) == before,
           "attribute clashing with a standard one: NBT_EINVAL, nothing left (%s)", err);
    s = nbt_image_read_exr(keep, &im, err, sizeof err);
    t_true(s == NBT_OK && im && im->w == 1 && im->h == 1, "failed writes left the old file (%s)", err);
    if (im)
        t_abs(im->rgb[0], 42.0, 0, "old file: R(0,0) = 42");
    nbt_image_free(im);
    unlink(keep);
    nbt_image_free(one);

    nbt_image empty = {.w = 0, .rgb = NULL};
    s = nbt_image_write_exr(&empty, keep, NULL, 0, err, sizeof err);
    t_true(s == NBT_EINVAL && file_size(keep) < 0, "empty image: NBT_EINVAL (%s)", err);
    nbt_image_free(big);
    free(a), free(v);
}

/* ---- overscan, kept channels and attributes, nbt_image_write_exr_ex ---- */

static exr_attr_box2i_t ebox(int x0, int y0, int x1, int y1)
{
    exr_attr_box2i_t b;
    b.min.x = x0, b.min.y = y0, b.max.x = x1, b.max.y = y1;
    return b;
}

static exr_result_t overscan_attrs(exr_context_t ctx, int p)
{
    exr_attr_m44f_t m;
    for (int i = 0; i < 16; i++)
        m.m[i] = (float)(i + 1) / 8.0f - 1.0f;
    exr_attr_v2f_t v;
    v.x = -1.5f, v.y = 2.25f;
    const char *sv[2] = {"left", "right eye"};
    exr_result_t rv = exr_attr_set_string(ctx, p, "owner", "nbt test");
    if (rv == EXR_ERR_SUCCESS)
        rv = exr_attr_set_int(ctx, p, "test.count", -12345);
    if (rv == EXR_ERR_SUCCESS)
        rv = exr_attr_set_float(ctx, p, "test.fov", 0.6789f);
    if (rv == EXR_ERR_SUCCESS)
        rv = exr_attr_set_m44f(ctx, p, "worldToCamera", &m);
    if (rv == EXR_ERR_SUCCESS)
        rv = exr_attr_set_v2f(ctx, p, "test.v2f", &v);
    if (rv == EXR_ERR_SUCCESS)
        rv = exr_attr_set_string_vector(ctx, p, "test.sv", 2, sv);
    if (rv == EXR_ERR_SUCCESS) { /* a 3 x 2 preview with every byte distinct */
        static uint8_t px[3 * 2 * 4];
        for (int i = 0; i < 24; i++)
            px[i] = (uint8_t)(7 * i + 3);
        exr_attr_preview_t pv;
        memset(&pv, 0, sizeof pv);
        pv.width = 3, pv.height = 2, pv.rgba = px;
        rv = exr_attr_set_preview(ctx, p, "preview", &pv);
    }
    if (rv == EXR_ERR_SUCCESS) /* cube (1), not the zero that a byte beside it would read as */
        rv = exr_attr_set_envmap(ctx, p, "envmap", EXR_ENVMAP_CUBE);
    if (rv == EXR_ERR_SUCCESS)
        rv = exr_set_pixel_aspect_ratio(ctx, p, 1.25f);
    if (rv == EXR_ERR_SUCCESS)
        rv = exr_set_screen_window_width(ctx, p, 0.75f);
    return rv;
}

/* Checks the header of a file written from the overscan input, with the
 * core library: windows, channel names and types, attributes. */
static void check_header(const char *path, const char *what, const exr_attr_box2i_t *dw_want,
                         const exr_attr_box2i_t *disp_want, const char *const *names, const exr_pixel_type_t *types,
                         int nnames, const char *owner)
{
    exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
    init.error_handler_fn = quiet;
    exr_context_t ctx = NULL;
    if (exr_start_read(&ctx, path, &init) != EXR_ERR_SUCCESS) {
        t_true(0, "%s: written file readable by the core library", what);
        return;
    }
    exr_attr_box2i_t dw, disp;
    exr_get_data_window(ctx, 0, &dw);
    exr_get_display_window(ctx, 0, &disp);
    t_true(dw.min.x == dw_want->min.x && dw.min.y == dw_want->min.y && dw.max.x == dw_want->max.x &&
               dw.max.y == dw_want->max.y,
           "%s: data window (%d, %d) - (%d, %d)", what, dw.min.x, dw.min.y, dw.max.x, dw.max.y);
    t_true(disp.min.x == disp_want->min.x && disp.min.y == disp_want->min.y && disp.max.x == disp_want->max.x &&
               disp.max.y == disp_want->max.y,
           "%s: display window (%d, %d) - (%d, %d)", what, disp.min.x, disp.min.y, disp.max.x, disp.max.y);
    const exr_attr_chlist_t *cl = NULL;
    exr_get_channels(ctx, 0, &cl);
    int ok = cl && cl->num_channels == nnames;
    for (int i = 0; ok && i < nnames; i++) {
        int found = 0;
        for (int j = 0; j < cl->num_channels; j++)
            if (!strcmp(cl->entries[j].name.str, names[i]) && cl->entries[j].pixel_type == types[i])
                found = 1;
        if (!found) {
            printf("      channel %s of type %d missing\n", names[i], (int)types[i]);
            ok = 0;
        }
    }
    t_true(ok, "%s: %d channels with their names and types (file has %d)", what, nnames, cl ? cl->num_channels : -1);
    const char *s = NULL;
    int32_t len = 0, iv = 0, nsv = 2;
    float f = 0, par = 0, sww = 0;
    exr_attr_m44f_t m;
    exr_attr_v2f_t v;
    v.x = v.y = 0.0f;
    const char *sv[2] = {NULL, NULL};
    memset(&m, 0, sizeof m);
    exr_attr_get_string(ctx, 0, "owner", &len, &s);
    exr_attr_get_int(ctx, 0, "test.count", &iv);
    exr_attr_get_float(ctx, 0, "test.fov", &f);
    exr_attr_get_m44f(ctx, 0, "worldToCamera", &m);
    exr_attr_get_v2f(ctx, 0, "test.v2f", &v);
    exr_attr_get_string_vector(ctx, 0, "test.sv", &nsv, sv);
    exr_get_pixel_aspect_ratio(ctx, 0, &par);
    exr_get_screen_window_width(ctx, 0, &sww);
    exr_envmap_t em = EXR_ENVMAP_LATLONG;
    exr_result_t emr = exr_attr_get_envmap(ctx, 0, "envmap", &em);
    t_true(s && !strcmp(s, owner), "%s: string attribute owner = \"%s\" (got %s)", what, owner, s ? s : "none");
    t_true(iv == -12345 && f == 0.6789f, "%s: int and float attributes copied (%d, %.9g)", what, iv, (double)f);
    t_true(m.m[0] == -0.875f && m.m[6] == -0.125f && m.m[15] == 1.0f, "%s: m44f attribute copied", what);
    t_true(v.x == -1.5f && v.y == 2.25f, "%s: v2f attribute copied", what);
    t_true(nsv == 2 && sv[0] && !strcmp(sv[0], "left") && sv[1] && !strcmp(sv[1], "right eye"),
           "%s: string vector attribute copied", what);
    t_true(par == 1.25f && sww == 0.75f, "%s: pixelAspectRatio and screenWindowWidth kept (%g, %g)", what, (double)par,
           (double)sww);
    t_true(emr == EXR_ERR_SUCCESS && em == EXR_ENVMAP_CUBE, "%s: envmap attribute kept as cube (%d, read %d)", what,
           (int)em, (int)emr);
    exr_attr_preview_t pv;
    memset(&pv, 0, sizeof pv);
    int pok = exr_attr_get_preview(ctx, 0, "preview", &pv) == EXR_ERR_SUCCESS && pv.width == 3 && pv.height == 2 && pv.rgba;
    for (int i = 0; pok && i < 24; i++)
        pok = pv.rgba[i] == (uint8_t)(7 * i + 3);
    t_true(pok, "%s: the 3 x 2 preview attribute copied byte for byte", what);
    exr_finish(&ctx);
}

static const nbt_image_channel *find_kept(const nbt_image *im, const char *name)
{
    for (size_t i = 0; i < im->nchannels; i++)
        if (!strcmp(im->channels[i].name, name))
            return &im->channels[i];
    return NULL;
}

static void test_overscan(void)
{
    /* data window (-7, -5) - (37, 25): 45 x 31, around a 30 x 20 display
     * window (0, 0) - (29, 19) with unequal margins 7, 8 (x) and 5, 6 (y) */
    const int w = 45, h = 31, X0 = -7, Y0 = -5, DW = 30, DH = 20;
    size_t n = (size_t)w * (size_t)h;
    float *r = plane(w, h, 0), *g = plane(w, h, 1), *b = plane(w, h, 2), *z = plane(w, h, 500);
    float *a = plane(w, h, 3), *ev = plane(w, h, 0.3f), *idv = malloc(n * sizeof(float));
    for (size_t i = 0; i < n; i++)
        idv[i] = (float)(i * 3 + 1);
    wch ch[] = {{"R", EXR_PIXEL_FLOAT, r, 0, 0},       {"G", EXR_PIXEL_FLOAT, g, 0, 0},
                {"B", EXR_PIXEL_FLOAT, b, 0, 0},       {"Z", EXR_PIXEL_FLOAT, z, 0, 0},
                {"A", EXR_PIXEL_HALF, a, 0, 0},        {"extra.V", EXR_PIXEL_FLOAT, ev, 0, 0},
                {"id", EXR_PIXEL_UINT, idv, 0, 0}};
    exr_attr_box2i_t disp = ebox(0, 0, DW - 1, DH - 1);
    wpart p = scan(w, h, EXR_COMPRESSION_ZIP, ch, 7);
    p.x0 = X0;
    p.y0 = Y0;
    p.dispbox = &disp;
    p.attrs = overscan_attrs;
    const char *in = in_dir("overscan.exr"), *out = in_dir("overscan_out.exr"), *full = in_dir("overscan_full.exr");
    char err[512] = "";
    nbt_image *im = NULL, *o = NULL;
    t_true(write_exr(in, &p, 1) == 0, "overscan: test file written");
    nbt_status s = nbt_image_read_exr(in, &im, err, sizeof err);
    t_true(s == NBT_OK && im && im->w == (size_t)w && im->h == (size_t)h, "overscan: read the 45 x 31 data window (%s)",
           err);
    if (!im || im->w != (size_t)w || im->h != (size_t)h)
        goto end;
    t_true(im->x0 == X0 && im->y0 == Y0, "overscan: origin (%d, %d)", im->x0, im->y0);
    t_true(im->display.min_x == 0 && im->display.min_y == 0 && im->display.max_x == DW - 1 &&
               im->display.max_y == DH - 1,
           "overscan: display window (%d, %d) - (%d, %d)", im->display.min_x, im->display.min_y, im->display.max_x,
           im->display.max_y);
    t_true(im->z && mismatches(im->rgb, 3, 0, r, n) + mismatches(im->rgb, 3, 2, b, n) + mismatches(im->z, 1, 0, z, n) == 0,
           "overscan: RGB and Z exact");
    t_true(!im->rgb_layer && !im->z_name, "overscan: plain names");
    t_true(im->nchannels == 3, "overscan: 3 other channels kept (%zu)", im->nchannels);
    const nbt_image_channel *ka = find_kept(im, "A"), *ke = find_kept(im, "extra.V"), *ki = find_kept(im, "id");
    t_true(ka && ka->type == NBT_PIXEL_HALF && ke && ke->type == NBT_PIXEL_FLOAT && ki && ki->type == NBT_PIXEL_UINT,
           "overscan: A HALF, extra.V FLOAT, id UINT kept in their types");
    if (ka && ke && ki && ka->data && ke->data && ki->data) {
        size_t bad = 0;
        for (size_t i = 0; i < n; i++)
            bad += ((const uint16_t *)ka->data)[i] != f2h(a[i]) || ((const float *)ke->data)[i] != ev[i] ||
                   ((const uint32_t *)ki->data)[i] != (uint32_t)idv[i];
        t_true(bad == 0, "overscan: kept channels' values exact (%zu wrong)", bad);
    }
    const char *tn = NULL;
    int has_m44 = 0;
    for (size_t i = 0; i < nbt_image_attr_count(im); i++)
        if (!strcmp(nbt_image_attr_name(im, i, &tn), "worldToCamera"))
            has_m44 = !strcmp(tn, "m44f");
    t_true(nbt_image_attr_count(im) == 11, "overscan: 11 attributes kept (%zu)", nbt_image_attr_count(im));
    t_true(has_m44 && nbt_image_attr_string(im, "owner") && !strcmp(nbt_image_attr_string(im, "owner"), "nbt test") &&
               !nbt_image_attr_string(im, "test.count") && !nbt_image_attr_name(im, 11, NULL),
           "overscan: attribute names, types, string value");

    /* the caller's layers over the data window: S (3), offscreen (1) */
    float *sl = malloc(n * 3 * sizeof(float)), *off = malloc(n * sizeof(float)), *ex = malloc(n * sizeof(float));
    for (size_t i = 0; i < n; i++) {
        for (int c = 0; c < 3; c++)
            sl[3 * i + (size_t)c] = 0.01f * (float)i - 0.5f * (float)c;
        off[i] = (float)(i % 13) / 16.0f;
        ex[i] = -(float)i;
    }
    const char *rgbn[3] = {"R", "G", "B"}, *xn[1] = {"X"}, *vn[1] = {"V"};
    nbt_image_layer layers[3] = {{"S", 3, rgbn, sl}, {"offscreen", 1, xn, off}, {"extra", 1, vn, ex}};
    const char *attrs[4] = {"nbt.method", "crop", "owner", "nbt-scatter"};
    nbt_exr_write_opts wo;
    memset(&wo, 0, sizeof wo);
    wo.window = &im->display;
    wo.layers = layers;
    wo.nlayers = 3;
    wo.attrs = attrs;
    wo.nattrs = 1;
    s = nbt_image_write_exr_ex(im, out, &wo, err, sizeof err);
    t_true(s == NBT_OK, "overscan: display window written (%s)", err);
    static const char *const names[] = {"A", "B", "G", "R", "Z", "S.R", "S.G", "S.B", "offscreen.X", "extra.V", "id"};
    static const exr_pixel_type_t types[] = {EXR_PIXEL_HALF,  EXR_PIXEL_FLOAT, EXR_PIXEL_FLOAT, EXR_PIXEL_FLOAT,
                                             EXR_PIXEL_FLOAT, EXR_PIXEL_FLOAT, EXR_PIXEL_FLOAT, EXR_PIXEL_FLOAT,
                                             EXR_PIXEL_FLOAT, EXR_PIXEL_FLOAT, EXR_PIXEL_UINT};
    check_header(out, "crop", &disp, &disp, names, types, 11, "nbt test");
    s = nbt_image_read_exr(out, &o, err, sizeof err);
    t_true(s == NBT_OK && o && o->w == (size_t)DW && o->h == (size_t)DH && o->x0 == 0 && o->y0 == 0,
           "crop: reads back as the 30 x 20 display window (%s)", err);
    if (o && o->w == (size_t)DW && o->h == (size_t)DH) {
        const nbt_image_channel *oa = find_kept(o, "A"), *osr = find_kept(o, "S.R"), *osb = find_kept(o, "S.B"),
                                *oof = find_kept(o, "offscreen.X"), *oev = find_kept(o, "extra.V"),
                                *oid = find_kept(o, "id");
        size_t bad = 0, checked = 0;
        if (oa && osr && osb && oof && oev && oid && o->z)
            for (int y = 0; y < DH; y++)
                for (int x = 0; x < DW; x++) {
                    size_t i = (size_t)(y * DW + x), j = (size_t)((y - Y0) * w + (x - X0));
                    bad += o->rgb[3 * i] != r[j] || o->rgb[3 * i + 1] != g[j] || o->rgb[3 * i + 2] != b[j] ||
                           o->z[i] != z[j] || ((const uint16_t *)oa->data)[i] != f2h(a[j]) ||
                           ((const float *)osr->data)[i] != sl[3 * j] || ((const float *)osb->data)[i] != sl[3 * j + 2] ||
                           ((const float *)oof->data)[i] != off[j] || ((const float *)oev->data)[i] != ex[j] ||
                           ((const uint32_t *)oid->data)[i] != (uint32_t)idv[j];
                    checked++;
                }
        t_true(checked == (size_t)(DW * DH) && bad == 0,
               "crop: every pixel of every channel is the input's at (x+7, y+5) (%zu of %zu wrong)", bad, checked);
        t_true(nbt_image_attr_string(o, "nbt.method") && !strcmp(nbt_image_attr_string(o, "nbt.method"), "crop"),
               "crop: the caller's nbt.* attribute written");
    }
    nbt_image_free(o);
    o = NULL;

    /* the caller's string attribute replaces a kept one; the whole data window */
    wo.window = NULL;
    wo.nlayers = 0;
    wo.attrs = attrs + 2;
    wo.nattrs = 1;
    s = nbt_image_write_exr_ex(im, full, &wo, err, sizeof err);
    t_true(s == NBT_OK, "full: data window written (%s)", err);
    exr_attr_box2i_t dwin = ebox(X0, Y0, X0 + w - 1, Y0 + h - 1);
    static const char *const fnames[] = {"A", "B", "G", "R", "Z", "extra.V", "id"};
    static const exr_pixel_type_t ftypes[] = {EXR_PIXEL_HALF,  EXR_PIXEL_FLOAT, EXR_PIXEL_FLOAT, EXR_PIXEL_FLOAT,
                                              EXR_PIXEL_FLOAT, EXR_PIXEL_FLOAT, EXR_PIXEL_UINT};
    check_header(full, "full", &dwin, &disp, fnames, ftypes, 7, "nbt-scatter");
    s = nbt_image_read_exr(full, &o, err, sizeof err);
    if (s == NBT_OK && o->w == (size_t)w && o->h == (size_t)h) {
        const nbt_image_channel *oe = find_kept(o, "extra.V");
        t_true(o->x0 == X0 && o->y0 == Y0 && o->display.max_x == DW - 1 && mismatches(o->rgb, 3, 1, g, n) == 0 &&
                   oe && !memcmp(oe->data, ev, n * sizeof(float)),
               "full: round trip keeps origin, display window and values");
    } else
        t_true(0, "full: reads back (%s)", err);
    nbt_image_free(o);
    o = NULL;

    /* refusals: nothing written */
    const char *bad = in_dir("refused.exr");
    nbt_box2i outside[3] = {{X0 - 1, 0, 10, 10}, {0, 0, X0 + w, 10}, {5, 5, 4, 10}};
    for (int k = 0; k < 3; k++) {
        memset(&wo, 0, sizeof wo);
        wo.window = &outside[k];
        s = nbt_image_write_exr_ex(im, bad, &wo, err, sizeof err);
        t_true(s == NBT_EINVAL && strstr(err, "not a non-empty box inside the image's data window (-7, -5) - (37, 25)") &&
                   file_size(bad) < 0,
               "window %d outside or empty: NBT_EINVAL, nothing written (%s)", k, err);
    }
    memset(&wo, 0, sizeof wo);
    nbt_image_layer twice[2] = {{"S", 3, rgbn, sl}, {"S", 1, rgbn, off}};
    wo.layers = twice;
    wo.nlayers = 2;
    s = nbt_image_write_exr_ex(im, bad, &wo, err, sizeof err);
    t_true(s == NBT_EINVAL && strstr(err, "two channels named S.R") && file_size(bad) < 0,
           "two layers of one name: NBT_EINVAL (%s)", err);
    nbt_image_layer empty[1] = {{"S", 0, rgbn, sl}};
    wo.layers = empty;
    wo.nlayers = 1;
    s = nbt_image_write_exr_ex(im, bad, &wo, err, sizeof err);
    t_true(s == NBT_EINVAL && file_size(bad) < 0, "layer without channels: NBT_EINVAL (%s)", err);
    memset(&wo, 0, sizeof wo);
    const char *cattr[2] = {"compression", "zip"};
    wo.attrs = cattr;
    wo.nattrs = 1;
    s = nbt_image_write_exr_ex(im, bad, &wo, err, sizeof err);
    t_true(s == NBT_EINVAL && strstr(err, "compression") && file_size(bad) < 0,
           "a layout attribute as a string: NBT_EINVAL (%s)", err);

    /* a new image given the input's metadata */
    nbt_image *c = nbt_image_alloc((size_t)w, (size_t)h, 0), *c2 = nbt_image_alloc(3, 3, 0);
    t_true(c && nbt_image_copy_meta(c, im) == NBT_OK && c->x0 == X0 && c->nchannels == 3 &&
               nbt_image_attr_count(c) == 11 && nbt_image_copy_meta(c2, im) == NBT_EINVAL,
           "copy_meta: same size copied, other size refused");
    /* one side differing is enough: the channel data copied are w x h of the source */
    nbt_image *cw = nbt_image_alloc((size_t)w, (size_t)h + 1, 0), *cx = nbt_image_alloc((size_t)w - 1, (size_t)h, 0);
    t_true(cw && cx && nbt_image_copy_meta(cw, im) == NBT_EINVAL && nbt_image_copy_meta(cx, im) == NBT_EINVAL &&
               cw->nchannels == 0 && cx->nchannels == 0,
           "copy_meta: 45 x 32 and 44 x 31 refused for a 45 x 31 source, nothing copied");
    nbt_image_free(cw);
    nbt_image_free(cx);
    if (c) {
        memcpy(c->rgb, im->rgb, n * 3 * sizeof(float));
        memset(&wo, 0, sizeof wo);
        wo.window = &c->display;
        s = nbt_image_write_exr_ex(c, out, &wo, err, sizeof err);
        static const char *const cn[] = {"A", "B", "G", "R", "extra.V", "id"};
        static const exr_pixel_type_t ct[] = {EXR_PIXEL_HALF,  EXR_PIXEL_FLOAT, EXR_PIXEL_FLOAT,
                                              EXR_PIXEL_FLOAT, EXR_PIXEL_FLOAT, EXR_PIXEL_UINT};
        t_true(s == NBT_OK, "copy_meta: written (%s)", err);
        check_header(out, "copy_meta", &disp, &disp, cn, ct, 6, "nbt test");
    }
    nbt_image_free(c);
    nbt_image_free(c2);
    free(sl), free(off), free(ex);
end:
    nbt_image_free(im);
    unlink(in), unlink(out), unlink(full);
    free(r), free(g), free(b), free(z), free(a), free(ev), free(idv);
}

/* Blender's multilayer names: RGB and Z written back where they were, the
 * layers beside them in the same view layer. */
static void test_blender_names(void)
{
    nbt_image *im = nbt_image_alloc(6, 4, 1);
    const char *path = in_dir("bl_out.exr");
    char err[512] = "";
    if (!im)
        return;
    for (size_t i = 0; i < 24; i++) {
        im->rgb[3 * i] = (float)i, im->rgb[3 * i + 1] = 0.5f, im->rgb[3 * i + 2] = -1.0f;
        im->z[i] = 10.0f + (float)i;
    }
    im->rgb_layer = strdup("ViewLayer.Combined");
    im->z_name = strdup("ViewLayer.Depth.Z");
    float t[24 * 3];
    for (int i = 0; i < 72; i++)
        t[i] = (float)i / 72.0f;
    const char *rgbn[3] = {"R", "G", "B"};
    nbt_image_layer L = {"T", 3, rgbn, t};
    nbt_exr_write_opts wo;
    memset(&wo, 0, sizeof wo);
    wo.layers = &L;
    wo.nlayers = 1;
    nbt_status s = nbt_image_write_exr_ex(im, path, &wo, err, sizeof err);
    static const char *const names[] = {"ViewLayer.Combined.R", "ViewLayer.Combined.G", "ViewLayer.Combined.B",
                                        "ViewLayer.Depth.Z",    "ViewLayer.T.R",        "ViewLayer.T.G",
                                        "ViewLayer.T.B"};
    static const exr_pixel_type_t types[7] = {EXR_PIXEL_FLOAT, EXR_PIXEL_FLOAT, EXR_PIXEL_FLOAT, EXR_PIXEL_FLOAT,
                                              EXR_PIXEL_FLOAT, EXR_PIXEL_FLOAT, EXR_PIXEL_FLOAT};
    t_true(s == NBT_OK, "blender names: written (%s)", err);
    exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
    init.error_handler_fn = quiet;
    exr_context_t ctx = NULL;
    const exr_attr_chlist_t *cl = NULL;
    int found = 0;
    if (exr_start_read(&ctx, path, &init) == EXR_ERR_SUCCESS && exr_get_channels(ctx, 0, &cl) == EXR_ERR_SUCCESS)
        for (int i = 0; i < 7; i++)
            for (int j = 0; j < cl->num_channels; j++)
                found += !strcmp(cl->entries[j].name.str, names[i]) && cl->entries[j].pixel_type == types[i];
    t_true(found == 7 && cl && cl->num_channels == 7, "blender names: ViewLayer.Combined.*, ViewLayer.Depth.Z, ViewLayer.T.*");
    if (ctx)
        exr_finish(&ctx);
    nbt_image *back = NULL;
    s = nbt_image_read_exr(path, &back, err, sizeof err);
    t_true(s == NBT_OK && back && back->rgb_layer && !strcmp(back->rgb_layer, "ViewLayer.Combined") && back->z &&
               back->z[23] == 33.0f && back->rgb[3 * 5] == 5.0f && back->nchannels == 3,
           "blender names: read back picks Combined and Depth, keeps T (%s)", err);
    nbt_image_free(back);
    wo.layer_prefix = "";
    s = nbt_image_write_exr_ex(im, path, &wo, err, sizeof err);
    cl = NULL;
    found = 0;
    if (s == NBT_OK && exr_start_read(&ctx, path, &init) == EXR_ERR_SUCCESS && exr_get_channels(ctx, 0, &cl) == EXR_ERR_SUCCESS)
        for (int j = 0; j < cl->num_channels; j++)
            found += !strcmp(cl->entries[j].name.str, "T.R");
    t_true(found == 1, "blender names: layer_prefix \"\" gives T.R");
    if (ctx)
        exr_finish(&ctx);
    unlink(path);
    nbt_image_free(im);
}

/* Names over 31 characters, as Blender's Cycles writes them
 * (cycles.ViewLayer.synchronization_time): written with the file's long-names
 * flag, read back and written again; a name over 255 characters is refused
 * with the library's reason. (The writer used to wait forever on the second:
 * the library reports the error holding the lock its user-data getter takes.) */
static void test_long_names(void)
{
    nbt_image *im = nbt_image_alloc(3, 2, 1), *back = NULL, *again = NULL;
    const char *path = in_dir("long.exr"), *path2 = in_dir("long2.exr");
    char err[512] = "", name300[301];
    if (!im)
        return;
    for (size_t i = 0; i < 6; i++)
        im->rgb[3 * i] = im->rgb[3 * i + 1] = im->rgb[3 * i + 2] = (float)i, im->z[i] = 2.5f;
    const char *attrs[] = {"cycles.ViewLayer.synchronization_time", "00:00.31"};
    nbt_exr_write_opts wo;
    memset(&wo, 0, sizeof wo);
    wo.attrs = attrs;
    wo.nattrs = 1;
    nbt_status s = nbt_image_write_exr_ex(im, path, &wo, err, sizeof err);
    t_true(s == NBT_OK, "long names: a 37-character attribute name is written (%s)", err);
    s = nbt_image_read_exr(path, &back, err, sizeof err);
    const char *v = s == NBT_OK ? nbt_image_attr_string(back, "cycles.ViewLayer.synchronization_time") : NULL;
    t_true(v && !strcmp(v, "00:00.31"), "long names: read back (%s)", err);
    memset(&wo, 0, sizeof wo); /* kept, not the caller's: written again from what was read */
    s = back ? nbt_image_write_exr_ex(back, path2, &wo, err, sizeof err) : NBT_EINVAL;
    v = s == NBT_OK && nbt_image_read_exr(path2, &again, err, sizeof err) == NBT_OK
            ? nbt_image_attr_string(again, "cycles.ViewLayer.synchronization_time") : NULL;
    t_true(v && !strcmp(v, "00:00.31"), "long names: a kept long name is written again (%s)", err);
    memset(name300, 'a', 300);
    name300[300] = '\0';
    const char *too_long[] = {name300, "x"};
    wo.attrs = too_long;
    wo.nattrs = 1;
    int before = count_entries(dir);
    s = nbt_image_write_exr_ex(im, path, &wo, err, sizeof err);
    t_true(s == NBT_EINVAL && strstr(err, "cannot be set (Provided name") && count_entries(dir) == before,
           "long names: a 300-character name is refused with the library's reason, nothing left (%s)", err);
    nbt_image_free(im), nbt_image_free(back), nbt_image_free(again);
    unlink(path), unlink(path2);
}

/* A subsampled channel beside RGB: listed with its sampling, not kept, not written. */
static void test_subsampled_kept(void)
{
    const int w = 8, h = 6;
    float *r = plane(w, h, 0), *c = plane(w / 2, h / 2, 1);
    wch ch[] = {{"B", EXR_PIXEL_FLOAT, r, 0, 0}, {"C", EXR_PIXEL_HALF, c, 2, 2}, {"G", EXR_PIXEL_FLOAT, r, 0, 0},
                {"R", EXR_PIXEL_FLOAT, r, 0, 0}};
    wpart p = scan(w, h, EXR_COMPRESSION_NONE, ch, 4);
    const char *in = in_dir("sub_in.exr"), *out = in_dir("sub_out.exr");
    char err[512] = "";
    nbt_image *im = NULL, *back = NULL;
    t_true(write_exr(in, &p, 1) == 0, "subsampled: test file written");
    nbt_status s = nbt_image_read_exr(in, &im, err, sizeof err);
    t_true(s == NBT_OK && im && im->nchannels == 1 && !strcmp(im->channels[0].name, "C") &&
               im->channels[0].x_sampling == 2 && im->channels[0].y_sampling == 2 && !im->channels[0].data,
           "subsampled: C listed with its 2 x 2 sampling, no data (%s)", err);
    nbt_exr_write_opts wo;
    memset(&wo, 0, sizeof wo);
    s = im ? nbt_image_write_exr_ex(im, out, &wo, err, sizeof err) : NBT_EINVAL;
    t_true(s == NBT_OK && nbt_image_read_exr(out, &back, err, sizeof err) == NBT_OK && back->nchannels == 0,
           "subsampled: left out of the written file (%s)", err);
    nbt_image_free(im);
    nbt_image_free(back);
    unlink(in), unlink(out);
    free(r), free(c);
}

int main(void)
{
    snprintf(dir, sizeof dir, "/tmp/nbt-test-imageXXXXXX");
    if (!mkdtemp(dir)) {
        perror("mkdtemp");
        return 1;
    }
    test_alloc();
    test_roundtrip(37, 23, 1);
    test_roundtrip(37, 23, 0);
    test_roundtrip(1, 1, 1);
    test_roundtrip(1, 1, 0);
    test_roundtrip(200, 67, 1);
    test_half();
    test_tiled();
    test_origin();
    test_blender();
    test_grey_and_parts();
    test_overscan();
    test_blender_names();
    test_subsampled_kept();
    test_long_names();
    test_errors();
    int left = count_entries(dir);
    t_true(left == 0, "temporary directory empty at the end (%d entries)", left);
    rmdir(dir);
    return t_done();
}
