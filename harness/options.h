/* options.h - the command line as data: the commands, and every option as one
 * row of sb_options[] (options.c).
 *
 * A row says the option's name, what its value is (kind, range or choices),
 * its default (and a command's own, where one differs), the commands that
 * take it, whether it is part of a run's identity, a line of help, and where
 * the parsed value goes (a field of sb_cli_opts). One loop over the table
 * parses a command line (sb_cli_parse) and a batch file's `defaults` line
 * (sb_cli_parse_tokens), writes `--help` for each command (sb_cli_help), tells
 * whether an option was given (sb_cli_given) and hashes a run's identity
 * (sb_run_id). An option a command does not take is refused naming both; a
 * value out of range names the range. Nothing else parses an option: add one
 * as a row (docs/architecture.md, "Where a change goes").
 *
 * The commands' table (commands.h: each command's handler, flags and
 * synopsis) is the harness's top; this module is given its rows, and knows
 * each command only by its sb_command and its flags. */
#pragma once
#include <stdio.h>

#include "run_opts.h"
#include "spec.h"

/* The commands (a history subcommand is a command of its own), in the order `--help` lists them. */
typedef enum sb_command {
    SB_CMD_RUN,
    SB_CMD_BATCH,
    SB_CMD_COMPARE,
    SB_CMD_MERGE,
    SB_CMD_TUNE,
    SB_CMD_STRESS,
    SB_CMD_HISTORY_ADD,
    SB_CMD_HISTORY_LIST,
    SB_CMD_HISTORY_REGRESSIONS,
    SB_CMD_HISTORY_ANNOTATE,
    SB_CMD_HISTORY_CHECK,
    SB_CMD_BISECT,
    SB_CMD_REPORT,
    SB_CMD_FLIP,
    SB_CMD_TECHNIQUES,
    SB_CMD_COLUMNS,
    SB_CMD_INFO,
    SB_CMD_PATH,
    SB_CMD_CAMERAS,
    SB_CMD_SCORE,
    SB_CMD_HELP,
    SB_CMD_COUNT
} sb_command;

/* What a command does, which decides the options it takes with every other command that does it (an option
 * row's `with`), and how it runs. */
enum {
    SB_CMDF_ANY = 1u << 0,        /* every command */
    SB_CMDF_CONTEXT = 1u << 1,    /* renders on a GL context it times: run, batch, tune, stress */
    SB_CMDF_MEASURE = 1u << 2,    /* measures runs along a path: run, batch, tune */
    SB_CMDF_MATRIX = 1u << 3,     /* runs a matrix in an order it is told: run, batch */
    SB_CMDF_SCENES = 1u << 4,     /* reads scene files: the measuring commands, info, path */
    SB_CMDF_INTERRUPT = 1u << 5,  /* a SIGINT or SIGTERM ends it at a frame boundary, its results kept */
    SB_CMDF_TAIL = 1u << 6,       /* what follows "--" is passed on as it is (bisect's run) */
    SB_CMDF_RESULTS = 1u << 7,    /* writes a results set: --out must be a folder it can write */
};

struct sb_cli;
typedef struct sb_command_def {
    sb_command id;
    const char *name;           /* "run", "history add" */
    const char *usage;          /* the synopsis lines, without "shadowbench " ('\n' between) */
    const char *summary;        /* what it does, one line */
    unsigned flags;             /* SB_CMDF_* */
    int (*handler)(const struct sb_cli *c);   /* returns an exit status of the table (util.h) */
} sb_command_def;

/* Which commands take a row beyond those its `with` flags name: a set of SB_IN(cmd) bits. */
#define SB_IN(cmd) (1u << (cmd))

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

/* How a run option enters a run's identity (its run_id, so its series): a run
 * made with another value is another run. In the hash's order: */
typedef enum sb_identity {
    SB_ID_NONE,
    SB_ID_DIM,          /* always, its ints in the dimensions block at id_slot (its two for WxH) */
    SB_ID_GIVEN,        /* when given: its doubles (ANGLES: both) */
    SB_ID_NAMED,        /* when not its default: its choice's name */
    SB_ID_LIGHT,        /* the light block, its value as a double, when a LIGHT row whose default is 0 is not */
    SB_ID_TEXT,         /* a TEXT row whose default is none, when given: its name and text */
} sb_identity;

/* Every option's parsed value, and which were given. */
#define SB_OPTION_MAX 88
typedef struct sb_cli_opts {
    bool given[SB_OPTION_MAX]; /* by row of sb_options; first, so that no row's
                                  field is at offset 0 (0: none) */
    sb_run_opts run; /* the run options: run, batch, tune, stress (and the scene
                        options of info and path) */
    const char *out, *resume, *shard, *metrics, *pair, *techniques, *history, *since, *series, *workdir, *map;
    const char *pattern, *mask, *renderer, *renderer_params;   /* score */
    int build_type;             /* bisect --build-type: an index of sb_build_types */
    int format; /* --format: an sb_output_format */
    int recent, pairs, nights;
    double noise_floor, threshold, max_err, max_flicker, max_flip, max_mb, budget_ms, time_limit_s, ppd;
    bool dry_run, quiet, verbose, accept, restart, yes, twins, all_pairs;
} sb_cli_opts;

/* A command's own default of a row (a list ends with def NULL). */
typedef struct sb_cmd_default {
    sb_command cmd;
    const char *def;
    const char *help;   /* what --help says of it (NULL: def) */
} sb_cmd_default;

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
    const sb_cmd_default *cmd_defs; /* commands whose default differs (NULL: none) */
    unsigned with;   /* SB_CMDF_*: every command with one of these flags takes it */
    unsigned commands; /* and these (SB_IN(...) bits) */
    bool run_option; /* a run option: a batch file's `defaults` line takes it */
    bool line_option; /* and a batch run line after its specs (a section of the file with its own value) */
    sb_identity identity; /* how it enters a run's identity */
    /* the summary column of its own that carries it into a run's key (runkey.h) and series: NULL for the rest,
       which the run_options column carries (sb_run_options_text); DIM rows are the measurement's dimensions (in the
       run id; size in width and height, the backend in renderer) and LIGHT rows the light column's */
    const char *id_column;
    int id_slot; /* SB_ID_DIM: its place in the dimensions block */
    size_t field, field2; /* offsets in sb_cli_opts (field2: SIZE's height,
                             ANGLES' elevation) */
    size_t given_field; /* a bool set when given (0: none) */
    const char *help;
    bool (*check)(const char *value, const sb_cli_opts *o, sb_err *err); /* what the range cannot say (NULL: none) */
    const char *excludes; /* an option that cannot be given with it (NULL: none) */
    bool of_set; /* part of what a results set is: --resume of a command with another value is refused
                    (sb_cli_set_identity) */
} sb_option;

extern const sb_option sb_options[];
extern const int sb_option_count;

/* Whether command `cmd` takes the row. */
bool sb_option_taken(const sb_option *opt, const sb_command_def *cmd);
/* The defaults of the run options and of the rows cmd takes, each command's own where it has one (cmd NULL: the
 * run options alone, their general defaults); a row without one: zero, or what code works out (--threads: all
 * cores). */
void sb_cli_defaults(sb_cli_opts *o, const sb_command_def *cmd);
/* The run options' general defaults alone. */
void sb_run_opts_defaults(sb_run_opts *o);
/* A row's default for a command (cmd NULL: the general one), as text; NULL when the table holds none. */
const char *sb_option_default(const sb_option *opt, const sb_command_def *cmd);
/* Parses argv[first..argc) for `cmd`: options into o (which holds the
 * defaults), the other words into pos (at most argc of them) in order.
 * `--name value` and `--name=value` are one spelling. false with a one-line
 * error naming the option (and the command when it does not take it). */
bool sb_cli_parse(sb_cli_opts *o, const sb_command_def *cmd, int argc, char **argv, int first, const char **pos,
                  int *npos, sb_err *err);
/* The same for a batch file's `defaults` line (the run options); where:
 * "FILE:LINE", said before each error. */
bool sb_cli_parse_tokens(sb_cli_opts *o, char **tok, int n, const char *where, sb_err *err);
/* Was the option given (by name, on the command line or the defaults line)? */
bool sb_cli_given(const sb_cli_opts *o, const char *name);
/* Copies the run options given in `from` over `to` (the command line beating a
 * batch file's defaults). */
void sb_cli_copy_given(sb_run_opts *to, const sb_cli_opts *from);
/* The same for the line options alone (a batch run line's over the file's). */
void sb_cli_copy_line_options(sb_run_opts *to, const sb_cli_opts *from);
/* "--sun-size, --lamp-radius and --ref-samples": the options a batch run line may carry. */
void sb_line_options_text(char *out, size_t len);
/* What makes a results set what it is, as "set: KEY VALUE" lines into out: the command's words (KEY "word 1", ...)
 * and each row `cmd` takes that is of_set, with its value now (given or default: "--lights lamps", "--frames 60").
 * A set's meta holds them; --resume compares them (sb_set_identity_differs). */
void sb_cli_set_identity(const sb_cli_opts *o, const sb_command_def *cmd, const char *const *words, int nwords,
                         char *out, size_t len);
/* The run options that make a run another run and have no summary column of their own (sb_option.id_column), as
 * "--sun 30,45 --taa on" ("" at their defaults): the run_options column, part of a run's key and series. A new
 * identity row is in it by being a row. */
void sb_run_options_text(const sb_run_opts *o, char *out, size_t len);
/* The first line of `now` whose KEY the set's `was` lines give another value (or lack while now has one): false
 * when they agree; true with "KEY: the set was made with A; this command gives B" in what. Lines of `was` whose KEY
 * `now` lacks are passed over (an option of an older or newer shadowbench). */
bool sb_set_identity_differs(const char *was, const char *now, char *what, size_t len);
/* The row of `name` that `cmd` takes (cmd NULL: any row of that name), or NULL. */
const sb_option *sb_option_find(const char *name, const sb_command_def *cmd);

/* `shadowbench --help` (every command of table[0..SB_CMD_COUNT) and option),
 * or one command's (its synopsis and the options it takes, with its own
 * defaults). */
void sb_cli_help(FILE *f, const sb_command_def *table, const sb_command_def *cmd);
/* An option's value as --help writes it ("--frames N", "--backend egl|osmesa").
 */
void sb_option_synopsis(const sb_option *opt, char *out, size_t len);
/* The default --help states for a row: for cmd (NULL: the general one, with each command's own after it:
 * "60; tune 33, stress 3"); "" when none. */
void sb_option_default_text(const sb_option *opt, const sb_command_def *table, const sb_command_def *cmd, char *out,
                            size_t len);

/* The command line's reference, from the same tables as every --help: the
 * synopsis of every command, every option (its commands, defaults and help)
 * and the exit statuses; docs/cli.md's and the man page's generated parts
 * (`shadowbench help --format markdown|man`, scripts/gen-docs), which the
 * options test holds to these tables. */
typedef enum sb_doc_format { SB_DOC_TEXT, SB_DOC_MARKDOWN, SB_DOC_MAN } sb_doc_format;
void sb_cli_doc(FILE *f, const sb_command_def *table, sb_doc_format fmt);

/* run_id: a hash of the scene's and the path's contents, the technique and
 * its canonical parameters, and the run options that are part of a run's
 * identity (the rows' `identity`). */
void sb_run_id(uint64_t scene_hash, uint64_t path_hash, const sb_run_opts *o, const sb_run_spec *spec, char out[17]);
