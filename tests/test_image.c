/* tests/test_image.c: nbt_image OpenEXR I/O. Float round trips (with and
 * without depth, odd sizes, special values, attributes, ZIP), files written
 * here with the OpenEXR core API (HALF, UINT, tiled with mipmaps, a data
 * window away from the origin, Blender multilayer names, luminance, multi
 * part) read back with known values, and failures: missing, non-EXR,
 * channel-less, ambiguous, subsampled and truncated files, and writes that
 * cannot complete (nothing left behind). */
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
            rv = exr_initialize_required_attr(ctx, idx, wp->disp ? &dispw : &dw, &dw, 1.0f, &swc, 1.0f,
                                              EXR_LINEORDER_INCREASING_Y, wp->comp);
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
    wpart p = {EXR_STORAGE_SCANLINE, comp, 0, 0, w, h, 0, 0, 0, EXR_TILE_ONE_LEVEL, ch, nch};
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
    wpart p = {EXR_STORAGE_TILED, EXR_COMPRESSION_ZIP, 3, -4, w, h, 1, 8, 5, EXR_TILE_MIPMAP_LEVELS, c4, 4};
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
    wpart p2 = {EXR_STORAGE_TILED, EXR_COMPRESSION_NONE, 0, 0, w2, h2, 0, 16, 16, EXR_TILE_ONE_LEVEL, c3, 3};
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

    nbt_image empty = {0, 0, NULL, NULL};
    s = nbt_image_write_exr(&empty, keep, NULL, 0, err, sizeof err);
    t_true(s == NBT_EINVAL && file_size(keep) < 0, "empty image: NBT_EINVAL (%s)", err);
    nbt_image_free(big);
    free(a), free(v);
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
    test_errors();
    int left = count_entries(dir);
    t_true(left == 0, "temporary directory empty at the end (%d entries)", left);
    rmdir(dir);
    return t_done();
}
