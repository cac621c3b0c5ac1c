/* run_opts.c - the run options' names and what is worked out from them (run_opts.h). */
#include "run_opts.h"

#include <stdio.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

sb_scene_opts sb_run_scene_opts(const sb_run_opts *o) {
    sb_scene_opts so = {.allow_external_uris = o->allow_external_uris, .blend = o->blend, .pose = o->pose,
                        .pose_time = o->pose_time, .anim_speed = o->anim_speed > 0 ? o->anim_speed : 1};
    if (o->anim && !strcmp(o->anim, "none")) so.anim = SB_ANIM_NONE;
    else if (o->anim && strcmp(o->anim, "all")) so.anim = SB_ANIM_LIST;
    if (so.anim == SB_ANIM_LIST) snprintf(so.anim_clips, sizeof so.anim_clips, "%s", o->anim);
    return so;
}

void sb_run_opts_finish(sb_run_opts *o) {
    if (o->order != SB_ORDER_SHUFFLE || o->seed) return;
    struct timespec ts;
    clock_gettime(CLOCK_REALTIME, &ts);
    uint64_t x = (uint64_t)ts.tv_sec * 1000000007u ^ (uint64_t)ts.tv_nsec ^ (uint64_t)getpid() << 32;
    o->seed = (x % 1000000000u) + 1; /* short enough to type back with --seed */
}

const char *sb_order_name(sb_order o) {
    return o == SB_ORDER_INTERLEAVE ? "interleave" : o == SB_ORDER_SHUFFLE ? "shuffle" : "matrix";
}

const char *sb_submit_name(sb_submit_mode m) { return m == SB_SUBMIT_INDIRECT ? "indirect" : "direct"; }
