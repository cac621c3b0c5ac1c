// planar.vert - casters flattened onto a receiver plane along the light
// (Blinn 1988). v_side is the original vertex's signed distance to the plane:
// geometry under the plane would cast an "anti-shadow" and is discarded.
layout(location = 0) in vec3 a_vertex;   // placed by sb_world (common.glsl): a_pos
uniform mat4 u_view;
uniform mat4 u_proj;
uniform mat4 u_flatten;     // projection onto the plane along the light
uniform vec4 u_plane;       // n, d (origin-relative)
out float v_side;
void main() {
    vec3 a_pos = sb_world(a_vertex);
    SB_ALPHA_VS();
    v_side = dot(u_plane.xyz, a_pos) + u_plane.w;
    gl_Position = u_proj * (u_view * (u_flatten * vec4(a_pos, 1.0)));
}
