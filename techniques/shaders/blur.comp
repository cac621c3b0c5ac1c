// blur.comp - one direction of the separable Gaussian over one layer of a
// moments map (defines: SB_BLUR_RADIUS, the radius in texels, and
// SB_IMAGE_FORMAT, the map's format). An invocation writes SB_RUN texels in a
// row along the direction from one window of SB_RUN + 2r loads, instead of
// 2r + 1 loads for each texel.
#define SB_RUN 8
layout(local_size_x = 64, local_size_y = 1) in;
layout(SB_IMAGE_FORMAT, binding = 0) uniform readonly image2DArray u_src;
layout(SB_IMAGE_FORMAT, binding = 1) uniform writeonly image2DArray u_dst;
uniform ivec2 u_dir;        // (1, 0) or (0, 1)
uniform int u_layer;
const int R = SB_BLUR_RADIUS;
void main() {
    ivec2 size = imageSize(u_src).xy;
    ivec2 across = ivec2(1) - u_dir;
    int a = int(gl_GlobalInvocationID.x), b = int(gl_GlobalInvocationID.y) * SB_RUN;
    int along_size = u_dir.x * size.x + u_dir.y * size.y;
    if (a >= across.x * size.x + across.y * size.y || b >= along_size) return;
    ivec2 p0 = across * a + u_dir * b;
    float sigma = max(float(R) * 0.5, 0.5);
    float w[2 * R + 1];
    float wsum = 0.0;
    for (int i = -R; i <= R; i++) {
        w[i + R] = exp(-0.5 * float(i * i) / (sigma * sigma));
        wsum += w[i + R];
    }
    vec4 win[SB_RUN + 2 * R];
    for (int j = 0; j < SB_RUN + 2 * R; j++)
        win[j] = imageLoad(u_src, ivec3(clamp(p0 + u_dir * (j - R), ivec2(0), size - 1), u_layer));
    for (int t = 0; t < SB_RUN; t++) {
        if (b + t >= along_size) break;
        vec4 sum = vec4(0.0);
        for (int i = -R; i <= R; i++) sum += w[i + R] * win[t + i + R];
        imageStore(u_dst, ivec3(p0 + u_dir * t, u_layer), sum / wsum);
    }
}
