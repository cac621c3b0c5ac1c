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

static const sb_param_def psm_params[] = {
    SB_SHADOWMAP_PARAMS,
    {"behind", SB_PARAM_ENUM, "inverse", 0, 0, "inverse|shift|naive",
     "casters behind the camera: inverse projection, virtual camera shift, or none (clipped)"},
    {"cube", SB_PARAM_ENUM, "off", 0, 0, "off|on", "one map, or a cube of maps around the light in PPS"},
    {"layered", SB_PARAM_ENUM, "off", 0, 0, "off|gs|vs|on", "cube=on: per-face draws, or layered as for cascades"},
    {"max_fov", SB_PARAM_FLOAT, "80", 30, 89, NULL,
     "one map: widest half-angle of the light frustum before the uniform map is used (degrees)"},
};

typedef struct {
    sb_csm csm;
    sb_psm_desc desc;
} psm_state;

static bool psm_create(void *state, sb_gpu *gpu, const sb_params *p, sb_err *err) {
    psm_state *s = state;
    bool cube = sb_param_choice(p, "cube") == 1;
    if (sb_param_choice(p, "filter") == 5)
        return sb_fail(err, "psm: filter=pcss needs depth linear in distance; a PSM's is not (use pcf3, pcf5, poisson16)");
    if (sb_param_choice(p, "stable") == 1) return sb_fail(err, "psm: stable=on cannot be combined with the warp");
    if (!cube && sb_param_choice(p, "layered") != 0) return sb_fail(err, "psm: layered= needs cube=on (one map otherwise)");
    sb_csm_desc d = {.maps = cube ? 6 : 1, .select_map = cube};
    if (!sb_csm_create_desc(&s->csm, gpu, p, "psm", &d, err)) return false;
    s->desc = (sb_psm_desc){.behind = sb_param_choice(p, "behind"),
                            .cube = cube,
                            .res = s->csm.res,
                            .max_half_fov_deg = sb_param_num(p, "max_fov")};
    return true;
}

static void psm_frame(void *state, sb_frame *f) {
    psm_state *s = state;
    sb_csm *c = &s->csm;
    sb_psm_info info;
    sb_light_fit fits[6];
    int n = sb_light_fit_psm(f->gpu->scene, f->gpu->sun, &f->cam, &s->desc, fits, &info);
    double zn[6], zf[6];
    for (int k = 0; k < n; k++) {
        c->fit[k] = fits[k];
        c->active[k] = !fits[k].empty;
        zn[k] = f->cam.znear;
        zf[k] = f->cam.zfar;
    }
    /* the naive ordering clips what the inverse projection would clamp */
    c->no_clamp = s->desc.behind == SB_PSM_NAIVE && info.inverted;
    f->counters.warp_fallbacks = info.fallback;
    f->counters.split_count = 1;
    f->counters.splits[0] = info.zfar;
    sb_csm_upload(c, zn, zf);
    sb_csm_draw(c, f);
}

static void psm_destroy(void *state, sb_gpu *gpu) {
    (void)gpu;
    psm_state *s = state;
    sb_csm_destroy(&s->csm);
}

const sb_technique sb_technique_psm = {
    .name = "psm",
    .summary = "perspective shadow map in post-projective space, Novosibirsk fixes (Stamminger & Drettakis 2002)",
    .params = psm_params,
    .param_count = (int)SB_COUNT(psm_params),
    .stages = SB_STAGE_BIT(SB_STAGE_CASCADE) | SB_STAGE_BIT(SB_STAGE_FINAL),
    .needs = SB_NEEDS_SUN,
    .state_size = sizeof(psm_state),
    .create = psm_create,
    .frame = psm_frame,
    .destroy = psm_destroy,
};
