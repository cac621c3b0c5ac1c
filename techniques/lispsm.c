/* lispsm.c - light space perspective shadow maps (Wimmer, Scherzer &
 * Purgathofer 2004): one map over the view, warped in light space along the
 * view direction's projection with n_opt = (zn + sqrt(zn zf)) / sin(gamma);
 * below `min_angle` between view and light it falls back to the uniform map.
 * The warp itself is in lightfit.c (sb_light_fit_lispsm), so `pssm` and
 * `sdsm:splits=cpu` warp each cascade with `warp=lispsm`. A row of the
 * cascade machinery with the warp fixed. */
#include "cascade.h"

typedef struct lispsm_desc {
    sb_csm_desc csm;
} lispsm_desc;

static const sb_param_def lispsm_params[] = {
    SB_SHADOWMAP_PARAMS,
    SB_PARAM_F(sb_csm_desc, min_angle, 5, 0, 90, "below this angle between view and light: no warp (degrees)"),
};
static const lispsm_desc lispsm_defaults = {.csm = {SB_CSM_DESC_DEFAULTS, .warp = SB_WARP_LISPSM}};

const sb_technique sb_technique_lispsm =
    SB_CSM_TECHNIQUE("lispsm", "light space perspective shadow map over the view (Wimmer et al. 2004)", lispsm_params,
                     lispsm_desc, &lispsm_defaults, sb_csm_view_splits, .stress = "");
