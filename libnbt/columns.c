/* libnbt/columns.c: reading the two-column text files of phase tables,
 * sum-of-Gaussians files and density profiles. Strict: every line is blank,
 * a comment ('#' to the end of the line) or exactly two finite numbers
 * (optionally followed by a comment); anything else is an error naming
 * file:line, so a mistyped line is never silently dropped. */
#include <config.h>
#include <ctype.h>
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
        int e = errno;
        snprintf(err, errlen, "%s '%s' cannot be opened: %s", what, path, strerror(e));
        return nbt__io_status(e);
    }
    size_t n = 0, cap = 64;
    double *x = malloc(cap * sizeof(double)), *y = malloc(cap * sizeof(double));
    char line[512];
    int ln = 0;
    nbt_status st = x && y ? NBT_OK : NBT_ENOMEM;
    while (st == NBT_OK && fgets(line, sizeof line, f)) {
        ln++;
        size_t len = strlen(line);
        if (len == sizeof line - 1 && line[len - 1] != '\n' && !feof(f)) {
            snprintf(err, errlen, "%s:%d: %s: the line is longer than %zu characters", path, ln, what, sizeof line - 2);
            st = NBT_EFORMAT;
            break;
        }
        while (len > 0 && isspace((unsigned char)line[len - 1]))
            line[--len] = '\0';
        char *h = strchr(line, '#');
        if (h)
            *h = '\0';
        const char *p = line;
        while (isspace((unsigned char)*p))
            p++;
        if (*p == '\0') /* blank or a comment */
            continue;
        /* data: exactly two finite numbers separated by white space, then
         * only white space (the comment is cut off above) */
        char *e1, *e2 = NULL;
        double a = strtod(p, &e1), b = e1 != p && isspace((unsigned char)*e1) ? strtod(e1, &e2) : 0;
        int ok = e1 != p && isspace((unsigned char)*e1) && e2 != e1;
        if (ok) {
            while (isspace((unsigned char)*e2))
                e2++;
            ok = *e2 == '\0' && isfinite(a) && isfinite(b);
        }
        if (!ok) {
            if (h)
                *h = '#';
            snprintf(err, errlen, "%s:%d: %s: '%.60s%s' is not accepted: expected two finite numbers '%s', "
                     "optionally followed by a '#' comment (blank lines and lines starting with '#' are skipped)",
                     path, ln, what, line, strlen(line) > 60 ? "..." : "", names);
            st = NBT_EFORMAT;
            break;
        }
        char why[160];
        if (check && check(n, a, b, n ? x[n - 1] : 0, why, sizeof why)) {
            snprintf(err, errlen, "%s:%d: %s: %s (columns '%s')", path, ln, what, why, names);
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
    if (st == NBT_OK && ferror(f)) {
        int e = errno;
        snprintf(err, errlen, "%s '%s' cannot be read: %s", what, path, strerror(e));
        st = nbt__io_status(e);
    }
    fclose(f);
    if (st == NBT_OK && n == 0) {
        snprintf(err, errlen, "%s: the %s is empty (no data lines): expected lines '%s' (two finite numbers)", path,
                 what, names);
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
