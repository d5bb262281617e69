/* tests/pngcheck.c: reads a PNG preview with libpng (independently of the
 * writer in gen/preview.c) for tests/test_gen.sh. Prints "W H". With --bar,
 * also finds the colour bar, the coloured vertical run of at least 64
 * pixels in the rightmost column that has one, and checks it is a ramp:
 * luma (0.299 R + 0.587 G + 0.114 B, rising along the viridis-like ramp)
 * never rises from top to bottom by more than rounding (1 unit: each
 * component is rounded to 8 bits), and falls from > 200 to < 45 overall
 * (the ramp's ends have luma 215 and 30). With --max-luma X Y W H, prints
 * the largest luma in that rectangle instead. The bar's line also gives its
 * width: the coloured columns of its middle row that adjoin the found column.
 * With --cells X Y W H N, prints how many distinct ink patterns (luma < 128)
 * the N cells of W x H pixels at (X + i W, Y) hold: a label's glyph cells.
 * Exit 0 ok, 1 failed check, 2 bad file or usage. */
#include <png.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static unsigned char **rows;
static png_uint_32 W, H;

static int load(FILE *f)
{
    png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, NULL, NULL, NULL);
    png_infop info = png ? png_create_info_struct(png) : NULL;
    if (!info || setjmp(png_jmpbuf(png))) {
        png_destroy_read_struct(&png, info ? &info : NULL, NULL);
        return -1;
    }
    png_init_io(png, f);
    png_read_png(png, info, PNG_TRANSFORM_STRIP_16 | PNG_TRANSFORM_EXPAND, NULL);
    W = png_get_image_width(png, info);
    H = png_get_image_height(png, info);
    int ch = png_get_channels(png, info);
    png_bytepp r = png_get_rows(png, info);
    rows = malloc(H * sizeof *rows);
    for (png_uint_32 y = 0; y < H; y++) {
        rows[y] = malloc(W * 3);
        for (png_uint_32 x = 0; x < W; x++)
            for (int k = 0; k < 3; k++)
                rows[y][3 * x + k] = r[y][x * (png_uint_32)ch + (png_uint_32)(ch >= 3 ? k : 0)];
    }
    png_destroy_read_struct(&png, &info, NULL);
    return 0;
}

static int coloured(png_uint_32 x, png_uint_32 y)
{
    const unsigned char *p = rows[y] + 3 * x;
    return !(p[0] == p[1] && p[1] == p[2]);
}

static double luma(png_uint_32 x, png_uint_32 y)
{
    const unsigned char *p = rows[y] + 3 * x;
    return 0.299 * p[0] + 0.587 * p[1] + 0.114 * p[2];
}

int main(int argc, char **argv)
{
    int bar = argc == 3 && !strcmp(argv[1], "--bar"), ml = argc == 7 && !strcmp(argv[1], "--max-luma"),
        cells = argc == 8 && !strcmp(argv[1], "--cells");
    if (argc != 2 + bar + 5 * ml + 6 * cells) {
        fprintf(stderr, "usage: pngcheck [--bar | --max-luma X Y W H | --cells X Y W H N] FILE.png\n");
        return 2;
    }
    FILE *f = fopen(argv[argc - 1], "rb");
    if (!f || load(f)) {
        fprintf(stderr, "pngcheck: cannot read '%s'\n", argv[argc - 1]);
        return 2;
    }
    fclose(f);
    if (ml) {
        unsigned x0 = (unsigned)atoi(argv[2]), y0 = (unsigned)atoi(argv[3]), w = (unsigned)atoi(argv[4]),
                 h = (unsigned)atoi(argv[5]);
        double m = -1;
        for (unsigned y = y0; y < y0 + h && y < H; y++)
            for (unsigned x = x0; x < x0 + w && x < W; x++)
                m = luma(x, y) > m ? luma(x, y) : m;
        printf("%.1f\n", m);
        return 0;
    }
    if (cells) {
        unsigned x0 = (unsigned)atoi(argv[2]), y0 = (unsigned)atoi(argv[3]), w = (unsigned)atoi(argv[4]),
                 h = (unsigned)atoi(argv[5]), n = (unsigned)atoi(argv[6]), distinct = 0;
        if (x0 + n * w > W || y0 + h > H) {
            fprintf(stderr, "pngcheck: cells outside the %ux%u image\n", (unsigned)W, (unsigned)H);
            return 2;
        }
        for (unsigned i = 0; i < n; i++) {
            int seen = 0; /* cell i equals an earlier one */
            for (unsigned j = 0; j < i && !seen; j++) {
                int same = 1;
                for (unsigned y = y0; y < y0 + h && same; y++)
                    for (unsigned x = 0; x < w && same; x++)
                        same = (luma(x0 + i * w + x, y) < 128) == (luma(x0 + j * w + x, y) < 128);
                seen = same;
            }
            distinct += !seen;
        }
        printf("%u\n", distinct);
        return 0;
    }
    printf("%u %u\n", (unsigned)W, (unsigned)H);
    if (!bar)
        return 0;
    for (png_uint_32 x = W; x-- > 0;) {
        png_uint_32 best = 0, b0 = 0;
        for (png_uint_32 y = 0; y < H;) {
            png_uint_32 y1 = y;
            while (y1 < H && coloured(x, y1))
                y1++;
            if (y1 - y > best) {
                best = y1 - y;
                b0 = y;
            }
            y = y1 + 1;
        }
        if (best < 64)
            continue;
        for (png_uint_32 y = b0 + 1; y < b0 + best; y++)
            if (luma(x, y) > luma(x, y - 1) + 1.0) {
                printf("bar at column %u: luma rises at row %u (%g -> %g)\n", (unsigned)x, (unsigned)y,
                       luma(x, y - 1), luma(x, y));
                return 1;
            }
        double top = luma(x, b0), bot = luma(x, b0 + best - 1);
        if (!(top > 200 && bot < 45)) {
            printf("bar at column %u: luma %g (top) to %g (bottom), expected > 200 to < 45\n", (unsigned)x, top, bot);
            return 1;
        }
        png_uint_32 ym = b0 + best / 2, x0 = x;
        while (x0 > 0 && coloured(x0 - 1, ym))
            x0--;
        printf("bar at column %u, rows %u..%u, width %u\n", (unsigned)x, (unsigned)b0, (unsigned)(b0 + best - 1),
               (unsigned)(x - x0 + 1));
        return 0;
    }
    printf("no colour bar (no coloured vertical run of 64 pixels)\n");
    return 1;
}
