/* libnbt/table_exr.c: tables as OpenEXR files (C core API).
 *
 * Scan line y holds node y of axis 1 (y = 0 is axis[1].lo), pixel x node x
 * of axis 0; a 3-D table stacks its slices: scan line m ny + y is node y of
 * slice m. Channels R, G, B, A carry consecutive table channels. Only
 * NONE and ZIP compression are written (ZIPS has an encoder bug in 3.1.5). */
#include <config.h>
#include <errno.h>
#include <float.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include <openexr.h>
#include <nbt/nbt.h>
#include "internal.h"

static const char *const CH[NBT_TABLE_MAX_CH] = {"R", "G", "B", "A"};

static void quiet(exr_const_context_t c, exr_result_t code, const char *msg)
{
    (void)c;
    (void)code;
    (void)msg; /* errors are reported through return codes */
}

static uint16_t half_bits(float f)
{
    /* f is already representable as a half (nbt_table_round_half) */
    union { float f; uint32_t u; } v = {f};
    uint32_t s = (v.u >> 16) & 0x8000u, e = (v.u >> 23) & 0xffu, m = v.u & 0x7fffffu;
    if (e == 0xff)
        return (uint16_t)(s | 0x7c00u | (m ? 0x200u : 0));
    int ee = (int)e - 127 + 15;
    if (ee >= 31)
        return (uint16_t)(s | 0x7c00u);
    if (ee <= 0) { /* subnormal half */
        if (ee < -10)
            return (uint16_t)s;
        m |= 0x800000u;
        return (uint16_t)(s | (m >> (14 - ee)));
    }
    return (uint16_t)(s | ((uint32_t)ee << 10) | (m >> 13));
}

static float half_float(uint16_t h)
{
    uint32_t s = (uint32_t)(h & 0x8000u) << 16, e = (h >> 10) & 0x1fu, m = h & 0x3ffu;
    float v;
    if (e == 0)
        v = ldexpf((float)m, -24);
    else if (e == 31)
        v = m ? NAN : INFINITY;
    else
        v = ldexpf((float)(m | 0x400u), (int)e - 25);
    return s ? -v : v;
}

static const char *axis_attr(int a, const char *what, char *buf, size_t n)
{
    snprintf(buf, n, "nbt.axis%d.%s", a, what);
    return buf;
}

/* recorded errors e[k * nc + c] (n per channel) as one float vector per
 * channel, nbt.NAME.R ..., rounded up so that they still bound; written
 * only where every value was recorded. NAME: cell_err (per g cell) or
 * row_err (per x0 row and g cell, g cell after g cell; readers without it
 * use cell_err). */
static exr_result_t write_err_vectors(exr_context_t ctx, int part, const double *e, size_t n, size_t nc,
                                      const char *name)
{
    for (size_t i = 0; i < n * nc; i++)
        if (!(e[i] >= 0.0))
            return EXR_ERR_SUCCESS;
    float *v = malloc(n * sizeof *v);
    if (!v)
        return EXR_ERR_OUT_OF_MEMORY;
    exr_result_t rv = EXR_ERR_SUCCESS;
    char an[64];
    for (size_t c = 0; c < nc && rv == EXR_ERR_SUCCESS; c++) {
        for (size_t k = 0; k < n; k++) {
            v[k] = (float)e[k * nc + c];
            if ((double)v[k] < e[k * nc + c])
                v[k] = nextafterf(v[k], INFINITY);
        }
        snprintf(an, sizeof an, "nbt.%s.%s", name, CH[c]);
        rv = exr_attr_set_float_vector(ctx, part, an, (int32_t)n, v);
    }
    free(v);
    return rv;
}

nbt_status nbt_table_write_exr(const nbt_table *t, const char *path, nbt_exr_compression comp)
{
    return nbt_table_write_exr_progress(t, path, comp, NULL, NULL);
}

nbt_status nbt_table_write_exr_progress(const nbt_table *t, const char *path, nbt_exr_compression comp,
                                        void (*progress)(double fraction, void *data), void *data)
{
    /* a 3-D table: its slices are scan lines one after another */
    size_t nx = t->axis[0].n, ny = t->axis[1].n * t->axis[2].n, nc = t->nch, plen = strlen(path);
    int nax = t->axis[2].n > 1 ? 3 : 2;
    char *tmp = malloc(plen + 32);
    if (!tmp)
        NBT_FAIL(NBT_ENOMEM, "EXR: out of memory");
    snprintf(tmp, plen + 32, "%s.tmp%ld", path, (long)getpid());
    int bpe = t->half ? 2 : 4;
    uint8_t *pix = malloc(nx * ny * nc * (size_t)bpe);
    if (!pix) {
        free(tmp);
        NBT_FAIL(NBT_ENOMEM, "EXR: out of memory");
    }
    for (size_t i = 0; i < nx * ny * nc; i++) {
        if (t->half) {
            uint16_t h = half_bits(t->data[i]);
            memcpy(pix + 2 * i, &h, 2);
        } else
            memcpy(pix + 4 * i, &t->data[i], 4);
    }
    exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
    init.error_handler_fn = quiet;
    nbt__exr_init(&init);
    exr_context_t ctx = NULL;
    exr_result_t rv = exr_start_write(&ctx, tmp, EXR_WRITE_FILE_DIRECTLY, &init);
    int part = 0;
    char an[64], buf[256];
    if (rv == EXR_ERR_SUCCESS)
        rv = exr_add_part(ctx, "nbt", EXR_STORAGE_SCANLINE, &part);
    if (rv == EXR_ERR_SUCCESS)
        rv = exr_initialize_required_attr_simple(ctx, part, (int32_t)nx, (int32_t)ny,
                                                 comp == NBT_EXR_ZIP ? EXR_COMPRESSION_ZIP : EXR_COMPRESSION_NONE);
    for (size_t c = 0; c < nc && rv == EXR_ERR_SUCCESS; c++)
        rv = exr_add_channel(ctx, part, CH[c], t->half ? EXR_PIXEL_HALF : EXR_PIXEL_FLOAT,
                             EXR_PERCEPTUALLY_LINEAR, 1, 1);
    if (rv == EXR_ERR_SUCCESS)
        rv = exr_set_version(ctx, part, 1);
    /* metadata: enough to use the file alone */
    if (rv == EXR_ERR_SUCCESS)
        rv = exr_attr_set_string(ctx, part, "nbt.kind", nbt_table_kind_name(t->kind));
    for (int a = 0; a < nax && rv == EXR_ERR_SUCCESS; a++) {
        const nbt_axis *ax = &t->axis[a];
        rv = exr_attr_set_string(ctx, part, axis_attr(a, "name", an, sizeof an), nbt_table_axis_name(t->kind, a));
        if (rv == EXR_ERR_SUCCESS && a == 2)
            rv = exr_attr_set_int(ctx, part, axis_attr(a, "n", an, sizeof an), (int32_t)ax->n);
        if (rv == EXR_ERR_SUCCESS && a == 2)
            rv = exr_attr_set_int(ctx, part, axis_attr(a, "interp", an, sizeof an),
                                  t->interp2 == 2 || t->interp2 == 3 ? t->interp2 : 1);
        if (rv == EXR_ERR_SUCCESS)
            rv = exr_attr_set_string(ctx, part, axis_attr(a, "map", an, sizeof an), nbt_axis_map_name(ax->map));
        if (rv == EXR_ERR_SUCCESS)
            rv = exr_attr_set_double(ctx, part, axis_attr(a, "lo", an, sizeof an), ax->lo);
        if (rv == EXR_ERR_SUCCESS)
            rv = exr_attr_set_double(ctx, part, axis_attr(a, "hi", an, sizeof an), ax->hi);
        if (rv == EXR_ERR_SUCCESS)
            rv = exr_attr_set_double(ctx, part, axis_attr(a, "c", an, sizeof an), ax->c);
    }
    if (rv == EXR_ERR_SUCCESS)
        rv = exr_attr_set_string(ctx, part, "nbt.texcoord",
                                 "node-aligned: s = map(x) in [0,1], tex = (s*(N-1)+0.5)/N; "
                                 "scanline 0 = axis1.lo; 3-D (nbt.axis2.n slices): scanline m*axis1.n + y "
                                 "= node y of slice m; sqrt: s = sqrt(r), log1p: s = log1p(c r)/log1p(c), "
                                 "cos: s = acos(1-2r)/pi, log1p_cbrt: s = cbrt(log1p(c r)/log1p(c)), "
                                 "r = (x-lo)/(hi-lo); atanh: s = (atanh x - atanh lo)/(atanh hi - atanh lo); "
                                 "axis2.interp 2: quadratic in s2 through slices m-1, m, m+1, "
                                 "m = round(s2 (N-1)) clamped to [1, N-2]; axis2.interp 3: cubic (Lagrange) "
                                 "through slices m0..m0+3, m0 = floor(s2 (N-1)) - 1 clamped to [0, N-4]");
    size_t off = 0;
    buf[0] = '\0';
    for (size_t c = 0; c < nc; c++)
        off += (size_t)snprintf(buf + off, sizeof buf - off, "%s%s=%d", c ? " " : "", CH[c], t->k[c]);
    if (rv == EXR_ERR_SUCCESS)
        rv = exr_attr_set_string(ctx, part, "nbt.channels_k", buf);
    if (rv == EXR_ERR_SUCCESS)
        rv = exr_attr_set_int(ctx, part, "nbt.n", t->n);
    if (rv == EXR_ERR_SUCCESS)
        rv = exr_attr_set_string(ctx, part, "nbt.phase", t->phase[0] ? t->phase : "legendre");
    if (rv == EXR_ERR_SUCCESS)
        rv = exr_attr_set_double(ctx, part, "nbt.quad_tol", t->quad_tol);
    if (rv == EXR_ERR_SUCCESS)
        rv = exr_attr_set_double(ctx, part, "nbt.quad_err", t->quad_err);
    for (size_t c = 0; c < nc && rv == EXR_ERR_SUCCESS; c++) {
        snprintf(an, sizeof an, "nbt.max_err.%s", CH[c]);
        rv = exr_attr_set_double(ctx, part, an, t->max_err[c]);
        snprintf(an, sizeof an, "nbt.max_abs.%s", CH[c]);
        if (rv == EXR_ERR_SUCCESS)
            rv = exr_attr_set_double(ctx, part, an, t->max_abs[c]);
    }
    if (rv == EXR_ERR_SUCCESS)
        rv = exr_attr_set_string(ctx, part, "nbt.form", nbt_table_form_name(t->form));
    /* form sub: the closed form the values exclude (its coefficients are
     * float values, so the vectors hold them exactly) */
    if (rv == EXR_ERR_SUCCESS && t->form == NBT_FORM_SUB)
        rv = exr_attr_set_string(ctx, part, "nbt.sub.decay", t->sub_decay == NBT_SUB_EXP ? "exp" : "recip");
    if (rv == EXR_ERR_SUCCESS && t->form == NBT_FORM_SUB)
        rv = exr_attr_set_double(ctx, part, "nbt.sub.w", t->sub_w);
    for (size_t c = 0; rv == EXR_ERR_SUCCESS && t->form == NBT_FORM_SUB && c < nc; c++) {
        float v[NBT_SUB_TERMS];
        for (int q = 0; q < NBT_SUB_TERMS; q++)
            v[q] = (float)t->sub_c[c][q];
        snprintf(an, sizeof an, "nbt.sub.%s", CH[c]);
        rv = exr_attr_set_float_vector(ctx, part, an, NBT_SUB_TERMS, v);
    }
    if (rv == EXR_ERR_SUCCESS && nax == 3)
        rv = write_err_vectors(ctx, part, t->cell_err, t->axis[2].n - 1, t->nch, "cell_err");
    if (rv == EXR_ERR_SUCCESS && t->row_err)
        rv = write_err_vectors(ctx, part, t->row_err, nbt_table_row_err_len(t) / t->nch, t->nch, "row_err");
    /* the theta map with its band width: a reader cannot take another layout */
    if (rv == EXR_ERR_SUCCESS && t->theta_err)
        rv = exr_attr_set_int(ctx, part, "nbt.theta_err.cells", (int32_t)t->theta_cells);
    if (rv == EXR_ERR_SUCCESS && t->theta_err)
        rv = exr_attr_set_string(ctx, part, "nbt.theta_err.layout",
                                 "theta_err[(m * B + b) * (axis0.n - 1) + i] bounds the lookup for axis0 between "
                                 "nodes i and i + 1, axis1 in cells b C .. (b + 1) C - 1 (C = nbt.theta_err.cells, "
                                 "B = ceil((axis1.n - 1) / C), the last band may hold fewer), axis2 in cell m");
    if (rv == EXR_ERR_SUCCESS && t->theta_err)
        rv = write_err_vectors(ctx, part, t->theta_err, nbt_table_theta_err_len(t) / t->nch, t->nch, "theta_err");
    if (rv == EXR_ERR_SUCCESS)
        rv = exr_attr_set_string(ctx, part, "nbt.version", nbt_version());
    if (rv == EXR_ERR_SUCCESS)
        rv = exr_write_header(ctx);
    int32_t lpc = 1;
    if (rv == EXR_ERR_SUCCESS)
        rv = exr_get_scanlines_per_chunk(ctx, part, &lpc);
    exr_encode_pipeline_t enc = EXR_ENCODE_PIPELINE_INITIALIZER;
    int first = 1;
    errno = 0; /* zlib allocates with malloc, not through the context: ENOMEM here is its failure */
    for (int32_t y = 0; y < (int32_t)ny && rv == EXR_ERR_SUCCESS; y += lpc) {
        exr_chunk_info_t ci;
        rv = exr_write_scanline_chunk_info(ctx, part, y, &ci);
        if (rv != EXR_ERR_SUCCESS)
            break;
        rv = first ? exr_encoding_initialize(ctx, part, &ci, &enc) : exr_encoding_update(ctx, part, &ci, &enc);
        if (rv != EXR_ERR_SUCCESS)
            break;
        for (int16_t c = 0; c < enc.channel_count; c++) {
            exr_coding_channel_info_t *ch = &enc.channels[c];
            size_t idx = 0;
            while (idx < nc && strcmp(ch->channel_name, CH[idx]))
                idx++;
            ch->user_pixel_stride = (int32_t)(nc * (size_t)bpe);
            ch->user_line_stride = (int32_t)(nx * nc * (size_t)bpe);
            ch->user_bytes_per_element = (int16_t)bpe;
            ch->user_data_type = t->half ? EXR_PIXEL_HALF : EXR_PIXEL_FLOAT;
            ch->encode_from_ptr = pix + ((size_t)y * nx * nc + idx) * (size_t)bpe;
        }
        if (first)
            rv = exr_encoding_choose_default_routines(ctx, part, &enc);
        first = 0;
        if (rv == EXR_ERR_SUCCESS)
            rv = exr_encoding_run(ctx, part, &enc);
        if (rv == EXR_ERR_SUCCESS && progress)
            progress(y + lpc >= (int32_t)ny ? 1.0 : (double)(y + lpc) / (double)ny, data);
    }
    int zlib_nomem = rv != EXR_ERR_SUCCESS && errno == ENOMEM;
    if (!first)
        exr_encoding_destroy(ctx, &enc);
    exr_result_t fr = ctx ? exr_finish(&ctx) : EXR_ERR_SUCCESS;
    free(pix);
    nbt_status st = NBT_OK;
    if (rv == EXR_ERR_OUT_OF_MEMORY || fr == EXR_ERR_OUT_OF_MEMORY || nbt__exr_nomem() || zlib_nomem)
        st = NBT_ENOMEM; /* whatever the library made of it */
    else if (rv != EXR_ERR_SUCCESS || fr != EXR_ERR_SUCCESS || rename(tmp, path) != 0)
        st = NBT_EIO;
    if (st != NBT_OK)
        unlink(tmp);
    free(tmp);
    if (st == NBT_ENOMEM)
        NBT_FAIL(st, "EXR: out of memory writing the table");
    if (st != NBT_OK)
        NBT_FAIL(st, "EXR: writing the table failed");
    return NBT_OK;
}

static nbt_status rd_fail(char *err, size_t n, const char *path, const char *what)
{
    snprintf(err, n, "%s: %s", path, what);
    return NBT_EFORMAT;
}

/* an error vector's n values into channel c of dst (nc channels), each >= 0 and finite */
static nbt_status copy_err_vector(const float *v, size_t n, double *dst, size_t nc, size_t c, const char *what,
                                  const char *path, char *err, size_t errlen)
{
    for (size_t k = 0; k < n; k++) {
        if (!(v[k] >= 0.0f && v[k] <= FLT_MAX)) {
            char msg[96];
            snprintf(msg, sizeof msg, "%s is negative or not finite (accepted: >= 0)", what);
            return rd_fail(err, errlen, path, msg);
        }
        dst[k * nc + c] = v[k];
    }
    return NBT_OK;
}

nbt_status nbt_table_read_exr(const char *path, nbt_table **out, char *err, size_t errlen)
{
    *out = NULL;
    FILE *probe = fopen(path, "rb");
    if (!probe) {
        int e = errno;
        snprintf(err, errlen, "%s: cannot open: %s", path, strerror(e));
        return nbt__io_status(e);
    }
    fclose(probe);
    exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
    init.error_handler_fn = quiet;
    init.flags = EXR_CONTEXT_FLAG_SILENT_HEADER_PARSE;
    nbt__exr_init(&init);
    exr_context_t ctx = NULL;
    exr_result_t rv0 = exr_start_read(&ctx, path, &init);
    if (rv0 != EXR_ERR_SUCCESS) {
        if (ctx)
            exr_finish(&ctx);
        if (rv0 == EXR_ERR_OUT_OF_MEMORY || nbt__exr_nomem()) {
            snprintf(err, errlen, "%s: out of memory", path);
            return NBT_ENOMEM;
        }
        return rd_fail(err, errlen, path, "not an OpenEXR file");
    }
    nbt_status st = NBT_OK;
    exr_result_t rv = EXR_ERR_SUCCESS;
    nbt_table *t = NULL;
    uint8_t *pix = NULL;
    const char *s;
    int32_t len;
    exr_attr_box2i_t dw;
    const exr_attr_chlist_t *cl;
    nbt_axis ax[3] = {{0, 0, NBT_AXIS_LINEAR, 0, 0}, {0, 0, NBT_AXIS_LINEAR, 0, 0}, {0, 1, NBT_AXIS_LINEAR, 0, 1}};
    nbt_table_kind kind = NBT_TABLE_H;
    char an[64];
    if (exr_attr_get_string(ctx, 0, "nbt.kind", &len, &s) != EXR_ERR_SUCCESS ||
        (strcmp(s, "H") && strcmp(s, "J") && strcmp(s, "PSI") && strcmp(s, "KERNEL"))) {
        st = rd_fail(err, errlen, path, "no nbt.kind attribute (H, J, PSI or KERNEL): not a table written by nbt");
        goto done;
    }
    kind = !strcmp(s, "H") ? NBT_TABLE_H : !strcmp(s, "J") ? NBT_TABLE_J : !strcmp(s, "PSI") ? NBT_TABLE_PSI : NBT_TABLE_KERNEL;
    if (exr_get_data_window(ctx, 0, &dw) != EXR_ERR_SUCCESS || exr_get_channels(ctx, 0, &cl) != EXR_ERR_SUCCESS) {
        st = rd_fail(err, errlen, path, "unreadable data window or channel list");
        goto done;
    }
    int32_t nslices = 1;
    int nax = exr_attr_get_int(ctx, 0, axis_attr(2, "n", an, sizeof an), &nslices) == EXR_ERR_SUCCESS ? 3 : 2;
    if (nax == 3 && nslices < 2) {
        st = rd_fail(err, errlen, path, "nbt.axis2.n must be at least 2");
        goto done;
    }
    for (int a = 0; a < nax; a++) {
        int64_t na = a == 0 ? (int64_t)dw.max.x - dw.min.x + 1
                   : a == 2 ? nslices : ((int64_t)dw.max.y - dw.min.y + 1);
        if (a == 1 && nax == 3) { /* slices stacked in y */
            if (na % nslices) {
                st = rd_fail(err, errlen, path, "the image height is not a multiple of nbt.axis2.n");
                goto done;
            }
            na /= nslices;
        }
        ax[a].n = na > 0 ? (size_t)na : 0; /* 0: rejected by nbt_table_alloc */
        if (exr_attr_get_string(ctx, 0, axis_attr(a, "map", an, sizeof an), &len, &s) != EXR_ERR_SUCCESS ||
            nbt_axis_map_parse(s, &ax[a].map) != NBT_OK ||
            exr_attr_get_double(ctx, 0, axis_attr(a, "lo", an, sizeof an), &ax[a].lo) != EXR_ERR_SUCCESS ||
            exr_attr_get_double(ctx, 0, axis_attr(a, "hi", an, sizeof an), &ax[a].hi) != EXR_ERR_SUCCESS ||
            exr_attr_get_double(ctx, 0, axis_attr(a, "c", an, sizeof an), &ax[a].c) != EXR_ERR_SUCCESS) {
            st = rd_fail(err, errlen, path, "missing or bad nbt.axis attributes");
            goto done;
        }
    }
    size_t nc = (size_t)cl->num_channels;
    int half = nc > 0 && cl->entries[0].pixel_type == EXR_PIXEL_HALF;
    for (size_t c = 0; c < nc; c++)
        if (c >= NBT_TABLE_MAX_CH || (cl->entries[c].pixel_type == EXR_PIXEL_HALF) != half ||
            (cl->entries[c].pixel_type != EXR_PIXEL_HALF && cl->entries[c].pixel_type != EXR_PIXEL_FLOAT)) {
            st = rd_fail(err, errlen, path, "channels must be 1-4 of R, G, B, A, all FLOAT or all HALF");
            goto done;
        }
    if (!nbt__exr_raw_plausible(path, (double)ax[0].n * (double)ax[1].n * (double)ax[2].n * (double)(nc ? nc : 1) *
                                          (half ? 2.0 : 4.0))) {
        st = rd_fail(err, errlen, path, "the data window is more than the file can hold: corrupt header");
        goto done;
    }
    errno = 0; /* NULL for bad axes (errno stays 0) or no memory (ENOMEM) */
    t = nbt_table_alloc3(kind, &ax[0], &ax[1], &ax[2], nc);
    if (!t && errno == ENOMEM) {
        st = NBT_ENOMEM;
        snprintf(err, errlen, "%s: out of memory", path);
        goto done;
    }
    if (!t) {
        st = rd_fail(err, errlen, path, "bad table axes or size");
        goto done;
    }
    t->half = half;
    if (exr_attr_get_string(ctx, 0, "nbt.channels_k", &len, &s) != EXR_ERR_SUCCESS) {
        st = rd_fail(err, errlen, path, "missing nbt.channels_k attribute");
        goto done;
    }
    for (size_t c = 0; c < nc; c++) {
        char key[4];
        snprintf(key, sizeof key, "%s=", CH[c]);
        const char *p = strstr(s, key);
        if (!p || sscanf(p + 2, "%d", &t->k[c]) != 1) {
            st = rd_fail(err, errlen, path, "nbt.channels_k does not name every channel");
            goto done;
        }
    }
    exr_attr_get_int(ctx, 0, "nbt.n", &t->n);
    if (exr_attr_get_string(ctx, 0, "nbt.phase", &len, &s) == EXR_ERR_SUCCESS && strcmp(s, "legendre"))
        snprintf(t->phase, sizeof t->phase, "%s", s);
    exr_attr_get_double(ctx, 0, "nbt.quad_tol", &t->quad_tol);
    exr_attr_get_double(ctx, 0, "nbt.quad_err", &t->quad_err);
    for (size_t c = 0; c < nc; c++) {
        snprintf(an, sizeof an, "nbt.max_err.%s", CH[c]);
        exr_attr_get_double(ctx, 0, an, &t->max_err[c]);
        snprintf(an, sizeof an, "nbt.max_abs.%s", CH[c]);
        exr_attr_get_double(ctx, 0, an, &t->max_abs[c]);
    }
    if (exr_attr_get_string(ctx, 0, "nbt.form", &len, &s) == EXR_ERR_SUCCESS &&
        nbt_table_form_parse(s, &t->form) != NBT_OK) {
        st = rd_fail(err, errlen, path, "unknown nbt.form (written by a newer nbt?)");
        goto done;
    }
    if (t->form == NBT_FORM_SUB) {
        double w = -1;
        if (nax == 3 || exr_attr_get_string(ctx, 0, "nbt.sub.decay", &len, &s) != EXR_ERR_SUCCESS ||
            (strcmp(s, "exp") && strcmp(s, "recip")) || exr_attr_get_double(ctx, 0, "nbt.sub.w", &w) != EXR_ERR_SUCCESS ||
            !(w >= 0 && w <= 1e3)) {
            st = rd_fail(err, errlen, path, "form sub needs a 2-D table with nbt.sub.decay (exp or recip) and "
                                            "nbt.sub.w in [0, 1e3]");
            goto done;
        }
        t->sub_decay = strcmp(s, "exp") ? NBT_SUB_RECIP : NBT_SUB_EXP;
        t->sub_w = w;
        for (size_t c = 0; c < nc; c++) {
            int32_t ne = 0;
            const float *v = NULL;
            snprintf(an, sizeof an, "nbt.sub.%s", CH[c]);
            if (exr_attr_get_float_vector(ctx, 0, an, &ne, &v) != EXR_ERR_SUCCESS || ne != NBT_SUB_TERMS) {
                st = rd_fail(err, errlen, path, "form sub needs nbt.sub.R.. with 10 coefficients per channel");
                goto done;
            }
            for (int q = 0; q < NBT_SUB_TERMS; q++)
                t->sub_c[c][q] = v[q];
        }
    }
    if (nax == 3) {
        int32_t ip = 1, ne;
        const float *ce;
        if (exr_attr_get_int(ctx, 0, axis_attr(2, "interp", an, sizeof an), &ip) == EXR_ERR_SUCCESS &&
            !(ip == 1 || (ip == 2 && ax[2].n >= 3) || (ip == 3 && ax[2].n >= 4))) {
            st = rd_fail(err, errlen, path,
                         "nbt.axis2.interp must be 1, 2 or 3 (2 needs at least 3 slices, 3 at least 4)");
            goto done;
        }
        t->interp2 = ip;
        for (size_t c = 0; c < nc; c++) {
            snprintf(an, sizeof an, "nbt.cell_err.%s", CH[c]);
            if (exr_attr_get_float_vector(ctx, 0, an, &ne, &ce) != EXR_ERR_SUCCESS)
                continue;
            if ((size_t)ne != ax[2].n - 1) {
                st = rd_fail(err, errlen, path, "an nbt.cell_err vector does not have one value per g cell");
                goto done;
            }
            for (size_t m = 0; m < (size_t)ne; m++)
                t->cell_err[m * nc + c] = ce[m];
        }
    }
    for (size_t c = 0; c < nc; c++) {
        int32_t ne;
        const float *re;
        snprintf(an, sizeof an, "nbt.row_err.%s", CH[c]);
        if (exr_attr_get_float_vector(ctx, 0, an, &ne, &re) != EXR_ERR_SUCCESS)
            continue;
        size_t nr = nbt_table_row_err_len(t) / nc;
        if ((size_t)ne != nr) {
            st = rd_fail(err, errlen, path, "an nbt.row_err vector does not have one value per x0 row and g cell");
            goto done;
        }
        if (!t->row_err && nbt_table_row_err_alloc(t) != NBT_OK) {
            st = NBT_ENOMEM;
            snprintf(err, errlen, "out of memory");
            goto done;
        }
        if ((st = copy_err_vector(re, nr, t->row_err, nc, c, "an nbt.row_err value", path, err, errlen)) != NBT_OK)
            goto done;
    }
    for (size_t c = 0; c < nc; c++) {
        int32_t ne, cells = 0;
        const float *re;
        snprintf(an, sizeof an, "nbt.theta_err.%s", CH[c]);
        if (exr_attr_get_float_vector(ctx, 0, an, &ne, &re) != EXR_ERR_SUCCESS)
            continue;
        if (!t->theta_err) {
            exr_attr_get_int(ctx, 0, "nbt.theta_err.cells", &cells);
            if (cells < 1 || (size_t)cells > ax[1].n - 1) {
                st = rd_fail(err, errlen, path, "nbt.theta_err needs nbt.theta_err.cells, theta cells per band, "
                                                "1 .. axis1.n - 1");
                goto done;
            }
            if (nbt_table_theta_err_alloc(t, (size_t)cells) != NBT_OK) {
                st = NBT_ENOMEM;
                snprintf(err, errlen, "out of memory");
                goto done;
            }
        }
        size_t nr = nbt_table_theta_err_len(t) / nc;
        if ((size_t)ne != nr) {
            st = rd_fail(err, errlen, path, "an nbt.theta_err vector does not have one value per x0 row, theta band "
                                            "and g cell");
            goto done;
        }
        if ((st = copy_err_vector(re, nr, t->theta_err, nc, c, "an nbt.theta_err value", path, err, errlen)) != NBT_OK)
            goto done;
    }
    size_t nx = ax[0].n, ny = ax[1].n * ax[2].n, bpe = half ? 2 : 4;
    pix = malloc(nx * ny * nc * bpe);
    if (!pix) {
        st = NBT_ENOMEM;
        snprintf(err, errlen, "out of memory");
        goto done;
    }
    int32_t lpc = 1;
    exr_get_scanlines_per_chunk(ctx, 0, &lpc);
    exr_decode_pipeline_t dec = EXR_DECODE_PIPELINE_INITIALIZER;
    int first = 1;
    errno = 0; /* zlib allocates with malloc, not through the context: ENOMEM here is its failure */
    for (int32_t y = dw.min.y; y <= dw.max.y && rv == EXR_ERR_SUCCESS; y += lpc) {
        exr_chunk_info_t ci;
        rv = exr_read_scanline_chunk_info(ctx, 0, y, &ci);
        if (rv != EXR_ERR_SUCCESS)
            break;
        rv = first ? exr_decoding_initialize(ctx, 0, &ci, &dec) : exr_decoding_update(ctx, 0, &ci, &dec);
        if (rv != EXR_ERR_SUCCESS)
            break;
        for (int16_t c = 0; c < dec.channel_count; c++) {
            exr_coding_channel_info_t *ch = &dec.channels[c];
            size_t idx = 0;
            while (idx < nc && strcmp(ch->channel_name, CH[idx]))
                idx++;
            if (idx == nc) {
                rv = EXR_ERR_INVALID_ARGUMENT;
                break;
            }
            ch->user_pixel_stride = (int32_t)(nc * bpe);
            ch->user_line_stride = (int32_t)(nx * nc * bpe);
            ch->user_bytes_per_element = (int16_t)bpe;
            ch->user_data_type = half ? EXR_PIXEL_HALF : EXR_PIXEL_FLOAT;
            ch->decode_to_ptr = pix + ((size_t)(y - dw.min.y) * nx * nc + idx) * bpe;
        }
        if (rv == EXR_ERR_SUCCESS && first)
            rv = exr_decoding_choose_default_routines(ctx, 0, &dec);
        first = 0;
        if (rv == EXR_ERR_SUCCESS)
            rv = exr_decoding_run(ctx, 0, &dec);
    }
    if (rv != EXR_ERR_SUCCESS && errno == ENOMEM)
        rv = EXR_ERR_OUT_OF_MEMORY;
    if (!first)
        exr_decoding_destroy(ctx, &dec);
    if (rv == EXR_ERR_OUT_OF_MEMORY)
        goto done; /* NBT_ENOMEM below */
    if (rv != EXR_ERR_SUCCESS) {
        st = rd_fail(err, errlen, path, "pixel data cannot be decoded (truncated or corrupt, or channels not R/G/B/A)");
        goto done;
    }
    for (size_t i = 0; i < nx * ny * nc; i++) {
        if (half) {
            uint16_t h;
            memcpy(&h, pix + 2 * i, 2);
            t->data[i] = half_float(h);
        } else
            memcpy(&t->data[i], pix + 4 * i, 4);
    }
done:
    free(pix);
    exr_finish(&ctx);
    if (nbt__exr_nomem() || rv == EXR_ERR_OUT_OF_MEMORY) {
        /* whatever the library made of it: a failed decode, or a header without the attribute it could not copy */
        st = NBT_ENOMEM;
        snprintf(err, errlen, "%s: out of memory", path);
    }
    if (st != NBT_OK) {
        nbt_table_free(t);
        return st;
    }
    *out = t;
    return NBT_OK;
}
