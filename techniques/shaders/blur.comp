// blur.comp - separable box-weighted Gaussian over one layer of a moments map.
layout(local_size_x = 16, local_size_y = 16) in;
layout(rgba32f, binding = 0) uniform readonly image2DArray u_src;
layout(rgba32f, binding = 1) uniform writeonly image2DArray u_dst;
uniform ivec2 u_dir;
uniform int u_radius;
uniform int u_layer;
void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    ivec2 size = imageSize(u_src).xy;
    if (p.x >= size.x || p.y >= size.y) return;
    vec4 sum = vec4(0.0);
    float wsum = 0.0;
    float sigma = max(float(u_radius) * 0.5, 0.5);
    for (int i = -u_radius; i <= u_radius; i++) {
        ivec2 q = clamp(p + u_dir * i, ivec2(0), size - 1);
        float w = exp(-0.5 * float(i * i) / (sigma * sigma));
        sum += w * imageLoad(u_src, ivec3(q, u_layer));
        wsum += w;
    }
    imageStore(u_dst, ivec3(p, u_layer), sum / wsum);
}
