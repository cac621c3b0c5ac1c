// pose.comp - the GPU's posing pass (techniques/pose.c): every moving vertex the GPU poses, from its rest data
// (scenes/motion.h, sb_pose_data), written into the scene's vertex buffer where the passes read it. One
// invocation a vertex: its placement's morph targets at their weights, then its joints' matrices weighted (a
// rigid placement: its node's matrix), the normal by the inverse transpose, as the CPU poses it
// (scenes/motion.cc) in double precision: the two agree within float rounding (tests/integration/test_motion.c).
layout(local_size_x = 64) in;
struct SbPosePlace {
    uint first, count, rest_first, palette_first, joints, morph_first, targets, weights_first;
};
struct SbRest {
    vec4 pos;       // xyz; w: its placement (uint bits)
    vec4 nrm;
    uvec4 j0, j1;   // joints of the two skin sets
    vec4 w0, w1;    // and their weights
};
layout(std430, binding = 8) readonly buffer SbPosePlaces { SbPosePlace sb_places[]; };
layout(std430, binding = 9) readonly buffer SbRests { SbRest sb_rest[]; };
layout(std430, binding = 10) readonly buffer SbMorphs { vec4 sb_morph[]; };      // delta pos, delta normal
layout(std430, binding = 11) readonly buffer SbPalette { mat4 sb_palette[]; };   // relative to the origin
layout(std430, binding = 12) readonly buffer SbWeights { float sb_weights[]; };
layout(std430, binding = 13) writeonly buffer SbVertices { float sb_vertices[]; };
uniform uint u_row0;         // the first row of the bound range of rest this dispatch poses
uniform uint u_rows;         // and the end of its rows
uniform uint u_rest_base;    // the row the bound range of rest starts at
uniform uint u_vertex_base;  // the float the bound range of the vertex buffer starts at
uniform vec3 u_origin;       // the scene's origin (a vertex no joint weighs lies at the world's 0)
const uint SB_VERTEX_FLOATS = 9u;

void main() {
    uint r = gl_GlobalInvocationID.x + u_row0;
    if (r >= u_rows) return;
    SbRest rv = sb_rest[r];
    SbPosePlace p = sb_places[floatBitsToUint(rv.pos.w)];
    uint v = r + u_rest_base - p.rest_first;
    vec3 pos = rv.pos.xyz, nrm = rv.nrm.xyz;
    for (uint t = 0u; t < p.targets; t++) {
        float w = sb_weights[p.weights_first + t];
        if (w == 0.0) continue;
        uint m = 2u * (p.morph_first + t * p.count + v);
        pos += w * sb_morph[m].xyz;
        nrm += w * sb_morph[m + 1u].xyz;
    }
    mat4 M;
    if (p.joints == 0u) {
        M = sb_palette[p.palette_first];
    } else {
        M = mat4(0.0);
        for (int c = 0; c < 4; c++)
            if (rv.w0[c] != 0.0 && rv.j0[c] < p.joints) M += rv.w0[c] * sb_palette[p.palette_first + rv.j0[c]];
        for (int c = 0; c < 4; c++)
            if (rv.w1[c] != 0.0 && rv.j1[c] < p.joints) M += rv.w1[c] * sb_palette[p.palette_first + rv.j1[c]];
    }
    vec4 h = M * vec4(pos, 1.0);   // h.w: the weights' sum, which the CPU divides by where it is not 0 or 1
    vec3 q = h.w == 0.0 ? -u_origin : h.w == 1.0 ? h.xyz : h.xyz / h.w;
    mat3 A = mat3(M);
    vec3 n = determinant(A) != 0.0 ? transpose(inverse(A)) * nrm : nrm;
    float len = length(n);
    if (len > 0.0) n /= len;
    uint o = (p.first + v) * SB_VERTEX_FLOATS - u_vertex_base;
    sb_vertices[o] = q.x;
    sb_vertices[o + 1u] = q.y;
    sb_vertices[o + 2u] = q.z;
    sb_vertices[o + 3u] = n.x;
    sb_vertices[o + 4u] = n.y;
    sb_vertices[o + 5u] = n.z;
}
