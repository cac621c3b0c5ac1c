// virtual_depth.vert - one page of a virtual shadow map: the page's orthographic view (with its border) into
// its slot of the atlas (the viewport).
layout(location = 0) in vec3 a_vertex;   // placed by sb_world (common.glsl): a_pos
uniform mat4 u_vp;
void main() {
    vec3 a_pos = sb_world(a_vertex);
    SB_ALPHA_VS();
    gl_Position = u_vp * vec4(a_pos, 1.0);
}
