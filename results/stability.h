/* stability.h - whether a run's timings can be trusted.
 *
 * Three tests, any of which marks a run unstable (stable=no, with the reason):
 *  - the calibration probe (a fixed GPU workload timed just before and just
 *    after the run's timed frames) changed during the run by more than
 *    probe_tol: the device's clocks or load moved under the run;
 *  - the probe before the run departs from the median of the batch's earlier
 *    runs by more than batch_tol (with at least 3 of them): the device was in
 *    another state than for the runs it will be compared with;
 *  - with two or more repetitions of the path, the frame times drifted: the
 *    same path frames in the last repetition against the first, a paired
 *    difference whose mean is beyond both its 95% confidence interval and
 *    drift_tol of the first repetition's mean. (One repetition has no pairs:
 *    the frames of a path differ by design.) */
#pragma once
#include <stdbool.h>
#include <stddef.h>

typedef struct sb_stability_in {
    double calib_before, calib_after;   /* ms (NaN: not measured) */
    const double *batch_calib;          /* earlier runs' calib_before */
    int nbatch;
    const double *frame_ms;             /* the measured frames' gpu_ms, repetitions one after another */
    int n, per_repeat;                  /* frames, and frames a repetition */
    double probe_tol, batch_tol, drift_tol;   /* 0: the defaults below */
} sb_stability_in;

/* The defaults, for a GPU; the run loop widens them on a software rasterizer
 * (0.25, 0.35, 0.20), whose times move with everything else on the CPU. */
#define SB_PROBE_TOL 0.10
#define SB_BATCH_TOL 0.15
#define SB_DRIFT_TOL 0.05

/* True when stable; otherwise false with the reasons ("; "-separated) in why. */
bool sb_stability(const sb_stability_in *in, char *why, size_t len);

/* A test seam: timings for the verdict replayed from a file (SB_REPLAY_TIMINGS
 * names it), so a test of what the verdict starts (a run flagged, run again,
 * recovered or not) decides on given numbers, not on the machine's load.
 * Each line: technique attempt calib_before calib_after ms_1 [ms_2 ...] --
 * `*` for any technique or attempt, every frame of repetition K taking ms_K
 * (the last one for the repetitions beyond), `#` a comment; the first line
 * that matches wins. */
#define SB_REPLAY_REPS 8
typedef struct sb_stability_replay {
    double calib_before, calib_after;
    double rep_ms[SB_REPLAY_REPS];
    int nreps;
} sb_stability_replay;

/* 1: text's line for (technique, attempt) in *out; 0: none matches; -1: a
 * malformed line anywhere in text, why says which ("line N: ..."). */
int sb_stability_replay_find(const char *text, const char *technique, int attempt, sb_stability_replay *out,
                             char *why, size_t len);

/* What to run again when a night ends with unstable runs (batch --rerun-unstable), decided on the night's own
 * figures (a pure function: tests replay them). A night is *disturbed* when more than SB_RERUN_DISTURBED of its
 * runs ended unstable and the calibration probe stayed above the night's calm (its 10th percentile) by more than
 * tol for a stretch of at least 3 runs and a fifth of them: the machine was busy for minutes, not a frame, and
 * running again at once would meet the same load (the batch then waits, at most SB_RERUN_WAIT of the night's time,
 * for the probe to come back to calm, or says the night was disturbed and runs nothing again). Re-runs, cheapest
 * first by their first attempt's wall time, take at most SB_RERUN_SHARE of the night's time (at least
 * SB_RERUN_FLOOR_S: a small night's one or two re-runs are not refused). */
#define SB_RERUN_DISTURBED 0.25
#define SB_RERUN_SHARE 0.25
#define SB_RERUN_FLOOR_S 30.0
#define SB_RERUN_WAIT 0.10

typedef struct sb_rerun_run {
    double wall_s;   /* the run's first attempt (NaN: unknown, counted as the night's mean) */
    bool unstable;
} sb_rerun_run;

typedef struct sb_rerun_plan {
    bool disturbed;
    int unstable, runs;     /* unstable runs of the night's runs */
    int busy_streak;        /* the longest stretch of runs whose probe stood above calm */
    double calm_ms;         /* the night's calm probe: its 10th percentile (NaN: no probe) */
    double budget_s;        /* the time re-runs may take */
    double planned_s;       /* what the chosen re-runs took the first time */
    int chosen;             /* runs to run again (rerun[i] true), within the budget */
} sb_rerun_plan;

/* runs[n]: the night's runs in order; probe[np]: its calibration probes in order (calib_before of each attempt);
 * night_s: the night's time so far; spent_s: re-runs' time already spent; tol: the batch tolerance the verdict
 * used. rerun[n] (caller's) gets the runs to run again. */
void sb_rerun_plan_make(const sb_rerun_run *runs, int n, const double *probe, int np, double night_s, double spent_s,
                        double tol, bool *rerun, sb_rerun_plan *out);
