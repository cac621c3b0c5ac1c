/* spec.h - glmark2-style technique specs: "sm:res=1024,2048:filter=pcf3".
 * A comma list makes a grid: the spec expands to the cartesian product. */
#pragma once
#include "technique.h"

/* The largest parameter struct a technique may have (sb_technique.desc_size). */
#define SB_DESC_MAX 512

/* One run's technique and parameters: the values as text and numbers, and
 * the technique's parameter struct bound from them once (made where the
 * spec is made, bound again only when a value changes: sb_spec_bind). */
typedef struct sb_run_spec {
    const sb_technique *tech;
    sb_params params;
    _Alignas(16) unsigned char desc[SB_DESC_MAX];
} sb_run_spec;

/* The technique's defaults, bound. */
void sb_spec_defaults(sb_run_spec *rs, const sb_technique *t);
/* Binds desc from params again (after a value changed: a calibrated auto value, the light's size). */
void sb_spec_bind(sb_run_spec *rs);
/* The shadow storage the spec holds (sb_technique.shadow_bytes; 0 when it keeps none), without a GL. */
double sb_spec_shadow_bytes(const sb_run_spec *rs);

/* The most runs one spec's grid may make (a grid past it is a typo, and its specs would not fit in memory). */
#define SB_SPEC_MAX_RUNS 100000

/* Expands one spec into runs appended to *runs (realloc'd). Validates names,
 * types and ranges against the technique's table. `where` prefixes messages
 * (e.g. "nightly.bench:12"); may be NULL. */
bool sb_spec_expand(const char *spec, const char *where, sb_run_spec **runs, int *count, sb_err *err);
/* A run with a sun of a size (--sun-size): a technique's own sun_size (PCSS's
 * penumbra) follows it unless the spec gave one, so soft shadows are
 * compared like for like. 0 leaves the spec as it is. */
void sb_spec_light_size(sb_run_spec *rs, double sun_size_deg);
