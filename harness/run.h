/* run.h - the run loop: one run = scene x path x technique x parameters.
 *
 * Each run creates its technique (session.h), renders warm-up frames
 * (discarded) and then the path's N frames, timing every stage, evaluates
 * the frames it scores (eval.h), and writes one per-frame CSV and one summary
 * row. A run that fails is recorded and the next one goes on. */
#pragma once
#include "session.h"

/* A run in passes of the path, for runs whose repetitions interleave:
 * begin (the run skipped when it cannot apply), then passes while it wants
 * more (each pass warms up, renders the path once and measures it), then end
 * (the evaluation pass, the CSV committed, the summary row). keep_instance:
 * one technique instance for every repetition (warmed up once); otherwise one
 * a pass, each warmed up. */
typedef struct sb_run sb_run;
sb_run *sb_run_begin(sb_session *s, const sb_run_spec *spec, const char *out_dir, sb_summary *sum, int run_index,
                     bool keep_instance);
bool sb_run_wants_more(const sb_run *r);
bool sb_run_pass(sb_run *r, int index, int total);
bool sb_run_end(sb_run *r);
/* Runs one spec; writes DIR/<run_id>.csv and a summary row. run_index is its
 * place in the matrix; progress shows "run i of n". Returns false if it failed. */
bool sb_run_one(sb_session *s, const sb_run_spec *spec, const char *out_dir, sb_summary *sum, int run_index, int i,
                int n);
/* The runs of one scene (specs[k], run_index[k]) in the order of --order,
 * the summary flushed after each run ends; progress counts from `first` of
 * `total`. Returns the number of runs that failed. */
int sb_run_group(sb_session *s, const sb_run_spec *const *specs, const int *run_index, int n, const char *out_dir,
                 sb_summary *sum, int first, int total);
/* Runs again runs that ended unstable (--rerun-unstable): each one's frames so far kept as
 * DIR/<run_id>.attempt-K.csv (K: the attempt before), its row taken out of the summary, and the run begun anew
 * as attempt `attempt` (2 and on), its figures those of the summary now. The summary counts the runs run again
 * (at attempt 2) and those stable now (recovered). */
void sb_run_again(sb_session *s, const sb_run_spec *const *specs, const int *run_index, int n, const char *out_dir,
                  sb_summary *sum, int attempt);
/* One attempt's re-runs (--rerun-unstable), for `run` and `batch` alike: the unstable runs' ids (n of them) and
 * which of them go again (pick[u]). */
typedef struct sb_rerun_round {
    char **ids;
    bool *pick;
    int n;
} sb_rerun_round;
/* Plans attempt `attempt`'s re-runs on the summary's figures so far (sb_rerun_plan_make: at most a stated share of
 * the night's night_s seconds, spent_s of it spent on re-runs already; nprobe: the first attempts' calibration
 * probes), a disturbed night (attempt 2) first waiting for a calm machine within its budget; the decisions said in
 * the log. False: nothing is to run again. Free the round with sb_rerun_round_free either way. */
bool sb_rerun_round_plan(sb_session *s, sb_summary *sum, int nprobe, double night_s, double spent_s, int attempt,
                         sb_rerun_round *out);
void sb_rerun_round_free(sb_rerun_round *r);
/* Says what a run or batch command's summary holds (counts and folder) and,
 * after a SIGINT/SIGTERM, where the completed rows are and how to resume
 * (even with --quiet); returns the command's exit status: 128 + the signal
 * when interrupted, 1 when a run failed, else 0. */
int sb_summary_conclude(const sb_summary *sum, const char *dir, const char *resume_command);
/* The run id of a spec in this session. */
void sb_session_run_id(const sb_session *s, const sb_run_spec *spec, char out[17]);
