/* pssm.c - parallel-split shadow maps (Zhang et al. 2006): the view frustum
 * is split along view depth by the practical scheme
 *   C_i = lambda * n (f/n)^(i/m) + (1 - lambda) * (n + (f - n) i/m)
 * (lambda 0: uniform, 1: logarithmic, 0.5: Zhang's original), one shadow map
 * per slice. Everything else is the shared cascade machinery. */
#include "cascade.h"

static const sb_param_def pssm_params[] = {
    SB_SHADOWMAP_PARAMS,
    SB_CASCADE_PARAMS,
    {"lambda", SB_PARAM_FLOAT, "0.5", 0, 1, NULL, "split scheme: 0 uniform, 1 logarithmic, between: practical"},
};

typedef struct {
    sb_csm csm;
    double lambda;
} pssm_state;

static bool pssm_create(void *state, sb_gpu *gpu, const sb_params *p, sb_err *err) {
    pssm_state *s = state;
    s->lambda = sb_param_num(p, "lambda");
    return sb_csm_create(&s->csm, gpu, p, "pssm", err);
}

static void pssm_frame(void *state, sb_frame *f) {
    pssm_state *s = state;
    double splits[SB_MAX_CASCADES + 1];
    sb_split_distances(s->lambda, s->csm.count, f->cam.znear, f->cam.zfar, splits);
    sb_csm_frame(&s->csm, f, splits);
}

static void pssm_destroy(void *state, sb_gpu *gpu) {
    (void)gpu;
    pssm_state *s = state;
    sb_csm_destroy(&s->csm);
}

const sb_technique sb_technique_pssm = {
    .name = "pssm",
    .summary = "parallel-split / cascaded shadow maps (Zhang et al. 2006)",
    .params = pssm_params,
    .param_count = (int)SB_COUNT(pssm_params),
    .stages = SB_STAGE_BIT(SB_STAGE_CASCADE) | SB_STAGE_BIT(SB_STAGE_FINAL),
    .needs = SB_NEEDS_SUN,
    .state_size = sizeof(pssm_state),
    .create = pssm_create,
    .frame = pssm_frame,
    .destroy = pssm_destroy,
};
