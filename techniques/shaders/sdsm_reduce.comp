// sdsm_reduce.comp - min/max of visible view depth and a log-depth histogram
// (sky, depth 1, excluded). An invocation reduces a run of SB_RUN pixels of a
// row in registers (neighbours mostly share a histogram bin: one shared
// atomic a change of bin), its workgroup in shared memory, then one atomic
// each into the statistics.
#define SB_RUN 8
layout(local_size_x = 8, local_size_y = 8) in;
uniform sampler2D u_depth;
shared uint s_min, s_max, s_n;
shared uint s_hist[64];
void main() {
    uint li = gl_LocalInvocationIndex;
    if (li == 0u) { s_min = 0xffffffffu; s_max = 0u; s_n = 0u; }
    s_hist[li] = 0u;   // 64 invocations, 64 bins
    barrier();
    ivec2 size = textureSize(u_depth, 0);
    ivec2 p0 = ivec2(gl_GlobalInvocationID.x * uint(SB_RUN), gl_GlobalInvocationID.y);
    uint lo = 0xffffffffu, hi = 0u, n = 0u, run = 0u;
    int bin = 0;
    if (p0.y < size.y) {
        for (int t = 0; t < SB_RUN; t++) {
            if (p0.x + t >= size.x) break;
            float d = texelFetch(u_depth, ivec2(p0.x + t, p0.y), 0).r;
            if (d < 1.0) {
                float z = sb_linear_depth(d);
                uint o = sb_order(z);
                lo = min(lo, o);
                hi = max(hi, o);
                n++;
                int b = sb_hist_bin(z);
                if (run > 0u && b != bin) {
                    atomicAdd(s_hist[bin], run);
                    run = 0u;
                }
                bin = b;
                run++;
            }
        }
    }
    if (run > 0u) atomicAdd(s_hist[bin], run);
    if (n > 0u) {
        atomicMin(s_min, lo);
        atomicMax(s_max, hi);
        atomicAdd(s_n, n);
    }
    barrier();
    if (li == 0u && s_n > 0u) {
        atomicMin(sb_zmin, s_min);
        atomicMax(sb_zmax, s_max);
        atomicAdd(sb_samples, s_n);
    }
    if (s_hist[li] > 0u) atomicAdd(sb_hist[li], s_hist[li]);
}
