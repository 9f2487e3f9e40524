// Shared GLSL for all mesolab shaders: no #version here; pull it in with
//   #include "common.glsl"
// (resolved under gpu/shaders/ by gpu/gl.cpp, included once per stage).
//
// Conventions (same as the CPU side, core/math.h and core/env.h):
//   * world space is right-handed with +z up;
//   * spherical angles: theta from +z, phi from +x towards +y;
//   * colours are linear; sRGB encoding only happens for display.

const float PI = 3.14159265358979323846;
const float TWO_PI = 6.28318530717958647692;
const float INV_PI = 0.31830988618379067154;

// [SECTION] sRGB transfer functions (IEC 61966-2-1), per channel
float srgb_to_linear(float c) {
    return c <= 0.04045 ? c / 12.92 : pow((c + 0.055) / 1.055, 2.4);
}
float linear_to_srgb(float c) {
    return c <= 0.0031308 ? 12.92 * c : 1.055 * pow(c, 1.0 / 2.4) - 0.055;
}
vec3 srgb_to_linear(vec3 c) {
    return vec3(srgb_to_linear(c.r), srgb_to_linear(c.g), srgb_to_linear(c.b));
}
vec3 linear_to_srgb(vec3 c) {
    return vec3(linear_to_srgb(c.r), linear_to_srgb(c.g), linear_to_srgb(c.b));
}

// [SECTION] Directions and the lat-long environment mapping
//
// Unit vector for spherical angles in degrees (theta from +z, phi from +x towards +y), exactly
// as mesolab::direction_from_degrees in core/math.h.
vec3 direction_from_degrees(float theta_deg, float phi_deg) {
    float t = radians(theta_deg), p = radians(phi_deg);
    return vec3(sin(t) * cos(p), sin(t) * sin(p), cos(t));
}

// Texture coordinates of direction `dir` (need not be normalised) in a lat-long map, following
// core/env.h: theta = angle from +z, phi = atan2(y, x) in [0, 2pi); u = phi / 2pi, v = theta / pi.
//
// Texture convention: the map is uploaded with glTexImage2D from top-row-first image data, so
// image row 0 (theta = 0, the +z pole) lies at t = 0 and the last row (theta = pi) at t = 1.
// The result is therefore (s, t) = (u, v) with no flip. Sample with GL_LINEAR filtering,
// GL_REPEAT on s (u wraps at phi = 0 / 2pi) and GL_CLAMP_TO_EDGE on t, which matches the CPU's
// bilinear lookup with texel centres at (i + 0.5) / size.
vec2 latlong_uv(vec3 dir) {
    vec3 d = normalize(dir);
    float theta = acos(clamp(d.z, -1.0, 1.0));
    // atan(0, 0) is undefined in GLSL; the CPU's std::atan2(0, 0) gives 0 at the poles.
    float phi = (d.x == 0.0 && d.y == 0.0) ? 0.0 : atan(d.y, d.x);
    if (phi < 0.0) phi += TWO_PI;
    return vec2(phi / TWO_PI, theta / PI);
}
