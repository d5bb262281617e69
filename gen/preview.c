/* gen/preview.c: false-colour PNG previews (libpng). */
#include <config.h>
#include <math.h>
#include <png.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
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
    for (int k = 0; k < 3; k++)
        rgb[k] = (unsigned char)lround(c[i][k] + f * (c[i + 1][k] - c[i][k]));
}

/* libpng reports errors by longjmp: keep that to a function whose locals do
 * not change after setjmp. */
static int write_png(FILE *f, const unsigned char *img, size_t W, size_t H)
{
    png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, NULL, NULL, NULL);
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

int preview_write_png(const nbt_table *t, const char *path)
{
    size_t nx = t->axis[0].n, ny = t->axis[1].n, nc = t->nch, gap = 4;
    size_t W = nc * nx + (nc - 1) * gap, H = ny;
    unsigned char *img = calloc(W * H * 3, 1);
    if (!img)
        return -1;
    memset(img, 255, W * H * 3);
    for (size_t c = 0; c < nc; c++) {
        double lo = INFINITY, hi = -INFINITY;
        for (size_t i = 0; i < nx * ny; i++) {
            lo = fmin(lo, t->data[i * nc + c]);
            hi = fmax(hi, t->data[i * nc + c]);
        }
        double span = hi > lo ? hi - lo : 1.0;
        for (size_t j = 0; j < ny; j++)
            for (size_t i = 0; i < nx; i++)
                ramp((t->data[(j * nx + i) * nc + c] - lo) / span,
                     img + ((H - 1 - j) * W + c * (nx + gap) + i) * 3);
    }
    int rc = preview_write_rgb8(path, img, W, H);
    free(img);
    return rc;
}
