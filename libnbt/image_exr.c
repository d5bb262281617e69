/* libnbt/image_exr.c: HDR RGB + depth images as OpenEXR (C core API).
 *
 * Reading lets the core library's decode pipeline convert HALF/UINT/FLOAT
 * samples to float (user_data_type = EXR_PIXEL_FLOAT) straight into the
 * interleaved RGB plane and the depth plane. Writing produces float32 R, G,
 * B (, Z) scan lines with ZIP compression only (ZIPS has an encoder bug in
 * 3.1.5), into a temporary file renamed over the target at the end. */
#define _POSIX_C_SOURCE 200809L
#include <config.h>
#include <errno.h>
#include <fcntl.h>
#include <stdarg.h>
#include <stdatomic.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>
#include <openexr.h>
#include <nbt/image.h>
#include "internal.h"

int nbt__exr_raw_plausible(const char *path, double raw_bytes)
{
    struct stat st;
    if (stat(path, &st) != 0)
        return 1; /* the reader reports the file's own problem */
    return raw_bytes <= 1e4 * (double)st.st_size + 16.0 * 1024 * 1024;
}

nbt_image *nbt_image_alloc(size_t w, size_t h, int with_z)
{
    if (w == 0 || h == 0 || h > SIZE_MAX / w)
        return NULL;
    size_t n = w * h;
    if (n > SIZE_MAX / (3 * sizeof(float)))
        return NULL;
    nbt_image *im = calloc(1, sizeof *im);
    if (!im)
        return NULL;
    im->w = w;
    im->h = h;
    im->rgb = calloc(n * 3, sizeof(float));
    im->z = with_z ? calloc(n, sizeof(float)) : NULL;
    if (!im->rgb || (with_z && !im->z)) {
        nbt_image_free(im);
        return NULL;
    }
    return im;
}

void nbt_image_free(nbt_image *im)
{
    if (!im)
        return;
    free(im->rgb);
    free(im->z);
    free(im);
}

/* ---- error reporting ---- */

/* The core library's first error message of a context, kept in its user data. */
#define LIBMSG_LEN 200

static void capture(exr_const_context_t c, exr_result_t code, const char *msg)
{
    void *ud = NULL;
    (void)code;
    if (!msg || exr_get_user_data(c, &ud) != EXR_ERR_SUCCESS || !ud)
        return;
    char *buf = ud;
    if (buf[0])
        return;
    size_t i = 0;
    for (; msg[i] && i + 1 < LIBMSG_LEN; i++)
        buf[i] = (msg[i] == '\n' || msg[i] == '\r') ? ' ' : msg[i];
    buf[i] = '\0';
}

static const char *lib_detail(const char *libmsg, exr_result_t rv)
{
    return libmsg[0] ? libmsg : exr_get_default_error_message(rv);
}

/* "path: what" to err and to the error handler; returns s. */
__attribute__((format(printf, 5, 6)))
static nbt_status fail(nbt_status s, const char *path, char *err, size_t errlen, const char *fmt, ...)
{
    char line[1024];
    int n = snprintf(line, sizeof line, "%s: ", path ? path : "(no path)");
    if (n < 0 || (size_t)n >= sizeof line)
        n = 0;
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(line + n, sizeof line - (size_t)n, fmt, ap);
    va_end(ap);
    if (err && errlen)
        snprintf(err, errlen, "%s", line);
    return nbt__fail(s, line);
}

/* ---- channel selection ---- */

enum { SEL_R, SEL_G, SEL_B, SEL_Z };

typedef struct {
    const char *name[4]; /* R, G, B, Z channel names; NULL: absent (G, B when grey) */
    int grey;            /* a luminance channel Y in name[SEL_R] */
    const char *layer;   /* RGB layer prefix (pointer into the R name), layer_len chars */
    size_t layer_len;
} chsel;

static const exr_attr_chlist_entry_t *find_ch(const exr_attr_chlist_t *cl, const char *name)
{
    for (int i = 0; i < cl->num_channels; i++)
        if (!strcmp(cl->entries[i].name.str, name))
            return &cl->entries[i];
    return NULL;
}

/* The channel named pfx[0..plen) followed by sfx. */
static const exr_attr_chlist_entry_t *find_pfx(const exr_attr_chlist_t *cl, const char *pfx, size_t plen,
                                               const char *sfx)
{
    size_t slen = strlen(sfx);
    for (int i = 0; i < cl->num_channels; i++) {
        const char *s = cl->entries[i].name.str;
        if (strlen(s) == plen + slen && !strncmp(s, pfx, plen) && !strcmp(s + plen, sfx))
            return &cl->entries[i];
    }
    return NULL;
}

static int ends_with(const char *s, const char *sfx)
{
    size_t n = strlen(s), m = strlen(sfx);
    return n >= m && !strcmp(s + n - m, sfx);
}

/* A layer prefix whose last dot-separated component is "Combined". */
static int is_combined(const char *pfx, size_t plen)
{
    static const char C[] = "Combined";
    size_t m = sizeof C - 1;
    return plen >= m && !strncmp(pfx + plen - m, C, m) && (plen == m || pfx[plen - m - 1] == '.');
}

/* Appends "a, b, ..." of up to n layer prefixes to buf. */
static void list_layers(const exr_attr_chlist_t *cl, int combined_only, char *buf, size_t n)
{
    size_t off = 0;
    buf[0] = '\0';
    for (int i = 0; i < cl->num_channels && off + 1 < n; i++) {
        const char *s = cl->entries[i].name.str;
        size_t plen = strlen(s) >= 2 ? strlen(s) - 2 : 0;
        if (!ends_with(s, ".R") || !find_pfx(cl, s, plen, ".G") || !find_pfx(cl, s, plen, ".B") ||
            (combined_only && !is_combined(s, plen)))
            continue;
        int k = snprintf(buf + off, n - off, "%s%.*s", off ? ", " : "", (int)plen, s);
        if (k < 0 || (size_t)k >= n - off)
            break;
        off += (size_t)k;
    }
}

/* Picks the channels of one part: 1 found, 0 none, -1 error (why). */
static int pick_channels(const exr_attr_chlist_t *cl, chsel *sel, char *why, size_t n)
{
    memset(sel, 0, sizeof *sel);
    const exr_attr_chlist_entry_t *r = find_ch(cl, "R"), *g = find_ch(cl, "G"), *b = find_ch(cl, "B");
    if (r && g && b) {
        sel->name[SEL_R] = r->name.str;
        sel->name[SEL_G] = g->name.str;
        sel->name[SEL_B] = b->name.str;
    } else {
        /* layers P with P.R, P.G, P.B */
        int nlayers = 0, ncombined = 0;
        const char *any = NULL, *comb = NULL;
        for (int i = 0; i < cl->num_channels; i++) {
            const char *s = cl->entries[i].name.str;
            if (!ends_with(s, ".R"))
                continue;
            size_t plen = strlen(s) - 2;
            if (!find_pfx(cl, s, plen, ".G") || !find_pfx(cl, s, plen, ".B"))
                continue;
            nlayers++;
            any = s;
            if (is_combined(s, plen)) {
                ncombined++;
                comb = s;
            }
        }
        const char *pick = nlayers == 1 ? any : ncombined == 1 ? comb : NULL;
        if (!pick && nlayers > 1) {
            char list[400];
            list_layers(cl, ncombined > 1, list, sizeof list);
            if (ncombined > 1)
                snprintf(why, n, "ambiguous R, G, B channels: %d \"Combined\" layers (%s)", ncombined, list);
            else
                snprintf(why, n, "ambiguous R, G, B channels: %d layers (%s), none named \"Combined\"", nlayers,
                         list);
            return -1;
        }
        if (pick) {
            size_t plen = strlen(pick) - 2;
            sel->name[SEL_R] = pick;
            sel->name[SEL_G] = find_pfx(cl, pick, plen, ".G")->name.str;
            sel->name[SEL_B] = find_pfx(cl, pick, plen, ".B")->name.str;
            sel->layer = pick;
            sel->layer_len = plen;
        } else {
            const exr_attr_chlist_entry_t *y = find_ch(cl, "Y");
            if (!y)
                return 0;
            if (find_ch(cl, "RY") || find_ch(cl, "BY")) {
                snprintf(why, n, "luminance/chroma channels (Y, RY, BY) are not supported");
                return -1;
            }
            sel->name[SEL_R] = y->name.str;
            sel->grey = 1;
        }
    }

    /* depth */
    const exr_attr_chlist_entry_t *z = find_ch(cl, "Z");
    if (!z && sel->layer) {
        /* "L.Pass" -> "L.Depth.Z", then "L.Pass.Z" */
        const char *dot = NULL;
        for (size_t i = 0; i < sel->layer_len; i++)
            if (sel->layer[i] == '.')
                dot = sel->layer + i;
        size_t llen = dot ? (size_t)(dot - sel->layer) : 0;
        if (dot)
            z = find_pfx(cl, sel->layer, llen, ".Depth.Z");
        if (!z)
            z = find_pfx(cl, sel->layer, sel->layer_len, ".Z");
    }
    for (int tier = 0; tier < 2 && !z; tier++) {
        /* tier 0: "Depth.Z" or "*.Depth.Z"; tier 1: "*.Z" that is not part
         * of a vector (no .X/.Y beside it) nor Blender's Mist pass */
        int count = 0;
        const exr_attr_chlist_entry_t *hit = NULL;
        for (int i = 0; i < cl->num_channels; i++) {
            const char *s = cl->entries[i].name.str;
            int ok;
            if (tier == 0)
                ok = !strcmp(s, "Depth.Z") || ends_with(s, ".Depth.Z");
            else {
                size_t plen = strlen(s) >= 2 ? strlen(s) - 2 : 0;
                ok = ends_with(s, ".Z") && !find_pfx(cl, s, plen, ".X") && !find_pfx(cl, s, plen, ".Y") &&
                     strcmp(s, "Mist.Z") && !ends_with(s, ".Mist.Z");
            }
            if (ok) {
                count++;
                hit = &cl->entries[i];
            }
        }
        if (count > 1) {
            snprintf(why, n, "ambiguous depth channels: %d named %s", count,
                     tier == 0 ? "\"Depth.Z\" or \"*.Depth.Z\"" : "\"*.Z\" (and no \"Z\" or \"*.Depth.Z\")");
            return -1;
        }
        z = hit;
    }
    sel->name[SEL_Z] = z ? z->name.str : NULL;

    for (int k = 0; k < 4; k++) {
        const exr_attr_chlist_entry_t *e = sel->name[k] ? find_ch(cl, sel->name[k]) : NULL;
        if (e && (e->x_sampling != 1 || e->y_sampling != 1)) {
            snprintf(why, n, "channel %s is subsampled (%d x %d); only full-resolution channels are supported",
                     e->name.str, e->x_sampling, e->y_sampling);
            return -1;
        }
    }
    return 1;
}

/* "A, B, ..." of every channel of every part (truncated with "..."). */
static void list_channels(exr_const_context_t ctx, int nparts, char *buf, size_t n)
{
    size_t off = 0;
    buf[0] = '\0';
    for (int p = 0; p < nparts; p++) {
        const exr_attr_chlist_t *cl;
        if (exr_get_channels(ctx, p, &cl) != EXR_ERR_SUCCESS)
            continue;
        for (int i = 0; i < cl->num_channels; i++) {
            const char *s = cl->entries[i].name.str;
            if (off + strlen(s) + 8 >= n) {
                snprintf(buf + off, n - off, "%s...", off ? ", " : "");
                return;
            }
            off += (size_t)snprintf(buf + off, n - off, "%s%s", off ? ", " : "", s);
        }
    }
    if (!off)
        snprintf(buf, n, "none");
}

/* ---- reading ---- */

typedef struct {
    exr_const_context_t ctx;
    int part;
    const chsel *sel;
    nbt_image *im;
    exr_decode_pipeline_t dec;
    int started; /* dec initialized (needs exr_decoding_destroy) */
} reader;

/* Decodes one chunk whose first pixel is (x0, y0) of the image. */
static exr_result_t decode_chunk(reader *r, const exr_chunk_info_t *ci, size_t x0, size_t y0)
{
    exr_result_t rv;
    if (r->started)
        rv = exr_decoding_update(r->ctx, r->part, ci, &r->dec);
    else {
        r->started = 1;
        rv = exr_decoding_initialize(r->ctx, r->part, ci, &r->dec);
    }
    if (rv != EXR_ERR_SUCCESS)
        return rv;
    size_t w = r->im->w;
    for (int16_t c = 0; c < r->dec.channel_count; c++) {
        exr_coding_channel_info_t *ch = &r->dec.channels[c];
        ch->decode_to_ptr = NULL;
        for (int k = 0; k < 4; k++) {
            if (!r->sel->name[k] || strcmp(ch->channel_name, r->sel->name[k]))
                continue;
            if (k == SEL_Z) {
                ch->decode_to_ptr = (uint8_t *)(r->im->z + y0 * w + x0);
                ch->user_pixel_stride = (int32_t)sizeof(float);
                ch->user_line_stride = (int32_t)(w * sizeof(float));
            } else {
                ch->decode_to_ptr = (uint8_t *)(r->im->rgb + (y0 * w + x0) * 3 + (size_t)k);
                ch->user_pixel_stride = (int32_t)(3 * sizeof(float));
                ch->user_line_stride = (int32_t)(w * 3 * sizeof(float));
            }
            ch->user_bytes_per_element = (int16_t)sizeof(float);
            ch->user_data_type = EXR_PIXEL_FLOAT;
            break;
        }
    }
    rv = exr_decoding_choose_default_routines(r->ctx, r->part, &r->dec);
    if (rv == EXR_ERR_SUCCESS)
        rv = exr_decoding_run(r->ctx, r->part, &r->dec);
    return rv;
}

nbt_status nbt_image_read_exr(const char *path, nbt_image **out, char *err, size_t errlen)
{
    if (out)
        *out = NULL;
    if (err && errlen)
        err[0] = '\0';
    if (!path || !out)
        return fail(NBT_EINVAL, path, err, errlen, "nbt_image_read_exr: no path or no output pointer");
    struct stat sb;
    if (stat(path, &sb) != 0)
        return fail(NBT_EIO, path, err, errlen, "cannot open: %s", strerror(errno));
    if (S_ISDIR(sb.st_mode))
        return fail(NBT_EIO, path, err, errlen, "cannot open: %s", strerror(EISDIR));
    FILE *probe = fopen(path, "rb");
    if (!probe)
        return fail(NBT_EIO, path, err, errlen, "cannot open: %s", strerror(errno));
    fclose(probe);

    char libmsg[LIBMSG_LEN] = "";
    exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
    init.error_handler_fn = capture;
    init.user_data = libmsg;
    exr_context_t ctx = NULL;
    exr_result_t rv = exr_start_read(&ctx, path, &init);
    if (rv != EXR_ERR_SUCCESS) {
        if (ctx)
            exr_finish(&ctx);
        return fail(NBT_EFORMAT, path, err, errlen, "not a readable OpenEXR file (%s)", lib_detail(libmsg, rv));
    }

    nbt_status st = NBT_OK;
    nbt_image *im = NULL;
    reader rd = {.ctx = ctx, .dec = EXR_DECODE_PIPELINE_INITIALIZER};
    chsel sel;
    char why[512];
    int nparts = 0, part = -1;
    if (exr_get_count(ctx, &nparts) != EXR_ERR_SUCCESS)
        nparts = 0;
    for (int p = 0; p < nparts && part < 0; p++) {
        exr_storage_t stor;
        const exr_attr_chlist_t *cl;
        if (exr_get_storage(ctx, p, &stor) != EXR_ERR_SUCCESS ||
            (stor != EXR_STORAGE_SCANLINE && stor != EXR_STORAGE_TILED) ||
            exr_get_channels(ctx, p, &cl) != EXR_ERR_SUCCESS || !cl)
            continue;
        int got = pick_channels(cl, &sel, why, sizeof why);
        if (got < 0) {
            if (nparts > 1)
                st = fail(NBT_EFORMAT, path, err, errlen, "part %d: %s", p, why);
            else
                st = fail(NBT_EFORMAT, path, err, errlen, "%s", why);
            goto done;
        }
        if (got > 0)
            part = p;
    }
    if (part < 0) {
        list_channels(ctx, nparts, why, 300);
        st = fail(NBT_EFORMAT, path, err, errlen, "no R, G, B channels (found: %s)", why);
        goto done;
    }

    exr_attr_box2i_t dw;
    exr_storage_t stor = EXR_STORAGE_SCANLINE;
    if (exr_get_data_window(ctx, part, &dw) != EXR_ERR_SUCCESS || exr_get_storage(ctx, part, &stor) != EXR_ERR_SUCCESS) {
        st = fail(NBT_EFORMAT, path, err, errlen, "no data window");
        goto done;
    }
    int64_t w64 = (int64_t)dw.max.x - dw.min.x + 1, h64 = (int64_t)dw.max.y - dw.min.y + 1;
    if (w64 <= 0 || h64 <= 0) {
        st = fail(NBT_EFORMAT, path, err, errlen, "empty data window (%d, %d) - (%d, %d)", dw.min.x, dw.min.y,
                  dw.max.x, dw.max.y);
        goto done;
    }
    if (w64 > INT32_MAX / (int64_t)(3 * sizeof(float))) {
        st = fail(NBT_EFORMAT, path, err, errlen, "data window too wide (%lld pixels)", (long long)w64);
        goto done;
    }
    if (!nbt__exr_raw_plausible(path, (double)w64 * (double)h64 * 4.0 * sizeof(float))) {
        st = fail(NBT_EFORMAT, path, err, errlen, "data window %lld x %lld is more than the file can hold: corrupt header",
                  (long long)w64, (long long)h64);
        goto done;
    }
    if ((uint64_t)w64 > SIZE_MAX || (uint64_t)h64 > SIZE_MAX ||
        !(im = nbt_image_alloc((size_t)w64, (size_t)h64, sel.name[SEL_Z] != NULL))) {
        st = fail(NBT_ENOMEM, path, err, errlen, "out of memory for a %lld x %lld image", (long long)w64,
                  (long long)h64);
        goto done;
    }
    size_t w = im->w, h = im->h;
    rd.part = part;
    rd.sel = &sel;
    rd.im = im;

    if (stor == EXR_STORAGE_SCANLINE) {
        int32_t lpc = 0;
        if (exr_get_scanlines_per_chunk(ctx, part, &lpc) != EXR_ERR_SUCCESS || lpc < 1) {
            st = fail(NBT_EFORMAT, path, err, errlen, "bad scan lines per chunk");
            goto done;
        }
        for (int64_t y = dw.min.y; y <= dw.max.y; y += lpc) {
            exr_chunk_info_t ci;
            rv = exr_read_scanline_chunk_info(ctx, part, (int)y, &ci);
            if (rv == EXR_ERR_SUCCESS &&
                (ci.start_y < dw.min.y || ci.height < 1 || ci.width != (int32_t)w ||
                 (uint64_t)((int64_t)ci.start_y - dw.min.y) + (uint64_t)ci.height > h))
                rv = EXR_ERR_BAD_CHUNK_LEADER;
            if (rv == EXR_ERR_SUCCESS)
                rv = decode_chunk(&rd, &ci, 0, (size_t)((int64_t)ci.start_y - dw.min.y));
            if (rv != EXR_ERR_SUCCESS) {
                st = fail(NBT_EFORMAT, path, err, errlen, "cannot decode scan line %lld: truncated or corrupt (%s)",
                          (long long)y, lib_detail(libmsg, rv));
                goto done;
            }
        }
    } else {
        uint32_t tw = 0, th = 0;
        exr_tile_level_mode_t lmode;
        exr_tile_round_mode_t rmode;
        int32_t lw = 0, lh = 0;
        if (exr_get_tile_descriptor(ctx, part, &tw, &th, &lmode, &rmode) != EXR_ERR_SUCCESS || tw == 0 || th == 0 ||
            exr_get_level_sizes(ctx, part, 0, 0, &lw, &lh) != EXR_ERR_SUCCESS || (size_t)lw != w || (size_t)lh != h) {
            st = fail(NBT_EFORMAT, path, err, errlen, "bad tile description");
            goto done;
        }
        size_t ntx = (w - 1) / tw + 1, nty = (h - 1) / th + 1;
        for (size_t ty = 0; ty < nty; ty++)
            for (size_t tx = 0; tx < ntx; tx++) {
                exr_chunk_info_t ci;
                size_t x0 = tx * tw, y0 = ty * th;
                rv = exr_read_tile_chunk_info(ctx, part, (int)tx, (int)ty, 0, 0, &ci);
                if (rv == EXR_ERR_SUCCESS && (ci.width < 1 || ci.height < 1 || x0 + (size_t)ci.width > w ||
                                              y0 + (size_t)ci.height > h))
                    rv = EXR_ERR_BAD_CHUNK_LEADER;
                if (rv == EXR_ERR_SUCCESS)
                    rv = decode_chunk(&rd, &ci, x0, y0);
                if (rv != EXR_ERR_SUCCESS) {
                    st = fail(NBT_EFORMAT, path, err, errlen, "cannot decode tile (%zu, %zu): truncated or corrupt (%s)",
                              tx, ty, lib_detail(libmsg, rv));
                    goto done;
                }
            }
    }
    if (sel.grey)
        for (size_t i = 0; i < w * h; i++)
            im->rgb[3 * i + 1] = im->rgb[3 * i + 2] = im->rgb[3 * i];
done:
    if (rd.started)
        exr_decoding_destroy(ctx, &rd.dec);
    exr_finish(&ctx);
    if (st != NBT_OK) {
        nbt_image_free(im);
        return st;
    }
    *out = im;
    return NBT_OK;
}

/* ---- writing ---- */

static const char *const WCH[4] = {"R", "G", "B", "Z"};

nbt_status nbt_image_write_exr(const nbt_image *im, const char *path, const char *const *attrs, size_t nattrs,
                               char *err, size_t errlen)
{
    static atomic_uint seq;
    if (err && errlen)
        err[0] = '\0';
    if (!path || !*path)
        return fail(NBT_EINVAL, path, err, errlen, "nbt_image_write_exr: no path");
    if (!im || !im->rgb || im->w == 0 || im->h == 0)
        return fail(NBT_EINVAL, path, err, errlen, "no image to write (empty or without pixels)");
    if (im->w > (size_t)INT32_MAX / (3 * sizeof(float)) || im->h > (size_t)INT32_MAX)
        return fail(NBT_EINVAL, path, err, errlen, "%zu x %zu pixels is too large for OpenEXR", im->w, im->h);
    if (nattrs && (!attrs || nattrs > SIZE_MAX / 2))
        return fail(NBT_EINVAL, path, err, errlen, "%zu attributes but no attribute list", nattrs);
    for (size_t i = 0; i < nattrs; i++)
        if (!attrs[2 * i] || !attrs[2 * i][0] || !attrs[2 * i + 1])
            return fail(NBT_EINVAL, path, err, errlen, "attribute %zu has no name or no value", i);

    size_t w = im->w, h = im->h, tlen = strlen(path) + 48;
    char *tmp = malloc(tlen);
    if (!tmp)
        return fail(NBT_ENOMEM, path, err, errlen, "out of memory");
    snprintf(tmp, tlen, "%s.tmp%ld.%u", path, (long)getpid(), atomic_fetch_add(&seq, 1u));
    /* create it here for a reliable errno (the core library opens it again, truncating) */
    int fd = open(tmp, O_WRONLY | O_CREAT | O_EXCL, 0666);
    if (fd < 0) {
        int e = errno;
        nbt_status s = fail(NBT_EIO, path, err, errlen, "cannot create %s: %s", tmp, strerror(e));
        free(tmp);
        return s;
    }
    close(fd);

    char libmsg[LIBMSG_LEN] = "";
    exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
    init.error_handler_fn = capture;
    init.user_data = libmsg;
    exr_context_t ctx = NULL;
    int part = 0, nch = im->z ? 4 : 3;
    exr_result_t rv = exr_start_write(&ctx, tmp, EXR_WRITE_FILE_DIRECTLY, &init);
    if (rv == EXR_ERR_SUCCESS)
        rv = exr_add_part(ctx, NULL, EXR_STORAGE_SCANLINE, &part);
    if (rv == EXR_ERR_SUCCESS)
        rv = exr_initialize_required_attr_simple(ctx, part, (int32_t)w, (int32_t)h, EXR_COMPRESSION_ZIP);
    /* pLinear = 0 (as OpenEXR's RGBA interface writes it): linear radiance is not perceptually linear */
    for (int c = 0; c < nch && rv == EXR_ERR_SUCCESS; c++) {
        int r = exr_add_channel(ctx, part, WCH[c], EXR_PIXEL_FLOAT, EXR_PERCEPTUALLY_LOGARITHMIC, 1, 1);
        rv = (exr_result_t)r;
    }
    size_t bad_attr = nattrs;
    for (size_t i = 0; i < nattrs && rv == EXR_ERR_SUCCESS; i++)
        if ((rv = exr_attr_set_string(ctx, part, attrs[2 * i], attrs[2 * i + 1])) != EXR_ERR_SUCCESS)
            bad_attr = i;
    if (rv == EXR_ERR_SUCCESS)
        rv = exr_write_header(ctx);
    int32_t lpc = 1;
    if (rv == EXR_ERR_SUCCESS)
        rv = exr_get_scanlines_per_chunk(ctx, part, &lpc);
    if (rv == EXR_ERR_SUCCESS && lpc < 1)
        rv = EXR_ERR_INVALID_ARGUMENT;
    exr_encode_pipeline_t enc = EXR_ENCODE_PIPELINE_INITIALIZER;
    int started = 0;
    for (int64_t y = 0; y < (int64_t)h && rv == EXR_ERR_SUCCESS; y += lpc) {
        exr_chunk_info_t ci;
        rv = exr_write_scanline_chunk_info(ctx, part, (int)y, &ci);
        if (rv != EXR_ERR_SUCCESS)
            break;
        if (started)
            rv = exr_encoding_update(ctx, part, &ci, &enc);
        else {
            started = 1;
            rv = exr_encoding_initialize(ctx, part, &ci, &enc);
        }
        if (rv != EXR_ERR_SUCCESS)
            break;
        size_t y0 = (size_t)ci.start_y;
        for (int16_t c = 0; c < enc.channel_count; c++) {
            exr_coding_channel_info_t *ch = &enc.channels[c];
            int k = 0;
            while (k < nch && strcmp(ch->channel_name, WCH[k]))
                k++;
            if (k == nch) {
                rv = EXR_ERR_INVALID_ARGUMENT;
                break;
            }
            if (k == SEL_Z) {
                ch->encode_from_ptr = (const uint8_t *)(im->z + y0 * w);
                ch->user_pixel_stride = (int32_t)sizeof(float);
                ch->user_line_stride = (int32_t)(w * sizeof(float));
            } else {
                ch->encode_from_ptr = (const uint8_t *)(im->rgb + y0 * w * 3 + (size_t)k);
                ch->user_pixel_stride = (int32_t)(3 * sizeof(float));
                ch->user_line_stride = (int32_t)(w * 3 * sizeof(float));
            }
            ch->user_bytes_per_element = (int16_t)sizeof(float);
            ch->user_data_type = EXR_PIXEL_FLOAT;
        }
        if (rv == EXR_ERR_SUCCESS)
            rv = exr_encoding_choose_default_routines(ctx, part, &enc);
        if (rv == EXR_ERR_SUCCESS)
            rv = exr_encoding_run(ctx, part, &enc);
    }
    if (started)
        exr_encoding_destroy(ctx, &enc);
    exr_result_t fr = ctx ? exr_finish(&ctx) : EXR_ERR_SUCCESS;
    nbt_status st = NBT_OK;
    if (bad_attr < nattrs) {
        unlink(tmp);
        st = fail(NBT_EINVAL, path, err, errlen, "attribute \"%s\" cannot be set (%s)", attrs[2 * bad_attr],
                  lib_detail(libmsg, rv));
    } else if (rv != EXR_ERR_SUCCESS || fr != EXR_ERR_SUCCESS) {
        unlink(tmp);
        st = fail(NBT_EIO, path, err, errlen, "cannot write OpenEXR data (%s)",
                  lib_detail(libmsg, rv != EXR_ERR_SUCCESS ? rv : fr));
    } else if (rename(tmp, path) != 0) {
        int e = errno;
        unlink(tmp);
        st = fail(NBT_EIO, path, err, errlen, "cannot rename %s to it: %s", tmp, strerror(e));
    }
    free(tmp);
    return st;
}
