// dpsm.vert - dual-paraboloid shadow maps (Brabec et al. 2002): the
// hemisphere around u_axis (u_side +1) or against it (-1) is projected onto a
// paraboloid; depth is the distance to the lamp, linear in [near, far].
layout(location = 0) in vec3 a_vertex;   // placed by sb_world (common.glsl): a_pos
uniform vec3 u_lamp;
uniform mat3 u_frame;       // world -> lamp frame, +z along the front hemisphere's axis
uniform float u_side;       // +1 front map, -1 back map
uniform float u_near, u_far;
void main() {
    vec3 a_pos = sb_world(a_vertex);
    SB_ALPHA_VS();
    vec3 v = u_frame * (a_pos - u_lamp);
    v.z *= u_side;
    float len = length(v);
    vec3 d = v / max(len, 1e-20);
    gl_ClipDistance[0] = d.z;                       // only this hemisphere
    gl_Position = vec4(d.xy / (1.0 + d.z), 2.0 * (len - u_near) / (u_far - u_near) - 1.0, 1.0);
}
