/* frepmill.c: the one-shot command-line tool. It dispatches to the
 * subcommands in cmd_*.c, which run the same pipeline as the daemon. */
#include "commands.h"

#include <stdio.h>
#include <string.h>

static const fm_command commands[] = {
    {"check", "find collisions and unsafe moves in a program before it runs", fm_cmd_check},
    {"eval", "evaluate a HyperFun model at a point", fm_cmd_eval},
    {"mesh", "mesh a HyperFun model (and draw it)", fm_cmd_mesh},
    {"simulate", "cut a program out of a stock and report what was removed", fm_cmd_simulate},
    {"motions", "print the motions of a G-code program or trajectory", fm_cmd_motions},
    {"time", "a program's cycle time as the controller plans it (docs/plan.md)", fm_cmd_time},
    {NULL, NULL, NULL}};

static void usage(FILE *out)
{
    fprintf(out, "usage: frepmill COMMAND [ARGS...]\n\ncommands:\n");
    for (const fm_command *c = commands; c->name; c++)
        fprintf(out, "  %-10s %s\n", c->name, c->summary);
    fprintf(out, "\n`frepmill COMMAND --help` describes a command.\n");
}

int main(int argc, char **argv)
{
    if (argc < 2) {
        usage(stderr);
        return 2;
    }
    if (!strcmp(argv[1], "--help") || !strcmp(argv[1], "-h") || !strcmp(argv[1], "help")) {
        usage(stdout);
        return 0;
    }
    for (const fm_command *c = commands; c->name; c++)
        if (!strcmp(argv[1], c->name)) return c->run(argc - 1, argv + 1);
    fprintf(stderr, "frepmill: unknown command '%s'\n", argv[1]);
    usage(stderr);
    return 2;
}
