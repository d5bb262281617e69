/* scatter/scenes.c: generated test renders (RGB + planar Z, Blender's
 * conventions: Z along the view axis, sky at 1e10). Deterministic. */
#include <config.h>
#include <math.h>
#include <stdint.h>
#include <string.h>
#include "scatter.h"

static const char *const NAMES[] = {"plane", "step", "layers", "slant", "blocks", "lamps"};

const char *scene_names(void)
{
    return "plane, step, layers, slant, blocks, lamps";
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

/* a 2x2 lamp at frame pixel (cx, cy) (may lie in the overscan border: ox, oy) */
static void lamp(nbt_image *im, long cx, long cy, size_t ox, size_t oy, double v)
{
    for (long y = cy; y < cy + 2; y++)
        for (long x = cx; x < cx + 2; x++) {
            long X = x + (long)ox, Y = y + (long)oy;
            if (X < 0 || Y < 0 || X >= (long)im->w || Y >= (long)im->h)
                continue;
            float *c = im->rgb + 3 * ((size_t)Y * im->w + (size_t)X);
            c[0] = (float)v, c[1] = (float)(0.8 * v), c[2] = (float)(0.5 * v);
        }
}

nbt_image *scene_make(int kind, size_t w, size_t h, size_t ox, size_t oy)
{
    /* the frame is w x h; the data window adds ox, oy pixels on each side (overscan), the scene
     * continuing beyond the frame as a renderer's would */
    nbt_image *im = nbt_image_alloc(w + 2 * ox, h + 2 * oy, 1);
    if (!im)
        return NULL;
    im->x0 = -(int32_t)ox;
    im->y0 = -(int32_t)oy;
    im->display.min_x = 0, im->display.min_y = 0;
    im->display.max_x = (int32_t)w - 1, im->display.max_y = (int32_t)h - 1;
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
    for (size_t Y = 0; Y < im->h; Y++)
        for (size_t X = 0; X < im->w; X++) {
            size_t i = Y * im->w + X;
            long x = (long)X - (long)ox, y = (long)Y - (long)oy; /* frame pixel, negative in the border */
            double fx = ((double)x + 0.5) / (double)w, fy = ((double)y + 0.5) / (double)h, Z = 6.0, tint = 1.0;
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
            case 5: /* lamps: one wall with HDR lamps (below) */
                Z = 6.0;
                tint = 0.15;
                break;
            case 4:
                Z = 15.0;
                for (int b = 0; b < 10; b++)
                    if (x >= (long)bx[b] && x < (long)(bx[b] + bw[b]) && y >= (long)by[b] &&
                        y < (long)(by[b] + bh[b]) && bz[b] < Z)
                        Z = bz[b], tint = 0.5 + 0.08 * b;
                break;
            }
            im->z[i] = (float)Z;
            if (Z >= 1e10) {
                im->rgb[3 * i] = 0.6f, im->rgb[3 * i + 1] = 0.7f, im->rgb[3 * i + 2] = 0.9f;
            } else
                texture(im->rgb + 3 * i, (size_t)(x + 4096), (size_t)(y + 4096), tint);
        }
    /* HDR lamps: in front of the step edge, on the near box, on the floor */
    long W = (long)w, H = (long)h;
    if (kind == 1)
        lamp(im, W / 2 - 3, H / 2, ox, oy, 200.0);
    else if (kind == 2)
        lamp(im, (long)(0.6 * W), (long)(0.4 * H), ox, oy, 150.0);
    else if (kind == 3)
        lamp(im, W / 3, (long)(0.7 * H), ox, oy, 100.0);
    else if (kind == 4)
        lamp(im, (long)(bx[0] + bw[0] / 2), (long)(by[0] + bh[0] / 2), ox, oy, 120.0);
    else if (kind == 5) { /* five in the frame (one at its edge), two just outside it (seen with overscan) */
        const double at[7][3] = {{0.5, 0.5, 300}, {0.2, 0.3, 150}, {0.8, 0.25, 200}, {0.3, 0.8, 100},
                                 {0.97, 0.6, 250}, {-0.06, 0.45, 300}, {0.55, 1.08, 200}};
        for (int j = 0; j < 7; j++)
            lamp(im, (long)floor(at[j][0] * W), (long)floor(at[j][1] * H), ox, oy, at[j][2]);
    } else
        lamp(im, W / 2, H / 2, ox, oy, 50.0);
    return im;
}
