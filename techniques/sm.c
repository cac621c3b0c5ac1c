/* sm.c - one shadow map (Williams 1978) fitted to the whole view frustum's
 * light-space bounds and extended toward the light, so off-screen casters
 * still shadow. It is the cascade machinery with one cascade over
 * [near, far]; bias (constant, slope-scaled, normal offset), filters and
 * stabilisation are the shared ones. */
#include "cascade.h"

static const sb_param_def sm_params[] = {SB_SHADOWMAP_PARAMS};

typedef struct {
    sb_csm csm;
} sm_state;

static bool sm_create(void *state, sb_gpu *gpu, const sb_params *p, sb_err *err) {
    sm_state *s = state;
    return sb_csm_create(&s->csm, gpu, p, "sm", err);
}

static void sm_frame(void *state, sb_frame *f) {
    sm_state *s = state;
    double splits[2] = {f->cam.znear, f->cam.zfar};
    sb_csm_frame(&s->csm, f, splits);
}

static void sm_destroy(void *state, sb_gpu *gpu) {
    (void)gpu;
    sm_state *s = state;
    sb_csm_destroy(&s->csm);
}

const sb_technique sb_technique_sm = {
    .name = "sm",
    .summary = "one shadow map fitted to the view frustum (Williams 1978)",
    .params = sm_params,
    .param_count = (int)SB_COUNT(sm_params),
    .stages = SB_STAGE_BIT(SB_STAGE_CASCADE) | SB_STAGE_BIT(SB_STAGE_FINAL),
    .needs = SB_NEEDS_SUN,
    .state_size = sizeof(sm_state),
    .create = sm_create,
    .frame = sm_frame,
    .destroy = sm_destroy,
};
