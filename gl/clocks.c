/* clocks.c - GPU clock and power state through NVML (dlopen) or sysfs (see clocks.h). */
#define _DEFAULT_SOURCE /* dirent d_type */
#include "clocks.h"

#include <dirent.h>
#include <dlfcn.h>
#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* The slice of NVML's C API used here (nvml.h is not needed to build). */
typedef int nvml_ret;
typedef void *nvml_dev;
enum { NVML_SUCCESS = 0, NVML_CLOCK_GRAPHICS = 0, NVML_CLOCK_MEM = 2, NVML_TEMPERATURE_GPU = 0 };

typedef struct nvml_api {
    void *lib;
    nvml_ret (*init)(void);
    nvml_ret (*shutdown)(void);
    nvml_ret (*count)(unsigned *);
    nvml_ret (*handle)(unsigned, nvml_dev *);
    nvml_ret (*clock)(nvml_dev, int, unsigned *);
    nvml_ret (*power)(nvml_dev, unsigned *);
    nvml_ret (*temp)(nvml_dev, int, unsigned *);
    nvml_ret (*reasons)(nvml_dev, unsigned long long *);
    nvml_ret (*driver)(char *, unsigned);
    nvml_ret (*name)(nvml_dev, char *, unsigned);
    nvml_ret (*persistence)(nvml_dev, int *);
    nvml_ret (*lock)(nvml_dev, unsigned, unsigned);
    nvml_ret (*unlock)(nvml_dev);
    nvml_ret (*app_clock)(nvml_dev, int, unsigned *);
    nvml_ret (*max_clock)(nvml_dev, int, unsigned *);
    const char *(*error)(nvml_ret);
} nvml_api;

struct sb_clocks {
    enum { SRC_NONE, SRC_NVML, SRC_AMD, SRC_INTEL } src;
    char source[256];
    nvml_api nv;
    nvml_dev dev;
    char sclk[1024], power[1024], temp[1024], freq[1024];   /* sysfs files */
    bool locked;
    unsigned locked_mhz;
};

/* ---- NVML ---- */

static bool nvml_load(nvml_api *a, char *why, size_t len) {
    memset(a, 0, sizeof *a);
    a->lib = dlopen("libnvidia-ml.so.1", RTLD_NOW | RTLD_LOCAL);
    if (!a->lib) {
        snprintf(why, len, "libnvidia-ml.so.1 (NVIDIA's management library) is not installed");
        return false;
    }
#define SYM(field, name) *(void **)&a->field = dlsym(a->lib, name)
    SYM(init, "nvmlInit_v2");
    SYM(shutdown, "nvmlShutdown");
    SYM(count, "nvmlDeviceGetCount_v2");
    SYM(handle, "nvmlDeviceGetHandleByIndex_v2");
    SYM(clock, "nvmlDeviceGetClockInfo");
    SYM(power, "nvmlDeviceGetPowerUsage");
    SYM(temp, "nvmlDeviceGetTemperature");
    SYM(reasons, "nvmlDeviceGetCurrentClocksEventReasons");
    if (!a->reasons) SYM(reasons, "nvmlDeviceGetCurrentClocksThrottleReasons");
    SYM(driver, "nvmlSystemGetDriverVersion");
    SYM(name, "nvmlDeviceGetName");
    SYM(persistence, "nvmlDeviceGetPersistenceMode");
    SYM(lock, "nvmlDeviceSetGpuLockedClocks");
    SYM(unlock, "nvmlDeviceResetGpuLockedClocks");
    SYM(app_clock, "nvmlDeviceGetDefaultApplicationsClock");
    SYM(max_clock, "nvmlDeviceGetMaxClockInfo");
    SYM(error, "nvmlErrorString");
#undef SYM
    if (!a->init || !a->handle || !a->clock || !a->count) {
        snprintf(why, len, "libnvidia-ml.so.1 lacks nvmlInit_v2/nvmlDeviceGetClockInfo");
        dlclose(a->lib);
        a->lib = NULL;
        return false;
    }
    return true;
}

static const char *nvml_err(const nvml_api *a, nvml_ret r) {
    static char buf[32];
    if (a->error) return a->error(r);
    snprintf(buf, sizeof buf, "NVML error %d", r);
    return buf;
}

static bool open_nvml(sb_clocks *c, const sb_context *ctx, char *why, size_t len) {
    if (strncmp(ctx->vendor, "NVIDIA", 6) != 0) {
        snprintf(why, len, "the GL vendor is %s, not NVIDIA", ctx->vendor);
        return false;
    }
    if (!nvml_load(&c->nv, why, len)) return false;
    nvml_ret r = c->nv.init();
    unsigned n = 0;
    if (r == NVML_SUCCESS) r = c->nv.count(&n);
    if (r == NVML_SUCCESS && n == 0) {
        snprintf(why, len, "NVML sees no device");
        return false;
    }
    if (r == NVML_SUCCESS) r = c->nv.handle(0, &c->dev); /* the GL device: the first GPU (see README) */
    if (r != NVML_SUCCESS) {
        snprintf(why, len, "NVML: %s", nvml_err(&c->nv, r));
        return false;
    }
    char name[96] = "?";
    if (c->nv.name) c->nv.name(c->dev, name, sizeof name);
    snprintf(c->source, sizeof c->source, "nvml: %s (device 0 of %u)", name, n);
    c->src = SRC_NVML;
    return true;
}

/* ---- sysfs ---- */

static bool read_text(const char *path, char *out, size_t len) {
    FILE *f = fopen(path, "r");
    if (!f) return false;
    size_t n = fread(out, 1, len - 1, f);
    fclose(f);
    out[n] = 0;
    return n > 0;
}

static double read_number(const char *path) {
    char buf[64];
    return path[0] && read_text(path, buf, sizeof buf) ? strtod(buf, NULL) : NAN;
}

/* The first hwmon folder of a card's device, into out. */
static bool find_hwmon(const char *device, char *out, size_t len) {
    char dir[600];
    snprintf(dir, sizeof dir, "%s/hwmon", device);
    DIR *d = opendir(dir);
    if (!d) return false;
    struct dirent *e;
    bool found = false;
    while ((e = readdir(d)))
        if (!strncmp(e->d_name, "hwmon", 5)) {
            snprintf(out, len, "%s/%.64s", dir, e->d_name);
            found = true;
            break;
        }
    closedir(d);
    return found;
}

static bool open_card(sb_clocks *c, const char *root, const char *card) {
    char dev[512], path[768], hw[700];
    snprintf(dev, sizeof dev, "%s/class/drm/%.64s/device", root, card);
    snprintf(path, sizeof path, "%s/pp_dpm_sclk", dev);
    char buf[8];
    if (read_text(path, buf, sizeof buf)) { /* amdgpu */
        c->src = SRC_AMD;
        snprintf(c->sclk, sizeof c->sclk, "%s", path);
        if (find_hwmon(dev, hw, sizeof hw)) {
            snprintf(c->power, sizeof c->power, "%s/power1_average", hw);
            snprintf(c->temp, sizeof c->temp, "%s/temp1_input", hw);
        }
        snprintf(c->source, sizeof c->source, "sysfs: amdgpu %s", card);
        return true;
    }
    const char *intel[] = {"gt_act_freq_mhz", "gt_cur_freq_mhz"};
    for (int i = 0; i < 2; i++) {
        snprintf(path, sizeof path, "%s/class/drm/%.64s/%s", root, card, intel[i]);
        if (read_text(path, buf, sizeof buf)) { /* i915 */
            c->src = SRC_INTEL;
            snprintf(c->freq, sizeof c->freq, "%s", path);
            snprintf(c->source, sizeof c->source, "sysfs: i915 %s", card);
            return true;
        }
    }
    return false;
}

/* The card of the EGL device (its DRM node, when EGL named one), else the first with clock files. */
static bool open_sysfs(sb_clocks *c, const sb_context *ctx, const char *root, char *why, size_t len) {
    const char *drm = strstr(ctx->device, "/dev/dri/card");
    if (drm && open_card(c, root, drm + strlen("/dev/dri/"))) return true;
    char dir[512];
    snprintf(dir, sizeof dir, "%s/class/drm", root);
    DIR *d = opendir(dir);
    if (d) {
        struct dirent *e;
        while ((e = readdir(d)))
            if (!strncmp(e->d_name, "card", 4) && !strchr(e->d_name, '-') && open_card(c, root, e->d_name)) {
                closedir(d);
                return true;
            }
        closedir(d);
    }
    snprintf(why, len, "no card under %s/class/drm has amdgpu or i915 clock files", root);
    return false;
}

/* pp_dpm_sclk: "0: 500Mhz\n1: 1800Mhz *\n": the starred level is the current one. */
static double amd_sclk(const char *path) {
    char buf[1024];
    if (!read_text(path, buf, sizeof buf)) return NAN;
    for (char *line = strtok(buf, "\n"); line; line = strtok(NULL, "\n"))
        if (strchr(line, '*')) {
            char *colon = strchr(line, ':');
            return colon ? strtod(colon + 1, NULL) : NAN;
        }
    return NAN;
}

/* ---- the reader ---- */

sb_clocks *sb_clocks_open(const sb_context *ctx, const char *sysfs_root) {
    sb_clocks *c = sb_xcalloc(1, sizeof *c);
    char why_nv[200] = "", why_fs[200] = "";
    if (open_nvml(c, ctx, why_nv, sizeof why_nv) || open_sysfs(c, ctx, sysfs_root, why_fs, sizeof why_fs)) return c;
    if (c->nv.lib) dlclose(c->nv.lib);
    memset(&c->nv, 0, sizeof c->nv);
    c->src = SRC_NONE;
    snprintf(c->source, sizeof c->source, "none: %s%s; %s", ctx->software ? "a software rasterizer has no GPU clock; " : "",
             why_nv, why_fs);
    return c;
}

void sb_clocks_close(sb_clocks *c) {
    if (!c) return;
    if (c->locked) sb_clocks_restore();
    if (c->src == SRC_NVML && c->nv.shutdown) c->nv.shutdown();
    if (c->nv.lib) dlclose(c->nv.lib);
    free(c);
}

const char *sb_clocks_source(const sb_clocks *c) { return c ? c->source : "none"; }

void sb_clocks_sample(const sb_clocks *c, sb_clock_sample *s) {
    s->gfx_mhz = s->mem_mhz = s->power_w = s->temp_c = NAN;
    s->throttle = 0;
    if (!c) return;
    unsigned v;
    unsigned long long bits;
    switch (c->src) {
    case SRC_NVML:
        if (c->nv.clock(c->dev, NVML_CLOCK_GRAPHICS, &v) == NVML_SUCCESS) s->gfx_mhz = v;
        if (c->nv.clock(c->dev, NVML_CLOCK_MEM, &v) == NVML_SUCCESS) s->mem_mhz = v;
        if (c->nv.power && c->nv.power(c->dev, &v) == NVML_SUCCESS) s->power_w = v / 1e3;
        if (c->nv.temp && c->nv.temp(c->dev, NVML_TEMPERATURE_GPU, &v) == NVML_SUCCESS) s->temp_c = v;
        if (c->nv.reasons && c->nv.reasons(c->dev, &bits) == NVML_SUCCESS) s->throttle = bits;
        break;
    case SRC_AMD:
        s->gfx_mhz = amd_sclk(c->sclk);
        s->power_w = read_number(c->power) / 1e6;
        s->temp_c = read_number(c->temp) / 1e3;
        break;
    case SRC_INTEL: s->gfx_mhz = read_number(c->freq); break;
    case SRC_NONE: break;
    }
}

double sb_clocks_mhz(const sb_clocks *c) {
    if (!c || c->src == SRC_NONE) return NAN;
    sb_clock_sample s;
    sb_clocks_sample(c, &s);
    return s.gfx_mhz;
}

/* ---- locking ---- */

static sb_clocks *g_locked; /* the one lock of the process, for exit and signal handlers */

void sb_clocks_restore(void) {
    sb_clocks *c = g_locked;
    if (!c || !c->locked) return;
    c->locked = false;
    g_locked = NULL;
    if (c->nv.unlock) c->nv.unlock(c->dev);
}

static void restore_and_reraise(int sig) {
    sb_clocks_restore();
    signal(sig, SIG_DFL);
    raise(sig);
}

static bool lock(sb_clocks *c, char *why, size_t len) {
    if (c->src != SRC_NVML) {
        snprintf(why, len, "clock locking is done through NVML only (%s)", c->source);
        return false;
    }
    if (!c->nv.lock || !c->nv.unlock) {
        snprintf(why, len, "this NVML has no nvmlDeviceSetGpuLockedClocks");
        return false;
    }
    unsigned mhz = 0;
    if (!c->nv.app_clock || c->nv.app_clock(c->dev, NVML_CLOCK_GRAPHICS, &mhz) != NVML_SUCCESS || !mhz) {
        unsigned max = 0; /* no default applications clock: 80% of the maximum */
        if (c->nv.max_clock && c->nv.max_clock(c->dev, NVML_CLOCK_GRAPHICS, &max) == NVML_SUCCESS) mhz = max * 4 / 5;
    }
    if (!mhz) {
        snprintf(why, len, "NVML reports neither a default applications clock nor a maximum clock");
        return false;
    }
    nvml_ret r = c->nv.lock(c->dev, mhz, mhz);
    if (r != NVML_SUCCESS) {
        snprintf(why, len, "nvmlDeviceSetGpuLockedClocks(%u MHz): %s (root or persistence mode may be needed)", mhz,
                 nvml_err(&c->nv, r));
        return false;
    }
    c->locked = true;
    c->locked_mhz = mhz;
    g_locked = c;
    atexit(sb_clocks_restore);
    const int sigs[] = {SIGINT, SIGTERM, SIGHUP};
    for (size_t i = 0; i < sizeof sigs / sizeof sigs[0]; i++) signal(sigs[i], restore_and_reraise);
    return true;
}

bool sb_clocks_apply(sb_clocks *c, sb_clocks_mode mode, char *used, size_t len, sb_err *err) {
    snprintf(used, len, "free");
    if (mode == SB_CLOCKS_FREE) return true;
    if (c->locked) {
        snprintf(used, len, "locked at %u MHz", c->locked_mhz);
        return true;
    }
    char why[400];
    if (lock(c, why, sizeof why)) {
        snprintf(used, len, "locked at %u MHz", c->locked_mhz);
        return true;
    }
    if (mode == SB_CLOCKS_LOCK) return sb_fail(err, "--clocks lock: cannot lock the GPU clock: %s", why);
    /* a note only where there is a clock to lock, once a process; a software rasterizer has none */
    static bool said;
    if (c->src == SRC_NONE) sb_verbose("note: no GPU clock to lock (%s)", why);
    else if (!said) sb_log("note: GPU clock not locked (%s); timings follow the clock: see docs/timing.md", why);
    if (c->src != SRC_NONE) said = true;
    return true;
}

void sb_clocks_describe(const sb_clocks *c, char *out, size_t len) {
    char driver[96] = "unknown", persist[32] = "unknown";
    if (c && c->src == SRC_NVML) {
        if (c->nv.driver) c->nv.driver(driver, sizeof driver);
        int mode = -1;
        if (c->nv.persistence && c->nv.persistence(c->dev, &mode) == NVML_SUCCESS)
            snprintf(persist, sizeof persist, "%s", mode ? "enabled" : "disabled");
    }
    char lock_state[64] = "free";
    if (c && c->locked) snprintf(lock_state, sizeof lock_state, "locked at %u MHz", c->locked_mhz);
    snprintf(out, len, "clocks_source: %s\ngpu_driver: %s\npersistence_mode: %s\nclocks: %s\n", sb_clocks_source(c),
             driver, persist, lock_state);
}

void sb_throttle_names(uint64_t bits, char *out, size_t len) {
    static const char *const names[] = {"gpu_idle", "applications_clocks", "sw_power_cap", "hw_slowdown",
                                        "sync_boost", "sw_thermal", "hw_thermal", "hw_power_brake", "display_clock"};
    out[0] = 0;
    for (size_t i = 0; i < sizeof names / sizeof names[0]; i++)
        if (bits & (1ull << i)) {
            size_t n = strlen(out);
            snprintf(out + n, len - n, "%s%s", n ? "|" : "", names[i]);
        }
}
