/* lamp.h - what the point-light techniques share, as cascade.h is the sun
 * techniques': the lamp and its clip range, a depth texture of `maps` layers
 * with a framebuffer per layer and one layered, the shadow stage's state and
 * the opaque-then-alpha-tested submission of the casters in the lamp's range,
 * and the final pass with the shared lookup uniforms. A lamp technique is its
 * parameter table (SB_LAMP_PARAMS and its own rows) and an sb_lamp_kind: how
 * it lays out and renders its maps and which lookup reads them, put together
 * by SB_LAMP_TECHNIQUE (cube.c, dpsm.c). With --lights it shadows every lamp
 * named, a map set each: with grid=on (the default) every lamp's maps are
 * layers of one texture and one camera pass finds each pixel's lamps by cluster
 * (lightgrid.h), as the atlas's does; with grid=off each lamp adds its light in
 * a camera pass of its own, cut to its footprint. */
#pragma once
#include "lightgrid.h"
#include "render.h"

/* The lamps' own stage: the light grid built and sent (grid=on). */
extern const sb_stage_def sb_stage_clusters;

/* Every lamp setting; a lamp technique's parameters are rows of this struct. */
typedef struct sb_lamp_desc {
    int res, light, filter, layered;   /* layered: only where the kind has it (SB_LAYERED_*) */
    int grid;                          /* with --lights: one pass through the light grid (1) or a pass a lamp */
    double bias, slope, normal;
} sb_lamp_desc;

/* The rows every lamp technique has; it adds filter (and layered). */
#define SB_LAMP_PARAMS(RES_HELP)                                                                                    \
    SB_PARAM_I(sb_lamp_desc, res, 1024, 64, 8192, RES_HELP, .tune = "512,1024,2048", .role = SB_PARAM_RES), \
        SB_PARAM_I(sb_lamp_desc, light, 0, 0, 15, "which point or spot light of the scene (in file order)"),       \
        SB_PARAM_FA(sb_lamp_desc, bias, 1.5, 0, 100, "constant bias, in texels at the point's distance"),          \
        SB_PARAM_FA(sb_lamp_desc, slope, 2, 0, 100, "slope-scaled bias (glPolygonOffset factor)"),                 \
        SB_PARAM_FA(sb_lamp_desc, normal, 1, 0, 100, "normal offset, in texels")

/* The grid= row, last of a lamp technique's table (added after series began: written only when off). */
#define SB_LAMP_GRID_PARAM                                                                                          \
    SB_PARAM_E_LATE(sb_lamp_desc, grid, on, "off|on",                                                               \
                    "with --lights: every lamp's maps layers of one texture, read by one camera pass that finds "   \
                    "each pixel's lamps by cluster (the clusters stage); off: a camera pass a lamp, cut to its "    \
                    "footprint")

/* Its counter: the light grid's lamp-cluster pairs (the atlas's column of that name). */
extern const sb_counter_def sb_lamp_counters[1];

typedef struct sb_lamp_state sb_lamp_state;

/* How one lamp technique differs. */
typedef struct sb_lamp_kind {
    GLenum target;              /* GL_TEXTURE_CUBE_MAP or GL_TEXTURE_2D_ARRAY */
    int maps;                   /* its layers: 6 cube faces, 2 paraboloids */
    bool layered;               /* takes layered= (off|gs|vs|on) */
    double near_share;          /* the near plane, as a share of the far one */
    const char *vis_glsl;       /* the lookup (SB_FILTER defined from filter=) */
    /* optional: what follows from the lamp (face matrices, a frame), after near and far are known */
    void (*setup)(sb_lamp_state *s);
    /* the depth program of variant a (1: for the alpha-tested draws; defines: the variant's), into s->pass[a] */
    bool (*program)(sb_lamp_state *s, int a, const char *defines, sb_err *err);
    /* renders the maps inside the shadow stage (the layered framebuffer bound and cleared, depth state and slope
       bias set), submitting through sb_lamp_draw; returns how many maps it rendered */
    int (*render)(sb_lamp_state *s, sb_frame *f);
    /* optional: the lookup's own uniforms, beyond the shared ones: their names (located at create into
       s->u_lookup), and what sets them each frame (its program bound) */
    const char *lookup_uniforms[4];
    void (*lookup)(const GLint u[4]);
} sb_lamp_kind;

struct sb_lamp_state {
    const sb_lamp_kind *kind;
    const sb_lamp_desc *d;
    int layered;                /* resolved: 0 per map, 1 geometry shader, 2 vertex shader */
    sb_v3 lamp;                 /* origin-relative */
    double near, far;
    GLuint tex, fbo_all, fbo[6];   /* fbo_all: every layer (cleared at once, layered rendering); fbo: one each */
    struct {   /* the depth pass: [0] without the alpha test (opaque draws), [1] with it (sb_draw_variant) */
        GLuint prog;
        GLint u[6];             /* the kind's uniform locations */
    } pass[2];
    sb_final_prog fp;
    GLint u_map, u_lamp, u_near, u_far, u_res, u_bias, u_normal;
    GLint u_lookup[4];          /* the kind's lookup_uniforms */
    /* --lights: the first light's state is the technique's; the others follow in `others` (count - 1 states of the
       technique's size, each with its lamp and maps, this one's programs shared) */
    int count;
    size_t size;
    char *others;
    const sb_light *source;     /* the scene's light: shaded and scored only within its range and a spot's cone */
    int index;                  /* its place among the lights (its layers in `array`) */
    /* grid=on with more than one light (the first light's state holds it): every light's maps as layers of one
       texture, each light's tex a view of its own; the lamps' records (vis_lamps.glsl), the light grid, and the
       camera pass that reads them */
    GLuint array, rec_buf, rec_tex;
    sb_final_prog loop_fp;
    GLint u_loop[4];            /* u_map, u_lights, u_bias, u_normal */
    GLint u_loop_lookup[4];
    sb_lightgrid *grid;
    sb_v3 *grid_pos;
    double *grid_range;
};

/* A lamp's clip range: far its range (a lamp of no range: twice the scene's size), near a share of far (at least
 * a hundredth of the share, in scene units): cube's and dpsm's maps, the atlas's tiles. */
void sb_lamp_clip(const sb_light *src, const sb_scene *s, double near_share, double *near, double *far);
/* The paraboloids' frame (dpsm.vert's u_frame, column-major: x = +X, y = +Z, z = -Y, so the front hemisphere
 * looks down) and a paraboloid
 * depth pass's uniforms: u holds the locations of u_lamp, u_frame, u_side, u_near and u_far; side 1 the front
 * hemisphere, -1 the back (dpsm's maps, the atlas's paraboloid tiles). */
extern const float sb_lamp_paraboloid_frame[9];
void sb_lamp_paraboloid_uniforms(const GLint u[5], sb_v3 lamp, double near, double far, float side);

/* The six faces of a cube around pos, in GL's cube-map order and orientation (+X -X +Y -Y +Z -Z): each face's
 * view-projection, 90 degrees from near to far (cube.c's maps, the atlas's tiles). */
void sb_lamp_cube_faces(sb_v3 pos, double near, double far, sb_m4 vp[6]);
/* The i-th light's state of a technique's (0: itself). */
sb_lamp_state *sb_lamp_light(sb_lamp_state *s, int i);

/* Casters within the lamp's range (the box around it) into f->scratch; returns how many. */
uint32_t sb_lamp_casters(const sb_lamp_state *s, sb_frame *f);
/* Submits the n casters of f->scratch: the opaque ones with pass 0, then the alpha-tested ones with pass 1, each
 * program bound and then set(s, a, arg) called to set its uniforms; instances per draw (6: layered by gl_Layer). */
void sb_lamp_draw(sb_lamp_state *s, sb_frame *f, uint32_t n, int instances,
                  void (*set)(const sb_lamp_state *s, int a, const void *arg), const void *arg);

bool sb_lamp_technique_supported(const sb_run_ctx *rc, const void *desc, sb_err *why);
double sb_lamp_technique_shadow_bytes(const sb_technique *t, const void *desc);
bool sb_lamp_technique_create(void *state, const sb_run_ctx *rc, const void *desc, sb_err *err);
void sb_lamp_technique_frame(void *state, sb_frame *f);
void sb_lamp_technique_destroy(void *state);

/* A lamp technique: STATE_T starts with an sb_lamp_state (its kind's own state after it). */
#define SB_LAMP_TECHNIQUE(NAME, SUMMARY, PARAMS, STATE_T, KIND)                                                    \
    {                                                                                                              \
        .name = NAME, .summary = SUMMARY, .params = PARAMS, .param_count = (int)SB_COUNT(PARAMS),                  \
        .desc_size = sizeof(sb_lamp_desc),                                                                         \
        SB_STAGES(&sb_stage_cascade, &sb_stage_clusters, &sb_stage_final),                                         \
        .counters = sb_lamp_counters, .counter_count = 1,                                                           \
        .needs = SB_NEEDS_POINT_LIGHT, .lights = SB_LIGHTS_LAMPS, .state_size = sizeof(STATE_T), .supported = sb_lamp_technique_supported,    \
        .shadow_bytes = sb_lamp_technique_shadow_bytes,                                                            \
        .create = sb_lamp_technique_create, .frame = sb_lamp_technique_frame,                                      \
        .destroy = sb_lamp_technique_destroy, .impl = KIND,                                                         \
    }
