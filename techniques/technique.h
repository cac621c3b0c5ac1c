/* technique.h - the one interface every shadow technique implements.
 *
 * A technique is a descriptor (sokol-style): a name, a parameter table with
 * types, defaults and valid ranges, the stages it has, what it needs from a
 * scene, and three functions. Whatever it does, its final pass writes one
 * screen-space visibility target (1 lit ... 0 shadowed) beside colour; the
 * error metrics and images read that. To add one: write techniques/NAME.c
 * with a `const sb_technique sb_technique_NAME`, list it in registry.c and
 * meson.build, and put its GLSL visibility function in techniques/shaders/. */
#pragma once
#include <stdbool.h>
#include <stddef.h>

#include "util.h"

typedef enum sb_stage {
    SB_STAGE_ZPASS,     /* camera depth pre-pass */
    SB_STAGE_MINMAX,    /* depth reduction */
    SB_STAGE_CASCADE,   /* all shadow-map rendering */
    SB_STAGE_FINAL,     /* camera pass with shadow lookup */
    SB_STAGE_VOLUMES,   /* stencil shadow volumes */
    SB_STAGE_RAYS,      /* CPU ray casting */
    SB_STAGE_COUNT
} sb_stage;

#define SB_STAGE_BIT(s) (1u << (s))
extern const char *const sb_stage_names[SB_STAGE_COUNT];

enum { SB_NEEDS_SUN = 1u << 0, SB_NEEDS_POINT_LIGHT = 1u << 1, SB_NEEDS_CLOSED = 1u << 2, SB_NEEDS_PLANE = 1u << 3 };

typedef enum sb_param_kind { SB_PARAM_INT, SB_PARAM_FLOAT, SB_PARAM_ENUM } sb_param_kind;

typedef struct sb_param_def {
    const char *name;
    sb_param_kind kind;
    const char *def;        /* default, as text */
    double min, max;        /* numeric range (inclusive) */
    const char *choices;    /* enums: "none|hw|pcf3" */
    const char *help;
} sb_param_def;

#define SB_MAX_PARAMS 24

/* Concrete values of one technique's parameters, in table order. */
typedef struct sb_params {
    int count;
    struct {
        const sb_param_def *def;
        double num;         /* INT/FLOAT value, or the enum's choice index */
        char text[32];      /* canonical text */
    } v[SB_MAX_PARAMS];
} sb_params;

double sb_param_num(const sb_params *p, const char *name);
int sb_param_choice(const sb_params *p, const char *name);
/* "res=2048:filter=pcf3:..." in table order */
void sb_params_canonical(const sb_params *p, char *out, size_t len);

struct sb_gpu;
struct sb_frame;
struct sb_counters;

typedef struct sb_technique {
    const char *name;
    const char *summary;
    const sb_param_def *params;
    int param_count;
    unsigned stages;        /* SB_STAGE_BIT()s it reports */
    unsigned needs;         /* SB_NEEDS_* */
    bool temporal;          /* a frame depends on earlier frames (re-rendered before an evaluated one) */
    size_t state_size;
    bool (*create)(void *state, struct sb_gpu *gpu, const sb_params *p, sb_err *err);
    void (*frame)(void *state, struct sb_frame *f);
    /* optional: fills counters known only after the run (read back from the
     * GPU once, outside the timed frames); seq is the frame's run sequence index */
    void (*collect)(void *state, int seq, struct sb_counters *out);
    void (*destroy)(void *state, struct sb_gpu *gpu);
} sb_technique;

const sb_technique *sb_technique_find(const char *name);
int sb_technique_count(void);
const sb_technique *sb_technique_at(int i);
/* Checks one value against a parameter's definition; fills err on failure. */
bool sb_param_set(sb_params *p, int index, const sb_param_def *def, const char *value, const char *tech,
                  sb_err *err);
void sb_params_defaults(sb_params *p, const sb_technique *t);
