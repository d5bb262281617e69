/* gen/main.c: nbt-gen, lookup tables for scattering in participating media. */
#include <config.h>
#include <stdio.h>
#include <string.h>
#include "cli.h"
#include "commands.h"
#include "outputs.h"

static void help(void)
{
    puts("Usage: nbt-gen [--quiet]       build the default scene into ./nbt-tables/ (form sub, 33x33;\n"
         "                               --quiet: no progress lines on stderr)\n"
         "       nbt-gen airlight [...]  H_k(u, v) tables (airlight)\n"
         "       nbt-gen surface [...]   J_k^n(T, theta) tables (surface radiance)\n"
         "       nbt-gen scene FILE      only the tables a scene needs\n"
         "       nbt-gen eval WHAT [...] one value with its error: H, J, airlight, surface\n"
         "       nbt-gen info FILE       a table's metadata and values\n"
         "       nbt-gen kernel [...]    the narrow-beam kernel's alpha, beta as a table\n"
         "       nbt-gen --version\n\n"
         "'nbt-gen COMMAND --help' describes each command. Exit status: 0 success,\n"
         "1 failure (including an output that cannot be written), 2 bad usage or an input\n"
         "file that is missing, unreadable or malformed.");
}

static int run(int argc, char **argv)
{
    if (argc < 2 || !strcmp(argv[1], "--quiet") || !strcmp(argv[1], "-q"))
        return cmd_default(argc, argv);
    const char *c = argv[1];
    if (!strcmp(c, "--help") || !strcmp(c, "-h")) {
        help();
        return 0;
    }
    if (!strcmp(c, "--version")) {
        printf("nbt-gen (nbt) %s\n", nbt_version());
        return 0;
    }
    if (!strcmp(c, "airlight") || !strcmp(c, "surface"))
        return cmd_tables(argc - 1, argv + 1);
    if (!strcmp(c, "scene"))
        return cmd_scene(argc - 1, argv + 1);
    if (!strcmp(c, "eval"))
        return cmd_eval(argc - 1, argv + 1);
    if (!strcmp(c, "info"))
        return cmd_info(argc - 1, argv + 1);
    if (!strcmp(c, "kernel"))
        return cmd_kernel(argc - 1, argv + 1);
    die_usage("unknown command '%s': airlight, surface, scene, eval, info, kernel (see 'nbt-gen --help')", c);
}

int main(int argc, char **argv)
{
    cli_prog = "nbt-gen";
    /* an interrupted or failed run leaves none of its files (outputs.h) */
    outputs_install();
    int rc = run(argc, argv);
    if (rc == 0)
        outputs_commit();
    return rc;
}
