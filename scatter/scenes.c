/* scatter/scenes.c: generated test renders (RGB + planar Z, Blender's
 * conventions: Z along the view axis, sky at 1e10). Deterministic. */
#include <config.h>
#include <math.h>
#include <stdint.h>
#include <string.h>
#include "scatter.h"

static const char *const NAMES[] = {"plane", "step", "layers", "slant", "blocks"};

const char *scene_names(void)
{
    return "plane, step, layers, slant, blocks";
}

int scene_parse(const char *name)
{
    for (int i = 0; i < (int)(sizeof NAMES / sizeof NAMES[0]); i++)
        if (!strcmp(name, NAMES[i]))
            return i;
    return -1;
}

static uint64_t rng_state;
static double uniform(void)
{
    uint64_t z = (rng_state += 0x9e3779b97f4a7c15u);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9u;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebu;
    return (double)((z ^ (z >> 31)) >> 11) / 9007199254740992.0;
}

/* a soft checker texture in [0.1, 1] so that scattering has structure to blur */
static void texture(float *c, size_t x, size_t y, double tint)
{
    int chk = ((x / 8) + (y / 8)) % 2;
    double v = chk ? 0.9 : 0.25;
    c[0] = (float)(v * tint);
    c[1] = (float)(v * 0.8);
    c[2] = (float)(v * (1.2 - 0.4 * tint));
}

static void lamp(nbt_image *im, size_t cx, size_t cy, double v)
{
    for (size_t y = cy; y < cy + 2 && y < im->h; y++)
        for (size_t x = cx; x < cx + 2 && x < im->w; x++) {
            float *c = im->rgb + 3 * (y * im->w + x);
            c[0] = (float)v, c[1] = (float)(0.8 * v), c[2] = (float)(0.5 * v);
        }
}

nbt_image *scene_make(int kind, size_t w, size_t h)
{
    nbt_image *im = nbt_image_alloc(w, h, 1);
    if (!im)
        return NULL;
    rng_state = 0x2385u;
    /* blocks: 10 rectangles at 6 depths over a far wall */
    size_t bx[10], by[10], bw[10], bh[10];
    double bz[10];
    const double depths[6] = {2.5, 3.7, 5.2, 7.4, 9.8, 13.0};
    for (int b = 0; b < 10; b++) {
        bw[b] = (size_t)(w * (0.1 + 0.2 * uniform()));
        bh[b] = (size_t)(h * (0.1 + 0.25 * uniform()));
        bx[b] = (size_t)((double)(w - bw[b]) * uniform());
        by[b] = (size_t)((double)(h - bh[b]) * uniform());
        bz[b] = depths[(int)(6 * uniform())];
    }
    for (size_t y = 0; y < h; y++)
        for (size_t x = 0; x < w; x++) {
            size_t i = y * w + x;
            double fx = (x + 0.5) / (double)w, fy = (y + 0.5) / (double)h, Z = 6.0, tint = 1.0;
            switch (kind) {
            case 0: /* plane: one wall */
                Z = 6.0;
                break;
            case 1: /* step: near left half, far right half */
                Z = fx < 0.5 ? 3.0 : 12.0;
                tint = fx < 0.5 ? 0.7 : 1.2;
                break;
            case 2: /* layers: near box, middle box, far wall, sky on top */
                Z = fy < 0.15 ? 1e10 : 14.0;
                if (fx > 0.15 && fx < 0.55 && fy > 0.35 && fy < 0.85)
                    Z = 6.0, tint = 0.6;
                if (fx > 0.45 && fx < 0.8 && fy > 0.25 && fy < 0.6)
                    Z = 2.5, tint = 1.1;
                break;
            case 3: /* slant: a floor receding to the horizon, sky above it */
                Z = fy < 0.4 ? 1e10 : 1.5 / (fy - 0.4 + 0.05);
                break;
            case 4:
                Z = 15.0;
                for (int b = 0; b < 10; b++)
                    if (x >= bx[b] && x < bx[b] + bw[b] && y >= by[b] && y < by[b] + bh[b] && bz[b] < Z)
                        Z = bz[b], tint = 0.5 + 0.08 * b;
                break;
            }
            im->z[i] = (float)Z;
            if (Z >= 1e10) {
                im->rgb[3 * i] = 0.6f, im->rgb[3 * i + 1] = 0.7f, im->rgb[3 * i + 2] = 0.9f;
            } else
                texture(im->rgb + 3 * i, x, y, tint);
        }
    /* HDR lamps: in front of the step edge, on the near box, on the floor */
    if (kind == 1)
        lamp(im, w / 2 - 3, h / 2, 200.0);
    else if (kind == 2)
        lamp(im, (size_t)(0.6 * w), (size_t)(0.4 * h), 150.0);
    else if (kind == 3)
        lamp(im, w / 3, (size_t)(0.7 * h), 100.0);
    else if (kind == 4)
        lamp(im, bx[0] + bw[0] / 2, by[0] + bh[0] / 2, 120.0);
    else
        lamp(im, w / 2, h / 2, 50.0);
    return im;
}
