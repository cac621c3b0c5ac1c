/* Integration: real rendering on llvmpipe, checked against geometry.
 * plane-box is a 2x2x2 box on a plane under a known sun; the analytic shadow
 * is a ray/box test for every plane pixel the camera sees. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>
#include <stdlib.h>
#include <string.h>

#include "cascade.h"
#include "support.h"
#include "timing.h"

static void check_backend(sb_backend b) {
    sb_session s;
    sb_err err;
    assert_true(pb_open(&s, b, 640, 360, &err));
    /* the sun comes from the file's KHR_lights_punctual light (azimuth 30, elevation 50) */
    sb_v3 expect = sb_sun_dir(30, 50);
    assert_true(s.scene.has_sun);
    assert_true(sb_v3_len(sb_v3_sub(s.scene.sun, expect)) < 1e-6);
    pb_result r;
    assert_true(pb_render(&s, "sm:res=2048", &r, NULL, &err));
    print_message("%s: plane %ld px, shadow exact %ld, sm %ld, mismatch %ld (%.3f%% of image)\n",
                  sb_backend_name(b), r.plane, r.shadow_exact, r.shadow_tech, r.mismatch,
                  100.0 * r.mismatch / r.pixels);
    assert_true(r.plane > r.pixels / 4);              /* the camera sees the plane */
    assert_true(r.shadow_exact > r.pixels / 100);     /* and a real shadow on it */
    assert_true(r.mismatch < r.pixels / 100);         /* within 1% of the image */
    long diff = labs(r.shadow_tech - r.shadow_exact);
    assert_true(diff < r.pixels / 100);
    /* none shadows nothing */
    assert_true(pb_render(&s, "none", &r, NULL, &err));
    assert_int_equal(r.shadow_tech, 0);
    sb_session_close(&s);
}

static void test_sm_matches_analytic_egl(void **st) {
    (void)st;
    check_backend(SB_BACKEND_EGL);
}

static void test_sm_matches_analytic_osmesa(void **st) {
    (void)st;
    check_backend(SB_BACKEND_OSMESA);
}

static void test_low_resolution_is_worse(void **st) {
    (void)st;
    sb_session s;
    sb_err err;
    assert_true(pb_open(&s, SB_BACKEND_EGL, 640, 360, &err));
    pb_result lo, hi;
    assert_true(pb_render(&s, "sm:res=64:filter=none", &lo, NULL, &err));
    assert_true(pb_render(&s, "sm:res=2048:filter=none", &hi, NULL, &err));
    print_message("mismatch res=64 %ld, res=2048 %ld\n", lo.mismatch, hi.mismatch);
    assert_true(lo.mismatch > 2 * hi.mismatch);
    sb_session_close(&s);
}

static void test_cascaded_match_analytic(void **st) {
    (void)st;
    sb_session s;
    sb_err err;
    assert_true(pb_open(&s, SB_BACKEND_EGL, 640, 360, &err));
    const char *specs[] = {"pssm:res=1024", "pssm:res=1024:layered=gs:stable=on", "sdsm:res=1024",
                           "sdsm:res=1024:splits=cpu:latency=0", "sdsm:res=1024:tight=on:partition=histogram",
                           "pssm:res=1024:select=map:blend=0.2:filter=pcf3", "lispsm:res=1024",
                           "pssm:res=1024:warp=lispsm", "sdsm:res=1024:splits=cpu:warp=lispsm", "tsm:res=1024",
                           "pssm:res=1024:warp=tsm:layered=gs", "psm:res=1024", "psm:res=1024:cube=on",
                           "psm:res=1024:cube=on:layered=gs", "psm:res=1024:behind=shift"};
    for (size_t i = 0; i < sizeof specs / sizeof specs[0]; i++) {
        pb_result r;
        bool ok = pb_render(&s, specs[i], &r, NULL, &err);
        if (!ok) print_error("%s\n", err.msg);
        assert_true(ok);
        print_message("%s: shadow exact %ld, technique %ld, mismatch %ld (%.3f%% of image)\n", specs[i], r.shadow_exact,
                      r.shadow_tech, r.mismatch, 100.0 * r.mismatch / r.pixels);
        assert_true(r.shadow_exact > r.pixels / 100);
        assert_true(r.mismatch < r.pixels / 100);
    }
    sb_session_close(&s);
}

static void test_pcss_converges_to_hard(void **st) {
    (void)st;
    sb_session s;
    sb_err err;
    assert_true(pb_open(&s, SB_BACKEND_EGL, 640, 360, &err));
    sb_error_metrics hard, zero, soft, wide;
    assert_true(eval_frame(&s, "sm:filter=none", 0, 1, &hard, NULL, NULL, &err));
    assert_true(eval_frame(&s, "sm:filter=pcss:sun_size=0", 0, 1, &zero, NULL, NULL, &err));
    assert_true(eval_frame(&s, "sm:filter=pcss:sun_size=1", 0, 1, &soft, NULL, NULL, &err));
    assert_true(eval_frame(&s, "sm:filter=pcss:sun_size=4", 0, 1, &wide, NULL, NULL, &err));
    print_message("pcss vis_mae: hard %.5f, sun 0 %.5f, 1 deg %.5f, 4 deg %.5f; err_rate %.5f %.5f %.5f %.5f\n",
                  hard.vis_mae, zero.vis_mae, soft.vis_mae, wide.vis_mae, hard.err_rate, zero.err_rate, soft.err_rate,
                  wide.err_rate);
    /* a point-sized sun gives the hard shadow; a wider one widens the penumbra */
    assert_true(fabs(zero.vis_mae - hard.vis_mae) < 0.002);
    assert_true(zero.err_rate < 0.005);
    assert_true(soft.vis_mae > zero.vis_mae);
    assert_true(wide.vis_mae > soft.vis_mae);
    assert_true(wide.err_rate < 0.05);   /* the binary state stays mostly right */
    sb_session_close(&s);
}

static void test_filtered_formats_converge(void **st) {
    (void)st;
    sb_session s;
    sb_err err;
    assert_true(pb_open(&s, SB_BACKEND_EGL, 640, 360, &err));
    sb_error_metrics hard;
    assert_true(eval_frame(&s, "sm:res=1024:filter=none", 0, 1, &hard, NULL, NULL, &err));
    const char *formats[] = {"vsm", "esm", "msm"};
    for (int i = 0; i < 3; i++) {
        sb_error_metrics m[3];
        const int blur[3] = {0, 2, 6};
        for (int b = 0; b < 3; b++) {
            char spec[96];
            snprintf(spec, sizeof spec, "sm:res=1024:format=%s:blur=%d:bleed=0", formats[i], blur[b]);
            bool ok = eval_frame(&s, spec, 0, 1, &m[b], NULL, NULL, &err);
            if (!ok) print_error("%s\n", err.msg);
            assert_true(ok);
        }
        print_message("%s: vis_mae blur 0 %.5f, 2 %.5f, 6 %.5f (hard %.5f); err_rate %.5f %.5f %.5f (hard %.5f)\n",
                      formats[i], m[0].vis_mae, m[1].vis_mae, m[2].vis_mae, hard.vis_mae, m[0].err_rate, m[1].err_rate,
                      m[2].err_rate, hard.err_rate);
        /* no filter width: the hard result; wider filters: softer edges */
        assert_true(m[0].err_rate < hard.err_rate + 0.003);
        assert_true(fabs(m[0].vis_mae - hard.vis_mae) < 0.004);
        assert_true(m[2].vis_mae > m[0].vis_mae);
    }
    sb_session_close(&s);
}

/* The sun low behind a low camera whose plane the box is behind: the box's
 * shadow falls forward over most of the view (tests/data/planebox-behind.path).
 * In the camera's post-projective space the sun is an inverted point light and
 * the box lies beyond the plane at infinity. PSM's inverse projection orders
 * it in front of every receiver; the naive ordering (an ordinary near plane)
 * clips it and loses the shadow; the virtual camera shift keeps it at a cost in
 * resolution. Checked against the analytic shadow and the ray-cast reference. */
static void test_psm_sun_behind_camera(void **st) {
    (void)st;
    sb_session s;
    sb_err err;
    assert_true(pb_open_view(&s, SB_BACKEND_EGL, 480, 270, "planebox-behind.path", 30, 20, &err));
    /* the setup is what it claims: every box corner behind the camera, the sun behind too */
    sb_camera cam = sb_path_camera(&s.path, 0, 1, 480.0 / 270, &s.scene);
    for (int k = 0; k < 8; k++) {
        sb_v3 c = sb_v3_make(k & 1 ? 1 : -1, k & 2 ? 2 : 0, k & 4 ? 1 : -1);
        assert_true(sb_v3_dot(sb_v3_sub(c, cam.pos), cam.forward) < 0);
    }
    assert_true(sb_v3_dot(s.gpu.sun, cam.forward) < 0);
    const char *specs[] = {"psm", "psm:behind=shift", "psm:cube=on", "psm:behind=naive"};
    pb_result r[4];
    sb_error_metrics m[4];
    for (int i = 0; i < 4; i++) {
        bool ok = pb_render(&s, specs[i], &r[i], NULL, &err) && eval_frame(&s, specs[i], 0, 1, &m[i], NULL, NULL, &err);
        if (!ok) print_error("%s\n", err.msg);
        assert_true(ok);
        print_message("%-18s analytic: shadow %ld, technique %ld, mismatch %ld (%.3f%%); reference: err_rate %.5f, "
                      "res_err_mean %.3f\n", specs[i], r[i].shadow_exact, r[i].shadow_tech, r[i].mismatch,
                      100.0 * r[i].mismatch / r[i].pixels, m[i].err_rate, m[i].res_err_mean);
    }
    assert_true(r[0].shadow_exact > r[0].pixels / 4);   /* the shadow fills much of the view */
    for (int i = 0; i < 3; i++) {
        assert_true(r[i].mismatch < r[i].pixels / 200);
        assert_true(m[i].err_rate < 0.002);
    }
    /* the shift costs resolution: coarser texels than the inverse projection */
    assert_true(m[1].res_err_mean > m[0].res_err_mean + 0.1);
    /* the naive ordering loses (nearly) the whole shadow */
    assert_true(r[3].mismatch > r[3].shadow_exact / 2);
    assert_true(m[3].err_rate > 0.3);
    sb_session_close(&s);
}

static void test_backends_agree(void **st) {
    (void)st;
    const int w = 320, h = 180;
    unsigned char *va = malloc((size_t)w * h), *vb = malloc((size_t)w * h);
    sb_session a, b;
    sb_err err;
    pb_result ra, rb;
    assert_true(pb_open(&a, SB_BACKEND_EGL, w, h, &err));
    assert_true(pb_render(&a, "sm:res=1024:filter=pcf3", &ra, va, &err));
    sb_session_close(&a);
    assert_true(pb_open(&b, SB_BACKEND_OSMESA, w, h, &err));
    assert_true(pb_render(&b, "sm:res=1024:filter=pcf3", &rb, vb, &err));
    sb_session_close(&b);
    long differ = 0;
    for (int i = 0; i < w * h; i++) differ += abs((int)va[i] - (int)vb[i]) > 8;
    print_message("egl vs osmesa: %ld of %d visibility pixels differ\n", differ, w * h);
    assert_true(differ <= w * h / 1000);
    assert_int_equal(ra.plane, rb.plane);
    free(va);
    free(vb);
}

/* Is `name` an output of program p? */
static bool has_output(GLuint p, const char *name) {
    return glGetProgramResourceIndex(p, GL_PROGRAM_OUTPUT, name) != GL_INVALID_INDEX;
}

/* Fills a colour attachment of the camera target with v. */
static void fill_target(const sb_gpu *g, int att, const float v[4]) {
    glBindFramebuffer(GL_FRAMEBUFFER, g->fbo);
    const GLenum all[] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1, GL_COLOR_ATTACHMENT2, GL_COLOR_ATTACHMENT3};
    glDrawBuffers(4, all);
    glClearBufferfv(GL_COLOR, att, v);
}

/* Reads attachment att of the camera target (RGBA float). */
static void read_target(const sb_gpu *g, int att, float *buf) {
    glBindFramebuffer(GL_READ_FRAMEBUFFER, g->fbo);
    glReadBuffer(GL_COLOR_ATTACHMENT0 + att);
    glReadPixels(0, 0, g->width, g->height, GL_RGBA, GL_FLOAT, buf);
    glReadBuffer(GL_COLOR_ATTACHMENT0);
}

/* Pixels of attachment att that differ from `before` (as read_target read it). */
static long changed(const sb_gpu *g, int att, const float *before, float *buf) {
    read_target(g, att, buf);
    long n = 0;
    for (long i = 0; i < (long)g->width * g->height; i++) n += memcmp(&buf[4 * i], &before[4 * i], 16) != 0;
    return n;
}

/* Timed frames run none of the evaluation's work, for every technique: the
 * program of their camera pass writes colour alone (no visibility, position or
 * normal outputs, no evaluation uniform), and the visibility, position and
 * normal targets come out of the frame as they went in (but raycast's, whose
 * rays start from the positions its own pass writes). The evaluation pass
 * of the same technique writes all three. */
static void test_timed_frames_skip_evaluation(void **st) {
    (void)st;
    const int w = 160, h = 90;
    sb_session s;
    sb_err err;
    assert_true(test_open(&s, "plane-box-lamp", "plane-box-lamp", w, h, &err));
    float *buf = malloc(sizeof(float) * 4 * w * h), *before[4];
    for (int att = 1; att <= 3; att++) before[att] = malloc(sizeof(float) * 4 * w * h);
    const float mark[4] = {0.25f, -7, 3, 9};
    int checked = 0;
    for (int i = 0; i < sb_technique_count(); i++) {
        const sb_technique *t = sb_technique_at(i);
        if (t->traits & SB_TRAIT_FOREIGN) {   /* another renderer's frames (score): it has no timed frame */
            assert_int_equal(t->stage_count, 0);
            checked++;
            continue;
        }
        sb_run_spec *runs = NULL;
        int n = 0;
        assert_true(sb_spec_expand(t->name, NULL, &runs, &n, &err));
        sb_instance in;
        bool ok = sb_instance_create(&in, &s, &runs[0], 2, &err);
        free(runs);
        if (!ok) {
            print_error("%s: %s\n", t->name, err.msg);
            fail();
        }
        sb_timer timer;
        sb_timer_init(&timer, SB_TIMING_SYNC, 1, 2);
        for (int att = 1; att <= 3; att++) {
            fill_target(&s.gpu, att, mark);
            read_target(&s.gpu, att, before[att]);
        }
        sb_frame f;
        memset(&f, 0, sizeof f);
        sb_timer_frame_begin(&timer, 0);
        sb_render_frame(&s, &in, &f, 0, 1, 0, &timer);
        GLint prog = 0;
        glGetIntegerv(GL_CURRENT_PROGRAM, &prog);
        long vis = changed(&s.gpu, 1, before[1], buf), pos = changed(&s.gpu, 2, before[2], buf),
             aux = changed(&s.gpu, 3, before[3], buf);
        print_message("%-8s timed: outputs colour %d vis %d pos %d aux %d; pixels written vis %ld pos %ld aux %ld\n",
                      t->name, has_output(prog, "o_color"), has_output(prog, "o_vis"), has_output(prog, "o_pos"),
                      has_output(prog, "o_aux"), vis, pos, aux);
        /* the camera pass is the last of every technique's frame: its program is the one in use */
        assert_true(has_output(prog, "o_color"));
        assert_false(has_output(prog, "o_vis") || has_output(prog, "o_pos") || has_output(prog, "o_aux"));
        assert_int_equal(glGetUniformLocation(prog, "sb_eval"), -1);
        /* raycast's position pass (its z-pass stage) is the technique's own work: its rays start there */
        if (strcmp(t->name, "raycast")) assert_int_equal(vis + pos + aux, 0);

        memset(&f, 0, sizeof f);
        sb_timer_frame_begin(&timer, 1);
        render_frame_eval(&s, &in, &f, 0, 1, 1, &timer);
        glGetIntegerv(GL_CURRENT_PROGRAM, &prog);
        pos = changed(&s.gpu, 2, before[2], buf);
        print_message("%-8s evaluation: outputs vis %d pos %d aux %d; position pixels written %ld\n", t->name,
                      has_output(prog, "o_vis"), has_output(prog, "o_pos"), has_output(prog, "o_aux"), pos);
        assert_true(has_output(prog, "o_vis") && has_output(prog, "o_pos") && has_output(prog, "o_aux"));
        assert_true(pos > (long)w * h / 4);
        assert_true(sb_gl_check(t->name, &err));
        sb_timer_free(&timer);
        sb_instance_destroy(&in);
        checked++;
    }
    assert_int_equal(checked, sb_technique_count());
    for (int att = 1; att <= 3; att++) free(before[att]);
    free(buf);
    sb_session_close(&s);
}

/* A scene with alpha-tested and opaque draws draws the opaque ones with
 * variants that have no alpha test (no discard, early depth testing kept) in
 * every scene pass: z-pass, shadow maps and camera pass; the alpha-tested ones
 * with it. A scene with none has one variant. (That the alpha test still
 * shapes the shadows: conformance, test_raster_matches_reference.) */
static void test_opaque_draws_skip_alpha_test(void **st) {
    (void)st;
    sb_session s;
    sb_err err;
    assert_true(test_open(&s, "conf-alpha-card", "conf-alpha-card", 160, 90, &err));
    assert_true(s.scene.alpha_tested_draws > 0 && s.scene.alpha_tested_draws < s.scene.draw_count);
    sb_run_spec *runs = NULL;
    int n = 0;
    assert_true(sb_spec_expand("pssm:layered=gs", NULL, &runs, &n, &err));
    sb_instance in;
    assert_true(sb_instance_create(&in, &s, &runs[0], 1, &err));
    free(runs);
    const sb_csm *c = in.state;
    const GLuint progs[][2] = {{s.gpu.zpass_prog[0], s.gpu.zpass_prog[1]},
                               {c->pass[0].prog_cascade, c->pass[1].prog_cascade},
                               {c->pass[0].prog_layered, c->pass[1].prog_layered},
                               {c->fp.v[0].prog, c->fp.v[1].prog},
                               {c->fp.v[2].prog, c->fp.v[3].prog}};
    for (size_t k = 0; k < sizeof progs / sizeof progs[0]; k++) {
        print_message("pass %zu: opaque variant %u (alpha texels %d), alpha-tested variant %u (alpha texels %d)\n", k,
                      progs[k][0], glGetUniformLocation(progs[k][0], "sb_texels"), progs[k][1],
                      glGetUniformLocation(progs[k][1], "sb_texels"));
        assert_true(progs[k][0] && progs[k][1]);
        assert_int_equal(glGetUniformLocation(progs[k][0], "sb_texels"), -1);
        assert_true(glGetUniformLocation(progs[k][1], "sb_texels") >= 0);
    }
    sb_instance_destroy(&in);
    sb_session_close(&s);

    assert_true(test_open(&s, "plane-box", "plane-box", 160, 90, &err));
    runs = NULL;   /* sb_spec_expand appends */
    n = 0;
    assert_true(sb_spec_expand("pssm", NULL, &runs, &n, &err));
    assert_true(sb_instance_create(&in, &s, &runs[0], 1, &err));
    free(runs);
    c = in.state;
    assert_true(c->fp.v[0].prog && c->pass[0].prog_cascade && s.gpu.zpass_prog[0]);
    assert_true(!c->fp.v[1].prog && !c->fp.v[3].prog && !c->pass[1].prog_cascade && !s.gpu.zpass_prog[1]);
    sb_instance_destroy(&in);
    sb_session_close(&s);
}

/* The programs alive in the context, by their labels: every one that reads the
 * alpha test's texels (sb_texels active) is an alpha-tested variant (its label
 * ends in " (alpha-tested draws)"), and each has its opaque sibling (the same
 * label without the ending) that does not read them. The number of pairs. */
static int alpha_variant_pairs(void) {
    static const char suffix[] = " (alpha-tested draws)";
    const size_t ls = sizeof suffix - 1;
    char labels[512][256];
    bool alpha[512];
    int n = 0;
    for (GLuint p = 1; p < 65536 && n < 512; p++) {
        if (!glIsProgram(p)) continue;
        GLsizei len = 0;
        glGetObjectLabel(GL_PROGRAM, p, sizeof labels[n], &len, labels[n]);
        labels[n][len] = 0;
        alpha[n] = glGetUniformLocation(p, "sb_texels") >= 0;
        n++;
    }
    int pairs = 0;
    for (int i = 0; i < n; i++) {
        size_t len = strlen(labels[i]);
        bool marked = len > ls && !strcmp(labels[i] + len - ls, suffix);
        if (alpha[i] != marked) print_message("program '%s': alpha test %s\n", labels[i], alpha[i] ? "on" : "off");
        assert_int_equal(alpha[i], marked);
        if (!marked) continue;
        int sibling = -1;
        for (int j = 0; j < n && sibling < 0; j++)
            if (strlen(labels[j]) == len - ls && !strncmp(labels[j], labels[i], len - ls)) sibling = j;
        print_message("'%s': opaque sibling %s\n", labels[i], sibling >= 0 ? "found" : "missing");
        assert_true(sibling >= 0 && !alpha[sibling]);
        pairs++;
    }
    return pairs;
}

/* The point-light techniques' own shadow passes split the same way (their
 * programs are their own): cube per face and layered both ways, and dpsm, on
 * the alpha card with its lamp. Only their programs are alive besides the
 * session's, so the labels tell which passes have both variants. */
static void test_lamp_passes_skip_alpha_test(void **st) {
    (void)st;
    sb_session s;
    sb_err err;
    assert_true(test_open(&s, "conf-alpha-card", "conf-alpha-card", 160, 90, &err));
    const int session = alpha_variant_pairs();   /* the z-pass */
    assert_true(session >= 1);
    const char *specs[] = {"cube:layered=off", "cube:layered=gs", "cube:layered=vs", "dpsm"};
    for (size_t k = 0; k < sizeof specs / sizeof specs[0]; k++) {
        sb_run_spec *runs = NULL;
        int n = 0;
        assert_true(sb_spec_expand(specs[k], NULL, &runs, &n, &err));
        sb_instance in;
        assert_true(sb_instance_create(&in, &s, &runs[0], 1, &err));
        free(runs);
        /* its shadow pass, and the camera pass's timed and evaluation variants */
        int pairs = alpha_variant_pairs() - session;
        print_message("%s: %d pass(es) with both variants\n", specs[k], pairs);
        assert_int_equal(pairs, 3);
        sb_instance_destroy(&in);
    }
    sb_session_close(&s);
}

/* (In a GL test of its own, not the loader suite's conformance test, which the sanitizer build runs: Mesa's
 * contexts keep allocations LeakSanitizer reports.) What `info SCENE` says a scene takes on the GPU is what the session's buffers hold, as the GL reports their
 * sizes: a scene without alpha-tested draws (vertex and index buffers) and one with (and its materials and
 * texels), and the draws' transforms. */
static void test_gpu_bytes_are_the_buffers(void **st) {
    (void)st;
    const char *scenes[] = {"plane-box", "conf-alpha-card"};
    for (size_t i = 0; i < SB_COUNT(scenes); i++) {
        sb_session s;
        sb_err err;
        assert_true(test_open(&s, scenes[i], scenes[i], 64, 36, &err));
        GLuint bufs[5] = {s.gpu.vbo, s.gpu.ibo, s.gpu.mat_ssbo, s.gpu.texel_buf, s.gpu.xform_buf};
        double gl = 0;
        for (int k = 0; k < 5; k++) {
            if (!bufs[k]) continue;
            GLint64 size = 0;
            glBindBuffer(GL_COPY_READ_BUFFER, bufs[k]);
            glGetBufferParameteri64v(GL_COPY_READ_BUFFER, GL_BUFFER_SIZE, &size);
            gl += (double)size;
        }
        double said = sb_gpu_scene_bytes(&s.scene);
        print_message("%s: GL buffers %.0f bytes, info says %.0f (CPU %.0f)\n", scenes[i], gl, said,
                      sb_scene_cpu_bytes(&s.scene));
        assert_true(gl == said);
        assert_true(sb_scene_cpu_bytes(&s.scene) >= (double)s.scene.index_count * 4 + s.scene.vertex_count * (double)SB_VERTEX_BYTES);
        sb_session_close(&s);
    }
    char out[8192];
    assert_int_equal(run_logged(out, sizeof out, "%s info conf-alpha-card", test_binary()), 0);
    assert_non_null(strstr(out, "memory: CPU "));
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_gpu_bytes_are_the_buffers),
        cmocka_unit_test(test_sm_matches_analytic_egl),
        cmocka_unit_test(test_sm_matches_analytic_osmesa),
        cmocka_unit_test(test_low_resolution_is_worse),
        cmocka_unit_test(test_backends_agree),
        cmocka_unit_test(test_cascaded_match_analytic),
        cmocka_unit_test(test_psm_sun_behind_camera),
        cmocka_unit_test(test_pcss_converges_to_hard),
        cmocka_unit_test(test_filtered_formats_converge),
        cmocka_unit_test(test_timed_frames_skip_evaluation),
        cmocka_unit_test(test_opaque_draws_skip_alpha_test),
        cmocka_unit_test(test_lamp_passes_skip_alpha_test),
    };
    return cmocka_run_group_tests_name("planebox", tests, NULL, NULL);
}
