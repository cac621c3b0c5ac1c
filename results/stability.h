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
