// Marching cubes from face segments (see marching_cubes.h).
#include "core/cloth/marching_cubes.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <unordered_map>

namespace mesolab::cloth {

namespace {
// Corner c of a cube at (i, j, k): (i + (c & 1), j + (c >> 1 & 1), k + (c >> 2 & 1)).
// The six faces, corners counter-clockwise seen from outside the cube.
constexpr int kFace[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 4, 6, 2}, {1, 3, 7, 5}, {0, 1, 5, 4}, {2, 6, 7, 3}};
// Per face: its two in-plane axes (u < v), for the decider's grid order.
constexpr int kFaceAxes[6][2] = {{0, 1}, {0, 1}, {1, 2}, {1, 2}, {0, 2}, {0, 2}};

glm::ivec3 corner_offset(int c) { return {c & 1, (c >> 1) & 1, (c >> 2) & 1}; }

// The cube edge between corners a and b (one bit apart): 0..11 as axis * 4 + the other two bits.
int edge_of(int a, int b) {
    const int d = a ^ b, axis = d == 1 ? 0 : d == 2 ? 1 : 2;
    const int lo = a & b;  // the corner with the axis bit clear
    int rest = 0, k = 0;
    for (int bit = 0; bit < 3; ++bit)
        if (bit != axis) rest |= ((lo >> bit) & 1) << k++;
    return axis * 4 + rest;
}

vec3 gradient(const ScalarGrid& g, int i, int j, int k) {
    auto at = [&](int x, int y, int z) {
        return g.value(std::clamp(x, 0, g.n.x - 1), std::clamp(y, 0, g.n.y - 1), std::clamp(z, 0, g.n.z - 1));
    };
    return vec3(at(i + 1, j, k) - at(i - 1, j, k), at(i, j + 1, k) - at(i, j - 1, k), at(i, j, k + 1) - at(i, j, k - 1));
}
}  // namespace

TriMesh marching_cubes(const ScalarGrid& g, float iso) {
    TriMesh m;
    if (g.n.x < 2 || g.n.y < 2 || g.n.z < 2) return m;
    // One vertex per grid edge that the surface crosses: key = 3 * point index + axis.
    std::unordered_map<uint64_t, uint32_t> vertex_of;
    std::vector<vec3> grad;
    auto vertex = [&](glm::ivec3 p, int axis) -> uint32_t {
        const uint64_t key = 3 * uint64_t(g.at(p.x, p.y, p.z)) + uint64_t(axis);
        auto [it, fresh] = vertex_of.try_emplace(key, uint32_t(m.position.size()));
        if (fresh) {
            glm::ivec3 q = p;
            q[axis] += 1;
            const float va = g.value(p.x, p.y, p.z), vb = g.value(q.x, q.y, q.z);
            const float t = std::clamp((iso - va) / (vb - va), 0.f, 1.f);
            m.position.push_back(glm::mix(g.point(p.x, p.y, p.z), g.point(q.x, q.y, q.z), t));
            grad.push_back(glm::mix(gradient(g, p.x, p.y, p.z), gradient(g, q.x, q.y, q.z), t));
        }
        return it->second;
    };
    for (int k = 0; k + 1 < g.n.z; ++k)
        for (int j = 0; j + 1 < g.n.y; ++j)
            for (int i = 0; i + 1 < g.n.x; ++i) {
                float val[8];
                int inside = 0;
                for (int c = 0; c < 8; ++c) {
                    const glm::ivec3 o = corner_offset(c);
                    val[c] = g.value(i + o.x, j + o.y, k + o.z);
                    inside |= (val[c] < iso ? 1 : 0) << c;
                }
                if (inside == 0 || inside == 255) continue;
                // next[e]: the edge crossing the segment leaving edge e's crossing goes to.
                std::array<int, 12> next;
                next.fill(-1);
                for (int f = 0; f < 6; ++f) {
                    const int* c = kFace[f];
                    bool in[4];
                    int n_in = 0;
                    for (int q = 0; q < 4; ++q) in[q] = (inside >> c[q]) & 1, n_in += in[q];
                    if (n_in == 0 || n_in == 4) continue;
                    // Edge q runs from corner q to corner q + 1 (counter-clockwise).
                    auto edge = [&](int q) { return edge_of(c[q & 3], c[(q + 1) & 3]); };
                    const bool alternating = n_in == 2 && in[0] == in[2];
                    bool cut_inside = true;  // cut off each inside corner (else each outside one)
                    if (alternating) {
                        // The saddle of the bilinear interpolant, from the corners in grid order.
                        const int u = kFaceAxes[f][0], w = kFaceAxes[f][1];
                        int lo = c[0];
                        for (int q = 1; q < 4; ++q) lo &= c[q];
                        const float v00 = val[lo], v10 = val[lo | 1 << u], v11 = val[lo | 1 << u | 1 << w], v01 = val[lo | 1 << w];
                        const float den = v00 + v11 - v10 - v01;
                        const float saddle = den != 0.f ? (v00 * v11 - v10 * v01) / den : 0.25f * (v00 + v10 + v11 + v01);
                        cut_inside = !(saddle < iso);
                    }
                    for (int q = 0; q < 4; ++q) {
                        const bool prev = in[(q + 3) & 3], here = in[q];
                        if (alternating) {
                            // A lone corner of the kind being cut off: the segment around it.
                            if (cut_inside && here) next[size_t(edge(q + 3))] = edge(q);
                            if (!cut_inside && !here) next[size_t(edge(q))] = edge(q + 3);
                        } else {
                            // One run of inside corners: from the edge entering it to the edge leaving it.
                            if (here && !prev) {
                                int end = q;
                                while (in[(end + 1) & 3]) ++end;
                                next[size_t(edge(q + 3))] = edge(end);
                            }
                        }
                    }
                }
                // Chain the segments into loops and fan each loop.
                std::array<bool, 12> used{};
                for (int e0 = 0; e0 < 12; ++e0) {
                    if (next[size_t(e0)] < 0 || used[size_t(e0)]) continue;
                    std::vector<uint32_t> loop;
                    for (int e = e0; e >= 0 && !used[size_t(e)]; e = next[size_t(e)]) {
                        used[size_t(e)] = true;
                        const int axis = e / 4, rest = e % 4;
                        glm::ivec3 p(i, j, k);
                        int r = 0;
                        for (int bit = 0; bit < 3; ++bit)
                            if (bit != axis) p[bit] += (rest >> r++) & 1;
                        loop.push_back(vertex(p, axis));
                    }
                    if (loop.size() == 3) {
                        m.index.insert(m.index.end(), {loop[0], loop[1], loop[2]});
                        continue;
                    }
                    // Longer loops: a fan around a vertex at their centroid. (A fan from a loop
                    // vertex would draw diagonals between crossings of one cube face, which the
                    // neighbouring cube may draw too: an edge of four triangles.)
                    vec3 c(0.f), gc(0.f);
                    for (uint32_t v : loop) c += m.position[v], gc += grad[v];
                    const uint32_t centre = uint32_t(m.position.size());
                    m.position.push_back(c / float(loop.size()));
                    grad.push_back(gc);
                    for (size_t t = 0; t < loop.size(); ++t) m.index.insert(m.index.end(), {centre, loop[t], loop[(t + 1) % loop.size()]});
                }
            }
    m.normal.resize(m.position.size());
    m.tangent.resize(m.position.size());
    for (size_t v = 0; v < m.position.size(); ++v) {
        const float len = glm::length(grad[v]);
        const vec3 n = len > 0.f ? grad[v] / len : vec3(0.f, 0.f, 1.f);
        m.normal[v] = n;
        const vec3 a = std::abs(n.x) < 0.9f ? vec3(1.f, 0.f, 0.f) : vec3(0.f, 1.f, 0.f);
        m.tangent[v] = glm::normalize(a - n * glm::dot(a, n));
    }
    return m;
}
}  // namespace mesolab::cloth
