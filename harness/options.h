/* options.h - the command line as data: the commands, and every option as one
 * row of sb_options[] (options.c).
 *
 * A row says the option's name, what its value is (kind, range or choices),
 * its default, the commands that take it, a line of help, and where the parsed
 * value goes (a field of sb_cli_opts). One loop over the table parses a command
 * line (sb_cli_parse) and a batch file's `defaults` line (sb_cli_parse_tokens),
 * writes `--help` for each command (sb_cli_help), and tells whether an option
 * was given (sb_cli_given). An option a command does not take is refused
 * naming both; a value out of range names the range. Nothing else parses an
 * option: add one as a row (docs/architecture.md, "Where a change goes"). */
#pragma once
#include <stdio.h>

#include "session.h"

/* The commands, in the order `--help` lists them. */
typedef enum sb_command {
    SB_CMD_RUN,
    SB_CMD_BATCH,
    SB_CMD_COMPARE,
    SB_CMD_MERGE,
    SB_CMD_TUNE,
    SB_CMD_STRESS,
    SB_CMD_HISTORY,
    SB_CMD_BISECT,
    SB_CMD_REPORT,
    SB_CMD_TECHNIQUES,
    SB_CMD_COLUMNS,
    SB_CMD_INFO,
    SB_CMD_PATH,
    SB_CMD_COUNT
} sb_command;

typedef struct sb_command_def {
    const char *name;
    const char *usage; /* the synopsis lines, without "shadowbench " (several
                          lines: '\n' between) */
    const char *summary; /* what it does, one line */
} sb_command_def;

extern const sb_command_def sb_commands[SB_CMD_COUNT];
/* The command named `name`, or -1. */
int sb_command_find(const char *name);

/* Which commands take a row: a set of SB_IN(cmd) bits; SB_IN_FILE is a batch
 * file's `defaults` line. */
#define SB_IN(cmd) (1u << (cmd))
#define SB_IN_FILE (1u << SB_CMD_COUNT)

typedef enum sb_opt_kind {
    SB_OPT_FLAG, /* no value: bool true */
    SB_OPT_INT, /* int in [min, max]; "auto" stored as -1 where the row allows it
                 */
    SB_OPT_SEED, /* uint64_t in [min, max] */
    SB_OPT_NUM, /* double in [min, max] (or (min, ...) with open_min) */
    SB_OPT_DURATION, /* double seconds: 600, 90s, 10m, 1.5h */
    SB_OPT_BYTES, /* double bytes: 512M, 8G */
    SB_OPT_CHOICE, /* int: one of `arg`'s '|' names (the index, or values[index])
                    */
    SB_OPT_TEXT, /* const char *: the argument itself */
    SB_OPT_SIZE, /* WxH: two ints (field and field2) in [min, max] */
    SB_OPT_ANGLES, /* AZ,EL: two doubles (field and field2), EL in [min, max] */
} sb_opt_kind;

/* Every option's parsed value, and which were given. */
#define SB_OPTION_MAX 64
typedef struct sb_cli_opts {
    bool given[SB_OPTION_MAX]; /* by row of sb_options; first, so that no row's
                                  field is at offset 0 (0: none) */
    sb_run_opts run; /* the run options: run, batch, tune, stress (and the scene
                        options of info and path) */
    const char *out, *resume, *shard, *metrics, *pair, *techniques, *history, *since, *series, *workdir;
    int format; /* --format: an sb_output_format */
    int recent, pairs, nights;
    double noise_floor, threshold, max_err, max_flicker, max_mb, budget_ms, time_limit_s;
    bool dry_run, quiet, verbose, accept;
} sb_cli_opts;

typedef struct sb_option {
    const char *name; /* "--frames" */
    sb_opt_kind kind;
    const char *arg; /* the value's name in --help ("N", "WxH"); SB_OPT_CHOICE: "a|b|c" */
    double min, max; /* the range (INT, SEED, NUM, DURATION, BYTES, SIZE; ANGLES:
                        the elevation) */
    bool open_min; /* NUM, DURATION: min itself is out of range */
    bool can_auto; /* INT: "auto" is a value (stored as -1) */
    const int *values; /* CHOICE: the value stored for each name (NULL: its index) */
    const char *def; /* the default, parsed as given (NULL: none, or one code
                        works out: def_help says) */
    const char *def_help; /* what --help says of a default the table cannot hold
                             (NULL: def) */
    unsigned commands; /* SB_IN(...) bits */
    size_t field, field2; /* offsets in sb_cli_opts (field2: SIZE's height,
                             ANGLES' elevation) */
    size_t given_field; /* a bool set when given (0: none) */
    const char *help;
    bool (*check)(const char *value, const sb_cli_opts *o, sb_err *err); /* what the range cannot say (NULL: none) */
} sb_option;

extern const sb_option sb_options[];
extern const int sb_option_count;

/* The defaults of the run options and of the rows of cmd (-1: the run
 * options alone); a row without one: zero, or what code works out (--threads:
 * all cores). */
void sb_cli_defaults(sb_cli_opts *o, int cmd);
/* The run options' defaults alone (the same rows). */
void sb_run_opts_defaults(sb_run_opts *o);
/* Parses argv[first..argc) for `cmd`: options into o (which holds the
 * defaults), the other words into pos (at most argc of them) in order. false
 * with a one-line error naming the option (and the command when it does not
 * take it). */
bool sb_cli_parse(sb_cli_opts *o, sb_command cmd, int argc, char **argv, int first, const char **pos, int *npos,
                  sb_err *err);
/* The same for a batch file's `defaults` line (rows marked SB_IN_FILE); where:
 * "FILE:LINE", said before each error. */
bool sb_cli_parse_tokens(sb_cli_opts *o, char **tok, int n, const char *where, sb_err *err);
/* Was the option given (by name, on the command line or the defaults line)? */
bool sb_cli_given(const sb_cli_opts *o, const char *name);
/* Copies the run options given in `from` over `to` (the command line beating a
 * batch file's defaults). */
void sb_cli_copy_given(sb_run_opts *to, const sb_cli_opts *from);
/* The row of `name` that `cmd` takes (cmd < 0: any row of that name), or NULL.
 */
const sb_option *sb_option_find(const char *name, int cmd);

/* `shadowbench --help` (every command and option), or one command's
 * (its synopsis and the options it takes). */
void sb_cli_help(FILE *f, int cmd);
/* An option's value as --help writes it ("--frames N", "--backend egl|osmesa").
 */
void sb_option_synopsis(const sb_option *opt, char *out, size_t len);
