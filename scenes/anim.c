/* anim.c - glTF animation samplers (see anim.h). */
#include "anim.h"

#include <string.h>

static size_t key_after(const sb_anim_sampler *s, double t) {
    size_t lo = 0, hi = s->keys; /* first key with in > t */
    while (lo < hi) {
        size_t mid = lo + (hi - lo) / 2;
        if (s->in[mid] <= t) lo = mid + 1;
        else hi = mid;
    }
    return lo;
}

/* The value (not a tangent) of key k. */
static const double *value(const sb_anim_sampler *s, size_t k) {
    return s->out + (s->interp == SB_INTERP_CUBIC ? (3 * k + 1) : k) * (size_t)s->ncomp;
}

static void normalise_rotation(const sb_anim_sampler *s, double *out) {
    if (!s->rotation) return;
    sb_quat q = sb_quat_norm((sb_quat){out[0], out[1], out[2], out[3]});
    out[0] = q.x, out[1] = q.y, out[2] = q.z, out[3] = q.w;
}

void sb_anim_sample(const sb_anim_sampler *s, double t, double *out) {
    const int n = s->ncomp;
    size_t i = key_after(s, t);
    if (i == 0 || i >= s->keys || s->interp == SB_INTERP_STEP) {
        memcpy(out, value(s, i == 0 ? 0 : i - 1), sizeof(double) * (size_t)n);
        normalise_rotation(s, out);
        return;
    }
    double t0 = s->in[i - 1], dt = s->in[i] - t0, u = (t - t0) / dt;
    const double *a = value(s, i - 1), *b = value(s, i);
    if (s->interp == SB_INTERP_CUBIC) { /* Hermite spline: value, out-tangent of a; in-tangent, value of b */
        const double *ta = s->out + (3 * (i - 1) + 2) * (size_t)n, *tb = s->out + (3 * i) * (size_t)n;
        double u2 = u * u, u3 = u2 * u;
        for (int k = 0; k < n; k++)
            out[k] = (2 * u3 - 3 * u2 + 1) * a[k] + (u3 - 2 * u2 + u) * dt * ta[k] + (-2 * u3 + 3 * u2) * b[k] +
                     (u3 - u2) * dt * tb[k];
        normalise_rotation(s, out);
        return;
    }
    if (s->rotation) {
        sb_quat q = sb_quat_slerp(sb_quat_norm((sb_quat){a[0], a[1], a[2], a[3]}),
                                  sb_quat_norm((sb_quat){b[0], b[1], b[2], b[3]}), u);
        out[0] = q.x, out[1] = q.y, out[2] = q.z, out[3] = q.w;
        return;
    }
    for (int k = 0; k < n; k++) out[k] = a[k] * (1 - u) + b[k] * u;
}

sb_m4 sb_trs_matrix(const sb_trs *x) {
    /* T * R * S written out: the rotation's columns scaled, the translation the last column (the same numbers as the
       products: their other terms are exact zeros and ones) */
    sb_m4 m = sb_quat_to_m4(sb_quat_norm((sb_quat){x->r[0], x->r[1], x->r[2], x->r[3]}));
    for (int c = 0; c < 3; c++)
        for (int row = 0; row < 3; row++) m.m[c * 4 + row] *= x->s[c];
    m.m[12] = x->t[0], m.m[13] = x->t[1], m.m[14] = x->t[2];
    return m;
}
