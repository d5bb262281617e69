/* tests/mkexr.c: writes small broken renders for nbt-scatter's bad-input
 * tests: mkexr OUT.exr noz|nan|negative|inf. */
#include <config.h>
#include <math.h>
#include <stdio.h>
#include <string.h>
#include <nbt/image.h>

int main(int argc, char **argv)
{
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
    char err[256];
    int rc = nbt_image_write_exr(im, argv[1], NULL, 0, err, sizeof err) != NBT_OK;
    if (rc)
        fprintf(stderr, "%s\n", err);
    nbt_image_free(im);
    return rc;
}
