/* stage.h - the stages of a frame that are timed, and what a frame counts as
 * it submits: the vocabulary the techniques and the results share. The timer
 * (gl/timing.h) keeps a ring of numbered stage slots and knows none of these
 * names; the summary columns a counter or stage has are results/columns.h's. */
#pragma once
#include <stdbool.h>
#include <stdint.h>

#include "timing.h"

/* A timed stage of a frame: a column <name>_ms and a slot of the timer's ring. A technique declares the stages it
 * times (sb_technique.stages), as it declares its counters: the rows below are the shared machinery's (a camera
 * pass, the cascade and volume passes: every technique that draws one names the same row), a stage only one
 * technique's machinery has stands in its file (raycast.c's rays, lamp.c's clusters), and the run's posing pass
 * is pose.c's. The columns and slots are every declared stage's, each once, in one order (sb_stage_at,
 * technique.h): these rows, then each technique's own in the technique list's order, then the posing pass. */
typedef struct sb_stage_def {
    const char *name;           /* its column: "<name>_ms" */
    bool shadow;                /* a shadow stage: its draws count in shadow_draw_calls, shadow_triangles */
    unsigned flags;             /* its column's SB_USE_* (a default metric of commands), below */
    const char *doc;
} sb_stage_def;

extern const sb_stage_def sb_stage_zpass;      /* camera depth pre-pass */
extern const sb_stage_def sb_stage_minmax;     /* depth reduction */
extern const sb_stage_def sb_stage_cascade;    /* all shadow-map rendering */
extern const sb_stage_def sb_stage_final;      /* camera pass with shadow lookup */
extern const sb_stage_def sb_stage_volumes;    /* stencil shadow volumes and planar casters */
/* The shared rows in their order (the first slots). */
extern const sb_stage_def *const sb_stages_shared[];
extern const int sb_stages_shared_count;

#define SB_STAGE_BIT(slot) (1u << (slot))

#define SB_MAX_CASCADES 8

/* Statistics a series is summarised by (the summary's columns; results/stats). */
enum {
    SB_STAT_MEAN = 1u << 0, SB_STAT_MEDIAN = 1u << 1, SB_STAT_P95 = 1u << 2, SB_STAT_P99 = 1u << 3,
    SB_STAT_STD = 1u << 4, SB_STAT_CI95 = 1u << 5, SB_STAT_MIN = 1u << 6, SB_STAT_MAX = 1u << 7,
    SB_STATS_TIMING = 0x3f,
};
#define SB_STAT_COUNT 8

/* What a counter declares of its use (sb_counter_def.flags; bit 0 is a column's own, results/columns.h's). The SB_USE_ bits make it a default metric of a command: which ones `compare`, `compare --pair`,
 * `history regressions` and the report's trend charts use when no --metric says. */
enum {
    SB_USE_COMPARE = 1u << 1,       /* compare BASE NEW */
    SB_USE_PAIR = 1u << 2,          /* compare --pair, the report's pair tables */
    SB_USE_HISTORY = 1u << 3,       /* history regressions */
    SB_USE_REPORT = 1u << 4,        /* the report's trend charts */
    SB_LOWER_WORSE = 1u << 5,       /* a metric that gets worse as it falls (default: as it rises) */
    SB_USE_NIGHT = 1u << 6,         /* the report's night table (a series: its centre statistic) */
};

/* How a technique's own counter takes a second count in one frame (another cascade's, another light's). */
typedef enum sb_counter_merge { SB_MERGE_SUM, SB_MERGE_MAX } sb_counter_merge;

/* A counter a technique declares of its own (sb_technique.counters, in the technique's file): a per-frame column
 * of its name, empty in the rows of every technique that does not declare it, summarised by `stats`. The column
 * table (results/columns.c), the frame record and the run loop know it only by this row; two techniques that
 * count the same thing share one row (the cascade machinery's, sb_csm_counters). */
typedef struct sb_counter_def {
    const char *name;
    const char *unit;           /* "count": a whole number; else a number ("share") */
    sb_counter_merge merge;
    unsigned stats;             /* SB_STAT_* of the summary (0: the frame column alone) */
    unsigned flags;             /* SB_USE_*, SB_LOWER_WORSE */
    bool moving;                /* counted only where the scene's clips play (empty in a still scene's rows) */
    const char *doc;
} sb_counter_def;

#define SB_MAX_OWN_COUNTERS 8

/* What a frame submitted, counted as it happens (technique-side counters). */
typedef struct sb_counters {
    uint32_t draw_calls, shadow_draw_calls;         /* draws (a mesh range and its instances); shadow: cascade and
                                                       volumes stages */
    uint32_t stage_draw_calls[SB_TIMER_STAGES];      /* by stage slot (sb_stage_slot) */
    uint32_t api_calls, shadow_api_calls;           /* GL draw calls issued: with --submit indirect one issues many draws */
    uint64_t triangles, shadow_triangles;           /* triangles x instances submitted */
    int cascades_rendered, cascades_skipped;
    int cascades_cached;            /* cache=on: active cascades kept from an earlier frame, not drawn again */
    int warp_fallbacks;                             /* warped maps (psm, lispsm, tsm) that used the uniform fit */
    bool moving;                                    /* the scene's clips play: the motion counters below hold */
    int casters_moved;                              /* draws whose box changed since the technique's last frame */
    int split_count;                                /* cascades whose far split is known this frame */
    double splits[SB_MAX_CASCADES];                 /* view-space far distance of each cascade */
    /* the frame's technique's own counters (its sb_technique.counters; the harness sets the table before the
       frame) and their values, in the table's order */
    const sb_counter_def *own_defs;
    int own_count;
    double own[SB_MAX_OWN_COUNTERS];
} sb_counters;

/* The place of own counter `def` among the frame's technique's (-1: it does not declare it). */
static inline int sb_counter_at(const sb_counters *c, const sb_counter_def *def) {
    for (int k = 0; k < c->own_count; k++)
        if (&c->own_defs[k] == def) return k;
    return -1;
}
/* Counts v into the own counter `def` as its row merges; a row the frame's technique does not declare is not
 * counted. */
static inline void sb_count(sb_counters *c, const sb_counter_def *def, double v) {
    int k = sb_counter_at(c, def);
    if (k < 0) return;
    if (def->merge == SB_MERGE_SUM) c->own[k] += v;
    else if (v > c->own[k]) c->own[k] = v;
}
/* The value of own counter `def` in a frame's counters; false where the frame's technique does not declare it. */
static inline bool sb_counted(const sb_counters *c, const sb_counter_def *def, double *v) {
    int k = sb_counter_at(c, def);
    if (k >= 0) *v = c->own[k];
    return k >= 0;
}
