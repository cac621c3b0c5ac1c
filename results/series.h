/* series.h - a series: the runs of one setting on one machine over the nights (what the history compares).
 *
 * Its identity is typed fields, kept by the history's store in columns of their own (history_store.h); the key
 * text "host|renderer|scene|path|WxH|technique|params[|light][|anim=A][|indirect][|--OPTION VALUE...]" is made from them where a
 * series is named or ordered (labels, annotation patterns, bisect's match), never parsed back except from a
 * history of schema 3 or older, which kept it as one column (the migration). */
#pragma once
#include <stdbool.h>
#include <stddef.h>

#include "table.h"

typedef struct sb_series {
    char host[256], renderer[256], scene[256], path[512], size[32], technique[64];
    char params[1024];          /* canonical, sorted: "filter=pcf3:res=2048" */
    char light[1200];           /* a light with a size ("sun 0.53 deg, 64 rays"), lights ("lights lamps (6)"); "": none */
    char anim[300];             /* what plays, where not the default (the anim column); "": the default */
    char run_options[640];      /* the other identity options not at their defaults ("--sun 30,45"); "": none */
    bool indirect;              /* --submit indirect */
} sb_series;

/* Its parameters and what follows them in the key (sb_key_tail, runkey.h): the text a label's items come from. */
void sb_series_params_text(const sb_series *s, char *out, size_t len);
/* Its key text (what orders series and what a pattern is matched against). */
void sb_series_key(const sb_series *s, char *out, size_t len);
/* A key text of a schema-3 history back into its fields. */
void sb_series_parse(const char *key, sb_series *out);
/* A summary row's series on a host and renderer. */
void sb_series_of_row(const sb_table *t, int r, const char *host, const char *renderer, sb_series *out);
/* Whether two are one series. */
bool sb_series_equal(const sb_series *a, const sb_series *b);
