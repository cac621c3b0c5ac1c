// vis_raycast.glsl - ray-cast shadows: visibility computed on the CPU per pixel.
uniform sampler2D u_rays;
float sb_visibility(vec3 p, vec3 n, float view_z) {
    return texelFetch(u_rays, ivec2(gl_FragCoord.xy), 0).r;
}
