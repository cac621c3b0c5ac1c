/* libFuzzer harness: batch files and technique specs (parsing and validation;
 * no scene is loaded). */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "batch.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    char *text = malloc(size + 1);
    memcpy(text, data, size);
    text[size] = 0;
    sb_err err = {{0}};
    if (!sb_batch_check("fuzz.bench", text, &err) && !err.msg[0]) __builtin_trap();
    /* the first line as a spec on its own */
    char *nl = strchr(text, '\n');
    if (nl) *nl = 0;
    sb_run_spec *runs = NULL;
    int n = 0;
    if (sb_spec_expand(text, "fuzz", &runs, &n, &err)) {
        for (int i = 0; i < n; i++) {
            char canon[2048];
            sb_params_canonical(&runs[i].params, canon, sizeof canon);
        }
    }
    free(runs);
    free(text);
    return 0;
}
