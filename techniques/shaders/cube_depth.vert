// cube_depth.vert - one cube face per draw.
layout(location = 0) in vec3 a_vertex;   // placed by sb_world (common.glsl): a_pos
uniform mat4 u_vp;
void main() {
    vec3 a_pos = sb_world(a_vertex);
    gl_Position = u_vp * vec4(a_pos, 1.0);
    SB_ALPHA_VS();
}
