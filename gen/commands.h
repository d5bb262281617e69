/* gen/commands.h: nbt-gen's subcommands and the table-set output they share. */
#ifndef NBT_GEN_COMMANDS_H
#define NBT_GEN_COMMANDS_H

#include <nbt/nbt.h>

int cmd_default(int argc, char **argv);
int cmd_tables(int argc, char **argv); /* "airlight" and "surface" */
int cmd_scene(int argc, char **argv);
int cmd_eval(int argc, char **argv);
int cmd_info(int argc, char **argv);
int cmd_kernel(int argc, char **argv);

/* Write each table of a built set as EXR (+ PNG preview unless !preview)
 * named "<stem>.exr" for one pack or "<stem>_k<a>-<b>.exr"; print a summary
 * line per table to stdout. All or nothing: on failure the files written by
 * this call are removed. Returns 0 or 1. */
int tableset_write(const nbt_tableset *ts, const char *path_stem, int preview);

double now_seconds(void);

/* The planner's Legendre budget as two '#' lines on stdout. */
void print_legendre(const nbt_plan_legendre *l, double gmax);

#endif
