/* sdsm.c - sample distribution shadow maps (Lauritzen, Salvi & Lefohn 2011).
 * The pixels decide the splits: a camera depth pre-pass (zpass, reused by
 * the final pass), a compute reduction to the visible [z_min, z_max] and a
 * log-depth histogram (minmax), partitions over that range (log, or from the
 * histogram: no split in empty depth), optionally tight per-partition x/y
 * bounds from the samples, and one shadow map per non-empty partition.
 *
 * splits=gpu (default): compute shaders write the partitions and light
 * matrices straight into the cascade block the shadow and final passes read;
 * the CPU never reads anything back in the frame loop. Casters are culled on
 * the CPU against the whole view's light volume (it cannot know the GPU's
 * partitions), and empty partitions are skipped on the GPU.
 * splits=cpu: the statistics are read back `latency` frames late (0 stalls:
 * how the Brno thesis did it, which is why its cascade time included the CPU
 * waiting) and the CPU fits and culls per cascade like PSSM. Statistics of a
 * view the camera has cut away from (SDSM_CUT_*: turned or moved far since)
 * say nothing of this one: that frame splits as if it had none, the way
 * engines drop temporal history at a camera cut. */
#include <math.h>
#include <stddef.h>
#include <stdlib.h>
#include <string.h>

#include "cascade.h"
#include "shaders.h"

typedef struct sdsm_desc {
    sb_csm_desc csm;
    int partition, tight, splits, latency;
    double guard;
} sdsm_desc;

enum { SPLITS_GPU, SPLITS_CPU };

static const sb_param_def sdsm_params[] = {
    SB_SHADOWMAP_PARAMS,
    SB_CASCADE_PARAMS,
    SB_PARAM_E(sdsm_desc, partition, log, "log|histogram", "partitions of [z_min, z_max]"),
    SB_PARAM_E(sdsm_desc, tight, off, "off|on", "per-partition light-space x/y bounds from the samples (splits=gpu)"),
    SB_PARAM_E(sdsm_desc, splits, gpu, "gpu|cpu", "where partitions and light matrices are computed"),
    SB_PARAM_I(sdsm_desc, latency, 1, 0, 2, "splits=cpu: frames between the reduction and its readback"),
    SB_PARAM_F(sdsm_desc, guard, 2, 0, 64, "guard band around tight bounds, in texels"),
};
static const sdsm_desc sdsm_defaults = {.csm = {SB_CSM_DESC_DEFAULTS}};

#define HIST 64

/* CPU mirror of SbDepthStats (std430). */
typedef struct depth_stats {
    uint32_t zmin, zmax, samples, pad;
    uint32_t hist[HIST];
    uint32_t part_count[8];
    uint32_t bounds[8][4];
} depth_stats;

/* A camera cut, for statistics read `latency` frames late: the view turned by more than SDSM_CUT_DEG, or moved by
 * more than SDSM_CUT_DEPTH of its depth range (far - near). Measured on a frame a third of overhangs' path after the
 * statistics' frame (pcf5, warp=tsm): err_rate 0.0107 split by them, 0.0066 split as a first frame is, 0.0048 at
 * latency=0 (docs/techniques.md). */
#define SDSM_CUT_DEG 20.0
#define SDSM_CUT_DEPTH 0.1

typedef struct {
    sb_csm csm;
    int partition, tight, latency;
    sb_camera ring_cam[3];      /* splits=cpu: the camera of each copy in the ring (latency is at most 2) */
    bool gpu;
    double guard;
    GLuint stats;               /* SSBO binding 1 */
    GLuint ring;                /* splits=cpu: latency+1 copies of the statistics */
    GLuint history;             /* splits=gpu: per-frame copy of the cascade block's splits and flags */
    int history_frames;
    GLuint reduce, splits_prog, bounds, matrices;
    GLint r_depth, r_near, r_far;
    GLint s_count, s_partition, s_hist_counts, s_near, s_far;
    GLint b_depth, b_inv, b_light, b_near, b_far;
    GLint m_light, m_eye, m_right, m_up, m_fwd, m_tan, m_lo, m_hi, m_tight, m_res, m_guard, m_near, m_far;
} sdsm_state;

static float unorder(uint32_t u) {
    uint32_t b = (u & 0x80000000u) ? (u & 0x7fffffffu) : ~u;
    float f;
    memcpy(&f, &b, 4);
    return f;
}

/* Partitions of [zmin, zmax] (same algorithm as sdsm_splits.comp). */
void sdsm_partition(int m, int histogram, double zmin, double zmax, double near, double far, const uint32_t *hist,
                    double *s);
void sdsm_partition(int m, int histogram, double zmin, double zmax, double near, double far, const uint32_t *hist,
                    double *s) {
    double la = log(zmin), lb = log(zmax);
    s[0] = zmin;
    s[m] = zmax;
    for (int i = 1; i < m; i++) s[i] = exp(la + (lb - la) * i / m);
    if (!histogram) return;
    double l0 = log(near), w = (log(far) - l0) / HIST, total = 0;
    for (int b = 0; b < HIST; b++)
        if (hist[b]) total += fmax(fmin(l0 + (b + 1) * w, lb) - fmax(l0 + b * w, la), 0);
    if (total <= 0) return;
    for (int i = 1; i < m; i++) {
        double target = total * i / m, acc = 0;
        for (int b = 0; b < HIST; b++) {
            if (!hist[b]) continue;
            double lo = fmax(l0 + b * w, la), len = fmax(fmin(l0 + (b + 1) * w, lb) - lo, 0);
            if (len > 0 && acc + len >= target) {
                s[i] = exp(lo + (target - acc));
                break;
            }
            acc += len;
        }
    }
}

static GLuint compute(const char *label, const char *src, const char *defines, sb_err *err) {
    const char *parts[] = {sb_shader_csm_block_glsl, sb_shader_sdsm_common_glsl, src};
    const sb_shader_src st[] = {{GL_COMPUTE_SHADER, parts, 3}};
    char defs[128];
    snprintf(defs, sizeof defs, "#define SB_CASCADE_STORAGE\n%s", defines ? defines : "");
    return sb_gpu_link(label, defs, st, 1, err);
}

static bool sdsm_check(const void *desc, sb_err *err) {
    const sdsm_desc *d = desc;
    if (d->splits == SPLITS_GPU && d->csm.warp != SB_WARP_NONE)
        return sb_fail(err, "warp= needs splits=cpu (the GPU fits are not warped)");
    if (d->csm.warp != SB_WARP_NONE && d->csm.format != SB_MAP_DEPTH)
        return sb_fail(err, "warp= with a moment format is refused for sdsm (its CPU splits read a frame late: the "
                            "warped, blurred moments had 5-8x the error of unwarped ones on towers; "
                            "docs/techniques.md)");
    if (d->csm.format == SB_MAP_ESM && d->splits == SPLITS_GPU)
        return sb_fail(err, "format=esm needs splits=cpu (the GPU's fits span the scene's whole light depth, over which "
                            "exp(c z) leaks: 5.4x splits=cpu's error on towers; docs/techniques.md)");
    if (d->csm.cache && d->splits == SPLITS_GPU)
        return sb_fail(err, "cache=on needs splits=cpu (the GPU's fits are not seen before the maps are drawn)");
    if (d->csm.stable && d->splits == SPLITS_GPU)
        return sb_fail(err, "stable=on needs splits=cpu (the GPU's fits are tight boxes of this frame's samples, not "
                            "snapped spheres)");
    if (d->csm.fit == SB_FIT_RECEIVERS && d->splits == SPLITS_GPU)
        return sb_fail(err, "fit=receivers needs splits=cpu (the GPU fits its partitions itself: tight=on bounds "
                            "them by their samples)");
    if (d->tight && d->splits != SPLITS_GPU)
        return sb_fail(err, "tight=on needs splits=gpu (the sample bounds depend on this frame's partitions)");
    return sb_csm_check(&d->csm, "", err);
}

static bool sdsm_supported(const sb_run_ctx *rc, const void *desc, sb_err *why) {
    return sb_csm_supported(rc->gpu, desc, "sdsm", why);
}

static bool sdsm_create(void *state, const sb_run_ctx *rc, const void *desc, sb_err *err) {
    sdsm_state *s = state;
    const sdsm_desc *d = desc;
    s->partition = d->partition;
    s->tight = d->tight;
    s->gpu = d->splits == SPLITS_GPU;
    s->latency = d->latency;
    s->guard = d->guard;
    if (!sb_csm_create(&s->csm, rc->gpu, &d->csm, "sdsm", err)) return false;
    const char *rw = "#define SB_CASCADE_ACCESS\n";
    if (!(s->reduce = compute("sdsm reduce", sb_shader_sdsm_reduce_comp, NULL, err))) return false;
    s->r_depth = glGetUniformLocation(s->reduce, "u_depth");
    s->r_near = glGetUniformLocation(s->reduce, "u_near");
    s->r_far = glGetUniformLocation(s->reduce, "u_far");
    if (s->gpu) {
        if (!(s->splits_prog = compute("sdsm splits", sb_shader_sdsm_splits_comp, rw, err))) return false;
        if (!(s->bounds = compute("sdsm bounds", sb_shader_sdsm_bounds_comp, NULL, err))) return false;
        if (!(s->matrices = compute("sdsm matrices", sb_shader_sdsm_matrices_comp, rw, err))) return false;
        s->s_count = glGetUniformLocation(s->splits_prog, "u_count");
        s->s_partition = glGetUniformLocation(s->splits_prog, "u_partition");
        s->s_hist_counts = glGetUniformLocation(s->splits_prog, "u_hist_counts");
        s->s_near = glGetUniformLocation(s->splits_prog, "u_near");
        s->s_far = glGetUniformLocation(s->splits_prog, "u_far");
        s->b_depth = glGetUniformLocation(s->bounds, "u_depth");
        s->b_inv = glGetUniformLocation(s->bounds, "u_inv_view_proj");
        s->b_light = glGetUniformLocation(s->bounds, "u_light_view");
        s->b_near = glGetUniformLocation(s->bounds, "u_near");
        s->b_far = glGetUniformLocation(s->bounds, "u_far");
        const char *names[] = {"u_light_view", "u_eye", "u_right", "u_up", "u_fwd", "u_tan", "u_scene_lo",
                               "u_scene_hi", "u_tight", "u_res", "u_guard", "u_near", "u_far"};
        GLint *locs[] = {&s->m_light, &s->m_eye, &s->m_right, &s->m_up, &s->m_fwd, &s->m_tan, &s->m_lo,
                         &s->m_hi, &s->m_tight, &s->m_res, &s->m_guard, &s->m_near, &s->m_far};
        for (size_t i = 0; i < SB_COUNT(names); i++) *locs[i] = glGetUniformLocation(s->matrices, names[i]);
        s->history_frames = rc->frames > 0 ? rc->frames : 1;
        glGenBuffers(1, &s->history);
        glBindBuffer(GL_COPY_WRITE_BUFFER, s->history);
        glBufferData(GL_COPY_WRITE_BUFFER, (GLsizeiptr)(s->history_frames * sizeof(sb_cascade_splits)), NULL,
                     GL_STREAM_READ);
    } else {
        glGenBuffers(1, &s->ring);
        glBindBuffer(GL_COPY_WRITE_BUFFER, s->ring);
        glBufferData(GL_COPY_WRITE_BUFFER, (GLsizeiptr)(s->latency + 1) * sizeof(depth_stats), NULL, GL_STREAM_READ);
    }
    glGenBuffers(1, &s->stats);
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, s->stats);
    glBufferData(GL_SHADER_STORAGE_BUFFER, sizeof(depth_stats), NULL, GL_DYNAMIC_COPY);
    return sb_gl_check("sdsm", err);
}

static void reset_stats(sdsm_state *s) {
    depth_stats init;
    memset(&init, 0, sizeof init);
    init.zmin = 0xffffffffu;
    for (int k = 0; k < 8; k++) init.bounds[k][0] = init.bounds[k][1] = 0xffffffffu;
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, s->stats);
    glBufferSubData(GL_SHADER_STORAGE_BUFFER, 0, sizeof init, &init);
}

/* The passes over the view's pixels: a group of 8 rows of 64 pixels, a run of
 * 8 an invocation (sdsm_reduce.comp, sdsm_bounds.comp). */
static void dispatch_pixels(const sb_gpu *g) {
    glDispatchCompute((GLuint)(g->width + 63) / 64, (GLuint)(g->height + 7) / 8, 1);
}

/* tight=on: per-partition sample counts and light-space bounds, a second pass over the pixels. */
static void tight_bounds(sdsm_state *s, sb_frame *f, sb_m4 light_view) {
    float m[16];
    sb_m4 inv;
    glUseProgram(s->bounds);
    glUniform1i(s->b_depth, 1);
    sb_m4_invert(f->view_proj, &inv);
    sb_m4_to_float(inv, m);
    glUniformMatrix4fv(s->b_inv, 1, GL_FALSE, m);
    sb_m4_to_float(light_view, m);
    glUniformMatrix4fv(s->b_light, 1, GL_FALSE, m);
    glUniform1f(s->b_near, (float)f->cam.znear);
    glUniform1f(s->b_far, (float)f->cam.zfar);
    dispatch_pixels(f->gpu);
    glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
}

/* splits=gpu: partitions, per-partition counts/bounds and light matrices, all on the GPU. */
static void gpu_splits(sdsm_state *s, sb_frame *f) {
    const sb_gpu *g = f->gpu;
    sb_csm *c = &s->csm;
    float nearf = (float)f->cam.znear, farf = (float)f->cam.zfar;
    glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
    glUseProgram(s->splits_prog);
    glUniform1i(s->s_count, c->count);
    glUniform1i(s->s_partition, s->partition);
    glUniform1i(s->s_hist_counts, !s->tight);
    glUniform1f(s->s_near, nearf);
    glUniform1f(s->s_far, farf);
    glDispatchCompute(1, 1, 1);
    glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);

    sb_m4 light_view = sb_light_view(g->sun);
    float m[16];
    if (s->tight) tight_bounds(s, f, light_view);
    sb_m4_to_float(light_view, m);
    glUseProgram(s->matrices);
    glUniformMatrix4fv(s->m_light, 1, GL_FALSE, m);
    sb_v3 eye = sb_v3_sub(f->cam.pos, g->scene->origin);
    glUniform3f(s->m_eye, (float)eye.x, (float)eye.y, (float)eye.z);
    glUniform3f(s->m_right, (float)f->cam.right.x, (float)f->cam.right.y, (float)f->cam.right.z);
    glUniform3f(s->m_up, (float)f->cam.up.x, (float)f->cam.up.y, (float)f->cam.up.z);
    glUniform3f(s->m_fwd, (float)f->cam.forward.x, (float)f->cam.forward.y, (float)f->cam.forward.z);
    double ty = tan(f->cam.fov_deg * SB_PI / 360);
    glUniform2f(s->m_tan, (float)(ty * f->cam.aspect), (float)ty);
    sb_v3 lo = {1e300, 1e300, 1e300}, hi = {-1e300, -1e300, -1e300};
    for (int k = 0; k < 8; k++) {
        const sb_aabb *b = &g->scene->bounds;
        sb_v3 q = sb_m4_point(light_view, sb_aabb_corner(b, k));
        lo = sb_v3_min(lo, q);
        hi = sb_v3_max(hi, q);
    }
    glUniform3f(s->m_lo, (float)lo.x, (float)lo.y, (float)lo.z);
    glUniform3f(s->m_hi, (float)hi.x, (float)hi.y, (float)hi.z);
    glUniform1i(s->m_tight, s->tight);
    glUniform1f(s->m_res, (float)c->d.res);
    glUniform1f(s->m_guard, (float)(s->tight ? s->guard : 1.0));
    glDispatchCompute(1, 1, 1);
    glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_UNIFORM_BARRIER_BIT | GL_BUFFER_UPDATE_BARRIER_BIT);
    /* keep this frame's splits and flags for the CSV, on the GPU (read after the run) */
    if (f->seq < s->history_frames) {
        glBindBuffer(GL_COPY_READ_BUFFER, c->block);
        glBindBuffer(GL_COPY_WRITE_BUFFER, s->history);
        glCopyBufferSubData(GL_COPY_READ_BUFFER, GL_COPY_WRITE_BUFFER, offsetof(sb_cascade_block, s),
                            (GLintptr)(f->seq * sizeof(sb_cascade_splits)), sizeof(sb_cascade_splits));
    }
}

/* splits=cpu: the statistics of `latency` frames ago, read back now. */
static void cpu_splits(sdsm_state *s, sb_frame *f) {
    sb_csm *c = &s->csm;
    double splits[SB_MAX_CASCADES + 1];
    depth_stats st;
    bool have = f->seq >= s->latency;
    if (have) {
        glBindBuffer(GL_COPY_READ_BUFFER, s->ring);
        glGetBufferSubData(GL_COPY_READ_BUFFER, (GLintptr)((f->seq - s->latency) % (s->latency + 1)) * (GLintptr)sizeof st,
                           sizeof st, &st);
    }
    if (have && s->latency > 0) {   /* statistics of a view this one has cut away from: as if there were none */
        const sb_camera *then = &s->ring_cam[(f->seq - s->latency) % (s->latency + 1)], *now = &f->cam;
        double turn = sb_v3_dot(then->forward, now->forward), moved = sb_v3_len(sb_v3_sub(then->pos, now->pos));
        have = turn >= cos(SDSM_CUT_DEG * SB_PI / 180) && moved <= SDSM_CUT_DEPTH * (now->zfar - now->znear);
    }
    if (have && st.samples == 0) { /* all sky: nothing to shadow */
        for (int k = 0; k <= c->count; k++) splits[k] = f->cam.znear;
    } else if (have) {
        double zmin = unorder(st.zmin), zmax = fmax(unorder(st.zmax), zmin * 1.0001);
        sdsm_partition(c->count, s->partition, zmin, zmax, f->cam.znear, f->cam.zfar, st.hist, splits);
        if (s->latency > 0) {
            /* statistics of an earlier frame: after a camera cut (or a sparse path) this view's pixels may lie
               outside their [z_min, z_max], and a pixel no cascade covers would be lit. The first and last
               cascades reach the view's near and far planes (the fit clips them to the scene), the partition's
               inner splits stay the samples'. */
            splits[0] = fmin(splits[0], f->cam.znear);
            splits[c->count] = fmax(splits[c->count], f->cam.zfar);
        }
    } else { /* before the first readback, or after a cut: the whole view, logarithmically */
        sb_split_distances(1.0, c->count, f->cam.znear, f->cam.zfar, splits);
    }
    sb_csm_fit(c, f, splits);
}

static void sdsm_frame(void *state, sb_frame *f) {
    sdsm_state *s = state;
    const sb_gpu *g = f->gpu;
    sb_csm *c = &s->csm;

    sb_stage_begin(f, &sb_stage_zpass);
    sb_zpass(f);
    sb_stage_end(f, &sb_stage_zpass);

    sb_stage_begin(f, &sb_stage_minmax);
    reset_stats(s);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, c->block);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, s->stats);
    glActiveTexture(GL_TEXTURE1);
    glBindTexture(GL_TEXTURE_2D, g->depth_tex);
    glUseProgram(s->reduce);
    glUniform1i(s->r_depth, 1);
    glUniform1f(s->r_near, (float)f->cam.znear);
    glUniform1f(s->r_far, (float)f->cam.zfar);
    dispatch_pixels(g);
    if (s->gpu) {
        gpu_splits(s, f);
    } else {
        glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
        glBindBuffer(GL_COPY_READ_BUFFER, s->stats);
        glBindBuffer(GL_COPY_WRITE_BUFFER, s->ring);
        glCopyBufferSubData(GL_COPY_READ_BUFFER, GL_COPY_WRITE_BUFFER, 0,
                            (GLintptr)(f->seq % (s->latency + 1)) * (GLintptr)sizeof(depth_stats), sizeof(depth_stats));
        s->ring_cam[f->seq % (s->latency + 1)] = f->cam;
    }
    glActiveTexture(GL_TEXTURE0);
    sb_stage_end(f, &sb_stage_minmax);

    sb_stage_begin(f, &sb_stage_cascade);
    if (s->gpu) {
        /* the GPU's partitions are unknown here: cull against the whole view's light volume */
        sb_v3 corners[8];
        sb_light_fit bound;
        sb_frustum_corners(&f->cam, g->scene->origin, f->cam.znear, f->cam.zfar, corners);
        sb_light_fit_points(g->scene, g->sun, corners, 8, c->d.res, &bound);
        for (int k = 0; k < c->count; k++) c->active[k] = !bound.empty; /* a view without scene: nothing casts */
        sb_csm_cull(c, f, bound.empty ? NULL : &bound);
    } else {
        cpu_splits(s, f);   /* latency=0 waits here for this frame's reduction */
        sb_csm_cull(c, f, NULL);
    }
    sb_csm_render(c, f);
    if (s->gpu) { /* rendered/skipped and splits are known after the run (collect) */
        f->counters.cascades_rendered = f->counters.cascades_skipped = 0;
    }
    sb_stage_end(f, &sb_stage_cascade);

    sb_stage_begin(f, &sb_stage_final);
    sb_csm_final(c, f, true);
    sb_stage_end(f, &sb_stage_final);
}

/* splits=gpu: after the timed frames, one readback of every frame's splits and flags. */
static void sdsm_collect(void *state, int seq, sb_counters *out) {
    sdsm_state *s = state;
    if (!s->gpu || seq >= s->history_frames) return;
    sb_cascade_splits block;
    glBindBuffer(GL_COPY_READ_BUFFER, s->history);
    glGetBufferSubData(GL_COPY_READ_BUFFER, (GLintptr)(seq * sizeof block), sizeof block, &block);
    int rendered = 0;
    out->split_count = s->csm.count;
    for (int k = 0; k < s->csm.count; k++) {
        out->splits[k] = block.cascade[k][1];       /* far split */
        rendered += block.flags[k][0] > 0.5f;       /* rendered */
    }
    out->cascades_rendered = rendered;
    out->cascades_skipped = s->csm.count - rendered;
}

static void sdsm_destroy(void *state) {
    sdsm_state *s = state;
    GLuint progs[] = {s->reduce, s->splits_prog, s->bounds, s->matrices};
    for (size_t i = 0; i < SB_COUNT(progs); i++)
        if (progs[i]) glDeleteProgram(progs[i]);
    GLuint bufs[] = {s->stats, s->ring, s->history};
    for (size_t i = 0; i < SB_COUNT(bufs); i++)
        if (bufs[i]) glDeleteBuffers(1, &bufs[i]);
    sb_csm_destroy(&s->csm);
}

/* splits=cpu uses the statistics of `latency` frames ago; splits=gpu, the frame's own. */
static int sdsm_history(const void *desc) {
    const sdsm_desc *d = desc;
    return d->splits == SPLITS_CPU ? d->latency : 0;
}

const sb_technique sb_technique_sdsm = {
    .name = "sdsm",
    .stress = ";splits=cpu:latency=0",   /* the stability battery's settings */
    .summary = "sample distribution shadow maps (Lauritzen, Salvi & Lefohn 2011)",
    .params = sdsm_params,
    .param_count = (int)SB_COUNT(sdsm_params),
    .desc_size = sizeof(sdsm_desc),
    .desc_defaults = &sdsm_defaults,
    SB_STAGES(&sb_stage_zpass, &sb_stage_minmax, &sb_stage_cascade, &sb_stage_final),
    .needs = SB_NEEDS_SUN,
    .history = sdsm_history,
    .state_size = sizeof(sdsm_state),
    .check = sdsm_check,
    .supported = sdsm_supported,
    .shadow_bytes = sb_csm_technique_shadow_bytes,   /* its maps; the reduction's buffers are a few KiB */
    .create = sdsm_create,
    .frame = sdsm_frame,
    .collect = sdsm_collect,
    SB_CSM_COUNTERS,
    .destroy = sdsm_destroy,
};
