// sdsm_splits.comp - partitions of [z_min, z_max] on the GPU: logarithmic, or
// from the histogram (splits spread over occupied log-depth only, so no split
// lands in an empty depth range). Same algorithm as sdsm_partition() in sdsm.c.
layout(local_size_x = 1) in;
uniform int u_count;
uniform int u_partition;    // 0 log, 1 histogram
uniform int u_hist_counts;  // 1: samples per partition from the histogram (conservative: a partition
                            // sharing a bin with samples counts as occupied); 0: sdsm_bounds.comp counts
void main() {
    sb_info = vec4(float(u_count), 0.0, 0.0, 0.0);
    for (int k = 0; k < 8; k++) { sb_flags[k] = vec4(0.0); sb_cascade[k] = vec4(0.0); }
    if (sb_samples == 0u) return;          // all sky: no cascades
    float zmin = sb_unorder(sb_zmin), zmax = max(sb_unorder(sb_zmax), sb_unorder(sb_zmin) * 1.0001);
    float s[9];
    s[0] = zmin;
    s[u_count] = zmax;
    float la = log(zmin), lb = log(zmax);
    for (int i = 1; i < u_count; i++) s[i] = exp(la + (lb - la) * float(i) / float(u_count));
    if (u_partition == 1) {
        float l0 = log(u_near), w = (log(u_far) - l0) / 64.0, total = 0.0;
        for (int b = 0; b < 64; b++)
            if (sb_hist[b] > 0u) total += max(min(l0 + float(b + 1) * w, lb) - max(l0 + float(b) * w, la), 0.0);
        if (total > 0.0) {
            for (int i = 1; i < u_count; i++) {
                float target = total * float(i) / float(u_count), acc = 0.0;
                for (int b = 0; b < 64; b++) {
                    if (sb_hist[b] == 0u) continue;
                    float lo = max(l0 + float(b) * w, la), len = max(min(l0 + float(b + 1) * w, lb) - lo, 0.0);
                    if (len > 0.0 && acc + len >= target) { s[i] = exp(lo + (target - acc)); break; }
                    acc += len;
                }
            }
        }
    }
    for (int k = 0; k < u_count; k++) sb_cascade[k] = vec4(s[k], s[k + 1], 0.0, 0.0);
    if (u_hist_counts == 0) return;
    for (int k = 0; k < u_count; k++) {
        uint n = 0u;
        int b0 = sb_hist_bin(s[k]), b1 = sb_hist_bin(s[k + 1]);
        for (int b = b0; b <= b1; b++) n += sb_hist[b];
        sb_part_count[k] = n;
    }
}
