// Lights and environment, the GLSL twin of core/render.cpp (Light::sample, Lighting) and
// core/env.cpp (lat-long look-up, SH9 irradiance). Keep the two in step: tests compare them.
#define MAX_LIGHTS 8
uniform int u_light_count;
uniform int u_light_point[MAX_LIGHTS];
uniform vec3 u_light_dir[MAX_LIGHTS];       // directional: unit vector towards the light
uniform vec3 u_light_pos[MAX_LIGHTS];
uniform vec3 u_light_radiance[MAX_LIGHTS];  // colour * intensity

uniform vec3 u_env_color;
uniform float u_env_intensity;
uniform int u_env_lighting;  // effects.environment
uniform int u_env_has_map;
uniform int u_env_has_sh;
uniform vec3 u_env_sh[9];
uniform sampler2D u_env_map;  // lat-long, row 0 (theta = 0, +z) at t = 0, s wraps

// Direction towards light i from p and the irradiance at normal incidence there.
void light_sample(int i, vec3 p, out vec3 wi, out vec3 E) {
    if (u_light_point[i] == 0) {
        wi = u_light_dir[i];
        E = u_light_radiance[i];
    } else {
        vec3 d = u_light_pos[i] - p;
        float r2 = max(dot(d, d), 1e-12);
        wi = d / sqrt(r2);
        E = u_light_radiance[i] / r2;
    }
}

vec3 env_radiance(vec3 dir) {
    if (u_env_has_map == 0 || dot(dir, dir) <= 0.0) return u_env_color * u_env_intensity;
    return texture(u_env_map, latlong_uv(normalize(dir))).rgb * u_env_intensity;
}

// Ramamoorthi & Hanrahan 2001: E(n) = sum_lm A_l L_lm Y_lm(n).
vec3 env_irradiance(vec3 n) {
    if (u_env_lighting == 0) return vec3(0.0);
    if (u_env_has_sh == 0) return PI * u_env_color * u_env_intensity;
    const float A0 = PI, A1 = 2.0 * PI / 3.0, A2 = PI / 4.0;
    const float Y00 = 0.28209479177387814, Y1 = 0.4886025119029199, Y2 = 1.0925484305920792;
    const float Y20 = 0.31539156525252005, Y22 = 0.5462742152960396;
    vec3 d = normalize(n);
    float x = d.x, y = d.y, z = d.z;
    vec3 e = A0 * Y00 * u_env_sh[0]
           + A1 * Y1 * (y * u_env_sh[1] + z * u_env_sh[2] + x * u_env_sh[3])
           + A2 * (Y2 * (x * y * u_env_sh[4] + y * z * u_env_sh[5] + x * z * u_env_sh[7])
                   + Y20 * (3.0 * z * z - 1.0) * u_env_sh[6] + Y22 * (x * x - y * y) * u_env_sh[8]);
    return e * u_env_intensity;
}
