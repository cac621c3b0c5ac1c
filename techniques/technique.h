/* technique.h - the one interface every shadow technique implements.
 *
 * A technique is a descriptor (sokol-style): a name, a parameter table whose
 * rows carry types, defaults, valid ranges and where each value goes in the
 * technique's parameter struct, the stages it has, what it needs from a
 * scene, and a few functions:
 *   check      (optional, no GL) parameter combinations that cannot work:
 *              refused with the spec, before anything renders;
 *   supported  (optional) whether this context and scene can run it; the
 *              reason becomes the run's `skipped` reason;
 *   load       (optional) work per scene that depends on no parameter, done
 *              once per scene and shared by its runs (unload frees it);
 *   create, frame, destroy; collect (optional) for counters known only after
 *              the timed frames;
 *   check_frame (optional) its own check of an evaluated frame's input;
 *   label      (optional) what its rows call a run (score: the renderer's).
 * Its stages are rows it declares (SB_STAGES, stage.h), as its counters are;
 * a technique that declares none is timed never (another renderer's frames).
 * Whatever it does, its final pass writes one screen-space visibility target
 * (1 lit ... 0 shadowed) beside colour; the error metrics and images read
 * that. Counters and warnings of its own are rows and a hook in its file
 * (counters, warn): nothing else knows them by name. To add one: write techniques/NAME.c exporting `const sb_technique
 * sb_technique_NAME` and add NAME to the list in techniques/meson.build. */
#pragma once
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include "stage.h"
#include "util.h"


enum {
    SB_NEEDS_SUN = 1u << 0,         /* a directional light (skipped on a scene lit only by lamps) */
    SB_NEEDS_POINT_LIGHT = 1u << 1, /* a point or spot light */
    SB_NEEDS_CLOSED = 1u << 2,      /* closed casters (reported, not enforced) */
    SB_NEEDS_PLANE = 1u << 3,       /* a large planar receiver */
    SB_NEEDS_REFERENCE = 1u << 4,   /* the Embree reference (sb_run_ctx.reference) */
};

/* TEXT: a string (a folder, a file pattern, a name): in a spec it holds no ':' or ',' (they divide options and
 * values); its field is a const char * (the value interned: alive for the process). */
typedef enum sb_param_kind { SB_PARAM_INT, SB_PARAM_FLOAT, SB_PARAM_ENUM, SB_PARAM_TEXT } sb_param_kind;

/* What a parameter is to the shared machinery that reasons about cost without rendering (batch's cost model). */
typedef enum sb_param_role {
    SB_PARAM_PLAIN,
    SB_PARAM_RES,           /* texels per side of each shadow map */
    SB_PARAM_MAPS,          /* shadow maps (cascades) rendered a frame */
    SB_PARAM_SUN_SIZE,      /* the sun's angular diameter a soft filter assumes: follows --sun-size unless given */
    SB_PARAM_CACHE,         /* on: maps or pages kept across frames (the stale check compares them with a fresh draw) */
} sb_param_role;

/* What a technique is to the commands that choose among techniques. */
enum {
    SB_TRAIT_NO_SHADOWS = 1u << 0,  /* draws no shadow at all (none): the baseline; tune and the error bounds skip it */
    SB_TRAIT_EXACT = 1u << 1,       /* the exact reference itself (raycast): nothing to tune; held to a tighter bound */
    /* another renderer's shadows, read from files for the path's frames (score): nothing of it is timed here (it
       declares no stage), it has no frame between the path's (no flicker twin, no TAA), tune does not search it */
    SB_TRAIT_FOREIGN = 1u << 2,
};

/* One parameter: INT and ENUM values (the choice's index) go to an int field
 * at `offset` of the technique's parameter struct, FLOAT to a double, TEXT to a const char *. */
typedef struct sb_param_def {
    const char *name;
    sb_param_kind kind;
    const char *def;        /* default, as text */
    double min, max;        /* numeric range (inclusive) */
    const char *choices;    /* enums: "none|hw|pcf3" */
    const char *help;
    size_t offset;          /* in the parameter struct */
    size_t size;            /* of that field: sizeof(int) or sizeof(double) */
    bool can_auto;          /* FLOAT: "auto" is a value (chosen per run by calibration, autobias.h) */
    bool late;              /* added after series began: left out of the canonical text at its default, so the
                               run ids, params and series of before stay what they were */
    const char *tune;       /* the values `tune` searches by default ("512,1024,2048"; those a technique's range or
                               choices refuse are left out); NULL: tune keeps the default */
    sb_param_role role;
} sb_param_def;

/* Rows of a parameter table; T is the parameter struct, f its field (and the
 * parameter's name). What follows the help are more of the row's fields
 * (.tune = "...", .role = ...). */
#define SB_PARAM_ROW_(T, f, k, d, lo, hi, ch, h) \
    .name = #f, .kind = k, .def = #d, .min = lo, .max = hi, .choices = ch, .help = h, .offset = offsetof(T, f), \
    .size = sizeof(((T *)0)->f)
#define SB_PARAM_I(T, f, def, lo, hi, help, ...) {SB_PARAM_ROW_(T, f, SB_PARAM_INT, def, lo, hi, NULL, help), __VA_ARGS__}
#define SB_PARAM_F(T, f, def, lo, hi, help, ...) \
    {SB_PARAM_ROW_(T, f, SB_PARAM_FLOAT, def, lo, hi, NULL, help), __VA_ARGS__}
/* A FLOAT parameter that also takes "auto": the run calibrates it (bias, slope, normal offset). */
#define SB_PARAM_FA(T, f, def, lo, hi, help, ...) \
    {SB_PARAM_ROW_(T, f, SB_PARAM_FLOAT, def, lo, hi, NULL, help), .can_auto = true, __VA_ARGS__}
#define SB_PARAM_E(T, f, def, choices, help, ...) \
    {SB_PARAM_ROW_(T, f, SB_PARAM_ENUM, def, 0, 0, choices, help), __VA_ARGS__}
/* A TEXT parameter; def is a string literal. */
#define SB_PARAM_T(T, f, def_text, help_text, ...)                                                                 \
    {.name = #f, .kind = SB_PARAM_TEXT, .def = def_text, .help = help_text, .offset = offsetof(T, f),              \
     .size = sizeof(((T *)0)->f), __VA_ARGS__}
/* An ENUM added after series began (sb_param_def.late): written in the canonical text only when not its default. */
#define SB_PARAM_E_LATE(T, f, def, choices, help, ...) \
    {SB_PARAM_ROW_(T, f, SB_PARAM_ENUM, def, 0, 0, choices, help), .late = true, __VA_ARGS__}

#define SB_MAX_PARAMS 32
#define SB_PARAM_TEXT_MAX 512   /* characters of a TEXT value */
#define SB_PARAMS_TEXT_LEN 4096 /* a canonical parameter text's buffer (sb_params_canonical): every value fits */

/* Concrete values of one technique's parameters, in table order. */
typedef struct sb_params {
    int count;
    struct {
        const sb_param_def *def;
        double num;         /* INT/FLOAT value, or the enum's choice index (auto: the default) */
        char text[32];      /* canonical text (TEXT: str) */
        const char *str;    /* TEXT: the value (interned) */
        bool automatic;     /* "auto": calibrated per run before it is bound */
        bool given;         /* written in the spec, not a default */
    } v[SB_MAX_PARAMS];
} sb_params;

/* Parameter i's value as text (its canonical text; a TEXT parameter's whole value). */
static inline const char *sb_param_text(const sb_params *p, int i) {
    return p->v[i].def->kind == SB_PARAM_TEXT ? p->v[i].str : p->v[i].text;
}

/* "res=2048:filter=pcf3:..." in table order (a late parameter only when not at its default) */
void sb_params_canonical(const sb_params *p, char *out, size_t len);

/* A technique's stages (sb_technique.stages): SB_STAGES(&sb_stage_cascade, &sb_stage_final). */
#define SB_STAGES(...)                                                                                       \
    .stages = (const sb_stage_def *const[]){__VA_ARGS__},                                                      \
    .stage_count = (int)(sizeof((const sb_stage_def *const[]){__VA_ARGS__}) / sizeof(const sb_stage_def *))

enum { SB_LIGHTS_SUN, SB_LIGHTS_LAMPS, SB_LIGHTS_ANY, SB_LIGHTS_EVERY_LAMP };

struct sb_gpu;
struct sb_frame;
struct sb_run_ctx;

/* What a run's rows call it (sb_technique.label): interned or static strings. */
typedef struct sb_label {
    const char *technique, *params, *renderer;
} sb_label;

typedef struct sb_technique {
    const char *name;
    const char *summary;
    const sb_param_def *params;
    int param_count;
    size_t desc_size;               /* the parameter struct */
    const void *desc_defaults;      /* copied into it before the parameters (NULL: zeros) */
    /* the stages its frames time, each a row (stage.h): the shared machinery's or its own; SB_STAGES(...) */
    const sb_stage_def *const *stages;
    int stage_count;
    unsigned needs;                 /* SB_NEEDS_* */
    unsigned traits;                /* SB_TRAIT_* */
    /* what --lights may name for it: SB_LIGHTS_SUN (0: the sun alone, as before), SB_LIGHTS_LAMPS (point and spot
       lights, any number: a map set each), SB_LIGHTS_ANY (the sun and lamps), SB_LIGHTS_EVERY_LAMP (lamps, and
       without --lights every lamp of the scene: the atlas); a run naming another is skipped */
    unsigned lights;
    /* the cost model (batch's shards): a pixel's work beyond the final pass's, in units of one (raycast: a CPU ray
       a pixel, 20) */
    double pixel_cost;
    /* the settings the numerical-stability battery runs (stress): ";"-separated parameter texts, "" for the
       defaults ("" + ";stable=on": the defaults, then stable=on); NULL: not in the battery */
    const char *stress;
    /* how many earlier frames a frame with these parameters depends on (the
       evaluation pass renders them again before an evaluated frame); NULL: none */
    int (*history)(const void *desc);
    size_t state_size;
    bool (*check)(const void *desc, sb_err *err);
    /* (optional, no GL) what its rows call a run where that is not its name, its canonical parameters and the GL's
       renderer: another renderer's frames (score) are that renderer's, named by its parameters */
    void (*label)(const void *desc, sb_label *out);
    bool (*supported)(const struct sb_run_ctx *rc, const void *desc, sb_err *why);
    /* (optional, no GL) the shadow storage a run of these parameters holds resident, in bytes: maps in their
       formats, moments and their blur copies, cube faces and paraboloids. One estimate, read by the GPU-memory
       check (skipped before rendering when it does not fit), the summary's shadow_mb and tune --max-mb;
       NULL: none (the technique keeps no shadow map) */
    double (*shadow_bytes)(const struct sb_technique *t, const void *desc);
    bool (*load)(const struct sb_gpu *gpu, void **data, sb_err *err);
    void (*unload)(void *data);
    bool (*create)(void *state, const struct sb_run_ctx *rc, const void *desc, sb_err *err);
    void (*frame)(void *state, struct sb_frame *f);
    /* (optional) after an evaluated frame's targets are read back (w x h; aux: the normals target, 0 where nothing
       was drawn): its own check of the frame's input against the tool's geometry, the pixels it compared and those
       that disagree counted with the rays' geometry check. false: the input is refused with one line naming the
       file (bad input: the command exits 2) */
    bool (*check_frame)(void *state, int frame, int w, int h, const float *aux, long *samples, long *mismatches,
                        sb_err *err);
    /* (optional) its own counters, at most SB_MAX_OWN_COUNTERS: a frame column each, empty in every other
       technique's rows, summarised as each row says (sb_counter_def, stage.h); its frame counts them with
       sb_count(&f->counters, &ROW, v) and its warn hook reads them back with sb_counted */
    const sb_counter_def *counters;
    int counter_count;
    /* fills counters known only after the run (read back from the GPU once,
       outside the timed frames); seq is the frame's run sequence index */
    void (*collect)(void *state, int seq, sb_counters *out);
    /* (optional, no GL) after a run: what the technique cannot stand behind in its figures, read from the
       measured frames' counters (n of them); a line into out ("" : nothing), which the run's warnings column
       holds. The run loop knows no technique's counters: a technique with a warning of its own says it here */
    void (*warn)(const sb_counters *frames, int n, char *out, size_t len);
    void (*destroy)(void *state);
    const void *impl;               /* data of a shared implementation (a cascade technique's split scheme) */
} sb_technique;

const sb_technique *sb_technique_find(const char *name);
int sb_technique_count(void);
const sb_technique *sb_technique_at(int i);
int sb_technique_index(const sb_technique *t);
/* Checks one value against a parameter's definition; fills err on failure. */
bool sb_param_set(sb_params *p, int index, const sb_param_def *def, const char *value, const char *tech,
                  sb_err *err);
void sb_params_defaults(sb_params *p, const sb_technique *t);
/* The value of a parameter by name (tests); false if the technique has none. */
bool sb_params_find(const sb_params *p, const char *name, double *out);
/* The value of the parameter with a role; false if the technique has none. */
bool sb_params_role(const sb_params *p, sb_param_role role, double *out);
/* Every technique's parameters as markdown tables (`shadowbench techniques --format markdown`: the generated part
 * of docs/techniques.md, which a test holds to the tables). */
void sb_techniques_markdown(FILE *out);
/* Every declared stage, each once, in slot order (stage.h): the shared rows, each technique's own in the list's
 * order, the posing pass. A stage's slot is its place here (-1: declared by no technique); a technique's stage
 * mask has bit slot for each stage it declares. */
int sb_stage_count(void);
const sb_stage_def *sb_stage_at(int slot);
int sb_stage_slot(const sb_stage_def *def);
unsigned sb_technique_stage_mask(const sb_technique *t);
/* Whether a technique times a stage. */
bool sb_technique_times(const sb_technique *t, const sb_stage_def *def);
/* The first technique with a trait, or NULL. */
const sb_technique *sb_technique_with(unsigned trait);
/* The technique's parameter struct: its defaults, then every value at its offset. */
void sb_params_bind(const sb_params *p, const sb_technique *t, void *desc);

