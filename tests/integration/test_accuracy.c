/* Accuracy: the Embree reference against analytic geometry, error metrics
 * that respond to resolution and to a deliberately broken technique, and an
 * evaluation that never touches the timed frames. */
#define _DEFAULT_SOURCE
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>
#include <stdlib.h>
#include <string.h>

#include "autobias.h"
#include "cascade.h"
#include "eval.h"
#include "reference.h"
#include "support.h"

static void test_reference_matches_analytic(void **st) {
    (void)st;
    sb_session s;
    sb_err err;
    assert_true(pb_open(&s, SB_BACKEND_EGL, 640, 360, &err));
    const int n = 640 * 360;
    float *pos = malloc(sizeof(float) * 4 * n);
    unsigned char *ref = malloc(n);
    sb_error_metrics m;
    assert_true(eval_frame(&s, "none", 0, 1, &m, pos, ref, &err));
    long plane = 0, mismatch = 0, false_shadow = 0, shadow = 0;
    for (int i = 0; i < n; i++) {
        if (ref[i] == 128) continue;   /* not evaluated */
        sb_v3 p = sb_v3_add(sb_v3_make(pos[4 * i], pos[4 * i + 1], pos[4 * i + 2]), s.scene.origin);
        if (fabs(p.y) > 1e-3 || (fabs(p.x) <= 1 && fabs(p.z) <= 1)) continue;   /* the plane, outside the box */
        plane++;
        bool exact = pb_box_shadows(p, s.gpu.sun), r = ref[i] == 0;
        shadow += exact;
        mismatch += exact != r;
        false_shadow += r && !exact;
    }
    print_message("plane %ld px, analytic shadow %ld, reference mismatch %ld (%.4f%%), false shadow %ld; %llu rays in %.1f ms\n",
                  plane, shadow, mismatch, 100.0 * mismatch / plane, false_shadow, (unsigned long long)m.rays, m.ray_ms);
    assert_true(plane > n / 4 && shadow > plane / 100);
    assert_true(mismatch * 1000 <= plane * 2);   /* within 0.2% of the plane's pixels */
    assert_true(false_shadow * 10000 <= plane);  /* no self-intersection on the lit plane */
    /* `none` shadows nothing: its error is the share of shadowed pixels */
    assert_true(fabs(m.false_lit - m.err_rate) < 1e-12 && m.false_shadow == 0);
    free(pos);
    free(ref);
    sb_session_close(&s);
}

static sb_session g_towers;

static int open_towers(void) {
    sb_err err;
    return test_open(&g_towers, "towers", "towers", 480, 270, &err) ? 0 : -1;
}

static void test_error_falls_with_resolution(void **st) {
    (void)st;
    assert_int_equal(open_towers(), 0);
    const int res[] = {512, 1024, 2048, 4096};
    double err_rate[4], res_err[4];
    /* frame 5 of 12: rising in the street, where the map's resolution is what limits it (from frame 7 the
       camera is above the roofs, where even 512 texels a side resolve every pixel's footprint) */
    for (int k = 0; k < 4; k++) {
        char spec[64];
        snprintf(spec, sizeof spec, "sm:res=%d:filter=none", res[k]);
        sb_error_metrics m;
        sb_err err;
        assert_true(eval_frame(&g_towers, spec, 5, 12, &m, NULL, NULL, &err));
        err_rate[k] = m.err_rate;
        res_err[k] = m.res_err_mean;
        print_message("%s: err_rate %.5f res_err_mean %.3f texel_px_p95 %.3f (%ld px)\n", spec, m.err_rate,
                      m.res_err_mean, m.texel_px_p95, m.pixels);
    }
    for (int k = 1; k < 4; k++) {
        assert_true(err_rate[k] < err_rate[k - 1]);
        assert_true(res_err[k] < res_err[k - 1]);
    }
    /* along the street (frames 0, 3, 6) each warp beats the uniform map of the same size, in
       error and in resolution: TSM, LiSPSM and PSM */
    const char *warps[] = {"sm:res=2048:filter=none", "tsm:res=2048:filter=none", "lispsm:res=2048:filter=none",
                           "psm:res=2048:filter=none"};
    double e[4] = {0}, r[4] = {0};
    for (int fr = 0; fr <= 6; fr += 3)
        for (int k = 0; k < 4; k++) {
            sb_error_metrics a;
            sb_err e2;
            assert_true(eval_frame(&g_towers, warps[k], fr, 12, &a, NULL, NULL, &e2));
            e[k] += a.err_rate / 3;
            r[k] += a.res_err_mean / 3;
        }
    print_message("frames 0,3,6: err_rate sm %.5f tsm %.5f lispsm %.5f psm %.5f; res_err_mean sm %.3f tsm %.3f "
                  "lispsm %.3f psm %.3f\n", e[0], e[1], e[2], e[3], r[0], r[1], r[2], r[3]);
    for (int k = 1; k < 4; k++) assert_true(e[k] < e[0] && r[k] < r[0]);
    /* the exact technique is (nearly) exact */
    sb_error_metrics m;
    sb_err err;
    assert_true(eval_frame(&g_towers, "raycast", 5, 12, &m, NULL, NULL, &err));
    print_message("raycast: err_rate %.5f\n", m.err_rate);
    assert_true(m.err_rate < 0.002 && m.err_rate < err_rate[3]);
}

static void test_broken_bias_is_detected(void **st) {
    (void)st;
    sb_error_metrics good, bad;
    sb_err err;
    assert_true(eval_frame(&g_towers, "sm:res=2048", 9, 12, &good, NULL, NULL, &err));
    /* the bias pushed into the surface, through the instance's state (a test seam: no production hook) */
    sb_run_spec *runs = NULL;
    int n = 0;
    assert_true(sb_spec_expand("sm:res=2048", NULL, &runs, &n, &err));
    sb_instance in;
    assert_true(sb_instance_create(&in, &g_towers, &runs[0], 1, &err));
    sb_csm *c = (sb_csm *)in.state;
    c->d.bias = -c->d.bias;
    c->d.slope = -c->d.slope;
    c->d.normal = -c->d.normal;
    assert_true(eval_instance(&g_towers, &in, 9, 12, &bad, NULL, NULL, &err));
    sb_instance_destroy(&in);
    free(runs);
    print_message("bias sign flipped: err_rate %.4f (false shadow %.4f) against %.4f\n", bad.err_rate,
                  bad.false_shadow, good.err_rate);
    assert_true(bad.err_rate > 0.05);
    assert_true(bad.err_rate > 10 * good.err_rate);
    assert_true(bad.false_shadow > bad.false_lit);   /* acne: surfaces shadow themselves */
}

/* Mean error of a spec over frames 0, 3, 6, 9 of 12 (as err_rate_mean). */
static void pooled(const sb_run_spec *spec, sb_error_metrics *out) {
    memset(out, 0, sizeof *out);
    sb_err err;
    for (int fr = 0; fr < 12; fr += 3) {
        sb_instance in;
        sb_error_metrics m;
        assert_true(sb_instance_create(&in, &g_towers, spec, 1, &err));
        assert_true(eval_instance(&g_towers, &in, fr, 12, &m, NULL, NULL, &err));
        sb_instance_destroy(&in);
        assert_true(m.pixels > 0);
        out->pixels += m.pixels;
        out->err_rate += m.err_rate / 4;
        out->false_shadow += m.false_shadow / 4;
    }
}

/* bias=auto: on the run's evaluated frames, the chosen offsets keep acne
 * near the least any tried offset reaches and have no more error than the
 * defaults (a candidate); offsets of zero, which it could have chosen, show acne. */
static void test_auto_offsets(void **st) {
    (void)st;
    sb_run_opts keep = g_towers.opts;
    g_towers.opts.frames = 12;
    g_towers.opts.error_every = 3;
    const char *specs[] = {"sm:res=1024:filter=none:bias=auto:slope=auto:normal=auto", "sm:res=1024:filter=none",
                           "sm:res=1024:filter=none:bias=0:slope=0:normal=0"};
    sb_run_spec *runs = NULL;
    int n = 0;
    sb_err err;
    for (int k = 0; k < 3; k++) assert_true(sb_spec_expand(specs[k], NULL, &runs, &n, &err));
    assert_true(sb_autobias_wanted(&runs[0]) && !sb_autobias_wanted(&runs[1]));
    sb_run_spec chosen;
    char text[160];
    int tried = 0;
    assert_true(sb_autobias_choose(&g_towers, &runs[0], &chosen, text, sizeof text, &tried, &err));
    assert_false(sb_autobias_wanted(&chosen));
    sb_error_metrics a, d, z;
    pooled(&chosen, &a);
    pooled(&runs[1], &d);
    pooled(&runs[2], &z);
    print_message("auto %s (%d candidates): err_rate %.5f false shadow %.5f; defaults %.5f / %.5f; zero %.5f / %.5f\n",
                  text, tried, a.err_rate, a.false_shadow, d.err_rate, d.false_shadow, z.err_rate, z.false_shadow);
    assert_true(tried >= 5);   /* the joint ladder at least */
    assert_true(z.false_shadow > 5 * d.false_shadow);                 /* the scene has acne to avoid */
    assert_true(a.false_shadow <= SB_AUTO_REL * fmin(d.false_shadow, z.false_shadow) + SB_AUTO_ABS);
    assert_true(a.err_rate < d.err_rate);   /* towers: the defaults are not the best on these frames */
    assert_true(a.err_rate < z.err_rate);
    /* an instance is never made with an uncalibrated auto value */
    sb_instance in;
    assert_false(sb_instance_create(&in, &g_towers, &runs[0], 1, &err));
    assert_non_null(strstr(err.msg, "bias=auto"));
    free(runs);
    g_towers.opts = keep;
}

/* Readbacks counted through the loader while the timed frames run. */
static unsigned long g_timed_reads;
static PFNGLREADPIXELSPROC o_readpix;
static PFNGLGETBUFFERSUBDATAPROC o_getbuf;
static PFNGLGETTEXIMAGEPROC o_getteximg;
static void GLAD_API_PTR c_readpix(GLint a, GLint b, GLsizei c, GLsizei d, GLenum e, GLenum f, void *g) {
    g_timed_reads += g_towers.timed;
    o_readpix(a, b, c, d, e, f, g);
}
static void GLAD_API_PTR c_getbuf(GLenum a, GLintptr b, GLsizeiptr c, void *d) {
    g_timed_reads += g_towers.timed;
    o_getbuf(a, b, c, d);
}
static void GLAD_API_PTR c_getteximg(GLenum a, GLint b, GLenum c, GLenum d, void *e) {
    g_timed_reads += g_towers.timed;
    o_getteximg(a, b, c, d, e);
}

static char *read_column(const char *csv, const char *name) {
    /* returns the column's values joined by ';' (no quoting in these columns) */
    char *text = strdup(csv), *save = NULL, *out = calloc(1, 65536);
    char *line = strtok_r(text, "\n", &save);
    int col = -1, k = 0;
    for (char *p = line, *f; (f = strsep(&p, ",")); k++)
        if (!strcmp(f, name)) col = k;
    assert_true(col >= 0);
    while ((line = strtok_r(NULL, "\n", &save))) {
        k = 0;
        for (char *p = line, *f; (f = strsep(&p, ",")); k++)
            if (k == col) {
                strcat(out, f);
                strcat(out, ";");
            }
    }
    free(text);
    return out;
}

static void test_evaluation_does_not_touch_timed_frames(void **st) {
    (void)st;
    char dir[] = "/tmp/sbaccXXXXXX";
    assert_non_null(mkdtemp(dir));
    o_readpix = glad_glReadPixels;
    glad_glReadPixels = c_readpix;
    o_getbuf = glad_glGetBufferSubData;
    glad_glGetBufferSubData = c_getbuf;
    o_getteximg = glad_glGetTexImage;
    glad_glGetTexImage = c_getteximg;
    char *csv[2];
    const char *specs[] = {"sm:res=1024", "sdsm:res=1024"};
    for (int sp = 0; sp < 2; sp++) {
        for (int e = 0; e < 2; e++) {
            g_towers.opts.frames = 8;
            g_towers.opts.warmup = 1;
            g_towers.opts.error_every = e ? 2 : 0;
            sb_run_spec *runs = NULL;
            int n = 0;
            sb_err err;
            assert_true(sb_spec_expand(specs[sp], NULL, &runs, &n, &err));
            char out[64], sum_path[128];
            snprintf(out, sizeof out, "%s/%d%d", dir, sp, e);
            assert_true(sb_mkdir_p(out, &err));
            snprintf(sum_path, sizeof sum_path, "%s/summary.csv", out);
            sb_summary sum;
            sb_summary_open(&sum, sum_path);
            g_timed_reads = 0;
            assert_true(sb_run_one(&g_towers, &runs[0], out, &sum, 0, 0, 1));
            print_message("%s error-every %d: %lu readbacks in timed frames\n", specs[sp], e ? 2 : 0, g_timed_reads);
            assert_int_equal(g_timed_reads, 0);
            char run_id[17], path[256];
            sb_session_run_id(&g_towers, &runs[0], run_id);
            snprintf(path, sizeof path, "%s/%s.csv", out, run_id);
            csv[e] = sb_read_file(path, NULL, &err);
            assert_non_null(csv[e]);
            sb_summary_free(&sum);
            free(runs);
        }
        /* the same timed frames either way; only the error columns differ */
        const char *same[] = {"frame", "repeat", "progress", "draw_calls", "shadow_draw_calls", "split_1"};
        for (size_t k = 0; k < sizeof same / sizeof same[0]; k++) {
            char *a = read_column(csv[0], same[k]), *b = read_column(csv[1], same[k]);
            assert_string_equal(a, b);
            free(a);
            free(b);
        }
        char *e0 = read_column(csv[0], "err_rate"), *e1 = read_column(csv[1], "err_rate");
        print_message("err_rate without evaluation: %s\nwith: %s\n", e0, e1);
        assert_string_equal(e0, ";;;;;;;;");
        assert_string_not_equal(e1, ";;;;;;;;");
        free(e0);
        free(e1);
        free(csv[0]);
        free(csv[1]);
    }
    { /* the hook does see readbacks in timed frames: SDSM reading its splits back without latency */
        sb_run_spec *runs = NULL;
        int n = 0;
        sb_err err;
        assert_true(sb_spec_expand("sdsm:res=512:splits=cpu:latency=0", NULL, &runs, &n, &err));
        char out[64], sum_path[128];
        snprintf(out, sizeof out, "%s/cpu", dir);
        assert_true(sb_mkdir_p(out, &err));
        snprintf(sum_path, sizeof sum_path, "%s/summary.csv", out);
        sb_summary sum;
        sb_summary_open(&sum, sum_path);
        g_towers.opts.error_every = 0;
        g_timed_reads = 0;
        assert_true(sb_run_one(&g_towers, &runs[0], out, &sum, 0, 0, 1));
        /* one a measured frame (warm-up frames, finished one by one, are not timed) */
        print_message("sdsm splits=cpu:latency=0: %lu readbacks in %d timed frames\n", g_timed_reads,
                      g_towers.opts.frames);
        assert_int_equal(g_timed_reads, g_towers.opts.frames);
        sb_summary_free(&sum);
        free(runs);
    }
    glad_glReadPixels = o_readpix;
    glad_glGetBufferSubData = o_getbuf;
    glad_glGetTexImage = o_getteximg;
    char cmd[64];
    snprintf(cmd, sizeof cmd, "rm -rf %s", dir);
    assert_int_equal(system(cmd), 0);
    sb_session_close(&g_towers);
}


/* The reference's background (--overlap): whichever way a frame goes (cast
 * there and found, waited for, or taken back by the evaluation and cast
 * there), its answers and rays are those of an evaluation with no cache at
 * all, its first use counts the rays, and every queued frame is accounted for. */
static void test_background_answers(void **st) {
    (void)st;
    sb_run_opts keep = g_towers.opts;
    enum { N = 8 };
    g_towers.opts.frames = N;
    g_towers.opts.error_every = 1;
    g_towers.opts.overlap = 1;
    sb_err err;
    assert_non_null(sb_session_reference(&g_towers, &err));
    sb_ref_cache *kept = g_towers.ref_cache;
    g_towers.ref_cache = NULL; /* no answers kept: every frame cast by its evaluation */
    sb_error_metrics alone[N], bg[N];
    for (int i = 0; i < N; i++) assert_true(eval_frame(&g_towers, "sm:res=1024", i, N, &alone[i], NULL, NULL, &err));
    g_towers.ref_cache = sb_ref_cache_new(SB_REF_CACHE_BYTES);
    assert_true(sb_eval_background(&g_towers, &err));
    /* the last frames first: they are likely still queued when asked for */
    for (int i = N - 1; i >= 0; i--) assert_true(eval_frame(&g_towers, "sm:res=1024", i, N, &bg[i], NULL, NULL, &err));
    sb_ref_background_stats stats = sb_ref_background_stop(g_towers.ref_cache);
    print_message("background: %d queued, %d cast, %d taken back, %d dropped, %d waits\n", stats.queued, stats.frames,
                  stats.taken_back, stats.dropped, stats.waited);
    assert_int_equal(stats.queued, N);
    assert_int_equal(stats.frames + stats.taken_back + stats.dropped, N);
    int from_bg = 0;
    for (int i = 0; i < N; i++) {
        assert_true(alone[i].rays > 0);
        assert_int_equal(bg[i].rays, alone[i].rays); /* counted by the first use, cast wherever */
        assert_false(bg[i].reused);
        from_bg += bg[i].background;
        assert_int_equal(bg[i].pixels, alone[i].pixels);
        assert_true(bg[i].err_rate == alone[i].err_rate && bg[i].vis_mae == alone[i].vis_mae);
        assert_int_equal(bg[i].geom_mismatches, alone[i].geom_mismatches);
        assert_int_equal(bg[i].floor_disagree, alone[i].floor_disagree);
    }
    assert_int_equal(from_bg, stats.frames);
    /* a second evaluation of a frame reuses what the first left */
    sb_error_metrics again;
    assert_true(eval_frame(&g_towers, "pssm:res=1024", 0, N, &again, NULL, NULL, &err));
    assert_true(again.reused && again.rays == 0 && !again.background);
    sb_ref_cache_free(g_towers.ref_cache);
    g_towers.ref_cache = kept;
    g_towers.opts = keep;
}

/* queries mode: every GL_QUERY_RESULT read finds its result available (the
 * frame's fence was waited for first), for a ring of 1 and of 3 frames. */
static unsigned long g_query_reads, g_unavailable;
static PFNGLGETQUERYOBJECTUI64VPROC o_getq64;
static void GLAD_API_PTR c_getq64(GLuint id, GLenum pname, GLuint64 *out) {
    if (pname == GL_QUERY_RESULT) {
        GLuint avail = 0;
        glad_glGetQueryObjectuiv(id, GL_QUERY_RESULT_AVAILABLE, &avail);
        g_query_reads++;
        g_unavailable += !avail;
    }
    o_getq64(id, pname, out);
}

static void test_query_reads_never_block(void **st) {
    (void)st;
    char dir[] = "/tmp/sbqryXXXXXX";
    assert_non_null(mkdtemp(dir));
    sb_timing_mode keep = g_towers.timing;
    g_towers.timing = SB_TIMING_QUERIES;
    g_towers.opts.frames = 10;
    g_towers.opts.warmup = 2;
    g_towers.opts.error_every = 0;
    o_getq64 = glad_glGetQueryObjectui64v;
    glad_glGetQueryObjectui64v = c_getq64;
    const char *specs[] = {"sm:res=512", "sdsm:res=512"};
    for (int ring = 1; ring <= 3; ring += 2)
        for (int k = 0; k < 2; k++) {
            g_towers.opts.ring = ring;
            sb_run_spec *runs = NULL;
            int n = 0;
            sb_err err;
            assert_true(sb_spec_expand(specs[k], NULL, &runs, &n, &err));
            char sum_path[128];
            snprintf(sum_path, sizeof sum_path, "%s/summary.csv", dir);
            sb_summary sum;
            sb_summary_open(&sum, sum_path);
            g_query_reads = g_unavailable = 0;
            assert_true(sb_run_one(&g_towers, &runs[0], dir, &sum, 0, 0, 1));
            print_message("%s ring %d: %lu query results read, %lu unavailable\n", specs[k], ring, g_query_reads,
                          g_unavailable);
            assert_true(g_query_reads >= 12 * 2);   /* the hook sees the reads */
            assert_int_equal(g_unavailable, 0);
            sb_summary_free(&sum);
            free(runs);
        }
    glad_glGetQueryObjectui64v = o_getq64;
    g_towers.timing = keep;
    g_towers.opts.ring = 3;
    tmp_remove(dir);
}

/* overhangs' path ends on a far view: its far plane reaches well beyond the
 * scene. A warp fitted to the view frustum rather than to the part of it
 * inside the scene spends its resolution on empty space; fitted to what can be
 * seen, each warp has well under half the uniform map's error. */
static void test_warps_fit_the_visible_scene(void **st) {
    (void)st;
    sb_session s;
    sb_err err;
    assert_true(test_open(&s, "overhangs", "overhangs", 480, 270, &err));
    const char *specs[] = {"sm:res=2048:filter=none", "tsm:res=2048:filter=none", "lispsm:res=2048:filter=none"};
    double e[3] = {0};
    for (int fr = 0; fr <= 6; fr += 3)
        for (int k = 0; k < 3; k++) {
            sb_error_metrics m;
            assert_true(eval_frame(&s, specs[k], fr, 12, &m, NULL, NULL, &err));
            e[k] += m.err_rate / 3;
        }
    print_message("overhangs frames 0,3,6: err_rate sm %.5f tsm %.5f lispsm %.5f\n", e[0], e[1], e[2]);
    assert_true(e[1] < 0.5 * e[0]);
    assert_true(e[2] < 0.5 * e[0]);
    sb_session_close(&s);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_reference_matches_analytic),
        cmocka_unit_test(test_error_falls_with_resolution),
        cmocka_unit_test(test_broken_bias_is_detected),
        cmocka_unit_test(test_auto_offsets),
        cmocka_unit_test(test_background_answers),
        cmocka_unit_test(test_query_reads_never_block),
        cmocka_unit_test(test_evaluation_does_not_touch_timed_frames),
        cmocka_unit_test(test_warps_fit_the_visible_scene),   /* its own session: after g_towers closes */
    };
    return cmocka_run_group_tests_name("accuracy", tests, NULL, NULL);
}
