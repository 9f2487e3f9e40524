#version 430 core
// Test technique `probe`, frame step probe.blur: a (2r+1)^2 box filter of the illumination map,
// clamped at the borders, as ProbeTechnique::run_step_cpu.
layout(local_size_x = 8, local_size_y = 8) in;
layout(rgba32f, binding = 0) uniform readonly image2D u_in;
layout(rgba32f, binding = 1) uniform writeonly image2D u_out;
uniform int u_radius;
void main() {
    ivec2 size = imageSize(u_in);
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(p, size))) return;
    vec3 sum = vec3(0.0);
    for (int dy = -u_radius; dy <= u_radius; ++dy)
        for (int dx = -u_radius; dx <= u_radius; ++dx) sum += imageLoad(u_in, clamp(p + ivec2(dx, dy), ivec2(0), size - 1)).rgb;
    float n = float((2 * u_radius + 1) * (2 * u_radius + 1));
    imageStore(u_out, p, vec4(sum / n, 1.0));
}
