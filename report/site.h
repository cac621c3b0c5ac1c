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
 * libjs-dygraphs at build time, with its licence beside it.
 *
 * A fifth kind, front.html, is the page `tune` writes for its search: the
 * night page's time-against-error chart over the candidates, with the bound
 * and the choice marked (sb_site_write_front). */
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

/* One point of a time-against-error chart: a candidate of a tune, a run of a night. */
typedef struct sb_site_point {
    const char *technique;
    const char *label;          /* technique[:the parameters that set it apart] */
    double x, y;                /* time (ms), error */
    int frames;                 /* the frames the figures are from */
    bool front;                 /* on the Pareto front */
    bool chosen;                /* the one recommended (ringed) */
} sb_site_point;

typedef struct sb_site_front {
    const char *out;            /* the site's folder (created; its files replaced) */
    const char *title;          /* the page's heading */
    const char *about;          /* a line under it: what the points' figures are */
    const char *xlabel, *ylabel;
    double bound;               /* a limit drawn as a dashed line (0: none) */
    bool bound_on_x;            /* the bound limits the time (else the error) */
    const char *chosen_is;      /* what the ringed point is ("recommended", ...) */
    const sb_site_point *points;
    int n;
} sb_site_front;

/* front.html and its data: one chart, the candidates' table. */
bool sb_site_write_front(const sb_site_front *f, sb_err *err);
