// final.frag - shared camera pass. The technique's GLSL, linked before this,
// defines sb_visibility(): 1 lit ... 0 shadowed. It is written, unshaded, to
// the visibility target that error metrics and images read.
in vec3 v_pos;
in vec3 v_nrm;
in float v_view_z;
uniform vec3 u_sun;
uniform vec4 u_color;
layout(location = 0) out vec4 o_color;
layout(location = 1) out float o_vis;
void main() {
    vec3 n = normalize(v_nrm);
    float ndl = dot(n, u_sun);
    float vis = sb_visibility(v_pos, n, v_view_z);
    o_vis = vis;
    o_color = vec4(u_color.rgb * (0.3 + 0.7 * max(ndl, 0.0) * vis), 1.0);
}
