/* scatter/preview.c: a tone-mapped sRGB preview of a linear HDR image. */
#include <config.h>
#include <math.h>
#include <stdlib.h>
#include "../gen/preview.h"
#include "scatter.h"

static int cmp_float(const void *a, const void *b)
{
    float x = *(const float *)a, y = *(const float *)b;
    return x < y ? -1 : x > y;
}

static unsigned char srgb8(double v)
{
    v = v <= 0.0031308 ? 12.92 * v : 1.055 * pow(v, 1.0 / 2.4) - 0.055;
    return (unsigned char)lround(255.0 * (v < 0 ? 0 : v > 1 ? 1 : v));
}

int scatter_preview_png(const nbt_image *im, const char *path)
{
    size_t np = im->w * im->h;
    float *lum = malloc(np * sizeof *lum);
    unsigned char *img = malloc(np * 3);
    int rc = -1;
    if (lum && img) {
        for (size_t i = 0; i < np; i++)
            lum[i] = 0.2126f * im->rgb[3 * i] + 0.7152f * im->rgb[3 * i + 1] + 0.0722f * im->rgb[3 * i + 2];
        qsort(lum, np, sizeof *lum, cmp_float);
        /* the median maps to mid grey (0.18); Reinhard x/(1+x) keeps lamps in range */
        double med = lum[np / 2], expo = med > 0 ? 0.18 / med : 1.0;
        for (size_t i = 0; i < np * 3; i++) {
            double v = expo * im->rgb[i];
            img[i] = srgb8(v / (1.0 + v));
        }
        rc = preview_write_rgb8(path, img, im->w, im->h);
    }
    free(lum);
    free(img);
    return rc;
}
