/* evaluate.h - a run's untimed evaluation pass: each evaluated frame's
 * measurements in order (its error against the reference with the
 * technique's check of its input, eval.h; its flicker twin; TAA, taa.h) and
 * its images. The run loop (run.c) calls it once a run and knows none of the
 * measurements: each decides for itself whether it applies (an option off,
 * --lights, a technique with none between the path's frames). */
#pragma once
#include <stdbool.h>

#include "columns.h"
#include "session.h"

/* Whether path frame pf is evaluated (an error figure or its images). */
bool sb_evaluate_wanted(const sb_run_opts *o, int pf);
/* The frames a run's instance renders in its evaluation: per evaluated frame, the frames it replays (at most 2),
 * the frame and its flicker twin, and TAA's display frames with --taa. */
int sb_evaluate_frames(const sb_run_opts *o);
/* Re-renders the evaluated path frames with the evaluation targets bound and reads them back, into recs[pf].err
 * (and evaluated), the images into OUT_DIR/images/: nothing here runs inside a timed frame. seq: the instance's
 * next sequence number (after the timed frames). */
bool sb_evaluate_run(sb_session *s, sb_instance *in, int seq, const char *out_dir, const char *run_id,
                     sb_frame_rec *recs, sb_err *err);
