// scene.vert - camera pass (and the z-pass, which must produce the same depth:
// gl_Position is invariant). Positions are relative to the scene origin.
layout(location = 0) in vec3 a_pos;
layout(location = 1) in vec3 a_nrm;
uniform mat4 u_view;
uniform mat4 u_proj;
out vec3 v_pos;
out vec3 v_nrm;
out float v_view_z;
invariant gl_Position;
void main() {
    vec4 vp = u_view * vec4(a_pos, 1.0);
    v_pos = a_pos;
    v_nrm = a_nrm;
    v_view_z = -vp.z;
    gl_Position = u_proj * vp;
    SB_ALPHA_VS();
}
