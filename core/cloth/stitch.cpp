// Stitch micro-geometry (see stitch.h).
#include "core/cloth/stitch.h"
#include "core/parallel.h"
#include "core/cloth/marching_cubes.h"
#include "core/error.h"


#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

namespace mesolab::cloth {

vec3 Bezier::at(float t) const {
    const float s = 1.f - t;
    return s * s * s * p[0] + 3.f * s * s * t * p[1] + 3.f * s * t * t * p[2] + t * t * t * p[3];
}

const std::vector<std::string>& stitch_names() {
    static const std::vector<std::string> names = {"knit", "purl", "loops2", "weave", "twill"};
    return names;
}

namespace {
// [SECTION] Skeletons
// A Catmull–Rom spline through q (its first and last points only steer the ends) as cubic Béziers.
std::vector<Bezier> catmull_rom(const std::vector<vec3>& q) {
    std::vector<Bezier> out;
    for (size_t i = 1; i + 2 < q.size(); ++i)
        out.push_back({{q[i], q[i] + (q[i + 1] - q[i - 1]) / 6.f, q[i + 1] - (q[i + 2] - q[i]) / 6.f, q[i + 1]}});
    return out;
}

// A woven pattern from its lift plan: over[i][j] when warp i (along y) passes over weft j (along
// x); threads one spacing apart, crossing at ±r.
StitchPattern weave(const std::vector<std::vector<bool>>& over, const StitchParams& p, int copies) {
    StitchPattern s;
    const int W = int(over.size()), F = int(over[0].size());
    s.tile = vec2(float(W), float(F));
    s.radius = p.yarn_radius;
    const float a = p.yarn_radius;
    const int lo = -(copies / 2) - 1, hi = copies - copies / 2 + 1;  // tile range, one extra each side
    for (int m = lo; m < hi; ++m)
        for (int i = 0; i < W; ++i) {
            std::vector<vec3> q;
            for (int n = lo; n <= hi; ++n)
                for (int j = 0; j < F; ++j)
                    q.push_back(vec3(float(m * W + i) + 0.5f, float(n * F + j) + 0.5f, over[size_t(i)][size_t(j)] ? a : -a));
            s.yarns.push_back({catmull_rom(q), p.color_a});
        }
    for (int n = lo; n < hi; ++n)
        for (int j = 0; j < F; ++j) {
            std::vector<vec3> q;
            for (int m = lo; m <= hi; ++m)
                for (int i = 0; i < W; ++i)
                    q.push_back(vec3(float(m * W + i) + 0.5f, float(n * F + j) + 0.5f, over[size_t(i)][size_t(j)] ? -a : a));
            s.yarns.push_back({catmull_rom(q), p.color_b});
        }
    s.z_lo = -a, s.z_hi = a;
    return s;
}

// Knitted loops: per course one yarn through a loop per wale; `flip` shows the back (purl);
// `two_colours` alternates the courses' colours.
StitchPattern knit(const StitchParams& p, int copies, bool flip, bool two_colours) {
    StitchPattern s;
    const float h = p.loop_height, d = 1.1f * p.yarn_radius * (flip ? -1.f : 1.f);
    s.tile = vec2(1.f, two_colours ? 2.f * h : h);
    s.radius = p.yarn_radius;
    // One loop, x in [0, 1): up the left leg in front, over the head behind the next course's
    // legs, down the right leg in front.
    const vec3 loop[] = {{0.00f, 0.00f, 0.f}, {0.22f, 0.18f, 1.f}, {0.28f, 0.60f, 1.f},  {0.24f, 0.95f, 0.f},  {0.32f, 1.20f, -1.f},
                         {0.50f, 1.28f, -1.f}, {0.68f, 1.20f, -1.f}, {0.76f, 0.95f, 0.f}, {0.72f, 0.60f, 1.f}, {0.78f, 0.18f, 1.f}};
    const int courses_per_tile = two_colours ? 2 : 1;
    const int lo = -(copies / 2) - 1, hi = copies - copies / 2 + 1;
    for (int n = lo * courses_per_tile - 1; n < hi * courses_per_tile; ++n) {
        std::vector<vec3> q;
        for (int m = lo - 1; m <= hi; ++m)
            for (const vec3& c : loop) q.push_back(vec3(float(m) + c.x, (float(n) + c.y) * h, c.z * d));
        const bool b = two_colours && ((n % 2) + 2) % 2 == 1;
        s.yarns.push_back({catmull_rom(q), b ? p.color_b : p.color_a});
    }
    s.z_lo = -std::abs(d), s.z_hi = std::abs(d);
    return s;
}
}  // namespace

StitchPattern make_stitch(const StitchParams& p, int copies) {
    if (!(p.yarn_radius > 0.f && p.yarn_radius < 0.5f))
        throw InputError("cloth.yarn_radius: " + std::to_string(p.yarn_radius) + " must be in (0, 0.5) (units of the yarn spacing)");
    if (!(p.loop_height >= 0.5f && p.loop_height <= 3.f))
        throw InputError("cloth.loop_height: " + std::to_string(p.loop_height) + " must be in [0.5, 3] (units of the yarn spacing)");
    if (p.stitch == "knit") return knit(p, copies, false, false);
    if (p.stitch == "purl") return knit(p, copies, true, false);
    if (p.stitch == "loops2") return knit(p, copies, false, true);
    if (p.stitch == "weave") return weave({{true, false}, {false, true}}, p, copies);
    if (p.stitch == "twill") {
        std::vector<std::vector<bool>> over(3, std::vector<bool>(3));
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) over[size_t(i)][size_t(j)] = ((j - i) % 3 + 3) % 3 != 2;
        return weave(over, p, copies);
    }
    std::string list;
    for (const std::string& n : stitch_names()) list += (list.empty() ? "" : ", ") + n;
    throw InputError("cloth.stitch: \"" + p.stitch + "\" is not a stitch (" + list + ")");
}

// [SECTION] The field and its mesh
StitchMesh build_stitch_mesh(const StitchPattern& s, int cells) {
    if (cells < 8 || cells > 256) throw InputError("cloth.stitch_resolution: " + std::to_string(cells) + " must be in [8, 256] cells per tile");
    const int copies = 3;
    const float h = std::max(s.tile.x, s.tile.y) / float(cells);
    const float r = s.radius, band = r + 2.f * h;
    ScalarGrid g;
    g.h = h;
    g.origin = vec3(-s.tile.x, -s.tile.y, s.z_lo - band);
    g.n = glm::ivec3(int(std::ceil(float(copies) * s.tile.x / h)) + 1, int(std::ceil(float(copies) * s.tile.y / h)) + 1,
                     int(std::ceil((s.z_hi - s.z_lo + 2.f * band) / h)) + 1);
    const size_t N = size_t(g.n.x) * size_t(g.n.y) * size_t(g.n.z);
    g.v.assign(N, band + h);
    std::vector<int16_t> owner(N, -1);
    // Each skeleton as line pieces; each piece lowers the field in its box (one z slab per task).
    struct Piece {
        vec3 a, b;
        int yarn;
    };
    std::vector<Piece> pieces;
    for (size_t y = 0; y < s.yarns.size(); ++y)
        for (const Bezier& b : s.yarns[y].segments) {
            const int n = 16;
            for (int k = 0; k < n; ++k) pieces.push_back({b.at(float(k) / float(n)), b.at(float(k + 1) / float(n)), int(y)});
        }
    mesolab::parallel_for(0, g.n.z, [&](int kz) {
        const float z = g.origin.z + h * float(kz);
        for (const Piece& p : pieces) {
            if (z < std::min(p.a.z, p.b.z) - band || z > std::max(p.a.z, p.b.z) + band) continue;
            const vec3 lo = glm::min(p.a, p.b) - vec3(band), hi = glm::max(p.a, p.b) + vec3(band);
            const int i0 = std::max(0, int(std::floor((lo.x - g.origin.x) / h))), i1 = std::min(g.n.x - 1, int(std::ceil((hi.x - g.origin.x) / h)));
            const int j0 = std::max(0, int(std::floor((lo.y - g.origin.y) / h))), j1 = std::min(g.n.y - 1, int(std::ceil((hi.y - g.origin.y) / h)));
            const vec3 ab = p.b - p.a;
            const float len2 = std::max(glm::dot(ab, ab), 1e-20f);
            for (int j = j0; j <= j1; ++j)
                for (int i = i0; i <= i1; ++i) {
                    const vec3 x = g.point(i, j, kz);
                    const float t = std::clamp(glm::dot(x - p.a, ab) / len2, 0.f, 1.f);
                    const float f = glm::length(x - (p.a + t * ab)) - r;
                    const size_t at = g.at(i, j, kz);
                    if (f < g.v[at]) g.v[at] = f, owner[at] = int16_t(p.yarn);
                }
        }
    });
    // The grid's faces are outside, so the tubes are capped where the grid ends.
    for (int k = 0; k < g.n.z; ++k)
        for (int j = 0; j < g.n.y; ++j)
            for (int i = 0; i < g.n.x; ++i)
                if (i == 0 || j == 0 || k == 0 || i == g.n.x - 1 || j == g.n.y - 1 || k == g.n.z - 1) g.v[g.at(i, j, k)] = std::max(g.v[g.at(i, j, k)], h);
    StitchMesh out;
    out.mesh = marching_cubes(g, 0.f);
    out.tile = s.tile;
    out.lo = vec3(0.f, 0.f, s.z_lo - r);
    out.hi = vec3(s.tile.x, s.tile.y, s.z_hi + r);
    out.grid_points = int(N);
    // Colours: the yarn owning the grid point with the lowest field value around each vertex.
    out.color.resize(out.mesh.position.size());
    for (size_t v = 0; v < out.color.size(); ++v) {
        const vec3 c = (out.mesh.position[v] - g.origin) / h;
        const glm::ivec3 b = glm::clamp(glm::ivec3(glm::floor(c)), glm::ivec3(0), g.n - 2);
        float best = std::numeric_limits<float>::infinity();
        int yarn = 0;
        for (int q = 0; q < 8; ++q) {
            const size_t at = g.at(b.x + (q & 1), b.y + (q >> 1 & 1), b.z + (q >> 2 & 1));
            if (owner[at] >= 0 && g.v[at] < best) best = g.v[at], yarn = owner[at];
        }
        out.color[v] = s.yarns.empty() ? vec3(0.8f) : s.yarns[size_t(yarn)].color;
    }
    return out;
}
}  // namespace mesolab::cloth
