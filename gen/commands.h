/* gen/commands.h: nbt-gen's subcommands and the table-set output they share. */
#ifndef NBT_GEN_COMMANDS_H
#define NBT_GEN_COMMANDS_H

#include <nbt/nbt.h>

int cmd_default(int argc, char **argv);
int cmd_tables(int argc, char **argv); /* "airlight" and "surface" */
int cmd_scene(int argc, char **argv);
int cmd_eval(int argc, char **argv);
int cmd_info(int argc, char **argv);
/* eval airlight|surface --method table --tables FILE...: geo is an
 * nbt_airlight_geom or nbt_surface_geom (gen/eval_tables.c) */
int eval_from_tables(int surface, const void *geo, const char *const *files, size_t nfiles, const char *g_arg,
                     const char *phase_arg);
int cmd_kernel(int argc, char **argv);

#include "progress.h"
/* Write each table of a built set as EXR (+ PNG preview unless !preview)
 * named "<stem>.exr" for one pack or "<stem>_k<a>-<b>.exr"; print a summary
 * line per table to stdout. All or nothing: on failure the files written by
 * this call are removed. With p (may be NULL): a line with the files, their
 * bytes and the predicted time, progress lines while they are written
 * ("WHAT: writing: N% done, ..., ETA ..."), a line with the time taken.
 * Returns 0 or 1. */
int tableset_write(const nbt_tableset *ts, const char *path_stem, int preview, progress *p);
/* The same for nsets sets at once (stems[i] for ts[i]), all or nothing over
 * all of them; the files are written in parallel, the lines printed in order. */
int tablesets_write(const nbt_tableset *ts, size_t nsets, const char *const *stems, int preview, progress *p);

/* A g-sliced table's recorded error as a pure lookup sees it: relative to
 * the value for the tail and log_et forms, else to the largest value. */
double gslice_lookup_err(const nbt_table *t);
/* 0 when t's recorded lookup error meets tol; else one message naming both
 * (and, for the tail form, what the error map covers) on stderr and 1,
 * or with allow a warning on stderr and 0. */
int gslice_tol_check(const nbt_table *t, const char *name, double tol, int allow);

double now_seconds(void);

/* Progress of planned builds (gen/progress.h): plan_announce notes the plan's
 * predicted build time and the predicted time to write its tables (one
 * warning when the two exceed 60 s) and returns the build time; build_set builds
 * set i with a line at its start (size, predicted time, ETA of the sets
 * left, *pred_left, which it then lowers) and one at its end (actual time). */
#include "progress.h"
double plan_announce(const nbt_plan *plan, progress *p);
nbt_status build_set(const nbt_plan *plan, size_t i, progress *p, double *pred_left, nbt_tableset *ts, char *err,
                     size_t errlen);

/* Whether an axis map has a strength c (log1p, log1p_cbrt, asinh, ends): the
 * tools print it beside the map's name. */
int axis_map_has_c(nbt_axis_map m);

/* The planner's Legendre budget as two '#' lines on stdout. */
void print_legendre(const nbt_plan_legendre *l, double gmax);

#endif
