/* gen/cli.h: argument and output checking shared by nbt-gen, nbt-fit and
 * nbt-scatter. Bad usage prints one line naming the option and the accepted
 * range, exits 2. */
#ifndef NBT_GEN_CLI_H
#define NBT_GEN_CLI_H

#include <stddef.h>

#define EXIT_USAGE 2

/* The program's name for messages ("nbt-gen", "nbt-fit"); set by main. */
extern const char *cli_prog;

_Noreturn void die_usage(const char *fmt, ...) __attribute__((format(printf, 1, 2)));
_Noreturn void die(const char *fmt, ...) __attribute__((format(printf, 1, 2)));
/* getopt's '?' (an unknown option) or ':' (a missing value), with an optstring
 * that starts with ':' so getopt itself prints nothing: one line naming the
 * option and pointing at CMD --help, exit 2. */
_Noreturn void die_bad_option(int c, char *const argv[], const char *cmd);

/* The parsers without the exit (what opt_* use; fuzzed by tests/fuzz_parsers.c):
 * 0 and *out set on success, -1 otherwise; parse_range returns NULL on
 * success, else why: "number", "length" (LO too long) or "order" (HI < LO). */
int parse_double(const char *arg, double lo, int lo_open, double hi, int hi_open, double *out);
int parse_long(const char *arg, long lo, long hi, long *out);
const char *parse_range(const char *arg, double lo, double hi, double *a, double *b);

/* The same with the opt_* message (naming OPT and the accepted range) written
 * to err instead of exiting: 0 and *v set, or -1. */
int msg_double(char *err, size_t n, const char *opt, const char *arg, double lo, int lo_open, double hi, int hi_open,
               double *v);
int msg_long(char *err, size_t n, const char *opt, const char *arg, long lo, long hi, long *v);
int msg_range(char *err, size_t n, const char *opt, const char *arg, double lo, double hi, double *a, double *b);

/* Parse a finite double in [lo, hi] (bounds excluded when *_open). */
double opt_double(const char *opt, const char *arg, double lo, int lo_open, double hi, int hi_open);
/* Parse an integer in [lo, hi]. */
long opt_long(const char *opt, const char *arg, long lo, long hi);
/* Parse "LO:HI" or a single value (LO = HI) within [lo, hi]. */
void opt_range(const char *opt, const char *arg, double lo, double hi, double *a, double *b);

/* Output paths are checked before any work: check_writable dies (exit 1)
 * with the OS reason unless PATH's directory exists and is writable and
 * PATH is not a directory; check_writable_dir does the same for a directory
 * to be written into (it may not exist yet: then its parent is checked).
 * OPT names the option in the message ("-o"). */
void check_writable(const char *opt, const char *path);
void check_writable_dir(const char *opt, const char *dir);

/* Output written all or nothing: out_open creates PATH.tmpPID for writing
 * (NULL on failure); out_close closes it and, if ok and the close worked,
 * renames it to PATH, else removes it. out_close returns 0 on success;
 * on failure both leave errno at the reason. */
#include <stdio.h>
FILE *out_open(const char *path, char **tmp);
int out_close(FILE *f, char *tmp, const char *path, int ok);

/* Is stderr a terminal (progress output only then)? */
int stderr_is_tty(void);

#endif
