#include "scene_load.h"
#include "support.h"

#include "blob.h"
#include "eval.h"
#include "table.h"

#include <setjmp.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <unistd.h>

const char *test_data(const char *name) {
    static char buf[4][4096];
    static int k;
    const char *dir = getenv("SB_TEST_DATA");
    k = (k + 1) % 4;
    snprintf(buf[k], sizeof buf[k], "%s/%s", dir ? dir : "tests/data", name);
    return buf[k];
}

const char *test_binary(void) {
    const char *b = getenv("SB_BINARY");
    return b ? b : "./shadowbench";
}

int run_capture(const char *cmd, char *out, size_t len) {
    char full[8192];
    snprintf(full, sizeof full, "%s 2>&1", cmd);
    FILE *p = popen(full, "r");
    if (!p) return -1;
    /* read to the end: a child whose output outgrew the buffer would otherwise block on the full pipe
       while pclose waits for it, for ever. Past len - 1 bytes the tail is kept (the results folder is
       the last line) and the start marked as cut. */
    size_t n = 0, cut = 0;
    char chunk[4096];
    for (size_t got; (got = fread(chunk, 1, sizeof chunk, p)) > 0;) {
        if (n + got > len - 1) {
            size_t drop = n + got - (len - 1) < n ? n + got - (len - 1) : n;
            memmove(out, out + drop, n - drop);
            n -= drop, cut += drop;
        }
        size_t keep = got > len - 1 ? len - 1 : got;
        memcpy(out + n, chunk + got - keep, keep);
        n += keep, cut += got - keep;
    }
    out[n] = 0;
    if (cut) printf("(the command's output was %zu bytes longer than the test keeps: its first bytes are cut)\n", cut);
    int st = pclose(p);
    return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
}

bool test_open(sb_session *s, const char *scene, const char *path, int w, int h, sb_err *err) {
    sb_run_opts o;
    sb_run_opts_defaults(&o);
    o.width = w;
    o.height = h;
    memset(s, 0, sizeof *s);
    return sb_session_open(s, &o, scene, path, err);
}

int run_logged(char *out, size_t len, const char *fmt, ...) {
    char cmd[8192];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(cmd, sizeof cmd, fmt, ap);
    va_end(ap);
    /* the command first, so that a test killed by its time limit shows what it was waiting for */
    printf("$ %s\n", cmd);
    fflush(stdout);
    double t0 = sb_now_ms();
    int rc = run_capture(cmd, out, len);
    printf("-> %d (%.1f s)\n%.2000s", rc, (sb_now_ms() - t0) / 1e3, out);
    fflush(stdout);
    return rc;
}

bool pb_open(sb_session *s, sb_backend backend, int w, int h, sb_err *err) {
    return pb_open_view(s, backend, w, h, "planebox-fixed.path", NAN, NAN, err);
}

bool pb_open_view(sb_session *s, sb_backend backend, int w, int h, const char *path, double sun_az, double sun_el,
                  sb_err *err) {
    sb_run_opts o;
    sb_run_opts_defaults(&o);
    o.backend = backend;
    o.width = w;
    o.height = h;
    o.frames = 1;
    o.warmup = 0;
    if (!isnan(sun_az)) {
        o.sun_override = true;
        o.sun_az = sun_az;
        o.sun_el = sun_el;
    }
    memset(s, 0, sizeof *s);
    return sb_session_open(s, &o, "plane-box", test_data(path), err);
}

bool pb_box_shadows(sb_v3 p, sb_v3 d) { return pb_box_blocks(p, d, 1e300); }

bool pb_box_blocks(sb_v3 p, sb_v3 d, double tmax) {
    const double lo[3] = {-1, 0, -1}, hi[3] = {1, 2, 1};
    return box_blocks(p, d, tmax, lo, hi);
}

bool box_blocks(sb_v3 p, sb_v3 d, double tmax, const double lo[3], const double hi[3]) {
    const double o[3] = {p.x, p.y, p.z}, v[3] = {d.x, d.y, d.z};
    double t0 = 1e-9, t1 = tmax;
    for (int a = 0; a < 3; a++) {
        if (fabs(v[a]) < 1e-15) {
            if (o[a] < lo[a] || o[a] > hi[a]) return false;
            continue;
        }
        double ta = (lo[a] - o[a]) / v[a], tb = (hi[a] - o[a]) / v[a];
        if (ta > tb) {
            double t = ta;
            ta = tb;
            tb = t;
        }
        if (ta > t0) t0 = ta;
        if (tb < t1) t1 = tb;
        if (t0 > t1) return false;
    }
    return true;
}

void render_frame_eval(sb_session *s, sb_instance *in, sb_frame *f, int i, int n, int seq, sb_timer *t) {
    sb_camera cam = sb_path_camera(&s->path, i, n, (double)s->opts.width / s->opts.height, &s->scene);
    f->index = i;
    f->progress = sb_path_progress(i, n);
    sb_render_camera(s, in, f, &cam, seq, t, true);
}

bool pb_render(sb_session *s, const char *spec, pb_result *out, unsigned char *vis_out, sb_err *err) {
    sb_run_spec *runs = NULL;
    int n = 0;
    if (!sb_spec_expand(spec, NULL, &runs, &n, err)) return false;
    sb_instance in;
    if (!sb_instance_create(&in, s, &runs[0], 1, err)) {
        free(runs);
        return false;
    }
    sb_frame f;
    memset(&f, 0, sizeof f);
    sb_timer timer;
    sb_timer_init(&timer, SB_TIMING_SYNC, 3, 1);
    sb_timer_frame_begin(&timer, 0);
    render_frame_eval(s, &in, &f, 0, 1, 0, &timer);
    int w = s->gpu.width, h = s->gpu.height;
    float *depth = malloc(sizeof(float) * w * h);
    unsigned char *vis = malloc((size_t)w * h);
    sb_gpu_readback(&s->gpu, depth, vis, NULL);
    memset(out, 0, sizeof *out);
    out->pixels = (long)w * h;
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            float d = depth[y * w + x];
            if (d >= 1.0f) continue;
            sb_v3 p = sb_frame_unproject(&f, x, y, d);
            if (fabs(p.y) > 0.02 || fabs(p.x) > 19.9 || fabs(p.z) > 19.9) continue;
            if (fabs(p.x) <= 1 && fabs(p.z) <= 1) continue; /* under the box */
            out->plane++;
            bool tech = vis[y * w + x] < 128;
            bool exact = pb_box_shadows(p, s->gpu.sun);
            out->shadow_tech += tech;
            out->shadow_exact += exact;
            out->mismatch += tech != exact;
        }
    if (vis_out) memcpy(vis_out, vis, (size_t)w * h);
    free(depth);
    free(vis);
    sb_timer_free(&timer);
    sb_instance_destroy(&in);
    free(runs);
    return sb_gl_check("pb_render", err);
}

bool eval_instance(sb_session *s, sb_instance *in, int i, int n, sb_error_metrics *m, float *pos_out,
                   unsigned char *ref_out, sb_err *err) {
    sb_eval_buf b;
    sb_eval_buf_init(&b, &s->gpu, false);
    sb_frame f;
    int seq = 0;
    bool ok = sb_eval_frame(s, in, i, n, 0, &seq, &b, &f, m, err);
    if (pos_out) memcpy(pos_out, b.pos, sizeof(float) * 4 * (size_t)b.w * b.h);
    if (ref_out) memcpy(ref_out, b.ref, (size_t)b.w * b.h);
    sb_eval_buf_free(&b);
    return ok;
}

bool eval_frame(sb_session *s, const char *spec, int i, int n, sb_error_metrics *m, float *pos_out, unsigned char *ref_out,
                sb_err *err) {
    sb_run_spec *runs = NULL;
    int nr = 0;
    if (!sb_spec_expand(spec, NULL, &runs, &nr, err)) return false;
    sb_instance in;
    bool ok = sb_instance_create(&in, s, &runs[0], 1, err);
    free(runs);
    if (!ok) return false;
    ok = eval_instance(s, &in, i, n, m, pos_out, ref_out, err);
    sb_instance_destroy(&in);
    return ok;
}

void test_base64(const unsigned char *in, size_t n, char *out) { sb_base64(in, n, out); }

bool gltf_tri_write(const char *path, const gltf_tri *t) {
    unsigned char buf[44] = {0};
    const float pos[9] = {0, 0, 0, 1, 0, 0, 0, 0, 1};
    const uint16_t idx[3] = {0, 1, 2};
    memcpy(buf, pos, sizeof pos);
    memcpy(buf + 36, idx, sizeof idx);
    char b64[80], data_uri[128];
    test_base64(buf, sizeof buf, b64);
    snprintf(data_uri, sizeof data_uri, "data:application/octet-stream;base64,%s", b64);
#define OR(f, d) (t->f ? t->f : (d))
    FILE *f = fopen(path, "w");
    if (!f) return false;
    fprintf(f,
            "{\"asset\":{\"version\":\"2.0\"},\"scene\":%s,\"scenes\":[{\"nodes\":%s}],"
            "\"nodes\":[{%s}%s],\"meshes\":[{\"primitives\":[{%s}]}],"
            "\"buffers\":[{\"byteLength\":%s,\"uri\":\"%s\"}],\"bufferViews\":[{%s},{%s}],"
            "\"accessors\":[{%s},{%s}]%s}\n",
            OR(scene, "0"), OR(scene_nodes, "[0]"), OR(node0, "\"mesh\":0"), OR(nodes_more, ""),
            OR(prim, "\"attributes\":{\"POSITION\":0},\"indices\":1"), OR(buffer_len, "44"), OR(uri, data_uri),
            OR(view0, "\"buffer\":0,\"byteOffset\":0,\"byteLength\":36"),
            OR(view1, "\"buffer\":0,\"byteOffset\":36,\"byteLength\":6"),
            OR(acc0, "\"bufferView\":0,\"byteOffset\":0,\"componentType\":5126,\"count\":3,\"type\":\"VEC3\""),
            OR(acc1, "\"bufferView\":1,\"byteOffset\":0,\"componentType\":5123,\"count\":3,\"type\":\"SCALAR\""),
            OR(root_more, ""));
#undef OR
    return fclose(f) == 0;
}

void expect_scene_refused(const char *path, const char *needle) {
    sb_scene s;
    sb_err err = {{0}};
    bool ok = sb_scene_load(&s, path, NULL, &err);
    print_message("%s\n", ok ? "(loaded)" : err.msg);
    if (ok) sb_scene_free(&s);
    assert_false(ok);
    assert_non_null(strstr(err.msg, path));
    assert_non_null(strstr(err.msg, needle));
    assert_null(strchr(err.msg, '\n'));
}

static const char *expect_exit_v(int status, const char *needle, const char *fmt, va_list ap) {
    static char out[16384];
    char cmd[8192];
    vsnprintf(cmd, sizeof cmd, fmt, ap);
    int rc = run_logged(out, sizeof out, "%s", cmd);
    assert_int_equal(rc, status);
    assert_non_null(strstr(out, needle));
    /* one line */
    assert_true(strchr(out, '\n') == NULL || strchr(out, '\n') == out + strlen(out) - 1);
    return out;
}

const char *last_line_of(char *out) {
    char *nl = strrchr(out, '\n');
    if (nl && nl > out && nl[1] == 0) *nl = 0;
    nl = strrchr(out, '\n');
    return nl ? nl + 1 : out;
}

const char *expect_cli_fail(const char *needle, const char *fmt, ...) {
    va_list ap;
    va_start(ap, fmt);
    const char *out = expect_exit_v(SB_EXIT_BAD_INPUT, needle, fmt, ap);   /* bad input of any kind: exit 2 */
    va_end(ap);
    return out;
}

const char *expect_cli_exit(int status, const char *needle, const char *fmt, ...) {
    va_list ap;
    va_start(ap, fmt);
    const char *out = expect_exit_v(status, needle, fmt, ap);
    va_end(ap);
    return out;
}

void copy_bundled(const char *name, const char *dst) {
    char cmd[8192];
    snprintf(cmd, sizeof cmd, "cp %s/%s %s", getenv("SB_DATA_DIR"), name, dst);
    assert_int_equal(system(cmd), 0);
}

int tmp_folder(char *dir, size_t len, const char *prefix) {
    snprintf(dir, len, "/tmp/%sXXXXXX", prefix);
    return mkdtemp(dir) ? 0 : -1;
}

int tmp_remove(const char *dir) {
    char cmd[4200];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
    return system(cmd) == 0 ? 0 : -1;
}

void summary_table(const char *dir, sb_table *t) {
    char path[4200];
    snprintf(path, sizeof path, "%s/summary.csv", dir);
    sb_err err;
    if (!sb_table_load(t, path, &err)) fail_msg("%s", err.msg);
}

void run_evaluated(const char *scene, const char *path, const char *specs, int frames, const char *size,
                   const char *out, sb_table *sum, char *dir, size_t len) {
    static char log[65536];
    assert_int_equal(run_logged(log, sizeof log, "%s run %s %s %s --frames %d --size %s --error-every 1 --warmup 0 "
                                "--quiet --out %s", test_binary(), scene, path, specs, frames, size, out), 0);
    snprintf(dir, len, "%s", last_line_of(log));
    summary_table(dir, sum);
}

void frames_table(const char *dir, const sb_table *sum, int r, sb_table *t) {
    char path[4200];
    snprintf(path, sizeof path, "%s/%s.csv", dir, sb_table_get(sum, r, "run_id"));
    sb_err err;
    if (!sb_table_load(t, path, &err)) fail_msg("%s", err.msg);
}

long table_int(const sb_table *t, int r, const char *col) { return atol(sb_table_get(t, r, col)); }

void assert_generated(const char *doc, const char *begin, const char *end, void (*write)(FILE *f)) {
    char path[4096];
    const char *root = getenv("SB_SOURCE_ROOT");
    snprintf(path, sizeof path, "%s/%s", root ? root : ".", doc);
    sb_err err;
    char *text = sb_read_file(path, NULL, &err);
    assert_non_null(text);
    char *sec = strstr(text, begin);
    if (!sec) print_error("%s has no marker '%s'\n", doc, begin);
    assert_non_null(sec);
    sec = strchr(sec, '\n');
    assert_non_null(sec);
    sec++;
    if (end) {
        char *stop = strstr(sec, end);
        if (!stop) print_error("%s has no end marker '%s'\n", doc, end);
        assert_non_null(stop);
        *stop = 0;
    }
    char *gen = NULL;
    size_t len = 0;
    FILE *f = open_memstream(&gen, &len);
    assert_non_null(f);
    write(f);
    fclose(f);
    if (strcmp(sec, gen)) {
        size_t i = 0;
        while (sec[i] && sec[i] == gen[i]) i++;
        print_error("%s differs from its table at byte %zu of its generated part (run scripts/gen-docs): \"%.60s\" "
                    "against \"%.60s\"\n", doc, i, sec + i, gen + i);
    }
    assert_string_equal(sec, gen);
    free(gen);
    free(text);
}
