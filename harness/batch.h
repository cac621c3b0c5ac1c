/* batch.h - batch files: the nightly matrix of scenes, paths and specs.
 *
 *   # comment
 *   scene NAME FILE [PATH-NAME]     a scene (file or bundled name) and, optionally, its path
 *   path  NAME FILE                 a path (file, bundled name, auto, orbit, FILE.glb#camera=K)
 *   defaults OPTION...              options for every run (--frames 30 --error-every 5 ...)
 *   [@SCENE[,SCENE...]] SPEC... [--sun-size DEG] [--lamp-radius M] [--ref-samples N]
 *                                   run lines: glmark2-style specs; comma lists make a grid;
 *                                   the options give the line's runs a light with a size
 *
 * A scene runs along the path named in its line, else the path with its own
 * name, else `auto`. Every run line applies to every scene unless it starts
 * with @ and a list of scene names. The matrix is scenes (in file order) x
 * run lines (in order) x each line's grid, which fixes the run order and
 * every run_id. Every error names file:line. */
#pragma once
#include "options.h"
#include "run.h"

typedef struct sb_batch_scene {
    char *name, *file, *path_name;
    int line;
    sb_scene scene;             /* loaded (no GL) for run ids and costs */
    sb_path path;
    char path_file[1024];
    char path_label[256];       /* the path's name in the batch, or its file (auto) */
} sb_batch_scene;

typedef struct sb_batch_path {
    char *name, *file;
    int line;
} sb_batch_path;

typedef struct sb_batch_run {
    int index;                  /* position in the full matrix */
    int scene;                  /* index into scenes */
    sb_run_spec spec;
    char run_id[17];
    double cost;                /* estimated work, for balancing shards */
    double sun_size, lamp_radius;   /* the light of the run (its line's, else the file's) */
    int ref_samples;
    const char *lights;         /* its --lights (interned; NULL: none) */
} sb_batch_run;

typedef struct sb_batch {
    char *file, *name;          /* name: file name without directory and extension */
    sb_run_opts opts;           /* defaults applied */
    sb_batch_scene *scenes;
    int nscenes;
    sb_batch_path *paths;
    int npaths;
    sb_batch_run *runs;
    int nruns;
} sb_batch;

/* Parses and validates the whole file (techniques, parameters, options),
 * loads every scene and path (no GL) and expands the matrix. `base` holds
 * the defaults; the run options given in `cli` (NULL: none) beat the file's. */
bool sb_batch_load(sb_batch *b, const char *file, const sb_run_opts *base, const sb_cli_opts *cli, sb_err *err);
void sb_batch_free(sb_batch *b);
/* Parses and validates the text alone (no scene or path is loaded): for
 * fuzzing and quick checks. */
bool sb_batch_check(const char *name, const char *text, sb_err *err);
/* Deterministic, cost-balanced share I of N (1-based): marks runs out of the share. */
void sb_batch_shard(const sb_batch *b, int shard, int nshards, bool *selected);

/* Resume: the rows of sum's file (DIR/summary.csv) for runs ids[i] (NULL:
 * not wanted) that are complete (a row and, unless skipped, the committed
 * per-frame CSV) are kept in sum as they were and marked done. Returns how many. */
/* Whether DIR may be resumed by this command: its meta's "set: " lines against `identity` (the first that differs
 * is refused, naming the option and both values), and every run of its summary among ids[0..n) (NULL entries
 * skipped; n < 0: no summary to hold to, tune's folder of rungs): false with one line to say, before anything is
 * written. */
bool sb_resume_check(const char *dir, const char *identity, const char *const *ids, int n, sb_err *err);
int sb_summary_keep_complete(sb_summary *sum, const char *dir, const char *const *ids, int n, bool *done);

/* `shadowbench batch`: what the command line gave. */
typedef struct sb_batch_cmd {
    const char *file;
    const sb_run_opts *base;            /* defaults with the command line's flags (progress, URIs) */
    const sb_cli_opts *cli;             /* the command line's options: the run options given beat the file's */
    const char *out, *resume, *shard;   /* --out, --resume DIR, --shard I/N (NULL: not given) */
    bool dry_run;
    const char *command_line, *version, *commit;   /* for the meta file */
    const char *identity;               /* the command's "set: " lines (sb_cli_set_identity): --resume's check */
} sb_batch_cmd;

/* Loads, shards and runs the batch (or prints it with dry_run): every scene
 * loaded once, its runs in matrix order, a run that fails recorded and the
 * batch going on; a resumed batch keeps complete runs. Prints the results
 * folder on stdout. Returns the exit status: 0, 1 (a run failed, or a results
 * folder could not be made) or 2 (bad input). */
int sb_batch_main(const sb_batch_cmd *cmd);

/* A matrix of more runs than this prints their count and an estimate of its
 * time and does not start, unless --yes (run, batch; --dry-run lists it). */
#define SB_GRID_CONFIRM 2000
/* false with the count, the frames and the estimate in err when n runs need --yes (o: the command line's). */
bool sb_grid_confirm(int n, const sb_cli_opts *o, sb_err *err);
