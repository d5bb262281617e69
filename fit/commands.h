/* fit/commands.h: nbt-fit's subcommands. */
#ifndef NBT_FIT_COMMANDS_H
#define NBT_FIT_COMMANDS_H

int cmd_mc(int argc, char **argv);

#endif
