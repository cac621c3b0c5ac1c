// sdsm_reduce.comp - min/max of visible view depth and a log-depth histogram
// (sky, depth 1, excluded). Workgroup reduction in shared memory, then atomics.
layout(local_size_x = 16, local_size_y = 16) in;
uniform sampler2D u_depth;
shared uint s_min, s_max, s_n;
shared uint s_hist[64];
void main() {
    uint li = gl_LocalInvocationIndex;
    if (li == 0u) { s_min = 0xffffffffu; s_max = 0u; s_n = 0u; }
    if (li < 64u) s_hist[li] = 0u;
    barrier();
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (all(lessThan(p, textureSize(u_depth, 0)))) {
        float d = texelFetch(u_depth, p, 0).r;
        if (d < 1.0) {
            float z = sb_linear_depth(d);
            uint o = sb_order(z);
            atomicMin(s_min, o);
            atomicMax(s_max, o);
            atomicAdd(s_n, 1u);
            atomicAdd(s_hist[sb_hist_bin(z)], 1u);
        }
    }
    barrier();
    if (li == 0u && s_n > 0u) {
        atomicMin(sb_zmin, s_min);
        atomicMax(sb_zmax, s_max);
        atomicAdd(sb_samples, s_n);
    }
    if (li < 64u && s_hist[li] > 0u) atomicAdd(sb_hist[li], s_hist[li]);
}
