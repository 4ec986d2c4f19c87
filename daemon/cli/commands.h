/* commands.h: the subcommands of the `frepmill` CLI. Each lives in its own
 * cmd_<name>.c file and returns the process exit status (0 success, 1
 * findings, 2 bad input, 3 resource limit, 4 I/O). */
#ifndef FM_COMMANDS_H
#define FM_COMMANDS_H

typedef struct fm_command {
    const char *name;
    const char *summary;
    int (*run)(int argc, char **argv); /* argv[0] is the subcommand name */
} fm_command;

/* Defined in the cmd_*.c files; listed in frepmill.c. */
int fm_cmd_check(int argc, char **argv);
int fm_cmd_eval(int argc, char **argv);
int fm_cmd_mesh(int argc, char **argv);
int fm_cmd_motions(int argc, char **argv);
int fm_cmd_simulate(int argc, char **argv);
int fm_cmd_time(int argc, char **argv);

#endif
