/* site.h - `shadowbench report`: a static site of a results set or of the
 * history, opened from file:// with no network.
 *
 * Four kinds of page, each a small HTML shell that loads its data as a script
 * (browsers do not let file:// pages fetch JSON): index.html (the nights, the
 * regressions and the series of a history), night.html?n=ID (a night's summary
 * table, its pairs, the time-against-error front per scene), run.html?n=ID&r=RUN
 * (a run's frame times by stage, draw calls and triangles, its images) and
 * series.html?s=ID (a series' trend per metric with its change points). The
 * charts are drawn by dygraphs (MIT), copied into assets/ from Debian's
 * libjs-dygraphs at build time, with its licence beside it. */
#pragma once
#include <stdbool.h>

#include "util.h"

typedef struct sb_site_opts {
    const char *dir;            /* a results set; or NULL and: */
    const char *history;        /* a history file */
    const char *out;            /* the site's folder (created; its pages replaced) */
    int recent;                 /* the newest nights whose regressions are marked recent (0: 3) */
} sb_site_opts;

/* Whether this build carries the charting library. */
bool sb_site_available(void);
bool sb_site_write(const sb_site_opts *o, sb_err *err);
