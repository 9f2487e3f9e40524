#pragma once
// Shared maths types (GLM). World space is right-handed with +z up; directions given as
// THETA,PHI are in degrees: theta from +z, phi from +x towards +y.
#include <glm/glm.hpp>
#include <cmath>

namespace mesolab {
using glm::vec2;
using glm::vec3;
using glm::vec4;
using glm::mat3;
using glm::mat4;
using glm::ivec2;

inline constexpr float kPi = 3.14159265358979323846f;
inline constexpr float kInvPi = 1.0f / kPi;

inline float radians(float deg) { return deg * (kPi / 180.0f); }

// Unit vector for spherical angles in degrees (theta from +z, phi from +x towards +y).
inline vec3 direction_from_degrees(float theta_deg, float phi_deg) {
    const float t = radians(theta_deg), p = radians(phi_deg);
    return {std::sin(t) * std::cos(p), std::sin(t) * std::sin(p), std::cos(t)};
}
}  // namespace mesolab
