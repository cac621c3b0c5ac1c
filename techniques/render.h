/* render.h - the GPU side of a run, shared by every technique: scene buffers,
 * the camera render target, the final-pass program, draw submission with
 * counting, what a technique's create receives (sb_run_ctx) and the per-frame
 * state its frame function works on (sb_frame). GL programs and textures
 * themselves are the GL layer's (gl.h). */
#pragma once
#include "gl.h"
#include "path.h"
#include "scene.h"
#include "technique.h"

struct sb_timer;
struct sb_reference;

/* One variant of the camera-pass program, with the shared pass's uniforms in
 * it and the links that bring the technique's uniforms over from `prog`. */
typedef struct sb_final_variant {
    GLuint prog;
    GLint u_view, u_proj, u_light, u_more, u_spot;
    GLint u_depth_view;     /* evaluation variants: the view the lookup's depth is in */
    sb_gl_links from_timed;
} sb_final_variant;

/* Shared program of the camera pass: scene.vert + final.frag + the technique's
 * visibility function, linked as up to four variants, v[2 * eval + alpha]:
 * timed frames draw with the timed ones, which write colour alone and hold
 * nothing of the evaluation; the (untimed) evaluation pass with the SB_EVAL
 * ones, which also write the visibility, position and normal targets. Where
 * the scene has alpha-tested draws, each comes without the alpha test (its
 * opaque draws keep early depth testing: no discard) and with it (alpha = 1,
 * drawn after the opaque draws); otherwise v[1] and v[3] are 0. Techniques use
 * `prog` (v[0]) and set their uniforms on it; the pass copies them to the
 * variant it draws with. */
typedef struct sb_final_prog {
    GLuint prog;            /* v[0].prog */
    GLuint eval_prog;       /* v[2].prog */
    sb_final_variant v[4];
} sb_final_prog;

/* The GPU side of a session: what every run and frame reads, never writes. */
typedef struct sb_gpu {
    const sb_scene *scene;
    const sb_context *ctx;
    int width, height;
    sb_v3 sun;                          /* unit vector toward the sun */
    bool has_sun;                       /* the scene has one, or --sun gave one (else `sun` is a default) */
    GLuint vao, vbo, ibo;
    GLuint fbo, color_tex, vis_tex, depth_tex;
    GLuint pos_tex, aux_tex;            /* evaluation targets (position, normal + cascade) */
    GLuint base_tex;                    /* evaluation target: base colour and the scored light's N.L (RGBA8) */
    GLuint zpass_prog[2];               /* camera depth-only program (same vertex shader as the final pass):
                                           without and (alpha-tested draws only) with the alpha test */
    GLint zpass_u_view[2], zpass_u_proj[2];
    GLuint mat_ssbo, texel_buf, texel_tex;  /* the alpha test's materials (binding 7) and texels (unit 15) */
    struct sb_facing *facing;           /* single-sided draws' triangles ordered by the light they face (harness-owned) */
    struct sb_gpu_geom *geom;           /* where each draw's triangles lie in vbo/ibo (render.c: a shared primitive once) */
    GLuint xform_buf;                   /* per draw: its instance transform (locations 6-8, identity unless shared) */
    /* per-draw data the shaders read through instanced attributes fetched at baseInstance = the draw's number
       (so a multi-draw needs no uniform between draws): colour (location 4, static) and caster mask (5, written
       by a layered shadow pass: sb_set_draw_masks) */
    GLuint color_buf, mask_buf;
    bool indirect;                      /* --submit indirect: a pass's draws are one glMultiDrawElementsIndirect */
    GLuint indirect_buf;                /* its commands (rewritten at every flush) */
    struct sb_gpu_pose *pose;           /* a moving scene's posing pass (pose.h; NULL: the CPU poses) */
    struct sb_gpu_pieces *pieces;       /* a software rasterizer's submission in bounded pieces (render.c; NULL: a GPU) */
} sb_gpu;

/* What a technique's create gets: the session (read-only), the run's size,
 * and what was prepared for it. */
typedef struct sb_run_ctx {
    const sb_gpu *gpu;
    const sb_technique *tech;
    int frames;                         /* frames the run will render, warm-up and repeats included */
    void *scene_data;                   /* what the technique's load step made for this scene (or NULL) */
    const struct sb_reference *reference;   /* the Embree reference, for SB_NEEDS_REFERENCE (else NULL) */
    const sb_light_set *lights;         /* --lights: the lights to shadow (NULL: the technique's one light) */
    /* the run's shadow range, the same every frame (engines' shadow distance): the path's nearest near plane
       and its farthest far plane, clamped to the farthest the scene reaches from any of its cameras */
    double shadow_near, shadow_far;
} sb_run_ctx;

/* The flicker twin's lookup (eval.c): the camera pass of a frame with one
 * draws this camera instead of the frame's own (the evaluated frame's, a
 * short step before), so that the same world points are looked up in this
 * frame's shadow maps, the view depth of the lookup (cascade selection) still
 * the frame's. Depth a z-pass of the frame's own camera left is not reused;
 * a pass that cannot look other points up (the stencil-split final pass of
 * volumes and planar) marks the frame's look_failed. */
typedef struct sb_look {
    sb_m4 view, proj;                   /* from origin-relative world */
    double frustum[6][4];
    sb_v3 eye;                          /* origin-relative */
} sb_look;

/* One frame: the camera and everything that varies from frame to frame. */
typedef struct sb_frame {
    const sb_gpu *gpu;
    struct sb_timer *timer;
    int index;                          /* frame of the path */
    int seq;                            /* position in the run (warm-up frames first) */
    double progress;
    double start_ms;                    /* sb_now_ms() when the frame began (timed frames) */
    sb_camera cam;                      /* world space */
    sb_m4 view, proj, view_proj;        /* from origin-relative world */
    double frustum[6][4];               /* camera planes, origin-relative */
    bool eval;                          /* evaluation pass: the final pass writes all four targets (timed
                                           frames: colour alone, with the timed variant) */
    double shade_light[4];              /* the light the frame is lit by: shadow stages draw the triangles
                                           of single-sided draws facing it, the final pass shades it and the
                                           evaluation tests it; xyz toward the sun (w 0) or a point light's
                                           position (w 1); the sun unless the technique shades a lamp
                                           (sb_frame_shade_point, before its shadow stage) */
    double shade_range;                 /* the shaded lamp's range, beyond which it lights nothing (0: none) */
    double shade_spot[4];               /* a shaded spot light: the way it shines and 1 - cos of its cone (0: none) */
    bool shade_add;                     /* --lights: a camera pass adding one more light to the colour (no ambient) */
    int pass_box_count;                 /* 6: the camera pass's draws also culled to pass_box (an added lamp's range,
                                           beyond which it adds nothing); 0: none */
    double pass_box[6][4];
    uint32_t *scratch;                  /* draw_count entries, for culling results */
    uint32_t *cmds;                     /* --submit indirect: the pass's pending commands, 5 words each (at most
                                           draw_count: a pass issues each draw once between flushes) */
    uint32_t cmd_count;
    const sb_stage_def *stage;          /* the stage being recorded (for draw counts), and its slot */
    int stage_slot;
    sb_counters counters;
    const sb_look *look;                /* the flicker twin's lookup (NULL: the frame's own camera) */
    bool look_depth;                    /* the target's depth is the look camera's (a G-buffer pass drew it) */
    bool look_failed;                   /* the technique's final pass could not look the points up */
    /* Motion (a scene whose clips play): the draws whose box changed since the technique's previous frame, and
     * their boxes then (origin-relative); their boxes now are the scene's. A cache invalidates what the old or
     * the new box of one of them overlaps. The harness fills them before the technique's frame. */
    const uint32_t *moved;
    const sb_aabb *moved_from;
    uint32_t moved_count;
    bool bypass_cache;                  /* draw every cached map or page again this frame (the stale check) */
    double anim_ms;                     /* posing the scene and uploading its moving vertices (NAN: none) */
    /* --lights, in an evaluation pass: 1 + the place in the run's set of the one light the frame shades and writes
       the visibility of, with maps for it alone (0: every light of the set, as a timed frame) */
    int eval_light;
} sb_frame;

/* Whether a caster that moved since the technique's previous frame meets a region, before or after its move:
 * meets(box, region) for each moved draw's old and new box (origin-relative). The one test every cache of moved
 * casters asks (cascades' layers, virtual pages, the atlas's lamps), each with its own region. */
bool sb_frame_moved_meets(const sb_frame *f, bool (*meets)(const sb_aabb *box, const void *region), const void *region);

bool sb_gpu_init(sb_gpu *g, const sb_context *ctx, const sb_scene *scene, int width, int height, sb_v3 sun,
                 sb_err *err);
/* The bytes sb_gpu_init uploads for a scene (its vertex and index buffers, a shared primitive once, and the
 * draws' transforms; with alpha-tested draws the materials and texels), without a GL: what `info SCENE` says
 * the scene takes on the GPU. A lamp's or planar's run may make copies after all (sb_gpu_share). */
double sb_gpu_scene_bytes(const sb_scene *s);
/* Instanced draws (sb_draw.proto) draw their proto's GPU copy through their transform: all that can by default.
 * sb_instance_create lowers it from the technique's needs, outside any timed frame: a lamp's (an open draw's
 * light-facing triangles then differ between copies: only draws drawn whole stay shared), and with `planar` a
 * receiver plane's (planar draws triangles by their scene numbers: none shared). Sharing only goes down in a
 * session; the pictures are the same either way. */
void sb_gpu_share(const sb_gpu *g, bool planar);
/* Triangle t's three vertices in the GPU's buffers as uploaded: after sb_gpu_share(g, true), t numbers the
 * scene's placed triangles (scene.h: the planes' tris). */
void sb_gpu_triangle(const sb_gpu *g, uint32_t t, uint32_t out[3]);
/* After sb_scene_pose moved the scene: the moving draws' vertices into the vertex buffer, posed there by the GPU
 * (pose.c) or sent from the CPU's pose (the placements the GPU leaves), and the light-facing order of open ones
 * made again when next needed. */
void sb_gpu_update_motion(const sb_gpu *g);

void sb_gpu_free(sb_gpu *g);
/* The final-pass program with the technique's visibility GLSL. */
bool sb_final_prog_create(sb_final_prog *fp, const sb_gpu *g, const char *label, const char *vis_glsl,
                          const char *defines, sb_err *err);
/* The same with the visibility GLSL in parts (the cascade block, then the lookup). */
bool sb_final_prog_create_parts(sb_final_prog *fp, const sb_gpu *g, const char *label, const char *const *vis_parts,
                                int nvis, const char *defines, sb_err *err);
/* The defines of a scene pass's variant without the alpha test ("" when the
 * scene has no alpha-tested draw: its one variant is that), and the variant
 * draw d is drawn with: 1 (with the test) for an alpha-tested draw, else 0.
 * A pass draws variant 0's draws first, then variant 1's. */
const char *sb_opaque_define(const sb_gpu *g);
int sb_draw_variant(const sb_gpu *g, uint32_t d);
void sb_final_prog_free(sb_final_prog *fp);
/* A visibility made on the CPU (raycast's rays, score's files): the final pass (sb_shader_vis_cpu_glsl) looks up the
 * pixel's own texel of an R8 texture of the frame's size, its sampler on unit 0. sb_cpu_vis_texture makes the
 * texture; sb_cpu_vis_bind binds it on unit 0, after sending it vis (a frame's worth, 255 lit, rows bottom-up)
 * unless NULL. */
GLuint sb_cpu_vis_texture(const sb_gpu *g);
void sb_cpu_vis_bind(GLuint tex, const sb_gpu *g, const unsigned char *vis);

/* Sets the frame's camera, matrices and planes, counters to zero and the shaded light to the sun. */
void sb_frame_setup(sb_frame *f, const sb_gpu *g, const sb_camera *cam);
/* After sb_frame_setup: the image shifted by (jx, jy) pixels (TAA's jitter): proj, view_proj and the frustum. */
void sb_frame_jitter(sb_frame *f, double jx, double jy);
/* A stage of the frame, timed in its slot (sb_stage_slot); a stage no technique declares is the build's mistake
 * (said, and the process aborts). */
void sb_stage_begin(sb_frame *f, const sb_stage_def *s);
void sb_stage_end(sb_frame *f, const sb_stage_def *s);
/* Draws every camera-visible draw into the render target with fp (already
 * in use, technique uniforms set). Clears colour, visibility and, unless
 * reuse_depth (a z-pass filled it; tested with LEQUAL), depth. Counts draws. */
void sb_final_pass(sb_frame *f, const sb_final_prog *fp, bool reuse_depth);
/* The final pass that fills depth the way a later sb_final_pass with
 * reuse_depth tests it (LEQUAL, writing: of equal depths the last drawn wins),
 * so both put the same triangle in every pixel (raycast's position pass). */
void sb_gbuffer_pass(sb_frame *f, const sb_final_prog *fp);
/* The same draws without clearing anything (a second pass over the frame). */
/* --lights: one more light added to the colour of the camera pass before it (blended, no ambient, its depth kept):
 * the technique has set the light's uniforms and sb_frame_shade_light_of / sb_frame_shade_point. */
void sb_final_pass_add(sb_frame *f, const sb_final_prog *fp);
void sb_final_draw(sb_frame *f, const sb_final_prog *fp, bool reuse_depth);
/* The eye the camera pass draws from (origin-relative): the frame's, or its look's. */
sb_v3 sb_frame_eye(const sb_frame *f);
/* Depth-only camera pass into the render target's depth (the z-pass). */
void sb_zpass(sb_frame *f);
/* Issues one draw (instanced when instances > 1) with whatever program is
 * bound, and counts it in the current stage. In a shadow stage (cascade,
 * volumes) a single-sided draw issues only its triangles whose front faces
 * the frame's light (they come first in its range: the index buffer is
 * ordered for the light on first use), as the reference's rays see them. */
void sb_submit(sb_frame *f, uint32_t draw, int instances);
/* With --submit indirect, sb_submit collects the draws and this issues them
 * as one glMultiDrawElementsIndirect (one API call): call it before any state
 * a draw depends on changes (program, uniforms, framebuffer, culling) and at
 * the end of a loop of draws; sb_stage_end calls it too. Nothing with direct. */
void sb_submit_flush(sb_frame *f);
/* Uploads each draw's caster mask (draw_count bytes) for the layered shadow
 * shaders (attribute 5, read at the draw's baseInstance). */
void sb_set_draw_masks(const sb_frame *f, const uint8_t *masks);
/* Whether `bytes` of `what` (e.g. "shadow maps") fit beside the camera
 * targets in the GPU memory the context has (sb_context_memory_free): false
 * with "WHO: needs 4.0 GiB of shadow maps, ..." in why when they do not. */
bool sb_gpu_memory_fits(const sb_gpu *g, double bytes, const char *who, const char *what, sb_err *why);
/* A point-light technique's light=K: false with the reason when the scene has no K-th point or spot light. */
bool sb_lamp_supported(const sb_gpu *g, int light, const char *technique, sb_err *why);
/* A point-light technique's maps (res² each, `bytes` of them in all: sb_lamp_technique_shadow_bytes; a
 * cube when cube is true): within GL_MAX_CUBE_MAP_TEXTURE_SIZE or
 * GL_MAX_TEXTURE_SIZE and within the GPU memory (sb_gpu_memory_fits). */
bool sb_lamp_maps_fit(const sb_gpu *g, const char *technique, int res, double bytes, bool cube, sb_err *why);
/* A shadow pass's depth state: the depth test (less) and writes on, and the slope-scaled offset (the
 * glPolygonOffset factor; 0: none) on where given. The pass turns GL_POLYGON_OFFSET_FILL off at its end. */
void sb_shadow_depth_state(float slope);
/* The lights [*first, *end) of a set of `count` a frame draws: all of them, or the one an evaluation pass scores
 * (sb_frame.eval_light). */
static inline void sb_frame_light_range(const sb_frame *f, int count, int *first, int *end) {
    *first = f->eval_light ? f->eval_light - 1 : 0;
    *end = f->eval_light ? f->eval_light : count;
}
/* Makes the frame lit by a lamp: sb_frame_shade_point at its place, its range and a spot's cone too. */
void sb_frame_shade_lamp(sb_frame *f, const sb_light *lamp);
/* Makes the frame lit by one light (SB_LIGHT_SUN or a lamp's index), its range and a spot's cone too. */
void sb_frame_shade_light_of(sb_frame *f, int idx);
/* Makes the frame lit by a point light at pos: call it before the shadow
 * stage (its draws keep the triangles facing the lamp), and the final pass
 * shades and the evaluation tests that lamp. */
void sb_frame_shade_point(sb_frame *f, sb_v3 pos);
/* The final pass split by the stencil (shadow volumes, planar shadows): where
 * (stencil & mask) == 0 it is drawn lit (u_lit 1), elsewhere in shadow (0).
 * Depth from the z-pass is reused; the stencil is left enabled off afterwards. */
void sb_final_pass_stencil(sb_frame *f, const sb_final_prog *fp, GLint u_lit, GLuint mask);
/* Uploads the frame's camera view and projection (float) to the bound program. */
void sb_set_camera_uniforms(const sb_frame *f, GLint u_view, GLint u_proj);
/* Counts a draw issued by the technique itself (its own geometry): one draw and one API call. */
void sb_count_draw(sb_frame *f, uint64_t triangles, int instances);

/* Reads the last frame's targets (any pointer may be NULL): depth (float,
 * window [0,1]), visibility (1 byte, 255 lit) and colour (RGBA8). Never
 * called inside timed frames. Rows bottom-up as in GL. */
void sb_gpu_readback(const sb_gpu *g, float *depth, unsigned char *vis, unsigned char *rgba);
/* Reads the evaluation targets (4 floats a pixel each; either may be NULL). */
void sb_gpu_readback_eval(const sb_gpu *g, float *pos, float *aux);
/* Whether they hold geometry at a pixel: sb_eval_has_geometry (reference/error.h). */

/* The camera pass's light (final.frag, and the shaded frames of --flip, eval.c): base colour x (ambient + direct
 * x N.L x visibility); at most 1, so no tone map. */
#define SB_SHADE_AMBIENT 0.3
#define SB_SHADE_DIRECT 0.7
/* The evaluation pass's base target: per pixel the base colour and N.L of the light it scores (the sky: its
 * colour and 1), 4 bytes, rows bottom-up. */
void sb_gpu_readback_base(const sb_gpu *g, unsigned char *rgba);
/* World-space (absolute, double) point of pixel (x, y) at window depth d. */
sb_v3 sb_frame_unproject(const sb_frame *f, double x, double y, double d);
