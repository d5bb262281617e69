/* gen/cli.h: argument checking shared by nbt-gen's commands. Bad usage
 * prints one line naming the option and the accepted range, exits 2. */
#ifndef NBT_GEN_CLI_H
#define NBT_GEN_CLI_H

#include <stddef.h>

#define EXIT_USAGE 2

/* The program's name for messages ("nbt-gen", "nbt-fit"); set by main. */
extern const char *cli_prog;

_Noreturn void die_usage(const char *fmt, ...) __attribute__((format(printf, 1, 2)));
_Noreturn void die(const char *fmt, ...) __attribute__((format(printf, 1, 2)));

/* Parse a finite double in [lo, hi] (bounds excluded when *_open). */
double opt_double(const char *opt, const char *arg, double lo, int lo_open, double hi, int hi_open);
/* Parse an integer in [lo, hi]. */
long opt_long(const char *opt, const char *arg, long lo, long hi);
/* Parse "LO:HI" or a single value (LO = HI) within [lo, hi]. */
void opt_range(const char *opt, const char *arg, double lo, double hi, double *a, double *b);

/* Output written all or nothing: out_open creates PATH.tmpPID for writing
 * (NULL on failure); out_close closes it and, if ok and the close worked,
 * renames it to PATH, else removes it. out_close returns 0 on success. */
#include <stdio.h>
FILE *out_open(const char *path, char **tmp);
int out_close(FILE *f, char *tmp, const char *path, int ok);

/* Is stderr a terminal (progress output only then)? */
int stderr_is_tty(void);

#endif
