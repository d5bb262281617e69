/* fit/commands.h: nbt-fit's subcommands. */
#ifndef NBT_FIT_COMMANDS_H
#define NBT_FIT_COMMANDS_H

int cmd_mc(int argc, char **argv);
int cmd_screenmodel(int argc, char **argv);
int cmd_kernel(int argc, char **argv); /* with Ceres only */
int cmd_phase(int argc, char **argv);  /* with Ceres only */
int cmd_model(int argc, char **argv);  /* with Ceres only */

#endif
