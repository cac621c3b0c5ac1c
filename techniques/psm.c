/* psm.c - perspective shadow maps (Stamminger & Drettakis 2002) with the
 * Novosibirsk paper's fixes. The map is rendered in the camera's
 * post-projective space, where near receivers are large, so they get more
 * texels; the sun becomes a point light there. The fit (sb_light_fit_psm in
 * lightfit.c) does the four fixes:
 *   (a) casters behind the camera with the sun behind it: an inverse light
 *       projection, z_ndc = a / z' (near -a, far a), instead of moving the
 *       camera back (`behind=shift`, the original fix, for comparison;
 *       `behind=naive`, an ordinary near plane, loses those casters);
 *   (b) the light frustum fitted to the receivers, not to the unit cube;
 *   (c) `cube=on`: six 90-degree faces around the light, so a light along the
 *       view needs no impossible field of view (faces without receivers skip);
 *   (d) bias in world space scaled by the local texel size (vis_csm.glsl,
 *       for every warped map).
 * It renders through the shared cascade machinery: one map, or one layer per
 * cube face (selected by map, `layered=` as for cascades). */
#include "cascade.h"

typedef struct psm_desc {
    sb_csm_desc csm;
    int behind, cube;
    double max_fov;
} psm_desc;

static const sb_param_def psm_params[] = {
    SB_SHADOWMAP_PARAMS,
    SB_PARAM_E(psm_desc, behind, inverse, "inverse|shift|naive",
               "casters behind the camera: inverse projection, virtual camera shift, or none (clipped)"),
    SB_PARAM_E(psm_desc, cube, off, "off|on", "one map, or a cube of maps around the light in PPS"),
    SB_PARAM_E(sb_csm_desc, layered, off, "off|gs|vs|on", "cube=on: per-face draws, or layered as for cascades"),
    SB_PARAM_F(psm_desc, max_fov, 80, 30, 89,
               "one map: widest half-angle of the light frustum before the uniform map is used (degrees)"),
};
static const psm_desc psm_defaults = {.csm = {SB_CSM_DESC_DEFAULTS}};

typedef struct {
    sb_csm csm;
    sb_psm_desc fit;
} psm_state;

static bool psm_check(const void *desc, sb_err *err) {
    const psm_desc *d = desc;
    if (d->csm.filter == SB_FILTER_PCSS)
        return sb_fail(err, "filter=pcss needs depth linear in distance; a PSM's is not (use pcf3, pcf5, poisson16)");
    if (d->csm.stable) return sb_fail(err, "stable=on cannot be combined with the warp");
    if (!d->cube && d->csm.layered != SB_LAYERED_OFF) return sb_fail(err, "layered= needs cube=on (one map otherwise)");
    return true;
}

/* The map count and selection follow from cube=: one map, or six faces selected by map. */
static sb_csm_desc maps_of(const psm_desc *d) {
    sb_csm_desc m = d->csm;
    m.cascades = d->cube ? 6 : 1;
    m.select = d->cube ? 1 : 0;
    m.perspective = 1;
    return m;
}

static double psm_shadow_bytes(const sb_technique *t, const void *desc) {
    (void)t;
    sb_csm_desc m = maps_of(desc);
    return sb_csm_bytes(&m);
}

static bool psm_supported(const sb_run_ctx *rc, const void *desc, sb_err *why) {
    sb_csm_desc m = maps_of(desc);
    return sb_csm_supported(rc->gpu, &m, "psm", why);
}

static bool psm_create(void *state, const sb_run_ctx *rc, const void *desc, sb_err *err) {
    psm_state *s = state;
    const psm_desc *d = desc;
    sb_csm_desc m = maps_of(d);
    if (!sb_csm_create(&s->csm, rc->gpu, &m, "psm", err)) return false;
    s->fit = (sb_psm_desc){.behind = d->behind, .cube = d->cube, .res = d->csm.res, .max_half_fov_deg = d->max_fov};
    return true;
}

static void psm_frame(void *state, sb_frame *f) {
    psm_state *s = state;
    sb_csm *c = &s->csm;
    sb_psm_info info;
    sb_light_fit fits[6];
    int n = sb_light_fit_psm(f->gpu->scene, f->gpu->sun, &f->cam, &s->fit, fits, &info);
    double zn[6], zf[6];
    for (int k = 0; k < n; k++) {
        c->fit[k] = fits[k];
        c->active[k] = !fits[k].empty;
        zn[k] = f->cam.znear;
        zf[k] = f->cam.zfar;
    }
    /* the naive ordering clips what the inverse projection would clamp */
    c->no_clamp = s->fit.behind == SB_PSM_NAIVE && info.inverted;
    f->counters.warp_fallbacks = info.fallback;
    f->counters.split_count = 1;
    f->counters.splits[0] = info.zfar;
    sb_csm_upload(c, zn, zf);
    sb_csm_draw(c, f);
}

const sb_technique sb_technique_psm = {
    .name = "psm",
    .stress = ";cube=on",   /* the stability battery's settings */
    .summary = "perspective shadow map in post-projective space, Novosibirsk fixes (Stamminger & Drettakis 2002)",
    .params = psm_params,
    .param_count = (int)SB_COUNT(psm_params),
    .desc_size = sizeof(psm_desc),
    .desc_defaults = &psm_defaults,
    SB_STAGES(&sb_stage_cascade, &sb_stage_final),
    .needs = SB_NEEDS_SUN,
    .state_size = sizeof(psm_state),
    .check = psm_check,
    .supported = psm_supported,
    .shadow_bytes = psm_shadow_bytes,
    .create = psm_create,
    .frame = psm_frame,
    SB_CSM_COUNTERS,
    .destroy = sb_csm_technique_destroy,   /* the state starts with its sb_csm */
};
