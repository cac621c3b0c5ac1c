/* libFuzzer harness: the glTF loader (tinygltf adapter, validation, scene
 * building, chunking, BVH). Inputs starting with the glb magic are loaded as
 * .glb, others as .gltf. Every input must load or fail with a message. */
#include <stdint.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>

#include "scene_load.h"
#include "scene.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    static char path[64];
    bool glb = size >= 4 && memcmp(data, "glTF", 4) == 0;
    snprintf(path, sizeof path, "/tmp/sb-fuzz-%d.%s", (int)getpid(), glb ? "glb" : "gltf");
    FILE *f = fopen(path, "wb");
    if (!f) return 0;
    fwrite(data, 1, size, f);
    fclose(f);
    sb_set_quiet(true);
    sb_scene s;
    sb_err err = {{0}};
    if (sb_scene_load(&s, path, NULL, &err)) {
        /* a loaded scene is usable: finite bounds, indices in range */
        if (!sb_v3_finite(s.bounds.lo) || !sb_v3_finite(s.bounds.hi)) __builtin_trap();
        for (uint32_t i = 0; i < s.index_count; i++)
            if (s.indices[i] >= s.vertex_count) __builtin_trap();
        sb_scene_free(&s);
    } else if (!err.msg[0]) {
        __builtin_trap(); /* a failure must say why */
    }
    unlink(path);
    return 0;
}
