/* gen/cli.c: argument checking and fatal errors for nbt-gen and nbt-fit. */
#include <config.h>
#include <getopt.h>
#include <errno.h>
#include <libgen.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>
#include "cli.h"

const char *cli_prog = "nbt";

static void vmsg(const char *fmt, va_list ap)
{
    fprintf(stderr, "%s: ", cli_prog);
    vfprintf(stderr, fmt, ap);
    fputc('\n', stderr);
}

void die_usage(const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vmsg(fmt, ap);
    va_end(ap);
    exit(EXIT_USAGE);
}

void die_bad_option(int c, char *const argv[], const char *cmd)
{
    /* what the user typed: the argument getopt just passed (a missing value is
     * always the last one; "--flag=1" is refused whole, as is an ambiguous
     * prefix); an unknown letter in a group of short options is optopt (glibc
     * leaves optopt 0 for an unknown long option) */
    const char *a = optind > 0 ? argv[optind - 1] : "?";
    if (c == ':')
        die_usage("%s needs a value (see '%s --help')", a, cmd);
    if (optopt > ' ' && optopt < 127 && strncmp(a, "--", 2) != 0)
        die_usage("unknown option '-%c' (see '%s --help')", optopt, cmd);
    die_usage("unknown option '%s' (see '%s --help')", a, cmd);
}

void die(const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vmsg(fmt, ap);
    va_end(ap);
    exit(EXIT_FAILURE);
}

static const char *bound(double v, int open, int lower)
{
    static char buf[2][64];
    if (isinf(v))
        return lower ? "(-inf" : "inf)";
    if (lower)
        snprintf(buf[1], sizeof buf[1], "%s%g", open ? "(" : "[", v);
    else
        snprintf(buf[0], sizeof buf[0], "%g%s", v, open ? ")" : "]");
    return buf[lower];
}

int parse_double(const char *arg, double lo, int lo_open, double hi, int hi_open, double *out)
{
    char *end;
    errno = 0;
    double v = strtod(arg, &end);
    int ok = end != arg && *end == '\0' && errno != ERANGE && isfinite(v) &&
             (lo_open ? v > lo : v >= lo) && (hi_open ? v < hi : v <= hi);
    if (ok)
        *out = v;
    return ok ? 0 : -1;
}

int parse_long(const char *arg, long lo, long hi, long *out)
{
    char *end;
    errno = 0;
    long v = strtol(arg, &end, 10);
    if (end == arg || *end != '\0' || errno == ERANGE || v < lo || v > hi)
        return -1;
    *out = v;
    return 0;
}

const char *parse_range(const char *arg, double lo, double hi, double *a, double *b)
{
    const char *colon = strchr(arg, ':');
    if (!colon) {
        if (parse_double(arg, lo, 0, hi, 0, a))
            return "number";
        *b = *a;
        return NULL;
    }
    char first[128];
    size_t n = (size_t)(colon - arg);
    if (n >= sizeof first)
        return "length";
    memcpy(first, arg, n);
    first[n] = '\0';
    if (parse_double(first, lo, 0, hi, 0, a) || parse_double(colon + 1, lo, 0, hi, 0, b))
        return "number";
    return *b < *a ? "order" : NULL;
}

int msg_double(char *err, size_t n, const char *opt, const char *arg, double lo, int lo_open, double hi, int hi_open,
               double *v)
{
    if (!parse_double(arg, lo, lo_open, hi, hi_open, v))
        return 0;
    snprintf(err, n, "%s: '%s' is not accepted: expected a number in %s, %s", opt, arg, bound(lo, lo_open, 1),
             bound(hi, hi_open, 0));
    return -1;
}

int msg_long(char *err, size_t n, const char *opt, const char *arg, long lo, long hi, long *v)
{
    if (!parse_long(arg, lo, hi, v))
        return 0;
    snprintf(err, n, "%s: '%s' is not accepted: expected an integer in [%ld, %ld]", opt, arg, lo, hi);
    return -1;
}

int msg_range(char *err, size_t n, const char *opt, const char *arg, double lo, double hi, double *a, double *b)
{
    const char *why = parse_range(arg, lo, hi, a, b);
    if (!why)
        return 0;
    if (!strcmp(why, "length"))
        snprintf(err, n, "%s: '%s' is too long", opt, arg);
    else if (!strcmp(why, "order"))
        snprintf(err, n, "%s: '%s' is not accepted: the range must be LO:HI with LO <= HI", opt, arg);
    else
        snprintf(err, n, "%s: '%s' is not accepted: expected a number or LO:HI in [%g, %g]", opt, arg, lo, hi);
    return -1;
}

double opt_double(const char *opt, const char *arg, double lo, int lo_open, double hi, int hi_open)
{
    double v;
    char err[512];
    if (msg_double(err, sizeof err, opt, arg, lo, lo_open, hi, hi_open, &v))
        die_usage("%s", err);
    return v;
}

long opt_long(const char *opt, const char *arg, long lo, long hi)
{
    long v;
    char err[512];
    if (msg_long(err, sizeof err, opt, arg, lo, hi, &v))
        die_usage("%s", err);
    return v;
}

void opt_range(const char *opt, const char *arg, double lo, double hi, double *a, double *b)
{
    char err[512];
    if (msg_range(err, sizeof err, opt, arg, lo, hi, a, b))
        die_usage("%s", err);
}

/* 0 if DIR (the directory of PATH) exists and is writable, else errno */
static int dir_of_writable(const char *path)
{
    char *dup = strdup(path);
    if (!dup)
        return ENOMEM;
    struct stat sb;
    const char *dir = dirname(dup);
    int e = stat(dir, &sb) != 0 ? errno : !S_ISDIR(sb.st_mode) ? ENOTDIR : access(dir, W_OK | X_OK) != 0 ? errno : 0;
    free(dup);
    return e;
}

void check_writable(const char *opt, const char *path)
{
    struct stat sb;
    int e = stat(path, &sb) == 0 && S_ISDIR(sb.st_mode) ? EISDIR : dir_of_writable(path);
    if (e)
        die("%s: cannot write '%s': %s", opt, path, strerror(e));
}

void check_writable_dir(const char *opt, const char *dir)
{
    struct stat sb;
    int e;
    if (stat(dir, &sb) == 0)
        e = !S_ISDIR(sb.st_mode) ? ENOTDIR : access(dir, W_OK | X_OK) != 0 ? errno : 0;
    else
        e = errno == ENOENT ? dir_of_writable(dir) : errno;
    if (e)
        die("%s: cannot write into the directory '%s': %s", opt, dir, strerror(e));
}

FILE *out_open(const char *path, char **tmp)
{
    size_t len = strlen(path) + 32;
    *tmp = malloc(len);
    if (!*tmp)
        return NULL;
    snprintf(*tmp, len, "%s.tmp%ld", path, (long)getpid());
    FILE *f = fopen(*tmp, "w");
    if (!f) {
        free(*tmp);
        *tmp = NULL;
    }
    return f;
}

int out_close(FILE *f, char *tmp, const char *path, int ok)
{
    int rc = fclose(f) != 0 || !ok || rename(tmp, path) != 0;
    int e = errno; /* the reason, for the caller's message */
    if (rc)
        unlink(tmp);
    free(tmp);
    errno = e;
    return rc;
}

int stderr_is_tty(void)
{
    return isatty(fileno(stderr));
}
