/* gen/preview.c: false-colour PNG previews (libpng): the table sampled by its
 * own lookup on a readable grid, physical axes with ticks, one colour scale
 * per table with a colour bar, a caption with the kind and recorded error. */
#include <config.h>
#include <math.h>
#include <png.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include <ctype.h>
#include "font5x7.h"
#include "preview.h"

/* A perceptually ordered dark-blue -> teal -> yellow ramp (viridis-like
 * anchor colours), interpolated linearly. */
static void ramp(double x, unsigned char *rgb)
{
    static const double c[5][3] = {{68, 1, 84}, {59, 82, 139}, {33, 145, 140}, {94, 201, 98}, {253, 231, 37}};
    if (!(x >= 0))
        x = 0;
    if (x > 1)
        x = 1;
    double p = x * 4;
    int i = (int)p;
    if (i > 3)
        i = 3;
    double f = p - i;
    for (int k = 0; k < 3; k++) /* round to nearest (the value is >= 0) */
        rgb[k] = (unsigned char)(c[i][k] + f * (c[i + 1][k] - c[i][k]) + 0.5);
}

/* libpng's default handlers print "libpng error: Write Error" beside the
 * caller's one message naming the file: these only return to the setjmp */
static void png_quiet_error(png_structp png, png_const_charp msg)
{
    (void)msg;
    png_longjmp(png, 1);
}

static void png_quiet_warning(png_structp png, png_const_charp msg)
{
    (void)png;
    (void)msg;
}

/* libpng reports errors by longjmp: keep that to a function whose locals do
 * not change after setjmp. */
static int write_png(FILE *f, const unsigned char *img, size_t W, size_t H)
{
    png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, NULL, png_quiet_error, png_quiet_warning);
    if (!png)
        return -1;
    png_infop info = png_create_info_struct(png);
    if (!info || setjmp(png_jmpbuf(png))) {
        png_destroy_write_struct(&png, info ? &info : NULL);
        return -1;
    }
    png_init_io(png, f);
    png_set_IHDR(png, info, (png_uint_32)W, (png_uint_32)H, 8, PNG_COLOR_TYPE_RGB, PNG_INTERLACE_NONE,
                 PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
    /* deflate's fastest level and the "up" filter (rows of a preview repeat
     * their neighbours): 2-3x the size of level 6 with adaptive filters at a
     * third of the time (measured on the default scene's previews) */
    png_set_compression_level(png, 1);
    png_set_filter(png, PNG_FILTER_TYPE_BASE, PNG_FILTER_UP);
    png_write_info(png, info);
    for (size_t r = 0; r < H; r++)
        png_write_row(png, (png_const_bytep)(img + r * W * 3));
    png_write_end(png, NULL);
    png_destroy_write_struct(&png, &info);
    return 0;
}

int preview_write_rgb8(const char *path, const unsigned char *img, size_t W, size_t H)
{
    size_t len = strlen(path) + 32;
    char *tmp = malloc(len);
    int rc = -1;
    if (tmp) {
        snprintf(tmp, len, "%s.tmp%ld", path, (long)getpid());
        FILE *f = fopen(tmp, "wb");
        if (f) {
            rc = write_png(f, img, W, H);
            if (fclose(f) != 0)
                rc = -1;
            if (rc == 0 && rename(tmp, path) != 0)
                rc = -1;
            if (rc != 0)
                unlink(tmp);
        }
    }
    free(tmp);
    return rc;
}

/* ---- drawing on an 8-bit RGB canvas ---- */

typedef struct {
    unsigned char *px;
    int w, h;
} canvas;

static void put(canvas *c, int x, int y, const unsigned char *rgb)
{
    if (x >= 0 && y >= 0 && x < c->w && y < c->h)
        memcpy(c->px + ((size_t)y * (size_t)c->w + (size_t)x) * 3, rgb, 3);
}

static void rect(canvas *c, int x0, int y0, int w, int h, const unsigned char *rgb)
{
    for (int y = y0; y < y0 + h; y++)
        for (int x = x0; x < x0 + w; x++)
            put(c, x, y, rgb);
}

static const unsigned char BLACK[3] = {0, 0, 0}, GREY[3] = {160, 160, 160};

/* text in the 5x7 font scaled by FS: a glyph cell is CW x LH pixels */
#define FS 2
#define CW (6 * FS)
#define LH (9 * FS)

static const unsigned char *glyph(char ch)
{
    ch = (char)toupper((unsigned char)ch);
    for (size_t i = 0; i < sizeof font5x7 / sizeof font5x7[0]; i++)
        if (font5x7[i].c == ch)
            return font5x7[i].row;
    return NULL;
}

/* align: 0 left at x, 1 centred on x, 2 right-aligned ending at x; y is the top */
static void text(canvas *c, int x, int y, int align, const char *s)
{
    int n = (int)strlen(s);
    if (align == 1)
        x -= (n * CW - FS) / 2;
    else if (align == 2)
        x -= n * CW - FS;
    for (int i = 0; i < n; i++, x += CW) {
        const unsigned char *g = s[i] == ' ' ? NULL : glyph(s[i]);
        if (!g && s[i] != ' ')
            g = glyph('?');
        for (int r = 0; g && r < 7; r++)
            for (int b = 0; b < 5; b++)
                if (g[r] & (0x10 >> b))
                    rect(c, x + b * FS, y + r * FS, FS, FS, BLACK);
    }
}

/* a tick step of 1, 2 or 5 times a power of ten giving about `target` intervals */
static double nice_step(double range, double target)
{
    double raw = range / target, p = pow(10, floor(log10(raw))), f = raw / p;
    return (f < 1.5 ? 1 : f < 3 ? 2 : f < 7 ? 5 : 10) * p;
}

static void number(char *buf, size_t n, double v, double step)
{
    if (fabs(v) < 1e-9 * step)
        v = 0;
    snprintf(buf, n, "%.4g", v);
}

/* Layout (pixels): see preview.h. */
#define PW PREVIEW_PANEL_W
#define PH PREVIEW_PANEL_H

/* A 3-D (g-sliced) table shows two panels of its one channel: the slice
 * nearest the middle of the slice axis (g = 0 for a symmetric g range) and
 * the last slice (the most forward-peaked phase). */
static double panel_slice(const nbt_table *t, int k)
{
    const nbt_axis *a = &t->axis[2];
    if (k == 1)
        return a->hi;
    double mid = 0.5 * (a->lo + a->hi), best = a->lo;
    for (size_t i = 0; i < a->n; i++)
        if (fabs(nbt_axis_node(a, i) - mid) < fabs(best - mid))
            best = nbt_axis_node(a, i);
    return best;
}

int preview_write_png(const nbt_table *t, const char *path)
{
    int sliced = t->axis[2].n >= 2 && t->nch == 1;
    int nc = sliced ? 2 : (int)t->nch;
    canvas c = {NULL, PREVIEW_W(nc), PREVIEW_H};
    c.px = malloc((size_t)c.w * (size_t)c.h * 3);
    float *val = malloc((size_t)nc * PW * PH * sizeof(float));
    if (!c.px || !val) {
        free(c.px);
        free(val);
        return -1;
    }
    memset(c.px, 255, (size_t)c.w * (size_t)c.h * 3);
    const nbt_axis *ax = &t->axis[0], *ay = &t->axis[1];
    /* the table's own bilinear lookup at each pixel centre, pixels linear in the physical
     * coordinates (the table's mapping only decides where its nodes sit); a 2-D table on
     * the whole pixel grid at once (each coordinate mapped once, not once per pixel) */
    double lo = INFINITY, hi = -INFINITY, v[NBT_TABLE_MAX_CH], xs[PW], ys[PH];
    for (int i = 0; i < PW; i++)
        xs[i] = ax->lo + (ax->hi - ax->lo) * (i + 0.5) / PW;
    for (int j = 0; j < PH; j++)
        ys[j] = ay->hi - (ay->hi - ay->lo) * (j + 0.5) / PH;
    double *grid = sliced ? NULL : malloc((size_t)PW * PH * t->nch * sizeof *grid);
    if ((!sliced && !grid) || (grid && nbt_table_lookup_grid(t, xs, PW, ys, PH, grid) != NBT_OK)) {
        free(grid);
        free(c.px);
        free(val);
        return -1;
    }
    for (int j = 0; j < PH; j++) {
        for (int i = 0; i < PW; i++) {
            if (sliced) {
                nbt_table_lookup3(t, xs[i], ys[j], panel_slice(t, 0), &v[0]);
                nbt_table_lookup3(t, xs[i], ys[j], panel_slice(t, 1), &v[1]);
            } else
                memcpy(v, grid + ((size_t)j * PW + (size_t)i) * t->nch, t->nch * sizeof *v);
            for (int k = 0; k < nc; k++) {
                val[((size_t)k * PH + (size_t)j) * PW + (size_t)i] = (float)v[k];
                if (isfinite(v[k])) {
                    lo = fmin(lo, v[k]);
                    hi = fmax(hi, v[k]);
                }
            }
        }
    }
    free(grid);
    if (!(lo <= hi))
        lo = hi = 0;
    double span = hi > lo ? hi - lo : 1.0;
    int y0 = PREVIEW_TOP;
    for (int k = 0; k < nc; k++) {
        int x0 = PREVIEW_LEFT + k * (PW + PREVIEW_GAP);
        for (int j = 0; j < PH; j++) { /* the panel lies inside the canvas */
            unsigned char *row = c.px + ((size_t)(y0 + j) * (size_t)c.w + (size_t)x0) * 3;
            for (int i = 0; i < PW; i++) {
                double f = val[((size_t)k * PH + (size_t)j) * PW + (size_t)i];
                if (isfinite(f))
                    ramp((f - lo) / span, row + 3 * i);
                else
                    memcpy(row + 3 * i, GREY, 3);
            }
        }
        /* frame, panel title */
        rect(&c, x0 - 1, y0 - 1, PW + 2, 1, BLACK);
        rect(&c, x0 - 1, y0 + PH, PW + 2, 1, BLACK);
        rect(&c, x0 - 1, y0 - 1, 1, PH + 2, BLACK);
        rect(&c, x0 + PW, y0 - 1, 1, PH + 2, BLACK);
        char title[64];
        if (sliced)
            snprintf(title, sizeof title, "%s = %.3g", nbt_table_axis_name(t->kind, 2),
                     fabs(panel_slice(t, k)) < 1e-12 ? 0.0 : panel_slice(t, k));
        else if (t->kind == NBT_TABLE_PSI)
            snprintf(title, sizeof title, "%s", k == 0 ? "psi" : "psi stderr");
        else if (t->k[k] >= 0)
            snprintf(title, sizeof title, "k = %d", t->k[k]);
        else if (nc == 1)
            snprintf(title, sizeof title, "fixed phase");
        else
            snprintf(title, sizeof title, "channel %d", k);
        text(&c, x0 + PW / 2, y0 - LH - 4, 1, title);
        /* x ticks and labels under every panel */
        double st = nice_step(ax->hi - ax->lo, 4);
        for (double xv = ceil(ax->lo / st - 1e-9) * st; xv <= ax->hi + 1e-9 * st; xv += st) {
            int px = x0 + (int)lround((xv - ax->lo) / (ax->hi - ax->lo) * (PW - 1));
            char lab[32];
            rect(&c, px, y0 + PH + 1, 1, 6, BLACK);
            number(lab, sizeof lab, xv, st);
            text(&c, px, y0 + PH + 10, 1, lab);
        }
        text(&c, x0 + PW / 2, y0 + PH + 10 + LH + 2, 1, nbt_table_axis_name(t->kind, 0));
    }
    /* y ticks and labels left of the first panel, the axis name above them */
    double st = nice_step(ay->hi - ay->lo, 4);
    for (double yv = ceil(ay->lo / st - 1e-9) * st; yv <= ay->hi + 1e-9 * st; yv += st) {
        int py = y0 + PH - 1 - (int)lround((yv - ay->lo) / (ay->hi - ay->lo) * (PH - 1));
        char lab[32];
        rect(&c, PREVIEW_LEFT - 8, py, 6, 1, BLACK);
        number(lab, sizeof lab, yv, st);
        text(&c, PREVIEW_LEFT - 12, py - 7 * FS / 2, 2, lab);
    }
    text(&c, PREVIEW_LEFT - 12, y0 - LH - 4, 2, nbt_table_axis_name(t->kind, 1));
    /* colour bar: the ramp from max (top) to min (bottom), labelled */
    int bx = PREVIEW_LEFT + nc * PW + (nc - 1) * PREVIEW_GAP + PREVIEW_BAR_GAP;
    for (int j = 0; j < PH; j++) {
        unsigned char rgb[3];
        ramp(1.0 - (j + 0.5) / PH, rgb);
        rect(&c, bx, y0 + j, PREVIEW_BAR_W, 1, rgb);
    }
    rect(&c, bx - 1, y0 - 1, PREVIEW_BAR_W + 2, 1, BLACK);
    rect(&c, bx - 1, y0 + PH, PREVIEW_BAR_W + 2, 1, BLACK);
    rect(&c, bx - 1, y0 - 1, 1, PH + 2, BLACK);
    rect(&c, bx + PREVIEW_BAR_W, y0 - 1, 1, PH + 2, BLACK);
    char lab[64];
    snprintf(lab, sizeof lab, "%.4g", hi);
    text(&c, bx + PREVIEW_BAR_W + 6, y0, 0, lab);
    snprintf(lab, sizeof lab, "%.4g", 0.5 * (lo + hi));
    text(&c, bx + PREVIEW_BAR_W + 6, y0 + PH / 2 - 7 * FS / 2, 0, lab);
    snprintf(lab, sizeof lab, "%.4g", lo);
    text(&c, bx + PREVIEW_BAR_W + 6, y0 + PH - 7 * FS, 0, lab);
    text(&c, bx + PREVIEW_BAR_W / 2, y0 - LH - 4, 1, "value");
    /* caption: kind, size, recorded interpolation error; then axes and phase */
    double e = nbt_table_max_err(t), m = nbt_table_max_abs(t);
    int have_err = 0;
    for (int k = 0; k < nc; k++)
        have_err |= isfinite(t->max_err[k]) != 0;
    static const char *what[4] = {"airlight H_k(u,v)", "surface J_k^n(T,theta)", "photon counts psi(r/z,z)",
                                  "narrow-beam kernel"};
    char cap[256], err[96];
    if (have_err && (t->form == NBT_FORM_TAIL || t->form == NBT_FORM_LOG_ET)) /* recorded relative to the value */
        snprintf(err, sizeof err, "max interp err %.2e (rel %.2e)", e, e);
    else if (have_err)
        snprintf(err, sizeof err, "max interp err %.2e (rel %.2e)", e, m > 0 ? e / m : 0.0);
    else
        snprintf(err, sizeof err, "data, no interpolation error recorded");
    char nn[16] = "";
    if (t->kind == NBT_TABLE_J)
        snprintf(nn, sizeof nn, " n=%d", t->n);
    if (sliced)
        snprintf(cap, sizeof cap, "%s table%s: %s  %zux%zux%zu nodes (%zu %s slices, 2 shown)",
                 nbt_table_kind_name(t->kind), nn, what[t->kind >= 0 && (int)t->kind < 4 ? (int)t->kind : 0], ax->n,
                 ay->n, t->axis[2].n, t->axis[2].n, nbt_table_axis_name(t->kind, 2));
    else
        snprintf(cap, sizeof cap, "%s table%s: %s  %zux%zu nodes", nbt_table_kind_name(t->kind), nn,
                 what[t->kind >= 0 && (int)t->kind < 4 ? (int)t->kind : 0], ax->n, ay->n);
    text(&c, 10, 8, 0, cap);
    text(&c, 10, 8 + LH, 0, err);
    snprintf(cap, sizeof cap, "nodes: %s %s, %s %s%s%.80s", nbt_table_axis_name(t->kind, 0),
             nbt_axis_map_name(ax->map), nbt_table_axis_name(t->kind, 1), nbt_axis_map_name(ay->map),
             t->phase[0] ? "  phase " : "", t->phase);
    text(&c, 10, 8 + 2 * LH, 0, cap);
    int rc = preview_write_rgb8(path, c.px, (size_t)c.w, (size_t)c.h);
    free(c.px);
    free(val);
    return rc;
}
