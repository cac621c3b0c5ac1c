/* glTF input held to the specification: the JSON reader, and files written
 * here that break one rule each, refused with the file and the JSON path.
 * Runs in the release build and in the ASan/UBSan build (suite `loader`). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "json.h"
#include "support.h"

static char g_tmp[64];

static int setup(void **st) {
    (void)st;
    snprintf(g_tmp, sizeof g_tmp, "/tmp/sbgltfXXXXXX");
    return mkdtemp(g_tmp) ? 0 : -1;
}

static int teardown(void **st) {
    (void)st;
    char cmd[128];
    snprintf(cmd, sizeof cmd, "rm -rf %s", g_tmp);
    return system(cmd) == 0 ? 0 : -1;
}

static const char *tmp_file(const char *name) {
    static char buf[4][256];
    static int k;
    k = (k + 1) % 4;
    snprintf(buf[k], sizeof buf[k], "%s/%s", g_tmp, name);
    return buf[k];
}

/* Writes the triangle with t's replacements and expects the refusal. */
static void refused(const char *name, const gltf_tri *t, const char *needle) {
    const char *f = tmp_file(name);
    assert_true(gltf_tri_write(f, t));
    expect_scene_refused(f, needle);
}

/* ---- the JSON reader ---- */

static void test_json_exact_integers(void **st) {
    (void)st;
    const char *text = "{\"a\": 18446744073709551615, \"b\": 18446744073709551616, \"c\": -12, \"d\": 3.0,"
                       " \"e\": 9007199254740993, \"f\": 1e3, \"g\": 2.5, \"h\": -0}";
    sb_json_doc doc;
    sb_err err;
    assert_true(sb_json_parse(&doc, "t", text, strlen(text), &err));
    uint64_t v;
    assert_true(sb_json_u64(sb_json_get(doc.root, "a"), &v));
    assert_true(v == UINT64_MAX);
    assert_false(sb_json_u64(sb_json_get(doc.root, "b"), &v));   /* 2^64: does not fit */
    assert_false(sb_json_u64(sb_json_get(doc.root, "c"), &v));
    assert_true(sb_json_negative(sb_json_get(doc.root, "c")));
    assert_true(sb_json_u64(sb_json_get(doc.root, "d"), &v) && v == 3);
    assert_true(sb_json_u64(sb_json_get(doc.root, "e"), &v) && v == 9007199254740993ull); /* a double would round */
    assert_true(sb_json_u64(sb_json_get(doc.root, "f"), &v) && v == 1000);
    assert_false(sb_json_u64(sb_json_get(doc.root, "g"), &v));
    assert_true(sb_json_u64(sb_json_get(doc.root, "h"), &v) && v == 0);
    sb_json_free(&doc);
}

static void test_json_strings(void **st) {
    (void)st;
    const char *text = "[\"a\\\"b\\\\c\\/\\n\", \"\\u00e9\\ud83d\\ude00\"]";
    sb_json_doc doc;
    sb_err err;
    assert_true(sb_json_parse(&doc, "t", text, strlen(text), &err));
    assert_int_equal(doc.root->count, 2);
    assert_string_equal(doc.root->items[0].text, "a\"b\\c/\n");
    assert_string_equal(doc.root->items[1].text, "\xc3\xa9\xf0\x9f\x98\x80");
    sb_json_free(&doc);
}

static void expect_syntax(const char *text, const char *needle) {
    sb_json_doc doc;
    sb_err err = {{0}};
    assert_false(sb_json_parse(&doc, "f.gltf", text, strlen(text), &err));
    print_message("%s\n", err.msg);
    assert_non_null(strstr(err.msg, needle));
}

static void test_json_syntax_errors(void **st) {
    (void)st;
    expect_syntax("{\n  \"a\": 1,\n  \"b\" 2\n}", "f.gltf: JSON syntax error at line 3, column 7: expected ':'");
    expect_syntax("", "line 1, column 1: expected a value, found the end");
    expect_syntax("{\"a\": [1, 2}", "line 1, column 12: expected ',' or ']'");
    expect_syntax("{\"a\": 01}", "line 1, column 8: expected ',' or '}'");
    expect_syntax("{\"a\": \"x", "line 1, column 7: a string is not closed");
    expect_syntax("{} x", "line 1, column 4: text after the end");
    expect_syntax("[\"\\ud800\"]", "without its low surrogate");
    char deep[2000];
    memset(deep, '[', 1000);
    deep[1000] = 0;
    expect_syntax(deep, "nesting deeper than 512 levels");
}

/* ---- issue 18: 64-bit offsets, lengths, counts and indices ---- */

static void test_loads_the_triangle(void **st) {
    (void)st;
    const char *f = tmp_file("ok.gltf");
    assert_true(gltf_tri_write(f, &(gltf_tri){0}));
    sb_scene s;
    sb_err err = {{0}};
    bool ok = sb_scene_load(&s, f, NULL, &err);
    if (!ok) print_message("%s\n", err.msg);
    assert_true(ok);
    assert_int_equal(sb_scene_triangles(&s), 1);
    sb_scene_free(&s);
}

static void test_accessor_offset_wraps(void **st) {
    (void)st;
    refused("acc-off.gltf",
            &(gltf_tri){.acc0 = "\"bufferView\":0,\"byteOffset\":18446744073709551580,\"componentType\":5126,\"count\":3,"
                                "\"type\":\"VEC3\""},
            ": /accessors/0: byteOffset 18446744073709551580 + 36 bytes (count 3, stride 12) run past the end of bufferView 0");
}

static void test_view_offset_wraps(void **st) {
    (void)st;
    refused("view-off.gltf", &(gltf_tri){.view0 = "\"buffer\":0,\"byteOffset\":18446744073709551608,\"byteLength\":36"},
            ": /bufferViews/0: byteOffset 18446744073709551608 + byteLength 36 run past the end of buffer 0 (44 bytes)");
}

static void test_index_offset_wraps(void **st) {
    (void)st;
    refused("idx-off.gltf",
            &(gltf_tri){.acc1 = "\"bufferView\":1,\"byteOffset\":18446744073709551614,\"componentType\":5123,\"count\":3,"
                                "\"type\":\"SCALAR\""},
            ": /accessors/1: byteOffset 18446744073709551614 + 6 bytes");
}

static void test_view_length_wraps(void **st) {
    (void)st;
    refused("view-len.gltf", &(gltf_tri){.view0 = "\"buffer\":0,\"byteOffset\":8,\"byteLength\":18446744073709551608"},
            ": /bufferViews/0: byteOffset 8 + byteLength 18446744073709551608 run past the end of buffer 0");
}

static void test_negative_offsets(void **st) {
    (void)st;
    refused("neg-acc.gltf",
            &(gltf_tri){.acc0 = "\"bufferView\":0,\"byteOffset\":-12,\"componentType\":5126,\"count\":3,\"type\":\"VEC3\""},
            ": /accessors/0/byteOffset: -12 is negative");
    refused("neg-view.gltf", &(gltf_tri){.view1 = "\"buffer\":0,\"byteOffset\":-4,\"byteLength\":6"},
            ": /bufferViews/1/byteOffset: -4 is negative");
}

static void test_indices_beyond_2_32(void **st) {
    (void)st;
    refused("mesh-idx.gltf", &(gltf_tri){.node0 = "\"mesh\":4294967296"},
            ": /nodes/0/mesh: mesh 4294967296 does not exist (the file has 1)");
    refused("node-idx.gltf", &(gltf_tri){.scene_nodes = "[4294967296]"},
            ": /scenes/0/nodes/0: node 4294967296 does not exist (the file has 1)");
    refused("light-idx.gltf",
            &(gltf_tri){.node0 = "\"mesh\":0,\"extensions\":{\"KHR_lights_punctual\":{\"light\":4294967296}}",
                        .root_more = ",\"extensions\":{\"KHR_lights_punctual\":{\"lights\":[{\"type\":\"directional\"}]}}"},
            ": /nodes/0/extensions/KHR_lights_punctual/light: light 4294967296 does not exist (the file has 1)");
    refused("acc-idx.gltf", &(gltf_tri){.prim = "\"attributes\":{\"POSITION\":4294967296},\"indices\":1"},
            ": /meshes/0/primitives/0/attributes/POSITION: accessor 4294967296 does not exist (the file has 2)");
}

static void test_count_wraps(void **st) {
    (void)st;
    refused("count.gltf",
            &(gltf_tri){.acc0 = "\"bufferView\":0,\"componentType\":5126,\"count\":4611686018427387904,\"type\":\"VEC3\""},
            ": /accessors/0: count 4611686018427387904 of 12-byte elements overflows 64 bits");
    refused("count-noview.gltf", &(gltf_tri){.acc0 = "\"componentType\":5126,\"count\":4611686018427387904,\"type\":\"VEC3\""},
            ": /accessors/0/count: 4611686018427387904 elements without a bufferView exceed 4 GiB");
    refused("count-huge.gltf", &(gltf_tri){.acc0 = "\"bufferView\":0,\"componentType\":5126,\"count\":1e300,\"type\":\"VEC3\""},
            ": /accessors/0/count: 1e300 is too large");
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_json_exact_integers),  cmocka_unit_test(test_json_strings),
        cmocka_unit_test(test_json_syntax_errors),   cmocka_unit_test(test_loads_the_triangle),
        cmocka_unit_test(test_accessor_offset_wraps), cmocka_unit_test(test_view_offset_wraps),
        cmocka_unit_test(test_index_offset_wraps),   cmocka_unit_test(test_view_length_wraps),
        cmocka_unit_test(test_negative_offsets),     cmocka_unit_test(test_indices_beyond_2_32),
        cmocka_unit_test(test_count_wraps),
    };
    return cmocka_run_group_tests_name("gltf", tests, setup, teardown);
}
