// Meshes (procedural primitives, OpenMesh loading) and the CPU rasteriser.
#include "core/error.h"
#include "core/mesh.h"
#include "core/raster.h"

#include <gtest/gtest.h>
#include <glm/gtc/matrix_transform.hpp>

#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <unistd.h>

using namespace mesolab;

namespace {

// [SECTION] Test helpers
struct TempDir {
    std::filesystem::path path;
    TempDir() {
        static int counter = 0;
        path = std::filesystem::temp_directory_path() /
               ("mesolab_mesh_test_" + std::to_string(::getpid()) + "_" + std::to_string(counter++));
        std::filesystem::create_directories(path);
    }
    ~TempDir() {
        std::error_code ec;
        std::filesystem::remove_all(path, ec);
    }
    std::string write(const std::string& name, const std::string& text) const {
        const std::string p = (path / name).string();
        std::ofstream(p, std::ios::binary) << text;
        return p;
    }
};

double triangle_area(const TriMesh& m, size_t t) {
    const vec3 a = m.position[m.index[3 * t]], b = m.position[m.index[3 * t + 1]], c = m.position[m.index[3 * t + 2]];
    return 0.5 * double(glm::length(glm::cross(b - a, c - a)));
}

double uv_area(const TriMesh& m, size_t t) {  // signed, positive when counter-clockwise in uv
    const vec2 a = m.uv[m.index[3 * t]], b = m.uv[m.index[3 * t + 1]], c = m.uv[m.index[3 * t + 2]];
    return 0.5 * (double(b.x - a.x) * double(c.y - a.y) - double(c.x - a.x) * double(b.y - a.y));
}

double surface_area(const TriMesh& m) {
    double a = 0.0;
    for (size_t t = 0; t < m.triangle_count(); ++t) a += triangle_area(m, t);
    return a;
}

// A mesh holding only triangle `t` of `m` (same vertex arrays).
TriMesh single_triangle(const TriMesh& m, size_t t) {
    TriMesh s = m;
    s.index.assign(m.index.begin() + std::ptrdiff_t(3 * t), m.index.begin() + std::ptrdiff_t(3 * t + 3));
    return s;
}

// A mesh from explicit triangles (positions only; normal +z, tangent +x, uv = xy).
TriMesh soup(const std::vector<vec3>& positions, const std::vector<uint32_t>& index) {
    TriMesh m;
    m.position = positions;
    m.index = index;
    for (const vec3& p : positions) {
        m.normal.push_back(vec3(0.f, 0.f, 1.f));
        m.tangent.push_back(vec3(1.f, 0.f, 0.f));
        m.uv.push_back(vec2(p.x, p.y));
    }
    m.has_uv = true;
    return m;
}

// Camera whose clip space equals object space (identity view and projection).
RasterCamera identity_camera(int w, int h) {
    RasterCamera cam;
    cam.width = w;
    cam.height = h;
    return cam;
}

RasterCamera perspective_camera(int w, int h, vec3 eye, vec3 target, float fovy_deg = 40.f, float near = 0.1f,
                                float far = 100.f) {
    RasterCamera cam;
    cam.width = w;
    cam.height = h;
    cam.view = glm::lookAt(eye, target, vec3(0.f, 0.f, 1.f));
    cam.proj = glm::perspective(radians(fovy_deg), float(w) / float(h), near, far);
    return cam;
}

GBuffer render(const TriMesh& m, const RasterCamera& cam, mat4 model = mat4(1.f), int id = 1) {
    GBuffer g;
    rasterize({DrawItem{&m, model, id}}, cam, g);
    return g;
}

size_t covered(const GBuffer& g) {
    size_t n = 0;
    for (int32_t o : g.object) n += o >= 0;
    return n;
}

// Window position (GL, y up) of world point p.
vec2 window_of(const RasterCamera& cam, vec3 p) {
    const vec4 c = cam.proj * cam.view * vec4(p, 1.f);
    return {(c.x / c.w + 1.f) * 0.5f * float(cam.width), (c.y / c.w + 1.f) * 0.5f * float(cam.height)};
}

// World-space ray through the centre of image pixel (x, row).
void pixel_ray(const RasterCamera& cam, int x, int row, glm::dvec3& origin, glm::dvec3& dir) {
    const glm::dmat4 inv = glm::inverse(glm::dmat4(cam.proj) * glm::dmat4(cam.view));
    const double xn = (x + 0.5) / cam.width * 2.0 - 1.0;
    const double yn = (cam.height - 1 - row + 0.5) / cam.height * 2.0 - 1.0;
    glm::dvec4 a = inv * glm::dvec4(xn, yn, -1.0, 1.0), b = inv * glm::dvec4(xn, yn, 1.0, 1.0);
    origin = glm::dvec3(a) / a.w;
    dir = glm::normalize(glm::dvec3(b) / b.w - origin);
}

bool all_finite(const GBuffer& g) {
    for (size_t i = 0; i < g.depth.size(); ++i) {
        if (!std::isfinite(g.depth[i]) || g.depth[i] < 0.f || g.depth[i] > 1.f) return false;
        for (int k = 0; k < 3; ++k)
            if (!std::isfinite(g.position[i][k]) || !std::isfinite(g.normal[i][k]) || !std::isfinite(g.tangent[i][k]))
                return false;
        if (!std::isfinite(g.uv[i].x) || !std::isfinite(g.uv[i].y)) return false;
    }
    return true;
}

constexpr double kPiD = 3.14159265358979323846;

const Primitive kPrimitives[] = {Primitive::Sphere, Primitive::Plane, Primitive::Torus, Primitive::Cylinder, Primitive::Teapot};
const char* name_of(Primitive p) {
    switch (p) {
        case Primitive::Sphere: return "sphere";
        case Primitive::Plane: return "plane";
        case Primitive::Torus: return "torus";
        case Primitive::Cylinder: return "cylinder";
        case Primitive::Teapot: return "teapot";
    }
    return "?";
}

// [SECTION] Teapot helpers
constexpr int kTeapotPatches = 32;
constexpr double kAtlasInset = 0.02;  // of a cell, on each side (mesh.h)

int teapot_segments(int resolution) { return std::max(2, resolution / 8); }

// Patch (atlas cell i % 8 + 8 * (i / 8)) whose cell holds uv; -1 outside every cell.
int atlas_cell(vec2 uv) {
    const int cu = int(std::floor(double(uv.x) * 8.0)), cv = int(std::floor(double(uv.y) * 4.0));
    if (cu < 0 || cu >= 8 || cv < 0 || cv >= 4) return -1;
    return cu + 8 * cv;
}

// Whether uv lies in the inset part of atlas cell `cell` (within `slack` in uv units).
bool in_inset_cell(vec2 uv, int cell, double slack) {
    const double lo_u = (cell % 8 + kAtlasInset) / 8.0, hi_u = (cell % 8 + 1 - kAtlasInset) / 8.0;
    const double lo_v = (cell / 8 + kAtlasInset) / 4.0, hi_v = (cell / 8 + 1 - kAtlasInset) / 4.0;
    return uv.x >= lo_u - slack && uv.x <= hi_u + slack && uv.y >= lo_v - slack && uv.y <= hi_v + slack;
}

// Whether the ray o + x d (x > 0) crosses triangle (a, b, c) (Moller-Trumbore, double).
bool ray_crosses(glm::dvec3 o, glm::dvec3 d, glm::dvec3 a, glm::dvec3 b, glm::dvec3 c) {
    const glm::dvec3 e1 = b - a, e2 = c - a, p = glm::cross(d, e2);
    const double det = glm::dot(e1, p);
    if (std::abs(det) < 1e-18) return false;
    const glm::dvec3 q = o - a;
    const double u = glm::dot(q, p) / det;
    if (u < 0.0 || u > 1.0) return false;
    const glm::dvec3 r = glm::cross(q, e1);
    const double v = glm::dot(d, r) / det;
    if (v < 0.0 || u + v > 1.0) return false;
    return glm::dot(e2, r) / det > 0.0;
}

// Triangle t's corners in double.
std::array<glm::dvec3, 3> corners(const TriMesh& m, size_t t) {
    return {glm::dvec3(m.position[m.index[3 * t]]), glm::dvec3(m.position[m.index[3 * t + 1]]),
            glm::dvec3(m.position[m.index[3 * t + 2]])};
}
}  // namespace

// [SECTION] Procedural primitives
TEST(Primitives, ConsistentArraysUnitFramesAndUvTiling) {
    for (Primitive p : kPrimitives)
        for (int res : {3, 4, 7, 16, 64}) {
            SCOPED_TRACE(std::string(name_of(p)) + " resolution " + std::to_string(res));
            const TriMesh m = make_primitive(p, res);
            ASSERT_TRUE(m.has_uv);
            ASSERT_GT(m.triangle_count(), 0u);
            ASSERT_EQ(m.normal.size(), m.vertex_count());
            ASSERT_EQ(m.tangent.size(), m.vertex_count());
            ASSERT_EQ(m.uv.size(), m.vertex_count());
            for (uint32_t i : m.index) ASSERT_LT(i, m.vertex_count());
            for (size_t v = 0; v < m.vertex_count(); ++v) {
                EXPECT_NEAR(glm::length(m.normal[v]), 1.f, 1e-5f);
                EXPECT_NEAR(glm::length(m.tangent[v]), 1.f, 1e-5f);
                EXPECT_NEAR(glm::dot(m.normal[v], m.tangent[v]), 0.f, 1e-5f);
                EXPECT_GE(m.uv[v].x, 0.f);
                EXPECT_LE(m.uv[v].x, 1.f);
                EXPECT_GE(m.uv[v].y, 0.f);
                EXPECT_LE(m.uv[v].y, 1.f);
            }
            double total_uv = 0.0;
            for (size_t t = 0; t < m.triangle_count(); ++t) {
                const double a = uv_area(m, t);
                EXPECT_GT(a, 0.0) << "triangle " << t;
                total_uv += a;
            }
            // The teapot's atlas cells are inset by 2% on each side: 0.96^2 of the square.
            const double inner = 1.0 - 2.0 * kAtlasInset;
            EXPECT_NEAR(total_uv, p == Primitive::Teapot ? inner * inner : 1.0, 1e-6);
        }
}

TEST(Primitives, CounterClockwiseFromOutside) {
    for (Primitive p : kPrimitives) {
        SCOPED_TRACE(name_of(p));
        const TriMesh m = make_primitive(p, 24);
        size_t degenerate = 0;
        for (size_t t = 0; t < m.triangle_count(); ++t) {
            const uint32_t i0 = m.index[3 * t], i1 = m.index[3 * t + 1], i2 = m.index[3 * t + 2];
            const vec3 n_geo = glm::cross(m.position[i1] - m.position[i0], m.position[i2] - m.position[i0]);
            if (glm::length(n_geo) < 1e-9f) {
                ++degenerate;
                continue;
            }
            EXPECT_GT(glm::dot(n_geo, m.normal[i0] + m.normal[i1] + m.normal[i2]), 0.f) << "triangle " << t;
            // The tangent follows +u: dP/du of the triangle points the same way.
            const vec2 d1 = m.uv[i1] - m.uv[i0], d2 = m.uv[i2] - m.uv[i0];
            const vec3 dpdu = ((m.position[i1] - m.position[i0]) * d2.y - (m.position[i2] - m.position[i0]) * d1.y) /
                              (d1.x * d2.y - d2.x * d1.y);
            EXPECT_GT(glm::dot(dpdu, m.tangent[i0] + m.tangent[i1] + m.tangent[i2]), 0.f) << "triangle " << t;
        }
        // Only the sphere's pole rows hold zero-area triangles, one per cell, and the teapot's
        // rows at the knob top and the bottom centre (8 patches, one per cell of their first row).
        const size_t expected = p == Primitive::Sphere ? size_t(2 * 24) : p == Primitive::Teapot ? size_t(8 * teapot_segments(24)) : size_t(0);
        EXPECT_EQ(degenerate, expected);
    }
}

TEST(Primitives, SphereGeometry) {
    const TriMesh m = make_primitive(Primitive::Sphere, 32);
    EXPECT_EQ(m.vertex_count(), size_t(33 * 17));
    for (size_t v = 0; v < m.vertex_count(); ++v) {
        EXPECT_NEAR(glm::length(m.position[v]), 1.f, 1e-6f);
        EXPECT_GT(glm::dot(m.normal[v], m.position[v]), 0.99f);  // outward (normal = position)
        // v = 0 at the south pole, 1 at the north pole; u = azimuth / 2pi from +x.
        EXPECT_NEAR(m.position[v].z, -std::cos(kPi * m.uv[v].y), 1e-5f);
        if (std::abs(m.position[v].z) < 0.999f && m.uv[v].x > 0.f && m.uv[v].x < 1.f) {
            float phi = std::atan2(m.position[v].y, m.position[v].x);
            if (phi < 0.f) phi += 2.f * kPi;
            EXPECT_NEAR(phi / (2.f * kPi), m.uv[v].x, 1e-5f);
        }
    }
    // Pole vertices: the tangent is the limit direction of dP/du for their u column.
    for (size_t v = 0; v < m.vertex_count(); ++v)
        if (m.uv[v].y == 0.f || m.uv[v].y == 1.f) {
            const float phi = 2.f * kPi * m.uv[v].x;
            EXPECT_NEAR(m.tangent[v].x, -std::sin(phi), 1e-5f);
            EXPECT_NEAR(m.tangent[v].y, std::cos(phi), 1e-5f);
            EXPECT_EQ(m.tangent[v].z, 0.f);
        }
}

TEST(Primitives, SeamVerticesCoincide) {
    for (Primitive p : kPrimitives) {
        // The teapot has no u seam (an atlas): Teapot.PatchBordersMeet. The plane's u = 0 and u = 1
        // edges are opposite sides, not a seam.
        if (p == Primitive::Teapot || p == Primitive::Plane) continue;
        SCOPED_TRACE(name_of(p));
        const TriMesh m = make_primitive(p, 12);
        size_t pairs = 0;
        for (size_t a = 0; a < m.vertex_count(); ++a)
            if (m.uv[a].x == 0.f)
                for (size_t b = 0; b < m.vertex_count(); ++b)
                    if (m.uv[b].x == 1.f && m.uv[b].y == m.uv[a].y) {
                        EXPECT_EQ(m.position[a], m.position[b]);  // bit-identical: no cracks
                        EXPECT_EQ(m.normal[a], m.normal[b]);
                        ++pairs;
                    }
        // One seam pair per ring of vertices along v: at least 13 at resolution 12 (7 for the sphere's 12 x 6 grid).
        EXPECT_GE(pairs, size_t(7)) << "no seam vertices found: nothing was compared";
    }
}

TEST(Primitives, SurfaceAreaConverges) {
    struct Case {
        Primitive p;
        double exact;
    };
    const double r = 0.35;
    const Case cases[] = {{Primitive::Sphere, 4.0 * kPiD},
                          {Primitive::Torus, 4.0 * kPiD * kPiD * r},  // (2 pi R)(2 pi r), R = 1
                          {Primitive::Plane, 4.0},
                          {Primitive::Cylinder, 4.0 * kPiD}};
    for (const Case& c : cases) {
        SCOPED_TRACE(name_of(c.p));
        double previous_error = 1e9;
        for (int res : {8, 16, 32, 64, 128, 256}) {
            const double error = std::abs(surface_area(make_primitive(c.p, res, float(r))) / c.exact - 1.0);
            // Second-order convergence (flat facets): relative error below 10 / res^2 (the sphere,
            // worst, is at 8.2 / res^2).
            EXPECT_LT(error, 10.0 / (res * res)) << "resolution " << res;
            if (c.p != Primitive::Plane) { EXPECT_LT(error, previous_error) << "resolution " << res; }
            previous_error = error;
        }
    }
}

TEST(Primitives, TorusAreaIsFourPiSquaredRr) {
    // Area of a torus with major radius R and minor radius r: (2 pi R)(2 pi r) = 4 pi^2 R r.
    const double r = 0.25;
    const double area = surface_area(make_primitive(Primitive::Torus, 512, float(r)));
    EXPECT_NEAR(area / (4.0 * kPiD * kPiD * 1.0 * r), 1.0, 1e-4);
}

TEST(Primitives, InvalidParametersAreInputErrors) {
    for (int res : {-1, 0, 2, 16385}) {
        try {
            make_primitive(Primitive::Sphere, res);
            ADD_FAILURE() << "resolution " << res << " accepted";
        } catch (const InputError& e) {
            EXPECT_NE(std::string(e.what()).find("geometry.resolution"), std::string::npos) << e.what();
            EXPECT_NE(std::string(e.what()).find("[3, 16384]"), std::string::npos) << e.what();
        }
    }
    EXPECT_NO_THROW(make_primitive(Primitive::Plane, 3));
    EXPECT_THROW(make_primitive(Primitive::Torus, 8, 0.f), InputError);
    EXPECT_THROW(make_primitive(Primitive::Torus, 8, 1.f), InputError);
    EXPECT_THROW(make_primitive(Primitive::Torus, 8, std::nanf("")), InputError);
    EXPECT_NO_THROW(make_primitive(Primitive::Sphere, 8, 5.f));  // ratio only matters for the torus
    EXPECT_NO_THROW(make_primitive(Primitive::Teapot, 3, 5.f));
    EXPECT_THROW(make_primitive(Primitive::Teapot, 2), InputError);
    for (Primitive p : kPrimitives) EXPECT_EQ(primitive_named(name_of(p)), p);
    EXPECT_THROW(primitive_named("mesh"), InputError);
    EXPECT_THROW(primitive_named("Teapot"), InputError);
}

TEST(Primitives, TransformAndBounds) {
    TriMesh m = make_primitive(Primitive::Sphere, 16);
    const TriMesh original = m;
    transform_mesh(m, 2.f, vec3(1.f, 2.f, 3.f));
    const Bounds b = bounds(m);
    EXPECT_NEAR(b.lo.z, 1.f, 1e-6f);
    EXPECT_NEAR(b.hi.z, 5.f, 1e-6f);
    EXPECT_NEAR(b.hi.x, 3.f, 1e-6f);
    EXPECT_EQ(m.normal, original.normal);
    EXPECT_EQ(m.tangent, original.tangent);
    const Bounds empty = bounds(TriMesh{});
    EXPECT_EQ(empty.lo, vec3(0.f));
    EXPECT_EQ(empty.hi, vec3(0.f));
}

// A shared mesh's bounds are remembered while it lives; a mesh made after it was freed (often at
// the same address), or another mesh sharing its owner, is walked on its own.
TEST(Mesh, SharedBoundsBelongToTheirOwnMesh) {
    for (int round = 0; round < 3; ++round) {
        auto m = std::make_shared<TriMesh>(make_primitive(Primitive::Sphere, 16));
        transform_mesh(*m, float(round + 1), vec3(float(round)));
        const std::shared_ptr<const TriMesh> shared = m;
        const Bounds walked = bounds(*shared), kept = bounds(shared), again = bounds(shared);
        EXPECT_EQ(kept.lo, walked.lo);
        EXPECT_EQ(kept.hi, walked.hi);
        EXPECT_EQ(again.hi, walked.hi);
        EXPECT_NEAR(kept.hi.x, float(round) + float(round + 1), 1e-5f);
    }
    // Two meshes inside one owner (an aliasing pointer each) keep two answers.
    struct Pair { TriMesh a, b; };
    auto pair = std::make_shared<Pair>();
    pair->a = make_primitive(Primitive::Plane, 4);
    pair->b = make_primitive(Primitive::Plane, 4);
    transform_mesh(pair->b, 3.f, vec3(0.f));
    const std::shared_ptr<const TriMesh> a(pair, &pair->a), b(pair, &pair->b);
    EXPECT_NEAR(bounds(a).hi.x, 1.f, 1e-6f);
    EXPECT_NEAR(bounds(b).hi.x, 3.f, 1e-6f);
}

// [SECTION] Utah teapot
TEST(Teapot, ClosedEnoughFiniteOutwardNormalsAndAtlasUv) {
    // Counts: 32 patches of n x n cells, n = max(2, resolution / 8).
    for (int res : {3, 16, 64, 128})
        EXPECT_EQ(make_primitive(Primitive::Teapot, res).triangle_count(), size_t(kTeapotPatches * 2 * teapot_segments(res) * teapot_segments(res)));
    EXPECT_EQ(make_primitive(Primitive::Teapot, 64).triangle_count(), 4096u);
    EXPECT_EQ(make_primitive(Primitive::Teapot, 128).triangle_count(), 16384u);

    for (int res : {16, 128, 512}) {
        SCOPED_TRACE("resolution " + std::to_string(res));
        const TriMesh m = make_primitive(Primitive::Teapot, res);
        ASSERT_TRUE(m.has_uv);
        ASSERT_EQ(m.normal.size(), m.vertex_count());
        ASSERT_EQ(m.tangent.size(), m.vertex_count());
        ASSERT_EQ(m.uv.size(), m.vertex_count());
        for (uint32_t i : m.index) ASSERT_LT(i, m.vertex_count());
        // Finite, unit frames (also where a patch edge collapses to a point).
        for (size_t v = 0; v < m.vertex_count(); ++v) {
            for (int k = 0; k < 3; ++k) {
                ASSERT_TRUE(std::isfinite(m.position[v][k]) && std::isfinite(m.normal[v][k]) && std::isfinite(m.tangent[v][k])) << v;
            }
            ASSERT_NEAR(glm::length(m.normal[v]), 1.f, 1e-4f) << v;
            ASSERT_NEAR(glm::length(m.tangent[v]), 1.f, 1e-4f) << v;
            ASSERT_NEAR(glm::dot(m.normal[v], m.tangent[v]), 0.f, 1e-4f) << v;
        }
        // Unit size: inside [-1,1]^3; the surface's box is centred with largest half-extent 1,
        // which the vertices reach to within the tessellation's sagitta.
        const Bounds b = bounds(m);
        for (int k = 0; k < 3; ++k) {
            EXPECT_GE(b.lo[k], -1.f - 1e-6f);
            EXPECT_LE(b.hi[k], 1.f + 1e-6f);
        }
        const vec3 half = 0.5f * (b.hi - b.lo), centre = 0.5f * (b.hi + b.lo);
        const float tolerance = res >= 512 ? 1e-4f : 1e-2f;
        EXPECT_NEAR(std::max({half.x, half.y, half.z}), 1.f, tolerance);
        EXPECT_NEAR(glm::length(centre), 0.f, tolerance);
        EXPECT_GT(half.x, half.y);  // spout to handle along x, then the body's width, then the height
        EXPECT_GT(half.y, half.z);
        // Every triangle's uv lies in the inset part of one atlas cell.
        for (size_t t = 0; t < m.triangle_count(); ++t) {
            const uint32_t i0 = m.index[3 * t], i1 = m.index[3 * t + 1], i2 = m.index[3 * t + 2];
            const int cell = atlas_cell((m.uv[i0] + m.uv[i1] + m.uv[i2]) / 3.f);
            ASSERT_GE(cell, 0) << t;
            for (uint32_t i : {i0, i1, i2}) {
                ASSERT_TRUE(m.uv[i].x >= 0.f && m.uv[i].x <= 1.f && m.uv[i].y >= 0.f && m.uv[i].y <= 1.f) << t;
                ASSERT_TRUE(in_inset_cell(m.uv[i], cell, 1e-6)) << "triangle " << t << " leaves cell " << cell;
            }
        }
    }

    // Orientation at resolution 128 (16 x 16 cells per patch).
    const TriMesh m = make_primitive(Primitive::Teapot, 128);
    std::vector<double> area(m.triangle_count());
    std::vector<int> patch(m.triangle_count());
    glm::dvec3 centroid(0.0);
    double total_area = 0.0;
    for (size_t t = 0; t < m.triangle_count(); ++t) {
        const auto [a, b, c] = corners(m, t);
        area[t] = triangle_area(m, t);
        patch[t] = atlas_cell((m.uv[m.index[3 * t]] + m.uv[m.index[3 * t + 1]] + m.uv[m.index[3 * t + 2]]) / 3.f);
        centroid += area[t] * (a + b + c) / 3.0;
        total_area += area[t];
    }
    centroid /= total_area;
    // Body (patches 4-11): the normals point away from the centroid over at least 95% of the
    // area (all of it with flipped normals would point towards it).
    double body = 0.0, body_outward = 0.0;
    for (size_t t = 0; t < m.triangle_count(); ++t) {
        if (patch[t] < 4 || patch[t] > 11) continue;
        const auto [a, b, c] = corners(m, t);
        const glm::dvec3 n(m.normal[m.index[3 * t]] + m.normal[m.index[3 * t + 1]] + m.normal[m.index[3 * t + 2]]);
        body += area[t];
        if (glm::dot(n, (a + b + c) / 3.0 - centroid) > 0.0) body_outward += area[t];
    }
    EXPECT_GT(body_outward, 0.95 * body);
    // Winding agrees with the vertex normals on at least 99% of the non-degenerate triangles.
    size_t agree = 0, non_degenerate = 0;
    for (size_t t = 0; t < m.triangle_count(); ++t) {
        const auto [a, b, c] = corners(m, t);
        const glm::dvec3 geo = glm::cross(b - a, c - a);
        if (glm::length(geo) < 1e-12) continue;
        ++non_degenerate;
        const glm::dvec3 n(m.normal[m.index[3 * t]] + m.normal[m.index[3 * t + 1]] + m.normal[m.index[3 * t + 2]]);
        agree += glm::dot(geo, n) >= 0.0;
    }
    EXPECT_GE(double(agree), 0.99 * double(non_degenerate)) << agree << " of " << non_degenerate;
    // Enclosed volume by the divergence theorem from the winding: positive (counter-clockwise
    // seen from outside).
    double volume = 0.0;
    for (size_t t = 0; t < m.triangle_count(); ++t) {
        const auto [a, b, c] = corners(m, t);
        volume += glm::dot(a, glm::cross(b, c)) / 6.0;
    }
    EXPECT_GT(volume, 0.5);
    // The collapsed edges (first row of the knob's patches 20-23 and of the bottom's 28-31) are
    // the highest and the lowest points (z up), with normals straight up and down.
    const size_t per_patch = size_t(17 * 17);
    const Bounds box = bounds(m);
    for (int p : {20, 21, 22, 23, 28, 29, 30, 31})
        for (size_t k = 0; k <= 16; ++k) {
            const size_t v = size_t(p) * per_patch + k;
            const float up = p < 28 ? 1.f : -1.f;
            EXPECT_EQ(m.position[v].z, p < 28 ? box.hi.z : box.lo.z) << "patch " << p;
            EXPECT_GT(up * m.normal[v].z, 0.9999f) << "patch " << p;
        }
    // Surface area converges: resolutions 128 and 512 agree within 1%.
    const double a128 = surface_area(m), a512 = surface_area(make_primitive(Primitive::Teapot, 512));
    EXPECT_NEAR(a128 / a512, 1.0, 0.01);
    EXPECT_LT(a128, a512);  // inscribed facets
}

TEST(Teapot, RaysFromOutsideLeaveTheSurfaceAnEvenNumberOfTimes) {
    // Outwardness without a centre: a ray from just outside a triangle along its normal crosses
    // the (nearly closed) surface an even number of times. Per part, for most of the area; the
    // spout and handle run into the body, and the lid leaves a gap to the rim, where parity fails.
    const TriMesh m = make_primitive(Primitive::Teapot, 64);
    struct Part {
        const char* name;
        int first, last;  // patches
    };
    const Part parts[] = {{"rim", 0, 3}, {"body", 4, 11}, {"handle", 12, 15}, {"spout", 16, 19}, {"lid", 20, 27}, {"bottom", 28, 31}};
    std::vector<std::array<glm::dvec3, 3>> tri(m.triangle_count());
    for (size_t t = 0; t < m.triangle_count(); ++t) tri[t] = corners(m, t);
    for (const Part& part : parts) {
        double area = 0.0, even = 0.0;
        for (size_t t = 0; t < m.triangle_count(); ++t) {
            const int cell = atlas_cell((m.uv[m.index[3 * t]] + m.uv[m.index[3 * t + 1]] + m.uv[m.index[3 * t + 2]]) / 3.f);
            if (cell < part.first || cell > part.last) continue;
            const auto& [a, b, c] = tri[t];
            const glm::dvec3 geo = glm::cross(b - a, c - a);
            if (glm::length(geo) < 1e-12) continue;
            const glm::dvec3 n = glm::normalize(glm::dvec3(m.normal[m.index[3 * t]] + m.normal[m.index[3 * t + 1]] + m.normal[m.index[3 * t + 2]]));
            const glm::dvec3 origin = (a + b + c) / 3.0 + 1e-4 * n;
            int crossings = 0;
            for (const auto& [p, q, r] : tri) crossings += ray_crosses(origin, n, p, q, r);
            area += 0.5 * glm::length(geo);
            if (crossings % 2 == 0) even += 0.5 * glm::length(geo);
        }
        std::printf("[ teapot   ] %-6s: rays from outside even for %.1f%% of the area\n", part.name, 100.0 * even / area);
        EXPECT_GT(even, 0.8 * area) << part.name;
    }
}

TEST(Teapot, PatchBordersMeet) {
    // Closed enough: every vertex on a patch border lies on a vertex of another patch, except on
    // the open ends (the rim's inner edge, the lid's outer edge, the handle's and the spout's ends).
    const int n = 8;
    const TriMesh m = make_primitive(Primitive::Teapot, 8 * n);
    const size_t per_patch = size_t((n + 1) * (n + 1));
    ASSERT_EQ(m.vertex_count(), kTeapotPatches * per_patch);
    auto open_end = [](int patch, int t) {  // t = 0 or n: first or last row of the patch
        if (patch <= 3) return t == 0;                     // rim: inner lip
        if (patch >= 24 && patch <= 27) return t != 0;    // lid: outer edge, next to the rim
        if (patch == 12 || patch == 13 || patch == 16 || patch == 17) return t == 0;  // handle, spout: start
        if (patch == 14 || patch == 15 || patch == 18 || patch == 19) return t != 0;  // handle, spout: end
        return false;
    };
    size_t checked = 0;
    for (size_t v = 0; v < m.vertex_count(); ++v) {
        const int patch = int(v / per_patch), j = int(v % per_patch) / (n + 1), k = int(v % per_patch) % (n + 1);
        if (j != 0 && j != n && k != 0 && k != n) continue;  // inside the patch
        if ((j == 0 || j == n) && open_end(patch, j) && k != 0 && k != n) continue;  // its corners meet the side neighbour
        float nearest = 1e9f;
        for (size_t w = 0; w < m.vertex_count(); ++w)
            if (w / per_patch != v / per_patch) nearest = std::min(nearest, glm::distance(m.position[v], m.position[w]));
        EXPECT_LT(nearest, 1e-6f) << "patch " << patch << " row " << j << " column " << k;
        ++checked;
    }
    EXPECT_GT(checked, size_t(kTeapotPatches * 2 * n));
}

// [SECTION] Texture-space rasterisation
TEST(Raster, TextureModePlaneCoversEveryPixelWithPixelCentreUv) {
    const TriMesh plane = make_primitive(Primitive::Plane, 8);
    for (ivec2 size : {ivec2(256, 128), ivec2(64, 64), ivec2(200, 40)}) {
        RasterCamera cam = identity_camera(size.x, size.y);
        cam.texture_space = true;
        const GBuffer g = render(plane, cam, mat4(1.f), 7);
        ASSERT_EQ(g.width, size.x);
        ASSERT_EQ(g.height, size.y);
        for (int y = 0; y < g.height; ++y)
            for (int x = 0; x < g.width; ++x) {
                const size_t i = g.index(x, y);
                ASSERT_EQ(g.object[i], 7) << x << "," << y;
                const vec2 uv((x + 0.5f) / float(g.width), 1.f - (y + 0.5f) / float(g.height));
                EXPECT_NEAR(g.uv[i].x, uv.x, 1e-5f) << x << "," << y;
                EXPECT_NEAR(g.uv[i].y, uv.y, 1e-5f) << x << "," << y;
                EXPECT_NEAR(g.position[i].x, 2.f * uv.x - 1.f, 2e-5f);
                EXPECT_NEAR(g.position[i].y, 2.f * uv.y - 1.f, 2e-5f);
                EXPECT_EQ(g.normal[i], vec3(0.f, 0.f, 1.f));
                EXPECT_EQ(g.tangent[i], vec3(1.f, 0.f, 0.f));
                EXPECT_EQ(g.depth[i], 0.5f);
            }
    }
}

TEST(Raster, TextureModeCoversEveryPixelExactlyOnceForEveryPrimitive) {
    // The primitives tile the uv square (the teapot: the inset cells of its atlas), so in
    // texture mode each pixel centre in them is covered by exactly one triangle and the others
    // by none: rendering the triangles one at a time, the counts must be 1 and 0.
    for (Primitive p : kPrimitives)
        for (ivec2 size : {ivec2(48, 40), ivec2(240, 120)}) {
            SCOPED_TRACE(std::string(name_of(p)) + " " + std::to_string(size.x) + "x" + std::to_string(size.y));
            const TriMesh m = make_primitive(p, 6);
            RasterCamera cam = identity_camera(size.x, size.y);
            cam.texture_space = true;
            std::vector<int> count(size_t(size.x * size.y), 0);
            for (size_t t = 0; t < m.triangle_count(); ++t) {
                const GBuffer g = render(single_triangle(m, t), cam);
                for (size_t i = 0; i < count.size(); ++i) count[i] += g.object[i] >= 0;
            }
            size_t expected_covered = 0;
            for (int y = 0; y < size.y; ++y)
                for (int x = 0; x < size.x; ++x) {
                    const vec2 uv((x + 0.5f) / float(size.x), 1.f - (y + 0.5f) / float(size.y));
                    const int expected = p != Primitive::Teapot || in_inset_cell(uv, atlas_cell(uv), 0.0);
                    expected_covered += size_t(expected);
                    ASSERT_EQ(count[size_t(y * size.x + x)], expected) << "pixel " << x << "," << y;
                }
            // At 240x120 the 2% insets are 0.6 pixel wide: the gaps between cells hold pixel centres.
            if (p == Primitive::Teapot && size.x == 240) { EXPECT_LT(expected_covered, count.size()); }
            const GBuffer all = render(m, cam);
            EXPECT_EQ(covered(all), expected_covered);
            EXPECT_TRUE(all_finite(all));
        }
}

TEST(Raster, EqualDepthKeepsTheFirstDrawnItem) {
    const TriMesh plane = make_primitive(Primitive::Plane, 4);
    RasterCamera cam = identity_camera(32, 32);
    cam.texture_space = true;
    GBuffer g;
    rasterize({DrawItem{&plane, mat4(1.f), 1}, DrawItem{&plane, mat4(1.f), 2}}, cam, g);
    for (int32_t o : g.object) ASSERT_EQ(o, 1);
}

// [SECTION] Fill rule: shared edges
TEST(Raster, SharedEdgesCoverEachPixelExactlyOnce) {
    std::mt19937 rng(1234);
    std::uniform_real_distribution<float> coord(-1.2f, 1.2f);
    const int w = 37, h = 29;
    const RasterCamera cam = identity_camera(w, h);
    int convex_trials = 0;
    for (int trial = 0; trial < 300; ++trial) {
        // A quad (a, b, c, d), split along a-c; on every third trial the diagonal and the
        // corners sit exactly on pixel centres or pixel corners to exercise ties.
        std::vector<vec3> q(4);
        for (vec3& p : q) {
            p = vec3(coord(rng), coord(rng), 0.f);
            if (trial % 3 == 0) {
                p.x = (std::round((p.x + 1.f) * 0.5f * w * 2.f) / 2.f) / (0.5f * w) - 1.f;
                p.y = (std::round((p.y + 1.f) * 0.5f * h * 2.f) / 2.f) / (0.5f * h) - 1.f;
            }
        }
        const TriMesh first = soup(q, {0, 1, 2}), second = soup(q, {0, 2, 3}), both = soup(q, {0, 1, 2, 0, 2, 3});
        const GBuffer g1 = render(first, cam), g2 = render(second, cam), g12 = render(both, cam);
        // Window positions (GL, y up) of the corners, in double.
        std::array<glm::dvec2, 4> wq;
        for (size_t k = 0; k < 4; ++k) wq[k] = {(double(q[k].x) + 1.0) * 0.5 * w, (double(q[k].y) + 1.0) * 0.5 * h};
        auto cross = [](glm::dvec2 a, glm::dvec2 b) { return a.x * b.y - a.y * b.x; };
        // With b and d on opposite sides of the diagonal a-c, the triangles do not overlap.
        const bool opposite_sides = cross(wq[2] - wq[0], wq[1] - wq[0]) * cross(wq[2] - wq[0], wq[3] - wq[0]) < 0.0;
        // Convex quad: the union is the quad, so pixel centres clearly inside it are covered.
        const bool convex = opposite_sides && cross(wq[3] - wq[1], wq[0] - wq[1]) * cross(wq[3] - wq[1], wq[2] - wq[1]) < 0.0;
        const double orientation = cross(wq[1] - wq[0], wq[2] - wq[0]) > 0.0 ? 1.0 : -1.0;
        convex_trials += convex;
        for (int row = 0; row < h; ++row)
            for (int x = 0; x < w; ++x) {
                const size_t i = g1.index(x, row);
                const bool c1 = g1.object[i] >= 0, c2 = g2.object[i] >= 0;
                if (opposite_sides) { ASSERT_FALSE(c1 && c2) << "trial " << trial << " pixel " << x << "," << row; }
                ASSERT_EQ(g12.object[i] >= 0, c1 || c2) << "trial " << trial << " pixel " << x << "," << row;
                if (!convex) continue;
                // Distance of the pixel centre inside each outer edge (positive inside).
                const glm::dvec2 p(x + 0.5, h - 1 - row + 0.5);
                double inside = 1e9;
                for (size_t k = 0; k < 4; ++k) {
                    const glm::dvec2 a = wq[k], b = wq[(k + 1) % 4];
                    inside = std::min(inside, orientation * cross(b - a, p - a) / glm::length(b - a));
                }
                if (inside > 0.01) { ASSERT_TRUE(c1 || c2) << "crack: trial " << trial << " pixel " << x << "," << row; }
                if (inside < -0.01) { ASSERT_FALSE(c1 || c2) << "trial " << trial << " pixel " << x << "," << row; }
            }
    }
    EXPECT_GT(convex_trials, 50);
}

TEST(Raster, FanAroundAPixelCentreCoversItOnce) {
    // Eight triangles around a vertex exactly at a pixel centre, with spokes through pixel
    // centres: the centre pixel and every pixel on a spoke belong to exactly one triangle.
    const int w = 32, h = 32;
    const RasterCamera cam = identity_camera(w, h);
    auto ndc = [&](float px, float py) { return vec3(px / (0.5f * w) - 1.f, py / (0.5f * h) - 1.f, 0.f); };
    std::vector<vec3> ring;
    for (int k = 0; k < 8; ++k) {
        const int dx[] = {10, 10, 0, -10, -10, -10, 0, 10}, dy[] = {0, 10, 10, 10, 0, -10, -10, -10};
        ring.push_back(ndc(16.5f + float(dx[k]), 16.5f + float(dy[k])));
    }
    std::vector<int> count(size_t(w * h), 0);
    for (int k = 0; k < 8; ++k) {
        const GBuffer g = render(soup({ndc(16.5f, 16.5f), ring[size_t(k)], ring[size_t((k + 1) % 8)]}, {0, 1, 2}), cam);
        for (size_t i = 0; i < count.size(); ++i) count[i] += g.object[i] >= 0;
    }
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const int gx = x, gy = h - 1 - y;  // GL window pixel
            const bool inside = std::abs(gx - 16) < 10 && std::abs(gy - 16) < 10;
            if (inside) { EXPECT_EQ(count[size_t(y * w + x)], 1) << gx << "," << gy; }
            EXPECT_LE(count[size_t(y * w + x)], 1) << gx << "," << gy;
        }
}

TEST(Raster, PerspectiveGridCoversEachPixelOnceIncludingNearPlaneClips) {
    // A tessellated ground plane seen in perspective, once wholly in front of the camera and
    // once crossing the near plane (clipped triangles share new vertices along shared edges).
    TriMesh plane = make_primitive(Primitive::Plane, 6);
    transform_mesh(plane, 4.f, vec3(0.f));
    struct View {
        vec3 eye, target;
    };
    const View views[] = {{vec3(1.3f, -9.f, 6.f), vec3(0.3f, 0.2f, 0.f)},   // whole plane visible
                          {vec3(0.37f, -3.1f, 0.6f), vec3(0.5f, 4.f, -0.4f)}};  // camera above the plane's middle
    for (const View& v : views) {
        const RasterCamera cam = perspective_camera(96, 64, v.eye, v.target, 60.f, 0.5f, 50.f);
        std::vector<int> count(size_t(96 * 64), 0);
        for (size_t t = 0; t < plane.triangle_count(); ++t) {
            const GBuffer g = render(single_triangle(plane, t), cam);
            ASSERT_TRUE(all_finite(g));
            for (size_t i = 0; i < count.size(); ++i) count[i] += g.object[i] >= 0;
        }
        const GBuffer all = render(plane, cam);
        size_t interior = 0;
        for (int row = 0; row < 64; ++row)
            for (int x = 0; x < 96; ++x) {
                const size_t i = all.index(x, row);
                ASSERT_LE(count[i], 1) << x << "," << row;
                ASSERT_EQ(count[i] == 1, all.object[i] >= 0) << x << "," << row;
                // Pixels whose ray meets the plane well inside its extent and beyond the near
                // plane must be covered.
                glm::dvec3 o, d;
                pixel_ray(cam, x, row, o, d);
                if (d.z >= -1e-9) continue;
                const double t = -o.z / d.z;
                const glm::dvec3 hit = o + d * t;
                const double depth_along_view = glm::dot(hit - glm::dvec3(v.eye), glm::normalize(glm::dvec3(v.target - v.eye)));
                if (std::abs(hit.x) < 3.95 && std::abs(hit.y) < 3.95 && depth_along_view > 0.55) {
                    ++interior;
                    ASSERT_EQ(count[i], 1) << x << "," << row;
                }
            }
        EXPECT_GT(interior, size_t(500));
    }
}

// [SECTION] Perspective rendering
TEST(Raster, SphereSilhouetteAndPerspectiveCorrectAttributes) {
    const TriMesh sphere = make_primitive(Primitive::Sphere, 128);
    const float distance = 3.f, fovy = 40.f;
    const RasterCamera cam = perspective_camera(512, 512, vec3(distance, 0.f, 0.f), vec3(0.f), fovy, 0.1f, 100.f);
    const GBuffer g = render(sphere, cam, mat4(1.f), 3);
    ASSERT_TRUE(all_finite(g));
    // Silhouette: a cone of half-angle asin(1/d) around the view axis, a disk on the image.
    const double r_px = std::tan(std::asin(1.0 / distance)) / std::tan(double(radians(fovy)) / 2.0) * 256.0;
    const double expected = kPiD * r_px * r_px;
    EXPECT_NEAR(double(covered(g)) / expected, 1.0, 0.02);

    const mat4 clip_from_world = cam.proj * cam.view;
    for (int row = 0; row < 512; ++row)
        for (int x = 0; x < 512; ++x) {
            const size_t i = g.index(x, row);
            if (g.object[i] < 0) continue;
            ASSERT_EQ(g.object[i], 3);
            const vec3 p = g.position[i];
            EXPECT_NEAR(glm::length(p), 1.f, 2e-3f);
            EXPECT_NEAR(glm::length(g.normal[i]), 1.f, 1e-5f);
            EXPECT_GT(glm::dot(g.normal[i], p), 0.99f);
            EXPECT_GT(glm::dot(g.normal[i], glm::normalize(vec3(distance, 0.f, 0.f) - p)), -0.06f);  // front side
            // The interpolated position projects onto the pixel centre (perspective-correct),
            // and its depth is the stored depth (screen-linear depth over a planar triangle).
            const vec2 wpos = window_of(cam, p);
            EXPECT_NEAR(wpos.x, x + 0.5f, 0.02f);
            EXPECT_NEAR(wpos.y, 511 - row + 0.5f, 0.02f);
            const vec4 c = clip_from_world * vec4(p, 1.f);
            EXPECT_NEAR((c.z / c.w + 1.f) * 0.5f, g.depth[i], 2e-6f);
        }
}

TEST(Raster, DepthTestKeepsTheNearerPlane) {
    const TriMesh plane = make_primitive(Primitive::Plane, 3);
    const RasterCamera cam = perspective_camera(64, 64, vec3(0.f, -1.f, 5.f), vec3(0.f), 50.f, 0.1f, 20.f);
    // Camera looks down from z=5; a plane at z=0.5 (id 2, nearer) half covers one at z=0 (id 1).
    const mat4 low(1.f);
    const mat4 high = glm::translate(mat4(1.f), vec3(1.f, 0.f, 0.5f));
    for (bool near_first : {false, true}) {
        std::vector<DrawItem> items{DrawItem{&plane, low, 1}, DrawItem{&plane, high, 2}};
        if (near_first) std::swap(items[0], items[1]);
        GBuffer g;
        rasterize(items, cam, g);
        size_t near_count = 0, far_count = 0;
        for (int row = 0; row < 64; ++row)
            for (int x = 0; x < 64; ++x) {
                const size_t i = g.index(x, row);
                if (g.object[i] < 0) continue;
                const vec3 p = g.position[i];
                // Where the high plane can be seen (its footprint), it must win.
                glm::dvec3 o, d;
                pixel_ray(cam, x, row, o, d);
                const glm::dvec3 hit = o + d * ((0.5 - o.z) / d.z);
                const bool on_high = hit.x > 0.0 && hit.x < 2.0 && std::abs(hit.y) < 1.0;
                if (std::abs(hit.x) < 1e-2 || std::abs(hit.x - 2.0) < 1e-2 || std::abs(std::abs(hit.y) - 1.0) < 1e-2) continue;
                if (on_high) {
                    EXPECT_EQ(g.object[i], 2) << x << "," << row;
                    EXPECT_NEAR(p.z, 0.5f, 1e-5f);
                    ++near_count;
                } else {
                    EXPECT_EQ(g.object[i], 1) << x << "," << row;
                    EXPECT_NEAR(p.z, 0.f, 1e-5f);
                    ++far_count;
                }
            }
        EXPECT_GT(near_count, size_t(200));
        EXPECT_GT(far_count, size_t(200));
    }
}

TEST(Raster, NearPlaneCrossingProducesNoNaN) {
    // A large ground plane under the camera (many triangles cross the near plane and lie
    // partly behind the camera) and a sphere around the camera (every pixel covered).
    TriMesh ground = make_primitive(Primitive::Plane, 16);
    transform_mesh(ground, 50.f, vec3(0.f));
    const RasterCamera cam = perspective_camera(160, 120, vec3(0.f, 0.f, 1.f), vec3(0.f, 10.f, 0.9f), 70.f, 0.05f, 200.f);
    const GBuffer g = render(ground, cam);
    ASSERT_TRUE(all_finite(g));
    size_t lower_half = 0;
    for (int row = 0; row < 120; ++row)
        for (int x = 0; x < 160; ++x) {
            const size_t i = g.index(x, row);
            if (row >= 64) {
                EXPECT_GE(g.object[i], 0) << x << "," << row;  // below the horizon: ground
                ++lower_half;
            }
            if (g.object[i] >= 0) {
                EXPECT_NEAR(g.position[i].z, 0.f, 1e-4f);
                EXPECT_NEAR(g.normal[i].z, 1.f, 1e-6f);
                EXPECT_GT(g.position[i].y, 0.f);  // in front of the camera only
                // Perspective-correct through the clipped vertices: the point is on the pixel's ray.
                const vec2 wpos = window_of(cam, g.position[i]);
                EXPECT_NEAR(wpos.x, x + 0.5f, 0.05f) << x << "," << row;
                EXPECT_NEAR(wpos.y, 119 - row + 0.5f, 0.05f) << x << "," << row;
            }
        }
    EXPECT_GT(lower_half, 0u);

    const TriMesh sphere = make_primitive(Primitive::Sphere, 24);
    for (vec3 eye : {vec3(0.f), vec3(0.3f, -1.2f, 0.4f)}) {
        const RasterCamera inside = perspective_camera(80, 60, eye, eye + vec3(0.3f, 1.f, -0.2f), 90.f, 0.01f, 10.f);
        const GBuffer s = render(sphere, inside, glm::scale(mat4(1.f), vec3(2.f)));
        ASSERT_TRUE(all_finite(s));
        EXPECT_EQ(covered(s), size_t(80 * 60));
        for (size_t i = 0; i < s.position.size(); ++i) EXPECT_NEAR(glm::length(s.position[i]), 2.f, 0.05f);
    }

    // A triangle with one vertex behind the camera and one beside it, before the near plane.
    const RasterCamera c2 = perspective_camera(40, 40, vec3(0.f), vec3(0.f, 1.f, 0.f), 60.f, 0.1f, 10.f);
    const TriMesh tri = soup({vec3(0.2f, 0.f, -0.3f), vec3(-1.f, 5.f, -1.f), vec3(1.f, -5.f, -0.5f)}, {0, 1, 2});
    const GBuffer t = render(tri, c2);
    EXPECT_TRUE(all_finite(t));
    EXPECT_GT(covered(t), 0u);
}

TEST(Raster, FarPlaneClipsLikeGL) {
    // A plane tilted away from the camera, partly beyond the far plane: what lies beyond it is
    // clipped (GL without depth clamp), what lies before it is drawn.
    TriMesh plane = make_primitive(Primitive::Plane, 4);
    transform_mesh(plane, 3.f, vec3(0.f));
    const vec3 eye(0.f, -4.f, 3.f), target(0.f);
    const float far = 5.5f;
    const RasterCamera cam = perspective_camera(64, 64, eye, target, 60.f, 0.1f, far);
    const GBuffer g = render(plane, cam);
    ASSERT_TRUE(all_finite(g));
    const glm::dvec3 forward = glm::normalize(glm::dvec3(target - eye));
    size_t drawn = 0, clipped = 0;
    for (int row = 0; row < 64; ++row)
        for (int x = 0; x < 64; ++x) {
            const size_t i = g.index(x, row);
            glm::dvec3 o, d;
            pixel_ray(cam, x, row, o, d);
            const glm::dvec3 hit = o + d * (-o.z / d.z);
            const double view_depth = glm::dot(hit - glm::dvec3(eye), forward);
            if (std::abs(hit.x) > 2.95 || std::abs(hit.y) > 2.95 || std::abs(view_depth - far) < 0.02) continue;
            if (view_depth < far) {
                EXPECT_GE(g.object[i], 0) << x << "," << row;
                ++drawn;
            } else {
                EXPECT_EQ(g.object[i], -1) << x << "," << row;
                ++clipped;
            }
        }
    EXPECT_GT(drawn, size_t(200));
    EXPECT_GT(clipped, size_t(50));
}

TEST(Raster, ModelMatrixTransformsNormalsAndTangents) {
    const TriMesh plane = make_primitive(Primitive::Plane, 3);
    // Non-uniform scale then rotation: normals use the inverse transpose.
    const mat4 model = glm::rotate(mat4(1.f), 0.6f, vec3(1.f, 0.f, 0.f)) * glm::scale(mat4(1.f), vec3(3.f, 1.f, 0.5f));
    const RasterCamera cam = perspective_camera(64, 64, vec3(0.f, -4.f, 6.f), vec3(0.f), 60.f);
    const GBuffer g = render(plane, cam, model);
    // Independent of the inverse transpose: the transformed plane is spanned by the images of its
    // two tangent directions, and its normal is their cross product.
    const vec3 t = glm::normalize(mat3(model) * vec3(1.f, 0.f, 0.f));
    const vec3 n = glm::normalize(glm::cross(mat3(model) * vec3(1.f, 0.f, 0.f), mat3(model) * vec3(0.f, 1.f, 0.f)));
    ASSERT_GT(covered(g), 100u);
    for (size_t i = 0; i < g.object.size(); ++i)
        if (g.object[i] >= 0) {
            EXPECT_NEAR(glm::distance(g.normal[i], n), 0.f, 1e-5f);
            EXPECT_NEAR(glm::distance(g.tangent[i], t), 0.f, 1e-5f);
        }
}

TEST(Raster, MissingTangentsStayZeroAndEmptySceneIsClear) {
    TriMesh plane = make_primitive(Primitive::Plane, 3);
    plane.tangent.clear();
    RasterCamera cam = identity_camera(16, 8);
    cam.texture_space = true;
    GBuffer g = render(plane, cam);
    EXPECT_EQ(covered(g), size_t(16 * 8));
    for (const vec3& t : g.tangent) EXPECT_EQ(t, vec3(0.f));

    rasterize({}, cam, g);  // reuses and clears the buffers
    EXPECT_EQ(covered(g), 0u);
    for (size_t i = 0; i < g.depth.size(); ++i) {
        EXPECT_EQ(g.depth[i], 1.f);
        EXPECT_EQ(g.object[i], -1);
        EXPECT_EQ(g.normal[i], vec3(0.f));
    }
}

TEST(Raster, ReusedGBufferEqualsAFreshOne) {
    // An interactive caller renders every frame into the same G-buffer: after a frame of another
    // size and scene, a 512x512 render of a 128x64 sphere must equal the one into a fresh buffer,
    // attribute for attribute (uv derivatives included) and bit for bit (nothing of the earlier
    // frames is left over).
    const TriMesh sphere = make_primitive(Primitive::Sphere, 128), torus = make_primitive(Primitive::Torus, 32);
    const RasterCamera cam = perspective_camera(512, 512, vec3(3.f, 0.f, 0.f), vec3(0.f), 40.f);
    GBuffer fresh;
    rasterize({DrawItem{&sphere, mat4(1.f), 0, true}}, cam, fresh);
    GBuffer g;
    rasterize({DrawItem{&torus, glm::translate(mat4(1.f), vec3(0.f, 0.6f, 0.f)), 5, true}}, perspective_camera(700, 300, vec3(0.f, -4.f, 1.f), vec3(0.f)), g);
    ASSERT_GT(covered(g), 0u);
    rasterize({DrawItem{&sphere, mat4(1.f), 0}}, cam, g);
    EXPECT_TRUE(g.uv_dx.empty() && g.uv_dy.empty());  // no item asked for them
    rasterize({DrawItem{&sphere, mat4(1.f), 0, true}}, cam, g);
    ASSERT_EQ(g.width, fresh.width);
    ASSERT_EQ(g.height, fresh.height);
    ASSERT_GT(covered(fresh), 0u);
    EXPECT_TRUE(g.object == fresh.object);
    EXPECT_TRUE(g.depth == fresh.depth);
    EXPECT_TRUE(g.position == fresh.position);
    EXPECT_TRUE(g.normal == fresh.normal);
    EXPECT_TRUE(g.tangent == fresh.tangent);
    EXPECT_TRUE(g.uv == fresh.uv);
    EXPECT_TRUE(g.uv_dx == fresh.uv_dx);
    EXPECT_TRUE(g.uv_dy == fresh.uv_dy);
}

// uv_dx and uv_dy are OpenGL's fine derivatives: differences across the pixel's 2 x 2 quad,
// aligned to even columns and rows of GL's window (y up: with an odd height, image rows pair
// differently from GL rows), both pixels on the pixel's own triangle extended past its edges.
// A fold of two planes in strong perspective (uv = xy on both): the expected differences come
// from the pixel rays through the quad's two pixel centres, met by the plane of the pixel's own
// triangle. Neighbours in the image rather than in the quad, or on the other plane, differ by
// more than the tolerance (checked, so that the test tells the rules apart).
TEST(Raster, UvDerivativesAreThoseOfTheQuadOnThePixelsOwnTriangle) {
    // z = 0 for x <= 0, z = 0.8 x for x >= 0, over [-2, 2] x [0, 6], 1 x 3 quads per plane.
    std::vector<vec3> pos;
    std::vector<uint32_t> idx;
    auto z_of = [](float x) { return x > 0.f ? 0.8f * x : 0.f; };
    const int nx = 2, ny = 3;
    for (int j = 0; j <= ny; ++j)
        for (int i = 0; i <= nx; ++i) {
            const float x = -2.f + 4.f * float(i) / float(nx), y = 6.f * float(j) / float(ny);
            pos.push_back(vec3(x, y, z_of(x)));
        }
    for (int j = 0; j < ny; ++j)
        for (int i = 0; i < nx; ++i) {
            const uint32_t a = uint32_t(j * (nx + 1) + i), b = a + 1, c = a + uint32_t(nx + 1), d = c + 1;
            idx.insert(idx.end(), {a, b, d, a, d, c});
        }
    const TriMesh fold = soup(pos, idx);
    const int W = 96, H = 63;  // an odd height
    const RasterCamera cam = perspective_camera(W, H, vec3(0.3f, -2.f, 3.f), vec3(0.f, 3.f, 0.f), 60.f, 0.1f, 100.f);
    GBuffer g;
    rasterize({DrawItem{&fold, mat4(1.f), 1, true}}, cam, g);
    ASSERT_EQ(g.uv_dx.size(), g.uv.size());
    // uv where the ray through pixel (x, row) meets the plane of the side `right` (x > 0).
    auto uv_on = [&](int x, int row, bool right) {
        glm::dvec3 o, d;
        pixel_ray(cam, x, row, o, d);
        const glm::dvec3 n = right ? glm::dvec3(-0.8, 0.0, 1.0) : glm::dvec3(0.0, 0.0, 1.0);  // planes through the origin
        const double t = -glm::dot(n, o) / glm::dot(n, d);
        const glm::dvec3 hit = o + d * t;
        return glm::dvec2(hit.x, hit.y);
    };
    size_t checked = 0, fold_quads = 0, other_rule_off = 0;
    for (int row = 0; row < H; ++row)
        for (int x = 0; x < W; ++x) {
            const size_t i = g.index(x, row);
            if (g.object[i] < 0) continue;
            const bool right = g.position[i].x > 0.f;
            if (std::fabs(g.position[i].x) < 1e-3f) continue;  // on the fold itself
            const int gy = H - 1 - row;                       // GL window row
            const int xl = x & ~1, gl = gy & ~1;              // the quad's left column and lower GL row
            const glm::dvec2 dx = uv_on(xl + 1, row, right) - uv_on(xl, row, right);
            const glm::dvec2 dy = uv_on(x, H - 1 - (gl + 1), right) - uv_on(x, H - 1 - gl, right);
            // Window positions snap to 1/256 pixel: 5e-4 of the differences here.
            const double tol = 2e-3 * std::max(glm::length(dx), glm::length(dy));
            ASSERT_NEAR(g.uv_dx[i].x, dx.x, tol) << x << "," << row;
            ASSERT_NEAR(g.uv_dx[i].y, dx.y, tol) << x << "," << row;
            ASSERT_NEAR(g.uv_dy[i].x, dy.x, tol) << x << "," << row;
            ASSERT_NEAR(g.uv_dy[i].y, dy.y, tol) << x << "," << row;
            ++checked;
            // The rules this is not: the image rows' pairs, and the other plane across the fold.
            if (row + 1 < H && (row & 1) == 0 && gy - 1 != gl) {
                const glm::dvec2 image_pair = uv_on(x, row, right) - uv_on(x, row + 1, right);
                other_rule_off += glm::length(image_pair - dy) > 2.0 * tol;
            }
            const int xo = x ^ 1;
            if (xo < W && g.object[g.index(xo, row)] >= 0 && (g.position[g.index(xo, row)].x > 0.f) != right) {
                ++fold_quads;
                const glm::dvec2 across = xo > x ? uv_on(xo, row, !right) - uv_on(x, row, right) : uv_on(x, row, right) - uv_on(xo, row, !right);
                other_rule_off += glm::length(across - dx) > 2.0 * tol;
            }
        }
    EXPECT_GT(checked, size_t(1500));
    EXPECT_GT(fold_quads, size_t(10));
    EXPECT_GT(other_rule_off, checked / 3);
}

// [SECTION] Mesh files
TEST(LoadMesh, ObjWithoutNormalsOrUv) {
    TempDir dir;
    const std::string path = dir.write("quad.obj",
                                       "# quad and a degenerate triangle\n"
                                       "v 0 0 0\nv 2 0 0\nv 2 1 0\nv 0 1 0\nv 4 0 0\nv 5 0 0\nv 6 0 0\n"
                                       "f 1 2 3 4\nf 5 6 7\n");
    const TriMesh m = load_mesh(path);
    EXPECT_FALSE(m.has_uv);
    EXPECT_EQ(m.triangle_count(), 3u);
    ASSERT_EQ(m.vertex_count(), 7u);
    EXPECT_EQ(m.uv.size(), m.vertex_count());
    EXPECT_EQ(m.tangent.size(), m.vertex_count());
    for (size_t v = 0; v < m.vertex_count(); ++v) {
        EXPECT_NEAR(glm::length(m.normal[v]), 1.f, 1e-6f);
        EXPECT_NEAR(glm::length(m.tangent[v]), 1.f, 1e-6f);
        EXPECT_NEAR(glm::dot(m.normal[v], m.tangent[v]), 0.f, 1e-6f);
        if (m.position[v].x <= 2.f) { EXPECT_EQ(m.normal[v], vec3(0.f, 0.f, 1.f)); }  // counter-clockwise quad
    }
    const Bounds b = bounds(m);
    EXPECT_EQ(b.lo, vec3(0.f));
    EXPECT_EQ(b.hi, vec3(6.f, 1.f, 0.f));
}

TEST(LoadMesh, ObjWithNormalsAndUvSeams) {
    TempDir dir;
    // Two triangles sharing the edge 1-3, with different uvs on each side of it (a seam), and a
    // normal given in the file (not the geometric one).
    const std::string path = dir.write("seam.obj",
                                       "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n"
                                       "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvt 0.5 0.5\n"
                                       "vn 0 1 1\n"
                                       "f 1/1/1 2/2/1 3/3/1\n"
                                       "f 1/5/1 3/3/1 4/4/1\n");
    const TriMesh m = load_mesh(path);
    EXPECT_TRUE(m.has_uv);
    EXPECT_EQ(m.triangle_count(), 2u);
    EXPECT_EQ(m.vertex_count(), 5u);  // vertex 1 is split by its two uvs
    const vec3 n = glm::normalize(vec3(0.f, 1.f, 1.f));
    for (size_t v = 0; v < m.vertex_count(); ++v) {
        EXPECT_NEAR(glm::distance(m.normal[v], n), 0.f, 1e-6f);
        EXPECT_NEAR(glm::length(m.tangent[v]), 1.f, 1e-6f);
        EXPECT_NEAR(glm::dot(m.normal[v], m.tangent[v]), 0.f, 1e-6f);
    }
    // Corner uvs as written.
    for (size_t t = 0; t < m.triangle_count(); ++t)
        for (int k = 0; k < 3; ++k) {
            const uint32_t i = m.index[3 * t + size_t(k)];
            const vec3 p = m.position[i];
            if (t == 0) { EXPECT_EQ(m.uv[i], vec2(p.x, p.y)); }
            if (t == 1 && p == vec3(0.f)) { EXPECT_EQ(m.uv[i], vec2(0.5f, 0.5f)); }
        }
    // First triangle: uv = xy, so dP/du = +x, orthogonalised against n.
    const uint32_t i0 = m.index[0];
    EXPECT_GT(m.tangent[i0].x, 0.99f);
}

TEST(LoadMesh, NonManifoldFacesKeepTheirCornerData) {
    // The second face runs the shared edge 1->2 in the same direction as the first one, so
    // OpenMesh adds it on copies of its vertices (and misplaces its face uvs); the corner
    // uvs and normals of the file must survive, on the file's vertices.
    TempDir dir;
    const std::string path = dir.write("flipped.obj",
                                       "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 -1 0\n"
                                       "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 -1\n"
                                       "vn 0 0 1\n"
                                       "f 1/1/1 2/2/1 3/3/1\nf 1/1/1 2/2/1 4/4/1\n");
    const TriMesh m = load_mesh(path);
    EXPECT_EQ(m.triangle_count(), 2u);
    EXPECT_EQ(m.vertex_count(), 4u);
    for (size_t i = 0; i < m.vertex_count(); ++i) {
        EXPECT_EQ(m.uv[i], vec2(m.position[i].x, m.position[i].y)) << i;
        EXPECT_EQ(m.normal[i], vec3(0.f, 0.f, 1.f)) << i;
    }
}

TEST(LoadMesh, PolygonsOffAndPly) {
    TempDir dir;
    const std::string obj = dir.write("pentagon.obj", "v 0 0 0\nv 1 0 0\nv 1.5 1 0\nv 0.5 2 0\nv -0.5 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0.5 1\nvt 0 1\nf 1/1 2/2 3/3 4/4 5/5\n");
    const TriMesh pentagon = load_mesh(obj);
    EXPECT_EQ(pentagon.triangle_count(), 3u);
    EXPECT_TRUE(pentagon.has_uv);
    EXPECT_NEAR(surface_area(pentagon), 2.5, 1e-6);

    const std::string off = dir.write("tetra.off", "OFF\n4 4 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n");
    const TriMesh tetra = load_mesh(off);
    EXPECT_EQ(tetra.triangle_count(), 4u);
    EXPECT_EQ(tetra.vertex_count(), 4u);
    const vec3 centre(0.25f);
    for (size_t v = 0; v < tetra.vertex_count(); ++v) EXPECT_GT(glm::dot(tetra.normal[v], tetra.position[v] - centre), 0.f);

    const std::string ply = dir.write("tri.ply",
                                      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                                      "property float z\nelement face 1\nproperty list uchar int vertex_indices\n"
                                      "end_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
    const TriMesh tri = load_mesh(ply);
    EXPECT_EQ(tri.triangle_count(), 1u);
    EXPECT_EQ(tri.normal[0], vec3(0.f, 0.f, 1.f));
}

TEST(LoadMesh, ErrorsNameTheFile) {
    TempDir dir;
    auto expect_error = [](const std::string& path, const std::string& phrase) {
        try {
            load_mesh(path);
            ADD_FAILURE() << path << " loaded";
        } catch (const InputError& e) {
            const std::string what = e.what();
            EXPECT_EQ(what.rfind(path + ": ", 0), 0u) << what;
            EXPECT_NE(what.find(phrase), std::string::npos) << what;
        }
    };
    expect_error((dir.path / "missing.obj").string(), "no such file");
    expect_error(dir.write("model.xyz", "v 0 0 0\n"), "could not be read as a mesh (OBJ, OFF, PLY, STL, OM expected)");
    expect_error(dir.write("broken.ply", "this is not a ply file\n\x01\x02"), "could not be read as a mesh");
    expect_error(dir.path.string(), "could not be read as a mesh");
    expect_error(dir.write("points.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\n"), "mesh has no triangles");
    expect_error(dir.write("empty.obj", ""), "mesh has no triangles");
    expect_error(dir.write("nan.obj", "v 0 0 0\nv 1 0 0\nv nan 1 0\nf 1 2 3\n"), "vertex 2 has a non-finite coordinate");
    expect_error(dir.write("inf.obj", "v 0 0 0\nv 1e39 0 0\nv 0 1 0\nf 1 2 3\n"), "vertex 1 has a non-finite coordinate");
    // Binary PLY carries the NaN through OpenMesh's reader.
    std::string ply = "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                      "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n";
    const float xyz[9] = {0.f, 0.f, 0.f, 1.f, 0.f, 0.f, 0.f, std::numeric_limits<float>::quiet_NaN(), 0.f};
    ply.append(reinterpret_cast<const char*>(xyz), sizeof xyz);
    const unsigned char count = 3;
    const int32_t face[3] = {0, 1, 2};
    ply.append(reinterpret_cast<const char*>(&count), 1);
    ply.append(reinterpret_cast<const char*>(face), sizeof face);
    expect_error(dir.write("nan.ply", ply), "vertex 2 has a non-finite coordinate");
}

TEST(LoadMesh, RendersLikeTheSameProceduralTriangles) {
    // A loaded OBJ quad and the equivalent plane produce the same texture-mode G-buffer.
    TempDir dir;
    const std::string path = dir.write("plane.obj", "v -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n"
                                                    "f 1/1 2/2 3/3\nf 1/1 3/3 4/4\n");
    const TriMesh loaded = load_mesh(path);
    const TriMesh plane = make_primitive(Primitive::Plane, 3);
    RasterCamera cam = identity_camera(30, 30);
    cam.texture_space = true;
    const GBuffer a = render(loaded, cam), b = render(plane, cam);
    ASSERT_EQ(covered(a), size_t(900));
    for (size_t i = 0; i < a.uv.size(); ++i) {
        EXPECT_NEAR(glm::distance(a.uv[i], b.uv[i]), 0.f, 1e-5f);
        EXPECT_NEAR(glm::distance(a.position[i], b.position[i]), 0.f, 2e-5f);
        EXPECT_NEAR(glm::distance(a.normal[i], b.normal[i]), 0.f, 1e-6f);
        EXPECT_NEAR(glm::distance(a.tangent[i], b.tangent[i]), 0.f, 1e-5f);
    }
}

// [SECTION] Key suggestions
TEST(NearestKey, LevenshteinCaseInsensitiveWithThreshold) {
    const std::vector<std::string> keys{"geometry.resolution", "geometry.type", "camera.distance", "basic.kd"};
    EXPECT_EQ(nearest_key("geometry.resolutoin", keys), "geometry.resolution");
    EXPECT_EQ(nearest_key("GEOMETRY.TYPE", keys), "geometry.type");
    EXPECT_EQ(nearest_key("basic.ks", keys), "basic.kd");
    EXPECT_EQ(nearest_key("lights", keys), "");
    EXPECT_EQ(nearest_key("x", {}), "");
    // Threshold max(2, size/3): "kd" -> "ks" (1) and "abcd" -> "ab" (2) suggest, 3 edits do not.
    EXPECT_EQ(nearest_key("abcd", {"ab"}), "ab");
    EXPECT_EQ(nearest_key("abcd", {"a"}), "");
    // 12 characters allow 4 edits, not 5.
    EXPECT_EQ(nearest_key("abcdefghijkl", {"abcdefghWXYZ"}), "abcdefghWXYZ");
    EXPECT_EQ(nearest_key("abcdefghijkl", {"abcdefgVWXYZ"}), "");
    // Ties go to the first candidate.
    EXPECT_EQ(nearest_key("cat", {"bat", "cut", "car"}), "bat");
}
