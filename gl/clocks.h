/* clocks.h - the GPU's clock and power state, read and (optionally) locked.
 *
 * A GPU whose clocks move measures the same work at different speeds: the
 * driver drops the graphics clock within a second of idling (an evaluation
 * pass, a scene load) and raises it again only under load. shadowbench reads
 * the state through the vendor's library loaded at run time (NVIDIA: NVML,
 * libnvidia-ml.so.1 by dlopen: no build or test dependency) or through sysfs
 * (AMD amdgpu: pp_dpm_sclk and hwmon; Intel i915: gt_act_freq_mhz), and
 * records it per frame and per run. Where nothing is readable (llvmpipe, no
 * driver library), the values are NaN and sb_clocks_source says why.
 *
 * --clocks lock locks the graphics clock for the whole invocation (NVML's
 * locked clocks, at the device's default applications clock: a clock it can
 * hold without thermal or power throttling) and restores it on every exit
 * path (normal exit, SIGINT, SIGTERM, SIGHUP); auto locks when permitted and
 * otherwise runs free with one warning line; free changes nothing. */
#pragma once
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "context.h"

typedef enum sb_clocks_mode { SB_CLOCKS_AUTO, SB_CLOCKS_LOCK, SB_CLOCKS_FREE } sb_clocks_mode;

typedef struct sb_clock_sample {
    double gfx_mhz, mem_mhz, power_w, temp_c;   /* NaN when not readable */
    uint64_t throttle;                          /* NVML clock event (throttle) reason bits */
} sb_clock_sample;

typedef struct sb_clocks sb_clocks;

/* The reader for the context's device (never NULL; a reader of nothing when
 * none is available). sysfs_root: "/sys" (tests give a folder of their own). */
sb_clocks *sb_clocks_open(const sb_context *ctx, const char *sysfs_root);
void sb_clocks_close(sb_clocks *c);
/* Where the values come from ("nvml: NVIDIA H100 ...", "sysfs: amdgpu card0"),
 * or why there are none ("none: ..."). */
const char *sb_clocks_source(const sb_clocks *c);
/* The graphics clock now, MHz (NaN when not readable; NULL reader allowed). */
double sb_clocks_mhz(const sb_clocks *c);
void sb_clocks_sample(const sb_clocks *c, sb_clock_sample *out);
/* Applies the mode; `used` gets what the summary's clocks column says ("locked
 * at 1755 MHz", "free"). lock that cannot lock fails with err; auto that cannot
 * logs one warning line and runs free. */
bool sb_clocks_apply(sb_clocks *c, sb_clocks_mode mode, char *used, size_t len, sb_err *err);
/* Undoes a lock (idempotent; also run at exit and on the signals above). */
void sb_clocks_restore(void);
/* Lines for a batch's meta file: source, driver, persistence mode, lock state. */
void sb_clocks_describe(const sb_clocks *c, char *out, size_t len);
/* Throttle reason bits as names joined by '|' ("" for none). */
void sb_throttle_names(uint64_t bits, char *out, size_t len);
