/* The command line end to end: output files, CSV contract, bad input. */
#include <signal.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <sys/wait.h>

#include "stats.h"
#include "support.h"
#include "table.h"

static char g_out[1 << 16];

#define sh(...) run_logged(g_out, sizeof g_out, __VA_ARGS__)

SB_TEST_SCRATCH("sbcli")

/* Splits a CSV line without quotes into fields (test data has none in these columns). */
static int fields(char *line, char **out, int max) {
    int n = 0;
    char *p = line;
    while (n < max) {
        out[n++] = p;
        char *c = strchr(p, ',');
        if (!c) break;
        *c = 0;
        p = c + 1;
    }
    return n;
}

static int column(char **hdr, int n, const char *name) {
    for (int i = 0; i < n; i++)
        if (!strcmp(hdr[i], name)) return i;
    fail_msg("no column %s", name);
    return -1;
}

static void test_run_writes_csv(void **st) {
    (void)st;
    assert_int_equal(sh("%s run plane-box plane-box none sm:res=512 --frames 6 --warmup 1 --size 160x90 --out %s/r --quiet",
                        test_binary(), g_tmp), 0);
    char dir[4096];
    size_t dl = strcspn(g_out, "\n");
    assert_true(dl < sizeof dir);
    memcpy(dir, g_out, dl);
    dir[dl] = 0;
    char path[4200];
    snprintf(path, sizeof path, "%s/summary.csv", dir);
    sb_err err;
    char *sum = sb_read_file(path, NULL, &err);
    assert_non_null(sum);
    /* header + 2 rows */
    int lines = 0;
    for (char *p = sum; *p; p++) lines += *p == '\n';
    assert_int_equal(lines, 3);
    char *hdr_line = strtok(sum, "\n");
    char *row1 = strtok(NULL, "\n");
    char *row2 = strtok(NULL, "\n");
    char *hdr[256], *r1[256], *r2[256];
    char hcopy[16384];
    snprintf(hcopy, sizeof hcopy, "%s", hdr_line);
    int nh = fields(hcopy, hdr, 256);
    /* the renderer column is quoted ("llvmpipe (LLVM ..., 256 bits)"): drop quotes' commas for this test */
    for (char *p = row1; *p; p++) if (*p == '"') { char *q = strchr(p + 1, '"'); for (char *k = p; k < q; k++) if (*k == ',') *k = ';'; p = q; }
    for (char *p = row2; *p; p++) if (*p == '"') { char *q = strchr(p + 1, '"'); for (char *k = p; k < q; k++) if (*k == ',') *k = ';'; p = q; }
    assert_int_equal(fields(row1, r1, 256), nh);
    assert_int_equal(fields(row2, r2, 256), nh);
    assert_string_equal(r1[column(hdr, nh, "technique")], "none");
    assert_string_equal(r2[column(hdr, nh, "technique")], "sm");
    assert_string_equal(r1[column(hdr, nh, "status")], "ok");
    assert_string_equal(r2[column(hdr, nh, "status")], "ok");
    assert_string_equal(r1[column(hdr, nh, "timing")], "sync");
    assert_string_equal(r1[column(hdr, nh, "cascade_ms_mean")], "");   /* none has no cascade stage */
    assert_string_not_equal(r2[column(hdr, nh, "cascade_ms_mean")], "");
    assert_string_equal(r2[column(hdr, nh, "shadow_draw_calls_mean")], "2");

    /* per-frame CSV of `none`: 6 rows, empty cascade columns, final and gpu filled */
    snprintf(path, sizeof path, "%s/%s.csv", dir, r1[column(hdr, nh, "run_id")]);
    char *frames = sb_read_file(path, NULL, &err);
    assert_non_null(frames);
    char *line = strtok(frames, "\n");
    char fh[4096];
    snprintf(fh, sizeof fh, "%s", line);
    char *fhdr[64], *fr[64];
    int nf = fields(fh, fhdr, 64);
    int rows = 0;
    while ((line = strtok(NULL, "\n"))) {
        assert_int_equal(fields(line, fr, 64), nf);
        assert_string_equal(fr[column(fhdr, nf, "cascade_ms")], "");
        assert_string_equal(fr[column(fhdr, nf, "cascades_rendered")], "");
        assert_string_equal(fr[column(fhdr, nf, "zpass_ms")], "");
        assert_string_not_equal(fr[column(fhdr, nf, "final_ms")], "");
        assert_string_equal(fr[column(fhdr, nf, "shadow_draw_calls")], "0");
        assert_int_equal(atoi(fr[column(fhdr, nf, "frame")]), rows);
        rows++;
    }
    assert_int_equal(rows, 6);
    /* nothing half-written left behind */
    assert_int_not_equal(sh("ls %s/*.tmp", dir), 0);
    free(frames);
    free(sum);
}

static void test_gltf_camera_path(void **st) {
    (void)st;
    /* a glTF whose camera node is animated along x: keys at t=0,1,2 at x=0,5,10 */
    float data[12] = {0, 1, 2, 0, 1, 10, 5, 1, 10, 10, 1, 10};
    static const char b64[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    const unsigned char *in = (const unsigned char *)data;
    char enc[128] = {0};
    int o = 0;
    for (int i = 0; i < 48; i += 3) {
        uint32_t v = (uint32_t)in[i] << 16 | (uint32_t)in[i + 1] << 8 | in[i + 2];
        enc[o++] = b64[v >> 18 & 63];
        enc[o++] = b64[v >> 12 & 63];
        enc[o++] = b64[v >> 6 & 63];
        enc[o++] = b64[v & 63];
    }
    char f[256];
    snprintf(f, sizeof f, "%s/cam.gltf", g_tmp);
    FILE *fp = fopen(f, "w");
    fprintf(fp,
            "{\"asset\":{\"version\":\"2.0\"},\"scene\":0,\"scenes\":[{\"nodes\":[0]}],"
            "\"nodes\":[{\"camera\":0,\"translation\":[0,1,10]}],"
            "\"cameras\":[{\"type\":\"perspective\",\"perspective\":{\"yfov\":0.8,\"znear\":0.5,\"zfar\":300}}],"
            "\"buffers\":[{\"byteLength\":48,\"uri\":\"data:application/octet-stream;base64,%s\"}],"
            "\"bufferViews\":[{\"buffer\":0,\"byteOffset\":0,\"byteLength\":12},{\"buffer\":0,\"byteOffset\":12,\"byteLength\":36}],"
            "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":3,\"type\":\"SCALAR\",\"min\":[0],\"max\":[2]},"
            "{\"bufferView\":1,\"componentType\":5126,\"count\":3,\"type\":\"VEC3\"}],"
            "\"animations\":[{\"channels\":[{\"sampler\":0,\"target\":{\"node\":0,\"path\":\"translation\"}}],"
            "\"samplers\":[{\"input\":0,\"output\":1}]}]}",
            enc);
    fclose(fp);
    assert_int_equal(sh("%s path '%s#camera=0' --frames 3", test_binary(), f), 0);
    char *line = strtok(g_out, "\n");
    assert_non_null(strstr(line, "frame,progress,t,px"));
    const double xs[3] = {0, 5, 10};
    for (int i = 0; i < 3; i++) {
        line = strtok(NULL, "\n");
        assert_non_null(line);
        char *fl[16] = {0};
        assert_int_equal(fields(line, fl, 16), 13);
        assert_true(fabs(atof(fl[3]) - xs[i]) < 1e-6);
        assert_true(fabs(atof(fl[10]) - 0.8 * 180 / SB_PI) < 1e-3);   /* fov from the glTF camera */
        assert_true(fabs(atof(fl[11]) - 0.5) < 1e-9);                  /* near */
    }
    expect_cli_fail("#camera=3: the file has 1 camera(s)", "%s path '%s#camera=3'", test_binary(), f);
}

static void test_builtin_paths(void **st) {
    (void)st;
    assert_int_equal(sh("%s run plane-box auto sm:res=256 --frames 2 --warmup 0 --size 64x36 --out %s/a --quiet",
                        test_binary(), g_tmp), 0);
    assert_int_equal(sh("%s path orbit plane-box --frames 4", test_binary()), 0);
    expect_cli_fail("a built-in path needs a scene", "%s path orbit", test_binary());
}

/* Reads column `name` of every row of the first per-frame CSV in a run folder. */
static int read_column(const char *dir, const char *name, char vals[][32], int max) {
    char cmd[4400];
    snprintf(cmd, sizeof cmd, "ls %s/*.csv | grep -v -e summary -e columns | head -1", dir);
    char file[4096];
    assert_int_equal(run_capture(cmd, file, sizeof file), 0);
    file[strcspn(file, "\n")] = 0;
    sb_err err;
    char *text = sb_read_file(file, NULL, &err);
    assert_non_null(text);
    char *save = NULL;
    char *line = strtok_r(text, "\n", &save);
    char *hdr[64], hbuf[4096];
    snprintf(hbuf, sizeof hbuf, "%s", line);
    int nh = fields(hbuf, hdr, 64), col = column(hdr, nh, name), n = 0;
    while ((line = strtok_r(NULL, "\n", &save)) && n < max) {
        char *f[64];
        fields(line, f, 64);
        snprintf(vals[n++], 32, "%s", f[col]);
    }
    free(text);
    return n;
}

static void run_dir(char *dir, size_t len, const char *fmt, ...) {
    char cmd[8192];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(cmd, sizeof cmd, fmt, ap);
    va_end(ap);
    assert_int_equal(sh("%s", cmd), 0);
    size_t dl = strcspn(g_out, "\n");
    assert_true(dl < len);
    memcpy(dir, g_out, dl);
    dir[dl] = 0;
}

/* A part of the file nothing draws is left out, not refused: info says it, and so does every run's warnings
 * column (here: a byte after a .glb's declared length). */
static void test_unused_parts_said(void **st) {
    (void)st;
    char f[256];
    snprintf(f, sizeof f, "%s/padded.glb", g_tmp);
    copy_bundled("plane-box.glb", f);
    FILE *fp = fopen(f, "ab");
    assert_non_null(fp);
    fputc(0, fp);
    fclose(fp);
    assert_int_equal(sh("%s info %s", test_binary(), f), 0);
    assert_non_null(strstr(g_out, "unused (left out, not refused): 1 byte(s) after the .glb's declared length"));
    char dir[4096];
    run_dir(dir, sizeof dir, "%s run %s plane-box none --frames 1 --warmup 0 --size 64x36 --error-every 1 --quiet "
            "--out %s/unused", test_binary(), f, g_tmp);
    sb_table t;
    summary_table(dir, &t);
    assert_int_equal(t.nrows, 1);
    print_message("warnings: %s\n", sb_table_get(&t, 0, "warnings"));
    assert_non_null(strstr(sb_table_get(&t, 0, "warnings"), "parts nothing draws, left out: 1 byte(s) after"));
    sb_table_free(&t);
    /* the bundled scenes hold nothing unused: the default benchmark carries no such warning */
    assert_int_equal(sh("%s info desert", test_binary()), 0);
    assert_non_null(strstr(g_out, "unused (left out, not refused): nothing"));
}

static void test_backends_same_draw_calls(void **st) {
    (void)st;
    char a[4096], b[4096];
    run_dir(a, sizeof a, "%s run towers towers sm:res=512 --frames 8 --warmup 0 --size 160x90 --backend egl --out %s/egl --quiet",
            test_binary(), g_tmp);
    run_dir(b, sizeof b, "%s run towers towers sm:res=512 --frames 8 --warmup 0 --size 160x90 --backend osmesa --out %s/osm --quiet",
            test_binary(), g_tmp);
    const char *cols[] = {"draw_calls", "shadow_draw_calls", "triangles", "shadow_triangles", "cascades_rendered"};
    for (size_t c = 0; c < sizeof cols / sizeof cols[0]; c++) {
        char va[16][32], vb[16][32];
        int na = read_column(a, cols[c], va, 16), nb = read_column(b, cols[c], vb, 16);
        assert_int_equal(na, 8);
        assert_int_equal(nb, 8);
        for (int i = 0; i < na; i++) assert_string_equal(va[i], vb[i]);
    }
}

static void test_query_timing(void **st) {
    (void)st;
    for (int ring = 1; ring <= 3; ring += 2) {
        char d[4096];
        run_dir(d, sizeof d, "%s run plane-box plane-box sm:res=256 --frames 7 --warmup 2 --size 64x36 --timing queries --ring %d --out %s/q --quiet",
                test_binary(), ring, g_tmp);
        char v[16][32], fr[16][32];
        assert_int_equal(read_column(d, "cascade_ms", v, 16), 7);
        assert_int_equal(read_column(d, "frame", fr, 16), 7);
        for (int i = 0; i < 7; i++) {
            assert_string_not_equal(v[i], "");
            assert_true(atof(v[i]) >= 0);
            assert_int_equal(atoi(fr[i]), i);   /* rows in frame order although results arrive late */
        }
        char cmd[4400];
        snprintf(cmd, sizeof cmd, "grep -c ',queries,' %s/summary.csv", d);
        assert_int_equal(sh("%s", cmd), 0);
    }
}

static int summary_int(const char *dir, const char *name) {
    char path[4200];
    snprintf(path, sizeof path, "%s/summary.csv", dir);
    sb_err err;
    char *text = sb_read_file(path, NULL, &err);
    assert_non_null(text);
    char *nl = strchr(text, '\n');
    *nl = 0;
    char *row = nl + 1;
    /* the renderer column is quoted: blank out commas inside quotes */
    for (char *p = row; *p; p++)
        if (*p == '"') {
            char *q = strchr(p + 1, '"');
            for (char *k = p; k < q; k++)
                if (*k == ',') *k = ';';
            p = q;
        }
    char *hdr[256], *f[256];
    int nh = fields(text, hdr, 256);
    fields(row, f, 256);
    int v = atoi(f[column(hdr, nh, name)]);
    free(text);
    return v;
}

/* The 95% CI of the first repetition's mean gpu_ms, in percent of it, from the run's per-frame CSV (the rule the
 * run stops by: columns.c's sb_columns_gpu_ci_pct of one repetition). */
static double first_repeat_ci(const char *dir) {
    char cmd[4400], file[4096];
    snprintf(cmd, sizeof cmd, "ls %s/*.csv | grep -v -e summary -e columns | head -1", dir);
    assert_int_equal(run_capture(cmd, file, sizeof file), 0);
    file[strcspn(file, "\n")] = 0;
    sb_table t;
    sb_err err;
    assert_true(sb_table_load(&t, file, &err));
    double v[64];
    int n = 0;
    for (int r = 0; r < t.nrows && n < 64; r++)
        if (atoi(sb_table_get(&t, r, "repeat")) == 0) v[n++] = atof(sb_table_get(&t, r, "gpu_ms"));
    sb_table_free(&t);
    sb_stats st = sb_stats_compute(v, n);
    return st.mean > 0 ? 100.0 * st.ci95 / st.mean : NAN;
}

static void test_repeats_and_target_ci(void **st) {
    (void)st;
    char d[4096];
    run_dir(d, sizeof d, "%s run plane-box plane-box sm:res=256 --frames 5 --warmup 0 --size 64x36 --repeat 3 --error-every 0 --out %s/rep --quiet",
            test_binary(), g_tmp);
    char rep[32][32], fr[32][32];
    assert_int_equal(read_column(d, "repeat", rep, 32), 15);
    assert_int_equal(read_column(d, "frame", fr, 32), 15);
    for (int i = 0; i < 15; i++) {
        assert_int_equal(atoi(rep[i]), i / 5);
        assert_int_equal(atoi(fr[i]), i % 5);
    }
    assert_int_equal(summary_int(d, "repeats"), 3);
    /* an unreachable target stops at --max-repeat; a loose one at the first repetition */
    run_dir(d, sizeof d, "%s run plane-box plane-box sm:res=256 --frames 4 --warmup 0 --size 64x36 --target-ci 0.0001 --max-repeat 2 --error-every 0 --out %s/ci --quiet",
            test_binary(), g_tmp);
    assert_int_equal(summary_int(d, "repeats"), 2);
    /* a loose one stops at the first repetition whose CI is within it. The CI is the machine's (beside a busy loop a
       preempted 0.3 ms frame made it 186%: four repetitions), the stop is the code's: held to the recorded frames */
    run_dir(d, sizeof d, "%s run plane-box plane-box sm:res=256 --frames 10 --warmup 3 --size 64x36 --target-ci 100 --max-repeat 5 --error-every 0 --out %s/ci2 --quiet",
            test_binary(), g_tmp);
    double ci = first_repeat_ci(d);
    int reps = summary_int(d, "repeats");
    print_message("--target-ci 100: the first repetition's CI %.1f%%, %d repetition(s)\n", ci, reps);
    assert_true(isfinite(ci));
    assert_int_equal(reps == 1, ci <= 100);
}

/* Runs that cannot mean anything are skipped with a reason that says why. */
static void test_skip_reasons(void **st) {
    (void)st;
    char flat[300], spot[300], d[4096];
    snprintf(flat, sizeof flat, "%s/flat.gltf", g_tmp);
    snprintf(spot, sizeof spot, "%s/spot.gltf", g_tmp);
    assert_true(gltf_tri_write(flat, &(gltf_tri){.node0 = "\"mesh\":0,\"scale\":[0,0,0]"}));
    assert_true(gltf_tri_write(spot, &(gltf_tri){
        .nodes_more = ",{\"translation\":[0,2,0],\"extensions\":{\"KHR_lights_punctual\":{\"light\":0}}}",
        .scene_nodes = "[0,1]",
        .root_more = ",\"extensions\":{\"KHR_lights_punctual\":{\"lights\":[{\"type\":\"spot\",\"spot\":{}}]}}"}));
    const char *scenes[] = {flat, spot};
    const char *expect[][2] = {{"the scene is degenerate: all 1 triangles have zero area", "the scene is degenerate"},
                               {"the scene is lit only by 1 spot light(s), no sun", NULL}};
    for (int k = 0; k < 2; k++) {
        run_dir(d, sizeof d, "%s run %s auto sm none --frames 2 --warmup 0 --size 64x36 --out %s/skip --quiet",
                test_binary(), scenes[k], g_tmp);
        sb_table t;
        summary_table(d, &t);
        assert_int_equal(t.nrows, 2);
        for (int r = 0; r < 2; r++) {
            const char *want = expect[k][r];
            print_message("%s %s: %s %s\n", scenes[k], sb_table_get(&t, r, "technique"), sb_table_get(&t, r, "status"),
                          sb_table_get(&t, r, "reason"));
            assert_string_equal(sb_table_get(&t, r, "status"), want ? "skipped" : "ok");
            if (want) assert_non_null(strstr(sb_table_get(&t, r, "reason"), want));
        }
        sb_table_free(&t);
    }
    /* a run that draws no caster in any frame (the camera sees only sky) says so */
    char sky[300];
    snprintf(sky, sizeof sky, "%s/sky.path", g_tmp);
    FILE *f = fopen(sky, "w");
    fputs("fov 60\nlook 0  0 30 0  0.001 60 0\nlook 1  3 30 0  3.001 60 1\n", f);
    fclose(f);
    run_dir(d, sizeof d, "%s run plane-box %s sm none --frames 2 --warmup 0 --size 64x36 --out %s/sky --quiet",
            test_binary(), sky, g_tmp);
    sb_table t;
    summary_table(d, &t);
    print_message("sky: sm warnings '%s', none warnings '%s'\n", sb_table_get(&t, 0, "warnings"), sb_table_get(&t, 1, "warnings"));
    assert_string_equal(sb_table_get(&t, 0, "status"), "ok");
    assert_non_null(strstr(sb_table_get(&t, 0, "warnings"), "no shadow-casting triangle was drawn in any frame"));
    assert_string_equal(sb_table_get(&t, 1, "warnings"), "");
    sb_table_free(&t);
}

/* The usage text names every command; the reference takes more than 16 threads. */
static void test_usage_and_threads(void **st) {
    (void)st;
    assert_int_equal(sh("%s --help", test_binary()), 0);
    const char *cmds[] = {"run SCENE", "batch FILE", "compare BASE NEW", "--pair", "merge DIR", "stress", "techniques",
                          "columns", "info", "path PATH"};
    for (size_t i = 0; i < sizeof cmds / sizeof cmds[0]; i++) assert_non_null(strstr(g_out, cmds[i]));
    char d[4096];
    run_dir(d, sizeof d, "%s run plane-box plane-box raycast:threads=64 sm --threads 64 --frames 2 --warmup 0 "
            "--size 64x36 --error-every 1 --out %s/thr --quiet", test_binary(), g_tmp);
    char v[4][32];
    assert_int_equal(read_column(d, "err_rate", v, 4), 2);
    assert_string_not_equal(v[0], "");
}

/* Clocks: lock without NVML is one clear line and exit 1; auto runs free, and
 * on a software rasterizer (no clock at all) says nothing unless --verbose. */
static void test_clocks_modes(void **st) {
    (void)st;
    const char *out = expect_cli_exit(1, "--clocks lock: cannot lock the GPU clock: ",
                                      "%s run plane-box plane-box sm --clocks lock --frames 1 --size 64x36 --out %s/lock",
                                      test_binary(), g_tmp);
    assert_non_null(strstr(out, "NVML"));
    char d[4096];
    run_dir(d, sizeof d, "%s run plane-box plane-box sm --clocks auto --frames 1 --size 64x36 --out %s/auto --quiet",
            test_binary(), g_tmp);
    assert_int_equal(sh("%s run plane-box plane-box sm --clocks auto --frames 1 --size 64x36 --out %s/auto", test_binary(),
                        g_tmp), 0);
    assert_null(strstr(g_out, "GPU clock"));
    assert_null(strstr(g_out, "note:"));
    assert_int_equal(sh("%s run plane-box plane-box sm --clocks auto --frames 1 --size 64x36 --out %s/auto --verbose",
                        test_binary(), g_tmp), 0);
    assert_non_null(strstr(g_out, "note: no GPU clock to lock ("));
    sb_table t;
    summary_table(d, &t);
    assert_string_equal(sb_table_get(&t, 0, "clocks"), "free");
    assert_string_equal(sb_table_get(&t, 0, "gpu_clock_mhz_median"), ""); /* llvmpipe has none */
    sb_table_free(&t);
}

/* The stability verdict of a run: its calibration probe measured before and after its timed frames (live, on
 * llvmpipe: whether this machine was calm is not asserted), and the verdict on replayed timings
 * (SB_REPLAY_TIMINGS): steady frames and probe stable; frames twice as long in the second repetition, drifted;
 * a probe 50% slower after the frames, moved. The verdict's arithmetic itself: test_stats. */
static void test_stability_verdict(void **st) {
    (void)st;
    const char *cmd = "%s run towers towers sm:res=512 --frames 4 --repeat 2 --size 160x90 --error-every 0 --quiet "
                      "--out %s/%s";
    char d[4096], replay[300];
    sb_table t;
    run_dir(d, sizeof d, cmd, test_binary(), g_tmp, "live");
    summary_table(d, &t);
    print_message("live: stable %s %s, probe %s ms before, %s ms after\n", sb_table_get(&t, 0, "stable"),
                  sb_table_get(&t, 0, "unstable_reason"), sb_table_get(&t, 0, "calib_ms_before"),
                  sb_table_get(&t, 0, "calib_ms_after"));
    assert_true(atof(sb_table_get(&t, 0, "calib_ms_before")) > 0 && atof(sb_table_get(&t, 0, "calib_ms_after")) > 0);
    assert_true(atoi(sb_table_get(&t, 0, "warmup")) > 0);
    assert_string_equal(sb_table_get(&t, 0, "warnings"), "");   /* no seam, no replay line */
    sb_table_free(&t);
    static const struct { const char *name, *line, *stable, *reason; } cases[] = {
        {"steady", "sm 1 6 6 10 10", "yes", ""},
        {"drifted", "* * 6 6 10 20", "no", "frame times drifted +100% from the first repetition of the path to the last"},
        {"moved", "sm * 6 9 10 10", "no", "the calibration probe changed +50% during the run (6 ms before, 9 ms after)"},
    };
    snprintf(replay, sizeof replay, "%s/verdict.replay", g_tmp);
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        FILE *f = fopen(replay, "w");
        assert_non_null(f);
        fprintf(f, "pssm * 6 6 10 40\n%s\n", cases[i].line);   /* another technique's line: not this run's */
        fclose(f);
        setenv("SB_REPLAY_TIMINGS", replay, 1);
        run_dir(d, sizeof d, cmd, test_binary(), g_tmp, cases[i].name);
        unsetenv("SB_REPLAY_TIMINGS");
        summary_table(d, &t);
        print_message("%s: stable %s %s\n", cases[i].name, sb_table_get(&t, 0, "stable"),
                      sb_table_get(&t, 0, "unstable_reason"));
        assert_string_equal(sb_table_get(&t, 0, "stable"), cases[i].stable);
        assert_true(!strncmp(sb_table_get(&t, 0, "unstable_reason"), cases[i].reason, strlen(cases[i].reason)));
        assert_true(*cases[i].reason || !*sb_table_get(&t, 0, "unstable_reason"));
        assert_non_null(strstr(sb_table_get(&t, 0, "warnings"), "SB_REPLAY_TIMINGS"));
        sb_table_free(&t);
    }
}

/* The reference is cast once per frame: in a two-spec run the second run
 * reuses the first's answers (ref_rays 0), and its error figures are those
 * of the same spec run alone, which casts its own. */
static void test_reference_shared(void **st) {
    (void)st;
    const char *cmd = "%s run towers towers %s --frames 4 --size 320x180 --error-every 1 --warmup 0 --quiet --out %s/%s";
    char two[4096], one[4096];
    run_dir(two, sizeof two, cmd, test_binary(), "sm:res=1024 pssm:res=1024", g_tmp, "ref2");
    run_dir(one, sizeof one, cmd, test_binary(), "pssm:res=1024", g_tmp, "ref1");
    sb_table a, b;
    summary_table(two, &a);
    summary_table(one, &b);
    assert_int_equal(a.nrows, 2);
    print_message("two specs: ref_rays %s then %s (reused %s, %s ms); alone: %s (%s ms)\n", sb_table_get(&a, 0, "ref_rays"),
                  sb_table_get(&a, 1, "ref_rays"), sb_table_get(&a, 1, "ref_reused"), sb_table_get(&a, 1, "ref_ms"),
                  sb_table_get(&b, 0, "ref_rays"), sb_table_get(&b, 0, "ref_ms"));
    assert_true(atoll(sb_table_get(&a, 0, "ref_rays")) > 0);
    assert_string_equal(sb_table_get(&a, 0, "ref_reused"), "0");
    assert_string_equal(sb_table_get(&a, 1, "ref_rays"), "0");
    assert_string_equal(sb_table_get(&a, 1, "ref_reused"), "4");
    assert_string_equal(sb_table_get(&b, 0, "ref_rays"), sb_table_get(&a, 0, "ref_rays"));
    const char *same[] = {"err_rate_mean", "err_rate_p95", "err_false_shadow_mean", "err_false_lit_mean", "vis_mae_mean",
                          "geom_mismatch", "err_floor"};
    for (size_t k = 0; k < sizeof same / sizeof same[0]; k++) {
        print_message("%s: %s shared, %s alone\n", same[k], sb_table_get(&a, 1, same[k]), sb_table_get(&b, 0, same[k]));
        assert_string_equal(sb_table_get(&a, 1, same[k]), sb_table_get(&b, 0, same[k]));
    }
    /* --overlap on (auto is off on llvmpipe): the first run's answers come from the background, counted as
       its own rays; the rays and every error figure are those without it */
    char bg[4096];
    sb_table g;
    run_dir(bg, sizeof bg, cmd, test_binary(), "sm:res=1024 pssm:res=1024 --overlap on", g_tmp, "ref-bg");
    summary_table(bg, &g);
    assert_int_equal(g.nrows, 2);
    print_message("overlap on: ref_rays %s (background %s, reused %s) then %s (reused %s)\n", sb_table_get(&g, 0, "ref_rays"),
                  sb_table_get(&g, 0, "ref_background"), sb_table_get(&g, 0, "ref_reused"), sb_table_get(&g, 1, "ref_rays"),
                  sb_table_get(&g, 1, "ref_reused"));
    assert_string_equal(sb_table_get(&a, 0, "ref_background"), "0");
    assert_string_equal(sb_table_get(&g, 0, "ref_background"), "4");
    assert_string_equal(sb_table_get(&g, 0, "ref_reused"), "0");
    assert_string_equal(sb_table_get(&g, 0, "ref_rays"), sb_table_get(&a, 0, "ref_rays"));
    assert_string_equal(sb_table_get(&g, 1, "ref_rays"), "0");
    assert_string_equal(sb_table_get(&g, 1, "ref_reused"), "4");
    for (int r = 0; r < 2; r++)
        for (size_t k = 0; k < sizeof same / sizeof same[0]; k++)
            assert_string_equal(sb_table_get(&g, r, same[k]), sb_table_get(&a, r, same[k]));
    sb_table_free(&g);
    /* a rerun into the same OUT reads the answers kept in OUT/.reference: no ray cast, the same figures */
    char again[4096];
    sb_table c;
    run_dir(again, sizeof again, cmd, test_binary(), "pssm:res=1024", g_tmp, "ref1");
    summary_table(again, &c);
    print_message("rerun: ref_rays %s, reused %s\n", sb_table_get(&c, 0, "ref_rays"), sb_table_get(&c, 0, "ref_reused"));
    assert_string_equal(sb_table_get(&c, 0, "ref_rays"), "0");
    assert_string_equal(sb_table_get(&c, 0, "ref_reused"), "4");
    for (size_t k = 0; k < sizeof same / sizeof same[0]; k++)
        assert_string_equal(sb_table_get(&c, 0, same[k]), sb_table_get(&b, 0, same[k]));
    sb_table_free(&c);
    /* a damaged file is not read: the rays are cast again */
    assert_int_equal(sh("for f in %s/ref1/.reference/*.ref; do printf 'xx' | dd of=$f bs=1 seek=100 conv=notrunc 2>/dev/null; done",
                        g_tmp), 0);
    run_dir(again, sizeof again, cmd, test_binary(), "pssm:res=1024", g_tmp, "ref1");
    summary_table(again, &c);
    assert_string_equal(sb_table_get(&c, 0, "ref_rays"), sb_table_get(&b, 0, "ref_rays"));
    assert_string_equal(sb_table_get(&c, 0, "err_rate_mean"), sb_table_get(&b, 0, "err_rate_mean"));
    sb_table_free(&c);
    sb_table_free(&a);
    sb_table_free(&b);
}

/* The gpu_ms and start_s of every frame of a run's per-frame file (n frames). */
static void frame_gpu_ms(const char *dir, const sb_table *sum, double *ms, double *start, int n) {
    char path[4200];
    snprintf(path, sizeof path, "%s/%s.csv", dir, sb_table_get(sum, 0, "run_id"));
    sb_table t;
    sb_err err;
    if (!sb_table_load(&t, path, &err)) fail_msg("%s", err.msg);
    assert_int_equal(t.nrows, n);
    for (int i = 0; i < n; i++) ms[i] = atof(sb_table_get(&t, i, "gpu_ms")), start[i] = atof(sb_table_get(&t, i, "start_s"));
    sb_table_free(&t);
}

static int cmp_double(const void *a, const void *b) {
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* --overlap on: the reference of the frames a scene's runs evaluate is cast
 * in the background, at idle CPU priority, while the timed frames render
 * (its answers: test_reference_shared). The timed frames are not slowed:
 * means within their CIs, and frame by frame over the frames the background was
 * casting through (the same background at normal priority measured 1.34 to
 * 1.56x on those frames here, its means outside the CIs). */
static void test_reference_background(void **st) {
    (void)st;
    /* timing: enough rays (desert at 960x540, every frame, one thread) that the background is still
       casting while the timed frames render. off, on, off: the run with it against the mean of its
       neighbours without; one try (at 640x360 the background ends before a third of the timed frames: never
       judged). A second one, where the background had cast too little, judged nothing more on a busy machine: the
       background runs at idle priority, and a neighbour's load starves it again (seen: 41 s for two skips) */
    const char *tcmd = "(%s run desert desert sm:res=1024 --frames 10 --size 960x540 --error-every 1 --warmup 2 "
                       "--threads 1 --progress --overlap %s --out %s/%s 2>%s/%s.log)";
    enum { N = 10 };
    bool ok = false;
    int overlapped_too_little = 0, judged = 0;
    for (int attempt = 1; attempt <= 1 && !ok; attempt++) {
        double ms[3][N], start[3][N], mean[3], ci[3], during = 0, timed = 0;
        for (int k = 0; k < 3; k++) {
            const bool on = k == 1;
            char name[32], dir[4096];
            snprintf(name, sizeof name, "t%d-%d", attempt, k);
            run_dir(dir, sizeof dir, tcmd, test_binary(), on ? "on" : "off", g_tmp, name, g_tmp, name);
            sb_table t;
            summary_table(dir, &t);
            frame_gpu_ms(dir, &t, ms[k], start[k], N);
            mean[k] = atof(sb_table_get(&t, 0, "gpu_ms_mean"));
            ci[k] = atof(sb_table_get(&t, 0, "gpu_ms_ci95"));
            sb_table_free(&t);
            print_message("try %d, overlap %s: gpu_ms mean %.2f +- %.2f\n", attempt, on ? "on" : "off", mean[k], ci[k]);
            if (!on) continue;
            for (int i = 0; i < N; i++) timed += ms[k][i];
            char log[4200];
            snprintf(log, sizeof log, "%s/%s.log", g_tmp, name);
            size_t size = 0;
            sb_err err;
            char *text = sb_read_file(log, &size, &err);
            assert_non_null(text);
            const char *at = strstr(text, " ms of it while timed frames rendered");
            assert_non_null(at);
            while (at > text && at[-1] != ' ') at--;
            during = atof(at);
            free(text);
        }
        /* the background cast during a good part of the timed frames (else this measures nothing); it
           starts before them with frames queued, so those are the first ones */
        int n = 0;
        while (n < N && (start[1][n] - start[1][0]) * 1e3 < during) n++;
        print_message("  the background cast during %.0f ms of the %.0f ms of timed frames (%d frames)\n", during, timed, n);
        if (during < 0.3 * timed || n < 4) {
            print_message("  too little overlap to judge: again\n");
            overlapped_too_little++;
            continue;
        }
        double ratio[N], base = 0.5 * (mean[0] + mean[2]), base_ci = 0.5 * (ci[0] + ci[2]);
        for (int i = 0; i < n; i++) ratio[i] = ms[1][i] / (0.5 * (ms[0][i] + ms[2][i]));
        qsort(ratio, (size_t)n, sizeof ratio[0], cmp_double);
        double median = n % 2 ? ratio[n / 2] : 0.5 * (ratio[n / 2 - 1] + ratio[n / 2]);
        /* the runs without agree with each other well enough that a slowdown of a third would show: this
           machine's speed drifts by up to a quarter over the three runs (seen: 98.9, 84.5 on, 119.4 ms), and
           the mean of the two neighbours is the baseline that drift leaves in the middle */
        bool quiet = fabs(mean[2] - mean[0]) <= 0.3 * base;
        print_message("  on against off: means %.2f and %.2f (CIs %.2f, %.2f), those frames' median ratio %.3f; off runs %s\n",
                      mean[1], base, ci[1], base_ci, median, quiet ? "agree" : "disagree (a noisy machine)");
        /* slowed is what fails: a run with the background faster than its neighbours is noise, not a fault.
           The one end-to-end timing check of --overlap: its bound (the overlapped frames 1.5x their neighbours'
           median) is twice the drift a shared machine shows between the runs without (up to a quarter); a
           machine too busy to judge on (the runs without disagree, or the background done before the frames)
           skips it, saying so: a neighbour's load is no fault of the tool's */
        if (!quiet) break;
        judged++;
        ok = median < 1.5;
        if (!ok) break;
    }
    if (!judged) {
        print_message("no try could judge (%d: too little overlap; the others: the runs without disagreed): skipped\n",
                      overlapped_too_little);
        skip();
    }
    assert_true(ok);
}

/* bias=auto: the run calibrates, says what it chose in auto_params, and renders
 * with it: its error figures are those of a run with the chosen values given. */
static void test_auto_offsets(void **st) {
    (void)st;
    const char *cmd = "%s run towers towers %s --frames 4 --size 320x180 --error-every 1 --warmup 0 --quiet --out %s/%s";
    char autod[4096], pinned[4096], spec[512];
    run_dir(autod, sizeof autod, cmd, test_binary(), "sm:res=1024:bias=auto:slope=auto:normal=auto", g_tmp, "auto");
    sb_table a, b;
    summary_table(autod, &a);
    const char *chosen = sb_table_get(&a, 0, "auto_params");
    print_message("auto: %s -> %s, err_rate %s\n", sb_table_get(&a, 0, "params"), chosen,
                  sb_table_get(&a, 0, "err_rate_mean"));
    assert_non_null(strstr(sb_table_get(&a, 0, "params"), "bias=auto:slope=auto:normal=auto"));
    assert_true(!strncmp(chosen, "bias=", 5) && strstr(chosen, ":slope=") && strstr(chosen, ":normal="));
    snprintf(spec, sizeof spec, "sm:res=1024:%s", chosen);
    run_dir(pinned, sizeof pinned, cmd, test_binary(), spec, g_tmp, "pinned");
    summary_table(pinned, &b);
    assert_string_equal(sb_table_get(&b, 0, "auto_params"), "");
    const char *same[] = {"err_rate_mean", "err_false_shadow_mean", "err_false_lit_mean", "shadow_draw_calls_mean"};
    for (size_t k = 0; k < sizeof same / sizeof same[0]; k++)
        assert_string_equal(sb_table_get(&a, 0, same[k]), sb_table_get(&b, 0, same[k]));
    sb_table_free(&a);
    sb_table_free(&b);
    /* only a parameter that says so takes auto; stress does not calibrate */
    expect_cli_fail("sm:res=auto: expected a number in [64, 16384]", "%s run towers towers sm:res=auto --quiet",
                    test_binary());
    expect_cli_fail("expected a number in [0, 100] or auto", "%s run towers towers sm:bias=x --quiet", test_binary());
    expect_cli_fail("sm:bias=auto: stress renders fixed offsets; auto is calibrated by run, batch and tune",
                    "%s stress sun-parallel sm:bias=auto --frames 2 --size 64x36 --quiet", test_binary());
}

/* The passes of a run folder's runs in the order they started: each pass as
 * run_index * 100 + repetition, from the per-frame repeat and start_s columns. */
static int pass_order(const char *dir, int *order, int max) {
    sb_table sum;
    summary_table(dir, &sum);
    double start[64];
    int n = 0;
    for (int r = 0; r < sum.nrows; r++) {
        char path[4200];
        snprintf(path, sizeof path, "%s/%s.csv", dir, sb_table_get(&sum, r, "run_id"));
        sb_table t;
        sb_err err;
        assert_true(sb_table_load(&t, path, &err));
        for (int i = 0; i < t.nrows && n < max; i++) {
            if (atoi(sb_table_get(&t, i, "frame")) != 0) continue; /* a pass starts with frame 0 */
            order[n] = atoi(sb_table_get(&sum, r, "run_index")) * 100 + atoi(sb_table_get(&t, i, "repeat"));
            start[n++] = atof(sb_table_get(&t, i, "start_s"));
        }
        sb_table_free(&t);
    }
    sb_table_free(&sum);
    for (int i = 1; i < n; i++) /* insertion sort by start time */
        for (int j = i; j > 0 && start[j] < start[j - 1]; j--) {
            double ts = start[j];
            start[j] = start[j - 1], start[j - 1] = ts;
            int to = order[j];
            order[j] = order[j - 1], order[j - 1] = to;
        }
    return n;
}

/* --order: matrix renders each run's repetitions together, interleave in
 * rounds A1 B1 A2 B2 ..., shuffle in rounds of a seeded order. */
static void test_run_order(void **st) {
    (void)st;
    const char *cmd = "%s run plane-box plane-box sm:res=256 pssm:res=256 --frames 3 --warmup 0 --size 64x36 "
                      "--repeat 3 --error-every 0 --quiet --out %s/order %s";
    char d[4096];
    int got[16], n;
    const int matrix[] = {0, 1, 2, 100, 101, 102}, interleave[] = {0, 100, 1, 101, 2, 102};
    run_dir(d, sizeof d, cmd, test_binary(), g_tmp, "");
    assert_int_equal(n = pass_order(d, got, 16), 6);
    for (int i = 0; i < n; i++) assert_int_equal(got[i], matrix[i]);
    run_dir(d, sizeof d, cmd, test_binary(), g_tmp, "--order interleave");
    assert_int_equal(n = pass_order(d, got, 16), 6);
    for (int i = 0; i < n; i++) assert_int_equal(got[i], interleave[i]);
    sb_table t;
    summary_table(d, &t);
    assert_string_equal(sb_table_get(&t, 0, "order"), "interleave");
    assert_string_equal(sb_table_get(&t, 0, "seed"), "");
    sb_table_free(&t);
    /* shuffle: every run once a round; the seed in every row */
    run_dir(d, sizeof d, cmd, test_binary(), g_tmp, "--order shuffle --seed 7");
    assert_int_equal(n = pass_order(d, got, 16), 6);
    for (int i = 0; i < n; i++) assert_int_equal(got[i] % 100, i / 2);
    summary_table(d, &t);
    assert_string_equal(sb_table_get(&t, 1, "order"), "shuffle");
    assert_string_equal(sb_table_get(&t, 1, "seed"), "7");
    sb_table_free(&t);
    expect_cli_fail("--order sideways: expected matrix, interleave or shuffle", "%s run plane-box plane-box sm --order sideways",
                    test_binary());
}

/* The last line of the output (a run's results folder when stderr came first). */
static void last_line(char *dir, size_t len) {
    size_t n = strlen(g_out);
    while (n && g_out[n - 1] == '\n') n--;
    size_t start = n;
    while (start && g_out[start - 1] != '\n') start--;
    assert_true(n - start < len);
    memcpy(dir, g_out + start, n - start);
    dir[n - start] = 0;
}

/* A run whose shadow maps would not fit in the GPU memory is refused before
 * it renders, in one line naming the parameter and the amount (skipped, with
 * that reason in the summary); a bad --gpu-memory is bad input. On a software
 * rasterizer the limit is the system memory available: the largest maps the
 * parameters allow (72 GiB) are refused without --gpu-memory too. */
static void test_gpu_memory_refused(void **st) {
    (void)st;
    char d[4096];
    assert_int_equal(sh("%s run plane-box plane-box pssm:res=16384 pssm:res=256 --frames 1 --warmup 0 --size 64x36 "
                        "--error-every 0 --gpu-memory 2G --out %s/mem", test_binary(), g_tmp), 0);
    last_line(d, sizeof d);
    const char *line = "pssm:res=16384:cascades=4: needs 4.0 GiB of shadow maps, more than the 2.0 GiB --gpu-memory";
    assert_non_null(strstr(g_out, line));   /* on stderr */
    sb_table t;
    summary_table(d, &t);
    print_message("%s: %s\n", sb_table_get(&t, 0, "status"), sb_table_get(&t, 0, "reason"));
    assert_string_equal(sb_table_get(&t, 0, "status"), "skipped");
    assert_non_null(strstr(sb_table_get(&t, 0, "reason"), line));
    assert_string_equal(sb_table_get(&t, 1, "status"), "ok");
    sb_table_free(&t);
    /* the point-light techniques too: six cube faces and two paraboloid maps of 32-bit depth */
    assert_int_equal(sh("%s run plane-box-lamp plane-box-lamp cube:res=8192 dpsm:res=8192 cube:res=256 --frames 1 "
                        "--warmup 0 --size 64x36 --error-every 0 --gpu-memory 1G --out %s/mem", test_binary(), g_tmp), 0);
    last_line(d, sizeof d);
    assert_non_null(strstr(g_out, "cube:res=8192: needs 1.5 GiB of shadow maps, more than the 1024 MiB --gpu-memory"));
    summary_table(d, &t);
    assert_int_equal(t.nrows, 3);
    const char *want[][2] = {{"skipped", "cube:res=8192: needs 1.5 GiB"}, {"ok", ""}, {"ok", ""}};
    assert_string_equal(sb_table_get(&t, 1, "technique"), "dpsm");   /* 512 MiB: fits in 1 GiB */
    for (int r = 0; r < 3; r++) {
        print_message("%s %s: %s %s\n", sb_table_get(&t, r, "technique"), sb_table_get(&t, r, "params"),
                      sb_table_get(&t, r, "status"), sb_table_get(&t, r, "reason"));
        assert_string_equal(sb_table_get(&t, r, "status"), want[r][0]);
        assert_non_null(strstr(sb_table_get(&t, r, "reason"), want[r][1]));
    }
    sb_table_free(&t);
    assert_int_equal(sh("%s run plane-box-lamp plane-box-lamp dpsm:res=8192 --frames 1 --warmup 0 --size 64x36 "
                        "--error-every 0 --gpu-memory 256M --out %s/mem", test_binary(), g_tmp), 0);
    assert_non_null(strstr(g_out, "dpsm:res=8192: needs 512 MiB of shadow maps, more than the "));
    assert_int_equal(sh("%s run plane-box plane-box sm --gpu-memory 12 --out %s/mem", test_binary(), g_tmp), 2);
    assert_non_null(strstr(g_out, "--gpu-memory 12: expected a size with M or G"));

    FILE *f = fopen("/proc/meminfo", "r");
    char l[256];
    double avail_kib = 0;
    while (f && fgets(l, sizeof l, f))
        if (sscanf(l, "MemAvailable: %lf kB", &avail_kib) == 1) break;
    if (f) fclose(f);
    if (avail_kib <= 0 || avail_kib > 70.0 * 1024 * 1024) {
        print_message("MemAvailable %.0f kB: the context's own limit is not checked here\n", avail_kib);
        return;
    }
    run_dir(d, sizeof d, "%s run plane-box plane-box pssm:res=16384:cascades=8:format=msm --frames 1 --warmup 0 "
            "--size 64x36 --error-every 0 --quiet --out %s/mem", test_binary(), g_tmp);
    summary_table(d, &t);
    print_message("%s: %s\n", sb_table_get(&t, 0, "status"), sb_table_get(&t, 0, "reason"));
    assert_string_equal(sb_table_get(&t, 0, "status"), "skipped");
    assert_non_null(strstr(sb_table_get(&t, 0, "reason"),
                           "pssm:res=16384:cascades=8: needs 72.0 GiB of shadow maps, more than the "));
    sb_table_free(&t);
}

/* Results into a full filesystem (a 28 KiB tmpfs, mounted in a user
 * namespace): a batch, then a run, exit 4, naming a file and the OS error;
 * nothing half-written is left under a final name; after the filesystem
 * grows, batch --resume and run --resume complete the set, and its rows are
 * those of a batch that never failed (timings aside). */
static void test_full_disk(void **st) {
    (void)st;
    if (sh("unshare -rm sh -c 'mount -t tmpfs -o size=40k tmpfs %s && echo mounted'", g_tmp) != 0 ||
        !strstr(g_out, "mounted")) {
        print_message("no user namespace with tmpfs here (%s): skipped\n", g_out);
        skip();
    }
    char bench[300];
    snprintf(bench, sizeof bench, "%s/tiny.bench", g_tmp);
    FILE *f = fopen(bench, "w");
    fputs("scene towers towers\npath towers towers\ndefaults --frames 8 --warmup 0 --error-every 4 --size 160x90\n"
          "sm:res=512\npssm:res=512\nsdsm:res=512\n", f);   /* small maps: the disk fills with the same rows */
    fclose(f);
    /* the clean set, on the real disk */
    char clean[4096];
    run_dir(clean, sizeof clean, "%s batch %s --out %s/clean --quiet", test_binary(), bench, g_tmp);
    /* into the tiny one: fails with 4; then more room and --resume; the listing and rows come back out */
    int rc = sh("unshare -rm sh -c 'D=%s/disk; mkdir -p $D && mount -t tmpfs -o size=28k tmpfs $D && "
                "%s batch %s --out $D --quiet > %s/dir.txt; echo first=$?; "
                "mount -o remount,size=64m $D && %s batch %s --resume $(tail -n 1 %s/dir.txt) --quiet; echo second=$?; "
                "find $D -name \"*.tmp\" | sed s/^/LEFT-BEHIND:/; cp $(tail -n 1 %s/dir.txt)/summary.csv %s/resumed.csv'",
                g_tmp, test_binary(), bench, g_tmp, test_binary(), bench, g_tmp, g_tmp, g_tmp);
    print_message("%s\n", g_out);
    assert_int_equal(rc, 0);
    assert_non_null(strstr(g_out, "first=4"));
    assert_non_null(strstr(g_out, "No space left on device"));
    assert_non_null(strstr(g_out, "/disk/"));                    /* the file is named */
    assert_non_null(strstr(g_out, "second=0"));
    assert_null(strstr(g_out, "LEFT-BEHIND:"));                   /* no temporary left behind */
    sb_table a, b;
    summary_table(clean, &a);
    char resumed[300];
    snprintf(resumed, sizeof resumed, "%s/resumed.csv", g_tmp);
    sb_err err;
    assert_true(sb_table_load(&b, resumed, &err));
    assert_int_equal(a.nrows, 3);
    assert_int_equal(b.nrows, a.nrows);
    const char *same[] = {"run_id", "technique", "params", "status", "frames", "draw_calls_mean", "err_rate_mean",
                          "texel_px_p95_mean"};
    for (int r = 0; r < a.nrows; r++)
        for (size_t k = 0; k < sizeof same / sizeof same[0]; k++) {
            int rb = -1;
            for (int j = 0; j < b.nrows; j++)
                if (!strcmp(sb_table_get(&a, r, "run_id"), sb_table_get(&b, j, "run_id"))) rb = j;
            assert_true(rb >= 0);
            assert_string_equal(sb_table_get(&a, r, same[k]), sb_table_get(&b, rb, same[k]));
        }
    sb_table_free(&a);
    sb_table_free(&b);

    /* a run the same way: exit 4 into the tiny one, then run --resume with room completes it */
    rc = sh("unshare -rm sh -c 'D=%s/rdisk; mkdir -p $D && mount -t tmpfs -o size=28k tmpfs $D && "
            "%s run towers towers sm:res=512 pssm:res=512 sdsm:res=512 --frames 8 --warmup 0 --error-every 4 "
            "--size 160x90 --out $D --quiet > %s/rdir.txt; echo first=$?; mount -o remount,size=64m $D && "
            "%s run towers towers sm:res=512 pssm:res=512 sdsm:res=512 --frames 8 "
            "--warmup 0 --error-every 4 --size 160x90 --quiet --resume $(tail -n 1 %s/rdir.txt); echo second=$?; "
            "find $D -name \"*.tmp\" | sed s/^/LEFT-BEHIND:/; cp $(tail -n 1 %s/rdir.txt)/summary.csv %s/rresumed.csv'",
            g_tmp, test_binary(), g_tmp, test_binary(), g_tmp, g_tmp, g_tmp);
    print_message("%s\n", g_out);
    assert_int_equal(rc, 0);
    assert_non_null(strstr(g_out, "first=4"));
    assert_non_null(strstr(g_out, "No space left on device"));
    assert_non_null(strstr(g_out, "second=0"));
    assert_null(strstr(g_out, "LEFT-BEHIND:"));
    snprintf(resumed, sizeof resumed, "%s/rresumed.csv", g_tmp);
    summary_table(clean, &a);
    assert_true(sb_table_load(&b, resumed, &err));
    assert_int_equal(b.nrows, a.nrows);
    for (int r = 0; r < a.nrows; r++)
        for (int j = 0; j < b.nrows; j++)
            if (!strcmp(sb_table_get(&a, r, "technique"), sb_table_get(&b, j, "technique")))
                for (size_t k = 1; k < sizeof same / sizeof same[0]; k++)
                    assert_string_equal(sb_table_get(&a, r, same[k]), sb_table_get(&b, j, same[k]));
    sb_table_free(&a);
    sb_table_free(&b);
}

/* Two groups, two tests of the suite (tests/meson.build): `cli-timed` (argument "timed"), the checks that rest
 * on the timings of live runs, runs alone; `cli`, the rest, beside other tests. */
int main(int argc, char **argv) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_run_writes_csv),   cmocka_unit_test(test_gltf_camera_path),
        cmocka_unit_test(test_unused_parts_said),
        cmocka_unit_test(test_builtin_paths),    cmocka_unit_test(test_skip_reasons),
        cmocka_unit_test(test_usage_and_threads),
        cmocka_unit_test(test_clocks_modes),
        cmocka_unit_test(test_backends_same_draw_calls),
        cmocka_unit_test(test_run_order),
        cmocka_unit_test(test_reference_shared),
        cmocka_unit_test(test_auto_offsets),
        cmocka_unit_test(test_gpu_memory_refused), cmocka_unit_test(test_full_disk),
        cmocka_unit_test(test_stability_verdict),
    };
    /* query timings; repeats until a CI; the reference's background overlapping the timed frames */
    const struct CMUnitTest timed[] = {
        cmocka_unit_test(test_query_timing),
        cmocka_unit_test(test_repeats_and_target_ci), cmocka_unit_test(test_reference_background),
    };
    if (argc > 1 && !strcmp(argv[1], "timed")) return cmocka_run_group_tests_name("cli-timed", timed, setup, teardown);
    return cmocka_run_group_tests_name("cli", tests, setup, teardown);
}
