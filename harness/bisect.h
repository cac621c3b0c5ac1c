/* bisect.h - `shadowbench bisect`: the first commit between GOOD and BAD that
 * changes one metric of one run.
 *
 * In a scratch worktree of the repository it runs in (kept, with every
 * binary it built, under the git directory's shadowbench-bisect/), each
 * candidate commit is checked out and built incrementally in one release
 * build folder; a commit that does not build is skipped and named, as `git
 * bisect skip` does. The run given after `--` is rendered by the candidate's
 * binary and by GOOD's. A deterministic metric (err_rate, draw_calls: any
 * metric not in ms) is judged exactly: a candidate is bad when its figure
 * differs from GOOD's. A timing is judged by the paired difference of
 * interleaved runs (candidate and GOOD alternately first, --repeat pairs):
 * BAD must differ from GOOD by more than the difference's 95% CI and by
 * --threshold percent, and a candidate is bad when its difference is nearer
 * BAD's than none. Exit 0: found (printed, with every step); 1: GOOD and BAD
 * do not differ beyond the noise; 2: bad input (not a repository, unknown
 * commits, GOOD not an ancestor of BAD, GOOD or BAD not building, a run that
 * is not one run of one technique). */
#pragma once
#include <stdbool.h>

#include "options.h"

typedef struct sb_bisect_cmd {
    const char *good, *bad;     /* commits (any git revision); the --history form fills them */
    char **run_argv;            /* after "--": run SCENE PATH SPEC [run options] (the --history form: options only) */
    int run_argc;
    const sb_command_def *run_cmd;   /* the run command's row: its options are checked before anything is built */
    const char *metric;         /* NULL: gpu_ms */
    int repeat;                 /* timings: paired runs a step (0: 5) */
    double threshold_pct;       /* timings: the least change that counts (0: 5) */
    const char *workdir;        /* NULL: <git common dir>/shadowbench-bisect */
    const char *build_type;     /* meson's buildtype of the scratch builds (NULL: release) */
    const char *history, *series; /* --history FILE --series TEXT: the newest regression of that series' metric */
} sb_bisect_cmd;

int sb_bisect_main(const sb_bisect_cmd *cmd);

/* Whether commit `ancestor` is `rev` or an ancestor of it, in the git
 * repository of the current folder (false when there is none). */
bool sb_git_is_ancestor(const char *ancestor, const char *rev);
