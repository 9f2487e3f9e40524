// The cells that translucency's truth finds its photons' events and exits in (CellMap, in
// core/translucency/truth.h): a ball's sum of weights and its records are those a brute-force scan
// finds, whether the cells sit in a dense grid (records packed in a small box) or in a hash table
// (records in a few far-apart clusters), with balls that reach past the records' extent on every
// side; built from parts, it gives the same sums to the bit.
#include "core/translucency/truth.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

using namespace mesolab;
using namespace mesolab::translucency;

namespace {
// Records: `clusters` boxes of side `side` at random corners of a cube of side `spread`.
std::vector<ScatterVertex> records(int count, int clusters, float side, float spread, uint32_t seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(0.f, 1.f);
    std::vector<vec3> corner(static_cast<size_t>(clusters));
    for (vec3& c : corner) c = vec3(u(rng), u(rng), u(rng)) * spread;
    std::vector<ScatterVertex> out(static_cast<size_t>(count));
    for (size_t i = 0; i < out.size(); ++i) {
        out[i].p = corner[i % corner.size()] + vec3(u(rng), u(rng), u(rng)) * side;
        out[i].weight = 0.5f + u(rng);
    }
    return out;
}

// For `queries` balls around the records (some past their extent), weight_within and for_each_near
// against a scan of every record.
void expect_as_brute_force(const std::vector<ScatterVertex>& all, float cell, int queries, uint32_t seed) {
    vec3 lo(3.4e38f), hi(-3.4e38f);
    for (const ScatterVertex& v : all) lo = glm::min(lo, v.p), hi = glm::max(hi, v.p);
    CellMap<ScatterVertex> found(all, cell, lo - vec3(cell));
    CellMap<ScatterVertex> sums(all, cell, lo - vec3(cell));
    sums.keep_weights([](const ScatterVertex& v) { return v.weight; });
    // The same records in uneven parts (one empty), weights only: the same sums, to the bit.
    std::vector<std::vector<ScatterVertex>> pieces(4);
    for (size_t i = 0; i < all.size(); ++i) pieces[i < all.size() / 7 ? 0 : i < all.size() / 2 ? 2 : 3].push_back(all[i]);
    std::vector<std::vector<ScatterVertex>*> parts;
    for (auto& piece : pieces) parts.push_back(&piece);
    const CellMap<ScatterVertex> parted(parts, cell, lo - vec3(cell), [](const ScatterVertex& v) { return v.weight; });
    for (const auto& piece : pieces) EXPECT_TRUE(piece.empty());  // emptied on the way
    EXPECT_EQ(parted.size(), 0u);  // positions and weights only
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(0.f, 1.f);
    int nonempty = 0;
    for (int q = 0; q < queries; ++q) {
        // Around a record, or anywhere in the box grown by two cells.
        const vec3 p = q % 2 == 0 ? all[size_t(rng() % all.size())].p + (vec3(u(rng), u(rng), u(rng)) - 0.5f) * cell
                                  : lo - 2.f * cell + vec3(u(rng), u(rng), u(rng)) * (hi - lo + 4.f * cell);
        const float radius = cell * (0.05f + 1.5f * u(rng));
        double expected = 0.0;
        int inside = 0;
        for (const ScatterVertex& v : all) {
            const vec3 d = v.p - p;
            if (glm::dot(d, d) <= radius * radius) expected += double(v.weight), ++inside;
        }
        nonempty += inside > 0;
        EXPECT_NEAR(sums.weight_within(p, radius), expected, 1e-5 * (1.0 + expected)) << "ball " << q << " at radius " << radius;
        EXPECT_EQ(parted.weight_within(p, radius), sums.weight_within(p, radius)) << "ball " << q << ", from parts";
        int near = 0, near_inside = 0;
        found.for_each_near(p, radius, [&](const ScatterVertex& v) {
            ++near;
            const vec3 d = v.p - p;
            near_inside += glm::dot(d, d) <= radius * radius;
        });
        EXPECT_EQ(near_inside, inside) << "ball " << q;
        EXPECT_GE(near, inside);
    }
    EXPECT_GT(nonempty, queries / 3);  // the balls found records, not only empty space
}
}  // namespace

TEST(TranslucencyCellMap, DenseGridFindsWhatABruteForceScanFinds) {
    // 20 000 records in a box of 12 cells a side: a dense grid.
    expect_as_brute_force(records(20000, 1, 12.f, 0.f, 1), 1.f, 400, 2);
}

TEST(TranslucencyCellMap, HashedCellsFindWhatABruteForceScanFinds) {
    // 3 000 records in 6 clusters spread over 10 000 cells a side: far too many cells for a grid.
    expect_as_brute_force(records(3000, 6, 3.f, 10000.f, 3), 1.f, 400, 4);
}

TEST(TranslucencyCellMap, SmallCellsAndAFewRecordsAtTheOriginsCorner) {
    // Records on a line from the origin's corner, cells a tenth of the radii: many rows a ball.
    std::vector<ScatterVertex> line(50);
    for (size_t i = 0; i < line.size(); ++i) line[i].p = vec3(float(i) * 0.01f), line[i].weight = 1.f;
    expect_as_brute_force(line, 0.05f, 200, 5);
}
