/* sm.c - one shadow map (Williams 1978) fitted to the whole view frustum's
 * light-space bounds and extended toward the light, so off-screen casters
 * still shadow. A row of the cascade machinery: one map over [near, far];
 * bias (constant, slope-scaled, normal offset), filters and stabilisation are
 * the shared ones. */
#include "cascade.h"

typedef struct sm_desc {
    sb_csm_desc csm;
} sm_desc;

static const sb_param_def sm_params[] = {SB_SHADOWMAP_PARAMS};
static const sm_desc sm_defaults = {.csm = {SB_CSM_DESC_DEFAULTS}};

const sb_technique sb_technique_sm = SB_CSM_TECHNIQUE("sm", "one shadow map fitted to the view frustum (Williams 1978)",
                                                      sm_params, sm_desc, &sm_defaults, sb_csm_view_splits,
                                                      .stress = "");
