/* spec.h - glmark2-style technique specs: "sm:res=1024,2048:filter=pcf3".
 * A comma list makes a grid: the spec expands to the cartesian product. */
#pragma once
#include "technique.h"

typedef struct sb_run_spec {
    const sb_technique *tech;
    sb_params params;
} sb_run_spec;

/* Expands one spec into runs appended to *runs (realloc'd). Validates names,
 * types and ranges against the technique's table. `where` prefixes messages
 * (e.g. "nightly.bench:12"); may be NULL. */
bool sb_spec_expand(const char *spec, const char *where, sb_run_spec **runs, int *count, sb_err *err);
