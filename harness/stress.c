/* stress.c - the numerical-stability battery.
 *
 * Every case is a small scene (a slab with two boxes, or a special geometry)
 * scaled and translated through its glTF node (the translation is a JSON
 * double), a camera path written as a path file, and a sun. Every technique
 * renders each frame, then the frame is evaluated against the Embree
 * reference. A row passes when: the technique was created and rendered with
 * no GL error; every matrix, split and metric is finite; every evaluated
 * sample that a cascade shades lies inside that cascade's shadow map (the
 * coverage property), and visible samples within the split range have a
 * cascade; and err_rate is within the case's bound. */
#include "stress.h"

#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "autobias.h"
#include "columns.h"
#include "cascade.h"
#include "error.h"
#include "eval.h"
#include "glb.h"

enum { GEO_BOXES, GEO_TRIANGLE, GEO_DEGENERATE };
enum { CAM_ORBIT, CAM_ONE_KEY, CAM_REPEATED, CAM_FLIPS, CAM_INSIDE, CAM_SKY, CAM_ALONG_SUN, CAM_AGAINST_SUN };

typedef struct stress_case {
    const char *name;
    double scale;
    double offset;          /* along (1, 0.3, -0.7) */
    double sun_az, sun_el;
    int geometry, camera;
    double near, far;       /* in unscaled units; 0: derived from the scene */
    double bound;           /* err_rate bound for shadow maps (raycast: bound / 5) */
    bool relative;          /* translated: bound is 2x the base case's err_rate + 0.01 */
} stress_case;

/* Bounds: a shadow map at 2048 on this small scene errs on well under 0.5% of
 * the pixels; a technique that loses its shadows errs on 1-5% (the `none` row
 * shows how much shadow a case has). Translated cases must stay within twice
 * the untranslated error. */
static const stress_case cases[] = {
    {"base", 1, 0, 30, 50, GEO_BOXES, CAM_ORBIT, 0, 0, 0.005, false},
    {"translate-1e3", 1, 1e3, 30, 50, GEO_BOXES, CAM_ORBIT, 0, 0, 0, true},
    {"translate-1e5", 1, 1e5, 30, 50, GEO_BOXES, CAM_ORBIT, 0, 0, 0, true},
    {"translate-1e6", 1, 1e6, 30, 50, GEO_BOXES, CAM_ORBIT, 0, 0, 0, true},
    {"near-far-1e8", 1, 0, 30, 50, GEO_BOXES, CAM_ORBIT, 1e-3, 1e5, 0.005, false},
    {"scene-1e-3", 1e-3, 0, 30, 50, GEO_BOXES, CAM_ORBIT, 0, 0, 0.005, false},
    {"scene-1e5", 1e5, 0, 30, 50, GEO_BOXES, CAM_ORBIT, 0, 0, 0.005, false},
    {"sun-vertical", 1, 0, 0, 90, GEO_BOXES, CAM_ORBIT, 0, 0, 0.005, false},
    {"sun-along-view", 1, 0, 30, 45, GEO_BOXES, CAM_ALONG_SUN, 0, 0, 0.005, false},
    {"sun-against-view", 1, 0, 30, 20, GEO_BOXES, CAM_AGAINST_SUN, 0, 0, 0.005, false},
    {"sun-grazing", 1, 0, 30, 0.5, GEO_BOXES, CAM_ORBIT, 0, 0, 0.01, false},
    {"camera-inside-caster", 1, 0, 30, 50, GEO_BOXES, CAM_INSIDE, 0, 0, 0.005, false},
    {"all-sky", 1, 0, 30, 50, GEO_BOXES, CAM_SKY, 0, 0, 0.0, false},
    {"single-triangle", 1, 0, 30, 50, GEO_TRIANGLE, CAM_ORBIT, 0, 0, 0.001, false},
    /* a 1e5-wide sliver stretches the scene bounds and every light frustum's depth */
    {"degenerate-huge-triangles", 1, 0, 30, 50, GEO_DEGENERATE, CAM_ORBIT, 0, 0, 0.02, false},
    {"path-one-key", 1, 0, 30, 50, GEO_BOXES, CAM_ONE_KEY, 0, 0, 0.005, false},
    {"path-repeated-keys", 1, 0, 30, 50, GEO_BOXES, CAM_REPEATED, 0, 0, 0.005, false},
    {"path-180-flips", 1, 0, 30, 50, GEO_BOXES, CAM_FLIPS, 0, 0, 0.005, false},
};

/* The battery's settings: each technique's (sb_technique.stress), in registry order. Shadow volumes are not in
 * it: they need closed casters, and the degenerate/huge case (open, zero-area and 1e5-wide triangles) breaks them
 * (err_rate 0.77 when tried); they report open casters when created. Returns how many (each malloc'd). */
static int battery(char ***out) {
    int n = 0;
    *out = NULL;
    for (int i = 0; i < sb_technique_count(); i++) {
        const sb_technique *t = sb_technique_at(i);
        for (const char *p = t->stress; p;) {
            size_t w = strcspn(p, ";");
            char spec[256];
            snprintf(spec, sizeof spec, "%s%s%.*s", t->name, w ? ":" : "", (int)w, p);
            *out = sb_xrealloc(*out, sizeof **out * (size_t)(n + 1));
            (*out)[n++] = sb_strdup(spec);
            p = p[w] ? p + w + 1 : NULL;
        }
    }
    return n;
}

/* The technique a spec names. */
static const sb_technique *technique_of(const char *spec) {
    char name[64];
    snprintf(name, sizeof name, "%.*s", (int)strcspn(spec, ":"), spec);
    return sb_technique_find(name);
}

static sb_v3 offset_of(const stress_case *c) { return sb_v3_scale(sb_v3_norm(sb_v3_make(1, 0.3, -0.7)), c->offset); }

static bool write_scene(const stress_case *c, const char *file) {
    sb_glb_scene s = {0};
    s.sun = sb_sun_dir(c->sun_az, c->sun_el);
    s.offset = offset_of(c);
    double k = c->scale;
    if (c->geometry == GEO_TRIANGLE) {
        sb_glb_mesh *m = sb_glb_new_mesh(&s, 0);
        uint32_t a = sb_glb_vert(m, -20 * k, 0, -20 * k, 0, 1, 0), b = sb_glb_vert(m, 0, 0, 20 * k, 0, 1, 0),
                 d = sb_glb_vert(m, 20 * k, 0, -20 * k, 0, 1, 0);
        sb_glb_tri(m, a, b, d);
    } else {
        sb_glb_box(sb_glb_new_mesh(&s, 0), -20 * k, -0.5 * k, -20 * k, 20 * k, 0, 20 * k);
        sb_glb_box(sb_glb_new_mesh(&s, 1), -1 * k, 0, -1 * k, 1 * k, 2 * k, 1 * k);
        sb_glb_box(sb_glb_new_mesh(&s, 4), 4 * k, 0, 2 * k, 5 * k, 5 * k, 3 * k);
        if (c->geometry == GEO_DEGENERATE) {
            sb_glb_mesh *m = sb_glb_new_mesh(&s, 3);
            /* zero-area: a repeated vertex, and three collinear ones */
            uint32_t v = sb_glb_vert(m, 3 * k, 1 * k, -3 * k, 0, 1, 0);
            sb_glb_tri(m, v, v, v);
            uint32_t a = sb_glb_vert(m, -3 * k, 1 * k, 3 * k, 0, 1, 0), b = sb_glb_vert(m, -2 * k, 1 * k, 3 * k, 0, 1, 0),
                     d = sb_glb_vert(m, -1 * k, 1 * k, 3 * k, 0, 1, 0);
            sb_glb_tri(m, a, b, d);
            /* a huge sliver far below the slab, 1e5 across */
            uint32_t h0 = sb_glb_vert(m, -5e4 * k, -30 * k, -5e4 * k, 0, 1, 0),
                     h1 = sb_glb_vert(m, 5e4 * k, -30 * k, -5e4 * k, 0, 1, 0),
                     h2 = sb_glb_vert(m, 0, -30 * k, 5e4 * k, 0, 1, 0);
            sb_glb_tri(m, h0, h2, h1);
        }
    }
    return sb_glb_write(&s, file) == 0;
}

static void look_key(FILE *f, double t, sb_v3 pos, sb_v3 target) {
    fprintf(f, "look %g  %.17g %.17g %.17g  %.17g %.17g %.17g\n", t, pos.x, pos.y, pos.z, target.x, target.y, target.z);
}

static bool write_path(const stress_case *c, const char *file) {
    FILE *f = fopen(file, "w");
    if (!f) return false;
    double k = c->scale;
    sb_v3 o = offset_of(c);
#define P(x, y, z) sb_v3_add(o, sb_v3_make((x) * k, (y) * k, (z) * k))
    fprintf(f, "# stress case %s\nfov 60\n", c->name);
    if (c->near > 0) fprintf(f, "near %.17g\nfar %.17g\n", c->near * k, c->far * k);
    sb_v3 target = P(-0.8, 0, -0.8);
    sb_v3 sun = sb_sun_dir(c->sun_az, c->sun_el);
    switch (c->camera) {
    case CAM_ORBIT:
        look_key(f, 0, P(-8, 6, -6), target);
        look_key(f, 1, P(-6, 5, -9), target);
        look_key(f, 2, P(-9, 7, -3), target);
        break;
    case CAM_ONE_KEY:
        look_key(f, 0, P(-8, 6, -6), target);
        break;
    case CAM_REPEATED:
        for (int i = 0; i < 3; i++) look_key(f, i, P(-8, 6, -6), target);
        look_key(f, 3, P(-6, 5, -9), target);
        break;
    case CAM_FLIPS: { /* the orientation turns 180 degrees about +Y between keys */
        sb_quat q = sb_quat_look(sb_v3_make(0.6, -0.5, 0.6), sb_v3_make(0, 1, 0));
        sb_quat flip = {0, 1, 0, 0};
        for (int i = 0; i < 4; i++) {
            sb_v3 p = P(-2 + i, 4, -2);
            fprintf(f, "key %d  %.17g %.17g %.17g  %.17g %.17g %.17g %.17g\n", i, p.x, p.y, p.z, q.x, q.y, q.z, q.w);
            q = sb_quat_mul(flip, q);
        }
        break;
    }
    case CAM_INSIDE:
        look_key(f, 0, P(0, 1, 0), P(10, 0.5, 3));
        look_key(f, 1, P(0.2, 1, 0.1), P(-10, 0.5, 3));
        break;
    case CAM_SKY:
        look_key(f, 0, P(0, 30, 0), P(0.001, 60, 0));
        look_key(f, 1, P(3, 30, 0), P(3.001, 60, 1));
        break;
    case CAM_ALONG_SUN: /* looking the way the light travels: the sun right behind the camera */
        look_key(f, 0, sb_v3_add(target, sb_v3_scale(sun, 14 * k)), target);
        look_key(f, 1, sb_v3_add(P(0.5, 0, 0.5), sb_v3_scale(sun, 12 * k)), P(0.5, 0, 0.5));
        break;
    case CAM_AGAINST_SUN: { /* looking into the sun, low over the slab */
        sb_v3 h = sb_v3_norm(sb_v3_make(sun.x, 0, sun.z));
        sb_v3 eye = sb_v3_add(P(0, 1.5, 0), sb_v3_scale(h, -9 * k));
        look_key(f, 0, eye, sb_v3_add(eye, sun));
        look_key(f, 1, sb_v3_add(eye, sb_v3_make(k, 0, 0)), sb_v3_add(sb_v3_add(eye, sb_v3_make(k, 0, 0)), sun));
        break;
    }
    }
#undef P
    return fclose(f) == 0;
}

/* Frobenius condition number of a 4x4 matrix (inf if singular). */
static double condition(sb_m4 m) {
    sb_m4 inv;
    if (!sb_m4_invert(m, &inv)) return INFINITY;
    double a = 0, b = 0;
    for (int i = 0; i < 16; i++) {
        a += m.m[i] * m.m[i];
        b += inv.m[i] * inv.m[i];
    }
    return sqrt(a) * sqrt(b);
}

typedef struct row_result {
    bool pass;
    double err_rate, worst_cond;
    long coverage_misses, samples;
    char note[SB_ERR_LEN + 128];
} row_result;

static void fail(row_result *r, const char *fmt, const char *a) {
    if (!r->pass) return; /* keep the first reason */
    r->pass = false;
    snprintf(r->note, sizeof r->note, fmt, a);
}

/* The light matrices of the cascade block: finite, invertible, and the worst condition number. */
static void check_block(const sb_cascade_block *blk, int count, row_result *r) {
    for (int k = 0; k < count; k++) {
        if (blk->s.flags[k][0] < 0.5f) continue;
        sb_m4 m;
        for (int e = 0; e < 16; e++) {
            m.m[e] = blk->light_vp[k][e];
            if (!isfinite(blk->shadow_mat[k][e])) fail(r, "shadow matrix %s is not finite", "");
        }
        double cond = condition(m);
        if (!(cond < INFINITY) || !sb_m4_finite(m)) fail(r, "light matrix %s is singular or not finite", "");
        else if (cond > r->worst_cond) r->worst_cond = cond;
    }
}

/* Coverage: every evaluated sample that a cascade shades lies inside that
 * cascade's map, and visible samples within the split range have a cascade. */
static void check_coverage(const sb_cascade_block *blk, const sb_frame *f, const sb_eval_buf *b, sb_v3 origin,
                           row_result *r) {
    for (int p = 0; p < b->w * b->h; p++) {
        if (b->ref[p] == 128) continue; /* sky or facing away */
        const float *a = b->aux + 4 * (size_t)p, *q = b->pos + 4 * (size_t)p;
        int k = (int)lroundf(a[3]);
        r->samples++;
        if (k < 0) {
            /* shaded by no map: a miss unless it is beyond the last split */
            sb_v3 pw = sb_v3_make(q[0], q[1], q[2]);
            double z = sb_v3_dot(sb_v3_sub(pw, sb_v3_sub(f->cam.pos, origin)), f->cam.forward);
            int last = f->counters.split_count - 1;
            if (last >= 0 && z <= f->counters.splits[last] * 0.999) r->coverage_misses++;
            continue;
        }
        const float *sm = blk->shadow_mat[k];
        double hw = sm[3] * q[0] + sm[7] * q[1] + sm[11] * q[2] + sm[15];
        double x = (sm[0] * q[0] + sm[4] * q[1] + sm[8] * q[2] + sm[12]) / hw;
        double y = (sm[1] * q[0] + sm[5] * q[1] + sm[9] * q[2] + sm[13]) / hw;
        double z = (sm[2] * q[0] + sm[6] * q[1] + sm[10] * q[2] + sm[14]) / hw;
        const double tol = 1e-3;
        if (x < -tol || x > 1 + tol || y < -tol || y > 1 + tol || z < -tol || z > 1 + tol) r->coverage_misses++;
    }
}

static void run_row(sb_session *s, const char *spec, int frames, row_result *r) {
    memset(r, 0, sizeof *r);
    r->pass = true;
    sb_run_spec *runs = NULL;
    int n = 0;
    sb_err err;
    if (!sb_spec_expand(spec, NULL, &runs, &n, &err)) {
        fail(r, "%s", err.msg);
        return;
    }
    sb_instance in;
    if (!sb_instance_create(&in, s, &runs[0], frames, &err)) {
        fail(r, "create: %s", err.msg);
        free(runs);
        return;
    }
    sb_eval_buf b;
    sb_eval_buf_init(&b, &s->gpu, false);
    bool cascades = sb_technique_times(runs[0].tech, &sb_stage_cascade);
    double err_sum = 0;
    int seq = 0;
    for (int i = 0; i < frames && r->pass; i++) {
        sb_frame f;
        sb_error_metrics em;
        if (!sb_eval_frame(s, &in, i, frames, 0, &seq, &b, &f, &em, &err)) fail(r, "%s", err.msg);
        for (int k = 0; k < f.counters.split_count; k++)
            if (!isfinite(f.counters.splits[k])) fail(r, "split %s is not finite", "");
        if (!sb_m4_finite(f.view_proj)) fail(r, "camera matrix %s is not finite", "");
        if (!isfinite(em.err_rate) || !isfinite(em.vis_mae)) fail(r, "error metric %s is not finite", "");
        err_sum += em.err_rate;
        if (cascades) {
            sb_cascade_block blk;
            sb_csm *c = (sb_csm *)in.state;
            glBindBuffer(GL_SHADER_STORAGE_BUFFER, c->block);
            glGetBufferSubData(GL_SHADER_STORAGE_BUFFER, 0, sizeof blk, &blk);
            check_block(&blk, c->count, r);
            check_coverage(&blk, &f, &b, s->scene.origin, r);
        }
    }
    r->err_rate = frames ? err_sum / frames : NAN;
    if (r->samples && r->coverage_misses * 1000 > r->samples) {
        char m[64];
        snprintf(m, sizeof m, "%ld of %ld", r->coverage_misses, r->samples);
        fail(r, "coverage: %s samples outside their cascade", m);
    }
    sb_eval_buf_free(&b);
    sb_instance_destroy(&in);
    free(runs);
}

static int stress_specs(const sb_run_opts *opts, const char *only, const char *const *specs, int nspecs, FILE *out,
                        sb_err *err);

int sb_stress_run(const sb_run_opts *opts, const char *only, const char *const *specs, int nspecs, FILE *out,
                  sb_err *err) {
    if (nspecs) return stress_specs(opts, only, specs, nspecs, out, err);
    char **own = NULL;
    int n = battery(&own);
    int rc = stress_specs(opts, only, (const char *const *)own, n, out, err);
    for (int i = 0; i < n; i++) free(own[i]);
    free(own);
    return rc;
}

static int stress_specs(const sb_run_opts *opts, const char *only, const char *const *specs, int nspecs, FILE *out,
                        sb_err *err) {
    for (int t = 0; t < nspecs; t++) { /* bad specs: one line before anything renders */
        sb_run_spec *runs = NULL;
        int n = 0;
        bool ok = sb_spec_expand(specs[t], NULL, &runs, &n, err);
        for (int r = 0; ok && r < n; r++)
            if (sb_autobias_wanted(&runs[r]))
                ok = sb_fail(err, "%s: stress renders fixed offsets; auto is calibrated by run, batch and tune",
                             specs[t]);
        free(runs);
        if (!ok) return -1;
    }
    if (only) { /* a CASE that matches none is a typo, not an empty battery */
        bool any = false;
        char names[1024] = "";
        for (size_t ci = 0; ci < SB_COUNT(cases); ci++) {
            any |= strstr(cases[ci].name, only) != NULL;
            size_t l = strlen(names);
            snprintf(names + l, sizeof names - l, "%s%s", ci ? ", " : "", cases[ci].name);
        }
        if (!any) return sb_fail(err, "stress: no case matches '%s' (cases: %s, or all)", only, names), -1;
    }
    /* SB_STRESS_KEEP=1 keeps each case's .glb and .path, to rerun a failing case with `run --images` */
    bool keep = getenv("SB_STRESS_KEEP") != NULL;
    /* in $TMPDIR where set (a cluster node's scratch), else /tmp */
    const char *tmp = getenv("TMPDIR");
    if (!tmp || !*tmp) tmp = "/tmp";
    char dir[4096];
    snprintf(dir, sizeof dir, "%s/shadowbench-stress-XXXXXX", tmp);
    if (!mkdtemp(dir)) return sb_fail(err, "cannot create a temporary folder for the stress scenes in %s", tmp), -1;
    sb_session s;
    memset(&s, 0, sizeof s);
    if (!sb_context_create(&s.ctx, opts->backend, err)) return -1;
    fprintf(out, "%-26s %-28s %-5s %9s %11s  %s\n", "case", "technique", "pass", sb_columns_role(SB_ROLE_ERROR),
            "worst_cond", "note");
    int failures = 0;
    double *base_err = sb_xmalloc(sizeof(double) * (size_t)nspecs);
    for (int t = 0; t < nspecs; t++) base_err[t] = NAN;
    /* a SIGINT or SIGTERM stops it between rows: the rows so far stand, the case's files go */
    for (size_t ci = 0; ci < SB_COUNT(cases) && !sb_interrupted(); ci++) {
        const stress_case *c = &cases[ci];
        if (only && !strstr(c->name, only) && strcmp(c->name, "base")) continue;
        char scene[4200], path[4200];
        snprintf(scene, sizeof scene, "%s/%s.glb", dir, c->name);
        snprintf(path, sizeof path, "%s/%s.path", dir, c->name);
        sb_run_opts o = *opts;
        o.sun_override = true;
        o.sun_az = c->sun_az;
        o.sun_el = c->sun_el;
        if (!write_scene(c, scene) || !write_path(c, path)) {
            fprintf(out, "%-26s %-28s FAIL  cannot write the case's files\n", c->name, "-");
            failures++;
            continue;
        }
        sb_err e;
        if (!sb_session_open(&s, &o, scene, path, &e)) {
            fprintf(out, "%-26s %-28s FAIL  %s\n", c->name, "-", e.msg);
            failures++;
            continue;
        }
        for (int t = 0; t < nspecs && !sb_interrupted(); t++) {
            row_result r;
            run_row(&s, specs[t], o.frames, &r);
            unsigned traits = technique_of(specs[t])->traits;
            double bound = c->relative                 ? 2 * base_err[t] + 0.001
                           : traits & SB_TRAIT_EXACT ? c->bound / 5 + 0.001
                                                       : c->bound;
            if (!(traits & SB_TRAIT_NO_SHADOWS) && r.pass && !(r.err_rate <= bound)) {
                char m[160];
                snprintf(m, sizeof m, "%s %.4f above the bound %.4f", sb_columns_role(SB_ROLE_ERROR), r.err_rate, bound);
                fail(&r, "%s", m);
            }
            if (!strcmp(c->name, "base")) base_err[t] = r.err_rate;
            failures += !r.pass;
            char cond[32] = "-";
            if (r.worst_cond > 0) snprintf(cond, sizeof cond, "%.3g", r.worst_cond);
            fprintf(out, "%-26s %-28s %-5s %9.5f %11s  %s\n", c->name, specs[t], r.pass ? "ok" : "FAIL", r.err_rate,
                    cond, r.note);
            fflush(out);
        }
        sb_session_close_scene(&s);
        if (!keep) {
            unlink(scene);
            unlink(path);
        }
    }
    if (keep) fprintf(out, "scenes and paths kept in %s (SB_STRESS_KEEP)\n", dir);
    else rmdir(dir);
    sb_context_destroy(&s.ctx);
    free(base_err);
    if (sb_interrupted()) fprintf(out, "interrupted by %s: the rows above were checked, the rest not\n", sb_interrupt_name());
    fprintf(out, "%d failure(s)\n", failures);
    return failures;
}
