/* autobias.c - per-run calibration of "auto" offsets (see autobias.h). */
#include "autobias.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "eval.h"

bool sb_autobias_wanted(const sb_run_spec *spec) {
    for (int i = 0; i < spec->params.count; i++)
        if (spec->params.v[i].automatic) return true;
    return false;
}

/* The frames to calibrate on: the run's evaluated ones (every error_every-th),
 * or when it evaluates none, frames spread along the path; at most
 * SB_AUTO_FRAMES of them, spread evenly. Returns how many. */
static int calib_frames(const sb_run_opts *o, int out[SB_AUTO_FRAMES]) {
    int n = o->frames, every = o->error_every > 0 ? o->error_every : 1;
    int cand = (n - 1) / every + 1;
    if (o->error_every <= 0) cand = n;
    int k = cand < SB_AUTO_FRAMES ? cand : SB_AUTO_FRAMES;
    for (int i = 0; i < k; i++) {
        int c = k == 1 ? 0 : (int)lround((double)i * (cand - 1) / (k - 1));
        out[i] = o->error_every > 0 ? c * every : c;
    }
    return k;
}

typedef struct {
    double false_shadow, err_rate;   /* means over the calibration frames, as the summary's _mean columns */
} calib_score;

/* Renders the calibration frames with params p and scores them. */
static bool score(sb_session *s, const sb_run_spec *spec, const sb_params *p, const int *frames, int nf,
                  calib_score *out, sb_err *err) {
    sb_run_spec rs = {.tech = spec->tech, .params = *p};
    sb_spec_bind(&rs);
    sb_instance in;
    if (!sb_instance_create(&in, s, &rs, nf, err)) return false;   /* frames: what it keeps per frame (sdsm's splits) */
    int replay = sb_instance_history(&in);
    sb_eval_buf b;
    sb_eval_buf_init(&b, &s->gpu, false);
    double fs = 0, er = 0;
    int counted = 0;
    int seq = 0;
    bool ok = true;
    for (int i = 0; ok && i < nf; i++) {
        sb_frame f;
        sb_error_metrics m;
        ok = sb_eval_frame(s, &in, frames[i], s->opts.frames, replay, &seq, &b, &f, &m, err);
        if (ok && m.pixels > 0) {
            fs += m.false_shadow;
            er += m.err_rate;
            counted++;
        }
    }
    sb_eval_buf_free(&b);
    sb_instance_destroy(&in);
    out->false_shadow = counted ? fs / counted : 0;
    out->err_rate = counted ? er / counted : 0;
    return ok;
}

static void set_value(sb_params *p, int i, double v) {
    const sb_param_def *d = p->v[i].def;
    v = fmin(fmax(v, d->min), d->max);
    p->v[i].num = v;
    p->v[i].automatic = false;
    snprintf(p->v[i].text, sizeof p->v[i].text, "%.10g", v);
}

static const double ladder[] = SB_AUTO_LADDER;
enum { LADDER = (int)(sizeof ladder / sizeof ladder[0]), MAX_AUTO = 3, MAX_TRIED = 128 };

/* The search: candidates are rungs of the ladder per auto parameter, each
 * scored once (memo). */
typedef struct {
    sb_session *s;
    const sb_run_spec *spec;
    int autos[MAX_AUTO], na, frames[SB_AUTO_FRAMES], nf;
    double def[MAX_AUTO];
    int rungs[MAX_TRIED][MAX_AUTO];
    calib_score sc[MAX_TRIED];
    int tried;
} search;

static void params_at(const search *x, const int *rung, sb_params *p) {
    *p = x->spec->params;
    for (int a = 0; a < x->na; a++) set_value(p, x->autos[a], x->def[a] * ladder[rung[a]]);
}

/* The score of a candidate: its index among the tried, or -1 (err) when its evaluation failed or none is left. */
static int try_rungs(search *x, const int *rung, sb_err *err) {
    for (int t = 0; t < x->tried; t++)
        if (!memcmp(x->rungs[t], rung, sizeof(int) * (size_t)x->na)) return t;
    if (x->tried == MAX_TRIED) return sb_fail(err, "more than %d candidates", MAX_TRIED), -1;
    sb_params p;
    params_at(x, rung, &p);
    int t = x->tried;
    if (!score(x->s, x->spec, &p, x->frames, x->nf, &x->sc[t], err)) return -1;
    memcpy(x->rungs[t], rung, sizeof(int) * (size_t)x->na);
    x->tried++;
    return t;
}

/* Better: acceptable acne, then the lower err_rate, then smaller offsets. */
static bool better(const search *x, int a, int b, double limit) {
    bool oka = x->sc[a].false_shadow <= limit, okb = x->sc[b].false_shadow <= limit;
    if (oka != okb) return oka;
    if (!oka) return x->sc[a].false_shadow < x->sc[b].false_shadow;
    if (x->sc[a].err_rate != x->sc[b].err_rate) return x->sc[a].err_rate < x->sc[b].err_rate;
    int sa = 0, sb = 0;
    for (int k = 0; k < x->na; k++) sa += x->rungs[a][k], sb += x->rungs[b][k];
    return sa < sb;
}

bool sb_autobias_choose(sb_session *s, const sb_run_spec *spec, sb_run_spec *out, char *chosen, size_t len, int *tried,
                        sb_err *err) {
    search x = {.s = s, .spec = spec};
    for (int i = 0; i < spec->params.count && x.na < MAX_AUTO; i++)
        if (spec->params.v[i].automatic) {
            x.def[x.na] = spec->params.v[i].num;  /* "auto" holds the table's default */
            x.autos[x.na++] = i;
        }
    x.nf = calib_frames(&s->opts, x.frames);
    *out = *spec;
    chosen[0] = 0;
    if (tried) *tried = 0;
    if (!x.na) return true;
    /* Joint: every auto parameter on the same rung; the least acne sets the limit. */
    double least = INFINITY;
    int best = -1;
    for (int k = 0; k < LADDER; k++) {
        int rung[MAX_AUTO] = {k, k, k};
        int t = try_rungs(&x, rung, err);
        if (t < 0) return false;
        least = fmin(least, x.sc[t].false_shadow);
    }
    double limit = SB_AUTO_REL * least + SB_AUTO_ABS;
    for (int t = 0; t < x.tried; t++)
        if (best < 0 || better(&x, t, best, limit)) best = t;
    /* Then from the best so far: each parameter along the whole ladder with
     * the others held, and each pair a rung up or down together (the
     * valleys run diagonally: less normal offset wants more slope); moving
     * to the best of those while that lowers err_rate. Every candidate is
     * scored once. */
    for (int cur = -1; x.na > 1 && cur != best;) {
        cur = best;
        int rung[MAX_AUTO];
        for (int a = 0; a < x.na; a++)
            for (int k = 0; k < LADDER; k++) {
                memcpy(rung, x.rungs[cur], sizeof rung);
                rung[a] = k;
                int t = try_rungs(&x, rung, err);
                if (t < 0) return false;
                if (better(&x, t, best, limit)) best = t;
            }
        for (int a = 0; a < x.na; a++)
            for (int b = a + 1; b < x.na; b++)
                for (int d = 0; d < 4; d++) {
                    memcpy(rung, x.rungs[cur], sizeof rung);
                    rung[a] += d & 1 ? 1 : -1;
                    rung[b] += d & 2 ? 1 : -1;
                    if (rung[a] < 0 || rung[a] >= LADDER || rung[b] < 0 || rung[b] >= LADDER) continue;
                    int t = try_rungs(&x, rung, err);
                    if (t < 0) return false;
                    if (better(&x, t, best, limit)) best = t;
                }
    }
    params_at(&x, x.rungs[best], &out->params);
    sb_spec_bind(out);
    size_t n = 0;
    for (int a = 0; a < x.na; a++) {
        if (n < len)
            n += (size_t)snprintf(chosen + n, len - n, "%s%s=%s", a ? ":" : "", out->params.v[x.autos[a]].def->name,
                                  out->params.v[x.autos[a]].text);
    }
    if (tried) *tried = x.tried;
    sb_log("%s: auto offsets %s: %d candidates on %d frame(s); false shadow %.5f (limit %.5f, least %.5f), "
           "%s %.5f", spec->tech->name, chosen, x.tried, x.nf, x.sc[best].false_shadow, limit, least,
           sb_columns_role(SB_ROLE_ERROR), x.sc[best].err_rate);
    return true;
}
