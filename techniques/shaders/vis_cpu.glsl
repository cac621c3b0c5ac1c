// vis_cpu.glsl - a visibility made on the CPU (raycast's rays, score's files): the pixel's own texel
// (sb_cpu_vis_texture, render.h; a sampler's unit is 0 unless set).
uniform sampler2D u_vis_cpu;
float sb_visibility(vec3 p, vec3 n, float view_z) {
    return texelFetch(u_vis_cpu, ivec2(gl_FragCoord.xy), 0).r;
}
