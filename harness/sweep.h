/* sweep.h - a covering set of a technique's enumerated parameters: every pair
 * of values of two of them (every value, for a technique with one) appears in
 * at least one spec the technique accepts, in far fewer specs than the full
 * product (pssm's 9 enumerated parameters: 27 specs for 3,456 combinations).
 * `shadowbench techniques --all-pairs SPEC...` prints them; the conformance
 * sweep (tests/integration/test_sweep.c) renders them and holds every frame's
 * error to its family's best.
 *
 * A pair no accepted spec can hold (stable=on with warp=lispsm) is refused:
 * the technique's own check says why, and the sweep lists it. */
#pragma once
#include "spec.h"

typedef struct sb_sweep {
    char (*specs)[1024];        /* the specs: the base spec with the swept values that are not defaults */
    int count;
    char (*refused)[512];       /* "stable=on with warp=lispsm: <the check's reason>" */
    int refused_count;
} sb_sweep;

/* base: one technique spec ("pssm", "sdsm:res=512"); the parameters it gives are held, every other enumerated one
 * is swept. Fails on a spec that does not parse or that lists several values of a parameter. */
bool sb_sweep_pairwise(const char *base, sb_sweep *out, sb_err *err);
void sb_sweep_free(sb_sweep *s);
