/* commands.h - the commands: one table of rows, each a command's name,
 * synopsis, flags (which decide the options it takes and whether a signal
 * stops it at a frame boundary) and handler. main() finds the row, parses
 * its options (options.h) and calls the handler, which returns through the
 * exit-status table (util.h). A new command is one row here and its module. */
#pragma once
#include "options.h"

/* A command line, parsed once. */
typedef struct sb_cli {
    sb_cli_opts o;              /* every option (options.h) */
    const sb_command_def *cmd;
    const char **pos;           /* the words that are not options, in order */
    int npos;
    int argc;
    char **argv;
    char **tail;                /* SB_CMDF_TAIL: the words after "--" */
    int ntail;
    const char *version, *commit;   /* this shadowbench's (version.h), written in every meta */
} sb_cli;

extern const sb_command_def sb_commands[SB_CMD_COUNT];
/* The command argv[1..] names ("history add" takes two words; *words says how many), or NULL. */
const sb_command_def *sb_command_find(int argc, char **argv, int *words);
/* Parses argv for the command and runs it: the exit status. */
int sb_command_main(int argc, char **argv, const char *version, const char *commit);
