/* cascade.h - the shared cascade machinery, written once: split schemes,
 * per-slice light fits (lightfit.c), stabilisation, receiver checks, exact
 * caster culling per cascade over the BVH, layered or per-cascade submission
 * into one 2D-array shadow map, and the final-pass lookup (vis_csm.glsl).
 * sm is one cascade over the whole view; pssm and sdsm differ only in where
 * their splits come from. */
#pragma once
#include "lightfit.h"

/* Parameters every shadow-map technique has. */
#define SB_SHADOWMAP_PARAMS                                                                                    \
    {"res", SB_PARAM_INT, "2048", 64, 16384, NULL, "shadow map resolution (texels per side, per cascade)"},     \
    {"depth", SB_PARAM_ENUM, "32f", 0, 0, "16|24|32f", "shadow map depth format"},                             \
    {"bias", SB_PARAM_FLOAT, "1", 0, 100, NULL, "constant depth bias, in shadow texels of world size"},        \
    {"slope", SB_PARAM_FLOAT, "2", 0, 100, NULL, "slope-scaled bias (glPolygonOffset factor)"},                \
    {"normal", SB_PARAM_FLOAT, "1", 0, 100, NULL, "normal offset, in shadow texels"},                          \
    {"filter", SB_PARAM_ENUM, "hw", 0, 0, "none|hw|pcf3|pcf5|poisson16|pcss", "shadow filter"},                \
    {"sun_size", SB_PARAM_FLOAT, "0.53", 0, 10, NULL, "pcss: angular diameter of the sun, degrees"},          \
    {"stable", SB_PARAM_ENUM, "off", 0, 0, "off|on", "sphere fit and texel snapping: no shimmer when moving"},  \
    {"format", SB_PARAM_ENUM, "depth", 0, 0, "depth|vsm|esm|msm", "what the map stores: depth, or filterable moments"}, \
    {"blur", SB_PARAM_INT, "2", 0, 16, NULL, "vsm/esm/msm: Gaussian blur radius of the moments, texels"},      \
    {"bleed", SB_PARAM_FLOAT, "0.2", 0, 0.95, NULL, "vsm/msm: light-bleeding reduction"},                      \
    {"exponent", SB_PARAM_FLOAT, "80", 1, 85, NULL, "esm: exponent c of exp(c z)"}

/* Parameters of the cascaded techniques. */
#define SB_CASCADE_PARAMS                                                                                      \
    {"cascades", SB_PARAM_INT, "4", 1, 8, NULL, "number of cascades"},                                         \
    {"select", SB_PARAM_ENUM, "interval", 0, 0, "interval|map", "cascade selection: by view depth or by map"}, \
    {"blend", SB_PARAM_FLOAT, "0", 0, 0.5, NULL, "blend band between cascades (fraction of a cascade)"},       \
    {"layered", SB_PARAM_ENUM, "off", 0, 0, "off|gs|vs|on",                                                    \
     "per-cascade draws, or one draw per caster routed by a geometry shader / vertex-shader gl_Layer"},        \
    {"warp", SB_PARAM_ENUM, "none", 0, 0, "none|lispsm|tsm", "perspective warp of each cascade (LiSPSM, TSM)"}

enum { SB_LAYERED_OFF, SB_LAYERED_GS, SB_LAYERED_VS };
enum { SB_SPLIT_UNIFORM, SB_SPLIT_LOG, SB_SPLIT_PRACTICAL };

/* Split distances out[0..m] over [n, f]: practical = lambda*log + (1-lambda)*uniform. */
void sb_split_distances(double lambda, int m, double n, double f, double *out);

/* The cascade block as the GPU sees it (std430, csm_block.glsl). */
typedef struct sb_cascade_block {
    float light_vp[SB_MAX_CASCADES][16];
    float shadow_mat[SB_MAX_CASCADES][16];
    float cascade[SB_MAX_CASCADES][4];   /* near split, far split, texel world size, depth range */
    float flags[SB_MAX_CASCADES][4];     /* x: rendered */
    float info[4];                       /* x: count */
} sb_cascade_block;

/* Techniques built on the machinery keep their sb_csm as the first member of
 * their state, so tests can read the shadow maps of any of them. */
typedef struct sb_csm {
    sb_gpu *gpu;
    int res, count, filter, select, layered, stable, warp;
    int format, blur;                     /* 0 depth, 1 vsm, 2 esm, 3 msm; blur radius in texels */
    double bleed, exponent;
    GLuint moments, moments_tmp;          /* RGBA32F arrays (filtered formats) */
    GLuint blur_prog;
    GLint b_dir, b_radius, b_layer;
    GLint u_moments, u_bleed, u_exponent, d_exponent[3];
    bool no_clamp;                        /* clip casters at the near plane (PSM's naive ordering) */
    double min_angle;                     /* LiSPSM falls back to uniform below this view/light angle */
    double focus;                         /* TSM: share of the footprint mapped to 80% of the map */
    double bias, slope, normal, blend, sun_size;
    GLuint raw_sampler;                   /* the map without comparison, for PCSS's blocker search */
    GLint u_depth_raw, u_sun_tan;
    GLenum depth_format;
    GLuint tex, fbo_all, fbo_layer[SB_MAX_CASCADES];
    GLuint block;                         /* SSBO, binding 0 */
    GLuint prog_cascade, prog_gs, prog_vs;
    GLint u_cascade, u_mask_gs, u_mask_vs;
    sb_final_prog fp;
    GLint u_shadow, u_bias, u_normal, u_blend, u_light, u_texel;
    /* this frame */
    double splits[SB_MAX_CASCADES + 1];
    sb_light_fit fit[SB_MAX_CASCADES];
    bool active[SB_MAX_CASCADES];
    uint8_t *mask;                        /* per draw: cascades it is a caster of */
    sb_cascade_block cpu;
} sb_csm;

/* Reads the shadow-map (and, if present, cascade) parameters; cascades
 * defaults to 1 when the technique has no `cascades` parameter. */
bool sb_csm_create(sb_csm *c, sb_gpu *g, const sb_params *p, const char *name, sb_err *err);
/* What a technique decides instead of its parameters (zero: from the parameters). */
typedef struct sb_csm_desc {
    int maps;               /* layers of the array map (PSM's cube: 6) */
    bool select_map;        /* select by map: the first map that holds the point */
} sb_csm_desc;
bool sb_csm_create_desc(sb_csm *c, sb_gpu *g, const sb_params *p, const char *name, const sb_csm_desc *desc,
                        sb_err *err);
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
/* A whole frame from CPU splits: fit, then the cascade stage (cull, render)
 * and the final stage. sm and pssm are this with their own splits. */
void sb_csm_frame(sb_csm *c, sb_frame *f, const double *splits);
/* The cascade stage (cull, render) and the final stage, for fits already uploaded. */
void sb_csm_draw(sb_csm *c, sb_frame *f);
