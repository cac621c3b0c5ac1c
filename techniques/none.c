/* none.c - no shadows: the baseline every other cost is measured against. */
#include "render.h"
#include "shaders.h"

typedef struct {
    sb_final_prog fp;
} none_state;

static bool none_create(void *state, const sb_run_ctx *rc, const void *desc, sb_err *err) {
    (void)rc;
    (void)desc;
    none_state *s = state;
    return sb_final_prog_create(&s->fp, rc->gpu, "none", sb_shader_vis_none_glsl, NULL, err);
}

static void none_frame(void *state, sb_frame *f) {
    none_state *s = state;
    sb_stage_begin(f, &sb_stage_final);
    glUseProgram(s->fp.prog);
    sb_final_pass(f, &s->fp, false);
    sb_stage_end(f, &sb_stage_final);
}

static void none_destroy(void *state) {
    none_state *s = state;
    sb_final_prog_free(&s->fp);
}

const sb_technique sb_technique_none = {
    .name = "none",
    .summary = "no shadows; the baseline cost of the camera pass",
    SB_STAGES(&sb_stage_final),
    .traits = SB_TRAIT_NO_SHADOWS,
    .stress = "",
    .state_size = sizeof(none_state),
    .create = none_create,
    .frame = none_frame,
    .destroy = none_destroy,
};
