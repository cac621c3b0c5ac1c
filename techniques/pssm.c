/* pssm.c - parallel-split shadow maps (Zhang et al. 2006): the view frustum
 * is split along view depth by the practical scheme
 *   C_i = lambda * n (f/n)^(i/m) + (1 - lambda) * (n + (f - n) i/m)
 * (lambda 0: uniform, 1: logarithmic, 0.5: Zhang's original), one shadow map
 * per slice. Everything else is the shared cascade machinery. */
#include "cascade.h"

typedef struct pssm_desc {
    sb_csm_desc csm;
    double lambda;
} pssm_desc;

static const sb_param_def pssm_params[] = {
    SB_SHADOWMAP_PARAMS,
    SB_CASCADE_PARAMS,
    SB_PARAM_F(pssm_desc, lambda, 0.5, 0, 1, "split scheme: 0 uniform, 1 logarithmic, between: practical",
               .tune = "0.5,0.75"),
};
static const pssm_desc pssm_defaults = {.csm = {SB_CSM_DESC_DEFAULTS}};

static void pssm_splits(const void *desc, const sb_frame *f, int count, double near, double far, double *out) {
    const pssm_desc *d = desc;
    (void)f;
    sb_split_distances(d->lambda, count, near, far, out);
}

const sb_technique sb_technique_pssm = SB_CSM_TECHNIQUE("pssm", "parallel-split / cascaded shadow maps (Zhang et al. 2006)",
                                                        pssm_params, pssm_desc, &pssm_defaults, pssm_splits,
                                                        .stress = ";stable=on;format=msm");
