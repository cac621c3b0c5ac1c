/* Cascaded techniques rendered for real on llvmpipe: layered and per-cascade
 * submission agree, SDSM's GPU splits read nothing back in the frame loop,
 * stable fits do not shimmer, all-sky frames render no cascade, the moments
 * blur is the separable Gaussian a CPU computes from the unblurred map, SDSM's
 * depth statistics are the CPU's over the same depth buffer, the evaluation
 * pass sees what the timed frame saw. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "cascade.h"
#include "eval.h"
#include "lightfit.h"
#include "shaders.h"
#include "support.h"

static sb_session g_s;

static int setup(void **st) {
    (void)st;
    sb_run_opts o;
    sb_run_opts_defaults(&o);
    o.width = 320;
    o.height = 180;
    o.frames = 12;
    sb_err err;
    memset(&g_s, 0, sizeof g_s);
    if (!sb_session_open(&g_s, &o, "towers", "towers", &err)) {
        print_error("%s\n", err.msg);
        return -1;
    }
    return 0;
}

static int teardown(void **st) {
    (void)st;
    sb_session_close(&g_s);
    return 0;
}

static bool make(sb_instance *in, const char *spec) {
    sb_run_spec *runs = NULL;
    int n = 0;
    sb_err err;
    bool ok = sb_spec_expand(spec, NULL, &runs, &n, &err) && sb_instance_create(in, &g_s, &runs[0], 16, &err);
    if (!ok) print_error("%s: %s\n", spec, err.msg);
    free(runs);
    return ok;
}

/* Renders path frame i of n as the instance's seq-th frame into *f and reads
 * the visibility target (vis may be NULL). */
static void render_seq(sb_instance *in, int i, int n, int seq, sb_frame *f, unsigned char *vis) {
    sb_timer t;
    sb_timer_init(&t, SB_TIMING_SYNC, 1, 1);
    sb_timer_frame_begin(&t, 0);
    memset(f, 0, sizeof *f);
    if (vis) render_frame_eval(&g_s, in, f, i, n, seq, &t);
    else sb_render_frame(&g_s, in, f, i, n, seq, &t);
    if (vis) sb_gpu_readback(&g_s.gpu, NULL, vis, NULL);
    sb_timer_free(&t);
}

/* Renders path frame i of n and reads the visibility target. */
static sb_counters render(sb_instance *in, int i, int n, unsigned char *vis) {
    sb_frame f;
    render_seq(in, i, n, 0, &f, vis);
    return f.counters;
}

static void test_layered_matches_per_cascade(void **st) {
    (void)st;
    const char *variants[] = {"pssm:layered=off", "pssm:layered=gs", "pssm:layered=vs", "sdsm:layered=off",
                              "sdsm:layered=gs", "sdsm:layered=vs"};
    const int npx = 320 * 180;
    unsigned char *ref = malloc(npx), *vis = malloc(npx);
    for (int frame = 2; frame < 12; frame += 4) {
        for (int v = 0; v < 6; v++) {
            sb_instance in;
            assert_true(make(&in, variants[v]));
            sb_counters c = render(&in, frame, 12, v % 3 == 0 ? ref : vis);
            static uint32_t off_draws;
            if (v % 3 == 0) {
                off_draws = c.shadow_draw_calls;
            } else {
                long differ = 0;
                for (int i = 0; i < npx; i++) differ += abs((int)ref[i] - (int)vis[i]) > 8;
                print_message("frame %d %s: %ld of %d pixels differ from per-cascade; shadow draws %u vs %u\n", frame,
                              variants[v], differ, npx, c.shadow_draw_calls, off_draws);
                assert_true(differ <= npx / 1000);
                assert_true(c.shadow_draw_calls < off_draws);
            }
            sb_instance_destroy(&in);
        }
    }
    free(ref);
    free(vis);
}

/* Readbacks counted through the loader: every GL entry point that moves data to the CPU. */
static unsigned long g_reads;
static PFNGLGETBUFFERSUBDATAPROC o_getbuf;
static PFNGLMAPBUFFERPROC o_map;
static PFNGLMAPBUFFERRANGEPROC o_maprange;
static PFNGLREADPIXELSPROC o_readpix;
static PFNGLGETTEXIMAGEPROC o_getteximg;
static PFNGLGETNAMEDBUFFERSUBDATAPROC o_getnamed;
static void GLAD_API_PTR c_getbuf(GLenum a, GLintptr b, GLsizeiptr c, void *d) { g_reads++; o_getbuf(a, b, c, d); }
static void *GLAD_API_PTR c_map(GLenum a, GLenum b) { g_reads++; return o_map(a, b); }
static void *GLAD_API_PTR c_maprange(GLenum a, GLintptr b, GLsizeiptr c, GLbitfield d) { g_reads++; return o_maprange(a, b, c, d); }
static void GLAD_API_PTR c_readpix(GLint a, GLint b, GLsizei c, GLsizei d, GLenum e, GLenum f, void *g) { g_reads++; o_readpix(a, b, c, d, e, f, g); }
static void GLAD_API_PTR c_getteximg(GLenum a, GLint b, GLenum c, GLenum d, void *e) { g_reads++; o_getteximg(a, b, c, d, e); }
static void GLAD_API_PTR c_getnamed(GLuint a, GLintptr b, GLsizeiptr c, void *d) { g_reads++; o_getnamed(a, b, c, d); }

static void hook_readbacks(bool on) {
    if (on) {
        o_getbuf = glad_glGetBufferSubData; glad_glGetBufferSubData = c_getbuf;
        o_map = glad_glMapBuffer; glad_glMapBuffer = c_map;
        o_maprange = glad_glMapBufferRange; glad_glMapBufferRange = c_maprange;
        o_readpix = glad_glReadPixels; glad_glReadPixels = c_readpix;
        o_getteximg = glad_glGetTexImage; glad_glGetTexImage = c_getteximg;
        o_getnamed = glad_glGetNamedBufferSubData; glad_glGetNamedBufferSubData = c_getnamed;
    } else {
        glad_glGetBufferSubData = o_getbuf;
        glad_glMapBuffer = o_map;
        glad_glMapBufferRange = o_maprange;
        glad_glReadPixels = o_readpix;
        glad_glGetTexImage = o_getteximg;
        glad_glGetNamedBufferSubData = o_getnamed;
    }
}

static unsigned long frame_loop_reads(const char *spec) {
    sb_instance in;
    assert_true(make(&in, spec));
    sb_timer t;
    sb_timer_init(&t, SB_TIMING_SYNC, 1, 12);
    hook_readbacks(true);
    g_reads = 0;
    for (int i = 0; i < 12; i++) {
        sb_frame f;
        memset(&f, 0, sizeof f);
        sb_timer_frame_begin(&t, i);
        sb_render_frame(&g_s, &in, &f, i, 12, i, &t);
    }
    unsigned long reads = g_reads;
    hook_readbacks(false);
    /* after the loop, the GPU splits are collected with one read per frame */
    sb_counters c;
    memset(&c, 0, sizeof c);
    if (strstr(spec, "splits=gpu")) {
        in.tech->collect(in.state, 6, &c);
        assert_int_equal(c.split_count, 4);
        assert_true(c.splits[0] > 0 && c.splits[3] > c.splits[0]);
        assert_int_equal(c.cascades_rendered + c.cascades_skipped, 4);
    }
    sb_timer_free(&t);
    sb_instance_destroy(&in);
    return reads;
}

static void test_sdsm_gpu_splits_read_nothing_back(void **st) {
    (void)st;
    unsigned long gpu = frame_loop_reads("sdsm:splits=gpu");
    unsigned long tight = frame_loop_reads("sdsm:splits=gpu:tight=on:partition=histogram");
    unsigned long cpu0 = frame_loop_reads("sdsm:splits=cpu:latency=0");
    unsigned long cpu2 = frame_loop_reads("sdsm:splits=cpu:latency=2");
    print_message("readbacks in 12 frames: gpu %lu, gpu tight %lu, cpu latency 0 %lu, cpu latency 2 %lu\n", gpu, tight,
                  cpu0, cpu2);
    assert_int_equal(gpu, 0);
    assert_int_equal(tight, 0);
    assert_int_equal(cpu0, 12);   /* the hook sees them: the count above can fail */
    assert_int_equal(cpu2, 10);
}

static sb_camera camera_at(sb_v3 pos, sb_v3 dir, double far) {
    return sb_camera_look(pos, dir, 60, 320.0 / 180, 0.5, far);
}

static void test_all_sky_frame(void **st) {
    (void)st;
    const char *specs[] = {"sdsm:splits=gpu", "sdsm:splits=cpu:latency=0", "pssm"};
    unsigned char *vis = malloc(320 * 180);
    for (int k = 0; k < 3; k++) {
        sb_instance in;
        assert_true(make(&in, specs[k]));
        sb_camera cam = camera_at(sb_v3_make(0, 400, 0), sb_v3_make(0.01, 1, 0), 400);   /* straight up, above the roofs */
        sb_timer t;
        sb_timer_init(&t, SB_TIMING_SYNC, 1, 1);
        sb_timer_frame_begin(&t, 0);
        sb_frame f;
        memset(&f, 0, sizeof f);
        sb_render_camera(&g_s, &in, &f, &cam, 0, &t, true);
        if (in.tech->collect) in.tech->collect(in.state, 0, &f.counters);
        sb_gpu_readback(&g_s.gpu, NULL, vis, NULL);
        print_message("%s: all-sky frame renders %d cascades, skips %d\n", specs[k], f.counters.cascades_rendered,
                      f.counters.cascades_skipped);
        assert_int_equal(f.counters.cascades_rendered, 0);
        assert_int_equal(f.counters.shadow_triangles, 0);
        for (int i = 0; i < 320 * 180; i++) assert_int_equal(vis[i], 255);
        sb_err err;
        assert_true(sb_gl_check(specs[k], &err));
        sb_timer_free(&t);
        sb_instance_destroy(&in);
    }
    free(vis);
}

/* Reads layer 0 of a shadow-map technique's map. */
static float *read_map(sb_instance *in) {
    sb_csm *c = (sb_csm *)in->state;
    float *m = malloc(sizeof(float) * c->d.res * c->d.res * c->count);
    glBindTexture(GL_TEXTURE_2D_ARRAY, c->tex);
    glGetTexImage(GL_TEXTURE_2D_ARRAY, 0, GL_DEPTH_COMPONENT, GL_FLOAT, m);
    return m;
}

/* Renders with two cameras a fraction of a texel apart and compares the maps,
 * allowing for a whole-texel shift of the window; returns differing texels. */
static long shimmer(const char *spec, double texels) {
    sb_instance in;
    assert_true(make(&in, spec));
    sb_csm *c = (sb_csm *)in.state;
    sb_v3 dir = sb_v3_make(0.3, -0.5, 1);
    sb_camera a = camera_at(sb_v3_make(3, 60, -120), dir, 80);
    sb_timer t;
    sb_timer_init(&t, SB_TIMING_SYNC, 1, 2);
    sb_frame f;
    memset(&f, 0, sizeof f);
    sb_timer_frame_begin(&t, 0);
    sb_render_camera(&g_s, &in, &f, &a, 0, &t, false);
    sb_light_fit fa = c->fit[0];
    float *ma = read_map(&in);
    /* move along the light's x axis by a fraction of a texel */
    sb_m4 lv = sb_light_view(g_s.gpu.sun);
    sb_v3 lx = sb_v3_make(lv.m[0], lv.m[4], lv.m[8]);
    sb_camera b = a;
    b.pos = sb_v3_add(a.pos, sb_v3_scale(lx, texels * fa.texel_world));
    sb_timer_frame_begin(&t, 1);
    sb_render_camera(&g_s, &in, &f, &b, 1, &t, false);
    sb_light_fit fb = c->fit[0];
    float *mb = read_map(&in);
    int res = c->d.res;
    double shift = (fb.l - fa.l) / fa.texel_world;
    int dx = (int)lround(shift);
    long differ = 0;
    {
        for (int y = 0; y < res; y++)
            for (int x = 0; x < res; x++) {
                int xs = x + dx;
                if (xs < 0 || xs >= res) continue;
                /* the same world texel; the rasterizer evaluates depth from other window
                   coordinates, so allow rounding (1e-5 of the depth range) */
                differ += fabsf(ma[y * res + xs] - mb[y * res + x]) > 1e-5f;
            }
    }
    print_message("%s: moved %.2f texels, window shifted %.4f texels, %ld texels differ\n", spec, texels, shift, differ);
    free(ma);
    free(mb);
    sb_timer_free(&t);
    sb_instance_destroy(&in);
    return differ;
}

static void test_stable_no_shimmer(void **st) {
    (void)st;
    const long texels = 512 * 512;
    for (double d = 0.15; d < 1.0; d += 0.3) {
        assert_true(shimmer("sm:stable=on:res=512", d) <= texels / 10000);
        assert_true(shimmer("pssm:stable=on:res=512:cascades=2", d) <= texels / 10000);
        assert_true(shimmer("sm:stable=off:res=512", d) > texels / 100);   /* without it the grid swims */
    }
}

/* The offsets and size of the cascade block in one program, as the uniform
 * block readers see (GL_UNIFORM) or as the storage block SDSM's compute
 * shaders write (GL_BUFFER_VARIABLE), against the C struct. */
static void check_block_layout(GLuint prog, GLenum var_iface, GLenum block_iface) {
    const struct {
        const char *name;
        size_t offset;
    } vars[] = {{"sb_light_vp[0]", offsetof(sb_cascade_block, light_vp)},
                {"sb_shadow_mat[0]", offsetof(sb_cascade_block, shadow_mat)},
                {"sb_cascade[0]", offsetof(sb_cascade_block, s.cascade)},
                {"sb_flags[0]", offsetof(sb_cascade_block, s.flags)},
                {"sb_info", offsetof(sb_cascade_block, info)}};
    int active = 0;
    for (size_t i = 0; i < sizeof vars / sizeof vars[0]; i++) {
        GLuint idx = glGetProgramResourceIndex(prog, var_iface, vars[i].name);
        if (idx == GL_INVALID_INDEX) continue; /* optimised out of this program */
        const GLenum prop = GL_OFFSET;
        GLint off = -1;
        glGetProgramResourceiv(prog, var_iface, idx, 1, &prop, 1, NULL, &off);
        print_message("%s: shader offset %d, C offset %zu\n", vars[i].name, off, vars[i].offset);
        assert_int_equal(off, (int)vars[i].offset);
        active++;
    }
    assert_true(active >= 3);
    GLuint block = glGetProgramResourceIndex(prog, block_iface, "SbCascades");
    assert_int_not_equal(block, GL_INVALID_INDEX);
    const GLenum prop = GL_BUFFER_DATA_SIZE;
    GLint size = 0;
    glGetProgramResourceiv(prog, block_iface, block, 1, &prop, 1, NULL, &size);
    print_message("SbCascades: %d bytes in the shader, %zu in C\n", size, sizeof(sb_cascade_block));
    assert_int_equal(size, (int)sizeof(sb_cascade_block));
}

/* The C struct of the cascade block and the shader's block agree, member by
 * member (the offsets the driver reports for every active variable) and in
 * size: in the final pass (a uniform block, both variants) and in a compute
 * shader that writes it (a storage block, as SDSM's). */
static void test_cascade_block_layout(void **st) {
    (void)st;
    sb_instance in;
    /* PCSS and a warp use different members; a warp refuses PCSS (docs/techniques.md): one program each */
    const char *specs[] = {"pssm:filter=pcss", "pssm:warp=lispsm"};
    for (size_t k = 0; k < sizeof specs / sizeof specs[0]; k++) {
        assert_true(make(&in, specs[k]));
        const sb_csm *c = in.state;
        check_block_layout(c->fp.prog, GL_UNIFORM, GL_UNIFORM_BLOCK);
        check_block_layout(c->fp.eval_prog, GL_UNIFORM, GL_UNIFORM_BLOCK);
        sb_instance_destroy(&in);
    }
    const char *src = "layout(local_size_x = 1) in;\n"
                      "void main() { sb_light_vp[1] = sb_shadow_mat[0]; sb_cascade[0] = sb_flags[1] + sb_info; }\n";
    const char *parts[] = {sb_shader_csm_block_glsl, src};
    const sb_shader_src cs[] = {{GL_COMPUTE_SHADER, parts, 2}};
    sb_err err;
    GLuint prog = sb_gpu_link("block layout", "#define SB_CASCADE_STORAGE\n#define SB_CASCADE_ACCESS\n", cs, 1, &err);
    if (!prog) print_error("%s\n", err.msg);
    assert_true(prog != 0);
    check_block_layout(prog, GL_BUFFER_VARIABLE, GL_SHADER_STORAGE_BLOCK);
    glDeleteProgram(prog);
}

/* Every layer of a filtered technique's moments (4 floats a texel, as stored:
 * channels the format lacks read 0, alpha 1). */
static float *read_moments(sb_instance *in) {
    sb_csm *c = (sb_csm *)in->state;
    float *m = malloc(sizeof(float) * 4 * c->d.res * c->d.res * c->count);
    glBindTexture(GL_TEXTURE_2D_ARRAY, c->moments);
    glGetTexImage(GL_TEXTURE_2D_ARRAY, 0, GL_RGBA, GL_FLOAT, m);
    return m;
}

/* One direction of the blur on the CPU: clamped at the edges, weights
 * exp(-i^2 / 2 sigma^2) with sigma = max(r / 2, 1/2), normalised. */
static void cpu_blur(const float *src, float *dst, int res, int layers, int r, int dx, int dy) {
    double sigma = fmax(r * 0.5, 0.5);
    for (int l = 0; l < layers; l++)
        for (int y = 0; y < res; y++)
            for (int x = 0; x < res; x++)
                for (int ch = 0; ch < 4; ch++) {
                    double sum = 0, wsum = 0;
                    for (int i = -r; i <= r; i++) {
                        int qx = x + dx * i, qy = y + dy * i;
                        qx = qx < 0 ? 0 : qx >= res ? res - 1 : qx;
                        qy = qy < 0 ? 0 : qy >= res ? res - 1 : qy;
                        double w = exp(-0.5 * i * i / (sigma * sigma));
                        sum += w * src[(((size_t)l * res + qy) * res + qx) * 4 + ch];
                        wsum += w;
                    }
                    dst[(((size_t)l * res + y) * res + x) * 4 + ch] = (float)(sum / wsum);
                }
}

/* The moments blur (blur.comp: a window of loads per run of texels) against
 * the CPU's from the same frame rendered with blur=0, for each format's
 * channels, radii 1 and 3 and a map side that is no multiple of the runs or
 * the groups, on every cascade of a layered map. */
static void test_moments_blur_matches_cpu(void **st) {
    (void)st;
    const char *formats[] = {"vsm", "esm", "msm"};
    const int radii[] = {1, 3};
    for (int fi = 0; fi < 3; fi++)
        for (int ri = 0; ri < 2; ri++) {
            char raw_spec[128], blur_spec[128];
            const char *base = "pssm:cascades=2:res=203:layered=off:exponent=20";
            snprintf(raw_spec, sizeof raw_spec, "%s:format=%s:blur=0", base, formats[fi]);
            snprintf(blur_spec, sizeof blur_spec, "%s:format=%s:blur=%d", base, formats[fi], radii[ri]);
            sb_instance raw, blurred;
            assert_true(make(&raw, raw_spec));
            assert_true(make(&blurred, blur_spec));
            render(&raw, 3, 12, NULL);
            render(&blurred, 3, 12, NULL);
            sb_csm *c = (sb_csm *)blurred.state;
            int res = c->d.res, layers = c->count;
            for (int k = 0; k < layers; k++) assert_true(c->active[k]);
            float *src = read_moments(&raw), *gpu = read_moments(&blurred);
            size_t n = (size_t)4 * res * res * layers;
            float *tmp = malloc(sizeof(float) * n), *cpu = malloc(sizeof(float) * n);
            cpu_blur(src, tmp, res, layers, radii[ri], 1, 0);
            cpu_blur(tmp, cpu, res, layers, radii[ri], 0, 1);
            double worst = 0, moved = 0;
            for (size_t i = 0; i < n; i++) {
                double scale = fmax(fabs(cpu[i]), 1e-6);
                worst = fmax(worst, fabs(gpu[i] - cpu[i]) / scale);
                moved = fmax(moved, fabs(src[i] - cpu[i]) / scale);
            }
            print_message("%s: worst relative difference from the CPU blur %.3g (the blur moves texels by up to %.3g)\n",
                          blur_spec, worst, moved);
            assert_true(moved > 1e-3);   /* the frame has edges for a blur to move */
            assert_true(worst < 1e-5);
            free(src), free(gpu), free(tmp), free(cpu);
            sb_instance_destroy(&raw);
            sb_instance_destroy(&blurred);
        }
}

/* SDSM's depth statistics (sdsm_reduce.comp, sdsm_bounds.comp: runs of pixels
 * an invocation) against the CPU's over the same depth buffer: visible pixels,
 * nearest and farthest view depth, the log-depth histogram, and with
 * tight=on each partition's pixels and light-space x/y bounds. A pixel on a
 * bin's or a split's edge may fall either side in float arithmetic (a few in
 * a thousand), which moves a partition's bounds by about its size. */
static uint32_t order_bits(float f) {
    uint32_t b;
    memcpy(&b, &f, 4);
    return (b & 0x80000000u) ? ~b : (b | 0x80000000u);
}
static float unorder_bits(uint32_t u) {
    uint32_t b = (u & 0x80000000u) ? (u & 0x7fffffffu) : ~u;
    float f;
    memcpy(&f, &b, 4);
    return f;
}

static void test_sdsm_statistics_match_cpu(void **st) {
    (void)st;
    const char *specs[] = {"sdsm:res=512:splits=cpu:latency=0:partition=histogram",
                           "sdsm:res=512:splits=gpu:tight=on:partition=histogram"};
    for (int si = 0; si < 2; si++) {
        const bool tight = si == 1;
        sb_instance in;
        assert_true(make(&in, specs[si]));
        sb_csm *c = (sb_csm *)in.state;
        for (int frame = 0; frame < 12; frame += 5) {
            sb_frame f;
            render_seq(&in, frame, 12, frame, &f, NULL);
            GLint buf = 0;   /* the statistics: binding 1 (sdsm_common.glsl) */
            glGetIntegeri_v(GL_SHADER_STORAGE_BUFFER_BINDING, 1, &buf);
            assert_true(buf != 0);
            uint32_t gpu[4 + 64 + 8 + 32];
            glBindBuffer(GL_SHADER_STORAGE_BUFFER, (GLuint)buf);
            glGetBufferSubData(GL_SHADER_STORAGE_BUFFER, 0, sizeof gpu, gpu);
            sb_cascade_block block;   /* the partitions the GPU chose (binding 0) */
            glBindBuffer(GL_SHADER_STORAGE_BUFFER, c->block);
            glGetBufferSubData(GL_SHADER_STORAGE_BUFFER, 0, sizeof block, &block);
            int w = g_s.gpu.width, h = g_s.gpu.height, parts = (int)block.info[0];
            float *depth = malloc(sizeof(float) * w * h);
            glBindTexture(GL_TEXTURE_2D, g_s.gpu.depth_tex);
            glGetTexImage(GL_TEXTURE_2D, 0, GL_DEPTH_COMPONENT, GL_FLOAT, depth);
            float n = (float)f.cam.znear, fa = (float)f.cam.zfar;
            uint32_t samples = 0, hist[64] = {0}, pcount[8] = {0}, pb[8][4];
            for (int k = 0; k < 8; k++) pb[k][0] = pb[k][1] = 0xffffffffu, pb[k][2] = pb[k][3] = 0;
            float zmin = INFINITY, zmax = 0;
            sb_m4 inv, lv = sb_light_view(g_s.gpu.sun);
            assert_true(sb_m4_invert(f.view_proj, &inv));
            for (int i = 0; i < w * h; i++) {
                if (!(depth[i] < 1.0f)) continue;
                float z = 2.0f * n * fa / ((fa + n) - (2.0f * depth[i] - 1.0f) * (fa - n));
                samples++;
                zmin = fminf(zmin, z), zmax = fmaxf(zmax, z);
                int b = (int)(64.0f * logf(z / n) / logf(fa / n));
                hist[b < 0 ? 0 : b > 63 ? 63 : b]++;
                if (!tight) continue;
                int k = parts - 1;
                for (int j = 0; j < parts; j++)
                    if (z <= block.s.cascade[j][1]) {
                        k = j;
                        break;
                    }
                sb_v3 ndc = {((i % w) + 0.5) / w * 2 - 1, ((i / w) + 0.5) / h * 2 - 1, 2.0 * depth[i] - 1};
                sb_v3 l = sb_m4_point(lv, sb_m4_point(inv, ndc));
                uint32_t ox = order_bits((float)l.x), oy = order_bits((float)l.y);
                pcount[k]++;
                pb[k][0] = ox < pb[k][0] ? ox : pb[k][0], pb[k][1] = oy < pb[k][1] ? oy : pb[k][1];
                pb[k][2] = ox > pb[k][2] ? ox : pb[k][2], pb[k][3] = oy > pb[k][3] ? oy : pb[k][3];
            }
            free(depth);
            float gmin = unorder_bits(gpu[0]), gmax = unorder_bits(gpu[1]);
            uint32_t gsum = 0, off = 0;
            for (int b = 0; b < 64; b++) gsum += gpu[4 + b], off += (uint32_t)abs((int)gpu[4 + b] - (int)hist[b]);
            print_message("%s frame %d: %u visible pixels (cpu %u), depth %.4f..%.3f (cpu %.4f..%.3f), %u histogram "
                          "counts in another bin\n", specs[si], frame, gpu[2], samples, gmin, gmax, zmin, zmax, off / 2);
            assert_true(samples > 1000);
            assert_int_equal(gpu[2], samples);
            assert_int_equal(gsum, samples);
            assert_true(fabsf(gmin - zmin) <= 1e-5f * zmin);
            assert_true(fabsf(gmax - zmax) <= 1e-5f * zmax);
            assert_true(off / 2 <= samples / 500);
            if (!tight) continue;
            const uint32_t *gcount = gpu + 68, (*gb)[4] = (const uint32_t(*)[4])(gpu + 76);
            uint32_t psum = 0, poff = 0;
            for (int k = 0; k < parts; k++) {
                psum += gcount[k], poff += (uint32_t)abs((int)gcount[k] - (int)pcount[k]);
                if (pcount[k] < 100) continue;
                double ext = fmax(unorder_bits(pb[k][2]) - unorder_bits(pb[k][0]),
                                  unorder_bits(pb[k][3]) - unorder_bits(pb[k][1]));
                double worst = 0;
                for (int e = 0; e < 4; e++) worst = fmax(worst, fabs(unorder_bits(gb[k][e]) - unorder_bits(pb[k][e])));
                print_message("  partition %d: %u pixels (cpu %u), light-space bounds within %.3g of the cpu's "
                              "(extent %.3g)\n", k, gcount[k], pcount[k], worst, ext);
                assert_true(worst <= 1e-3 * ext);
            }
            assert_int_equal(psum, samples);
            assert_true(poff / 2 <= samples / 500);
        }
        sb_instance_destroy(&in);
    }
}

/* The evaluation pass renders a frame again after the run: it must see what
 * the timed frame saw. SDSM with splits=cpu uses the statistics of `latency`
 * frames before (replayed first: sb_instance_history); splits=gpu none. The
 * frames rendered after it leave other frames' statistics behind, so a
 * replay too short shows. */
static void test_eval_sees_the_timed_frame(void **st) {
    (void)st;
    const char *specs[] = {"sdsm:splits=cpu:latency=2", "sdsm:splits=cpu:latency=1", "sdsm:splits=gpu"};
    const int want[] = {2, 1, 0}, n = 12, k = 5;
    int w = g_s.gpu.width, h = g_s.gpu.height;
    unsigned char *timed = malloc((size_t)w * h);
    for (int i = 0; i < 3; i++) {
        sb_instance in;
        assert_true(make(&in, specs[i]));
        assert_int_equal(sb_instance_history(&in), want[i]);
        int seq = 0;
        for (int j = 0; j < n; j++) {
            sb_frame f;
            render_seq(&in, j, n, seq++, &f, j == k ? timed : NULL);
        }
        sb_eval_buf b;
        sb_eval_buf_init(&b, &g_s.gpu, false);
        sb_frame f;
        sb_error_metrics m;
        sb_err err;
        bool ok = sb_eval_frame(&g_s, &in, k, n, sb_instance_history(&in), &seq, &b, &f, &m, &err);
        if (!ok) print_error("%s\n", err.msg);
        assert_true(ok);
        long differ = 0, shadowed = 0;
        for (int p = 0; p < w * h; p++) differ += b.vis[p] != timed[p], shadowed += timed[p] < 128;
        print_message("%s: replays %d, %ld of %d pixels differ from the timed frame (%ld shadowed)\n", specs[i],
                      sb_instance_history(&in), differ, w * h, shadowed);
        assert_true(shadowed > 100);
        assert_int_equal(differ, 0);
        sb_eval_buf_free(&b);
        sb_instance_destroy(&in);
    }
    free(timed);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_layered_matches_per_cascade),
        cmocka_unit_test(test_sdsm_gpu_splits_read_nothing_back),
        cmocka_unit_test(test_all_sky_frame),
        cmocka_unit_test(test_stable_no_shimmer),
        cmocka_unit_test(test_cascade_block_layout),
        cmocka_unit_test(test_moments_blur_matches_cpu),
        cmocka_unit_test(test_sdsm_statistics_match_cpu),
        cmocka_unit_test(test_eval_sees_the_timed_frame),
    };
    return cmocka_run_group_tests_name("cascades", tests, setup, teardown);
}
