/* cascade.h - the shared cascade machinery, written once: split schemes,
 * per-slice light fits (lightfit.c), stabilisation, receiver checks, exact
 * caster culling per cascade over the BVH, layered or per-cascade submission
 * into one 2D-array shadow map, and the final-pass lookup (vis_csm.glsl).
 *
 * Everything is configured by one descriptor, sb_csm_desc, filled once from a
 * technique's parameter table (its rows bind to the fields below). A
 * technique whose frame is "splits, then fit, cull, render and shade" is a row:
 * SB_CSM_TECHNIQUE with its split callback (sm, pssm, lispsm, tsm). psm and
 * sdsm compute their fits elsewhere and use the pieces. */
#pragma once
#include "lightfit.h"

enum { SB_WARP_NONE, SB_WARP_LISPSM, SB_WARP_TSM };
/* What a cascade's window is fitted to (fit=): the slice of the view (clipped to the scene's box), or the part of
 * the slice where receivers are (the draws' boxes inside it), as Filament's and Unreal's fits are; auto (pssm's
 * and sdsm's default): the receivers unless a sphere (stable=on) or a trapezoid (warp=tsm) is the fit. The
 * techniques without the parameter (sm, lispsm, tsm) keep 0, the slice. */
enum { SB_FIT_SLICE, SB_FIT_RECEIVERS, SB_FIT_AUTO };
/* What a shadow map stores (format=): depth, or the moments of a filtered format. */
enum { SB_MAP_DEPTH, SB_MAP_VSM, SB_MAP_ESM, SB_MAP_MSM };
enum { SB_FILTER_NONE, SB_FILTER_HW, SB_FILTER_PCF3, SB_FILTER_PCF5, SB_FILTER_POISSON16, SB_FILTER_PCSS };

/* Every shadow-map setting; a technique's parameter struct starts with one. */
typedef struct sb_csm_desc {
    int res, depth, filter, stable, format, blur;
    double bias, slope, normal, sun_size, bleed, exponent;
    int cascades;               /* maps (cascades, or PSM's 6 cube faces); 0 means 1 */
    int select;                 /* 0 interval (by view depth), 1 map (the first map holding the point) */
    double blend;
    int layered;                /* SB_LAYERED_*; ON resolved to the best available at create */
    int warp;                   /* SB_WARP_* */
    double min_angle;           /* LiSPSM: below this view/light angle, no warp (degrees) */
    double focus;               /* TSM: share of the footprint mapped to 80% of the map */
    int perspective;            /* not a parameter: the maps may be perspective without a warp (PSM) */
    int cache;                  /* cached cascades: one whose snapped window did not change is not rendered again */
    int fit;                    /* SB_FIT_*: a cascade's light-space window over its whole slice, or its receivers */
    double distance;            /* stable=on: the shadow range's far end (0: the run's, sb_run_ctx.shadow_far) */
} sb_csm_desc;

/* Whether the cascades of d are fitted to their receivers (fit=receivers, or auto where it applies). */
bool sb_csm_fits_receivers(const sb_csm_desc *d);

/* The defaults of the fields a technique's table may not have. */
#define SB_CSM_DESC_DEFAULTS .cascades = 1, .min_angle = 5, .focus = 0.3

/* Parameters every sun shadow-map technique has. They bind to sb_csm_desc's
 * fields, so a technique's parameter struct must start with its
 * `sb_csm_desc csm` (offset 0). */
#define SB_SHADOWMAP_PARAMS                                                                                    \
    SB_PARAM_I(sb_csm_desc, res, 2048, 64, 16384, "shadow map resolution (texels per side, per cascade)",            \
               .tune = "512,1024,2048", .role = SB_PARAM_RES),     \
    SB_PARAM_E(sb_csm_desc, depth, 32f, "16|24|32f", "shadow map depth format"),                               \
    SB_PARAM_FA(sb_csm_desc, bias, 1, 0, 100, "constant depth bias, in shadow texels of world size"),          \
    SB_PARAM_FA(sb_csm_desc, slope, 0.5, 0, 100, "slope-scaled bias (glPolygonOffset factor; 4x it for warped maps)"), \
    SB_PARAM_FA(sb_csm_desc, normal, 0.25, 0, 100, "normal offset, in shadow texels"),                          \
    SB_PARAM_E(sb_csm_desc, filter, hw, "none|hw|pcf3|pcf5|poisson16|pcss", "shadow filter", .tune = "none,hw,pcf3"),                   \
    SB_PARAM_F(sb_csm_desc, sun_size, 0.53, 0, 10, "pcss: angular diameter of the sun, degrees", .role = SB_PARAM_SUN_SIZE), \
    SB_PARAM_E(sb_csm_desc, stable, off, "off|on", "sphere fit and texel snapping: no shimmer when moving"),    \
    SB_PARAM_E(sb_csm_desc, format, depth, "depth|vsm|esm|msm", "what the map stores: depth, or filterable moments"), \
    SB_PARAM_I(sb_csm_desc, blur, 2, 0, 16, "vsm/esm/msm: Gaussian blur radius of the moments, texels"),        \
    SB_PARAM_F(sb_csm_desc, bleed, 0.2, 0, 0.95, "vsm/msm: light-bleeding reduction"),                          \
    SB_PARAM_F(sb_csm_desc, exponent, 80, 1, 85, "esm: exponent c of exp(c z)"),                                \
    SB_PARAM_F(sb_csm_desc, distance, 0, 0, 1e9,                                                                \
               "stable=on: the shadow range's far end, world units (0: the path's farthest far plane, clamped to "  \
               "the scene), fixed for the run", .late = true)

/* Parameters of the cascaded techniques (pssm, sdsm). */
#define SB_CASCADE_PARAMS                                                                                      \
    SB_PARAM_I(sb_csm_desc, cascades, 4, 1, 8, "number of cascades", .tune = "2,3,4", .role = SB_PARAM_MAPS),                                           \
    SB_PARAM_E(sb_csm_desc, select, interval, "interval|map", "cascade selection: by view depth or by map"),    \
    SB_PARAM_F(sb_csm_desc, blend, 0, 0, 0.5, "blend band between cascades (fraction of a cascade)"),          \
    SB_PARAM_E(sb_csm_desc, layered, off, "off|gs|vs|on",                                                       \
               "per-cascade draws, or one draw per caster routed by a geometry shader / vertex-shader gl_Layer"), \
    SB_PARAM_E(sb_csm_desc, warp, none, "none|lispsm|tsm", "perspective warp of each cascade (LiSPSM, TSM)"),     \
    SB_PARAM_E_LATE(sb_csm_desc, cache, off, "off|on",                                                          \
                    "a cascade whose snapped window and light did not change, and into whose light volume no caster "  \
                    "moved, is not rendered again (stable=on)", .role = SB_PARAM_CACHE),                               \
    SB_PARAM_E_LATE(sb_csm_desc, fit, auto, "slice|receivers|auto",                                             \
                    "each cascade's window over its view slice, or over the receivers inside it (not with stable=on "  \
                    "nor warp=tsm); auto: the receivers where neither is asked")

/* Split distances out[0..m] over [n, f]: practical = lambda*log + (1-lambda)*uniform. */
void sb_split_distances(double lambda, int m, double n, double f, double *out);

/* The cascade block as the GPU sees it (std430, csm_block.glsl; a test
 * compares these offsets with the shader's). `splits` is the part SDSM's GPU
 * fits write and the CSV reads back. */
typedef struct sb_cascade_splits {
    float cascade[SB_MAX_CASCADES][4];  /* near split, far split, texel world size, depth range */
    float flags[SB_MAX_CASCADES][4];    /* x: rendered, y: warped */
} sb_cascade_splits;
typedef struct sb_cascade_block {
    float light_vp[SB_MAX_CASCADES][16];
    float shadow_mat[SB_MAX_CASCADES][16];
    sb_cascade_splits s;
    float info[4];                      /* x: count */
} sb_cascade_block;

/* The programs of the shadow-map stage in one variant: per cascade, and
 * layered (geometry shader or gl_Layer from the vertex shader) when asked. */
typedef struct sb_csm_pass {
    GLuint prog_cascade, prog_layered;
    GLint u_cascade, e_cascade, e_layered;   /* e_: the ESM exponent (u_exponent) */
} sb_csm_pass;

/* Techniques built on the machinery keep their sb_csm as the first member of
 * their state, so tests can read (and break) the shadow maps of any of them. */
typedef struct sb_csm {
    sb_csm_desc d;                        /* as created: layered resolved, cascades >= 1 */
    const sb_gpu *gpu;
    int count;                            /* maps: d.cascades */
    bool no_clamp;                        /* clip casters at the near plane (PSM's naive ordering) */
    GLuint moments, moments_tmp;          /* float arrays of the format's channels (filtered formats) */
    GLuint blur_prog;
    GLint b_dir, b_layer;
    GLint u_moments, u_bleed, u_exponent;
    GLuint raw_sampler;                   /* the map without comparison, for PCSS's blocker search */
    GLint u_depth_raw, u_sun_tan;
    GLuint tex, fbo_all, fbo_layer[SB_MAX_CASCADES];
    GLuint block;                         /* uniform block 0 (storage block 0 for SDSM's compute) */
    sb_csm_pass pass[2];                  /* without the alpha test, and (alpha-tested draws) with it */
    sb_final_prog fp;
    GLint u_shadow, u_bias, u_normal, u_blend, u_light, u_texel;
    /* this frame */
    double splits[SB_MAX_CASCADES + 1];
    sb_light_fit fit[SB_MAX_CASCADES];
    bool active[SB_MAX_CASCADES];
    uint8_t *mask;                        /* per draw: cascades it is a caster of */
    sb_cascade_block cpu;
    /* cache=on: what each map layer holds (the light view-projection it was rendered with; valid once rendered) */
    float cached_vp[SB_MAX_CASCADES][16];
    bool cached[SB_MAX_CASCADES];
    /* stable=on: the shadow range split and fitted every frame, fixed for the run (the run's nearest near plane
       and its shadow distance), so no frame's near or far, nor where the scene cuts its view, moves a split, a
       sphere or its snapped grid */
    double range_near, range_far;
} sb_csm;

/* Parameter combinations that cannot work (no GL): stable with a warp, cache without stable. */
bool sb_csm_check(const sb_csm_desc *d, const char *name, sb_err *err);
/* What the context must offer: the resolution, gl_Layer from the vertex shader
 * for layered=vs, and the memory for the maps and moments (sb_gpu_memory_fits). */
bool sb_csm_supported(const sb_gpu *g, const sb_csm_desc *d, const char *name, sb_err *why);
bool sb_csm_create(sb_csm *c, const sb_gpu *g, const sb_csm_desc *d, const char *name, sb_err *err);
void sb_csm_destroy(sb_csm *c);
/* CPU fits: cascade k covers view depth [splits[k], splits[k+1]]; a slice
 * with no receiver in view is skipped. Uploads the cascade block and records
 * splits in the frame's counters. */
void sb_csm_fit(sb_csm *c, sb_frame *f, const double *splits);
/* Writes the cascade block from c->fit and c->active; map k covers view
 * depth [zn[k], zf[k]] (interval selection). */
void sb_csm_upload(sb_csm *c, const double *zn, const double *zf);
/* Light-space fit for one slice (exposed for tests): sphere + snapping when stable. */
void sb_csm_fit_slice(const sb_csm *c, const sb_frame *f, double zn, double zf, sb_light_fit *out);
/* Per-cascade caster culling into c->mask; cascades whose block was written by
 * the GPU (gpu_fits) are culled against `bound` instead. Returns casters. */
uint32_t sb_csm_cull(sb_csm *c, sb_frame *f, const sb_light_fit *bound);
/* The cascade stage's draws: layered or per cascade, into the array map. */
void sb_csm_render(sb_csm *c, sb_frame *f);
/* The final pass with the cascade lookup. */
void sb_csm_final(sb_csm *c, sb_frame *f, bool reuse_depth);
/* The cascade stage (cull, render) and the final stage, for fits already uploaded. */
void sb_csm_draw(sb_csm *c, sb_frame *f);

/* ---- cascade techniques as rows ---- */

/* A row's split scheme: view depths out[0..count] over [near, far] (the frame's view; stable=on: the run's
 * shadow range). */
typedef struct sb_csm_kind {
    void (*splits)(const void *desc, const sb_frame *f, int count, double near, double far, double *out);
} sb_csm_kind;

/* The splits of one map over the whole range: [near, far]. */
void sb_csm_view_splits(const void *desc, const sb_frame *f, int count, double near, double far, double *out);
/* The range a frame's cascades split: the run's fixed shadow range with stable=on, else the frame's view. */
void sb_csm_range(const sb_csm *c, const sb_frame *f, double *near, double *far);
bool sb_csm_technique_check(const void *desc, sb_err *err);
bool sb_csm_technique_supported(const struct sb_run_ctx *rc, const void *desc, sb_err *why);
bool sb_csm_technique_create(void *state, const struct sb_run_ctx *rc, const void *desc, sb_err *err);
void sb_csm_technique_frame(void *state, sb_frame *f);
void sb_csm_technique_destroy(void *state);

/* The shadow maps' bytes (sb_technique.shadow_bytes): res^2 a cascade, in the depth format, and with a moment
 * format its moments and their blur copy (32-bit float channels). */
double sb_csm_bytes(const sb_csm_desc *d);
double sb_csm_technique_shadow_bytes(const sb_technique *t, const void *desc);

/* The state of a row: the machinery, its split scheme and parameter struct. */
typedef struct sb_csm_state {
    sb_csm csm;
    const sb_csm_kind *kind;
    const void *desc;           /* the instance's parameter struct (alive until destroy) */
} sb_csm_state;

/* The cascade machinery's own counters (sb_technique.counters of every technique drawing through sb_csm_render):
 * cascades_invalidated. SB_CSM_COUNTERS names them in a technique's descriptor. */
#define SB_CSM_COUNTER_COUNT 1
extern const sb_counter_def sb_csm_counters[SB_CSM_COUNTER_COUNT];
#define SB_CSM_COUNTERS .counters = sb_csm_counters, .counter_count = SB_CSM_COUNTER_COUNT

/* A cascade technique: name, summary, parameter table, parameter struct
 * type, its defaults, and the split scheme; then more of its fields (.stress = ...). */
#define SB_CSM_TECHNIQUE(NAME, SUMMARY, PARAMS, DESC_T, DEFAULTS, SPLITS, ...)                                 \
    {                                                                                                          \
        .name = NAME, .summary = SUMMARY, .params = PARAMS, .param_count = (int)SB_COUNT(PARAMS),              \
        .desc_size = sizeof(DESC_T), .desc_defaults = DEFAULTS,                                                \
        SB_STAGES(&sb_stage_cascade, &sb_stage_final), .needs = SB_NEEDS_SUN,                                  \
        .state_size = sizeof(sb_csm_state), .check = sb_csm_technique_check,                                   \
        .supported = sb_csm_technique_supported, .shadow_bytes = sb_csm_technique_shadow_bytes,                \
        .create = sb_csm_technique_create,                                                                     \
        .frame = sb_csm_technique_frame, .destroy = sb_csm_technique_destroy, SB_CSM_COUNTERS,                 \
        .impl = &(const sb_csm_kind){SPLITS}, __VA_ARGS__                                                      \
    }
