#include "core/microgeom/directions.h"
#include "core/error.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <stdexcept>

namespace mesolab::microgeom {

namespace {

// [SECTION] Exact-enough predicates (double precision on the float directions)
struct dvec3 {
    double x, y, z;
};
dvec3 to_d(vec3 v) { return {double(v.x), double(v.y), double(v.z)}; }
dvec3 operator-(dvec3 a, dvec3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
double dot(dvec3 a, dvec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
dvec3 cross(dvec3 a, dvec3 b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }
// det(a, b, c) = a . (b x c): positive when c lies left of the great circle a -> b seen from
// outside, i.e. on the inner side of the cone edge (a, b) of a counter-clockwise triangle.
double det(dvec3 a, dvec3 b, dvec3 c) { return dot(a, cross(b, c)); }
// Positive when p lies outside the plane of the counter-clockwise (seen from outside) face abc.
double orient(dvec3 a, dvec3 b, dvec3 c, dvec3 p) { return det(b - a, c - a, p - a); }

// [SECTION] Incremental convex hull (randomised, radial conflict pointers)
// Every point lies on the hull (unit sphere), and the hull always contains the origin strictly,
// so the face a point sees "first" is the face its radial ray crosses: each uninserted point keeps
// that face as its conflict pointer. Inserting p deletes the faces visible from p (a connected
// disc found by a walk from p's radial face), and cones the horizon to p; the new cone covers the
// same radial region as the deleted disc, so the orphaned points are re-pointed to new faces.
// Random (deterministic) insertion order gives O(n log n) expected time.
class Hull {
public:
    explicit Hull(const std::vector<vec3>& pts) : n_(int(pts.size())), p_(pts.size()), conflict_(pts.size(), -1) {
        for (size_t i = 0; i < pts.size(); ++i) p_[i] = to_d(pts[i]);
    }

    std::vector<std::array<int, 3>> build() {
        const std::array<int, 4> tet = initial_tetrahedron();
        std::vector<char> used(size_t(n_), 0);
        for (int v : tet) used[size_t(v)] = 1;
        // Tetrahedron faces, counter-clockwise from outside.
        const int a = tet[0], b = tet[1], c = tet[2], d = tet[3];
        const bool ccw = orient(p_[size_t(a)], p_[size_t(b)], p_[size_t(c)], p_[size_t(d)]) < 0;  // d behind abc
        const std::array<std::array<int, 3>, 4> faces = ccw ? std::array<std::array<int, 3>, 4>{{{a, b, c}, {a, d, b}, {b, d, c}, {c, d, a}}}
                                                            : std::array<std::array<int, 3>, 4>{{{a, c, b}, {a, b, d}, {b, c, d}, {c, a, d}}};
        for (const auto& f : faces) add_face(f[0], f[1], f[2]);
        link_all_initial();

        // Deterministic shuffle of the remaining points (SplitMix64, Fisher-Yates).
        std::vector<int> order;
        for (int i = 0; i < n_; ++i)
            if (!used[size_t(i)]) order.push_back(i);
        uint64_t state = 0x9E3779B97F4A7C15ull;
        auto next = [&state] {
            uint64_t z = (state += 0x9E3779B97F4A7C15ull);
            z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
            z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
            return z ^ (z >> 31);
        };
        for (size_t i = order.size(); i > 1; --i) std::swap(order[i - 1], order[size_t(next() % i)]);

        // Initial conflicts: the tetrahedron face whose cone contains each point.
        const std::vector<int> first = {0, 1, 2, 3};
        for (int q : order) assign(q, first);

        for (int q : order) insert(q);

        std::vector<std::array<int, 3>> out;
        for (const Face& f : faces_)
            if (f.alive) out.push_back(f.v);
        return out;
    }

private:
    struct Face {
        std::array<int, 3> v;
        std::array<int, 3> nb{-1, -1, -1};  // neighbour across edge (v[k], v[k+1])
        std::vector<int> pts;                // uninserted points whose radial ray crosses this face
        bool alive = true;
        int mark = -1;
    };

    int n_;
    std::vector<dvec3> p_;
    std::vector<int> conflict_;
    std::vector<Face> faces_;

    int add_face(int a, int b, int c) {
        Face f;
        f.v = {a, b, c};
        faces_.push_back(std::move(f));
        return int(faces_.size()) - 1;
    }

    // Index of edge (a, b) in face f, or -1.
    int edge_index(int f, int a, int b) const {
        const auto& v = faces_[size_t(f)].v;
        for (int k = 0; k < 3; ++k)
            if (v[size_t(k)] == a && v[size_t((k + 1) % 3)] == b) return k;
        return -1;
    }

    void link_all_initial() {
        for (int f = 0; f < 4; ++f)
            for (int k = 0; k < 3; ++k) {
                const int a = faces_[size_t(f)].v[size_t(k)], b = faces_[size_t(f)].v[size_t((k + 1) % 3)];
                for (int g = 0; g < 4; ++g)
                    if (g != f && edge_index(g, b, a) >= 0) faces_[size_t(f)].nb[size_t(k)] = g;
            }
    }

    // Four points whose tetrahedron contains the origin strictly (as far from its faces as
    // possible among the candidates tried).
    std::array<int, 4> initial_tetrahedron() const {
        auto margin = [&](const std::array<int, 4>& t) {
            // Smallest distance-like margin of the origin inside the tetrahedron (<= 0: outside).
            const dvec3 o{0, 0, 0};
            double m = std::numeric_limits<double>::infinity();
            for (int k = 0; k < 4; ++k) {
                const dvec3 a = p_[size_t(t[size_t(k)])], b = p_[size_t(t[size_t((k + 1) % 4)])], c = p_[size_t(t[size_t((k + 2) % 4)])],
                            d = p_[size_t(t[size_t((k + 3) % 4)])];
                const double od = orient(a, b, c, d), oo = orient(a, b, c, o);
                if (od == 0.0) return -1.0;
                m = std::min(m, oo / od);  // origin on d's side, relative to d's height
            }
            return m;
        };
        std::array<int, 4> best{0, 1, 2, 3};
        double best_margin = -1.0;
        if (n_ <= 12) {
            for (int a = 0; a < n_; ++a)
                for (int b = a + 1; b < n_; ++b)
                    for (int c = b + 1; c < n_; ++c)
                        for (int d = c + 1; d < n_; ++d) {
                            const std::array<int, 4> t{a, b, c, d};
                            const double m = margin(t);
                            if (m > best_margin) best_margin = m, best = t;
                        }
        } else {
            // The points nearest to the corners of a regular tetrahedron.
            const double s = 1.0 / std::sqrt(3.0);
            const dvec3 corners[4] = {{s, s, s}, {s, -s, -s}, {-s, s, -s}, {-s, -s, s}};
            for (int k = 0; k < 4; ++k) {
                double bd = -2.0;
                for (int i = 0; i < n_; ++i)
                    if (const double dd = dot(p_[size_t(i)], corners[k]); dd > bd) bd = dd, best[size_t(k)] = i;
            }
            best_margin = margin(best);
        }
        if (!(best_margin > 1e-9)) throw std::logic_error("microgeom: direction set does not enclose the origin");
        return best;
    }

    // Sets q's conflict face to the face among `cands` whose cone contains q (the best one when
    // rounding leaves none containing it exactly).
    void assign(int q, const std::vector<int>& cands) {
        const dvec3 w = p_[size_t(q)];
        int best = -1;
        double best_m = -std::numeric_limits<double>::infinity();
        for (int f : cands) {
            const auto& v = faces_[size_t(f)].v;
            const dvec3 a = p_[size_t(v[0])], b = p_[size_t(v[1])], c = p_[size_t(v[2])];
            const double m = std::min({det(a, b, w), det(b, c, w), det(c, a, w)});
            if (m > best_m) best_m = m, best = f;
            if (m >= 0.0) break;
        }
        conflict_[size_t(q)] = best;
        faces_[size_t(best)].pts.push_back(q);
    }

    void insert(int q) {
        const dvec3 pq = p_[size_t(q)];
        const int start = conflict_[size_t(q)];
        // Visible faces: a walk from q's radial face (always taken as visible) through faces
        // that q lies strictly above.
        std::vector<int> visible{start}, stack{start};
        faces_[size_t(start)].mark = q;
        while (!stack.empty()) {
            const int f = stack.back();
            stack.pop_back();
            for (int g : faces_[size_t(f)].nb) {
                Face& fg = faces_[size_t(g)];
                if (fg.mark == q) continue;
                if (orient(p_[size_t(fg.v[0])], p_[size_t(fg.v[1])], p_[size_t(fg.v[2])], pq) > 0.0) {
                    fg.mark = q;
                    visible.push_back(g);
                    stack.push_back(g);
                }
            }
        }
        // Horizon edges (a, b) of visible faces whose neighbour is not visible; cone them to q.
        std::vector<int> created;
        for (int f : visible) {
            for (int k = 0; k < 3; ++k) {
                const int g = faces_[size_t(f)].nb[size_t(k)];
                if (faces_[size_t(g)].mark == q) continue;
                const int a = faces_[size_t(f)].v[size_t(k)], b = faces_[size_t(f)].v[size_t((k + 1) % 3)];
                const int nf = add_face(a, b, q);
                faces_[size_t(nf)].nb[0] = g;
                faces_[size_t(g)].nb[size_t(edge_index(g, b, a))] = nf;
                created.push_back(nf);
            }
        }
        // Link the cone: face (a, b, q) meets the cone face starting at b across (b, q).
        if (from_.size() < size_t(n_)) from_.assign(size_t(n_), -1);
        for (int nf : created) {
            int& slot = from_[size_t(faces_[size_t(nf)].v[0])];
            if (slot != -1) throw std::logic_error("microgeom: convex hull horizon is not a simple cycle");
            slot = nf;
        }
        for (int nf : created) {
            const int b = faces_[size_t(nf)].v[1];
            const int next = from_[size_t(b)];
            if (next < 0) throw std::logic_error("microgeom: convex hull horizon is not closed");
            faces_[size_t(nf)].nb[1] = next;
            faces_[size_t(next)].nb[2] = nf;
        }
        for (int nf : created) from_[size_t(faces_[size_t(nf)].v[0])] = -1;

        // Delete the visible faces and re-point their orphaned points.
        for (int f : visible) {
            Face& face = faces_[size_t(f)];
            face.alive = false;
            std::vector<int> orphans;
            orphans.swap(face.pts);
            for (int r : orphans)
                if (r != q) assign(r, created);
        }
    }

    std::vector<int> from_;  // scratch: cone face starting at a horizon vertex
};

// Neighbour of triangle t across its edge (a, b): the triangle of a's fan holding edge (b, a).
int across(const DirectionSet& s, int t, int a, int b) {
    for (int g : s.fan[size_t(a)]) {
        if (g == t) continue;
        const auto& v = s.triangles[size_t(g)];
        for (int k = 0; k < 3; ++k)
            if (v[size_t(k)] == b && v[size_t((k + 1) % 3)] == a) return g;
    }
    return -1;
}
}  // namespace

// [SECTION] Spherical triangle area
float spherical_triangle_area(vec3 a, vec3 b, vec3 c) {
    const dvec3 da = to_d(a), db = to_d(b), dc = to_d(c);
    const double num = std::abs(det(da, db, dc));
    const double den = 1.0 + dot(da, db) + dot(db, dc) + dot(dc, da);
    return float(2.0 * std::atan2(num, den));
}

// [SECTION] Direction set construction
DirectionSet make_direction_set(int n) {
    if (n < 4 || n > 65536)
        throw InputError("microgeom.directions: value " + std::to_string(n) + " is out of range [4, 65536]");
    DirectionSet s;
    s.d.resize(size_t(n));
    const double golden = 3.14159265358979323846 * (3.0 - std::sqrt(5.0));
    for (int i = 0; i < n; ++i) {
        const double z = 1.0 - (2.0 * i + 1.0) / double(n);
        const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
        const double phi = golden * double(i);
        const vec3 v(float(r * std::cos(phi)), float(r * std::sin(phi)), float(z));
        s.d[size_t(i)] = glm::normalize(v);
    }

    s.triangles = Hull(s.d).build();
    if (s.triangles.size() != size_t(2 * n - 4)) throw std::logic_error("microgeom: direction triangulation has the wrong size");

    s.fan.assign(size_t(n), {});
    std::vector<double> share(size_t(n), 0.0);
    for (size_t t = 0; t < s.triangles.size(); ++t) {
        const auto& v = s.triangles[t];
        const double third = double(spherical_triangle_area(s.d[size_t(v[0])], s.d[size_t(v[1])], s.d[size_t(v[2])])) / 3.0;
        for (int k : v) {
            s.fan[size_t(k)].push_back(int(t));
            share[size_t(k)] += third;
        }
    }
    s.solid_angle.resize(size_t(n));
    for (int i = 0; i < n; ++i) s.solid_angle[size_t(i)] = float(share[size_t(i)]);
    return s;
}

// [SECTION] Queries
int DirectionSet::nearest(vec3 w) const {
    const int n = size();
    if (n == 0) return -1;
    const dvec3 q = to_d(w);
    auto closeness = [&](int i) { return dot(to_d(d[size_t(i)]), q); };
    int best = 0;
    double best_c = -std::numeric_limits<double>::infinity();
    if (fan.size() != size_t(n) || n <= 64) {  // small or untriangulated: brute force
        for (int i = 0; i < n; ++i)
            if (const double c = closeness(i); c > best_c) best_c = c, best = i;
        return best;
    }
    // Start guess: on a Fibonacci lattice (z decreasing with the index) the directions near w lie
    // at indices around the one of w's height; scan a window of ~sqrt(n) of them.
    const double len = std::sqrt(dot(q, q));
    const double z = len > 0.0 ? q.z / len : 1.0;
    const int centre = std::clamp(int(std::lround((1.0 - z) * 0.5 * double(n) - 0.5)), 0, n - 1);
    const int half = int(std::sqrt(double(n))) / 2 + 2;
    for (int i = std::max(0, centre - half); i <= std::min(n - 1, centre + half); ++i)
        if (const double c = closeness(i); c > best_c) best_c = c, best = i;
    // Greedy walk on the triangulation: in a (spherical) Delaunay triangulation a vertex that is
    // not the nearest to w always has a neighbour nearer to w.
    for (int step = 0; step < 4 * n; ++step) {
        int next = best;
        double next_c = best_c;
        for (int t : fan[size_t(best)])
            for (int k : triangles[size_t(t)])
                if (const double c = closeness(k); c > next_c) next_c = c, next = k;
        if (next == best) return best;
        best = next;
        best_c = next_c;
    }
    return best;
}

int DirectionSet::locate(vec3 w, vec3& bary) const {
    const dvec3 q = to_d(w);
    // Cone coordinates of w in triangle t: (det(b,c,w), det(c,a,w), det(a,b,w)); w lies in t's
    // cone when all three are >= 0, and normalised they are the barycentrics of the point where
    // the ray along w crosses t's plane.
    auto coords = [&](int t) {
        const auto& v = triangles[size_t(t)];
        const dvec3 a = to_d(d[size_t(v[0])]), b = to_d(d[size_t(v[1])]), c = to_d(d[size_t(v[2])]);
        return std::array<double, 3>{det(b, c, q), det(c, a, q), det(a, b, q)};
    };
    auto finish = [&](int t, std::array<double, 3> c) {
        for (double& x : c) x = std::max(0.0, x);
        const double sum = c[0] + c[1] + c[2];
        bary = sum > 0.0 ? vec3(float(c[0] / sum), float(c[1] / sum), float(c[2] / sum)) : vec3(1.f / 3.f);
        return t;
    };
    constexpr double kTol = -1e-12;
    const int ntri = int(triangles.size());
    if (ntri == 0) {
        bary = vec3(1.f / 3.f);
        return -1;
    }

    // Start in the fan of the nearest direction, then walk towards w across the edge that w lies
    // beyond (the containing triangle need not touch the nearest direction).
    int t = 0;
    double t_min = -std::numeric_limits<double>::infinity();
    std::array<double, 3> tc{};
    const int v0 = nearest(w);
    if (v0 >= 0 && size_t(v0) < fan.size())
        for (int f : fan[size_t(v0)]) {
            const auto c = coords(f);
            const double m = std::min({c[0], c[1], c[2]});
            if (m > t_min) t_min = m, t = f, tc = c;
            if (m >= 0.0) return finish(f, c);
        }
    if (t_min == -std::numeric_limits<double>::infinity()) tc = coords(t), t_min = std::min({tc[0], tc[1], tc[2]});
    for (int step = 0; step < 64 + ntri && t_min < kTol; ++step) {
        const int k = int(std::min_element(tc.begin(), tc.end()) - tc.begin());  // edge opposite corner k
        const auto& v = triangles[size_t(t)];
        const int g = across(*this, t, v[size_t((k + 1) % 3)], v[size_t((k + 2) % 3)]);
        if (g < 0) break;
        t = g;
        tc = coords(t);
        t_min = std::min({tc[0], tc[1], tc[2]});
    }
    if (t_min >= kTol) return finish(t, tc);

    // Fallback (not expected on a valid triangulation): the best triangle overall.
    for (int f = 0; f < ntri; ++f) {
        const auto c = coords(f);
        const double m = std::min({c[0], c[1], c[2]});
        if (m > t_min) t_min = m, t = f, tc = c;
    }
    return finish(t, tc);
}
}  // namespace mesolab::microgeom
