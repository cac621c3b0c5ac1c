/* eval.c - one evaluated frame (see eval.h). */
#include "eval.h"

#include <stdlib.h>
#include <string.h>

void sb_eval_buf_init(sb_eval_buf *b, const sb_gpu *g, bool rgba) {
    memset(b, 0, sizeof *b);
    b->w = g->width;
    b->h = g->height;
    size_t n = (size_t)b->w * b->h;
    b->vis = sb_xmalloc(n);
    b->ref = sb_xmalloc(n);
    b->rgba = rgba ? sb_xmalloc(4 * n) : NULL;
    b->pos = sb_xmalloc(sizeof(float) * 4 * n);
    b->aux = sb_xmalloc(sizeof(float) * 4 * n);
}

void sb_eval_buf_free(sb_eval_buf *b) {
    free(b->vis);
    free(b->ref);
    free(b->rgba);
    free(b->pos);
    free(b->aux);
    memset(b, 0, sizeof *b);
}

bool sb_eval_frame(sb_session *s, sb_instance *in, int pf, int n, int replay, int *seq, sb_eval_buf *b, sb_frame *f,
                   sb_error_metrics *m, sb_err *err) {
    const sb_reference *ref = sb_session_reference(s, err);
    if (!ref) return false;
    sb_timer timer;
    sb_timer_init(&timer, SB_TIMING_SYNC, 1, 1);
    for (int k = replay; k >= 0; k--) {
        if (pf - k < 0) continue;
        memset(f, 0, sizeof *f);
        sb_timer_frame_begin(&timer, 0);
        sb_camera cam = sb_path_camera(&s->path, pf - k, n, (double)s->opts.width / s->opts.height, &s->scene);
        f->index = pf - k;
        f->progress = sb_path_progress(pf - k, n);
        sb_render_camera(s, in, f, &cam, (*seq)++, &timer, k == 0);
    }
    sb_timer_free(&timer);
    if (in->tech->collect) in->tech->collect(in->state, f->seq, &f->counters);
    sb_gpu_readback(&s->gpu, NULL, b->vis, b->rgba);
    sb_gpu_readback_eval(&s->gpu, b->pos, b->aux);
    sb_m4 inv;
    bool have_inv = sb_m4_invert(f->view_proj, &inv);
    sb_eval_view view = {b->w, b->h, b->pos, b->aux, sb_v3_sub(f->cam.pos, s->scene.origin), have_inv ? &inv : NULL,
                         f->shade_light};
    sb_evaluate_frame(ref, s->ref_cache, &view, b->vis, b->ref, m, s->opts.threads);
    return sb_gl_check("evaluation pass", err);
}
