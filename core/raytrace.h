#pragma once
// [SECTION] Ray casting through Embree 3: triangle meshes placed in one scene, first hits and
// shadow rays. Used by cloth's virtual acquisition and by the truth renderer (core/truth/).
// Thread-safe after commit(): intersect() and occluded() may be called from any thread.
#include "core/math.h"
#include "core/mesh.h"

#include <memory>

namespace mesolab {

struct RayHit {
    int geometry = -1;     // the add() order of the mesh hit, -1 when the ray escapes
    int triangle = -1;     // the mesh's triangle
    float u = 0.f, v = 0.f;  // barycentrics of the triangle's vertices 1 and 2
    float t = 0.f;         // distance along the (unit) direction
    vec3 ng{0.f};          // geometric normal of the triangle as placed (unnormalised, winding order)
    bool hit() const { return geometry >= 0; }
};

class RayScene {
public:
    RayScene();
    ~RayScene();
    RayScene(const RayScene&) = delete;
    RayScene& operator=(const RayScene&) = delete;

    // Adds a mesh placed by `to_world` (positions transformed once); returns its geometry index.
    int add(const TriMesh& mesh, const mat4& to_world = mat4(1.f));
    void commit();  // builds the acceleration structure; std::runtime_error if Embree fails

    // The first hit along o + t d for t in (tnear, tfar).
    RayHit intersect(vec3 o, vec3 d, float tnear = 0.f, float tfar = 3.4e38f) const;
    // Whether anything lies along o + t d for t in (tnear, tfar).
    bool occluded(vec3 o, vec3 d, float tnear = 0.f, float tfar = 3.4e38f) const;

    // The meshes as placed: how many were added, a mesh's triangle count, and a triangle's corners
    // in world space (read from Embree's own buffers: nothing is kept twice).
    int geometry_count() const;
    size_t triangle_count(int geometry) const;
    void triangle(int geometry, size_t t, vec3& a, vec3& b, vec3& c) const;

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};
}  // namespace mesolab
