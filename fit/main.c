/* fit/main.c: nbt-fit, photon counting and (later) kernel fits. */
#include <config.h>
#include <stdio.h>
#include <string.h>
#include <nbt/nbt.h>
#include "../gen/cli.h"
#include "commands.h"

static void help(void)
{
    puts("Usage: nbt-fit mc [...]     photon counting: a pencil beam in a layered medium or a slab\n"
         "       nbt-fit kernel [...] fit alpha, beta of the narrow-beam kernel to photon counts\n"
         "       nbt-fit phase [...]  fit a sum of Gaussian lobes to a phase function\n"
         "       nbt-fit model [...]  fit the kernel model (nbt_beam_fit) over depth, albedo and phase width\n"
         "       nbt-fit screenmodel [...]  fit nbt-scatter's model of the higher scattering orders for a phase\n"
         "       nbt-fit --version\n\n"
         "'nbt-fit COMMAND --help' describes each command. Exit status: 0 success,\n"
         "1 failure (including an output that cannot be written), 2 bad usage or an input\n"
         "file that is missing, unreadable or malformed.");
}

int main(int argc, char **argv)
{
    cli_prog = "nbt-fit";
    if (argc < 2)
        die_usage("say what to do: mc, kernel, phase, model or screenmodel (see 'nbt-fit --help')");
    const char *c = argv[1];
    if (!strcmp(c, "--help") || !strcmp(c, "-h")) {
        help();
        return 0;
    }
    if (!strcmp(c, "--version")) {
        printf("nbt-fit (nbt) %s\n", nbt_version());
        return 0;
    }
    if (!strcmp(c, "mc"))
        return cmd_mc(argc - 1, argv + 1);
    if (!strcmp(c, "screenmodel"))
        return cmd_screenmodel(argc - 1, argv + 1);
    if (!strcmp(c, "kernel") || !strcmp(c, "phase") || !strcmp(c, "model")) {
#ifdef HAVE_CERES
        if (!strcmp(c, "model"))
            return cmd_model(argc - 1, argv + 1);
        return !strcmp(c, "kernel") ? cmd_kernel(argc - 1, argv + 1) : cmd_phase(argc - 1, argv + 1);
#else
        die("'%s' needs Ceres, which this build was configured without (install libceres-dev "
            "libeigen3-dev libgoogle-glog-dev and re-run configure)", c);
#endif
    }
    die_usage("unknown command '%s': mc, kernel, phase, model, screenmodel (see 'nbt-fit --help')", c);
}
