/* gen/commands.h: nbt-gen's subcommands and the table-set builder they share. */
#ifndef NBT_GEN_COMMANDS_H
#define NBT_GEN_COMMANDS_H

#include <nbt/nbt.h>

int cmd_default(int argc, char **argv);
int cmd_tables(int argc, char **argv); /* "airlight" and "surface" */
int cmd_scene(int argc, char **argv);
int cmd_eval(int argc, char **argv);
int cmd_info(int argc, char **argv);
int cmd_kernel(int argc, char **argv);

/* What to tabulate: H (airlight) or J^n (surface), Legendre orders
 * 0..nterms-1 in packs of four, or one fixed-phase channel. */
typedef struct {
    nbt_table_kind kind;
    int n;                  /* J: cosine exponent */
    size_t nterms;          /* Legendre orders, when phase == NULL */
    const nbt_phase *phase; /* fixed phase, or NULL */
    double xmax;            /* upper end of u (H) or T (J) */
    double tol;             /* target: max interpolation error / max |value|; 0: use size */
    size_t size[2];         /* nodes per axis when tol == 0 */
    int half;
    unsigned threads;
} tableset_spec;

#define TABLESET_MAX 64
typedef struct {
    nbt_table *t[TABLESET_MAX];
    size_t count;
    double seconds;
    double scale;            /* largest value of the first pack: the set's scale */
    double rel_err;          /* max over tables of max_err / scale */
} tableset;

/* Build (choosing axis mappings and size when spec->tol > 0). Returns 0 or
 * prints the reason and returns 1. */
int tableset_build(const tableset_spec *spec, tableset *out);
void tableset_free(tableset *ts);
/* Write each table as EXR (+ PNG preview unless !preview) named
 * "<dir>/<stem>.exr" for one pack or "<dir>/<stem>_k<a>-<b>.exr"; print a
 * summary line per table to stdout. All or nothing: on failure the files
 * written by this call are removed. Returns 0 or 1. */
int tableset_write(const tableset *ts, const char *path_stem, int preview);
/* Table file name stem for a spec, e.g. "H", "J20", "H_hg0.8". */
void tableset_stem(const tableset_spec *spec, char *buf, size_t n);

double now_seconds(void);

/* For Legendre tables serving |g| <= gmax at total relative error tol: the
 * number of terms (truncation error <= tol/2, measured on sample rays with u
 * up to xmax) and the per-table interpolation target (tol/2 over the error
 * amplification sum (2k+1)|g|^k). Prints both as '#' lines. 0, or 1 when
 * more than 512 terms would be needed. */
/* Legendre terms for |g| <= gmax at tol (half truncation, half tables); 1 when
 * more than nmax (<= 512) terms are needed (*nterms then holds the need, or
 * 513 past 512), without printing. */
int legendre_budget(double gmax, double xmax, double tol, size_t nmax, size_t *nterms, double *table_tol);

#endif
