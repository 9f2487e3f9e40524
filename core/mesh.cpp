#include "core/mesh.h"
#include "core/error.h"

// OpenMesh's property vectors push back uninitialised VectorT values (its default constructor
// leaves them unset), which GCC reports from our translation unit in optimised sanitizer builds.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#include <OpenMesh/Core/IO/MeshIO.hh>
#include <OpenMesh/Core/Mesh/PolyMesh_ArrayKernelT.hh>
#pragma GCC diagnostic pop

#include <algorithm>
#include <array>
#include <cmath>
#include <cctype>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <mutex>
#include <map>
#include <optional>

namespace mesolab {

// [SECTION] Shared helpers
namespace {

constexpr double kTwoPi = 6.283185307179586476925286766559;
constexpr double kPiD = 3.1415926535897932384626433832795;
constexpr int kMaxResolution = 16384;  // keeps vertex indices within uint32_t

bool is_finite(vec3 v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

// Tangent perpendicular to unit n (Duff et al. 2017, "Building an Orthonormal Basis, Revisited").
vec3 any_tangent(vec3 n) {
    const float sign = std::copysign(1.f, n.z);
    const float a = -1.f / (sign + n.z);
    const float b = n.x * n.y * a;
    return {1.f + sign * n.x * n.x * a, sign * b, -sign * n.x};
}

// Gram-Schmidt: t made perpendicular to unit n and normalised; any_tangent(n) when t is
// (nearly) parallel to n, zero or not finite.
vec3 orthonormal_tangent(vec3 t, vec3 n) {
    const vec3 t_perp = t - n * glm::dot(n, t);
    const float len = glm::length(t_perp);
    if (!(len > 1e-12f * std::max(1.f, glm::length(t))) || !std::isfinite(len)) return any_tangent(n);
    return t_perp / len;
}

// Unit n, or `fallback` when n is zero or not finite.
vec3 normalize_or(vec3 n, vec3 fallback) {
    const float len = glm::length(n);
    return (len > 0.f && std::isfinite(len)) ? n / len : fallback;
}
}  // namespace

// [SECTION] Procedural primitives
namespace {

// Surface point, unit normal and dP/du direction at (u, v) in [0,1]^2, evaluated in double.
// The trigonometric angles come from the integer grid indices so that the seam columns (u=0
// and u=1, v=0 and v=1 on the torus) and the sphere poles are bit-identical.
struct SurfaceSample {
    vec3 p, n, dpdu;
};

SurfaceSample sample_primitive(Primitive prim, int i, int nu, int j, int nv, double minor) {
    const double u = double(i) / nu, v = double(j) / nv;
    const double phi = kTwoPi * double(i % nu) / nu;  // azimuth; u=1 reuses u=0
    const double cos_phi = std::cos(phi), sin_phi = std::sin(phi);
    const vec3 azimuth_tangent(float(-sin_phi), float(cos_phi), 0.f);
    switch (prim) {
        case Primitive::Sphere: {
            // Polar angle theta from +z: v=0 is the south pole (theta=pi), v=1 the north pole.
            double sin_theta, cos_theta;
            if (j == 0) { sin_theta = 0.0; cos_theta = -1.0; }
            else if (j == nv) { sin_theta = 0.0; cos_theta = 1.0; }
            else {
                const double theta = kPiD * (1.0 - v);
                sin_theta = std::sin(theta);
                cos_theta = std::cos(theta);
            }
            const vec3 p(float(sin_theta * cos_phi), float(sin_theta * sin_phi), float(cos_theta));
            // dP/du = 2pi sin(theta) (-sin phi, cos phi, 0): its direction is the same for every
            // theta, which is also the limit at the poles for this u column.
            return {p, p, azimuth_tangent};
        }
        case Primitive::Plane: {
            const vec3 p(float(2.0 * u - 1.0), float(2.0 * v - 1.0), 0.f);
            return {p, vec3(0.f, 0.f, 1.f), vec3(1.f, 0.f, 0.f)};
        }
        case Primitive::Torus: {
            const double beta = kTwoPi * double(j % nv) / nv;  // around the tube; v=1 reuses v=0
            const double cos_beta = std::cos(beta), sin_beta = std::sin(beta);
            const double ring = 1.0 + minor * cos_beta;
            const vec3 p(float(ring * cos_phi), float(ring * sin_phi), float(minor * sin_beta));
            const vec3 n(float(cos_beta * cos_phi), float(cos_beta * sin_phi), float(sin_beta));
            return {p, n, azimuth_tangent};
        }
        case Primitive::Cylinder: {
            const vec3 p(float(cos_phi), float(sin_phi), float(2.0 * v - 1.0));
            return {p, vec3(float(cos_phi), float(sin_phi), 0.f), azimuth_tangent};
        }
        case Primitive::Teapot: break;  // Bezier patches: make_teapot
    }
    return {};
}
}  // namespace

// [SECTION] Utah teapot
// Newell's control points and the 32 patches (one-based indices into the points, 4 rows along t of
// 4 along s): data, in core/data/teapot.txt, made into arrays in the build (teapot_data.cpp).
namespace data {
extern const double kTeapotPoints[306][3];
extern const uint16_t kTeapotPatches[32][16];
}  // namespace data

namespace {
using data::kTeapotPatches;
using data::kTeapotPoints;

constexpr int kTeapotPatchCount = 32;
constexpr int kAtlasColumns = 8, kAtlasRows = 4;  // patch i in cell (i % 8, i / 8)
constexpr double kAtlasInset = 0.02;              // of a cell's size, on each side

// Control points of one patch, [4 * row + column]: rows along t, columns along s.
using PatchGrid = std::array<glm::dvec3, 16>;

// Cubic Bernstein polynomials b and their derivatives db at x.
void bernstein(double x, double b[4], double db[4]) {
    const double y = 1.0 - x;
    b[0] = y * y * y, b[1] = 3.0 * x * y * y, b[2] = 3.0 * x * x * y, b[3] = x * x * x;
    db[0] = -3.0 * y * y, db[1] = 3.0 * y * (y - 2.0 * x), db[2] = 3.0 * x * (2.0 * y - x), db[3] = 3.0 * x * x;
}

// Point and partial derivatives of a patch at (s, t).
struct PatchPoint {
    glm::dvec3 p{0.0}, dpds{0.0}, dpdt{0.0};
};

PatchPoint eval_patch(const PatchGrid& g, double s, double t) {
    double bs[4], dbs[4], bt[4], dbt[4];
    bernstein(s, bs, dbs);
    bernstein(t, bt, dbt);
    PatchPoint e;
    for (int row = 0; row < 4; ++row)
        for (int col = 0; col < 4; ++col) {
            const glm::dvec3& q = g[size_t(4 * row + col)];
            e.p += (bt[row] * bs[col]) * q;
            e.dpds += (bt[row] * dbs[col]) * q;
            e.dpdt += (dbt[row] * bs[col]) * q;
        }
    return e;
}

// Point, unnormalised normal dP/ds x dP/dt and dP/ds at (s, t). Where the normal vanishes (an
// edge collapsed to a point: the knob top and the bottom centre, where dP/ds = 0) the normal and
// dP/ds are taken a step of 1e-5 of the way towards the patch centre: their limit along the
// grid line, to within ~1e-5 rad.
struct PatchSample {
    glm::dvec3 p, normal, dpds;
};

PatchSample sample_patch(const PatchGrid& g, double s, double t) {
    const PatchPoint at = eval_patch(g, s, t);
    PatchPoint e = at;
    glm::dvec3 n = glm::cross(e.dpds, e.dpdt);
    const double size = glm::length(e.dpds) + glm::length(e.dpdt);
    if (!(glm::length(n) > 1e-9 * size * size)) {
        constexpr double kInside = 1e-5;
        e = eval_patch(g, s + kInside * (0.5 - s), t + kInside * (0.5 - t));
        n = glm::cross(e.dpds, e.dpdt);
    }
    return {at.p, n, e.dpds};
}

// Widen [lo, hi] to the range of the cubic Bezier with coefficients a over [0, 1]: its end
// points and the zeros of its derivative (a quadratic) inside.
void extend_by_cubic(const double a[4], double& lo, double& hi) {
    auto widen = [&](double x) {
        const double y = 1.0 - x;
        const double v = y * y * y * a[0] + 3.0 * x * y * y * a[1] + 3.0 * x * x * y * a[2] + x * x * x * a[3];
        lo = std::min(lo, v), hi = std::max(hi, v);
    };
    widen(0.0), widen(1.0);
    const double d0 = a[1] - a[0], d1 = a[2] - a[1], d2 = a[3] - a[2];
    const double qa = d0 - 2.0 * d1 + d2, qb = 2.0 * (d1 - d0), qc = d0;  // derivative / 3
    auto widen_inside = [&](double x) { if (x > 0.0 && x < 1.0) widen(x); };
    if (std::abs(qa) < 1e-14) {
        if (qb != 0.0) widen_inside(-qc / qb);
        return;
    }
    const double disc = qb * qb - 4.0 * qa * qc;
    if (disc < 0.0) return;
    widen_inside((-qb + std::sqrt(disc)) / (2.0 * qa));
    widen_inside((-qb - std::sqrt(disc)) / (2.0 * qa));
}

// Bounding box of a patch: the exact range of every iso-line s = k/32 and t = k/32 (exact for
// extremes on a patch edge, as all of the teapot's are; second order in 1/32 inside).
void extend_by_patch(const PatchGrid& g, glm::dvec3& lo, glm::dvec3& hi) {
    constexpr int kLines = 32;
    for (int k = 0; k <= kLines; ++k) {
        double b[4], db[4];
        bernstein(double(k) / kLines, b, db);
        for (int axis = 0; axis < 3; ++axis) {
            double along_t[4] = {0.0, 0.0, 0.0, 0.0}, along_s[4] = {0.0, 0.0, 0.0, 0.0};
            for (int row = 0; row < 4; ++row)
                for (int col = 0; col < 4; ++col) {
                    along_t[row] += b[col] * g[size_t(4 * row + col)][axis];  // s = k/32 fixed
                    along_s[col] += b[row] * g[size_t(4 * row + col)][axis];  // t = k/32 fixed
                }
            extend_by_cubic(along_t, lo[axis], hi[axis]);
            extend_by_cubic(along_s, lo[axis], hi[axis]);
        }
    }
}

// Area-weighted sum of dot(dP/ds x dP/dt, P - centre) over a 16 x 16 grid of the patch:
// positive when dP/ds x dP/dt points away from `centre` (outwards) on the whole.
double outwardness(const PatchGrid& g, glm::dvec3 centre) {
    constexpr int kSamples = 16;
    double sum = 0.0;
    for (int j = 0; j < kSamples; ++j)
        for (int k = 0; k < kSamples; ++k) {
            const PatchPoint e = eval_patch(g, (k + 0.5) / kSamples, (j + 0.5) / kSamples);
            sum += glm::dot(glm::cross(e.dpds, e.dpdt), e.p - centre);
        }
    return sum;
}

// The teapot's patches, oriented outwards, and the map to unit size: p' = (p - centre) * scale.
struct TeapotModel {
    std::array<PatchGrid, kTeapotPatchCount> patch;
    glm::dvec3 centre{0.0};
    double scale = 1.0;
};

TeapotModel build_teapot_model() {
    TeapotModel model;
    glm::dvec3 lo(std::numeric_limits<double>::max()), hi(-std::numeric_limits<double>::max());
    for (int i = 0; i < kTeapotPatchCount; ++i) {
        PatchGrid& g = model.patch[size_t(i)];
        for (size_t k = 0; k < 16; ++k) {
            const double* q = kTeapotPoints[kTeapotPatches[i][k] - 1];
            g[k] = glm::dvec3(q[0], q[1], q[2]);
        }
        extend_by_patch(g, lo, hi);
    }
    model.centre = 0.5 * (lo + hi);
    const glm::dvec3 half = 0.5 * (hi - lo);
    model.scale = 1.0 / std::max({half.x, half.y, half.z});
    // Reverse s (the columns) of patches whose dP/ds x dP/dt points inwards, so that every
    // patch's (s, t) is counter-clockwise seen from outside.
    for (PatchGrid& g : model.patch)
        if (outwardness(g, model.centre) < 0.0)
            for (size_t row = 0; row < 4; ++row) {
                std::swap(g[4 * row], g[4 * row + 3]);
                std::swap(g[4 * row + 1], g[4 * row + 2]);
            }
    return model;
}

const TeapotModel& teapot_model() {
    static const TeapotModel model = build_teapot_model();
    return model;
}

// Atlas position of patch-local (s, t): inside the patch's cell, inset on every side.
vec2 atlas_uv(int patch, double s, double t) {
    const double inner = 1.0 - 2.0 * kAtlasInset;
    const double u = (double(patch % kAtlasColumns) + kAtlasInset + inner * s) / kAtlasColumns;
    const double v = (double(patch / kAtlasColumns) + kAtlasInset + inner * t) / kAtlasRows;
    return {float(u), float(v)};
}

// 32 patches of n x n cells, two triangles each; vertices per patch (not welded).
TriMesh make_teapot(int resolution) {
    const TeapotModel& model = teapot_model();
    const int n = std::max(2, resolution / 8);
    const size_t side = size_t(n) + 1;
    TriMesh m;
    m.has_uv = true;
    const size_t n_vertices = size_t(kTeapotPatchCount) * side * side;
    m.position.reserve(n_vertices);
    m.normal.reserve(n_vertices);
    m.tangent.reserve(n_vertices);
    m.uv.reserve(n_vertices);
    m.index.reserve(size_t(kTeapotPatchCount) * size_t(n) * size_t(n) * 6);
    for (int i = 0; i < kTeapotPatchCount; ++i) {
        const PatchGrid& g = model.patch[size_t(i)];
        const size_t first = m.position.size();
        for (int j = 0; j <= n; ++j)
            for (int k = 0; k <= n; ++k) {
                const double s = double(k) / n, t = double(j) / n;
                const PatchSample f = sample_patch(g, s, t);
                const double len = glm::length(f.normal);
                const vec3 normal = len > 0.0 && std::isfinite(len) ? vec3(f.normal / len) : vec3(0.f, 0.f, 1.f);
                m.position.push_back(vec3((f.p - model.centre) * model.scale));
                m.normal.push_back(normal);
                m.tangent.push_back(orthonormal_tangent(vec3(f.dpds), normal));
                m.uv.push_back(atlas_uv(i, s, t));
            }
        // Counter-clockwise in (s, t), hence seen from outside (dP/ds x dP/dt points outwards).
        for (int j = 0; j < n; ++j)
            for (int k = 0; k < n; ++k) {
                const uint32_t a = uint32_t(first + size_t(j) * side + size_t(k)), b = a + 1;
                const uint32_t d = uint32_t(first + size_t(j + 1) * side + size_t(k)), c = d + 1;
                m.index.insert(m.index.end(), {a, b, c, a, c, d});
            }
    }
    return m;
}
}  // namespace

TriMesh make_primitive(Primitive prim, int resolution, float minor_ratio) {
    if (resolution < 3 || resolution > kMaxResolution)
        throw InputError("geometry.resolution: value " + std::to_string(resolution) + " is out of range [3, " +
                         std::to_string(kMaxResolution) + "]");
    if (prim == Primitive::Torus && !(minor_ratio > 0.f && minor_ratio < 1.f))
        throw InputError("geometry.minor_ratio: value " + std::to_string(minor_ratio) +
                         " is out of range (0, 1) (torus minor radius relative to the major radius)");
    if (prim == Primitive::Teapot) return make_teapot(resolution);

    const int nu = resolution;
    const int nv = prim == Primitive::Sphere ? std::max(2, resolution / 2) : resolution;
    const size_t columns = size_t(nu) + 1;

    // Vertices on a (nu+1) x (nv+1) grid: the last column (and row) duplicates the first one
    // with u=1 (v=1) so that uv is continuous inside every triangle.
    TriMesh m;
    m.has_uv = true;
    const size_t n_vertices = columns * (size_t(nv) + 1);
    m.position.reserve(n_vertices);
    m.normal.reserve(n_vertices);
    m.tangent.reserve(n_vertices);
    m.uv.reserve(n_vertices);
    for (int j = 0; j <= nv; ++j)
        for (int i = 0; i <= nu; ++i) {
            const SurfaceSample s = sample_primitive(prim, i, nu, j, nv, double(minor_ratio));
            const vec3 n = glm::normalize(s.n);
            m.position.push_back(s.p);
            m.normal.push_back(n);
            m.tangent.push_back(orthonormal_tangent(s.dpdu, n));
            m.uv.push_back(vec2(float(double(i) / nu), float(double(j) / nv)));
        }

    // Two triangles per cell, counter-clockwise in (u, v); dP/du x dP/dv points outwards for
    // every primitive, so they are counter-clockwise seen from outside. On the sphere's pole
    // rows one triangle per cell has zero surface area but keeps its uv area, so the triangles
    // tile the whole uv square (texture mode covers every texel).
    m.index.reserve(size_t(nu) * size_t(nv) * 6);
    for (int j = 0; j < nv; ++j)
        for (int i = 0; i < nu; ++i) {
            const uint32_t a = uint32_t(size_t(j) * columns + size_t(i)), b = a + 1;
            const uint32_t d = uint32_t(size_t(j + 1) * columns + size_t(i)), c = d + 1;
            m.index.insert(m.index.end(), {a, b, c, a, c, d});
        }
    return m;
}

Primitive primitive_named(const std::string& type) {
    if (type == "sphere") return Primitive::Sphere;
    if (type == "plane") return Primitive::Plane;
    if (type == "torus") return Primitive::Torus;
    if (type == "cylinder") return Primitive::Cylinder;
    if (type == "teapot") return Primitive::Teapot;
    throw InputError("geometry.type: '" + type + "' is not a procedural primitive (sphere, plane, torus, cylinder, teapot)");
}

// [SECTION] Mesh files (OpenMesh)
namespace {

using PolyMesh = OpenMesh::PolyMesh_ArrayKernelT<>;

// OpenMesh's importer, recording what the reader hands over in our own arrays: OpenMesh leaves
// properties that a file does not set uninitialised, assigns face texture coordinates to the
// wrong corners of faces it had to split off as non-manifold (their vertices are copies), and
// per-vertex texture coordinates lose uv seams. Recording the reader's calls keeps, for every
// face, the file's vertex indices and per-corner texture coordinates.
class RecordingImporter : public OpenMesh::IO::ImporterT<PolyMesh> {
public:
    struct FaceRecord {
        std::vector<int> vertex;     // file vertex indices, in the file's corner order
        std::vector<vec2> texcoord;  // per corner, empty when the face has none
    };
    std::vector<std::optional<FaceRecord>> faces;  // by face handle index
    std::vector<std::optional<vec3>> normal;       // by vertex handle index
    std::vector<std::optional<vec2>> texcoord;     // by vertex handle index

    explicit RecordingImporter(PolyMesh& m) : ImporterT(m) {}

    OpenMesh::FaceHandle add_face(const VHandles& indices) override {
        const OpenMesh::FaceHandle fh = ImporterT::add_face(indices);
        if (fh.is_valid()) {
            if (faces.size() <= size_t(fh.idx())) faces.resize(size_t(fh.idx()) + 1);
            FaceRecord r;
            for (const auto& vh : indices) r.vertex.push_back(vh.idx());
            faces[size_t(fh.idx())] = std::move(r);
        }
        return fh;
    }
    void add_face_texcoords(OpenMesh::FaceHandle fh, OpenMesh::VertexHandle,
                            const std::vector<OpenMesh::Vec2f>& tc) override {
        set_face_texcoords(fh, tc.size(), [&](size_t k) { return vec2(tc[k][0], tc[k][1]); });
    }
    void add_face_texcoords(OpenMesh::FaceHandle fh, OpenMesh::VertexHandle,
                            const std::vector<OpenMesh::Vec3f>& tc) override {
        set_face_texcoords(fh, tc.size(), [&](size_t k) { return vec2(tc[k][0], tc[k][1]); });
    }
    void set_normal(OpenMesh::VertexHandle vh, const OpenMesh::Vec3f& n) override {
        store(normal, vh, vec3(n[0], n[1], n[2]));
    }
    void set_normal(OpenMesh::VertexHandle vh, const OpenMesh::Vec3d& n) override {
        store(normal, vh, vec3(float(n[0]), float(n[1]), float(n[2])));
    }
    void set_texcoord(OpenMesh::VertexHandle vh, const OpenMesh::Vec2f& t) override {
        store(texcoord, vh, vec2(t[0], t[1]));
    }
    void set_texcoord(OpenMesh::VertexHandle vh, const OpenMesh::Vec3f& t) override {
        store(texcoord, vh, vec2(t[0], t[1]));
    }

private:
    template <class T>
    static void store(std::vector<std::optional<T>>& a, OpenMesh::VertexHandle vh, T value) {
        if (!vh.is_valid()) return;
        if (a.size() <= size_t(vh.idx())) a.resize(size_t(vh.idx()) + 1);
        a[size_t(vh.idx())] = value;
    }
    template <class F>
    void set_face_texcoords(OpenMesh::FaceHandle fh, size_t count, F&& at) {
        if (!fh.is_valid() || size_t(fh.idx()) >= faces.size() || !faces[size_t(fh.idx())]) return;
        FaceRecord& r = *faces[size_t(fh.idx())];
        if (count != r.vertex.size()) return;
        r.texcoord.resize(count);
        for (size_t k = 0; k < count; ++k) r.texcoord[k] = at(k);
    }
};

// OpenMesh's OBJ reader silently skips "v" lines whose numbers do not parse (nan, inf, values
// beyond float range), which shifts every later vertex index; find them first. Returns the
// 0-based index of the first such vertex. Other formats are checked after reading.
std::optional<size_t> first_nonfinite_obj_vertex(const std::string& path) {
    std::string ext = std::filesystem::path(path).extension().string();
    for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
    if (ext != ".obj") return std::nullopt;
    std::ifstream in(path);
    std::string line;
    size_t vertex = 0;
    while (std::getline(in, line)) {
        size_t k = line.find_first_not_of(" \t");
        if (k == std::string::npos || line[k] != 'v' || k + 1 >= line.size() || (line[k + 1] != ' ' && line[k + 1] != '\t'))
            continue;
        const char* s = line.c_str() + k + 1;
        for (int axis = 0; axis < 3; ++axis) {
            char* end = nullptr;
            const double x = std::strtod(s, &end);
            if (end == s) break;  // fewer than three numbers: OpenMesh's business
            if (!(std::abs(x) <= double(std::numeric_limits<float>::max()))) return vertex;  // nan, inf, overflow
            s = end;
        }
        ++vertex;
    }
    return std::nullopt;
}

// One face corner of the output: a file vertex and, when known, its texture coordinate.
struct Corner {
    int vertex;
    std::optional<vec2> uv;
};
}  // namespace

TriMesh load_mesh(const std::string& path) {
    namespace fs = std::filesystem;
    std::error_code ec;
    if (!fs::exists(path, ec)) throw InputError(path + ": no such file");
    const std::string unreadable = path + ": could not be read as a mesh (OBJ, OFF, PLY, STL, OM expected)";
    if (fs::is_directory(path, ec)) throw InputError(unreadable);

    PolyMesh pm;  // no normal/texcoord properties: the importer records them itself
    RecordingImporter importer(pm);
    OpenMesh::IO::Options opt = OpenMesh::IO::Options::VertexNormal | OpenMesh::IO::Options::VertexTexCoord |
                                OpenMesh::IO::Options::FaceTexCoord;
    bool ok = false;
    try {
        ok = OpenMesh::IO::IOManager().read(path, importer, opt);
    } catch (const std::exception&) {
        ok = false;
    }
    if (!ok) throw InputError(unreadable);

    if (auto bad = first_nonfinite_obj_vertex(path))
        throw InputError(path + ": vertex " + std::to_string(*bad) + " has a non-finite coordinate");
    const size_t n_file_vertices = pm.n_vertices();
    for (size_t i = 0; i < n_file_vertices; ++i) {
        const auto& p = pm.point(PolyMesh::VertexHandle(int(i)));
        if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2]))
            throw InputError(path + ": vertex " + std::to_string(i) + " has a non-finite coordinate");
    }
    auto file_point = [&](int v) {
        const auto& p = pm.point(PolyMesh::VertexHandle(v));
        return vec3(p[0], p[1], p[2]);
    };

    // Faces as corner lists: recorded faces keep the file's vertices and corner uvs; faces
    // that did not pass through add_face(VHandles) (e.g. OM connectivity) come from the mesh.
    // (What the file holds is taken from the recorded calls: not every reader reports it in
    // `opt`, e.g. STL leaves the requested options set.)
    auto vertex_uv = [&](int v) -> std::optional<vec2> {
        if (size_t(v) >= importer.texcoord.size()) return std::nullopt;
        return importer.texcoord[size_t(v)];
    };
    std::vector<std::vector<Corner>> polygons;
    polygons.reserve(pm.n_faces());
    bool any_uv = false;
    for (const auto fh : pm.faces()) {
        std::vector<Corner> poly;
        const size_t f = size_t(fh.idx());
        if (f < importer.faces.size() && importer.faces[f]) {
            const auto& r = *importer.faces[f];
            for (size_t k = 0; k < r.vertex.size(); ++k)
                poly.push_back({r.vertex[k], r.texcoord.empty() ? vertex_uv(r.vertex[k]) : r.texcoord[k]});
        } else {
            for (const auto vh : pm.fv_range(fh)) poly.push_back({vh.idx(), vertex_uv(vh.idx())});
        }
        for (const Corner& c : poly) any_uv |= c.uv.has_value();
        if (poly.size() >= 3) polygons.push_back(std::move(poly));
    }

    // Output vertices: one per distinct (file vertex, uv) pair, so uv seams split vertices.
    TriMesh m;
    m.has_uv = any_uv;
    std::vector<std::vector<uint32_t>> outputs_of(n_file_vertices);  // output vertices per file vertex
    std::vector<int> file_vertex_of;
    auto output_vertex = [&](const Corner& c) {
        vec2 uv = c.uv.value_or(vec2(0.f));
        if (!std::isfinite(uv.x) || !std::isfinite(uv.y)) uv = vec2(0.f);
        for (uint32_t o : outputs_of[size_t(c.vertex)])
            if (m.uv[o] == uv) return o;
        const uint32_t o = uint32_t(m.position.size());
        m.position.push_back(file_point(c.vertex));
        m.uv.push_back(uv);
        file_vertex_of.push_back(c.vertex);
        outputs_of[size_t(c.vertex)].push_back(o);
        return o;
    };
    for (const auto& poly : polygons) {
        // Fan triangulation, as OpenMesh's TriMesh does.
        const uint32_t o0 = output_vertex(poly[0]);
        uint32_t prev = output_vertex(poly[1]);
        for (size_t k = 2; k < poly.size(); ++k) {
            const uint32_t next = output_vertex(poly[k]);
            m.index.insert(m.index.end(), {o0, prev, next});
            prev = next;
        }
    }
    if (m.index.empty()) throw InputError(path + ": mesh has no triangles");

    // Area-weighted normals per file vertex (shared across uv seams), used where the file has
    // no normal or an unusable one. A vertex whose triangles all have zero area gets +z.
    std::vector<vec3> area_normal(n_file_vertices, vec3(0.f));
    for (size_t t = 0; t < m.index.size(); t += 3) {
        const uint32_t i0 = m.index[t], i1 = m.index[t + 1], i2 = m.index[t + 2];
        const vec3 n2a = glm::cross(m.position[i1] - m.position[i0], m.position[i2] - m.position[i0]);
        if (!is_finite(n2a)) continue;
        for (uint32_t i : {i0, i1, i2}) area_normal[size_t(file_vertex_of[i])] += n2a;
    }
    m.normal.resize(m.position.size());
    for (size_t o = 0; o < m.position.size(); ++o) {
        const size_t v = size_t(file_vertex_of[o]);
        const vec3 computed = normalize_or(area_normal[v], vec3(0.f, 0.f, 1.f));
        std::optional<vec3> given;
        if (v < importer.normal.size()) given = importer.normal[v];
        m.normal[o] = given ? normalize_or(*given, computed) : computed;
    }

    // Tangents: accumulated per-triangle dP/du (Lengyel) where uv exist, then made orthonormal
    // to the normal; an arbitrary orthonormal tangent where uv give none.
    std::vector<vec3> dpdu(m.position.size(), vec3(0.f));
    if (m.has_uv)
        for (size_t t = 0; t < m.index.size(); t += 3) {
            const uint32_t i0 = m.index[t], i1 = m.index[t + 1], i2 = m.index[t + 2];
            const vec3 e1 = m.position[i1] - m.position[i0], e2 = m.position[i2] - m.position[i0];
            const vec2 d1 = m.uv[i1] - m.uv[i0], d2 = m.uv[i2] - m.uv[i0];
            const float det = d1.x * d2.y - d2.x * d1.y;
            if (!(std::abs(det) > 0.f)) continue;
            const vec3 t_dpdu = (e1 * d2.y - e2 * d1.y) / det;
            if (!is_finite(t_dpdu)) continue;
            for (uint32_t i : {i0, i1, i2}) dpdu[i] += t_dpdu;
        }
    m.tangent.resize(m.position.size());
    for (size_t o = 0; o < m.position.size(); ++o) m.tangent[o] = orthonormal_tangent(dpdu[o], m.normal[o]);
    return m;
}

// [SECTION] Mesh utilities
void transform_mesh(TriMesh& m, float scale, vec3 translation) {
    for (vec3& p : m.position) p = p * scale + translation;
}

Bounds bounds(const TriMesh& m) {
    if (m.position.empty()) return {};
    Bounds b{m.position[0], m.position[0]};
    for (const vec3& p : m.position) {
        b.lo = glm::min(b.lo, p);
        b.hi = glm::max(b.hi, p);
    }
    return b;
}

Bounds bounds(const std::shared_ptr<const TriMesh>& m) {
    struct Key {
        std::weak_ptr<const void> owner;
        const TriMesh* mesh;
    };
    struct Less {
        bool operator()(const Key& a, const Key& b) const {
            if (a.owner.owner_before(b.owner)) return true;
            if (b.owner.owner_before(a.owner)) return false;
            return std::less<const TriMesh*>()(a.mesh, b.mesh);
        }
    };
    static std::mutex mutex;
    static std::map<Key, Bounds, Less> known;
    const Key key{m, m.get()};
    {
        std::lock_guard lock(mutex);
        if (auto it = known.find(key); it != known.end()) return it->second;
    }
    const Bounds b = bounds(*m);  // outside the lock: other threads' lookups do not wait for the walk
    std::lock_guard lock(mutex);
    if (known.size() >= 256)  // forget meshes that are gone
        std::erase_if(known, [](const auto& kv) { return kv.first.owner.expired(); });
    known.emplace(key, b);
    return b;
}
}  // namespace mesolab
