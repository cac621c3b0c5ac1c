/* stage.c - the stages the shared machinery times (stage.h): every technique that draws one of these passes
 * declares the same row. */
#include "stage.h"

#define SHARED_USES (SB_USE_COMPARE | SB_USE_HISTORY | SB_USE_REPORT | SB_USE_NIGHT)

const sb_stage_def sb_stage_zpass = {.name = "zpass", .doc = "camera depth pre-pass"};
const sb_stage_def sb_stage_minmax = {.name = "minmax", .doc = "depth reduction"};
const sb_stage_def sb_stage_cascade = {.name = "cascade", .shadow = true, .flags = SHARED_USES,
                                       .doc = "all shadow-map rendering"};
const sb_stage_def sb_stage_final = {.name = "final", .flags = SHARED_USES, .doc = "camera pass with the shadow lookup"};
const sb_stage_def sb_stage_volumes = {.name = "volumes", .shadow = true,
                                       .doc = "stencil shadow volumes (and planar casters)"};

const sb_stage_def *const sb_stages_shared[] = {&sb_stage_zpass, &sb_stage_minmax, &sb_stage_cascade, &sb_stage_final,
                                                &sb_stage_volumes};
const int sb_stages_shared_count = (int)(sizeof sb_stages_shared / sizeof sb_stages_shared[0]);
