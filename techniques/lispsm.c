/* lispsm.c - light space perspective shadow maps (Wimmer, Scherzer &
 * Purgathofer 2004): one map over the view, warped in light space along the
 * view direction's projection with n_opt = (zn + sqrt(zn zf)) / sin(gamma);
 * below `min_angle` between view and light it falls back to the uniform map.
 * The warp itself is in lightfit.c (sb_light_fit_lispsm), so `pssm` and
 * `sdsm:splits=cpu` warp each cascade with `warp=lispsm`. */
#include "cascade.h"

static const sb_param_def lispsm_params[] = {
    SB_SHADOWMAP_PARAMS,
    {"min_angle", SB_PARAM_FLOAT, "5", 0, 90, NULL, "below this angle between view and light: no warp (degrees)"},
};

typedef struct {
    sb_csm csm;
} lispsm_state;

static bool lispsm_create(void *state, sb_gpu *gpu, const sb_params *p, sb_err *err) {
    lispsm_state *s = state;
    if (!sb_csm_create(&s->csm, gpu, p, "lispsm", err)) return false;
    if (s->csm.stable) return sb_fail(err, "lispsm: stable=on cannot be combined with the warp");
    s->csm.warp = 1;
    return true;
}

static void lispsm_frame(void *state, sb_frame *f) {
    lispsm_state *s = state;
    double splits[2] = {f->cam.znear, f->cam.zfar};
    sb_csm_frame(&s->csm, f, splits);
}

static void lispsm_destroy(void *state, sb_gpu *gpu) {
    (void)gpu;
    lispsm_state *s = state;
    sb_csm_destroy(&s->csm);
}

const sb_technique sb_technique_lispsm = {
    .name = "lispsm",
    .summary = "light space perspective shadow map over the view (Wimmer et al. 2004)",
    .params = lispsm_params,
    .param_count = (int)SB_COUNT(lispsm_params),
    .stages = SB_STAGE_BIT(SB_STAGE_CASCADE) | SB_STAGE_BIT(SB_STAGE_FINAL),
    .needs = SB_NEEDS_SUN,
    .state_size = sizeof(lispsm_state),
    .create = lispsm_create,
    .frame = lispsm_frame,
    .destroy = lispsm_destroy,
};
