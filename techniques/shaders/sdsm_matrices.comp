// sdsm_matrices.comp - one invocation per cascade: the light frustum of the
// partition's slice (or, tight=on, of its samples plus a guard band), clipped
// to the scene, depth over the scene's extent toward the light. Empty
// partitions are flagged and render nothing.
layout(local_size_x = 8) in;
uniform mat4 u_light_view;
uniform vec3 u_eye;             // origin-relative camera position
uniform vec3 u_right, u_up, u_fwd;
uniform vec2 u_tan;             // tan of the half field of view: x, y
uniform vec3 u_scene_lo, u_scene_hi;   // scene bounds in light space
uniform int u_tight;
uniform float u_res;
uniform float u_guard;          // texels
void main() {
    int k = int(gl_LocalInvocationID.x);
    if (k >= int(sb_info.x)) return;
    if (sb_part_count[k] == 0u) { sb_flags[k] = vec4(0.0); return; }
    float zs[2] = float[](sb_cascade[k].x, sb_cascade[k].y);
    vec3 lo = vec3(3.0e38), hi = vec3(-3.0e38);
    for (int i = 0; i < 8; i++) {
        float z = zs[i / 4];
        vec3 c = u_eye + u_fwd * z + u_right * (((i & 1) != 0 ? 1.0 : -1.0) * u_tan.x * z)
                 + u_up * (((i & 2) != 0 ? 1.0 : -1.0) * u_tan.y * z);
        vec3 l = (u_light_view * vec4(c, 1.0)).xyz;
        lo = min(lo, l);
        hi = max(hi, l);
    }
    if (u_tight != 0) {
        lo.xy = max(lo.xy, vec2(sb_unorder(sb_bounds[k][0]), sb_unorder(sb_bounds[k][1])));
        hi.xy = min(hi.xy, vec2(sb_unorder(sb_bounds[k][2]), sb_unorder(sb_bounds[k][3])));
    }
    lo = max(lo, u_scene_lo);
    hi = min(hi, u_scene_hi);
    hi.xy = max(hi.xy, lo.xy + 1e-6);
    vec2 g = (hi.xy - lo.xy) / u_res * u_guard;
    lo.xy -= g;
    hi.xy += g;
    float zn = -u_scene_hi.z, zf = -max(lo.z, u_scene_lo.z);
    float pad = 1e-4 * (zf - zn) + 1e-6;
    zn -= pad;
    zf += pad;
    mat4 o = mat4(1.0);
    o[0][0] = 2.0 / (hi.x - lo.x);
    o[1][1] = 2.0 / (hi.y - lo.y);
    o[2][2] = -2.0 / (zf - zn);
    o[3][0] = -(hi.x + lo.x) / (hi.x - lo.x);
    o[3][1] = -(hi.y + lo.y) / (hi.y - lo.y);
    o[3][2] = -(zf + zn) / (zf - zn);
    mat4 vp = o * u_light_view;
    mat4 bias = mat4(0.5, 0.0, 0.0, 0.0, 0.0, 0.5, 0.0, 0.0, 0.0, 0.0, 0.5, 0.0, 0.5, 0.5, 0.5, 1.0);
    sb_light_vp[k] = vp;
    sb_shadow_mat[k] = bias * vp;
    sb_cascade[k].z = max(hi.x - lo.x, hi.y - lo.y) / u_res;
    sb_cascade[k].w = zf - zn;
    sb_flags[k] = vec4(1.0, 0.0, 0.0, 0.0);
}
