/* autobias.h - values for the parameters a spec gives as "auto" (bias,
 * slope, normal offset), calibrated on the frames the run evaluates: of the
 * offsets that keep false shadow (acne) within a threshold of the least any
 * tried offset reaches, the ones with the least err_rate (the least false
 * light, as acne is held), the smaller on a tie. Untimed: it runs before the run's timed
 * frames, through the same evaluation pass as the error figures (eval.h),
 * and the reference answers it casts are the ones the run reuses after. */
#pragma once
#include "session.h"

/* The offsets tried: each auto parameter's default times these (joint, then
 * a descent: one parameter along the ladder, two a rung together). */
#define SB_AUTO_LADDER {0.0, 0.25, 0.5, 1.0, 2.0}
/* Accepted false shadow: at most SB_AUTO_REL times the least, plus SB_AUTO_ABS of the evaluated pixels
 * (acne multiplies false shadow: zero offsets on towers, 0.29 against 0.001). */
#define SB_AUTO_REL 2.0
#define SB_AUTO_ABS 1e-4
/* Frames calibrated on: the run's evaluated frames, at most this many spread along them. */
#define SB_AUTO_FRAMES 4

/* Whether any parameter of the spec is "auto". */
bool sb_autobias_wanted(const sb_run_spec *spec);

/* Fills *out with spec's parameters, every "auto" one replaced by the chosen
 * value; chosen gets them as "bias=0.5:normal=0.125". tried (may be NULL):
 * candidates evaluated. False (err) when an evaluation fails. */
bool sb_autobias_choose(sb_session *s, const sb_run_spec *spec, sb_run_spec *out, char *chosen, size_t len, int *tried,
                        sb_err *err);
