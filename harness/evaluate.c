/* evaluate.c - a run's evaluation pass (evaluate.h). */
#include "evaluate.h"

#include <stdio.h>

#include "eval.h"
#include "frame_images.h"
#include "taa.h"

bool sb_evaluate_wanted(const sb_run_opts *o, int pf) {
    return (o->error_every > 0 && pf % o->error_every == 0) || (o->images > 0 && pf % o->images == 0);
}

int sb_evaluate_frames(const sb_run_opts *o) {
    int frames = 0;
    for (int pf = 0; pf < o->frames; pf++) frames += sb_evaluate_wanted(o, pf) ? 4 + sb_taa_frames(o) : 0;
    return frames;
}

bool sb_evaluate_run(sb_session *s, sb_instance *in, int seq, const char *out_dir, const char *run_id,
                     sb_frame_rec *recs, sb_err *err) {
    const sb_run_opts *o = &s->opts;
    const int n = o->frames;
    char dir[4200];
    snprintf(dir, sizeof dir, "%s/images", out_dir);
    if (o->images > 0 && !sb_mkdir_p(dir, err)) return false;
    sb_eval_buf b;
    sb_eval_buf_init(&b, &s->gpu, o->images > 0);
    sb_taa_buf *taa = NULL;   /* made by the first frame TAA resolves */
    bool ok = true;
    for (int pf = 0; ok && pf < n; pf++) {
        if (!sb_evaluate_wanted(o, pf)) continue;
        if (sb_interrupted()) {
            sb_fail(err, "interrupted by %s in the evaluation", sb_interrupt_name());
            ok = false;
            break;
        }
        sb_frame f;
        sb_frame_rec *r = &recs[pf];
        ok = sb_eval_frame(s, in, pf, n, sb_instance_history(in), &seq, &b, &f, &r->err, err) &&
             sb_eval_flicker(s, in, pf, n, &seq, &b, &f, &r->err, err) &&
             sb_eval_taa(s, in, pf, n, &seq, &taa, b.w, b.h, &r->err, err);
        if (ok && o->error_every > 0 && pf % o->error_every == 0) r->evaluated = true;
        if (ok && o->images > 0 && pf % o->images == 0)
            ok = sb_images_write_frame(dir, run_id, pf, b.w, b.h, b.rgba, b.vis, b.ref, b.pos, b.aux, err) &&
                 (!b.flicker_drawn || sb_images_write_flicker(dir, run_id, pf, b.w, b.h, b.flicker, err)) &&
                 (!b.flip_drawn ||
                  sb_images_write_shaded(dir, run_id, pf, b.w, b.h, b.shaded, b.shaded_ref, b.flip, err));
    }
    sb_eval_buf_free(&b);
    sb_taa_buf_free(taa);
    return ok;
}
