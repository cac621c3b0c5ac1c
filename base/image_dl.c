/* image_dl.c - the image writer of a build with OpenImageIO: the adapter is a
 * module of its own (libsbimages.so beside the binary, or $SB_IMAGE_MODULE),
 * opened on first use, so that a run without --images never loads the
 * OpenImageIO stack (process start: see README, Building). */
#define _GNU_SOURCE
#include <dlfcn.h>
#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "image.h"
#include "image_module.h"

static sb_image_module_fn g_write;
static sb_image_module_read_fn g_read;
static sb_image_module_can_write_fn g_can_write;
static bool g_tried;
static char g_why[SB_ERR_LEN];

static void open_module(void) {
    if (g_tried) return;
    g_tried = true;
    char path[PATH_MAX];
    const char *env = getenv("SB_IMAGE_MODULE");
    if (env && *env) {
        snprintf(path, sizeof path, "%s", env);
    } else {
        ssize_t n = readlink("/proc/self/exe", path, sizeof path - 1);
        if (n <= 0) {
            snprintf(g_why, sizeof g_why, "cannot find the binary's folder to open %s", SB_IMAGE_MODULE_FILE);
            return;
        }
        path[n] = 0;
        char *slash = strrchr(path, '/');
        snprintf(slash ? slash + 1 : path, sizeof path - (size_t)(slash ? slash + 1 - path : 0), "%s",
                 SB_IMAGE_MODULE_FILE);
    }
    void *h = dlopen(path, RTLD_NOW | RTLD_LOCAL);
    if (!h) {
        snprintf(g_why, sizeof g_why, "the image module cannot be opened: %s", dlerror());
        return;
    }
    *(void **)&g_write = dlsym(h, SB_IMAGE_MODULE_SYMBOL);
    *(void **)&g_read = dlsym(h, SB_IMAGE_MODULE_READ_SYMBOL);
    *(void **)&g_can_write = dlsym(h, SB_IMAGE_MODULE_CAN_WRITE_SYMBOL);
    if (!g_write || !g_read || !g_can_write) {
        snprintf(g_why, sizeof g_why, "%.400s has no %s", path,
                 !g_write ? SB_IMAGE_MODULE_SYMBOL : !g_read ? SB_IMAGE_MODULE_READ_SYMBOL : SB_IMAGE_MODULE_CAN_WRITE_SYMBOL);
        g_write = NULL;
    }
}

bool sb_images_available(void) {
    open_module();
    return g_write != NULL;
}

const char *sb_images_unavailable_reason(void) {
    open_module();
    return g_write ? "" : g_why;
}

static bool write_image(const char *path, int w, int h, int channels, int is_float, const void *pixels, sb_err *err) {
    if (!sb_images_available()) return sb_fail(err, "%s: %s", path, g_why);
    char msg[SB_ERR_LEN] = "";
    if (g_write(path, w, h, channels, is_float, pixels, msg, sizeof msg)) return true;
    return sb_fail(err, "%s", msg);
}

bool sb_image_can_write(const char *path, sb_err *err) {
    if (!sb_images_available()) return sb_fail(err, "%s: %s", path, g_why);
    char msg[SB_ERR_LEN] = "";
    if (g_can_write(path, msg, sizeof msg)) return true;
    return sb_fail(err, "%s", msg);
}

bool sb_image_write_u8(const char *path, int w, int h, int channels, const unsigned char *pixels, sb_err *err) {
    return write_image(path, w, h, channels, 0, pixels, err);
}

bool sb_image_write_f32(const char *path, int w, int h, int channels, const float *pixels, sb_err *err) {
    return write_image(path, w, h, channels, 1, pixels, err);
}

bool sb_image_read_rgb(const char *path, int *w, int *h, float **rgb, sb_err *err) {
    *rgb = NULL;
    /* a regular file only (followed through links): a device or a FIFO would be read for ever, a folder is no
       image; named before anything is opened */
    struct stat st;
    if (stat(path, &st) != 0) return sb_fail(err, "%s: %s", path, strerror(errno));
    if (!S_ISREG(st.st_mode))
        return sb_fail(err, "%s: not a regular file (%s): images are read from files", path,
                       S_ISDIR(st.st_mode) ? "a folder" : S_ISFIFO(st.st_mode) ? "a FIFO" : "a device or socket");
    if (!sb_images_available()) return sb_fail(err, "%s: %s", path, g_why);
    char msg[SB_ERR_LEN] = "";
    if (!g_read(path, w, h, rgb, msg, sizeof msg)) return sb_fail(err, "%s", msg);
    /* NaN and infinity are no visibility nor colour: refused with the pixel (x from the left, y from the top) */
    for (size_t i = 0; i < (size_t)*w * *h * 3; i++)
        if (!isfinite((*rgb)[i])) {
            size_t px = i / 3;
            sb_fail(err, "%s: pixel (%zu, %zu) channel %zu is %s", path, px % (size_t)*w, px / (size_t)*w, i % 3,
                    isnan((*rgb)[i]) ? "NaN" : "infinite");
            free(*rgb);
            *rgb = NULL;
            return false;
        }
    return true;
}
