/* libFuzzer harness: the path parser and the interpolation of what it accepts. */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "path.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    char *text = malloc(size + 1);
    memcpy(text, data, size);
    text[size] = 0;
    sb_path p;
    sb_err err = {{0}};
    if (sb_path_parse(&p, "fuzz.path", text, &err)) {
        /* every accepted path gives finite cameras */
        for (int i = 0; i < 7; i++) {
            sb_camera c = sb_path_camera(&p, i, 7, 1.5, NULL);
            if (!sb_v3_finite(c.pos) || !isfinite(c.rot.w) || !sb_v3_finite(c.forward) || !isfinite(c.fov_deg))
                __builtin_trap();
        }
        sb_path_free(&p);
    } else if (!err.msg[0]) {
        __builtin_trap();
    }
    free(text);
    return 0;
}
