/* runkey.h - a run's identity as a results set records it, read in one place.
 *
 * The option table (harness/options.c, its `.identity` rows) decides what makes a run what it is; a results set
 * records that in its summary's identity columns. Everything that reads a set back (compare, history, report,
 * batch's resume, tune, merge) takes the run key, never a column by name: the names are read here alone. */
#pragma once
#include <stdbool.h>
#include <stddef.h>

#include "table.h"

/* One row's identity: pointers into the table's cells ("" for a column a set from before it lacks). */
typedef struct sb_run_key {
    const char *run_id;
    const char *scene, *path;
    const char *technique, *params;     /* params as written (sb_run_key_text sorts them) */
    const char *light;                  /* "" in a set from before the column */
    const char *anim;                   /* "" by default, and in a set from before the column */
    const char *submit;                 /* "indirect": another series of timings */
    const char *renderer;
    const char *width, *height;
    const char *run_options;            /* the identity options without a column of their own ("--sun 30,45"): the
                                           option table's rows, whatever they are; "" at their defaults and in a set
                                           from before the column */
} sb_run_key;

/* The first identity column a summary must have and t lacks (NULL: none missing): the run, scene, path,
 * technique and parameters, and with `sized` the image size (older sets lack the rest). */
const char *sb_run_key_missing(const sb_table *t, bool sized);
/* Row r's key. */
void sb_run_key_of(const sb_table *t, int r, sb_run_key *k);
/* Row r's run id alone. */
const char *sb_run_key_id(const sb_table *t, int r);
/* Every row's key (t->nrows of them; free() it). */
sb_run_key *sb_run_keys(const sb_table *t);
/* The parameters in a stable order (sorted items), what two runs of one setting share however written. */
void sb_run_key_sorted_params(const char *params, char *out, size_t len);
/* What two sets' runs are matched by: scene|path|technique|sorted params, then |light where the run's light is
 * sized or a section's, |anim=A where the clips play otherwise than the file says, |indirect where its draws were
 * issued indirectly, |--OPTION VALUE... where other identity options are not at their defaults (each left out
 * where empty or direct: the keys of sets from before those columns). */
void sb_run_key_text(const sb_run_key *k, char *out, size_t len);
/* What follows the parameters in a key's text, each where it applies (|light, |anim=A, |indirect, |--OPTION
 * VALUE...): one rule for a run key's text and a series' (series.h). */
void sb_key_tail(const char *light, const char *anim, bool indirect, const char *run_options, char *out, size_t len);
/* Whether the run's draws were issued indirectly. */
bool sb_run_key_indirect(const sb_run_key *k);
