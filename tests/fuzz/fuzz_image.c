/* libFuzzer harness: the reader of images from outside (base/image_oiio.cc's entry, built into this harness
 * with a limit of 2048 x 2048 pixels so that what it accepts fits the fuzzer's memory). The bytes are written to a
 * file named .png or .exr by their magic (OpenImageIO picks its reader by the name, then tries the others). An
 * image accepted has a size within the limit and every value written (NaN is image_dl.c's to refuse); a refusal
 * is one line naming the file. */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "image_module.h"

bool SB_IMAGE_MODULE_READ_ENTRY(const char *path, int *w, int *h, float **pixels, char *err, size_t err_len);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    static char path[64];
    bool exr = size >= 4 && data[0] == 0x76 && data[1] == 0x2f && data[2] == 0x31 && data[3] == 0x01;
    snprintf(path, sizeof path, "fuzz-image-%d.%s", (int)getpid(), exr ? "exr" : "png");
    FILE *f = fopen(path, "wb");
    if (!f) __builtin_trap();
    if (size && fwrite(data, 1, size, f) != size) __builtin_trap();
    if (fclose(f) != 0) __builtin_trap();
    int w = 0, h = 0;
    float *px = NULL;
    char err[512] = "";
    if (SB_IMAGE_MODULE_READ_ENTRY(path, &w, &h, &px, err, sizeof err)) {
        if (w <= 0 || h <= 0 || (double)w * h > SB_IMAGE_MAX_PIXELS || !px) __builtin_trap();
        volatile float sum = 0;
        for (size_t i = 0; i < (size_t)w * h * 3; i++) sum += px[i];   /* every value was written */
        (void)sum;
    } else if (!strstr(err, path) || strchr(err, '\n')) {
        __builtin_trap();   /* a refusal names the file, on one line */
    }
    free(px);
    unlink(path);
    return 0;
}
