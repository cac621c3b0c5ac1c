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
/* A run with a sun of a size (--sun-size): a technique's own sun_size (PCSS's
 * penumbra) follows it unless the spec gave one, so soft shadows are
 * compared like for like. 0 leaves the spec as it is. */
void sb_spec_light_size(sb_run_spec *rs, double sun_size_deg);
