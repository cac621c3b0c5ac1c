// vis_files.glsl - another renderer's visibility, read from its files (score): a pixel's own value.
uniform sampler2D u_files;
float sb_visibility(vec3 p, vec3 n, float view_z) {
    return texelFetch(u_files, ivec2(gl_FragCoord.xy), 0).r;
}
