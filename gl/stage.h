/* stage.h - the stages of a frame that are timed, and what a frame counts as
 * it submits: the vocabulary the timer, the techniques and the results share. */
#pragma once
#include <stdbool.h>
#include <stdint.h>

typedef enum sb_stage {
    SB_STAGE_ZPASS,     /* camera depth pre-pass */
    SB_STAGE_MINMAX,    /* depth reduction */
    SB_STAGE_CASCADE,   /* all shadow-map rendering */
    SB_STAGE_FINAL,     /* camera pass with shadow lookup */
    SB_STAGE_VOLUMES,   /* stencil shadow volumes */
    SB_STAGE_RAYS,      /* CPU ray casting */
    SB_STAGE_COUNT
} sb_stage;

#define SB_STAGE_BIT(s) (1u << (s))
extern const char *const sb_stage_names[SB_STAGE_COUNT];

#define SB_MAX_CASCADES 8

/* What a frame submitted, counted as it happens (technique-side counters). */
typedef struct sb_counters {
    uint32_t draw_calls, shadow_draw_calls;         /* draws (a mesh range and its instances); shadow: cascade and
                                                       volumes stages */
    uint32_t stage_draw_calls[SB_STAGE_COUNT];
    uint32_t api_calls, shadow_api_calls;           /* GL draw calls issued: with --submit indirect one issues many draws */
    uint64_t triangles, shadow_triangles;           /* triangles x instances submitted */
    int cascades_rendered, cascades_skipped;
    int cascades_cached;            /* cache=on: active cascades kept from an earlier frame, not drawn again */
    bool paged;                                     /* a virtual shadow map: the page counters below are its */
    int pages_needed, pages_rendered, pages_cached; /* pages the pixels needed; drawn this frame; kept from before */
    int pool_overflow;                              /* needed pages the pool had no slot for */
    int pages_stand_in;                             /* coarser pages drawn or kept in place of those (in rendered,
                                                       cached): rendered + cached - stand_in + overflow = needed */
    int warp_fallbacks;                             /* warped maps (psm, lispsm, tsm) that used the uniform fit */
    bool moving;                                    /* the scene's clips play: the motion counters below hold */
    int casters_moved;                              /* draws whose box changed since the technique's last frame */
    int cascades_invalidated;                       /* cache=on: kept maps drawn again for a moved caster */
    int pages_invalidated;                          /* virtual cache=on: kept pages dropped for a moved caster */
    int pages_dynamic;                              /* virtual split=on: pages the moving casters were drawn over */
    bool atlas;                                     /* a shadow atlas of lamps: the counters below are its */
    int lights_shadowed;                            /* lamps with tiles this frame */
    int lights_dropped;                             /* lamps in view left unshadowed: max_lights, or no room */
    int lights_downscaled;                          /* lamps whose tiles are smaller than they asked for (no room) */
    double atlas_occupancy;                         /* share of the atlas its tiles cover */
    int split_count;                                /* cascades whose far split is known this frame */
    double splits[SB_MAX_CASCADES];                 /* view-space far distance of each cascade */
} sb_counters;
