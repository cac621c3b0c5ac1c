// cube_layer.geom - point-light shadows in one pass: each triangle goes to
// every cube face whose frustum it touches.
layout(triangles) in;
layout(triangle_strip, max_vertices = 18) out;
in vec3 g_pos[];
uniform mat4 u_face_vp[6];
void main() {
    for (int f = 0; f < 6; f++) {
        vec4 p0 = u_face_vp[f] * vec4(g_pos[0], 1.0);
        vec4 p1 = u_face_vp[f] * vec4(g_pos[1], 1.0);
        vec4 p2 = u_face_vp[f] * vec4(g_pos[2], 1.0);
        if (p0.x > p0.w && p1.x > p1.w && p2.x > p2.w) continue;
        if (p0.x < -p0.w && p1.x < -p1.w && p2.x < -p2.w) continue;
        if (p0.y > p0.w && p1.y > p1.w && p2.y > p2.w) continue;
        if (p0.y < -p0.w && p1.y < -p1.w && p2.y < -p2.w) continue;
        if (p0.w < 0.0 && p1.w < 0.0 && p2.w < 0.0) continue;
        gl_Layer = f; gl_Position = p0; SB_ALPHA_GS(0); EmitVertex();
        gl_Layer = f; gl_Position = p1; SB_ALPHA_GS(1); EmitVertex();
        gl_Layer = f; gl_Position = p2; SB_ALPHA_GS(2); EmitVertex();
        EndPrimitive();
    }
}
