/* session.c - sessions (context, scene, path, GPU buffers) and
 * technique instances rendering a frame: what the run loop, the evaluation and
 * bias=auto render with (session.h). */
#include "session.h"

#include "motion.h"

#include "pathcheck.h"
#include "pose.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <sys/utsname.h>
#include <unistd.h>

#include "image.h"
#include "reference.h"
#include "scene_load.h"

static void base_name(const char *path, char *out, size_t len) {
    const char *b = strrchr(path, '/');
    b = b ? b + 1 : path;
    snprintf(out, len, "%s", b);
    char *dot = strrchr(out, '.');
    if (dot && dot != out && !strchr(dot, '#')) *dot = 0;
}

/* The names the scene and path files give every result (their base names): one line of text each. */
static bool names_check(const char *scene, const char *path, sb_err *err) {
    const char *files[2] = {scene, path};
    for (int i = 0; i < 2; i++) {
        char name[256], what[4400];
        base_name(files[i], name, sizeof name);
        snprintf(what, sizeof what, "%s: its name (the %s column of every result)", files[i], i ? "path" : "scene");
        if (!sb_name_check(what, name, err)) return false;
    }
    return true;
}

/* ---- sessions ---- */

/* The path check (pathcheck.h): its flagged frames in path_note; refused with --strict-path. */
static bool check_path(sb_session *s, sb_err *err) {
    const sb_reference *ref = sb_session_reference(s, err);
    if (!ref) return false;
    int n = s->opts.frames;
    sb_path_frame *f = sb_xmalloc(sizeof *f * (size_t)(n > 0 ? n : 1));
    double t0 = sb_now_ms(), aspect = (double)s->opts.width / s->opts.height;
    int bad = 0;
    if (!sb_scene_moves(&s->scene)) {
        bad = sb_path_check(ref, &s->scene, &s->path, n, aspect, f, s->opts.threads);
    } else {   /* each camera against the scene as it is at that frame's time */
        for (int i = 0; i < n; i++) {
            sb_session_pose(s, sb_session_frame_time(s, i, n));
            if (!(ref = sb_session_reference(s, err))) {
                free(f);
                return false;
            }
            bad += sb_path_check_frames(ref, &s->scene, &s->path, i, 1, n, aspect, f + i, s->opts.threads);
        }
    }
    sb_verbose("path check: %d of %d frame(s) flagged in %.1f ms", bad, n, sb_now_ms() - t0);
    if (bad) sb_path_check_text(f, n, s->path_note, sizeof s->path_note);
    free(f);
    if (bad && s->opts.strict_path) {
        s->files_refused = true;
        return sb_fail(err, "%s: %s (--strict-path)", s->path.file, s->path_note);
    }
    if (bad) sb_log("warning: %s: %s", s->path.file, s->path_note);
    return true;
}

bool sb_session_open(sb_session *s, const sb_run_opts *o, const char *scene, const char *path, sb_err *err) {
    /* files first: a broken scene or path is refused before any GL is touched */
    sb_scene sc;
    sb_path p;
    sb_scene_opts so = sb_run_scene_opts(o);
    s->files_refused = true;
    if (!names_check(scene, path, err) || !sb_scene_load(&sc, scene, &so, err)) return false;
    if (!sb_path_load(&p, path, &sc, err)) {
        sb_scene_free(&sc);
        return false;
    }
    sb_light_set lights = {0};
    if (o->lights && !sb_scene_light_set(&sc, o->lights, sc.has_sun || o->sun_override, &lights, err)) {
        char why[sizeof err->msg];
        memcpy(why, err->msg, sizeof why);
        sb_fail(err, "%s: %.*s", scene, (int)(sizeof why / 2), why);
        sb_scene_free(&sc);
        sb_path_free(&p);
        return false;
    }
    const char *lights_name = o->lights ? sb_lights_name(&sc, &lights) : NULL;
    if (!sb_session_attach(s, o, &sc, &p, err)) return false;
    s->lights = lights;
    s->opts.lights = lights_name;   /* one name a set: its run ids and its light column */
    base_name(scene, s->scene_name, sizeof s->scene_name);
    base_name(path, s->path_name, sizeof s->path_name);
    return true;
}


bool sb_session_clocks(sb_session *s, const sb_run_opts *o, sb_err *err) {
    if (s->clocks) return true;
    s->clocks = sb_clocks_open(&s->ctx, "/sys");
    return sb_clocks_apply(s->clocks, o->clocks, s->clocks_mode, sizeof s->clocks_mode, err);
}

bool sb_session_attach(sb_session *s, const sb_run_opts *o, sb_scene *scene, sb_path *path, sb_err *err) {
    bool have_ctx = s->ctx.renderer[0] != 0;
    sb_context keep = s->ctx;
    sb_clocks *clocks = s->clocks;
    char mode[sizeof s->clocks_mode];
    memcpy(mode, s->clocks_mode, sizeof mode);
    memset(s, 0, sizeof *s);
    s->opts = *o;
    s->scene = *scene;
    s->path = *path;
    memset(scene, 0, sizeof *scene);
    memset(path, 0, sizeof *path);
    if (have_ctx) {
        s->ctx = keep;
        s->clocks = clocks;
        memcpy(s->clocks_mode, mode, sizeof mode);
    }
    if ((!have_ctx && !sb_context_create(&s->ctx, o->backend, err)) || !sb_session_clocks(s, o, err)) {
        sb_session_close_scene(s);
        return false;
    }
    s->ctx.memory_limit = o->gpu_memory;
    sb_v3 sun = s->scene.has_sun ? s->scene.sun : sb_sun_dir(135, 40);
    if (o->sun_override) sun = sb_sun_dir(o->sun_az, o->sun_el);
    double t0 = sb_now_ms();
    if (!sb_gpu_init(&s->gpu, &s->ctx, &s->scene, o->width, o->height, sun, err)) {
        sb_session_close_scene(s);
        return false;
    }
    glFinish();
    s->gpu_upload_ms = sb_now_ms() - t0;
    s->gpu.has_sun = s->scene.has_sun || o->sun_override;
    s->scratch = sb_xcalloc(s->scene.draw_count + 1, sizeof(uint32_t));
    s->gpu.indirect = o->submit == SB_SUBMIT_INDIRECT;
    if (s->gpu.indirect) s->cmds = sb_xcalloc(5 * ((size_t)s->scene.draw_count + 1), sizeof(uint32_t));
    s->tech_data = sb_xcalloc((size_t)sb_technique_count(), sizeof *s->tech_data);
    s->tech_loaded = sb_xcalloc((size_t)sb_technique_count(), sizeof *s->tech_loaded);
    s->timing = o->timing;
    if (s->timing == SB_TIMING_AUTO) s->timing = s->ctx.software ? SB_TIMING_SYNC : SB_TIMING_QUERIES;
    if (s->timing == SB_TIMING_QUERIES && !s->ctx.has_timer_query) {
        sb_log("note: %s has no timer queries; using sync timing", s->ctx.renderer);
        s->timing = SB_TIMING_SYNC;
    }
    if (!sb_calib_init(&s->calib, &s->ctx, s->timing == SB_TIMING_QUERIES, err)) {
        sb_session_close_scene(s);
        return false;
    }
    /* the path's cameras against the scene, with the reference the evaluation builds anyway (its kept answers
       are loaded when sb_session_keep_reference names their folder) */
    if ((o->error_every > 0 || o->strict_path) && !check_path(s, err)) {
        bool refused = s->files_refused;
        sb_session_close_scene(s);
        s->files_refused = refused;
        return false;
    }
    return true;
}

/* The file of the scene's kept answers and the tag they are kept under. */
static bool ref_store_file(const sb_session *s, char *out, size_t len, uint64_t *tag) {
    if (!s->ref_store[0]) return false;
    uint64_t v[3] = {s->scene.content_hash, sb_binary_identity(), 1 /* format */};
    *tag = sb_fnv1a(SB_FNV_SEED, v, sizeof v);
    return (size_t)snprintf(out, len, "%s/%016llx.ref", s->ref_store, (unsigned long long)*tag) < len;
}

void sb_session_keep_reference(sb_session *s, const char *results_dir) {
    const char *slash = strrchr(results_dir, '/');
    int n = slash ? (int)(slash - results_dir) : 0;
    snprintf(s->ref_store, sizeof s->ref_store, "%.*s%s.reference", n, results_dir, slash ? "/" : "");
    char file[4200];
    uint64_t tag;   /* the reference is built already (the path check): its kept answers come in now */
    if (s->ref_cache && ref_store_file(s, file, sizeof file, &tag)) sb_ref_cache_load(s->ref_cache, file, tag);
}

void sb_session_close_scene(sb_session *s) {
    char file[4200];
    uint64_t tag;
    if (s->ref_cache) sb_ref_background_stop(s->ref_cache); /* before the reference it casts with goes */
    if (sb_ref_cache_dirty(s->ref_cache) && ref_store_file(s, file, sizeof file, &tag)) {
        sb_err e;
        if (!sb_mkdir_p(s->ref_store, &e)) sb_cache_unkept("the reference's answers", e.msg);
        else sb_ref_cache_save(s->ref_cache, file, tag, &e);   /* a cache: its save warns (once) itself */
    }
    for (int i = 0; s->tech_loaded && i < sb_technique_count(); i++)
        if (s->tech_loaded[i] && sb_technique_at(i)->unload) sb_technique_at(i)->unload(s->tech_data[i]);
    free(s->tech_data);
    free(s->tech_loaded);
    s->tech_data = NULL;
    s->tech_loaded = NULL;
    if (s->ref) {
        sb_reference_free(s->ref);
        free(s->ref);
        s->ref = NULL;
    }
    sb_ref_cache_free(s->ref_cache);
    s->ref_cache = NULL;
    free(s->scratch);
    free(s->cmds);
    s->scratch = s->cmds = NULL;
    sb_calib_free(&s->calib);
    sb_gpu_free(&s->gpu);
    sb_path_free(&s->path);
    sb_scene_free(&s->scene);
}

void sb_session_close(sb_session *s) {
    sb_session_close_scene(s);
    sb_clocks_close(s->clocks);
    sb_context_destroy(&s->ctx);
    memset(s, 0, sizeof *s);
}

void sb_session_set_light_size(sb_session *s, double sun_size, double lamp_radius, int ref_samples) {
    s->opts.sun_size = sun_size;
    s->opts.lamp_radius = lamp_radius;
    s->opts.ref_samples = ref_samples;
    if (s->ref) sb_reference_set_light_size(s->ref, sun_size, lamp_radius, ref_samples);
}

const sb_reference *sb_session_reference(sb_session *s, sb_err *err) {
    if (s->ref) {
        sb_reference_update(s->ref);   /* the pose the scene holds now (nothing for a still scene) */
        return s->ref;
    }
    sb_reference *r = sb_xcalloc(1, sizeof *r);
    if (!sb_reference_build(r, &s->scene, err)) {
        free(r);
        return NULL;
    }
    sb_reference_set_light_size(r, s->opts.sun_size, s->opts.lamp_radius, s->opts.ref_samples);
    s->ref = r;
    s->ref_cache = sb_ref_cache_new(SB_REF_CACHE_BYTES);
    char file[4200];
    uint64_t tag;
    if (ref_store_file(s, file, sizeof file, &tag)) sb_ref_cache_load(s->ref_cache, file, tag);
    return r;
}

/* What the technique's load step made for this scene (made on first use). */
static bool scene_data(sb_session *s, const sb_technique *t, void **out, sb_err *err) {
    int i = sb_technique_index(t);
    *out = NULL;
    if (!t->load || i < 0) return true;
    if (!s->tech_loaded[i]) {
        s->tech_loaded[i] = true;   /* unload frees whatever a failed load left */
        if (!t->load(&s->gpu, &s->tech_data[i], err)) return false;
    }
    *out = s->tech_data[i];
    return true;
}

double sb_session_shadow_bytes(const sb_session *s, const sb_run_spec *rs) {
    double bytes = sb_spec_shadow_bytes(rs);
    return rs->tech->lights == SB_LIGHTS_LAMPS && s->lights.count ? bytes * s->lights.count : bytes;   /* a set each */
}

const char *sb_lights_name(const sb_scene *sc, const sb_light_set *set) {
    char text[8 * SB_MAX_LIGHTS];
    sb_light_set_text(sc, set, text, sizeof text);
    return sb_intern(text);
}

bool sb_spec_lights_check(const sb_scene *sc, const sb_run_spec *rs, const char *lights, sb_err *err) {
    int lamps = 0;
    sb_scene_point_light(sc, 0, &lamps);
    for (int i = 0; i < rs->params.count; i++) {
        if (strcmp(rs->params.v[i].def->name, "light") || !rs->params.v[i].given) continue;
        const char *k = rs->params.v[i].text, *t = rs->tech->name;
        if (lights)
            return sb_fail(err, "%s:light=%s with --lights %s: both say which lights the run shadows; give one of them", t,
                           k, lights);
        if (rs->params.v[i].num >= lamps)
            return lamps ? sb_fail(err, "%s:light=%s: the scene has no lamp %s (its point and spot lights are 0..%d)", t, k,
                                   k, lamps - 1)
                         : sb_fail(err, "%s:light=%s: the scene has no point or spot light", t, k);
    }
    return true;
}

void sb_session_light_label(const sb_session *s, char *out, size_t len) {
    const sb_run_opts *o = &s->opts;
    out[0] = 0;
    if (o->sun_size > 0 || o->lamp_radius > 0) {
        char sun[40] = "", lamp[40] = "";
        if (o->sun_size > 0) snprintf(sun, sizeof sun, "sun %g deg, ", o->sun_size);
        if (o->lamp_radius > 0) snprintf(lamp, sizeof lamp, "lamp %g, ", o->lamp_radius);
        snprintf(out, len, "%s%s%d rays", sun, lamp, o->ref_samples);
    }
    if (s->lights.count) {
        size_t used = strlen(out);
        snprintf(out + used, len - used, "%slights %s (%d)", used ? "; " : "", o->lights, s->lights.count);
    }
}

bool sb_session_set_lights(sb_session *s, const char *spec, sb_err *err) {
    s->opts.lights = spec;
    memset(&s->lights, 0, sizeof s->lights);
    if (!spec) return true;
    if (!sb_scene_light_set(&s->scene, spec, s->gpu.has_sun, &s->lights, err)) return false;
    s->opts.lights = sb_lights_name(&s->scene, &s->lights);
    return true;
}

/* ---- why a run cannot apply ---- */

/* The lights a technique's run shadows: --lights, or for one that shadows every lamp by default, every lamp. */
static const sb_light_set *instance_lights(sb_session *s, const sb_technique *t) {
    if (s->lights.count) return &s->lights;
    if (t->lights != SB_LIGHTS_EVERY_LAMP) return NULL;
    sb_err e;
    if (!s->every_lamp.count && !sb_scene_light_set(&s->scene, "lamps", false, &s->every_lamp, &e)) return NULL;
    return &s->every_lamp;
}

static const char *scene_skip_reason(sb_session *s, const sb_technique *t) {
    if (t->needs & SB_NEEDS_PLANE) sb_scene_find_planes(&s->scene);   /* searched on the first need */
    const sb_scene *sc = &s->scene;
    int points = 0, spots = 0;
    for (uint32_t i = 0; i < sc->light_count; i++) {
        points += sc->lights[i].type == SB_LIGHT_POINT;
        spots += sc->lights[i].type == SB_LIGHT_SPOT;
    }
    if (sc->degenerate[0]) {
        snprintf(s->skip, sizeof s->skip, "the scene is degenerate: %s", sc->degenerate);
        return s->skip;
    }
    if ((t->needs & SB_NEEDS_SUN) && !sc->has_sun && points + spots && !s->opts.sun_override) {
        char lamps[96];
        if (points && spots) snprintf(lamps, sizeof lamps, "%d point and %d spot light(s)", points, spots);
        else snprintf(lamps, sizeof lamps, "%d %s light(s)", points + spots, points ? "point" : "spot");
        snprintf(s->skip, sizeof s->skip, "the scene is lit only by %s, no sun; --sun AZ,EL adds one", lamps);
        return s->skip;
    }
    if ((t->needs & SB_NEEDS_PLANE) && sc->plane_count == 0) return "the scene has no large planar receiver";
    if ((t->needs & SB_NEEDS_POINT_LIGHT) && !(points + spots)) return "the scene has no point or spot light";
    for (int i = 0; i < s->lights.count; i++) {
        bool sun = s->lights.idx[i] == SB_LIGHT_SUN;
        bool lamps = t->lights == SB_LIGHTS_LAMPS || t->lights == SB_LIGHTS_EVERY_LAMP;
        if (t->lights == SB_LIGHTS_ANY || lamps != sun) continue;
        snprintf(s->skip, sizeof s->skip, "%s shadows %s; --lights %s names %s", t->name,
                 lamps ? "point and spot lights" : "the sun alone", s->opts.lights,
                 sun ? "the sun" : "a lamp");
        return s->skip;
    }
    return NULL;
}

const char *sb_skip_reason(sb_session *s, const sb_technique *t, const sb_run_spec *spec) {
    const char *why = scene_skip_reason(s, t);
    if (why || !t->supported) return why;
    sb_run_spec *defaults = NULL;
    if (!spec) {
        defaults = sb_xmalloc(sizeof *defaults);
        sb_spec_defaults(defaults, t);
        spec = defaults;
    }
    sb_run_ctx rc = {.gpu = &s->gpu, .tech = t, .lights = instance_lights(s, t)};
    sb_err e;
    bool ok = t->supported(&rc, spec->desc, &e);
    free(defaults);
    if (ok) return NULL;
    snprintf(s->skip, sizeof s->skip, "%s", e.msg);
    return s->skip;
}

/* ---- instances and frames ---- */

/* The run's shadow range (sb_run_ctx): over the path's frames, the nearest near plane and the farthest far plane,
 * the far end clamped to the farthest corner of the scene's box from any of the cameras. */
static void shadow_range(const sb_session *s, double *near, double *far) {
    const sb_scene *sc = &s->scene;
    int n = s->opts.frames > 0 ? s->opts.frames : 1;
    double aspect = (double)s->opts.width / s->opts.height, zn = INFINITY, zf = 0, reach = 0;
    for (int i = 0; i < n; i++) {
        sb_camera cam = sb_path_camera(&s->path, i, n, aspect, sc);
        zn = fmin(zn, cam.znear);
        zf = fmax(zf, cam.zfar);
        sb_v3 eye = sb_v3_sub(cam.pos, sc->origin);
        for (int k = 0; k < 8; k++) {
            sb_v3 q = sb_aabb_corner(&sc->bounds, k);
            reach = fmax(reach, sb_v3_len(sb_v3_sub(q, eye)));
        }
    }
    *near = isfinite(zn) ? zn : 0;
    *far = reach > *near ? fmin(zf, reach) : zf;
}

bool sb_instance_create(sb_instance *in, sb_session *s, const sb_run_spec *spec, int frames, sb_err *err) {
    const sb_technique *t = spec->tech;
    memset(in, 0, sizeof *in);
    for (int i = 0; i < spec->params.count; i++)
        if (spec->params.v[i].automatic)
            return sb_fail(err, "%s:%s=auto: only run, batch and tune calibrate auto values", t->name,
                           spec->params.v[i].def->name);
    in->tech = t;
    in->spec = sb_xmalloc(sizeof *in->spec);
    *in->spec = *spec;
    in->desc = in->spec->desc;
    in->rc = (sb_run_ctx){.gpu = &s->gpu, .tech = t, .frames = frames, .lights = instance_lights(s, t)};
    shadow_range(s, &in->rc.shadow_near, &in->rc.shadow_far);
    if (t->needs & SB_NEEDS_PLANE) sb_scene_find_planes(&s->scene);   /* on the first need, not at load */
    /* shared geometry the technique cannot draw shared (render.h): copies uploaded now, not in a timed frame */
    if (t->needs & (SB_NEEDS_PLANE | SB_NEEDS_POINT_LIGHT)) sb_gpu_share(&s->gpu, t->needs & SB_NEEDS_PLANE);
    bool ok = !t->supported || t->supported(&in->rc, in->desc, err);
    if (ok) ok = scene_data(s, t, &in->rc.scene_data, err);
    if (ok && (t->needs & SB_NEEDS_REFERENCE)) ok = (in->rc.reference = sb_session_reference(s, err)) != NULL;
    if (ok) {
        in->state = sb_xcalloc(1, t->state_size ? t->state_size : 1);
        ok = t->create(in->state, &in->rc, in->desc, err);
    }
    if (!ok) {
        sb_instance_destroy(in);
        sb_gl_drain_errors();
    }
    return ok;
}

int sb_instance_history(const sb_instance *in) { return in->tech->history ? in->tech->history(in->desc) : 0; }

void sb_instance_destroy(sb_instance *in) {
    if (in->state) in->tech->destroy(in->state);
    free(in->state);
    free(in->seen);
    free(in->moved);
    free(in->moved_from);
    in->seen = NULL, in->moved = NULL, in->moved_from = NULL;
    free(in->spec);
    in->spec = NULL;
    in->state = in->desc = NULL;
}

double sb_session_frame_time(const sb_session *s, int i, int n) {
    return sb_path_progress(i, n) * sb_path_duration(&s->path);
}

double sb_session_pose(sb_session *s, double t) {
    if (!sb_scene_moves(&s->scene)) return NAN;
    double t0 = sb_now_ms(), speed = s->scene.opts.anim_speed > 0 ? s->scene.opts.anim_speed : 1;
    if (sb_scene_pose(&s->scene, t * speed)) sb_gpu_update_motion(&s->gpu);
    return sb_now_ms() - t0;
}

/* What moved since the instance's previous frame: the draws whose box changed, with their boxes then. */
static void motion_since(const sb_session *s, sb_instance *in, sb_frame *f) {
    const sb_scene *sc = &s->scene;
    f->counters.moving = true;
    if (!in->seen) {   /* its first frame: nothing it holds can be stale */
        in->seen = sb_xmalloc(sizeof *in->seen * (sc->draw_count + 1));
        in->moved = sb_xmalloc(sizeof *in->moved * (sc->draw_count + 1));
        in->moved_from = sb_xmalloc(sizeof *in->moved_from * (sc->draw_count + 1));
        for (uint32_t d = 0; d < sc->draw_count; d++) in->seen[d] = sc->draws[d].box;
        in->seen_serial = sc->pose_serial;
    }
    uint32_t n = 0;
    if (in->seen_serial != sc->pose_serial)
        for (uint32_t d = 0; d < sc->draw_count; d++) {
            if (sc->draws[d].motion == SB_DRAW_STILL || !memcmp(&in->seen[d], &sc->draws[d].box, sizeof in->seen[d]))
                continue;
            in->moved[n] = d, in->moved_from[n++] = in->seen[d];
            in->seen[d] = sc->draws[d].box;
        }
    in->seen_serial = sc->pose_serial;
    f->moved = in->moved, f->moved_from = in->moved_from, f->moved_count = n;
    f->counters.casters_moved = (int)n;
}

void sb_render_camera(sb_session *s, sb_instance *in, sb_frame *f, const sb_camera *cam, int seq, sb_timer *timer,
                      bool eval) {
    sb_render_camera_jittered(s, in, f, cam, seq, timer, eval, 0, 0);
}

void sb_render_camera_jittered(sb_session *s, sb_instance *in, sb_frame *f, const sb_camera *cam, int seq,
                               sb_timer *timer, bool eval, double jx, double jy) {
    f->timer = timer;
    f->seq = seq;
    sb_frame_setup(f, &s->gpu, cam);
    f->counters.own_defs = in->tech->counters;   /* the technique's own counters (sb_technique.counters) */
    f->counters.own_count = in->tech->counter_count;
    if (jx != 0 || jy != 0) sb_frame_jitter(f, jx, jy);
    f->scratch = s->scratch;
    f->cmds = s->cmds;
    f->eval = eval;
    if (sb_pose_pending(s->gpu.pose, s->gpu.scene)) {   /* the pose's GPU pass, in the first frame drawn at it */
        sb_stage_begin(f, &sb_stage_pose);
        sb_pose_run(s->gpu.pose, s->gpu.scene, s->gpu.vbo);
        sb_stage_end(f, &sb_stage_pose);
    }
    if (sb_scene_moves(&s->scene)) {
        motion_since(s, in, f);
        if ((in->tech->needs & SB_NEEDS_REFERENCE) && s->ref) sb_reference_update(s->ref);   /* raycast's rays */
    }
    in->tech->frame(in->state, f);
}

void sb_render_frame(sb_session *s, sb_instance *in, sb_frame *f, int i, int n, int seq, sb_timer *timer) {
    f->anim_ms = sb_session_pose(s, sb_session_frame_time(s, i, n));
    sb_camera cam = sb_path_camera(&s->path, i, n, (double)s->opts.width / s->opts.height, &s->scene);
    f->index = i;
    f->progress = sb_path_progress(i, n);
    sb_render_camera(s, in, f, &cam, seq, timer, false);
}

static void cpu_model(char *out, size_t len) {
    snprintf(out, len, "unknown");
    FILE *f = fopen("/proc/cpuinfo", "r");
    if (!f) return;
    char line[512];
    while (fgets(line, sizeof line, f))
        if (!strncmp(line, "model name", 10)) {
            char *colon = strchr(line, ':');
            if (colon) {
                snprintf(out, len, "%s", colon + 2);
                out[strcspn(out, "\n")] = 0;
            }
            break;
        }
    fclose(f);
}

static const char *g_build = "";
void sb_session_set_build(const char *options) { g_build = options ? options : ""; }

bool sb_session_write_meta(const sb_session *s, const char *dir, const char *command_line, const char *version,
                           const char *commit, const char *extra, sb_err *err) {
    char buf[12288], cpu[256], date[64], host[256] = "unknown", clocks[1024];
    cpu_model(cpu, sizeof cpu);
    struct utsname u;
    uname(&u);
    if (gethostname(host, sizeof host - 1)) snprintf(host, sizeof host, "unknown");
    time_t now = time(NULL);
    struct tm tm;
    gmtime_r(&now, &tm);
    strftime(date, sizeof date, "%Y-%m-%dT%H:%M:%SZ", &tm);
    sb_clocks_describe(s->clocks, clocks, sizeof clocks);
    const sb_context *ctx = &s->ctx;
    int n = snprintf(buf, sizeof buf,
                     "command: %s\nversion: %s\ncommit: %s\nbuild: %s\ndate: %s\nhost: %s\n%s"
                     "backend: %s (%s)\ngl_vendor: %s\ngl_renderer: %s\ngl_version: %s\ncpu: %s\ncores: %ld\n"
                     "kernel: %s %s %s\n%s",
                     command_line, version, commit, g_build, date, host, extra ? extra : "", sb_backend_name(ctx->backend),
                     ctx->device, ctx->vendor, ctx->renderer, ctx->version, cpu, sysconf(_SC_NPROCESSORS_ONLN),
                     u.sysname, u.release, u.machine, clocks);
    char path[4200];
    snprintf(path, sizeof path, "%s/meta", dir);
    return sb_write_file_atomic(path, buf, (size_t)(n < (int)sizeof buf ? n : (int)sizeof buf - 1), err);
}
