// volume.vert - shadow-volume geometry: w = 1 on the caster, w = 0 extruded
// to infinity away from the light (kept by depth clamping).
layout(location = 0) in vec4 a_pos;
uniform mat4 u_view;
uniform mat4 u_proj;
void main() { gl_Position = u_proj * (u_view * a_pos); }
