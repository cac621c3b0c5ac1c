/* glTF input held to the specification: the JSON reader, and files written
 * here that break one rule each, refused with the file and the JSON path.
 * Runs in the release build and in the ASan/UBSan build (suite `loader`). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "path.h"
#include "scene_load.h"
#include "json.h"
#include "gltf_check.h"
#include "support.h"


SB_TEST_SCRATCH("sbgltf")

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

/* ---- issue 17: URIs, layouts, transforms, graphs, degenerate scenes, lights ---- */

static void test_uri_directory(void **st) {
    (void)st;
    refused("dir.gltf", &(gltf_tri){.uri = "."}, ": /buffers/0/uri: \".\" is a directory, not a regular file");
}

/* The 44 bytes of the triangle in a .bin file at path. */
static void write_bin(const char *path) {
    unsigned char buf[44] = {0};
    const float pos[9] = {0, 0, 0, 1, 0, 0, 0, 0, 1};
    const uint16_t idx[3] = {0, 1, 2};
    memcpy(buf, pos, sizeof pos);
    memcpy(buf + 36, idx, sizeof idx);
    FILE *f = fopen(path, "wb");
    assert_non_null(f);
    assert_int_equal(fwrite(buf, 1, sizeof buf, f), sizeof buf);
    fclose(f);
}

static void test_uri_confined(void **st) {
    (void)st;
    char dir[300], out[300], cmd[700];
    snprintf(dir, sizeof dir, "%s/scene", g_tmp);
    snprintf(out, sizeof out, "%s/outside", g_tmp);
    snprintf(cmd, sizeof cmd, "mkdir -p %s %s", dir, out);
    assert_int_equal(system(cmd), 0);
    char bin[400], in_bin[400], link[400], file[400];
    snprintf(bin, sizeof bin, "%s/tri.bin", out);
    snprintf(in_bin, sizeof in_bin, "%s/tri.bin", dir);
    write_bin(bin);
    write_bin(in_bin);
    /* inside the folder: read */
    snprintf(file, sizeof file, "%s/in.gltf", dir);
    assert_true(gltf_tri_write(file, &(gltf_tri){.uri = "tri.bin"}));
    sb_scene s;
    sb_err err = {{0}};
    assert_true(sb_scene_load(&s, file, NULL, &err));
    sb_scene_free(&s);
    /* '..', an absolute path, a device, a symbolic link out of the folder: refused */
    snprintf(file, sizeof file, "%s/up.gltf", dir);
    assert_true(gltf_tri_write(file, &(gltf_tri){.uri = "../outside/tri.bin"}));
    expect_scene_refused(file, "/buffers/0/uri: \"../outside/tri.bin\" resolves to");
    expect_scene_refused(file, "outside the scene's folder");
    snprintf(file, sizeof file, "%s/passwd.gltf", dir);
    assert_true(gltf_tri_write(file, &(gltf_tri){.uri = "../../../../../../../etc/passwd"}));
    expect_scene_refused(file, "outside the scene's folder");
    snprintf(file, sizeof file, "%s/abs.gltf", dir);
    assert_true(gltf_tri_write(file, &(gltf_tri){.uri = bin}));
    expect_scene_refused(file, "outside the scene's folder");
    snprintf(file, sizeof file, "%s/zero.gltf", dir);
    assert_true(gltf_tri_write(file, &(gltf_tri){.uri = "/dev/zero"}));
    expect_scene_refused(file, "/buffers/0/uri: \"/dev/zero\" is a device, not a regular file");
    snprintf(link, sizeof link, "%s/link.bin", dir);
    assert_int_equal(symlink(bin, link), 0);
    snprintf(file, sizeof file, "%s/link.gltf", dir);
    assert_true(gltf_tri_write(file, &(gltf_tri){.uri = "link.bin"}));
    expect_scene_refused(file, "outside the scene's folder");
    /* image URIs alike */
    snprintf(file, sizeof file, "%s/img.gltf", dir);
    assert_true(gltf_tri_write(file, &(gltf_tri){.root_more = ",\"images\":[{\"uri\":\"../../../../../etc/passwd\"}]"}));
    expect_scene_refused(file, "/images/0/uri: \"../../../../../etc/passwd\" resolves to");
    /* --allow-external-uris reads outside the folder, but never a device */
    sb_scene_opts allow = {.allow_external_uris = true};
    snprintf(file, sizeof file, "%s/up.gltf", dir);
    assert_true(sb_scene_load(&s, file, &allow, &err));
    assert_int_equal(sb_scene_triangles(&s), 1);
    sb_scene_free(&s);
    snprintf(file, sizeof file, "%s/zero.gltf", dir);
    assert_false(sb_scene_load(&s, file, &allow, &err));
    assert_non_null(strstr(err.msg, "is a device"));
}

static void test_layouts(void **st) {
    (void)st;
    refused("stride-small.gltf", &(gltf_tri){.view0 = "\"buffer\":0,\"byteLength\":36,\"byteStride\":4"},
            ": /accessors/0: byteStride 4 of bufferView 0 is smaller than its 12-byte VEC3 elements");
    refused("stride-odd.gltf", &(gltf_tri){.view0 = "\"buffer\":0,\"byteLength\":36,\"byteStride\":14"},
            ": /bufferViews/0/byteStride: 14 is not a multiple of 4");
    refused("pos-offset.gltf",
            &(gltf_tri){.view0 = "\"buffer\":0,\"byteLength\":40",
                        .acc0 = "\"bufferView\":0,\"byteOffset\":2,\"componentType\":5126,\"count\":3,\"type\":\"VEC3\""},
            ": /accessors/0/byteOffset: 2 is not a multiple of the component size 4");
    refused("view-offset.gltf", &(gltf_tri){.view0 = "\"buffer\":0,\"byteOffset\":2,\"byteLength\":36"},
            ": /accessors/0: offset in the buffer (bufferView 0 at 2 + byteOffset 0) is not a multiple of the component size 4");
    refused("idx-offset.gltf",
            &(gltf_tri){.view1 = "\"buffer\":0,\"byteOffset\":36,\"byteLength\":8",
                        .acc1 = "\"bufferView\":1,\"byteOffset\":1,\"componentType\":5123,\"count\":3,\"type\":\"SCALAR\""},
            ": /accessors/1/byteOffset: 1 is not a multiple of the component size 2");
    refused("idx-stride.gltf", &(gltf_tri){.view1 = "\"buffer\":0,\"byteOffset\":34,\"byteLength\":10,\"byteStride\":4"},
            ": /meshes/0/primitives/0/indices: accessor 1: bufferView 1 of indices must not have a byteStride");
}

static void test_transforms(void **st) {
    (void)st;
    refused("quat-zero.gltf", &(gltf_tri){.node0 = "\"mesh\":0,\"rotation\":[0,0,0,0]"},
            ": /nodes/0/rotation: a zero-length quaternion is not a rotation");
    refused("matrix-w.gltf", &(gltf_tri){.node0 = "\"mesh\":0,\"matrix\":[1,0,0,0, 0,1,0,0, 0,0,1,0, 0,0,0,0]"},
            ": /nodes/0/matrix: not decomposable to translation, rotation and scale: its last row is (0, 0, 0, 0)");
    refused("scene-neg.gltf", &(gltf_tri){.scene = "-1"}, ": /scene: -1 is negative");
    refused("scene-big.gltf", &(gltf_tri){.scene = "1"}, ": /scene: scene 1 does not exist (the file has 1)");
    /* a quaternion of length 2 is normalised (with a warning): the identity */
    const char *f = tmp_file("quat-two.gltf");
    assert_true(gltf_tri_write(f, &(gltf_tri){.node0 = "\"mesh\":0,\"rotation\":[0,0,0,2]"}));
    sb_scene s;
    sb_err err;
    assert_true(sb_scene_load(&s, f, NULL, &err));
    sb_v3 hi = sb_v3_add(s.bounds.hi, s.origin);
    assert_true(fabs(hi.x - 1) < 1e-9 && fabs(hi.z - 1) < 1e-9);
    sb_scene_free(&s);
}

static void test_node_graphs(void **st) {
    (void)st;
    /* a real cycle (nodes 1 and 2, off the scene) and two parents */
    refused("cycle.gltf", &(gltf_tri){.nodes_more = ",{\"children\":[2]},{\"children\":[1]}"},
            ": /nodes/1/children: the node graph has a cycle through node 1");
    refused("self.gltf", &(gltf_tri){.node0 = "\"mesh\":0,\"children\":[0]"},
            ": /nodes/0/children/0: node 0 is its own child");
    refused("parents.gltf", &(gltf_tri){.node0 = "\"children\":[2]", .nodes_more = ",{\"children\":[2]},{\"mesh\":0}"},
            ": /nodes/1/children/0: node 2 has two parents (nodes 0 and 1)");
    refused("not-root.gltf", &(gltf_tri){.node0 = "\"children\":[1]", .nodes_more = ",{\"mesh\":0}", .scene_nodes = "[0,1]"},
            ": /scenes/0/nodes/1: node 1 is not a root node (it is a child of node 0)");
    /* a chain of 20,000 nodes is no cycle: it loads, every translation applied */
    const int n = 20000;
    char *more = malloc((size_t)n * 64);
    size_t len = 0;
    for (int i = 1; i < n; i++) {
        char next[32];
        snprintf(next, sizeof next, "\"children\":[%d]", i + 1);
        len += (size_t)snprintf(more + len, 64, ",{\"translation\":[0,0.001,0],%s}", i + 1 < n ? next : "\"mesh\":0");
    }
    const char *f = tmp_file("chain.gltf");
    assert_true(gltf_tri_write(f, &(gltf_tri){.node0 = "\"children\":[1],\"translation\":[0,0.001,0]", .nodes_more = more}));
    free(more);
    sb_scene s;
    sb_err err = {{0}};
    bool ok = sb_scene_load(&s, f, NULL, &err);
    if (!ok) print_message("%s\n", err.msg);
    assert_true(ok);
    assert_int_equal(sb_scene_triangles(&s), 1);
    print_message("chain of %d nodes: the triangle at y = %.9f\n", n, s.origin.y);
    assert_true(fabs(s.origin.y - 0.001 * n) < 1e-6);
    sb_scene_free(&s);
}

/* The node rules tying a node to its mesh and skin, one file each: a skinned
 * mesh without joints, node and mesh morph weights that do not match the
 * targets, a node with a skin or weights and no mesh, a skin whose joints are
 * not in the scene that draws it. */
static void test_skin_and_morph_rules(void **st) {
    (void)st;
    const char *skin = ",\"skins\":[{\"joints\":[1]}]";
    refused("skin-no-joints.gltf", &(gltf_tri){.node0 = "\"mesh\":0,\"skin\":0,\"children\":[1]",
                                                 .nodes_more = ",{}", .root_more = skin},
            ": /meshes/0/primitives/0/attributes: node 0 skins this mesh, but this primitive has no JOINTS_0");
    refused("skin-no-mesh.gltf", &(gltf_tri){.node0 = "\"mesh\":0,\"children\":[1]", .nodes_more = ",{\"skin\":0}",
                                               .root_more = skin},
            ": /nodes/1/skin: a node with a skin has a mesh to skin (none here)");
    refused("node-weights.gltf", &(gltf_tri){.node0 = "\"mesh\":0,\"weights\":[0.5]"},
            ": /nodes/0/weights: 1 weight(s), but its mesh 0's primitive 0 has 0 morph target(s)");
    refused("weights-no-mesh.gltf", &(gltf_tri){.nodes_more = ",{\"weights\":[0.5]}", .scene_nodes = "[0,1]"},
            ": /nodes/1/weights: a node with morph weights has a mesh (none here)");
    refused("mesh-weights.gltf",
            /* the mesh's own weights after its one primitive (the rest closes an "extras" array) */
            &(gltf_tri){.prim = "\"attributes\":{\"POSITION\":0},\"indices\":1,\"targets\":[{\"POSITION\":0}]}],"
                                "\"weights\":[0.5,0.5],\"extras\":[{\"y\":0"},
            ": /meshes/0/weights: 2 weight(s), but primitive 0 has 1 morph target(s)");
    refused("joint-off-scene.gltf",
            &(gltf_tri){.prim = "\"attributes\":{\"POSITION\":0,\"JOINTS_0\":0,\"WEIGHTS_0\":0},\"indices\":1",
                        .node0 = "\"mesh\":0,\"skin\":0", .nodes_more = ",{}", .root_more = skin},
            ": /skins/0/joints/0: joint node 1 is not in scene 0, which draws node 0 with this skin");
}

static void test_degenerate(void **st) {
    (void)st;
    const char *cases[][2] = {
        {"scale0.gltf", "\"mesh\":0,\"scale\":[0,0,0]"},
        {"point.gltf", NULL}, /* every vertex at one point: positions without a bufferView are zeros */
    };
    for (int k = 0; k < 2; k++) {
        const char *f = tmp_file(cases[k][0]);
        gltf_tri t = {.node0 = cases[k][1]};
        if (!cases[k][1]) t.acc0 = "\"componentType\":5126,\"count\":3,\"type\":\"VEC3\"";
        assert_true(gltf_tri_write(f, &t));
        sb_scene s;
        sb_err err;
        assert_true(sb_scene_load(&s, f, NULL, &err));
        print_message("%s: %s\n", cases[k][0], s.degenerate);
        assert_non_null(strstr(s.degenerate, "all 1 triangles have zero area"));
        sb_scene_free(&s);
    }
    /* the triangle itself is not degenerate */
    const char *f = tmp_file("fine.gltf");
    assert_true(gltf_tri_write(f, &(gltf_tri){0}));
    sb_scene s;
    sb_err err;
    assert_true(sb_scene_load(&s, f, NULL, &err));
    assert_string_equal(s.degenerate, "");
    sb_scene_free(&s);
}

static void test_lights(void **st) {
    (void)st;
    static const char node[] = "\"mesh\":0,\"extensions\":{\"KHR_lights_punctual\":{\"light\":0}}";
    refused("spot-cone.gltf",
            &(gltf_tri){.node0 = node,
                        .root_more = ",\"extensions\":{\"KHR_lights_punctual\":{\"lights\":[{\"type\":\"spot\","
                                     "\"spot\":{\"outerConeAngle\":2}}]}}"},
            ": /extensions/KHR_lights_punctual/lights/0/spot/outerConeAngle: 2 is out of range (0, 1.5708]");
    refused("spot-inner.gltf",
            &(gltf_tri){.node0 = node,
                        .root_more = ",\"extensions\":{\"KHR_lights_punctual\":{\"lights\":[{\"type\":\"spot\","
                                     "\"spot\":{\"innerConeAngle\":0.5,\"outerConeAngle\":0.4}}]}}"},
            ": /extensions/KHR_lights_punctual/lights/0/spot/innerConeAngle: 0.5 is out of range [0, 0.4)");
    refused("spot-intensity.gltf",
            &(gltf_tri){.node0 = node,
                        .root_more = ",\"extensions\":{\"KHR_lights_punctual\":{\"lights\":[{\"type\":\"spot\","
                                     "\"intensity\":-1,\"spot\":{}}]}}"},
            ": /extensions/KHR_lights_punctual/lights/0/intensity: -1 is out of range [0, inf)");
    refused("spot-missing.gltf",
            &(gltf_tri){.node0 = node,
                        .root_more = ",\"extensions\":{\"KHR_lights_punctual\":{\"lights\":[{\"type\":\"spot\"}]}}"},
            ": /extensions/KHR_lights_punctual/lights/0: 'spot' is missing");
    refused("light-type.gltf",
            &(gltf_tri){.node0 = node,
                        .root_more = ",\"extensions\":{\"KHR_lights_punctual\":{\"lights\":[{\"type\":\"area\"}]}}"},
            ": /extensions/KHR_lights_punctual/lights/0/type: \"area\" is not one of directional|point|spot");
}

/* Required extensions: applied ones load, any other is refused in one line
 * naming it (a loader must not draw what it does not understand). */
static void test_required_extensions(void **st) {
    (void)st;
    const char *f = tmp_file("req.gltf");
    const char *ok[] = {"KHR_mesh_quantization", "KHR_texture_transform", "EXT_mesh_gpu_instancing",
                        "KHR_materials_transmission"};
    char more[256];
    for (size_t i = 0; i < sizeof ok / sizeof ok[0]; i++) {
        snprintf(more, sizeof more, ",\"extensionsUsed\":[\"%s\"],\"extensionsRequired\":[\"%s\"]", ok[i], ok[i]);
        assert_true(gltf_tri_write(f, &(gltf_tri){.root_more = more}));
        sb_scene s;
        sb_err err;
        assert_true(sb_scene_load(&s, f, NULL, &err));
        sb_scene_free(&s);
    }
    assert_true(gltf_tri_write(f, &(gltf_tri){.root_more = ",\"extensionsRequired\":[\"KHR_gaussian_splatting\"]"}));
    expect_scene_refused(f, "/extensionsRequired/0: the file requires the extension KHR_gaussian_splatting");
    assert_true(gltf_tri_write(f, &(gltf_tri){.root_more = ",\"extensionsRequired\":[\"EXT_meshopt_compression\"]"}));
    expect_scene_refused(f, "requires EXT_meshopt_compression: meshopt-compressed buffers are not decoded");
    assert_true(gltf_tri_write(f, &(gltf_tri){.root_more = ",\"extensionsRequired\":[\"KHR_draco_mesh_compression\"]"}));
    if (!SB_HAVE_DRACO) expect_scene_refused(f, "built without Draco");
    /* a Draco primitive whose bitstream is not one: its extension's place in the message */
    assert_true(gltf_tri_write(f, &(gltf_tri){.prim = "\"attributes\":{\"POSITION\":0},\"indices\":1,\"extensions\":"
                                                      "{\"KHR_draco_mesh_compression\":{\"bufferView\":0,\"attributes\":"
                                                      "{\"POSITION\":0}}}"}));
    expect_scene_refused(f, SB_HAVE_DRACO ? "/meshes/0/primitives/0/extensions/KHR_draco_mesh_compression: Draco:"
                                          : "built without Draco");
}

/* What nothing draws is held leniently: it loads, and the scene says what was left out (info, every run's
 * warnings); where something does use it, the same rule refuses it. */
static void loads_with_note(const char *file, const char *needle) {
    sb_scene s;
    sb_err err = {{0}};
    bool ok = sb_scene_load(&s, file, NULL, &err);
    if (!ok) print_error("%s\n", err.msg);
    assert_true(ok);
    print_message("unused: %s\n", s.unused);
    assert_non_null(strstr(s.unused, needle));
    assert_int_equal(sb_scene_triangles(&s), 1);   /* what is drawn is all there */
    sb_scene_free(&s);
}

/* Appends an object to one of the document's top-level arrays (after its last element). */
static void append_to(const char *f, const char *array, const char *object) {
    sb_err err;
    char *doc = sb_read_file(f, NULL, &err);
    assert_non_null(doc);
    char key[64];
    snprintf(key, sizeof key, "\"%s\":[", array);
    char *at = strstr(doc, key);
    assert_non_null(at);
    int depth = 0;
    char *close = at + strlen(key) - 1;
    for (; *close; close++) {
        depth += *close == '[' || *close == '{';
        depth -= *close == ']' || *close == '}';
        if (depth == 0) break;
    }
    FILE *g = fopen(f, "w");
    assert_non_null(g);
    fprintf(g, "%.*s,%s%s", (int)(close - doc), doc, object, close);
    fclose(g);
    free(doc);
}
static void add_accessor(const char *f, const char *obj) { append_to(f, "accessors", obj); }
static void add_view(const char *f, const char *obj) { append_to(f, "bufferViews", obj); }
static void add_buffer(const char *f, const char *obj) { append_to(f, "buffers", obj); }

/* Adds a second buffer of 8 bytes with no uri to a file gltf_tri_write wrote. */
static void add_buffer_without_uri(const char *f) {
    sb_err err;
    char *doc = sb_read_file(f, NULL, &err);
    assert_non_null(doc);
    char *at = strstr(doc, "\"buffers\":[{");
    assert_non_null(at);
    char *close = strchr(at, ']');
    FILE *g = fopen(f, "w");
    assert_non_null(g);
    fprintf(g, "%.*s,{\"byteLength\":8}%s", (int)(close - doc), doc, close);
    fclose(g);
    free(doc);
}

/* A camera and animation channels nothing applies: left out and said; the same parts used are refused. */
static void test_unused_cameras_and_channels(void **st) {
    (void)st;
    /* a camera no path uses, with yfov >= pi; the path that uses it is refused with the same rule */
    const char *f = tmp_file("camera.gltf");
    assert_true(gltf_tri_write(f, &(gltf_tri){.nodes_more = ",{\"camera\":0}", .scene_nodes = "[0,1]",
                                              .root_more = ",\"cameras\":[{\"type\":\"perspective\",\"perspective\":"
                                                           "{\"yfov\":4.0,\"znear\":0.1}}]"}));
    loads_with_note(f, "/cameras/0/perspective/yfov: 4.0 is out of range (0, 3.14159)");
    char spec[300];
    snprintf(spec, sizeof spec, "%s#camera=0", f);
    sb_path p;
    sb_err err = {{0}};
    assert_false(sb_path_load(&p, spec, NULL, &err));
    print_message("%s\n", err.msg);
    assert_non_null(strstr(err.msg, "/cameras/0/perspective/yfov: 4.0 is out of range"));
    /* an animation channel of KHR_animation_pointer: not applied, said; path "pointer" without it is refused */
    static const char anim[] = ",\"extensionsUsed\":[\"KHR_animation_pointer\"],\"animations\":[{\"samplers\":"
                               "[{\"input\":1,\"output\":0}],\"channels\":[{\"sampler\":0,\"target\":{\"path\":"
                               "\"pointer\",\"extensions\":{\"KHR_animation_pointer\":{\"pointer\":"
                               "\"/materials/0/alphaCutoff\"}}}}]}]";
    f = tmp_file("pointer.gltf");
    assert_true(gltf_tri_write(f, &(gltf_tri){.root_more = anim}));
    loads_with_note(f, "/animations/0/channels/0: KHR_animation_pointer is not applied");
    /* a "pointer" channel without the extension declared (the Khronos validator's valid files have one): left out,
       said, as with it; any other unknown path is refused */
    f = tmp_file("pointer-bare.gltf");
    assert_true(gltf_tri_write(f, &(gltf_tri){.root_more = ",\"animations\":[{\"samplers\":[{\"input\":1,\"output\":0}],"
                                                           "\"channels\":[{\"sampler\":0,\"target\":{\"path\":\"pointer\"}}]}]"}));
    loads_with_note(f, "/animations/0/channels/0: a \"pointer\" channel is not applied");
    refused("path-typo.gltf",
            &(gltf_tri){.root_more = ",\"animations\":[{\"samplers\":[{\"input\":1,\"output\":0}],\"channels\":"
                                     "[{\"sampler\":0,\"target\":{\"path\":\"rotaton\"}}]}]"},
            "/animations/0/channels/0/target/path: \"rotaton\" is not one of translation|rotation|scale|weights");
}

static void test_unused_parts_lenient(void **st) {
    (void)st;
    const char *f;
    sb_err err = {{0}};
    /* parts nothing draws or animates never refuse a file (the Khronos validator's valid files): an accessor of an
       unknown type, a buffer without uri read only by a view nothing reads, a data: URI that is not base64 on a buffer
       nothing reads, a light of an unknown type no node uses; the same parts read by what is drawn are refused */
    f = tmp_file("acc-unknown.gltf");
    assert_true(gltf_tri_write(f, &(gltf_tri){.root_more = ""}));
    add_accessor(f, "{\"bufferView\":0,\"componentType\":5126,\"count\":1,\"type\":\"VEC5\"}");
    loads_with_note(f, "/accessors/2/type: \"VEC5\" is not one of SCALAR|VEC2|VEC3|VEC4|MAT2|MAT3|MAT4 (nothing reads this accessor)");
    refused("acc-unknown-read.gltf", &(gltf_tri){.acc1 = "\"bufferView\":1,\"componentType\":5123,\"count\":3,\"type\":\"VEC5\""},
            "/accessors/1/type: \"VEC5\" is not one of");
    f = tmp_file("nouri-unused-view.gltf");
    assert_true(gltf_tri_write(f, &(gltf_tri){0}));
    add_buffer_without_uri(f);
    add_view(f, "{\"buffer\":1,\"byteLength\":8}");
    loads_with_note(f, "/buffers/1: a buffer with no uri that nothing reads");
    f = tmp_file("data-unused.gltf");
    assert_true(gltf_tri_write(f, &(gltf_tri){0}));
    add_buffer(f, "{\"byteLength\":4,\"uri\":\"data:application/octet-stream,abcd\"}");
    loads_with_note(f, "/buffers/1/uri: a data: URI must be base64 (nothing reads this buffer)");
    refused("data-read.gltf", &(gltf_tri){.uri = "data:application/octet-stream,abcd"}, "a data: URI must be base64");
    /* a matrix of 1-byte components pads each column to 4 bytes but the last: 3 MAT3s of bytes fit in
       12 + 12 + 11 = 35 bytes, not 36 (glTF 2.0, 3.6.2.4; the validator's accessor lengths say the same) */
    for (int len = 35; len >= 34; len--) {
        f = tmp_file(len == 35 ? "mat3-fits.gltf" : "mat3-short.gltf");
        assert_true(gltf_tri_write(f, &(gltf_tri){.prim = "\"attributes\":{\"POSITION\":0,\"_M\":2},\"indices\":1"}));
        char view[80];
        snprintf(view, sizeof view, "{\"buffer\":0,\"byteOffset\":0,\"byteLength\":%d}", len);
        add_view(f, view);
        add_accessor(f, "{\"bufferView\":2,\"componentType\":5121,\"count\":3,\"type\":\"MAT3\"}");
        if (len == 35) {
            sb_scene s;
            bool ok = sb_scene_load(&s, f, NULL, &err);
            if (!ok) print_error("%s\n", err.msg);
            assert_true(ok);
            sb_scene_free(&s);
        } else {
            expect_scene_refused(f, "/accessors/2: byteOffset 0 + 35 bytes (count 3, stride 12) run past the end of "
                                    "bufferView 2 (34 bytes)");
        }
    }
    static const char light[] = ",\"extensionsUsed\":[\"KHR_lights_punctual\"],\"extensions\":{\"KHR_lights_punctual\":"
                                "{\"lights\":[{\"type\":\"area\"}]}}";
    f = tmp_file("light-unused.gltf");
    assert_true(gltf_tri_write(f, &(gltf_tri){.root_more = light}));
    loads_with_note(f, "(nothing reads this light)");
    refused("light-used.gltf",
            &(gltf_tri){.root_more = light, .node0 = "\"mesh\":0,\"extensions\":{\"KHR_lights_punctual\":{\"light\":0}}"},
            "/extensions/KHR_lights_punctual/lights/0/type: \"area\" is not one of directional|point|spot");
    /* a buffer with no uri that no bufferView reads: left out; one that a bufferView reads: refused */
    f = tmp_file("nouri.gltf");
    assert_true(gltf_tri_write(f, &(gltf_tri){0}));
    add_buffer_without_uri(f);
    loads_with_note(f, "/buffers/1: a buffer with no uri that nothing reads");
    f = tmp_file("nouri-read.gltf");
    assert_true(gltf_tri_write(f, &(gltf_tri){.view1 = "\"buffer\":1,\"byteOffset\":0,\"byteLength\":6"}));
    add_buffer_without_uri(f);
    expect_scene_refused(f, "/buffers/1: no uri (only the first buffer of a .glb may omit it), and bufferView 1 reads it");
    /* bytes after a .glb's declared length: left out; fewer than it declares: refused */
    f = tmp_file("padded.glb");
    copy_bundled("plane-box.glb", f);
    FILE *fp = fopen(f, "ab");
    assert_non_null(fp);
    fputc(0, fp);
    fclose(fp);
    sb_scene s;
    assert_true(sb_scene_load(&s, f, NULL, &err));
    print_message("unused: %s\n", s.unused);
    assert_non_null(strstr(s.unused, "1 byte(s) after the .glb's declared length"));
    assert_int_equal(sb_scene_triangles(&s), 24);
    sb_scene_free(&s);
    f = tmp_file("short.glb");
    copy_bundled("plane-box.glb", f);
    assert_int_equal(truncate(f, 1000), 0);
    expect_scene_refused(f, "the file has 1000 (truncated?)");
}

static void test_syntax_in_a_file(void **st) {
    (void)st;
    const char *f = tmp_file("syntax.gltf");
    FILE *fp = fopen(f, "w");
    fputs("{\n  \"asset\": {\"version\": \"2.0\"},\n  \"nodes\": [ {\"mesh\": 0} }\n}\n", fp);
    fclose(fp);
    expect_scene_refused(f, ": JSON syntax error at line 3, column 26: expected ',' or ']'");
    f = tmp_file("empty.gltf");
    fp = fopen(f, "w");
    fputs("{}", fp);
    fclose(fp);
    expect_scene_refused(f, ": /: 'asset' is missing");
}

/* ---- numbers of any size (SB_SCENE_MAX_COORD) ---- */

/* A triangle with animations: its buffer holds the triangle (accessors 0, 1), key times 0 and 1 as floats (2)
 * and as unsigned ints (7), two keys of `keys` as VEC3 (3), VEC4 (4) and SCALAR (5), and a morph target moving
 * every vertex by `delta` in x (6). nodes, prim_more (after the primitive's attributes), mesh_more, root_more and
 * acc_more (accessors 8 and on) are JSON. */
static void anim_file(const char *path, const char *nodes, const char *prim_more, const char *mesh_more,
                      const float keys[8], float delta, const char *root_more, const char *acc_more) {
    unsigned char buf[128] = {0};
    const float pos[9] = {0, 0, 0, 1, 0, 0, 0, 0, 1}, times[2] = {0, 1}, d[9] = {delta, 0, 0, delta, 0, 0, delta, 0, 0};
    const uint16_t idx[3] = {0, 1, 2};
    const uint32_t utimes[2] = {0, 1};
    memcpy(buf, pos, 36);
    memcpy(buf + 36, idx, 6);
    memcpy(buf + 44, times, 8);
    memcpy(buf + 52, keys, 32);
    memcpy(buf + 84, d, 36);
    memcpy(buf + 120, utimes, 8);
    char b64[200];
    test_base64(buf, sizeof buf, b64);
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    fprintf(f,
            "{\"asset\":{\"version\":\"2.0\"},\"scene\":0,\"scenes\":[{\"nodes\":[0]}],\"nodes\":[%s],"
            "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0},\"indices\":1%s}]%s}],"
            "\"buffers\":[{\"byteLength\":128,\"uri\":\"data:application/octet-stream;base64,%s\"}],"
            "\"bufferViews\":[{\"buffer\":0,\"byteLength\":36},{\"buffer\":0,\"byteOffset\":36,\"byteLength\":6},"
            "{\"buffer\":0,\"byteOffset\":44,\"byteLength\":8},{\"buffer\":0,\"byteOffset\":52,\"byteLength\":32},"
            "{\"buffer\":0,\"byteOffset\":84,\"byteLength\":36},{\"buffer\":0,\"byteOffset\":120,\"byteLength\":8}],"
            "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":3,\"type\":\"VEC3\","
            "\"min\":[0,0,0],\"max\":[1,0,1]},"
            "{\"bufferView\":1,\"componentType\":5123,\"count\":3,\"type\":\"SCALAR\"},"
            "{\"bufferView\":2,\"componentType\":5126,\"count\":2,\"type\":\"SCALAR\",\"min\":[0],\"max\":[1]},"
            "{\"bufferView\":3,\"componentType\":5126,\"count\":2,\"type\":\"VEC3\"},"
            "{\"bufferView\":3,\"componentType\":5126,\"count\":2,\"type\":\"VEC4\"},"
            "{\"bufferView\":3,\"componentType\":5126,\"count\":2,\"type\":\"SCALAR\"},"
            "{\"bufferView\":4,\"componentType\":5126,\"count\":3,\"type\":\"VEC3\"},"
            "{\"bufferView\":5,\"componentType\":5125,\"count\":2,\"type\":\"SCALAR\"}%s]%s}\n",
            nodes, prim_more, mesh_more, b64, acc_more, root_more);
    fclose(f);
}

/* One channel of node n: "path" from accessor `out` (key times from accessor `in`). */
static const char *channel(int in, int out, int n, const char *path) {
    static char buf[4][256];
    static int k;
    k = (k + 1) % 4;
    snprintf(buf[k], sizeof buf[k], ",\"animations\":[{\"samplers\":[{\"input\":%d,\"output\":%d}],\"channels\":"
             "[{\"sampler\":0,\"target\":{\"node\":%d,\"path\":\"%s\"}}]}]", in, out, n, path);
    return buf[k];
}

static void test_numbers_of_any_size(void **st) {
    (void)st;
    const float small[8] = {0, 0, 0, 10, 0, 0, 0, 1}, huge[8] = {0, 0, 0, 1e25f, 0, 0, 0, 1};
    const float scale[8] = {1, 1, 1, 1e5f, 1e5f, 1e5f, 0, 1}, zero_q[8] = {0, 0, 0, 1, 0, 0, 0, 0};
    const float weight[8] = {0, 1e9f, 0, 0, 0, 0, 0, 0}, weight_huge[8] = {0, 1e25f, 0, 0, 0, 0, 0, 0};
    const char *morph = ",\"targets\":[{\"POSITION\":6}]", *w0 = ",\"weights\":[0]";
    const char *f = tmp_file("ok-anim.gltf");
    /* the control: a translation of 10 loads and plays */
    anim_file(f, "{\"mesh\":0}", "", "", small, 0, channel(2, 3, 0, "translation"), "");
    sb_scene s;
    sb_err err;
    assert_true(sb_scene_load(&s, f, NULL, &err));
    assert_true(sb_scene_moves(&s));
    sb_scene_free(&s);
    /* a node's scale of 1e25 (finite, valid JSON): refused at load with the node */
    f = tmp_file("scale.gltf");
    anim_file(f, "{\"mesh\":0,\"scale\":[1e25,1e25,1e25]}", "", "", small, 0, "", "");
    expect_scene_refused(f, "/nodes/0: vertex 1 of its mesh lies at 1e+25 as placed");
    /* a translation key of 1e25 */
    f = tmp_file("key.gltf");
    anim_file(f, "{\"mesh\":0}", "", "", huge, 0, channel(2, 3, 0, "translation"), "");
    expect_scene_refused(f, "/animations/0/channels/0/output: value 3 is");
    /* scale keys of 1e5 on three nested nodes: each key fits, the pose they make (1e15) does not */
    f = tmp_file("chain.gltf");
    anim_file(f, "{\"mesh\":0},{\"children\":[0]},{\"children\":[1]}", "", "", scale, 0,
              ",\"animations\":[{\"samplers\":[{\"input\":2,\"output\":3}],\"channels\":["
              "{\"sampler\":0,\"target\":{\"node\":0,\"path\":\"scale\"}},"
              "{\"sampler\":0,\"target\":{\"node\":1,\"path\":\"scale\"}},"
              "{\"sampler\":0,\"target\":{\"node\":2,\"path\":\"scale\"}}]}]", "");
    /* the file's scene is node 0 only: make node 2 the root */
    char cmd[600];
    snprintf(cmd, sizeof cmd, "sed -i 's/\"nodes\":\\[0\\]}/\"nodes\":[2]}/' %s", f);
    assert_int_equal(system(cmd), 0);
    expect_scene_refused(f, "/nodes/0: as its clips can pose it");
    /* a morph weight key of 1e25, and one of 1e9 on a target that moves a vertex 1e4 (1e13 as posed) */
    f = tmp_file("weight.gltf");
    anim_file(f, "{\"mesh\":0}", morph, w0, weight_huge, 1, channel(2, 5, 0, "weights"), "");
    expect_scene_refused(f, "/animations/0/channels/0/output: value 1 is");
    f = tmp_file("weight-pose.gltf");
    anim_file(f, "{\"mesh\":0}", morph, w0, weight, 1e4f, channel(2, 5, 0, "weights"), "");
    expect_scene_refused(f, "/nodes/0: as its clips can pose it");
    /* key times as integers (glTF: an input is FLOAT), a zero-length rotation key */
    f = tmp_file("uint-times.gltf");
    anim_file(f, "{\"mesh\":0}", "", "", small, 0, channel(7, 3, 0, "translation"), "");
    expect_scene_refused(f, "/animations/0/channels/0/input: key times must be floats");
    f = tmp_file("zero-q.gltf");
    anim_file(f, "{\"mesh\":0}", "", "", zero_q, 0, channel(2, 4, 0, "rotation"), "");
    expect_scene_refused(f, "/animations/0/channels/0/output: key 1 is a zero-length quaternion");
}

/* A chain of `levels` nodes, the mesh at its end. */
static void chain_file(const char *path, int levels) {
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    fputs("{\"asset\":{\"version\":\"2.0\"},\"scene\":0,\"scenes\":[{\"nodes\":[0]}],\"nodes\":[", f);
    for (int i = 0; i < levels - 1; i++) fprintf(f, "{\"children\":[%d]},", i + 1);
    fputs("{\"mesh\":0}],\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0}}]}],\"buffers\":[{\"byteLength\":"
          "36,\"uri\":\"data:application/octet-stream;base64,AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAAAAAAIA/\"}],"
          "\"bufferViews\":[{\"buffer\":0,\"byteLength\":36}],\"accessors\":[{\"bufferView\":0,\"componentType\":5126,"
          "\"count\":3,\"type\":\"VEC3\",\"min\":[0,0,0],\"max\":[1,0,1]}]}\n", f);
    fclose(f);
}

/* Node chains of any depth are walked in linear time (the skin check walked each node up to its root: 100,000
 * levels took 7 s, 200,000 29 s); one deeper than SB_GLTF_MAX_DEPTH is refused naming the limit. */
static void test_deep_chains(void **st) {
    (void)st;
    const char *f = tmp_file("chain.gltf");
    chain_file(f, SB_GLTF_MAX_DEPTH);
    sb_scene s;
    sb_err err;
    double t0 = sb_now_ms();
    assert_true(sb_scene_load(&s, f, NULL, &err));
    print_message("%d levels: loaded in %.0f ms\n", SB_GLTF_MAX_DEPTH, sb_now_ms() - t0);
    assert_int_equal(sb_scene_triangles(&s), 1);
    sb_scene_free(&s);
    chain_file(f, SB_GLTF_MAX_DEPTH + 1);
    expect_scene_refused(f, "levels deep here, deeper than the 100000 levels shadowbench reads");
}

/* glTF animation semantics: refused with the place, or said (info and every run's warnings), never silent. */
static void test_animation_semantics(void **st) {
    (void)st;
    const float scale[8] = {1, 1, 1, -1, 1, 1, 0, 1}, move[8] = {0, 0, 0, 1, 0, 0, 0, 1};
    /* a morph target whose count is not the primitive's (accessor 3: two vertices of three) */
    const char *f = tmp_file("morph-count.gltf");
    anim_file(f, "{\"mesh\":0}", ",\"targets\":[{\"POSITION\":3}]", ",\"weights\":[0.5]", move, 0, "", "");
    expect_scene_refused(f, "/meshes/0/primitives/0/targets/0/POSITION: count 2 differs from the primitive's 3 vertices");
    /* 65 morph targets played by a clip: left out and said, as --pose says it */
    char targets[2048] = ",\"targets\":[", weights[512] = ",\"weights\":[";
    for (int t = 0; t < 65; t++) {
        strcat(targets, t ? ",{\"POSITION\":6}" : "{\"POSITION\":6}");
        strcat(weights, t ? ",0" : "0");
    }
    strcat(targets, "]");
    strcat(weights, "]");
    f = tmp_file("morph-65.gltf");
    anim_file(f, "{\"mesh\":0}", targets, weights, move, 1, channel(2, 8, 0, "weights"),
              ",{\"componentType\":5126,\"count\":130,\"type\":\"SCALAR\"}");
    sb_scene s;
    sb_err err;
    assert_true(sb_scene_load(&s, f, NULL, &err));
    print_message("unused: %s\n", s.unused);
    assert_non_null(strstr(s.unused, "/animations/0/channels/0: 65 morph weights, more than the 64 played: not applied"));
    sb_scene_free(&s);
    sb_scene_opts po = {.pose = true, .pose_time = 0.5};
    assert_true(sb_scene_load(&s, f, &po, &err));
    assert_non_null(strstr(s.unused, "65 morph weights, more than the 64 played"));
    sb_scene_free(&s);
    /* a skinned vertex whose weights are all 0 (accessor 9: zeros), and a joint whose inverse bind matrix is 0 */
    const char *skin_nodes = "{\"mesh\":0,\"skin\":0,\"children\":[1]},{}";
    const char *skin_prim = ",\"attributes\":{\"POSITION\":0,\"JOINTS_0\":8,\"WEIGHTS_0\":9}";
    const char *skin_acc = ",{\"componentType\":5121,\"count\":3,\"type\":\"VEC4\"},"
                           "{\"componentType\":5126,\"count\":3,\"type\":\"VEC4\"},"
                           "{\"componentType\":5126,\"count\":1,\"type\":\"MAT4\"}";
    f = tmp_file("zero-weights.gltf");
    anim_file(f, skin_nodes, skin_prim, "", move, 0, ",\"skins\":[{\"joints\":[1]}]", skin_acc);
    /* the primitive names its attributes once: the skinned ones replace the triangle's own */
    char cmd[600];
    snprintf(cmd, sizeof cmd, "sed -i 's/\"attributes\":{\"POSITION\":0},\"indices\":1,/\"indices\":1,/' %s", f);
    assert_int_equal(system(cmd), 0);
    expect_scene_refused(f, "/attributes/WEIGHTS_0: the weights of vertex 0 sum to 0");
    f = tmp_file("zero-ibm.gltf");
    anim_file(f, skin_nodes, skin_prim, "", move, 0, ",\"skins\":[{\"joints\":[1],\"inverseBindMatrices\":10}]",
              skin_acc);
    snprintf(cmd, sizeof cmd, "sed -i 's/\"attributes\":{\"POSITION\":0},\"indices\":1,/\"indices\":1,/' %s", f);
    assert_int_equal(system(cmd), 0);
    expect_scene_refused(f, "/skins/0/inverseBindMatrices: matrix 0 is not invertible");
    /* a scale key that mirrors the node: said (its winding is its rest pose's) */
    f = tmp_file("mirror.gltf");
    anim_file(f, "{\"mesh\":0}", "", "", scale, 0, channel(2, 3, 0, "scale"), "");
    assert_true(sb_scene_load(&s, f, NULL, &err));
    assert_non_null(strstr(s.unused, "/nodes/0: a scale key (1) mirrors it"));
    sb_scene_free(&s);
    /* a lamp on a node a clip moves: said (lights stay where the file places them) */
    f = tmp_file("lamp-moves.gltf");
    anim_file(f, "{\"mesh\":0,\"children\":[1]},{\"extensions\":{\"KHR_lights_punctual\":{\"light\":0}}}", "", "",
              move, 0,
              ",\"extensionsUsed\":[\"KHR_lights_punctual\"],\"extensions\":{\"KHR_lights_punctual\":{\"lights\":"
              "[{\"type\":\"point\"}]}},\"animations\":[{\"samplers\":[{\"input\":2,\"output\":3}],\"channels\":"
              "[{\"sampler\":0,\"target\":{\"node\":0,\"path\":\"translation\"}}]}]",
              "");
    assert_true(sb_scene_load(&s, f, NULL, &err));
    print_message("unused: %s\n", s.unused);
    assert_non_null(strstr(s.unused, "/nodes/1: its light is moved by a clip"));
    sb_scene_free(&s);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_json_exact_integers),  cmocka_unit_test(test_json_strings),
        cmocka_unit_test(test_json_syntax_errors),   cmocka_unit_test(test_loads_the_triangle),
        cmocka_unit_test(test_accessor_offset_wraps), cmocka_unit_test(test_view_offset_wraps),
        cmocka_unit_test(test_index_offset_wraps),   cmocka_unit_test(test_view_length_wraps),
        cmocka_unit_test(test_negative_offsets),     cmocka_unit_test(test_indices_beyond_2_32),
        cmocka_unit_test(test_count_wraps),          cmocka_unit_test(test_uri_directory),
        cmocka_unit_test(test_uri_confined),         cmocka_unit_test(test_layouts),
        cmocka_unit_test(test_transforms),           cmocka_unit_test(test_node_graphs),
        cmocka_unit_test(test_skin_and_morph_rules),
        cmocka_unit_test(test_degenerate),           cmocka_unit_test(test_lights),
        cmocka_unit_test(test_syntax_in_a_file),     cmocka_unit_test(test_required_extensions),
        cmocka_unit_test(test_unused_cameras_and_channels), cmocka_unit_test(test_unused_parts_lenient),
        cmocka_unit_test(test_numbers_of_any_size),
        cmocka_unit_test(test_deep_chains),
        cmocka_unit_test(test_animation_semantics),
    };
    return cmocka_run_group_tests_name("gltf", tests, setup, teardown);
}
