// scene.vert - camera pass (and the z-pass, which must produce the same depth:
// gl_Position is invariant). Positions are relative to the scene origin.
layout(location = 0) in vec3 a_vertex;   // placed by sb_world (common.glsl): a_pos
layout(location = 1) in vec3 a_nrm;
layout(location = 4) in vec4 a_color;   // the draw's colour: per draw, read at its baseInstance (render.c)
uniform mat4 u_view;
uniform mat4 u_proj;
out vec3 v_pos;
out vec3 v_nrm;
out float v_view_z;
flat out vec4 v_color;
#ifdef SB_EVAL
// the view the shadow lookup's depth is taken in: u_view, except in the
// flicker twin's lookup, where the evaluated frame's points are drawn through
// its camera (u_view) and looked up as the twin would (its view)
uniform mat4 u_depth_view;
#endif
invariant gl_Position;
void main() {
    vec3 a_pos = sb_world(a_vertex);
    vec4 vp = u_view * vec4(a_pos, 1.0);
    v_pos = a_pos;
    v_nrm = sb_world_dir(a_nrm);   // a similarity's scale: final.frag normalizes
    v_color = a_color;
#ifdef SB_EVAL
    v_view_z = -(u_depth_view * vec4(a_pos, 1.0)).z;
#else
    v_view_z = -vp.z;
#endif
    gl_Position = u_proj * vp;
    SB_ALPHA_VS();
}
