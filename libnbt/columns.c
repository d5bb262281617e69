/* libnbt/columns.c: reading the two-column text files of phase tables and
 * density profiles. */
#include <config.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "internal.h"

nbt_status nbt__read_columns(const char *path, const char *what, const char *names, nbt__row_check check,
                             double **xo, double **yo, size_t *no, char *err, size_t errlen)
{
    *xo = *yo = NULL;
    *no = 0;
    FILE *f = fopen(path, "r");
    if (!f) {
        snprintf(err, errlen, "%s '%s' cannot be opened: %s", what, path, strerror(errno));
        return NBT_EIO;
    }
    size_t n = 0, cap = 64;
    double *x = malloc(cap * sizeof(double)), *y = malloc(cap * sizeof(double));
    char line[512];
    int ln = 0;
    nbt_status st = x && y ? NBT_OK : NBT_ENOMEM;
    while (st == NBT_OK && fgets(line, sizeof line, f)) {
        ln++;
        char *h = strchr(line, '#'), extra;
        if (h)
            *h = '\0';
        double a, b;
        int got = sscanf(line, "%lf %lf %c", &a, &b, &extra);
        if (got <= 0)
            continue;
        const char *why = got != 2 || !isfinite(a) || !isfinite(b) ? "expected two finite numbers"
                                                                   : (check ? check(n, a, b, n ? x[n - 1] : 0) : NULL);
        if (why) {
            snprintf(err, errlen, "%s '%s' line %d: %s '%s'", what, path, ln, why, names);
            st = NBT_EFORMAT;
            break;
        }
        if (n == cap) {
            cap *= 2;
            double *x2 = realloc(x, cap * sizeof(double));
            if (x2)
                x = x2;
            double *y2 = x2 ? realloc(y, cap * sizeof(double)) : NULL;
            if (y2)
                y = y2;
            if (!x2 || !y2) {
                st = NBT_ENOMEM;
                break;
            }
        }
        x[n] = a;
        y[n] = b;
        n++;
    }
    fclose(f);
    if (st == NBT_OK && n == 0) {
        snprintf(err, errlen, "%s '%s' is empty: expected lines '%s'", what, path, names);
        st = NBT_EFORMAT;
    }
    if (st == NBT_ENOMEM)
        snprintf(err, errlen, "out of memory");
    if (st != NBT_OK) {
        free(x);
        free(y);
        return st;
    }
    *xo = x;
    *yo = y;
    *no = n;
    return NBT_OK;
}
