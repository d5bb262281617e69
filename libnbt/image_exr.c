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

/* OpenEXR's allocations for nbt's contexts (their alloc_fn, free_fn): a
 * failed one is remembered for the calling thread. The library reports
 * running out of memory as a format or I/O error, or not at all: 3.1's
 * header parser drops an attribute whose copy it cannot allocate and the
 * read succeeds without it (tests/test_oom: an H table read without its
 * nbt.max_err.G). The readers and writers clear the flag before they start
 * and answer NBT_ENOMEM when it is set. */
static _Thread_local int exr_nomem;

static void *exr_alloc(size_t n)
{
    void *p = malloc(n);
    if (!p)
        exr_nomem = 1;
    return p;
}

static void exr_free(void *p)
{
    free(p);
}

void nbt__exr_init(exr_context_initializer_t *init)
{
    init->alloc_fn = exr_alloc;
    init->free_fn = exr_free;
    exr_nomem = 0;
}

int nbt__exr_nomem(void)
{
    return exr_nomem;
}

/* rv, noting a failure for lack of memory: the library's own code, or
 * errno ENOMEM (cleared before the call) from zlib, which allocates with
 * malloc rather than through the context. */
static exr_result_t noted(exr_result_t rv)
{
    if (rv == EXR_ERR_OUT_OF_MEMORY || (rv != EXR_ERR_SUCCESS && errno == ENOMEM))
        exr_nomem = 1;
    return rv;
}

/* ---- kept header attributes ---- */

/* One attribute, its value flattened into bytes: POD and fixed-size
 * structs as their C struct; string: the characters and a NUL; string
 * vector: the strings each with its NUL (count in n); float vector: the
 * floats; preview: exr_attr_preview_t's width, height then the RGBA bytes;
 * opaque: the packed bytes as in the file. */
typedef struct {
    char *name, *type_name;
    exr_attribute_type_t type;
    int32_t n;
    size_t size;
    unsigned char *bytes;
} kattr;

struct nbt_image_attrs {
    size_t n;
    kattr *a;
};

static void attrs_free(nbt_image_attrs *l)
{
    if (!l)
        return;
    for (size_t i = 0; i < l->n; i++) {
        free(l->a[i].name);
        free(l->a[i].type_name);
        free(l->a[i].bytes);
    }
    free(l->a);
    free(l);
}

static void *memdup(const void *p, size_t n)
{
    void *q = malloc(n ? n : 1);
    if (q && n)
        memcpy(q, p, n);
    return q;
}

static nbt_image_attrs *attrs_dup(const nbt_image_attrs *l)
{
    nbt_image_attrs *d = calloc(1, sizeof *d);
    if (!d)
        return NULL;
    if (l->n && !(d->a = calloc(l->n, sizeof *d->a))) {
        free(d);
        return NULL;
    }
    for (size_t i = 0; i < l->n; i++, d->n++) {
        kattr *k = &d->a[i];
        *k = l->a[i];
        k->name = strdup(l->a[i].name);
        k->type_name = strdup(l->a[i].type_name);
        k->bytes = memdup(l->a[i].bytes, l->a[i].size);
        if (!k->name || !k->type_name || !k->bytes) {
            d->n++;
            attrs_free(d);
            return NULL;
        }
    }
    return d;
}

size_t nbt_image_attr_count(const nbt_image *im)
{
    return im && im->attrs ? im->attrs->n : 0;
}

const char *nbt_image_attr_name(const nbt_image *im, size_t i, const char **type_name)
{
    if (!im || !im->attrs || i >= im->attrs->n)
        return NULL;
    if (type_name)
        *type_name = im->attrs->a[i].type_name;
    return im->attrs->a[i].name;
}

const char *nbt_image_attr_string(const nbt_image *im, const char *name)
{
    for (size_t i = 0; name && i < nbt_image_attr_count(im); i++)
        if (im->attrs->a[i].type == EXR_ATTR_STRING && !strcmp(im->attrs->a[i].name, name))
            return (const char *)im->attrs->a[i].bytes;
    return NULL;
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
    im->display.max_x = (int32_t)(w > (size_t)INT32_MAX ? INT32_MAX : w - 1);
    im->display.max_y = (int32_t)(h > (size_t)INT32_MAX ? INT32_MAX : h - 1);
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
    free(im->rgb_layer);
    free(im->z_name);
    for (size_t i = 0; i < im->nchannels; i++) {
        free(im->channels[i].name);
        free(im->channels[i].data);
    }
    free(im->channels);
    attrs_free(im->attrs);
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

/* The writer's handler: the core library calls the error handler of a write
 * context with the context's lock held, and exr_get_user_data takes that lock
 * (it waited forever on "name too long"), so write_any hands the handler its
 * buffer through this per-thread pointer, set only while it runs. */
static _Thread_local char *capture_write_buf;

static void capture_write(exr_const_context_t c, exr_result_t code, const char *msg)
{
    char *buf = capture_write_buf;
    (void)c, (void)code;
    if (!msg || !buf || buf[0])
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
    /* after an allocation failed in OpenEXR (the flag is cleared when a read or write starts), the
     * failure it caused is reported as what it is */
    int nomem = exr_nomem && (s == NBT_EFORMAT || s == NBT_EIO || s == NBT_EINVAL);
    if (nomem)
        s = NBT_ENOMEM;
    int n = snprintf(line, sizeof line, "%s: %s", path ? path : "(no path)", nomem ? "out of memory: " : "");
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

/* Attributes that describe the layout of the part, which the writer sets
 * itself; every other one is kept. */
static int structural(const char *name)
{
    static const char *const S[] = {"channels", "compression", "dataWindow", "displayWindow", "lineOrder", "tiles",
                                    "type", "name", "version", "chunkCount", "maxSamplesPerPixel"};
    for (size_t i = 0; i < sizeof S / sizeof S[0]; i++)
        if (!strcmp(name, S[i]))
            return 1;
    return 0;
}

/* Flattens one attribute into k (see kattr); 0 ok, -1 out of memory, 1 not
 * keepable (a channel list under another name). */
static int flatten_attr(const exr_attribute_t *a, kattr *k)
{
    memset(k, 0, sizeof *k);
    k->type = a->type;
    const void *src = NULL;
    size_t sz = 0;
    unsigned char *own = NULL;
    switch (a->type) {
    case EXR_ATTR_COMPRESSION:
    case EXR_ATTR_ENVMAP:
    case EXR_ATTR_LINEORDER: src = &a->uc, sz = sizeof a->uc; break;
    case EXR_ATTR_DOUBLE: src = &a->d, sz = sizeof a->d; break;
    case EXR_ATTR_FLOAT: src = &a->f, sz = sizeof a->f; break;
    case EXR_ATTR_INT: src = &a->i, sz = sizeof a->i; break;
    case EXR_ATTR_BOX2I: src = a->box2i, sz = sizeof *a->box2i; break;
    case EXR_ATTR_BOX2F: src = a->box2f, sz = sizeof *a->box2f; break;
    case EXR_ATTR_CHROMATICITIES: src = a->chromaticities, sz = sizeof *a->chromaticities; break;
    case EXR_ATTR_KEYCODE: src = a->keycode, sz = sizeof *a->keycode; break;
    case EXR_ATTR_M33F: src = a->m33f, sz = sizeof *a->m33f; break;
    case EXR_ATTR_M33D: src = a->m33d, sz = sizeof *a->m33d; break;
    case EXR_ATTR_M44F: src = a->m44f, sz = sizeof *a->m44f; break;
    case EXR_ATTR_M44D: src = a->m44d, sz = sizeof *a->m44d; break;
    case EXR_ATTR_RATIONAL: src = a->rational, sz = sizeof *a->rational; break;
    case EXR_ATTR_TILEDESC: src = a->tiledesc, sz = sizeof *a->tiledesc; break;
    case EXR_ATTR_TIMECODE: src = a->timecode, sz = sizeof *a->timecode; break;
    case EXR_ATTR_V2I: src = a->v2i, sz = sizeof *a->v2i; break;
    case EXR_ATTR_V2F: src = a->v2f, sz = sizeof *a->v2f; break;
    case EXR_ATTR_V2D: src = a->v2d, sz = sizeof *a->v2d; break;
    case EXR_ATTR_V3I: src = a->v3i, sz = sizeof *a->v3i; break;
    case EXR_ATTR_V3F: src = a->v3f, sz = sizeof *a->v3f; break;
    case EXR_ATTR_V3D: src = a->v3d, sz = sizeof *a->v3d; break;
    case EXR_ATTR_STRING:
        sz = (size_t)(a->string->length > 0 ? a->string->length : 0) + 1;
        if (!(own = malloc(sz)))
            return -1;
        memcpy(own, a->string->str, sz - 1);
        own[sz - 1] = '\0';
        break;
    case EXR_ATTR_STRING_VECTOR: {
        const exr_attr_string_vector_t *v = a->stringvector;
        for (int32_t i = 0; i < v->n_strings; i++)
            sz += (size_t)(v->strings[i].length > 0 ? v->strings[i].length : 0) + 1;
        if (!(own = malloc(sz ? sz : 1)))
            return -1;
        size_t off = 0;
        for (int32_t i = 0; i < v->n_strings; i++) {
            size_t n = (size_t)(v->strings[i].length > 0 ? v->strings[i].length : 0);
            memcpy(own + off, v->strings[i].str, n);
            own[off + n] = '\0';
            off += n + 1;
        }
        k->n = v->n_strings;
        break;
    }
    case EXR_ATTR_FLOAT_VECTOR:
        src = a->floatvector->arr;
        k->n = a->floatvector->length > 0 ? a->floatvector->length : 0;
        sz = (size_t)k->n * sizeof(float);
        break;
    case EXR_ATTR_PREVIEW: {
        const exr_attr_preview_t *p = a->preview;
        size_t n = (size_t)p->width * p->height * 4;
        sz = 2 * sizeof(uint32_t) + n;
        if (!(own = malloc(sz)))
            return -1;
        memcpy(own, &p->width, sizeof(uint32_t));
        memcpy(own + sizeof(uint32_t), &p->height, sizeof(uint32_t));
        if (n)
            memcpy(own + 2 * sizeof(uint32_t), p->rgba, n);
        break;
    }
    case EXR_ATTR_OPAQUE:
        src = a->opaque->packed_data;
        sz = (size_t)(a->opaque->size > 0 ? a->opaque->size : 0);
        break;
    default: return 1; /* channel lists */
    }
    if (!own && !(own = memdup(src, sz)))
        return -1;
    k->bytes = own;
    k->size = sz;
    k->name = strdup(a->name);
    k->type_name = strdup(a->type_name);
    if (!k->name || !k->type_name) {
        free(k->name), free(k->type_name), free(k->bytes);
        return -1;
    }
    return 0;
}

/* The part's non-structural attributes; 0 ok, -1 out of memory. */
static int keep_attrs(exr_const_context_t ctx, int part, nbt_image_attrs **out)
{
    int32_t n = 0;
    *out = NULL;
    if (exr_get_attribute_count(ctx, part, &n) != EXR_ERR_SUCCESS || n <= 0)
        return 0;
    nbt_image_attrs *l = calloc(1, sizeof *l);
    if (!l || !(l->a = calloc((size_t)n, sizeof *l->a))) {
        free(l);
        return -1;
    }
    for (int32_t i = 0; i < n; i++) {
        const exr_attribute_t *a = NULL;
        if (exr_get_attribute_by_index(ctx, part, EXR_ATTR_LIST_FILE_ORDER, i, &a) != EXR_ERR_SUCCESS || !a ||
            structural(a->name))
            continue;
        int r = flatten_attr(a, &l->a[l->n]);
        if (r < 0) {
            attrs_free(l);
            return -1;
        }
        if (r == 0)
            l->n++;
    }
    if (!l->n) {
        attrs_free(l);
        l = NULL;
    }
    *out = l;
    return 0;
}

static size_t ptype_size(nbt_pixel_type t)
{
    return t == NBT_PIXEL_HALF ? 2 : 4;
}

/* The channels of the part other than the chosen RGB/Z ones (file order);
 * subsampled ones listed with data NULL. 0 ok, -1 out of memory. */
static int keep_channels(const exr_attr_chlist_t *cl, const chsel *sel, nbt_image *im)
{
    im->channels = calloc((size_t)cl->num_channels + 1, sizeof *im->channels);
    if (!im->channels)
        return -1;
    for (int i = 0; i < cl->num_channels; i++) {
        const exr_attr_chlist_entry_t *e = &cl->entries[i];
        int chosen = 0;
        for (int k = 0; k < 4; k++)
            chosen |= sel->name[k] && !strcmp(sel->name[k], e->name.str);
        if (chosen)
            continue;
        nbt_image_channel *c = &im->channels[im->nchannels];
        if (!(c->name = strdup(e->name.str)))
            return -1;
        im->nchannels++;
        c->type = (nbt_pixel_type)e->pixel_type;
        c->x_sampling = e->x_sampling;
        c->y_sampling = e->y_sampling;
        c->linear = e->p_linear;
        if (e->x_sampling == 1 && e->y_sampling == 1 &&
            !(c->data = calloc(im->w * im->h, ptype_size(c->type))))
            return -1;
    }
    return 0;
}


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
        for (size_t k = 0; !ch->decode_to_ptr && k < r->im->nchannels; k++) {
            nbt_image_channel *kc = &r->im->channels[k];
            if (!kc->data || strcmp(ch->channel_name, kc->name))
                continue;
            size_t b = ptype_size(kc->type);
            ch->decode_to_ptr = (uint8_t *)kc->data + (y0 * w + x0) * b;
            ch->user_pixel_stride = (int32_t)b;
            ch->user_line_stride = (int32_t)(w * b);
            ch->user_bytes_per_element = (int16_t)b;
            ch->user_data_type = (uint16_t)kc->type; /* unconverted */
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
    exr_nomem = 0;
    if (!path || !out)
        return fail(NBT_EINVAL, path, err, errlen, "nbt_image_read_exr: no path or no output pointer");
    struct stat sb;
    if (stat(path, &sb) != 0)
        return fail(NBT_EIO, path, err, errlen, "cannot open: %s", strerror(errno));
    if (S_ISDIR(sb.st_mode))
        return fail(NBT_EIO, path, err, errlen, "cannot open: %s", strerror(EISDIR));
    FILE *probe = fopen(path, "rb");
    if (!probe) {
        int e = errno;
        return fail(nbt__io_status(e), path, err, errlen, "cannot open: %s", strerror(e));
    }
    fclose(probe);

    char libmsg[LIBMSG_LEN] = "";
    exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
    init.error_handler_fn = capture;
    init.user_data = libmsg;
    nbt__exr_init(&init);
    exr_context_t ctx = NULL;
    errno = 0;
    exr_result_t rv = noted(exr_start_read(&ctx, path, &init));
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

    exr_attr_box2i_t dw, disp;
    exr_storage_t stor = EXR_STORAGE_SCANLINE;
    const exr_attr_chlist_t *pcl = NULL;
    if (exr_get_data_window(ctx, part, &dw) != EXR_ERR_SUCCESS || exr_get_storage(ctx, part, &stor) != EXR_ERR_SUCCESS ||
        exr_get_channels(ctx, part, &pcl) != EXR_ERR_SUCCESS || !pcl) {
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
    if (exr_get_display_window(ctx, part, &disp) != EXR_ERR_SUCCESS)
        disp = dw;
    for (int i = 0; i < pcl->num_channels; i++)
        if ((unsigned)pcl->entries[i].pixel_type > (unsigned)NBT_PIXEL_FLOAT) {
            st = fail(NBT_EFORMAT, path, err, errlen, "channel %s has an unknown pixel type %d", pcl->entries[i].name.str,
                      (int)pcl->entries[i].pixel_type);
            goto done;
        }
    if (!nbt__exr_raw_plausible(path, (double)w64 * (double)h64 * (3.0 + pcl->num_channels) * sizeof(float))) {
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
    im->x0 = dw.min.x;
    im->y0 = dw.min.y;
    im->display.min_x = disp.min.x;
    im->display.min_y = disp.min.y;
    im->display.max_x = disp.max.x;
    im->display.max_y = disp.max.y;
    if ((sel.layer && !(im->rgb_layer = strndup(sel.layer, sel.layer_len))) ||
        (sel.name[SEL_Z] && strcmp(sel.name[SEL_Z], "Z") && !(im->z_name = strdup(sel.name[SEL_Z]))) ||
        keep_channels(pcl, &sel, im) != 0 || keep_attrs(ctx, part, &im->attrs) != 0) {
        st = fail(NBT_ENOMEM, path, err, errlen, "out of memory for the channels and attributes");
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
            errno = 0;
            if (rv == EXR_ERR_SUCCESS)
                rv = noted(decode_chunk(&rd, &ci, 0, (size_t)((int64_t)ci.start_y - dw.min.y)));
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
                errno = 0;
                if (rv == EXR_ERR_SUCCESS)
                    rv = noted(decode_chunk(&rd, &ci, x0, y0));
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
    if (st == NBT_OK && exr_nomem) /* 3.1's header parser drops an attribute it cannot copy and succeeds */
        st = fail(NBT_ENOMEM, path, err, errlen, "out of memory reading the header");
    if (st != NBT_OK) {
        nbt_image_free(im);
        return st;
    }
    *out = im;
    return NBT_OK;
}

/* ---- writing ---- */

/* One output channel: where its values for image pixel (0, 0) are and how
 * they are laid out. */
typedef struct {
    const char *name;
    char *owned;            /* name when built here */
    exr_pixel_type_t type;
    int linear;
    const uint8_t *base;
    int32_t pixel_stride, line_stride, bpe;
} wchan;

/* Sets one kept attribute on the output part. */
static exr_result_t put_attr(exr_context_t ctx, int part, const kattr *k)
{
    const void *b = k->bytes;
    const char *n = k->name;
    switch (k->type) {
    case EXR_ATTR_COMPRESSION: return exr_attr_set_compression(ctx, part, n, (exr_compression_t)k->bytes[0]);
    case EXR_ATTR_ENVMAP: return exr_attr_set_envmap(ctx, part, n, (exr_envmap_t)k->bytes[0]);
    case EXR_ATTR_LINEORDER: return exr_attr_set_lineorder(ctx, part, n, (exr_lineorder_t)k->bytes[0]);
    case EXR_ATTR_DOUBLE: {
        double d;
        memcpy(&d, b, sizeof d);
        return exr_attr_set_double(ctx, part, n, d);
    }
    case EXR_ATTR_FLOAT: {
        float f;
        memcpy(&f, b, sizeof f);
        return exr_attr_set_float(ctx, part, n, f);
    }
    case EXR_ATTR_INT: {
        int32_t v;
        memcpy(&v, b, sizeof v);
        return exr_attr_set_int(ctx, part, n, v);
    }
    case EXR_ATTR_BOX2I: return exr_attr_set_box2i(ctx, part, n, b);
    case EXR_ATTR_BOX2F: return exr_attr_set_box2f(ctx, part, n, b);
    case EXR_ATTR_CHROMATICITIES: return exr_attr_set_chromaticities(ctx, part, n, b);
    case EXR_ATTR_KEYCODE: return exr_attr_set_keycode(ctx, part, n, b);
    case EXR_ATTR_M33F: return exr_attr_set_m33f(ctx, part, n, b);
    case EXR_ATTR_M33D: return exr_attr_set_m33d(ctx, part, n, b);
    case EXR_ATTR_M44F: return exr_attr_set_m44f(ctx, part, n, b);
    case EXR_ATTR_M44D: return exr_attr_set_m44d(ctx, part, n, b);
    case EXR_ATTR_RATIONAL: return exr_attr_set_rational(ctx, part, n, b);
    case EXR_ATTR_TILEDESC: return exr_attr_set_tiledesc(ctx, part, n, b);
    case EXR_ATTR_TIMECODE: return exr_attr_set_timecode(ctx, part, n, b);
    case EXR_ATTR_V2I: return exr_attr_set_v2i(ctx, part, n, b);
    case EXR_ATTR_V2F: return exr_attr_set_v2f(ctx, part, n, b);
    case EXR_ATTR_V2D: return exr_attr_set_v2d(ctx, part, n, b);
    case EXR_ATTR_V3I: return exr_attr_set_v3i(ctx, part, n, b);
    case EXR_ATTR_V3F: return exr_attr_set_v3f(ctx, part, n, b);
    case EXR_ATTR_V3D: return exr_attr_set_v3d(ctx, part, n, b);
    case EXR_ATTR_STRING: return exr_attr_set_string(ctx, part, n, b);
    case EXR_ATTR_FLOAT_VECTOR: return exr_attr_set_float_vector(ctx, part, n, k->n, b);
    case EXR_ATTR_STRING_VECTOR: {
        const char **sv = malloc(((size_t)k->n + 1) * sizeof *sv);
        if (!sv)
            return EXR_ERR_OUT_OF_MEMORY;
        const char *p = b;
        for (int32_t i = 0; i < k->n; i++, p += strlen(p) + 1)
            sv[i] = p;
        exr_result_t rv = exr_attr_set_string_vector(ctx, part, n, k->n, sv);
        free(sv);
        return rv;
    }
    case EXR_ATTR_PREVIEW: {
        exr_attr_preview_t pv;
        memset(&pv, 0, sizeof pv);
        memcpy(&pv.width, k->bytes, sizeof(uint32_t));
        memcpy(&pv.height, k->bytes + sizeof(uint32_t), sizeof(uint32_t));
        pv.rgba = k->bytes + 2 * sizeof(uint32_t);
        return exr_attr_set_preview(ctx, part, n, &pv);
    }
    case EXR_ATTR_OPAQUE: return exr_attr_set_user(ctx, part, n, k->type_name, (int32_t)k->size, b);
    default: return EXR_ERR_INVALID_ATTR;
    }
}

static int box_inside(const nbt_box2i *in, const nbt_box2i *out)
{
    return in->min_x >= out->min_x && in->min_y >= out->min_y && in->max_x <= out->max_x && in->max_y <= out->max_y;
}

/* The writer of both entry points; legacy: nbt_image_write_exr's fixed
 * layout (origin (0, 0), plain names, nothing kept). */
static nbt_status write_any(const nbt_image *im, const char *path, const nbt_exr_write_opts *o, int legacy, char *err,
                            size_t errlen)
{
    static atomic_uint seq;
    static const nbt_exr_write_opts none;
    if (!o)
        o = &none;
    if (err && errlen)
        err[0] = '\0';
    exr_nomem = 0;
    if (!path || !*path)
        return fail(NBT_EINVAL, path, err, errlen, "%s: no path", legacy ? "nbt_image_write_exr" : "nbt_image_write_exr_ex");
    if (!im || !im->rgb || im->w == 0 || im->h == 0)
        return fail(NBT_EINVAL, path, err, errlen, "no image to write (empty or without pixels)");
    if (im->w > (size_t)INT32_MAX / (3 * sizeof(float)) || im->h > (size_t)INT32_MAX)
        return fail(NBT_EINVAL, path, err, errlen, "%zu x %zu pixels is too large for OpenEXR", im->w, im->h);
    size_t w = im->w, h = im->h;
    int64_t ox = legacy ? 0 : im->x0, oy = legacy ? 0 : im->y0;
    if (ox + (int64_t)w - 1 > INT32_MAX || oy + (int64_t)h - 1 > INT32_MAX)
        return fail(NBT_EINVAL, path, err, errlen, "data window (%lld, %lld) + %zu x %zu pixels exceeds OpenEXR's coordinates",
                    (long long)ox, (long long)oy, w, h);
    nbt_box2i data = {(int32_t)ox, (int32_t)oy, (int32_t)(ox + (int64_t)w - 1), (int32_t)(oy + (int64_t)h - 1)};
    nbt_box2i win = o->window ? *o->window : data;
    nbt_box2i disp = legacy ? data : o->display ? *o->display : im->display;
    if (win.max_x < win.min_x || win.max_y < win.min_y || !box_inside(&win, &data))
        return fail(NBT_EINVAL, path, err, errlen,
                    "window (%d, %d) - (%d, %d) is not a non-empty box inside the image's data window (%d, %d) - (%d, %d)",
                    win.min_x, win.min_y, win.max_x, win.max_y, data.min_x, data.min_y, data.max_x, data.max_y);
    if (disp.max_x < disp.min_x || disp.max_y < disp.min_y)
        return fail(NBT_EINVAL, path, err, errlen, "empty display window (%d, %d) - (%d, %d)", disp.min_x, disp.min_y,
                    disp.max_x, disp.max_y);
    if (o->nattrs && (!o->attrs || o->nattrs > SIZE_MAX / 2))
        return fail(NBT_EINVAL, path, err, errlen, "%zu attributes but no attribute list", o->nattrs);
    for (size_t i = 0; i < o->nattrs; i++)
        if (!o->attrs[2 * i] || !o->attrs[2 * i][0] || !o->attrs[2 * i + 1])
            return fail(NBT_EINVAL, path, err, errlen, "attribute %zu has no name or no value", i);
    if (o->nlayers && !o->layers)
        return fail(NBT_EINVAL, path, err, errlen, "%zu layers but no layer list", o->nlayers);
    for (size_t l = 0; l < o->nlayers; l++) {
        const nbt_image_layer *L = &o->layers[l];
        if (!L->name || !L->name[0] || L->nchan < 1 || L->nchan > 64 || !L->chan || !L->data)
            return fail(NBT_EINVAL, path, err, errlen,
                        "layer %zu (%s): needs a name, 1 to 64 channel names and data", l, L->name ? L->name : "no name");
        for (size_t c = 0; c < L->nchan; c++)
            if (!L->chan[c] || !L->chan[c][0])
                return fail(NBT_EINVAL, path, err, errlen, "layer %s: channel %zu has no name", L->name, c);
    }

    /* the channel table: main, caller's layers, then kept channels */
    int keep_ch = !legacy && !o->drop_channels;
    size_t cap = 4 + (keep_ch ? im->nchannels : 0);
    for (size_t l = 0; l < o->nlayers; l++)
        cap += o->layers[l].nchan;
    wchan *ch = calloc(cap, sizeof *ch);
    if (!ch)
        return fail(NBT_ENOMEM, path, err, errlen, "out of memory");
    size_t nch = 0;
    nbt_status st = NBT_OK;
    const char *rl = legacy ? NULL : im->rgb_layer;
    for (int k = 0; k < 4 && st == NBT_OK; k++) {
        static const char *const C[4] = {"R", "G", "B", "Z"};
        wchan *c = &ch[nch];
        if (k == SEL_Z) {
            if (!im->z)
                break;
            c->name = !legacy && im->z_name ? im->z_name : "Z";
            c->base = (const uint8_t *)im->z;
            c->pixel_stride = (int32_t)sizeof(float);
        } else {
            if (rl) {
                size_t n = strlen(rl) + 3;
                if (!(c->owned = malloc(n)))
                    st = NBT_ENOMEM;
                else
                    snprintf(c->owned, n, "%s.%s", rl, C[k]);
                c->name = c->owned;
            } else
                c->name = C[k];
            c->base = (const uint8_t *)(im->rgb + k);
            c->pixel_stride = (int32_t)(3 * sizeof(float));
        }
        c->type = EXR_PIXEL_FLOAT;
        c->bpe = (int32_t)sizeof(float);
        nch++;
    }
    /* layer prefix: the caller's, else the view layer of the RGB layer ("L.Pass" -> "L.") */
    const char *pfx = o->layer_prefix ? o->layer_prefix : rl ? rl : "";
    size_t pfx_len = o->layer_prefix ? strlen(pfx) : 0;
    if (!o->layer_prefix && rl) {
        const char *dot = strrchr(rl, '.');
        pfx_len = dot ? (size_t)(dot - rl) + 1 : 0;
    }
    for (size_t l = 0; l < o->nlayers && st == NBT_OK; l++) {
        const nbt_image_layer *L = &o->layers[l];
        for (size_t c = 0; c < L->nchan && st == NBT_OK; c++) {
            wchan *wc = &ch[nch];
            size_t n = pfx_len + strlen(L->name) + strlen(L->chan[c]) + 2;
            if (!(wc->owned = malloc(n))) {
                st = NBT_ENOMEM;
                break;
            }
            snprintf(wc->owned, n, "%.*s%s.%s", (int)pfx_len, pfx, L->name, L->chan[c]);
            wc->name = wc->owned;
            wc->type = EXR_PIXEL_FLOAT;
            wc->bpe = (int32_t)sizeof(float);
            wc->base = (const uint8_t *)(L->data + c);
            wc->pixel_stride = (int32_t)(L->nchan * sizeof(float));
            nch++;
        }
    }
    size_t nmade = nch;
    if (st == NBT_ENOMEM) {
        st = fail(NBT_ENOMEM, path, err, errlen, "out of memory");
        goto out;
    }
    for (size_t i = 0; i < nmade; i++)
        for (size_t j = 0; j < i; j++)
            if (!strcmp(ch[i].name, ch[j].name)) {
                st = fail(NBT_EINVAL, path, err, errlen, "two channels named %s", ch[i].name);
                goto out;
            }
    for (size_t i = 0; keep_ch && i < im->nchannels; i++) {
        const nbt_image_channel *kc = &im->channels[i];
        if (!kc->data || !kc->name)
            continue; /* subsampled: not kept */
        int taken = 0;
        for (size_t j = 0; j < nmade; j++)
            taken |= !strcmp(kc->name, ch[j].name); /* replaced by the caller's layer */
        if (taken)
            continue;
        wchan *wc = &ch[nch++];
        wc->name = kc->name;
        wc->type = (exr_pixel_type_t)kc->type;
        wc->linear = kc->linear;
        wc->bpe = (int32_t)ptype_size(kc->type);
        wc->base = kc->data;
        wc->pixel_stride = wc->bpe;
    }
    for (size_t i = 0; i < nch; i++)
        ch[i].line_stride = (int32_t)((size_t)ch[i].pixel_stride * w);

    size_t tlen = strlen(path) + 48;
    char *tmp = malloc(tlen);
    if (!tmp) {
        st = fail(NBT_ENOMEM, path, err, errlen, "out of memory");
        goto out;
    }
    snprintf(tmp, tlen, "%s.tmp%ld.%u", path, (long)getpid(), atomic_fetch_add(&seq, 1u));
    /* create it here for a reliable errno (the core library opens it again, truncating) */
    int fd = open(tmp, O_WRONLY | O_CREAT | O_EXCL, 0666);
    if (fd < 0) {
        int e = errno;
        st = fail(NBT_EIO, path, err, errlen, "cannot create %s: %s", tmp, strerror(e));
        free(tmp);
        goto out;
    }
    close(fd);

    char libmsg[LIBMSG_LEN] = "";
    exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
    init.error_handler_fn = capture_write;
    capture_write_buf = libmsg;
    nbt__exr_init(&init);
    exr_context_t ctx = NULL;
    int part = 0;
    const nbt_image_attrs *ka = legacy || o->drop_attrs ? NULL : im->attrs;
    float par = 1.0f, sww = 1.0f;
    exr_attr_v2f_t swc;
    swc.x = swc.y = 0.0f;
    for (size_t i = 0; ka && i < ka->n; i++) {
        if (ka->a[i].type == EXR_ATTR_FLOAT && !strcmp(ka->a[i].name, "pixelAspectRatio"))
            memcpy(&par, ka->a[i].bytes, sizeof par);
        if (ka->a[i].type == EXR_ATTR_FLOAT && !strcmp(ka->a[i].name, "screenWindowWidth"))
            memcpy(&sww, ka->a[i].bytes, sizeof sww);
        if (ka->a[i].type == EXR_ATTR_V2F && !strcmp(ka->a[i].name, "screenWindowCenter"))
            memcpy(&swc, ka->a[i].bytes, sizeof swc);
    }
    exr_attr_box2i_t edw, edisp;
    edw.min.x = win.min_x, edw.min.y = win.min_y, edw.max.x = win.max_x, edw.max.y = win.max_y;
    edisp.min.x = disp.min_x, edisp.min.y = disp.min_y, edisp.max.x = disp.max_x, edisp.max.y = disp.max_y;
    /* names over 31 characters (Blender's cycles.ViewLayer.synchronization_time)
     * need the file's long-names flag, as OpenEXR's C++ library sets it */
    int longnames = 0;
    for (size_t c = 0; c < nch; c++)
        longnames |= strlen(ch[c].name) > 31;
    for (size_t i = 0; i < o->nattrs; i++)
        longnames |= strlen(o->attrs[2 * i]) > 31;
    for (size_t i = 0; ka && i < ka->n; i++)
        longnames |= strlen(ka->a[i].name) > 31;
    errno = 0; /* from here an ENOMEM is an allocation's (noted) */
    exr_result_t rv = exr_start_write(&ctx, tmp, EXR_WRITE_FILE_DIRECTLY, &init);
    if (rv == EXR_ERR_SUCCESS && longnames)
        rv = exr_set_longname_support(ctx, 1);
    if (rv == EXR_ERR_SUCCESS)
        rv = exr_add_part(ctx, NULL, EXR_STORAGE_SCANLINE, &part);
    if (rv == EXR_ERR_SUCCESS)
        rv = exr_initialize_required_attr(ctx, part, &edisp, &edw, par, &swc, sww, EXR_LINEORDER_INCREASING_Y,
                                          EXR_COMPRESSION_ZIP);
    /* pLinear = 0 (as OpenEXR's RGBA interface writes it): linear radiance is not perceptually linear */
    for (size_t c = 0; c < nch && rv == EXR_ERR_SUCCESS; c++)
        rv = (exr_result_t)exr_add_channel(ctx, part, ch[c].name, ch[c].type,
                                           ch[c].linear ? EXR_PERCEPTUALLY_LINEAR : EXR_PERCEPTUALLY_LOGARITHMIC, 1, 1);
    size_t bad_attr = o->nattrs;
    for (size_t i = 0; i < o->nattrs && rv == EXR_ERR_SUCCESS; i++)
        if ((rv = exr_attr_set_string(ctx, part, o->attrs[2 * i], o->attrs[2 * i + 1])) != EXR_ERR_SUCCESS)
            bad_attr = i;
    /* kept attributes that the caller's and the layout's do not replace */
    const char *bad_kept = NULL;
    for (size_t i = 0; ka && i < ka->n && rv == EXR_ERR_SUCCESS; i++) {
        const exr_attribute_t *have = NULL;
        if (exr_get_attribute_by_name(ctx, part, ka->a[i].name, &have) == EXR_ERR_SUCCESS)
            continue;
        libmsg[0] = '\0';
        if ((rv = put_attr(ctx, part, &ka->a[i])) != EXR_ERR_SUCCESS)
            bad_kept = ka->a[i].name;
    }
    if (rv == EXR_ERR_SUCCESS)
        rv = exr_write_header(ctx);
    int32_t lpc = 1;
    if (rv == EXR_ERR_SUCCESS)
        rv = exr_get_scanlines_per_chunk(ctx, part, &lpc);
    if (rv == EXR_ERR_SUCCESS && lpc < 1)
        rv = EXR_ERR_INVALID_ARGUMENT;
    exr_encode_pipeline_t enc = EXR_ENCODE_PIPELINE_INITIALIZER;
    int started = 0;
    size_t col = (size_t)((int64_t)win.min_x - data.min_x);
    for (int64_t y = win.min_y; y <= win.max_y && rv == EXR_ERR_SUCCESS; y += lpc) {
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
        size_t row = (size_t)((int64_t)ci.start_y - data.min_y);
        for (int16_t c = 0; c < enc.channel_count; c++) {
            exr_coding_channel_info_t *ec = &enc.channels[c];
            size_t k = 0;
            while (k < nch && strcmp(ec->channel_name, ch[k].name))
                k++;
            if (k == nch) {
                rv = EXR_ERR_INVALID_ARGUMENT;
                break;
            }
            ec->encode_from_ptr = ch[k].base + row * (size_t)ch[k].line_stride + col * (size_t)ch[k].pixel_stride;
            ec->user_pixel_stride = ch[k].pixel_stride;
            ec->user_line_stride = ch[k].line_stride;
            ec->user_bytes_per_element = (int16_t)ch[k].bpe;
            ec->user_data_type = (uint16_t)ch[k].type;
        }
        if (rv == EXR_ERR_SUCCESS)
            rv = exr_encoding_choose_default_routines(ctx, part, &enc);
        errno = 0;
        if (rv == EXR_ERR_SUCCESS)
            rv = noted(exr_encoding_run(ctx, part, &enc));
    }
    noted(rv);
    if (started)
        exr_encoding_destroy(ctx, &enc);
    exr_result_t fr = ctx ? noted(exr_finish(&ctx)) : EXR_ERR_SUCCESS;
    capture_write_buf = NULL;
    if (exr_nomem) { /* whatever the library made of it */
        unlink(tmp);
        st = fail(NBT_ENOMEM, path, err, errlen, "out of memory writing OpenEXR data");
    } else if (bad_attr < o->nattrs) {
        unlink(tmp);
        st = fail(NBT_EINVAL, path, err, errlen, "attribute \"%s\" cannot be set (%s)", o->attrs[2 * bad_attr],
                  lib_detail(libmsg, rv));
    } else if (bad_kept) {
        unlink(tmp);
        st = fail(NBT_EFORMAT, path, err, errlen, "kept attribute \"%s\" cannot be written (%s)", bad_kept,
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
out:
    for (size_t i = 0; i < cap; i++)
        free(ch[i].owned);
    free(ch);
    return st;
}

nbt_status nbt_image_write_exr(const nbt_image *im, const char *path, const char *const *attrs, size_t nattrs,
                               char *err, size_t errlen)
{
    nbt_exr_write_opts o;
    memset(&o, 0, sizeof o);
    o.attrs = attrs;
    o.nattrs = nattrs;
    return write_any(im, path, &o, 1, err, errlen);
}

nbt_status nbt_image_write_exr_ex(const nbt_image *im, const char *path, const nbt_exr_write_opts *opts, char *err,
                                  size_t errlen)
{
    return write_any(im, path, opts, 0, err, errlen);
}

nbt_status nbt_image_copy_meta(nbt_image *dst, const nbt_image *src)
{
    if (!dst || !src || dst == src)
        return nbt__fail(NBT_EINVAL, "nbt_image_copy_meta: no image, or the same image twice");
    if (dst->w != src->w || dst->h != src->h) {
        char line[160];
        snprintf(line, sizeof line, "nbt_image_copy_meta: images differ in size (%zu x %zu and %zu x %zu)", dst->w,
                 dst->h, src->w, src->h);
        return nbt__fail(NBT_EINVAL, line);
    }
    nbt_image t;
    memset(&t, 0, sizeof t);
    int bad = 0;
    if (src->rgb_layer && !(t.rgb_layer = strdup(src->rgb_layer)))
        bad = 1;
    if (src->z_name && !(t.z_name = strdup(src->z_name)))
        bad = 1;
    if (src->attrs && !(t.attrs = attrs_dup(src->attrs)))
        bad = 1;
    if (src->nchannels && !(t.channels = calloc(src->nchannels, sizeof *t.channels)))
        bad = 1;
    for (size_t i = 0; !bad && i < src->nchannels; i++, t.nchannels++) {
        const nbt_image_channel *c = &src->channels[i];
        t.channels[i] = *c;
        t.channels[i].data = NULL;
        if (!(t.channels[i].name = strdup(c->name)) ||
            (c->data && !(t.channels[i].data = memdup(c->data, src->w * src->h * ptype_size(c->type)))))
            bad = 1;
    }
    if (bad) {
        free(t.rgb_layer), free(t.z_name), attrs_free(t.attrs);
        for (size_t i = 0; i < t.nchannels; i++)
            free(t.channels[i].name), free(t.channels[i].data);
        free(t.channels);
        return nbt__fail(NBT_ENOMEM, "nbt_image_copy_meta: out of memory");
    }
    free(dst->rgb_layer), free(dst->z_name), attrs_free(dst->attrs);
    for (size_t i = 0; i < dst->nchannels; i++)
        free(dst->channels[i].name), free(dst->channels[i].data);
    free(dst->channels);
    dst->x0 = src->x0;
    dst->y0 = src->y0;
    dst->display = src->display;
    dst->rgb_layer = t.rgb_layer;
    dst->z_name = t.z_name;
    dst->attrs = t.attrs;
    dst->channels = t.channels;
    dst->nchannels = t.nchannels;
    return NBT_OK;
}
