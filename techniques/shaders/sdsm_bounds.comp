// sdsm_bounds.comp - per partition: how many samples fall in it and, for
// tight=on, their light-space x/y bounds (the "second axis"). An invocation
// takes a run of SB_RUN pixels of a row, as sdsm_reduce.comp, and adds to
// the shared figures once per change of partition.
#define SB_RUN 8
layout(local_size_x = 8, local_size_y = 8) in;
uniform sampler2D u_depth;
uniform mat4 u_inv_view_proj;   // clip -> origin-relative world
uniform mat4 u_light_view;
shared uint s_count[8];
shared uint s_b[8][4];
void flush(int k, uint count, uvec4 b) {
    atomicAdd(s_count[k], count);
    atomicMin(s_b[k][0], b.x);
    atomicMin(s_b[k][1], b.y);
    atomicMax(s_b[k][2], b.z);
    atomicMax(s_b[k][3], b.w);
}
void main() {
    uint li = gl_LocalInvocationIndex;
    if (li < 8u) { s_count[li] = 0u; s_b[li][0] = 0xffffffffu; s_b[li][1] = 0xffffffffu; s_b[li][2] = 0u; s_b[li][3] = 0u; }
    barrier();
    ivec2 size = textureSize(u_depth, 0);
    ivec2 p0 = ivec2(gl_GlobalInvocationID.x * uint(SB_RUN), gl_GlobalInvocationID.y);
    int n = int(sb_info.x);
    int part = 0;
    uint count = 0u;
    uvec4 b = uvec4(0xffffffffu, 0xffffffffu, 0u, 0u);
    if (p0.y < size.y && n > 0) {
        for (int t = 0; t < SB_RUN; t++) {
            ivec2 p = ivec2(p0.x + t, p0.y);
            if (p.x >= size.x) break;
            float d = texelFetch(u_depth, p, 0).r;
            if (d < 1.0) {
                float z = sb_linear_depth(d);
                int k = n - 1;
                for (int i = 0; i < n; i++) if (z <= sb_cascade[i].y) { k = i; break; }
                vec4 ndc = vec4((vec2(p) + 0.5) / vec2(size) * 2.0 - 1.0, 2.0 * d - 1.0, 1.0);
                vec4 w = u_inv_view_proj * ndc;
                vec3 l = (u_light_view * vec4(w.xyz / w.w, 1.0)).xyz;
                if (count > 0u && k != part) {
                    flush(part, count, b);
                    count = 0u;
                    b = uvec4(0xffffffffu, 0xffffffffu, 0u, 0u);
                }
                part = k;
                count++;
                uvec2 o = uvec2(sb_order(l.x), sb_order(l.y));
                b = uvec4(min(b.xy, o), max(b.zw, o));
            }
        }
    }
    if (count > 0u) flush(part, count, b);
    barrier();
    if (li < 8u && s_count[li] > 0u) {
        atomicAdd(sb_part_count[li], s_count[li]);
        atomicMin(sb_bounds[li][0], s_b[li][0]);
        atomicMin(sb_bounds[li][1], s_b[li][1]);
        atomicMax(sb_bounds[li][2], s_b[li][2]);
        atomicMax(sb_bounds[li][3], s_b[li][3]);
    }
}
