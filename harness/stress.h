/* stress.h - the numerical-stability battery (`shadowbench stress`). */
#pragma once
#include <stdio.h>

#include "run.h"

/* Builds every case (glTF scenes and paths written to a temporary folder and
 * read back through the normal loaders), runs every technique on each, and
 * prints one row per technique x case. Returns the number of failures, or -1
 * if the battery itself could not run. `only` (may be NULL) limits the cases
 * to names containing it (and the base case, the bound of the translated
 * ones); specs (nspecs > 0) replace the battery's technique list. */
int sb_stress_run(const sb_run_opts *opts, const char *only, const char *const *specs, int nspecs, FILE *out,
                  sb_err *err);
