/* tests/mkexr.c: writes small broken renders for nbt-scatter's bad-input
 * tests (mkexr OUT.exr noz|nan|negative|inf|nanrgb|negrgb|border), the means of a
 * written file's layer (mkexr IN.exr mean LAYER [X0 Y0 X1 Y1]), the frame against its
 * layers (mkexr OUT.exr composite IN.exr: max |RGB - (T IN + S)| / max |RGB|), and a constant density grid
 * over x, y in [-20, 20], z in [-40, 1] as nbt's raw grid or, in builds
 * with OpenVDB, as a .vdb file (mkexr OUT.raw|OUT.vdb grid VALUE; gridy: the
 * same with y in [-10, 30], a box whose x and y ranges differ).
 * mkexr OUT.exr layers IN.exr crop|full: IN's pixels and everything it
 * kept, plus layers S = 0.25 RGB, T (R 0.5, G 0.25, B 0.125) and offscreen
 * (the fraction of pixels x0..x of the row outside the display window),
 * written over the display window (crop) or the data window (full), with
 * the attribute nbt.method = layers; for the EXR tool tests. A sixth argument
 * PREFIX names the S layer PREFIX.S (a Blender view layer's prefix).
 * mkexr OUT.exr rename IN.exr FROM TO: IN with its channel FROM renamed TO
 * (no longer than FROM), e.g. to take one channel out of a layer.
 * mkexr OUT.exr flip IN.exr: IN's RGB and depth mirrored left to right (vflip: top to bottom)
 * (other channels dropped). mkexr IN.exr depths: the number of distinct
 * depth values in IN's display window.
 * mkexr OUT.exr lamp0|lamp1|lamp2: the 16x12 grey render (0.5, depth 4)
 * with one lamp, 1000 in channel R, G or B at x = 1, y = 5 (near the left
 * edge, so the mirror continuation holds its image). mkexr OUT.exr
 * greenred: pure green (0, 1, 0) in columns 0..9, pure red in 10..15; red: all pure red.
 * mkexr IN.exr noise B and mkexr IN.exr zsq OTHER.exr check a path-traced
 * output's Sse layer (below). mkexr OUT.exr halo SUM [ROW]: a frame with a pixel of R + G + B = SUM
 * (in row ROW, default 3) against --compare's lamp threshold; capband, capband-ext: a frame for nbt-scatter's mirrored-lamp cap, and
 * the same frame with that continuation written out as overscan (both below).
 * Any other name: the grey render alone. */
#include <config.h>
#include <math.h>
#include <stdio.h>
#include <string.h>
#include <stdlib.h>
#include <nbt/grid.h>
#include <nbt/image.h>
#ifdef HAVE_OPENVDB
#include "../scatter/vdb_shim.h"
#endif

/* the float channels LAYER.R, LAYER.G, LAYER.B of im (NULL where missing) */
static int find_layer(const nbt_image *im, const char *layer, const float *out[3])
{
    static const char *const RGB[3] = {"R", "G", "B"};
    size_t n = strlen(layer);
    out[0] = out[1] = out[2] = NULL;
    for (size_t j = 0; j < im->nchannels; j++)
        for (int c = 0; c < 3; c++) {
            const nbt_image_channel *ch = &im->channels[j];
            if (ch->type == NBT_PIXEL_FLOAT && ch->data && !strncmp(ch->name, layer, n) && ch->name[n] == '.' &&
                !strcmp(ch->name + n + 1, RGB[c]))
                out[c] = ch->data;
        }
    return out[0] && out[1] && out[2];
}

int main(int argc, char **argv)
{
    char err[256];
    if ((argc == 4 || argc == 8) && !strcmp(argv[2], "mean")) {
        /* the mean of every FLOAT channel named LAYER.* over the data window,
         * or over its pixels X0 <= x < X1, Y0 <= y < Y1 (from the top left) */
        nbt_image *im = NULL;
        if (nbt_image_read_exr(argv[1], &im, err, sizeof err) != NBT_OK) {
            fprintf(stderr, "%s\n", err);
            return 1;
        }
        size_t n = strlen(argv[3]), found = 0;
        for (size_t j = 0; j < im->nchannels; j++) {
            const nbt_image_channel *c = &im->channels[j];
            if (c->type != NBT_PIXEL_FLOAT || !c->data || strncmp(c->name, argv[3], n) || c->name[n] != '.')
                continue;
            size_t x0 = 0, y0 = 0, x1 = im->w, y1 = im->h;
            if (argc == 8) {
                x0 = (size_t)atol(argv[4]), y0 = (size_t)atol(argv[5]), x1 = (size_t)atol(argv[6]),
                y1 = (size_t)atol(argv[7]);
                if (!(x0 < x1 && x1 <= im->w && y0 < y1 && y1 <= im->h)) {
                    fprintf(stderr, "mkexr: region %s %s %s %s is not inside the %zux%zu image\n", argv[4], argv[5],
                            argv[6], argv[7], im->w, im->h);
                    nbt_image_free(im);
                    return 1;
                }
            }
            double sum = 0;
            for (size_t y = y0; y < y1; y++)
                for (size_t x = x0; x < x1; x++)
                    sum += ((const float *)c->data)[y * im->w + x];
            printf("%s %.9g\n", c->name, sum / (double)((x1 - x0) * (y1 - y0)));
            found++;
        }
        nbt_image_free(im);
        return found ? 0 : 1;
    }
    if (argc == 4 && !strcmp(argv[2], "composite")) {
        /* nbt-scatter's frame OUT against its own layers and the input IN:
         * the largest |R - (T.R IN.R + S.R)| (and G, B) over max |R| */
        nbt_image *out = NULL, *in = NULL;
        if (nbt_image_read_exr(argv[1], &out, err, sizeof err) != NBT_OK ||
            nbt_image_read_exr(argv[3], &in, err, sizeof err) != NBT_OK) {
            fprintf(stderr, "%s\n", err);
            return 1;
        }
        const float *S[3], *T[3];
        int rc = 1;
        if (in->w != out->w || in->h != out->h || !find_layer(out, "S", S) || !find_layer(out, "T", T))
            fprintf(stderr, "mkexr: %s has no float S and T layers of %s's size\n", argv[1], argv[3]);
        else {
            double d = 0, m = 0;
            for (size_t i = 0; i < out->w * out->h; i++)
                for (int c = 0; c < 3; c++) {
                    double want = (double)T[c][i] * in->rgb[3 * i + c] + S[c][i];
                    d = fmax(d, fabs(out->rgb[3 * i + c] - want));
                    m = fmax(m, fabs(out->rgb[3 * i + c]));
                }
            printf("composite %.3g\n", m > 0 ? d / m : d);
            rc = 0;
        }
        nbt_image_free(out);
        nbt_image_free(in);
        return rc;
    }
    if (argc == 4 && (!strcmp(argv[2], "noise") || !strcmp(argv[2], "zsq"))) {
        /* a path-traced output's standard-error layer Sse, checked from its
         * definition: "noise B" is sqrt(2/pi) sqrt(sum se^2) / |sum S| summed
         * over BxB bins and the three channels (the expected |error| of a bin's
         * sum over its size); "zsq OTHER.exr" is, per channel, the mean over
         * pixels of (S - S')^2 / (se^2 + se'^2) between two independent runs
         * (1 when the errors are what Sse says) */
        nbt_image *a = NULL, *b = NULL;
        const float *S[3], *E[3], *S2[3], *E2[3];
        int zsq = argv[2][0] == 'z';
        if (nbt_image_read_exr(argv[1], &a, err, sizeof err) != NBT_OK ||
            (zsq && nbt_image_read_exr(argv[3], &b, err, sizeof err) != NBT_OK)) {
            fprintf(stderr, "%s\n", err);
            nbt_image_free(a);
            return 1;
        }
        int rc = 1;
        if (!find_layer(a, "S", S) || !find_layer(a, "Sse", E) ||
            (zsq && (b->w != a->w || b->h != a->h || !find_layer(b, "S", S2) || !find_layer(b, "Sse", E2))))
            fprintf(stderr, "mkexr: no S and Sse layers (of the same size)\n");
        else if (zsq) {
            for (int c = 0; c < 3; c++) {
                double sum = 0;
                size_t n = 0;
                for (size_t i = 0; i < a->w * a->h; i++) {
                    double v = (double)E[c][i] * E[c][i] + (double)E2[c][i] * E2[c][i], d = S[c][i] - S2[c][i];
                    if (v > 0)
                        sum += d * d / v, n++;
                }
                printf("%s%.4g", c ? " " : "zsq ", n ? sum / (double)n : NAN);
            }
            printf("\n");
            rc = 0;
        } else {
            size_t bin = (size_t)atol(argv[3]), w = a->w, h = a->h;
            double num = 0, den = 0;
            for (size_t by = 0; bin && by < h; by += bin)
                for (size_t bx = 0; bx < w; bx += bin)
                    for (int c = 0; c < 3; c++) {
                        double s = 0, v = 0;
                        for (size_t y = by; y < h && y < by + bin; y++)
                            for (size_t x = bx; x < w && x < bx + bin; x++)
                                s += S[c][y * w + x], v += (double)E[c][y * w + x] * E[c][y * w + x];
                        num += sqrt(2 / 3.14159265358979323846) * sqrt(v);
                        den += fabs(s);
                    }
            printf("noise %.6g\n", num / den);
            rc = 0;
        }
        nbt_image_free(a);
        nbt_image_free(b);
        return rc;
    }
    if (argc == 4 && (!strcmp(argv[2], "grid") || !strcmp(argv[2], "gridy"))) {
        double o[3] = {-19.5, argv[2][4] ? -9.5 : -19.5, -39.5}; /* gridy: y in [-10, 30] */
        nbt_grid *g = nbt_grid_alloc(40, 40, 41, o, 1.0);
        if (!g)
            return 1;
        for (size_t i = 0; i < 40 * 40 * 41; i++)
            g->data[i] = (float)atof(argv[3]);
        size_t n = strlen(argv[1]);
        int rc;
        if (n > 4 && !strcmp(argv[1] + n - 4, ".vdb")) {
#ifdef HAVE_OPENVDB
            nbt_vdb_grid v = {g->nx, g->ny, g->nz, {o[0], o[1], o[2]}, g->voxel, g->data};
            rc = nbt_vdb_write(argv[1], "density", &v, err, sizeof err) != 0;
#else
            rc = 1;
            snprintf(err, sizeof err, "no OpenVDB in this build");
#endif
        } else
            rc = nbt_grid_write_raw(g, argv[1], err, sizeof err) != NBT_OK;
        if (rc)
            fprintf(stderr, "%s\n", err);
        nbt_grid_free(g);
        return rc;
    }
    if ((argc == 5 || argc == 6) && !strcmp(argv[2], "layers")) {
        nbt_image *in = NULL;
        if (nbt_image_read_exr(argv[3], &in, err, sizeof err) != NBT_OK) {
            fprintf(stderr, "%s\n", err);
            return 1;
        }
        size_t n = in->w * in->h;
        float *s = malloc(n * 3 * sizeof(float)), *t = malloc(n * 3 * sizeof(float)), *f = malloc(n * sizeof(float));
        if (!s || !t || !f)
            return 1;
        for (size_t i = 0; i < n; i++) {
            long x = in->x0 + (long)(i % in->w), y = in->y0 + (long)(i / in->w);
            int outside = x < in->display.min_x || x > in->display.max_x || y < in->display.min_y || y > in->display.max_y;
            for (int c = 0; c < 3; c++) {
                s[3 * i + (size_t)c] = 0.25f * in->rgb[3 * i + (size_t)c];
                t[3 * i + (size_t)c] = 0.5f / (float)(1 << c);
            }
            f[i] = outside ? 1.0f : 0.0f;
        }
        const char *rgb[3] = {"R", "G", "B"}, *x1[1] = {"X"}, *attrs[2] = {"nbt.method", "layers"};
        char sname[64] = "S"; /* argv[5]: a view-layer prefix, S named PREFIX.S (as Blender writes) */
        if (argc == 6)
            snprintf(sname, sizeof sname, "%s.S", argv[5]);
        nbt_image_layer layers[3] = {{sname, 3, rgb, s}, {"T", 3, rgb, t}, {"offscreen", 1, x1, f}};
        nbt_exr_write_opts o = {.layers = layers, .nlayers = 3, .attrs = attrs, .nattrs = 1};
        if (!strcmp(argv[4], "crop"))
            o.window = &in->display;
        int rc = nbt_image_write_exr_ex(in, argv[1], &o, err, sizeof err) != NBT_OK;
        if (rc)
            fprintf(stderr, "%s\n", err);
        free(s), free(t), free(f);
        nbt_image_free(in);
        return rc;
    }
    if (argc == 6 && !strcmp(argv[2], "rename")) {
        nbt_image *in = NULL;
        if (nbt_image_read_exr(argv[3], &in, err, sizeof err) != NBT_OK) {
            fprintf(stderr, "%s\n", err);
            return 1;
        }
        int rc = 1;
        for (size_t j = 0; j < in->nchannels; j++)
            if (!strcmp(in->channels[j].name, argv[4]) && strlen(argv[5]) <= strlen(argv[4])) {
                strcpy(in->channels[j].name, argv[5]);
                rc = 0;
            }
        if (rc)
            fprintf(stderr, "mkexr: no channel '%s' to rename to '%s'\n", argv[4], argv[5]);
        else if ((rc = nbt_image_write_exr_ex(in, argv[1], NULL, err, sizeof err) != NBT_OK))
            fprintf(stderr, "%s\n", err);
        nbt_image_free(in);
        return rc;
    }
    if (argc == 3 && !strcmp(argv[2], "depths")) {
        nbt_image *in = NULL;
        if (nbt_image_read_exr(argv[1], &in, err, sizeof err) != NBT_OK || !in->z) {
            fprintf(stderr, "%s\n", in ? "mkexr: no depth" : err);
            return 1;
        }
        float seen[64];
        size_t n = 0;
        for (size_t i = 0; i < in->w * in->h; i++) {
            long x = in->x0 + (long)(i % in->w), y = in->y0 + (long)(i / in->w);
            if (x < in->display.min_x || x > in->display.max_x || y < in->display.min_y || y > in->display.max_y)
                continue;
            size_t k = 0;
            while (k < n && seen[k] != in->z[i])
                k++;
            if (k == n && n < 64)
                seen[n++] = in->z[i];
        }
        printf("%zu\n", n);
        nbt_image_free(in);
        return 0;
    }
    if (argc == 4 && (!strcmp(argv[2], "flip") || !strcmp(argv[2], "vflip"))) {
        int v = argv[2][0] == 'v';
        nbt_image *in = NULL;
        if (nbt_image_read_exr(argv[3], &in, err, sizeof err) != NBT_OK || !in->z) {
            fprintf(stderr, "%s\n", in ? "mkexr: no depth" : err);
            return 1;
        }
        nbt_image *o = nbt_image_alloc(in->w, in->h, 1);
        if (!o)
            return 1;
        for (size_t y = 0; y < in->h; y++)
            for (size_t x = 0; x < in->w; x++) {
                size_t i = y * in->w + x, j = v ? (in->h - 1 - y) * in->w + x : y * in->w + (in->w - 1 - x);
                o->z[i] = in->z[j];
                for (int c = 0; c < 3; c++)
                    o->rgb[3 * i + (size_t)c] = in->rgb[3 * j + (size_t)c];
            }
        int rc = nbt_image_write_exr_ex(o, argv[1], NULL, err, sizeof err) != NBT_OK;
        if (rc)
            fprintf(stderr, "%s\n", err);
        nbt_image_free(o);
        nbt_image_free(in);
        return rc;
    }
    if ((argc == 4 || argc == 5) && !strcmp(argv[2], "halo")) {
        /* 16x12 at depth 4: grey 0.5 in rows 0..7, 2.0 in rows 8..11 (the frame's bottom third), and one pixel
         * (5, ROW) of R = SUM (G = B = 0), ROW 3 or argv[4] (0..7, so the mean below stays the same).
         * --compare's lamps are pixels whose R + G + B exceeds 10 x the frame's mean of R + G + B,
         * (190.5 + SUM + 384) / 192 here: SUM above 31.57 is a lamp, SUM below is not */
        nbt_image *im = nbt_image_alloc(16, 12, 1);
        if (!im)
            return 1;
        for (size_t i = 0; i < 16 * 12; i++) {
            im->rgb[3 * i] = im->rgb[3 * i + 1] = im->rgb[3 * i + 2] = i < 8 * 16 ? 0.5f : 2.0f;
            im->z[i] = 4.0f;
        }
        size_t row = argc == 5 ? (size_t)atoi(argv[4]) : 3;
        if (row > 7)
            return 1;
        im->rgb[3 * (row * 16 + 5)] = (float)atof(argv[3]);
        im->rgb[3 * (row * 16 + 5) + 1] = im->rgb[3 * (row * 16 + 5) + 2] = 0.0f;
        int rc = nbt_image_write_exr_ex(im, argv[1], NULL, err, sizeof err) != NBT_OK;
        if (rc)
            fprintf(stderr, "%s\n", err);
        nbt_image_free(im);
        return rc;
    }
    if (argc == 3 && (!strcmp(argv[2], "capband") || !strcmp(argv[2], "capband-ext"))) {
        /* capband: 40x30 at depth 4 whose 8-pixel border band (864 pixels) has R + G + B = 1 in its left 8
         * columns (R = 1) and right 8 columns (G = 1), 480 pixels, and 0.3 (grey 0.1, as inside) in the other 384:
         * its median is 1, so nbt-scatter's cap on the mirrored border (4 x the band's median of R + G + B) is 4.
         * Two lamps on the left edge: (0, 5) with R = 3, under the cap, and (0, 20) with R = 100, over it.
         * capband-ext: the same frame as a render with 10 px of overscan per side (--extend 0.25 of 40) that
         * holds the continuation explicitly: the mirror image (the edge pixel repeated: -1 -> 0, 40 -> 39),
         * with the mirrored R = 100 lamp at the cap, R = 4 (R = 3 mirrored as it is; P = 10 reaches the mirror
         * images of both lamps across the left edge, of (0, 20) across the bottom edge and the corner too, and of
         * (0, 5) across the top edge). */
        int ext = argv[2][7] == '-', P = ext ? 10 : 0, W = 40 + 2 * P, H = 30 + 2 * P;
        nbt_image *im = nbt_image_alloc((size_t)W, (size_t)H, 1);
        if (!im)
            return 1;
        for (int y = 0; y < H; y++)
            for (int x = 0; x < W; x++) {
                int sx = x - P, sy = y - P, cx = sx < 0 ? -1 - sx : sx >= 40 ? 79 - sx : sx,
                    cy = sy < 0 ? -1 - sy : sy >= 30 ? 59 - sy : sy;
                float *c = im->rgb + 3 * ((size_t)y * (size_t)W + (size_t)x);
                c[0] = c[1] = c[2] = 0.1f;
                if (cx < 8)
                    c[0] = 1.0f, c[1] = c[2] = 0.0f;
                else if (cx >= 32)
                    c[1] = 1.0f, c[0] = c[2] = 0.0f;
                if (cx == 0 && cy == 5)
                    c[0] = 3.0f;
                if (cx == 0 && cy == 20) /* mirrored across the left and bottom edges and the corner */
                    c[0] = sx < 0 || sy >= 30 ? 4.0f : 100.0f;
                im->z[(size_t)y * (size_t)W + (size_t)x] = 4.0f;
            }
        im->x0 = -P, im->y0 = -P;
        im->display.min_x = 0, im->display.min_y = 0, im->display.max_x = 39, im->display.max_y = 29;
        int rc = nbt_image_write_exr_ex(im, argv[1], NULL, err, sizeof err) != NBT_OK;
        if (rc)
            fprintf(stderr, "%s\n", err);
        nbt_image_free(im);
        return rc;
    }
    if (argc != 3)
        return 2;
    const char *kind = argv[2];
    nbt_image *im = nbt_image_alloc(16, 12, strcmp(kind, "noz") != 0);
    if (!im)
        return 1;
    for (size_t i = 0; i < 16 * 12; i++) {
        im->rgb[3 * i] = im->rgb[3 * i + 1] = im->rgb[3 * i + 2] = 0.5f;
        if (im->z)
            im->z[i] = 4.0f;
    }
    if (!strcmp(kind, "nan"))
        im->z[5 * 16 + 3] = NAN;
    else if (!strcmp(kind, "negative"))
        im->z[5 * 16 + 3] = -2.0f;
    else if (!strcmp(kind, "inf"))
        im->z[5 * 16 + 3] = INFINITY; /* sky: accepted */
    else if (!strcmp(kind, "nanrgb"))
        im->rgb[3 * (7 * 16 + 2) + 1] = NAN;
    else if (!strcmp(kind, "negrgb"))
        im->rgb[3 * (7 * 16 + 2) + 2] = -1e6f;
    else if (!strncmp(kind, "lamp", 4) && kind[4] >= '0' && kind[4] <= '2' && !kind[5])
        im->rgb[3 * (5 * 16 + 1) + (kind[4] - '0')] = 1000.0f;
    else if (!strcmp(kind, "greenred"))
        for (size_t i = 0; i < 16 * 12; i++)
            for (size_t c = 0; c < 3; c++)
                im->rgb[3 * i + c] = c == (i % 16 < 10 ? 1u : 0u) ? 1.0f : 0.0f;
    else if (!strcmp(kind, "red"))
        for (size_t i = 0; i < 16 * 12; i++)
            im->rgb[3 * i] = 1.0f, im->rgb[3 * i + 1] = im->rgb[3 * i + 2] = 0.0f;
    else if (!strcmp(kind, "border")) { /* a region render: the data window inside a larger display window */
        im->x0 = 4, im->y0 = 2;
        im->display.min_x = 0, im->display.min_y = 0, im->display.max_x = 31, im->display.max_y = 23;
    }
    int rc = nbt_image_write_exr_ex(im, argv[1], NULL, err, sizeof err) != NBT_OK;
    if (rc)
        fprintf(stderr, "%s\n", err);
    nbt_image_free(im);
    return rc;
}
