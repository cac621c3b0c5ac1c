/* sweep.c - pairwise covering sets of a technique's enumerated parameters (see sweep.h).
 *
 * Greedy, deterministic: take the first pair of values no spec holds yet, set
 * it over the defaults, give every other parameter the value that covers the
 * most pairs still open with those already set (a tie keeps the default), and
 * ask the technique. A spec it refuses is repaired by moving one, then two,
 * other parameters off that choice; a pair no repair makes acceptable is
 * refused with the technique's reason. */
#include "sweep.h"

#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#define SW_VALUES 16
#define SW_SLOTS (SB_MAX_PARAMS * SW_VALUES)

typedef struct {
    const sb_param_def *def;
    int n, dflt;
    char vals[SW_VALUES][32];
} sw_axis;

typedef struct {
    const char *base;
    sw_axis ax[SB_MAX_PARAMS];
    int naxes;
    bool *pair;                 /* [slot a][slot b], a < b: held by an accepted spec, or refused */
    bool single[SW_SLOTS];
} sw_state;

static int slot(int axis, int value) { return axis * SW_VALUES + value; }
static bool *pair_at(sw_state *s, int i, int a, int j, int b) {
    int x = slot(i, a), y = slot(j, b);
    return x < y ? &s->pair[x * SW_SLOTS + y] : &s->pair[y * SW_SLOTS + x];
}

/* The spec text of a choice of values: the base, then each value that is not the default. */
static void spec_text(const sw_state *s, const int *v, char *out, size_t len) {
    snprintf(out, len, "%s", s->base);
    for (int i = 0; i < s->naxes; i++) {
        if (v[i] == s->ax[i].dflt) continue;
        size_t n = strlen(out);
        snprintf(out + n, len - n, ":%s=%s", s->ax[i].def->name, s->ax[i].vals[v[i]]);
    }
}

/* Does the technique accept it? why: its reason when not (may be NULL). */
static bool accepted(const sw_state *s, const int *v, char *why, size_t len) {
    char text[1024];
    spec_text(s, v, text, sizeof text);
    sb_run_spec *runs = NULL;
    int count = 0;
    sb_err e;
    bool ok = sb_spec_expand(text, NULL, &runs, &count, &e);
    free(runs);
    if (!ok && why) {
        const char *r = strstr(e.msg, ": ");   /* the check's own words, after the combination it names */
        snprintf(why, len, "%.*s", (int)len - 1, r ? r + 2 : e.msg);
    }
    return ok;
}

/* Pairs still open that value x of axis p would cover with the axes already set (set[q]). */
static int gain(sw_state *s, const int *v, const bool *set, int p, int x) {
    int g = !s->single[slot(p, x)];
    for (int q = 0; q < s->naxes; q++)
        if (q != p && set[q] && !*pair_at(s, p, x, q, v[q])) g++;
    return g;
}

/* Pairs still open that hold value x of axis p (a tie's breaker: the value the most pairs still wait for). */
static int open_pairs(sw_state *s, int p, int x) {
    int n = 0;
    for (int q = 0; q < s->naxes; q++)
        for (int y = 0; q != p && y < s->ax[q].n; y++) n += !*pair_at(s, p, x, q, y);
    return n;
}

/* Tries w with at most two other axes than i and j moved; true (w the accepted one) when one is accepted. */
static bool moved(const sw_state *s, int *w, int i, int j) {
    if (accepted(s, w, NULL, 0)) return true;
    for (int p = 0; p < s->naxes; p++) {
        if (p == i || p == j) continue;
        int keep = w[p];
        for (int x = 0; x < s->ax[p].n; x++) {
            if (x == keep) continue;
            w[p] = x;
            if (accepted(s, w, NULL, 0)) return true;
        }
        for (int x = 0; x < s->ax[p].n; x++) {
            w[p] = x;
            for (int q = p + 1; q < s->naxes; q++) {
                if (q == i || q == j) continue;
                int keep_q = w[q];
                for (int y = 0; y < s->ax[q].n; y++) {
                    if (y == keep_q) continue;
                    w[q] = y;
                    if (accepted(s, w, NULL, 0)) return true;
                }
                w[q] = keep_q;
            }
        }
        w[p] = keep;
    }
    return false;
}

/* Repairs v (axes i and j held): the greedy choice with one or two axes moved, else the defaults around the
 * pair with one or two moved. True when accepted (v the accepted spec). */
static bool repair(const sw_state *s, int *v, int i, int j) {
    int w[SB_MAX_PARAMS];
    memcpy(w, v, sizeof w);
    if (!moved(s, w, i, j)) {
        for (int p = 0; p < s->naxes; p++) w[p] = (p == i || p == j) ? v[p] : s->ax[p].dflt;
        if (!moved(s, w, i, j)) return false;
    }
    memcpy(v, w, sizeof w);
    return true;
}

/* How many of the pair's parameters a reason names. */
static int names(const sw_state *s, const char *why, int i, int j) {
    return (strstr(why, s->ax[i].def->name) != NULL) + (j >= 0 && strstr(why, s->ax[j].def->name) != NULL);
}

/* Why a pair is refused: the defaults around it, another axis moved while that makes the reason name more of the
 * pair (sdsm's stable=on with warp=lispsm: at the defaults the warp wants splits=cpu; with it, stable and the warp
 * are the reason). */
static void refusal(const sw_state *s, int *v, int i, int j, char *why, size_t len) {
    accepted(s, v, why, len);
    for (bool changed = true; changed && names(s, why, i, j) < (j >= 0 ? 2 : 1);) {
        changed = false;
        for (int p = 0; p < s->naxes && !changed; p++)
            for (int x = 0; x < s->ax[p].n && !changed && p != i && p != j; x++) {
                char other[400];
                int keep = v[p];
                v[p] = x;
                if (x != keep && !accepted(s, v, other, sizeof other) && names(s, other, i, j) > names(s, why, i, j)) {
                    snprintf(why, len, "%s", other);
                    changed = true;
                } else v[p] = keep;
            }
    }
}

#define SW_ORDERS 4

/* The k-th order of the axes: as declared, reversed, then shuffles of a fixed generator (the output is the same
 * every time). */
static void axis_order(int n, int k, int *order) {
    for (int p = 0; p < n; p++) order[p] = k == 1 ? n - 1 - p : p;
    uint32_t x = 2654435761u * (uint32_t)(k + 1);
    for (int p = n - 1; k >= 2 && p > 0; p--) {
        x = x * 1664525u + 1013904223u;
        int q = (int)((x >> 8) % (uint32_t)(p + 1)), t = order[p];
        order[p] = order[q], order[q] = t;
    }
}

/* The pair (or value) held, every other axis given in `order` the value that covers the most open pairs with
 * those given before it (a tie: the value the most pairs wait for, then the default). */
static void greedy(sw_state *s, const int *order, int i, int a, int j, int b, int *v) {
    bool set[SB_MAX_PARAMS] = {0};
    for (int p = 0; p < s->naxes; p++) v[p] = s->ax[p].dflt;
    v[i] = a, set[i] = true;
    if (j >= 0) v[j] = b, set[j] = true;
    for (int o = 0; o < s->naxes; o++) {
        int p = order[o];
        if (set[p]) continue;
        /* the value of the most gain among those the technique accepts with the axes given so far (the rest at
           their defaults); when it accepts none, the value of the most gain (a later axis may make it whole) */
        int best = -1, best_gain = -1, best_open = -1, any = s->ax[p].dflt, any_gain = -1, any_open = -1;
        for (int x = 0; x < s->ax[p].n; x++) {
            int g = gain(s, v, set, p, x), op = open_pairs(s, p, x);
            bool more = g > any_gain || (g == any_gain && op > any_open);
            if (more) any = x, any_gain = g, any_open = op;
            if (g < best_gain || (g == best_gain && op <= best_open)) continue;
            v[p] = x;
            if (accepted(s, v, NULL, 0)) best = x, best_gain = g, best_open = op;
        }
        v[p] = best >= 0 ? best : any, set[p] = true;
    }
}

/* Open pairs (and values) a spec would cover. */
static int new_pairs(sw_state *s, const int *v) {
    int n = 0;
    for (int p = 0; p < s->naxes; p++) {
        n += !s->single[slot(p, v[p])];
        for (int q = p + 1; q < s->naxes; q++) n += !*pair_at(s, p, v[p], q, v[q]);
    }
    return n;
}

/* v made acceptable by moving axes other than i and j, one at a time: an accepted move that covers the most open
 * pairs ends it; else the move that answers the spec's reason (the technique then names another, or none) and
 * keeps the most open pairs is taken, and the next reason asked, a few rounds at most. */
static bool best_move(sw_state *s, int *v, int i, int j) {
    char why[400], other[400];
    for (int round = 0; round < 6; round++) {
        if (accepted(s, v, why, sizeof why)) return true;
        int ap = -1, ax = 0, an = -1, rp = -1, rx = 0, rn = -1;
        for (int p = 0; p < s->naxes; p++) {
            if (p == i || p == j) continue;
            int keep = v[p];
            for (int x = 0; x < s->ax[p].n; x++) {
                if (x == keep) continue;
                v[p] = x;
                int n = new_pairs(s, v);
                if (accepted(s, v, other, sizeof other)) {
                    if (n > an) ap = p, ax = x, an = n;
                } else if (strcmp(other, why) && n > rn) {
                    rp = p, rx = x, rn = n;
                }
            }
            v[p] = keep;
        }
        if (ap >= 0) {
            v[ap] = ax;
            return true;
        }
        if (rp < 0) return false;
        v[rp] = rx;
    }
    return accepted(s, v, NULL, 0);
}

static void cover(sw_state *s, const int *v) {
    for (int p = 0; p < s->naxes; p++) {
        s->single[slot(p, v[p])] = true;
        for (int q = p + 1; q < s->naxes; q++) *pair_at(s, p, v[p], q, v[q]) = true;
    }
}

/* The first pair (or, with one axis, value) no spec holds: false when none is left. */
static bool open_target(sw_state *s, int *i, int *a, int *j, int *b) {
    for (int p = 0; p < s->naxes; p++)
        for (int x = 0; x < s->ax[p].n; x++) {
            for (int q = p + 1; q < s->naxes; q++)
                for (int y = 0; y < s->ax[q].n; y++)
                    if (!*pair_at(s, p, x, q, y)) {
                        *i = p, *a = x, *j = q, *b = y;
                        return true;
                    }
            if (!s->single[slot(p, x)]) {
                *i = p, *a = x, *j = -1, *b = 0;
                return true;
            }
        }
    return false;
}

static bool axes_of(sw_state *s, const sb_run_spec *rs, sb_err *err) {
    for (int k = 0; k < rs->params.count; k++) {
        const sb_param_def *d = rs->params.v[k].def;
        if (d->kind != SB_PARAM_ENUM || rs->params.v[k].given) continue;
        sw_axis *a = &s->ax[s->naxes++];
        a->def = d;
        char buf[512];
        snprintf(buf, sizeof buf, "%s", d->choices);
        char *save = NULL;
        for (char *t = strtok_r(buf, "|", &save); t; t = strtok_r(NULL, "|", &save)) {
            if (a->n == SW_VALUES) return sb_fail(err, "%s: %s has more than %d values", s->base, d->name, SW_VALUES);
            snprintf(a->vals[a->n], sizeof a->vals[0], "%s", t);
            if (!strcmp(t, d->def)) a->dflt = a->n;
            a->n++;
        }
    }
    return true;
}

static void push(char (**list)[1024], int *n, const char *text) {
    *list = sb_xrealloc(*list, sizeof **list * (size_t)(*n + 1));
    snprintf((*list)[(*n)++], sizeof **list, "%s", text);
}

bool sb_sweep_pairwise(const char *base, sb_sweep *out, sb_err *err) {
    memset(out, 0, sizeof *out);
    sb_run_spec *runs = NULL;
    int count = 0;
    if (!sb_spec_expand(base, NULL, &runs, &count, err)) return false;
    if (count != 1) {
        free(runs);
        return sb_fail(err, "--all-pairs %s: a base spec gives one value a parameter (it makes %d runs)", base, count);
    }
    sw_state *s = sb_xcalloc(1, sizeof *s);
    s->base = base;
    s->pair = sb_xcalloc((size_t)SW_SLOTS * SW_SLOTS, sizeof *s->pair);
    bool ok = axes_of(s, &runs[0], err);
    free(runs);
    int v[SB_MAX_PARAMS], i, a, j, b;
    for (int p = 0; p < s->naxes; p++) v[p] = s->ax[p].dflt;
    char text[1024];
    if (ok && (!s->naxes || accepted(s, v, NULL, 0))) {   /* the defaults first: the family's reference row */
        spec_text(s, v, text, sizeof text);
        push(&out->specs, &out->count, text);
        cover(s, v);
    }
    while (ok && open_target(s, &i, &a, &j, &b)) {
        /* candidates from several orders of the axes (the first value given decides the others' gains), each
           made acceptable; the one that covers the most open pairs is kept */
        int best_v[SB_MAX_PARAMS], best_new = -1;
        for (int k = 0; k < SW_ORDERS; k++) {
            int order[SB_MAX_PARAMS], c[SB_MAX_PARAMS];
            axis_order(s->naxes, k, order);
            greedy(s, order, i, a, j, b, c);
            if (!best_move(s, c, i, j) && !repair(s, c, i, j)) continue;
            int fresh = new_pairs(s, c);
            if (fresh > best_new) best_new = fresh, memcpy(best_v, c, sizeof c);
        }
        if (best_new >= 0) {
            memcpy(v, best_v, sizeof best_v);
            spec_text(s, v, text, sizeof text);
            push(&out->specs, &out->count, text);
            cover(s, v);
            continue;
        }
        for (int p = 0; p < s->naxes; p++) v[p] = s->ax[p].dflt;
        v[i] = a;
        if (j >= 0) v[j] = b;
        /* no accepted spec holds the pair: refused, with the reason of the defaults around it */
        char why[400];
        for (int p = 0; p < s->naxes; p++) v[p] = (p == i || p == j) ? v[p] : s->ax[p].dflt;
        refusal(s, v, i, j, why, sizeof why);
        out->refused = sb_xrealloc(out->refused, sizeof *out->refused * (size_t)(out->refused_count + 1));
        if (j >= 0)
            snprintf(out->refused[out->refused_count++], sizeof *out->refused, "%s=%s with %s=%s: %s",
                     s->ax[i].def->name, s->ax[i].vals[a], s->ax[j].def->name, s->ax[j].vals[b], why);
        else
            snprintf(out->refused[out->refused_count++], sizeof *out->refused, "%s=%s: %s", s->ax[i].def->name,
                     s->ax[i].vals[a], why);
        if (j >= 0) *pair_at(s, i, a, j, b) = true;
        else s->single[slot(i, a)] = true;
    }
    free(s->pair);
    free(s);
    if (!ok) sb_sweep_free(out);
    return ok;
}

void sb_sweep_free(sb_sweep *s) {
    free(s->specs);
    free(s->refused);
    memset(s, 0, sizeof *s);
}
