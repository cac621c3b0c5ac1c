// sdsm_bounds.comp - per partition: how many samples fall in it and, for
// tight=on, their light-space x/y bounds (the "second axis").
layout(local_size_x = 16, local_size_y = 16) in;
uniform sampler2D u_depth;
uniform mat4 u_inv_view_proj;   // clip -> origin-relative world
uniform mat4 u_light_view;
shared uint s_count[8];
shared uint s_b[8][4];
void main() {
    uint li = gl_LocalInvocationIndex;
    if (li < 8u) { s_count[li] = 0u; s_b[li][0] = 0xffffffffu; s_b[li][1] = 0xffffffffu; s_b[li][2] = 0u; s_b[li][3] = 0u; }
    barrier();
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    ivec2 size = textureSize(u_depth, 0);
    int n = int(sb_info.x);
    if (all(lessThan(p, size)) && n > 0) {
        float d = texelFetch(u_depth, p, 0).r;
        if (d < 1.0) {
            float z = sb_linear_depth(d);
            int k = n - 1;
            for (int i = 0; i < n; i++) if (z <= sb_cascade[i].y) { k = i; break; }
            vec4 ndc = vec4((vec2(p) + 0.5) / vec2(size) * 2.0 - 1.0, 2.0 * d - 1.0, 1.0);
            vec4 w = u_inv_view_proj * ndc;
            vec3 l = (u_light_view * vec4(w.xyz / w.w, 1.0)).xyz;
            atomicAdd(s_count[k], 1u);
            atomicMin(s_b[k][0], sb_order(l.x));
            atomicMin(s_b[k][1], sb_order(l.y));
            atomicMax(s_b[k][2], sb_order(l.x));
            atomicMax(s_b[k][3], sb_order(l.y));
        }
    }
    barrier();
    if (li < 8u && s_count[li] > 0u) {
        atomicAdd(sb_part_count[li], s_count[li]);
        atomicMin(sb_bounds[li][0], s_b[li][0]);
        atomicMin(sb_bounds[li][1], s_b[li][1]);
        atomicMax(sb_bounds[li][2], s_b[li][2]);
        atomicMax(sb_bounds[li][3], s_b[li][3]);
    }
}
