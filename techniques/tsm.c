/* tsm.c - trapezoidal shadow maps (Martin & Tan 2004): the view frustum's
 * footprint in a uniform light map is enclosed by a trapezoid along the
 * view's centre line, whose shape puts the focus point (`focus` of the way
 * from the near to the far end) on the map's 80% line, and the trapezoid is
 * mapped to the square by a projective transform (sb_light_fit_tsm). `pssm`
 * and `sdsm:splits=cpu` warp each cascade with `warp=tsm`. */
#include "cascade.h"

static const sb_param_def tsm_params[] = {
    SB_SHADOWMAP_PARAMS,
    {"focus", SB_PARAM_FLOAT, "0.3", 0.01, 0.9, NULL, "share of the footprint mapped to 80% of the map"},
};

typedef struct {
    sb_csm csm;
} tsm_state;

static bool tsm_create(void *state, sb_gpu *gpu, const sb_params *p, sb_err *err) {
    tsm_state *s = state;
    if (!sb_csm_create(&s->csm, gpu, p, "tsm", err)) return false;
    if (s->csm.stable) return sb_fail(err, "tsm: stable=on cannot be combined with the warp");
    s->csm.warp = 2;
    return true;
}

static void tsm_frame(void *state, sb_frame *f) {
    tsm_state *s = state;
    double splits[2] = {f->cam.znear, f->cam.zfar};
    sb_csm_frame(&s->csm, f, splits);
}

static void tsm_destroy(void *state, sb_gpu *gpu) {
    (void)gpu;
    tsm_state *s = state;
    sb_csm_destroy(&s->csm);
}

const sb_technique sb_technique_tsm = {
    .name = "tsm",
    .summary = "trapezoidal shadow map over the view (Martin & Tan 2004)",
    .params = tsm_params,
    .param_count = (int)SB_COUNT(tsm_params),
    .stages = SB_STAGE_BIT(SB_STAGE_CASCADE) | SB_STAGE_BIT(SB_STAGE_FINAL),
    .needs = SB_NEEDS_SUN,
    .state_size = sizeof(tsm_state),
    .create = tsm_create,
    .frame = tsm_frame,
    .destroy = tsm_destroy,
};
