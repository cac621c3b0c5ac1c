/* run.c - the timed frame loop: a run's passes, its evaluation and its rows. */
#include "run.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "autobias.h"
#include "options.h"
#include "eval.h"
#include "evaluate.h"
#include "pose.h"
#include "reference.h"
#include "columns.h"
#include "stability.h"
#include "stats.h"

/* ---- run ids ---- */

void sb_session_run_id(const sb_session *s, const sb_run_spec *spec, char out[17]) {
    sb_run_spec as_run = *spec;   /* the id of the run sb_run_begin makes of it */
    sb_spec_light_size(&as_run, s->opts.sun_size);
    sb_run_id(s->scene.content_hash, s->path.content_hash, &s->opts, &as_run, out);
}

static void progress_line(const sb_session *s, int index, int total, const char *tech, int frame, int frames,
                          double t0) {
    if (!s->opts.progress) return;
    double el = (sb_now_ms() - t0) / 1e3;
    double eta = frame > 0 ? el / frame * (frames - frame) : 0;
    fprintf(stderr, "\rrun %d/%d %-10s frame %d/%d  %.1fs  ETA %.1fs   ", index + 1, total, tech, frame, frames, el,
            eta);
    if (frame == frames) fputc('\n', stderr);
}

/* ---- one run: passes of the path ---- */

struct sb_run {
    sb_session *s;
    bool writes_failed_before;  /* a result write had failed before this run began (sb_result_writes_failed) */
    const sb_run_spec *spec;    /* &own */
    sb_run_spec own;            /* the spec as run: a technique's sun_size follows --sun-size (sb_spec_light_size) */
    sb_run_spec used;           /* spec with its "auto" values chosen (autobias.h) */
    bool calibrated;
    sb_summary *sum;
    char run_id[17], params[SB_PARAMS_TEXT_LEN], csv_path[4096], out_dir[4096];
    sb_run_info info;
    sb_instance in;
    bool have_instance, keep_instance;   /* matrix order: one instance for every repetition */
    int seq;                    /* the instance's next frame sequence number (warm-up frames first) */
    sb_timer timer;             /* the measured frames: repetition r's frame j at r*N + j */
    sb_frame_rec *recs;
    int capacity, done, written, repeats;
    int warmup_frames;          /* warm-up frames rendered, every pass */
    double calib_before, calib_after;
    sb_csv rows;
    sb_csv_file cf;
    bool failed, finished;
    bool interrupted;           /* stopped by SIGINT/SIGTERM: its row says `interrupted` */
    double t_run;
    sb_err err;
};

/* The stages a run's frames may time: its technique's, and the posing pass where the GPU poses a moving scene (none
 * for a technique that times nothing: another renderer's frames). */
static unsigned run_stages(const sb_run *r) {
    const unsigned own = sb_technique_stage_mask(r->spec->tech);
    return own ? own | (r->s->gpu.pose ? SB_STAGE_BIT(sb_stage_slot(&sb_stage_pose)) : 0) : 0;
}

static bool fail_run(sb_run *r, const char *fmt, const char *what) {
    char copy[sizeof r->err.msg];   /* `what` is often r->err.msg itself: formatting it into itself lost it */
    snprintf(copy, sizeof copy, "%s", what);
    if (!r->failed) sb_fail(&r->err, fmt, copy);
    r->failed = true;
    return false;
}

/* The stop a signal asked for, at a frame boundary: the run ends `interrupted`. */
static bool interrupt_run(sb_run *r, const char *where) {
    if (!sb_interrupted() || r->failed) return false;
    char what[160];
    snprintf(what, sizeof what, "interrupted by %s %s", sb_interrupt_name(), where);
    r->interrupted = true;
    fail_run(r, "%s", what);
    return true;
}

static bool ensure_instance(sb_run *r) {
    if (r->have_instance) return true;
    const sb_run_opts *o = &r->s->opts;
    int frames = (o->warmup < 0 ? SB_WARMUP_AUTO_CAP : o->warmup) + o->frames * (r->keep_instance ? r->capacity / o->frames : 1);
    /* and the evaluation pass's (what a technique keeps per frame, sdsm's splits, covers them too) */
    frames += sb_evaluate_frames(o);
    if (!r->calibrated) { /* once per run, before its first frame */
        if (!sb_autobias_choose(r->s, r->spec, &r->used, r->info.auto_params, sizeof r->info.auto_params, NULL, &r->err))
            return fail_run(r, "auto offsets: %s", r->err.msg);
        r->calibrated = true;
    }
    if (!sb_instance_create(&r->in, r->s, &r->used, frames, &r->err)) return fail_run(r, "%s", r->err.msg);
    r->have_instance = true;
    r->seq = 0;
    return true;
}

static void drop_instance(sb_run *r) {
    if (!r->have_instance) return;
    sb_instance_destroy(&r->in);
    r->have_instance = false;
}

/* One warm-up frame: rendered and finished (its time is GPU-bound); returns that time. */
static double warm_frame(sb_run *r, sb_timer *wt, int k) {
    sb_session *s = r->s;
    double w0 = sb_now_ms();
    sb_timer_frame_begin(wt, k);
    sb_frame f;
    memset(&f, 0, sizeof f);
    int pf = s->opts.warmup < 0 ? 0 : k % s->opts.frames;   /* auto: the same frame, so times compare */
    sb_render_frame(s, &r->in, &f, pf, s->opts.frames, r->seq++, wt);
    sb_timer_frame_end(wt);
    glFinish();
    double ms = sb_now_ms() - w0;
    r->info.frames_wall_ms += ms; /* warm-up frames render too */
    return ms;
}

/* Warm-up: --warmup N frames replaying the path's first frames, or (auto, N < 0)
 * the path's first frame until the GPU has been busy long enough and the last
 * frames' times (and clocks, where readable) agree; capped. */
static void warm_up(sb_run *r) {
    sb_session *s = r->s;
    const bool hw = !s->ctx.software;
    const int fixed = s->opts.warmup;
    const int window = hw ? 5 : 4, cap = hw ? SB_WARMUP_AUTO_CAP : 30;
    const double min_busy = hw ? 300 : 0, tol = hw ? 0.03 : 0.10, cap_ms = 5000;
    sb_timer wt;
    sb_timer_init(&wt, s->timing, s->opts.ring, fixed >= 0 ? (fixed ? fixed : 1) : cap);
    double t[SB_WARMUP_AUTO_CAP], mhz[SB_WARMUP_AUTO_CAP], busy = 0, t0 = sb_now_ms();
    int k = 0;
    for (; fixed >= 0 ? k < fixed : k < cap; k++) {
        if (sb_interrupted()) break;
        t[k] = warm_frame(r, &wt, k);
        mhz[k] = sb_clocks_mhz(s->clocks);
        busy += t[k];
        if (fixed >= 0 || k + 1 < window || busy < min_busy) continue;
        double lo = 1e300, hi = 0, clo = 1e300, chi = 0;
        for (int i = k + 1 - window; i <= k; i++) {
            lo = fmin(lo, t[i]), hi = fmax(hi, t[i]);
            clo = fmin(clo, mhz[i]), chi = fmax(chi, mhz[i]);
        }
        bool times_agree = hi - lo <= tol * lo;
        bool clocks_agree = isnan(mhz[k]) || chi - clo <= 0.02 * clo;
        if ((times_agree && clocks_agree) || sb_now_ms() - t0 > cap_ms) {
            k++;
            break;
        }
    }
    sb_timer_drain(&wt);
    sb_timer_free(&wt);
    r->warmup_frames += k;
}

static void record_frame(sb_run *r, int i, int pf, const sb_frame *f, double wall_ms) {
    sb_frame_rec *rec = &r->recs[i];
    rec->frame = pf;
    rec->repeat = i / r->s->opts.frames;
    rec->seq = f->seq;
    rec->progress = f->progress;
    rec->counters = f->counters;
    rec->wall_ms = wall_ms;
    rec->cpu_ms = wall_ms - r->timer.wait_ms;
    rec->anim_ms = f->anim_ms;
    sb_clock_sample cs;
    sb_clocks_sample(r->s->clocks, &cs);
    rec->gpu_clock_mhz = cs.gfx_mhz;
    rec->throttle = cs.throttle;
    rec->start_s = (f->start_ms - sb_process_start_ms()) / 1e3;
    r->info.frames_wall_ms += wall_ms;
    r->done = i + 1;
}

/* The measured frames of repetition `rep`; false on failure (r->err). */
static bool measured_frames(sb_run *r, int rep, int index, int total) {
    sb_session *s = r->s;
    const sb_run_opts *o = &s->opts;
    const int N = o->frames;
    s->timed = true;
    sb_ref_background_timed(s->ref_cache, true);
    for (int j = 0; j < N; j++) {
        int i = rep * N + j;
        double w0 = sb_now_ms();
        sb_timer_frame_begin(&r->timer, i);
        sb_frame f;
        memset(&f, 0, sizeof f);
        f.start_ms = w0;
        sb_render_frame(s, &r->in, &f, j, N, r->seq++, &r->timer);
        sb_timer_frame_end(&r->timer);
        record_frame(r, i, j, &f, sb_now_ms() - w0);
        progress_line(s, index, total, r->spec->tech->name, j + 1, N, r->t_run);
        if (j + 1 < N && sb_interrupted()) {   /* the where is formatted only then: nothing more a frame */
            char where[64];
            snprintf(where, sizeof where, "after frame %d of %d", i + 1, r->capacity);
            if (interrupt_run(r, where)) {
                sb_timer_drain(&r->timer);
                s->timed = false;
                sb_ref_background_timed(s->ref_cache, false);
                return false;
            }
        }
        if (o->run_timeout_s > 0 && sb_now_ms() - r->t_run > o->run_timeout_s * 1e3) {
            char what[128];
            snprintf(what, sizeof what, "the run took longer than %g s (frame %d of %d)", o->run_timeout_s, i + 1,
                     r->capacity);
            s->timed = false;
            sb_ref_background_timed(s->ref_cache, false);
            return fail_run(r, "timeout: %s", what);
        }
    }
    sb_timer_drain(&r->timer); /* between repetitions, never inside a frame */
    s->timed = false;
    sb_ref_background_timed(s->ref_cache, false);
    if (r->spec->tech->collect)
        for (int j = 0; j < N; j++) r->spec->tech->collect(r->in.state, r->recs[rep * N + j].seq, &r->recs[rep * N + j].counters);
    return true;
}

/* A technique that declares no stage (another renderer's frames): nothing to time, the path's frames recorded
 * untimed (no timings or counts), the evaluation pass to fill their errors. */
static bool untimed_frames(sb_run *r) {
    const int N = r->s->opts.frames;
    for (int j = 0; j < N; j++) {
        sb_frame_rec *rec = &r->recs[j];
        rec->frame = j;
        rec->progress = sb_path_progress(j, N);
        rec->untimed = true;
        rec->start_s = rec->gpu_clock_mhz = rec->cpu_ms = rec->wall_ms = rec->anim_ms = NAN;
    }
    r->done = N;
    r->repeats = 1;
    return true;
}

/* The test seam SB_REPLAY_FRAME_MS: each measured frame of [first, r->done) has its stage times scaled so that its
 * gpu_ms is the file's cost for the run's setting within +-2 % (a fixed jitter by run id and frame), so that tests
 * of what tune decides from frame times (test_tune) hold it to exact costs whatever runs beside them. The file's
 * lines are "TECHNIQUE[:ITEM...] MS" ('#' a comment): the first whose technique is the run's and whose items are
 * all among its parameters wins; no line, the measured times stand. False: a failed run (the file unreadable or a
 * line malformed). */
static bool replayed_frame_costs(sb_run *r, int first) {
    const char *file = getenv("SB_REPLAY_FRAME_MS");
    if (!file || !*file || r->done <= first) return true;
    sb_err e;
    char *text = sb_read_file(file, NULL, &e);
    if (!text) return fail_run(r, "SB_REPLAY_FRAME_MS: %s", e.msg);
    char have[SB_PARAMS_TEXT_LEN + 2];
    snprintf(have, sizeof have, ":%s:", r->params);
    double cost = NAN;
    int line = 0;
    for (char *p = text, *next; p && *p && isnan(cost); p = next) {
        next = strchr(p, '\n');
        if (next) *next++ = 0;
        line++;
        char spec[512];
        double ms;
        if (*p == '#' || strspn(p, " \t\r") == strlen(p)) continue;
        if (sscanf(p, "%511s %lf", spec, &ms) != 2 || !(ms > 0)) {
            free(text);
            char where[400];
            snprintf(where, sizeof where, "%.360s:%d", file, line);
            return fail_run(r, "SB_REPLAY_FRAME_MS %s: not \"TECHNIQUE[:ITEM...] MS\"", where);
        }
        char *item = strchr(spec, ':');
        if (item) *item++ = 0;
        bool match = !strcmp(spec, r->spec->tech->name);
        for (char *it = item ? strtok(item, ":") : NULL; match && it; it = strtok(NULL, ":")) {
            char want[300];
            snprintf(want, sizeof want, ":%s:", it);
            match = strstr(have, want) != NULL;
        }
        if (match) cost = ms;
    }
    free(text);
    if (isnan(cost)) return true;
    uint64_t seed = sb_fnv1a(SB_FNV_SEED, r->run_id, strlen(r->run_id));
    for (int i = first; i < r->done; i++) {
        sb_stage_times *t = &r->timer.times[i];
        double now = sb_columns_gpu_ms(t), u = (double)(sb_mix64(seed ^ (uint64_t)i) >> 11) * 0x1p-53;
        double k = now > 0 ? cost * (1 + 0.02 * (2 * u - 1)) / now : 0;
        for (int st = 0; st < SB_TIMER_STAGES && k > 0; st++) t->ms[st] *= k;
    }
    if (first == 0) {
        sb_run_mark_replayed(&r->info, "frame-costs");
        sb_run_warn(&r->info, "its frame times are replayed from %s (SB_REPLAY_FRAME_MS, a test seam), not measured",
                    file);
    }
    return true;
}

bool sb_run_pass(sb_run *r, int index, int total) {
    if (r->failed || r->finished) return false;
    if (!run_stages(r)) return untimed_frames(r);
    const sb_run_opts *o = &r->s->opts;
    bool first = r->repeats == 0;
    if (!ensure_instance(r)) return false;
    if (first || !r->keep_instance) warm_up(r);
    if (interrupt_run(r, "in the warm-up")) return false;
    if (first) r->calib_before = sb_calib_measure(&r->s->calib);
    int first_frame = r->done;
    bool ok = measured_frames(r, r->repeats, index, total) && replayed_frame_costs(r, first_frame);
    if (ok) r->repeats++;
    r->calib_after = sb_calib_measure(&r->s->calib);
    if (!r->keep_instance) drop_instance(r);
    if (!ok) return false;
    if (o->error_every == 0) { /* nothing fills these rows later: they can go out now */
        for (; r->written < r->done; r->written++)
            sb_columns_frame_row(&r->rows, &r->recs[r->written], &r->timer.times[r->written], run_stages(r));
        if (!sb_csv_file_write(&r->cf, &r->rows, &r->err)) return fail_run(r, "%s", r->err.msg);
    }
    return true;
}

bool sb_run_wants_more(const sb_run *r) {
    const sb_run_opts *o = &r->s->opts;
    if (r->failed || r->finished || r->repeats * o->frames >= r->capacity) return false;
    /* untimed frames are recorded once, whatever --repeat says: a repetition would time nothing (and the loop
       that asked for one would ask again for ever) */
    if (!run_stages(r)) return r->repeats == 0;
    if (o->target_ci <= 0) return r->repeats < o->repeat;
    return r->repeats == 0 || sb_columns_gpu_ci_pct(r->timer.times, r->done, o->frames) > o->target_ci;
}

/* A technique with shadow stages that drew no caster in any measured frame
 * measured nothing a user asked about: said in the run's warnings. */
static void check_shadows_drawn(sb_run *r) {
    bool shadow = false;
    for (int k = 0; k < r->spec->tech->stage_count; k++) shadow |= r->spec->tech->stages[k]->shadow;
    if (!shadow) return;
    for (int i = 0; i < r->done; i++)
        if (r->recs[i].counters.shadow_triangles) return;
    sb_run_warn(&r->info, "no shadow-casting triangle was drawn in any frame (nothing in view casts toward the light)");
}

/* The technique's own warnings (sb_technique.warn), from the measured frames' counters. */
static void technique_warnings(sb_run *r) {
    if (!r->spec->tech->warn || !r->done) return;
    sb_counters *frames = sb_xmalloc(sizeof *frames * (size_t)r->done);
    for (int i = 0; i < r->done; i++) frames[i] = r->recs[i].counters;
    char line[sizeof r->info.warnings] = "";
    r->spec->tech->warn(frames, r->done, line, sizeof line);
    free(frames);
    if (line[0]) sb_run_warn(&r->info, "%s", line);
}

/* When the evaluation cannot stand behind its figures: rays and rasterizer
 * disagree on the geometry, or the reference itself is not exact enough. */
static void check_geometry(sb_run *r) {
    long mism = 0, ns = 0, flip = 0, nf = 0;
    for (int i = 0; i < r->done; i++) {
        if (!r->recs[i].evaluated) continue;
        mism += r->recs[i].err.geom_mismatches, ns += r->recs[i].err.geom_samples;
        flip += r->recs[i].err.floor_disagree, nf += r->recs[i].err.floor_samples;
    }
    if (ns && (double)mism / ns > SB_GEOM_MISMATCH_WARN)
        sb_run_warn(&r->info, "rays and rasterizer disagree on the first surface at %.3g%% of sampled pixels "
                    "(geom_mismatch): the error figures are not against the geometry that was drawn",
                    100.0 * mism / ns);
    if (nf && (double)flip / nf > SB_ERR_FLOOR_WARN)
        sb_run_warn(&r->info, "the reference flips at %.3g%% of sampled pixels when cast from the exact surface "
                    "(err_floor): error differences below that are noise", 100.0 * flip / nf);
}

/* The test seam SB_REPLAY_TIMINGS (stability.h): the probe and frame times the verdict judges, from the file's
 * line for this run's technique and attempt. False: no seam or no line (the measured ones stand), or a failed run
 * (the file unreadable or malformed). */
/* How far a probe may stray from the batch's before a run is unstable, and a night's probe from its calm before
 * the night is disturbed: one tolerance for both. A software rasterizer shares the CPU with everything else on the
 * machine: wider tolerances there (stability.h's defaults are a GPU's). */
static double batch_tol(const sb_session *s) { return s->ctx.software ? 0.35 : SB_BATCH_TOL; }

static bool replayed_timings(sb_run *r, double *ms, double *before, double *after) {
    const char *file = getenv("SB_REPLAY_TIMINGS");
    if (!file || !*file) return false;
    sb_err e;
    char *text = sb_read_file(file, NULL, &e), why[200];
    if (!text) return fail_run(r, "SB_REPLAY_TIMINGS: %s", e.msg);
    sb_stability_replay rp;
    int found = sb_stability_replay_find(text, r->spec->tech->name, r->info.attempt, &rp, why, sizeof why);
    free(text);
    if (found < 0) {
        char msg[sizeof why + 300];
        snprintf(msg, sizeof msg, "%s: %s", file, why);
        return fail_run(r, "SB_REPLAY_TIMINGS %s", msg);
    }
    if (found == 0) return false;
    const int N = r->s->opts.frames;
    for (int i = 0; i < r->done; i++) ms[i] = rp.rep_ms[i / N < rp.nreps ? i / N : rp.nreps - 1];
    *before = rp.calib_before, *after = rp.calib_after;
    sb_run_mark_replayed(&r->info, "timings");
    sb_run_warn(&r->info, "the stability verdict judged timings replayed from %s (SB_REPLAY_TIMINGS, a test seam), "
                "not this run's", file);
    return true;
}

/* The stability verdict from the probe, the batch's probes and the frames' drift; false: a failed run. */
static bool judge_stability(sb_run *r) {
    double *ms = sb_xmalloc(sizeof(double) * (size_t)(r->done ? r->done : 1));
    for (int i = 0; i < r->done; i++) ms[i] = sb_columns_gpu_ms(&r->timer.times[i]);
    double before = r->calib_before, after = r->calib_after;
    if (!replayed_timings(r, ms, &before, &after) && r->failed) {
        free(ms);
        return false;
    }
    const bool sw = r->s->ctx.software;
    sb_stability_in in = {.calib_before = before, .calib_after = after,
                          .batch_calib = r->sum->calib, .nbatch = r->sum->ncalib, .frame_ms = ms, .n = r->done,
                          .per_repeat = r->s->opts.frames, .probe_tol = sw ? 0.25 : 0.10,
                          .batch_tol = batch_tol(r->s), .drift_tol = sw ? 0.20 : 0.05};
    r->info.stable = sb_stability(&in, r->info.unstable_reason, sizeof r->info.unstable_reason) ? "yes" : "no";
    free(ms);
    r->info.calib_ms_before = r->calib_before;
    r->info.calib_ms_after = r->calib_after;
    sb_summary_add_calib(r->sum, before);
    return true;
}

/* After the passes: the evaluation pass, the rest of the rows, the file committed. */
static bool finish_run(sb_run *r) {
    const sb_run_opts *o = &r->s->opts;
    if (r->failed) return false;
    if (o->error_every > 0 || o->images > 0) {
        if (!ensure_instance(r)) return false;
        double t0 = sb_now_ms(), refit0 = r->s->ref ? r->s->ref->refit_ms : 0;
        uint32_t refits0 = r->s->ref ? r->s->ref->refits : 0;
        bool evaluated = sb_evaluate_run(r->s, &r->in, r->seq, r->out_dir, r->run_id, r->recs, &r->err);
        r->info.eval_s = (sb_now_ms() - t0) / 1e3;
        if (r->s->ref && r->s->ref->refits > refits0)   /* a moving scene: the reference refit at each pose */
            r->info.ref_refit_ms = (r->s->ref->refit_ms - refit0) / (r->s->ref->refits - refits0);
        if (!evaluated) {
            r->interrupted = sb_interrupted() != 0;
            return fail_run(r, "%s", r->err.msg);
        }
    }
    for (; r->written < r->done; r->written++)
        sb_columns_frame_row(&r->rows, &r->recs[r->written], &r->timer.times[r->written], run_stages(r));
    if (!sb_csv_file_write(&r->cf, &r->rows, &r->err) || !sb_gl_check(r->spec->tech->name, &r->err) ||
        !sb_csv_file_commit(&r->cf, &r->err))
        return fail_run(r, "%s", r->err.msg);
    check_shadows_drawn(r);
    technique_warnings(r);
    if (r->s->path_note[0])   /* the path check's flagged frames: their figures are the geometry check's doubt */
        sb_run_warn(&r->info, "the path's cameras: %s", r->s->path_note);
    /* a size for a light the run does not shade is no size at all: said, not ignored in silence */
    double light = -1;
    bool lamp = (r->spec->tech->needs & SB_NEEDS_POINT_LIGHT) ||
                (sb_params_find(&r->spec->params, "light", &light) && light >= 0);   /* raycast:light=K */
    if (o->sun_size > 0 && lamp)
        sb_run_warn(&r->info, "--sun-size %g: this run shades a point or spot light, whose size is --lamp-radius", o->sun_size);
    if (o->lamp_radius > 0 && !lamp)
        sb_run_warn(&r->info, "--lamp-radius %g: this run shades the sun, whose size is --sun-size", o->lamp_radius);
    if (r->s->scene.unused[0])   /* what the file holds and the run does not draw: every run of the scene says it */
        sb_run_warn(&r->info, "the scene file holds parts nothing draws, left out: %s", r->s->scene.unused);
    check_geometry(r);
    return !run_stages(r) || judge_stability(r);   /* nothing timed, nothing to judge */
}

sb_run *sb_run_begin(sb_session *s, const sb_run_spec *spec, const char *out_dir, sb_summary *sum, int run_index,
                     bool keep_instance) {
    sb_run *r = sb_xcalloc(1, sizeof *r);
    const sb_run_opts *o = &s->opts;
    r->s = s;
    r->own = *spec;
    sb_spec_light_size(&r->own, o->sun_size);
    r->spec = spec = &r->own;
    r->sum = sum;
    r->keep_instance = keep_instance;
    r->t_run = sb_now_ms();
    r->writes_failed_before = sb_result_writes_failed();
    sb_session_run_id(s, spec, r->run_id);
    sb_params_canonical(&spec->params, r->params, sizeof r->params);
    snprintf(r->csv_path, sizeof r->csv_path, "%s/%s.csv", out_dir, r->run_id);
    snprintf(r->out_dir, sizeof r->out_dir, "%s", out_dir);
    r->info = (sb_run_info){
        .run_id = r->run_id, .run_index = run_index, .attempt = s->attempt > 1 ? s->attempt : 1,
        .scene = s->scene_name, .path = s->path_name,
        .technique = spec->tech->name, .params = r->params, .backend = sb_backend_name(o->backend),
        .renderer = s->ctx.renderer, .timing = sb_timing_name(s->timing), .clocks = s->clocks_mode, .status = SB_STATUS_OK,
        .order = sb_order_name(o->order), .submit = sb_submit_name(o->submit), .anim = s->scene.anim, .seed = o->order == SB_ORDER_SHUFFLE ? o->seed : 0,
        .reason = "", .frames = o->frames, .warmup = o->warmup, .width = o->width, .height = o->height,
        .target_ci = o->target_ci, .scene_triangles = sb_scene_triangles(&s->scene), .load_ms = s->scene.load_ms,
        .shadow_mb = sb_session_shadow_bytes(s, spec) / 1048576.0,
        .calib_ms_before = NAN, .calib_ms_after = NAN, .eval_s = NAN, .ref_refit_ms = NAN, .stable = "", .unstable_reason = "",
    };
    if (spec->tech->label) {   /* another renderer's frames: its name and settings */
        sb_label l = {spec->tech->name, r->params, s->ctx.renderer};
        spec->tech->label(spec->desc, &l);
        r->info.technique = l.technique, r->info.params = l.params, r->info.renderer = l.renderer;
    }
    /* another renderer's frames against clips that play: a renderer that drew the file still is scored against
       casters that moved (score's own default is --anim none) */
    if ((spec->tech->traits & SB_TRAIT_FOREIGN) && s->scene.moving_draws && strcmp(s->scene.anim, "none"))
        sb_run_warn(&r->info, "another renderer's frames are scored with the file's clips playing (--anim %s): "
                    "frames drawn still are scored against casters that moved (--anim none scores them still)",
                    o->anim ? o->anim : "all");
    if (!run_stages(r)) r->info.timing = "";   /* nothing timed */
    sb_session_light_label(s, r->info.light, sizeof r->info.light);
    sb_run_options_text(o, r->info.run_options, sizeof r->info.run_options);
    const char *skip = sb_skip_reason(s, spec->tech, spec);
    if (skip) {
        r->finished = true;
        r->info.status = SB_STATUS_SKIPPED;
        r->info.reason = skip;
        sb_log("run %s (%s): skipped: %s", r->run_id, spec->tech->name, skip);
        return r;
    }
    r->capacity = o->frames * (o->target_ci > 0 ? o->max_repeat : o->repeat);
    sb_timer_init(&r->timer, s->timing, o->ring, r->capacity);
    r->recs = sb_xcalloc((size_t)r->capacity, sizeof *r->recs);
    if (sb_csv_file_open(&r->cf, r->csv_path, &r->err)) {
        sb_columns_frame_header(&r->rows);
        if (!sb_csv_file_write(&r->cf, &r->rows, &r->err)) fail_run(r, "%s", r->err.msg);
    } else {
        fail_run(r, "%s", r->err.msg);
    }
    if (!r->failed && keep_instance) ensure_instance(r);
    return r;
}

bool sb_run_end(sb_run *r) {
    bool ok = r->info.status == SB_STATUS_SKIPPED || finish_run(r); /* skipped runs have nothing to finish */
    drop_instance(r);
    if (r->cf.f && r->failed) sb_csv_file_abort(&r->cf);
    r->info.run_wall_s = (sb_now_ms() - r->t_run) / 1e3;
    r->info.repeats = r->repeats;
    r->info.warmup = r->s->opts.warmup < 0 ? (r->repeats ? r->warmup_frames / r->repeats : 0) : r->s->opts.warmup;
    if (!ok) {
        /* a result this run could not write is named even with --quiet: the exit status (4) says "named above" */
        bool lost = !r->writes_failed_before && sb_result_writes_failed();
        const char *status = sb_status_names[r->interrupted ? SB_STATUS_INTERRUPTED : SB_STATUS_FAILED];
        if (lost) fprintf(stderr, "shadowbench: run %s (%s): %s: %s\n", r->run_id, r->spec->tech->name, status, r->err.msg);
        else sb_log("run %s (%s): %s: %s", r->run_id, r->spec->tech->name, status, r->err.msg);
        r->info.status = r->interrupted ? SB_STATUS_INTERRUPTED : SB_STATUS_FAILED;
        r->info.reason = r->err.msg;
    }
    bool measured = ok && r->info.status == SB_STATUS_OK;
    sb_summary_add_outcome(r->sum, &r->info, run_stages(r), measured ? r->recs : NULL, r->timer.times,
                           r->done);
    sb_csv_free(&r->rows);
    free(r->recs);
    if (r->timer.times) sb_timer_free(&r->timer);
    free(r);
    return ok;
}

bool sb_run_one(sb_session *s, const sb_run_spec *spec, const char *out_dir, sb_summary *sum, int run_index,
                int index, int total) {
    sb_run *r = sb_run_begin(s, spec, out_dir, sum, run_index, true);
    while (sb_run_wants_more(r) && sb_run_pass(r, index, total)) {}
    return sb_run_end(r);
}

static void shuffle(int *v, int n, uint64_t *rng) {
    for (int i = n - 1; i > 0; i--) {
        int j = (int)(sb_splitmix64(rng) % (uint64_t)(i + 1));
        int t = v[i];
        v[i] = v[j], v[j] = t;
    }
}

static bool end_run(sb_run *r, sb_summary *sum) {
    bool ok = sb_run_end(r);
    sb_err e;
    if (!sb_summary_flush(sum, &e)) fprintf(stderr, "shadowbench: %s\n", e.msg);
    return ok;
}

/* Rounds: every run that wants another repetition renders one, in the
 * round's order (interleave: matrix order; shuffle: a fresh permutation). */
static void run_rounds(sb_session *s, sb_run **runs, int n, int first, int total, uint64_t *rng) {
    int *perm = sb_xmalloc(sizeof(int) * (size_t)n);
    for (;;) {
        bool more = false;
        for (int k = 0; k < n; k++) more |= sb_run_wants_more(runs[k]);
        if (!more) break;
        for (int k = 0; k < n; k++) perm[k] = k;
        if (s->opts.order == SB_ORDER_SHUFFLE) shuffle(perm, n, rng);
        for (int k = 0; k < n; k++)
            if (sb_run_wants_more(runs[perm[k]])) sb_run_pass(runs[perm[k]], first + perm[k], total);
        for (int k = 0; sb_interrupted() && k < n; k++)
            if (sb_run_wants_more(runs[k])) interrupt_run(runs[k], "between repetitions");
    }
    free(perm);
}

/* --overlap: the reference of the frames the runs evaluate is cast in the
 * background while they render, when a run will use it: one that is not
 * skipped and shades with the sun (a lamp's frames have other answers). */
static void start_background(sb_session *s, const sb_run_spec *const *specs, int n) {
    bool wanted = false;
    for (int k = 0; k < n && !wanted; k++)
        wanted = !(specs[k]->tech->needs & SB_NEEDS_POINT_LIGHT) && !sb_skip_reason(s, specs[k]->tech, specs[k]);
    sb_err err;
    if (wanted && !sb_eval_background(s, &err))
        sb_log("the reference is not cast in the background: %s", err.msg); /* the evaluation says it again */
}

static void stop_background(sb_session *s) {
    if (!s->ref_cache) return;
    sb_ref_background_stats st = sb_ref_background_stop(s->ref_cache);
    if (st.queued && s->opts.progress)
        sb_log("reference background: %d frame(s) queued, %d cast (%llu rays, %.0f ms, %.0f ms of it while timed frames "
               "rendered), %d taken back by the evaluation, %d dropped",
               st.queued, st.frames, (unsigned long long)st.rays, st.ms, st.timed_ms, st.taken_back, st.dropped);
}

int sb_summary_conclude(const sb_summary *sum, const char *dir, const char *resume_command) {
    char stopped[32] = "";
    if (sum->interrupted) snprintf(stopped, sizeof stopped, ", %d interrupted", sum->interrupted);
    char rerun[96] = "";
    if (sum->rerun)
        snprintf(rerun, sizeof rerun, "; %d unstable run(s) run again, %d recovered", sum->rerun, sum->recovered);
    sb_log("%d run(s): %d ok (%d unstable), %d failed, %d skipped%s%s; results in %s", sum->count,
           sum->count - sum->failed - sum->skipped - sum->interrupted, sum->unstable, sum->failed, sum->skipped, stopped,
           rerun, dir);
    if (!sb_interrupted()) return sum->failed ? 1 : 0;
    /* said even with --quiet: the user asked for the stop and needs the way back */
    fprintf(stderr, "shadowbench: interrupted: the completed runs' rows are in %s/summary.csv; the rest: %s --resume %s\n",
            dir, resume_command, dir);
    return SB_EXIT_SIGNAL + sb_interrupted();
}

int sb_run_group(sb_session *s, const sb_run_spec *const *specs, const int *run_index, int n, const char *out_dir,
                 sb_summary *sum, int first, int total) {
    const sb_run_opts *o = &s->opts;
    if (n <= 0) return 0;
    start_background(s, specs, n);
    int failed = 0, *at = sb_xmalloc(sizeof(int) * (size_t)n);
    sb_run **runs = sb_xmalloc(sizeof *runs * (size_t)n);
    uint64_t rng = o->seed;
    for (int k = 0; k < n; k++) at[k] = k;
    /* one pass each: interleaving has nothing to interleave, shuffle permutes the runs */
    bool one_pass = o->repeat == 1 && o->target_ci <= 0;
    if (o->order == SB_ORDER_SHUFFLE && one_pass) shuffle(at, n, &rng);
    if (o->order == SB_ORDER_MATRIX || one_pass) {
        for (int k = 0; k < n && !sb_interrupted(); k++) {
            failed += !sb_run_one(s, specs[at[k]], out_dir, sum, run_index[at[k]], first + k, total);
            sb_err e;
            if (!sb_summary_flush(sum, &e)) fprintf(stderr, "shadowbench: %s\n", e.msg);
        }
    } else {
        for (int k = 0; k < n; k++) runs[k] = sb_run_begin(s, specs[k], out_dir, sum, run_index[k], false);
        run_rounds(s, runs, n, first, total, &rng);
        for (int k = 0; k < n; k++) failed += !end_run(runs[k], sum);
    }
    stop_background(s);
    free(runs);
    free(at);
    return failed;
}

void sb_run_again(sb_session *s, const sb_run_spec *const *specs, const int *run_index, int n, const char *out_dir,
                  sb_summary *sum, int attempt) {
    char (*ids)[17] = sb_xmalloc(sizeof *ids * (size_t)(n ? n : 1));
    for (int k = 0; k < n; k++) {
        sb_session_run_id(s, specs[k], ids[k]);
        char from[4400], to[4400];
        snprintf(from, sizeof from, "%s/%s.csv", out_dir, ids[k]);
        snprintf(to, sizeof to, "%s/%s.attempt-%d.csv", out_dir, ids[k], attempt - 1);
        if (rename(from, to) != 0) sb_log("%s: cannot keep the earlier attempt's frames as %s", from, to);
        sb_summary_drop(sum, ids[k]);
    }
    sb_log("%d unstable run(s) run again (attempt %d)", n, attempt);
    s->attempt = attempt;
    sb_run_group(s, specs, run_index, n, out_dir, sum, 0, n);
    s->attempt = 0;
    if (attempt == 2) sum->rerun += n;
    for (int k = 0; k < n; k++) sum->recovered += sb_summary_stable(sum, ids[k]);
    free(ids);
}

/* The calibration probe now: measured (a probe of its own), or replayed from
 * SB_REPLAY_TIMINGS as technique "calm-probe", attempt k (the test seam of stability.h). NaN: none. */
static double probe_now(sb_session *s, int k) {
    const char *file = getenv("SB_REPLAY_TIMINGS");
    if (file && *file) {
        char *text = sb_read_file(file, NULL, NULL), why[200];
        sb_stability_replay rp;
        int found = text ? sb_stability_replay_find(text, "calm-probe", k, &rp, why, sizeof why) : 0;
        free(text);
        if (found > 0) return rp.calib_before;
    }
    sb_calib c;
    sb_err err;
    memset(&c, 0, sizeof c);
    if (!sb_calib_init(&c, &s->ctx, s->ctx.has_timer_query && !s->ctx.software, &err)) return NAN;
    double ms = sb_calib_measure(&c);
    sb_calib_free(&c);
    return ms;
}

/* A disturbed night waits for the probe to come back to calm (three probes in a row within tol of it), a probe a
 * second for at most wait_s; true: calm again. */
static bool wait_for_calm(sb_session *s, double calm_ms, double tol, double wait_s, double *waited_s, double *last_ms) {
    double t0 = sb_now_ms();
    *last_ms = NAN;
    for (int k = 1, calm = 0; !sb_interrupted(); k++) {
        *last_ms = probe_now(s, k);
        calm = isfinite(*last_ms) && *last_ms <= calm_ms * (1 + tol) ? calm + 1 : 0;
        *waited_s = (sb_now_ms() - t0) / 1e3;
        if (calm >= 3) return true;
        if (!calm && *waited_s + 1 > wait_s) return false;   /* a calm probe is checked twice more, budget or not */
        nanosleep(&(struct timespec){.tv_sec = calm ? 0 : 1, .tv_nsec = calm ? 200000000L : 0}, NULL);
    }
    return false;
}

/* The re-runs of one attempt, planned on the figures so far (sb_rerun_plan_make), said in the log: a disturbed night
 * (at attempt 2) waits for calm or says so and runs nothing again; re-runs take at most a stated share of the
 * night's time. */
bool sb_rerun_round_plan(sb_session *s, sb_summary *sum, int nprobe, double night_s, double spent_s, int attempt,
                         sb_rerun_round *out) {
    const double tol = batch_tol(s);
    sb_rerun_run *rr = NULL;
    memset(out, 0, sizeof *out);
    out->n = sb_summary_rerun_runs(sum, &out->ids, &rr);
    out->pick = sb_xcalloc((size_t)out->n + 1, sizeof *out->pick);
    sb_rerun_plan plan;
    sb_rerun_plan_make(rr, out->n, sum->calib, nprobe, night_s, spent_s, tol, out->pick, &plan);
    free(rr);
    bool go = plan.unstable > 0;
    if (go && attempt == 2 && plan.disturbed) {
        double waited = 0, last = NAN;
        char what[400];
        snprintf(what, sizeof what, "the night was disturbed: %d of %d runs unstable, the calibration probe above "
                 "its calm %.3g ms by more than %.0f%% for %d runs in a row", plan.unstable, plan.runs,
                 plan.calm_ms, 100 * tol, plan.busy_streak);
        go = wait_for_calm(s, plan.calm_ms, tol, SB_RERUN_WAIT * night_s, &waited, &last);
        if (go) sb_log("%s; calm again after %.0f s: running again what %.0f%% of the night's time buys", what,
                       waited, 100 * SB_RERUN_SHARE);
        else
            sb_log("%s; not calm within %.0f s (%.0f%% of the night's time; the probe %.3g ms): no run run again, "
                   "its %d unstable run(s) stay stable=no", what, waited, 100 * SB_RERUN_WAIT, last, plan.unstable);
    }
    if (go && plan.chosen < plan.unstable)
        sb_log("%d of %d unstable run(s) not run again (attempt %d): re-runs take at most %.0f%% of the night's "
               "%.0f s (at least %.0f s), %.0f s of it spent", plan.unstable - plan.chosen, plan.unstable, attempt,
               100 * SB_RERUN_SHARE, night_s, SB_RERUN_FLOOR_S, spent_s);
    return go;
}

void sb_rerun_round_free(sb_rerun_round *r) {
    for (int u = 0; u < r->n; u++) free(r->ids[u]);
    free(r->ids);
    free(r->pick);
    memset(r, 0, sizeof *r);
}
