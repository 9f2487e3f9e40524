// Mesh preparation for translucency: weld, clean, keep manifold, decimate (see mesh_prep.h).
#include "core/translucency/mesh_prep.h"
#include "core/error.h"

// OpenMesh's property vectors push back uninitialised VectorT values (see core/mesh.cpp).
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>
#include <OpenMesh/Tools/Decimater/DecimaterT.hh>
#include <OpenMesh/Tools/Decimater/ModAspectRatioT.hh>
#include <OpenMesh/Tools/Decimater/ModNormalFlippingT.hh>
#include <OpenMesh/Tools/Decimater/ModQuadricT.hh>
#pragma GCC diagnostic pop

#include <algorithm>
#include <array>
#include <cmath>
#include <iostream>
#include <set>
#include <unordered_map>

namespace mesolab::translucency {

namespace {
using OmMesh = OpenMesh::TriMesh_ArrayKernelT<>;
}

namespace {
// Position of a point along a 3D Hilbert curve of 2^bits cells per side (Skilling 2004,
// "Programming the Hilbert curve": axes to transposed index, then its bits interleaved).
uint64_t hilbert_index(std::array<uint32_t, 3> x, int bits) {
    const uint32_t top = 1u << (bits - 1);
    for (uint32_t q = top; q > 1; q >>= 1) {  // inverse undo of the excess work
        const uint32_t p = q - 1;
        for (int i = 0; i < 3; ++i) {
            if (x[size_t(i)] & q) x[0] ^= p;
            else {
                const uint32_t t = (x[0] ^ x[size_t(i)]) & p;
                x[0] ^= t, x[size_t(i)] ^= t;
            }
        }
    }
    for (int i = 1; i < 3; ++i) x[size_t(i)] ^= x[size_t(i - 1)];  // Gray encode
    uint32_t t = 0;
    for (uint32_t q = top; q > 1; q >>= 1)
        if (x[2] & q) t ^= q - 1;
    for (uint32_t& v : x) v ^= t;
    uint64_t h = 0;
    for (int b = bits - 1; b >= 0; --b)
        for (int i = 0; i < 3; ++i) h = (h << 1) | ((x[size_t(i)] >> b) & 1u);
    return h;
}

// Vertices renumbered in the order of a Hilbert curve through their positions: a vertex's
// neighbours on the surface get nearby numbers, so the factors of one row (the vertices within
// the dipole's reach) form long runs of consecutive columns and the product reads E and writes
// B in cache lines it has just used.
void reorder_along_hilbert_curve(PreparedMesh& m) {
    const size_t n = m.position.size();
    if (n < 2) return;
    vec3 lo(INFINITY), hi(-INFINITY);
    for (const vec3& p : m.position) lo = glm::min(lo, p), hi = glm::max(hi, p);
    const float extent = std::max({hi.x - lo.x, hi.y - lo.y, hi.z - lo.z});
    if (!(extent > 0.f) || !std::isfinite(extent)) return;
    constexpr int kBits = 16;
    const float cells = float((1u << kBits) - 1) / extent;
    std::vector<std::pair<uint64_t, uint32_t>> key(n);
    for (size_t i = 0; i < n; ++i) {
        const vec3 q = (m.position[i] - lo) * cells;
        key[i] = {hilbert_index({uint32_t(q.x), uint32_t(q.y), uint32_t(q.z)}, kBits), uint32_t(i)};
    }
    std::sort(key.begin(), key.end());
    std::vector<uint32_t> new_of(n);
    std::vector<vec3> position(n), normal(n);
    for (size_t k = 0; k < n; ++k) {
        const uint32_t old = key[k].second;
        new_of[old] = uint32_t(k);
        position[k] = m.position[old];
        normal[k] = m.normal[old];
    }
    m.position = std::move(position), m.normal = std::move(normal);
    for (uint32_t& v : m.index) v = new_of[v];
}
}  // namespace

PreparedMesh prepare_mesh(const std::vector<vec3>& position, const std::vector<uint32_t>& index, int target_vertices,
                          const std::vector<vec2>* uv) {
    if (target_vertices < 0) throw InputError("translucency.vertices: " + std::to_string(target_vertices) + " must be >= 0 (0 keeps every vertex)");
    PreparedMesh out;

    // [SECTION] Weld: a grid of cells of the tolerance; a vertex joins the first vertex within
    // the tolerance in its cell or the neighbouring ones.
    vec3 lo(INFINITY), hi(-INFINITY);
    for (const vec3& p : position)
        if (std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z)) lo = glm::min(lo, p), hi = glm::max(hi, p);
    const float diag = glm::length(hi - lo);
    const float tol = std::isfinite(diag) && diag > 0.f ? 1e-6f * diag : 1e-12f;
    std::unordered_map<uint64_t, std::vector<uint32_t>> cells;
    std::vector<uint32_t> remap(position.size(), UINT32_MAX);
    std::vector<vec3> welded;
    const auto cell_key = [](int64_t x, int64_t y, int64_t z) {
        return uint64_t((x * 73856093) ^ (y * 19349663) ^ (z * 83492791));
    };
    for (size_t v = 0; v < position.size(); ++v) {
        const vec3 p = position[v];
        if (!(std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z))) continue;
        const glm::i64vec3 c(glm::floor((p - lo) / tol));
        uint32_t found = UINT32_MAX;
        for (int dz = -1; dz <= 1 && found == UINT32_MAX; ++dz)
            for (int dy = -1; dy <= 1 && found == UINT32_MAX; ++dy)
                for (int dx = -1; dx <= 1 && found == UINT32_MAX; ++dx) {
                    const auto it = cells.find(cell_key(c.x + dx, c.y + dy, c.z + dz));
                    if (it == cells.end()) continue;
                    for (uint32_t w : it->second)
                        if (glm::length(welded[w] - p) <= tol) {
                            found = w;
                            break;
                        }
                }
        if (found == UINT32_MAX) {
            found = uint32_t(welded.size());
            welded.push_back(p);
            cells[cell_key(c.x, c.y, c.z)].push_back(found);
        } else {
            ++out.welded_vertices;
        }
        remap[v] = found;
    }
    // Texture coordinates of each welded vertex (several where a seam was welded).
    const bool with_uv = uv && uv->size() == position.size();
    std::vector<std::vector<vec2>> welded_uv(with_uv ? welded.size() : 0);
    if (with_uv)
        for (size_t v = 0; v < position.size(); ++v) {
            if (remap[v] == UINT32_MAX) continue;
            auto& c = welded_uv[remap[v]];
            const vec2 t = (*uv)[v];
            if (std::find(c.begin(), c.end(), t) == c.end()) c.push_back(t);
        }

    // [SECTION] Clean: degenerate and duplicate triangles
    std::vector<std::array<uint32_t, 3>> tris;
    std::set<std::array<uint32_t, 3>> seen;
    for (size_t f = 0; f + 2 < index.size(); f += 3) {
        std::array<uint32_t, 3> t{};
        bool ok = true;
        for (int j = 0; j < 3; ++j) {
            const uint32_t i = index[f + size_t(j)];
            ok = ok && i < remap.size() && remap[i] != UINT32_MAX;
            t[size_t(j)] = ok ? remap[i] : 0;
        }
        if (ok) ok = t[0] != t[1] && t[1] != t[2] && t[0] != t[2];
        if (ok) {
            const vec3 n = glm::cross(welded[t[1]] - welded[t[0]], welded[t[2]] - welded[t[0]]);
            ok = glm::length(n) > 1e-12f * diag * diag;
        }
        if (ok) {
            std::array<uint32_t, 3> key = t;
            std::sort(key.begin(), key.end());
            ok = seen.insert(key).second;
        }
        if (ok) tris.push_back(t);
        else ++out.removed_triangles;
    }
    if (tris.empty()) throw InputError("translucency: the mesh has no triangle left after removing " + std::to_string(out.removed_triangles) + " degenerate ones");

    // [SECTION] Manifold: OpenMesh refuses a face that would make an edge or vertex non-manifold;
    // such a face is added with its own copies of its corners.
    OmMesh m;
    OpenMesh::VPropHandleT<int> source;  // the welded vertex an OpenMesh vertex stands for
    m.add_property(source);
    std::vector<OmMesh::VertexHandle> vh(welded.size());
    for (size_t v = 0; v < welded.size(); ++v) {
        vh[v] = m.add_vertex(OmMesh::Point(welded[v].x, welded[v].y, welded[v].z));
        m.property(source, vh[v]) = int(v);
    }
    for (const auto& t : tris) {
        OmMesh::FaceHandle fh;
        {
            // OpenMesh reports a complex edge or vertex on std::cerr; the count below says it once.
            const std::vector<OmMesh::VertexHandle> c{vh[t[0]], vh[t[1]], vh[t[2]]};
            std::streambuf* old = std::cerr.rdbuf(nullptr);
            fh = m.add_face(c);
            std::cerr.rdbuf(old);
        }
        if (!fh.is_valid()) {
            std::vector<OmMesh::VertexHandle> c;
            for (uint32_t i : t) {
                c.push_back(m.add_vertex(OmMesh::Point(welded[i].x, welded[i].y, welded[i].z)));
                m.property(source, c.back()) = int(i);
            }
            m.add_face(c);
            ++out.detached_triangles;
        }
    }
    // Unused vertices (welded away from every kept triangle) go.
    m.request_vertex_status();
    m.request_edge_status();
    m.request_face_status();
    for (const auto& v : m.vertices())
        if (m.is_isolated(v)) m.delete_vertex(v, false);
    m.garbage_collection();
    out.input_vertices = int(m.n_vertices());

    // [SECTION] Decimate
    if (target_vertices > 0 && size_t(target_vertices) < m.n_vertices()) {
        m.request_face_normals();
        m.update_face_normals();
        OpenMesh::Decimater::DecimaterT<OmMesh> dec(m);
        OpenMesh::Decimater::ModQuadricT<OmMesh>::Handle quadric;
        OpenMesh::Decimater::ModNormalFlippingT<OmMesh>::Handle flipping;
        OpenMesh::Decimater::ModAspectRatioT<OmMesh>::Handle aspect;
        dec.add(quadric);
        dec.add(flipping);
        dec.add(aspect);
        dec.module(quadric).unset_max_err();
        dec.module(flipping).set_max_normal_deviation(60.0);
        dec.module(aspect).set_aspect_ratio(6.0);
        dec.module(aspect).set_binary(true);
        dec.initialize();
        dec.decimate_to(size_t(target_vertices));
        m.garbage_collection();
        if (m.n_vertices() > size_t(target_vertices) + size_t(target_vertices) / 20 + 8)
            out.warnings.push_back("decimation stopped at " + std::to_string(m.n_vertices()) + " vertices (translucency.vertices = " +
                                   std::to_string(target_vertices) + "): further collapses would flip normals or make slivers");
    }

    // [SECTION] Arrays, normals, boundary
    out.position.resize(m.n_vertices());
    for (const auto& v : m.vertices()) {
        const OmMesh::Point p = m.point(v);
        out.position[size_t(v.idx())] = vec3(p[0], p[1], p[2]);
    }
    out.normal.assign(out.position.size(), vec3(0.f));
    for (const auto& f : m.faces()) {
        std::array<uint32_t, 3> t{};
        int j = 0;
        for (const auto& v : m.fv_range(f)) t[size_t(j++)] = uint32_t(v.idx());
        for (uint32_t i : t) out.index.push_back(i);
        const vec3 n = glm::cross(out.position[t[1]] - out.position[t[0]], out.position[t[2]] - out.position[t[0]]);  // 2 x area
        for (uint32_t i : t) out.normal[i] += n;
    }
    for (vec3& n : out.normal) n = glm::length(n) > 0.f ? glm::normalize(n) : vec3(0.f, 0.f, 1.f);
    // Corner texture coordinates: per corner, among its welded vertex's coordinates, the one
    // nearest the triangle's others (a seam vertex takes the side of the triangle it is in).
    if (with_uv) {
        out.corner_uv.resize(out.index.size());
        for (size_t f = 0; f < out.triangle_count(); ++f) {
            const std::vector<vec2>* c[3];
            for (int j = 0; j < 3; ++j) c[j] = &welded_uv[size_t(m.property(source, OmMesh::VertexHandle(int(out.index[3 * f + size_t(j)]))))];
            float best = INFINITY;
            const size_t n0 = std::min<size_t>(c[0]->size(), 16);
            for (size_t a = 0; a < n0; ++a) {
                const vec2 t0 = (*c[0])[a];
                const auto nearest = [](const std::vector<vec2>& cand, vec2 to) {
                    vec2 b = cand.empty() ? to : cand[0];
                    for (const vec2& q : cand)
                        if (glm::length(q - to) < glm::length(b - to)) b = q;
                    return b;
                };
                const vec2 t1 = nearest(*c[1], t0), t2 = nearest(*c[2], 0.5f * (t0 + t1));
                const float spread = glm::length(t1 - t0) + glm::length(t2 - t0) + glm::length(t2 - t1);
                if (spread < best) {
                    best = spread;
                    out.corner_uv[3 * f] = t0, out.corner_uv[3 * f + 1] = t1, out.corner_uv[3 * f + 2] = t2;
                }
            }
        }
    }
    for (const auto& e : m.edges()) out.boundary_edges += m.is_boundary(e) ? 1 : 0;
    reorder_along_hilbert_curve(out);
    out.corner_normal = corner_normals(out.position, out.index);

    if (out.welded_vertices > 0) out.warnings.push_back(std::to_string(out.welded_vertices) + " duplicate vertices welded");
    if (out.removed_triangles > 0) out.warnings.push_back(std::to_string(out.removed_triangles) + " degenerate or duplicate triangles removed");
    if (out.detached_triangles > 0)
        out.warnings.push_back(std::to_string(out.detached_triangles) + " triangles on non-manifold edges or vertices kept detached");
    if (out.boundary_edges > 0) out.warnings.push_back(std::to_string(out.boundary_edges) + " boundary edges (holes or open borders)");
    return out;
}

std::vector<vec3> corner_normals(const std::vector<vec3>& position, const std::vector<uint32_t>& index) {
    const size_t faces = index.size() / 3;
    std::vector<vec3> face(faces);  // 2 x area x unit normal
    std::vector<std::vector<uint32_t>> around(position.size());
    for (size_t f = 0; f < faces; ++f) {
        const vec3 a = position[index[3 * f]], b = position[index[3 * f + 1]], c = position[index[3 * f + 2]];
        face[f] = glm::cross(b - a, c - a);
        for (int k = 0; k < 3; ++k) around[index[3 * f + size_t(k)]].push_back(uint32_t(f));
    }
    const float cos_crease = std::cos(kCreaseDegrees * 3.14159265358979f / 180.f);
    std::vector<vec3> out(index.size());
    for (size_t f = 0; f < faces; ++f) {
        const float lf = glm::length(face[f]);
        const vec3 nf = lf > 0.f ? face[f] / lf : vec3(0.f);
        for (int k = 0; k < 3; ++k) {
            vec3 sum(0.f);
            for (const uint32_t g : around[index[3 * f + size_t(k)]]) {
                const float lg = glm::length(face[g]);
                if (g == f || (lf > 0.f && lg > 0.f && glm::dot(nf, face[g] / lg) >= cos_crease)) sum += face[g];
            }
            out[3 * f + size_t(k)] = glm::length(sum) > 0.f ? glm::normalize(sum) : vec3(0.f, 0.f, 1.f);
        }
    }
    return out;
}
}  // namespace mesolab::translucency
