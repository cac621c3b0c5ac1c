/* tsm.c - trapezoidal shadow maps (Martin & Tan 2004): the view frustum's
 * footprint in a uniform light map is enclosed by a trapezoid along the
 * view's centre line, whose shape puts the focus point (`focus` of the way
 * from the near to the far end) on the map's 80% line, and the trapezoid is
 * mapped to the square by a projective transform (sb_light_fit_tsm). `pssm`
 * and `sdsm:splits=cpu` warp each cascade with `warp=tsm`. A row of the
 * cascade machinery with the warp fixed. */
#include "cascade.h"

typedef struct tsm_desc {
    sb_csm_desc csm;
} tsm_desc;

static const sb_param_def tsm_params[] = {
    SB_SHADOWMAP_PARAMS,
    SB_PARAM_F(sb_csm_desc, focus, 0.3, 0.01, 0.9, "share of the footprint mapped to 80% of the map"),
};
static const tsm_desc tsm_defaults = {.csm = {SB_CSM_DESC_DEFAULTS, .warp = SB_WARP_TSM}};

const sb_technique sb_technique_tsm = SB_CSM_TECHNIQUE("tsm", "trapezoidal shadow map over the view (Martin & Tan 2004)",
                                                       tsm_params, tsm_desc, &tsm_defaults, sb_csm_view_splits,
                                                       .stress = "");
