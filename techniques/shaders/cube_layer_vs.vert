// cube_layer_vs.vert - layered cube pass without a geometry shader
// (ARB_shader_viewport_layer_array): instance k draws the triangle into face k.
layout(location = 0) in vec3 a_vertex;   // placed by sb_world (common.glsl): a_pos
uniform mat4 u_face_vp[6];
void main() {
    vec3 a_pos = sb_world(a_vertex);
    gl_Layer = gl_InstanceID;
    gl_Position = u_face_vp[gl_InstanceID] * vec4(a_pos, 1.0);
    SB_ALPHA_VS();
}
