// Cloth sample files and model files (core/cloth/samples.h): parsing, the errors that name the
// line, and the model's JSON round trip.
#include "core/cloth/samples.h"
#include "core/error.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>

using namespace mesolab;
using namespace mesolab::cloth;

namespace {
std::string error_of(const std::string& csv) {
    try {
        parse_samples_csv(csv, "s.csv");
    } catch (const InputError& e) {
        return e.what();
    }
    return "";
}
}  // namespace

TEST(ClothSamples, RowsAreNormalisedAndGroupedByPointAndView) {
    const std::string csv =
        "point,lx,ly,lz,vx,vy,vz,r,g,b\n"
        "a,0,0,2,0,0,1,0.1,0.2,0.3\n"
        "a,1,0,1,0,0,1,0.2,0.2,0.2\n"
        "\n"
        "b,0,0,1,0,1,1,1,1,1\n"
        "a,0,1,1,0,0,3,0.3,0.3,0.3\n";
    const SampleSet s = parse_samples_csv(csv, "s.csv");
    ASSERT_EQ(s.names, (std::vector<std::string>{"a", "b"}));
    EXPECT_EQ(s.rows, 4u);
    ASSERT_EQ(s.points[0].s.size(), 3u);
    EXPECT_EQ(s.points[0].views.size(), 1u);  // (0,0,1) and (0,0,3) are one direction
    EXPECT_NEAR(glm::length(s.points[0].s[1].l), 1.0, 1e-15);
    EXPECT_NEAR(s.points[1].s[0].v.y, std::sqrt(0.5), 1e-15);
    // Without a point column: one point.
    const SampleSet one = parse_samples_csv("0,0,1,0,0,1,1,2,3\n", "t.csv");
    EXPECT_EQ(one.points.size(), 1u);
    EXPECT_EQ(one.points[0].s[0].f, dvec3(1, 2, 3));
}

TEST(ClothSamples, MalformedRowsNameTheFileAndLine) {
    EXPECT_NE(error_of("0,0,1,0,0,1,1,1\n").find("s.csv:1: expected 9 values"), std::string::npos);
    EXPECT_NE(error_of("lx,ly,lz,vx,vy,vz,r,g,b\n0,0,1,0,0,1,1,x,1\n").find("s.csv:2: a value is not a number"), std::string::npos);
    EXPECT_NE(error_of("0,0,1,0,0,1,1,1,1\n0,0,-1,0,0,1,1,1,1\n").find("s.csv:2: the light direction"), std::string::npos);
    EXPECT_NE(error_of("0,0,1,0,0.5,-0.2,1,1,1\n").find("below the horizon"), std::string::npos);
    EXPECT_NE(error_of("0,0,0,0,0,1,1,1,1\n").find("zero length"), std::string::npos);
    EXPECT_NE(error_of("0,0,1,0,0,1,1,-0.5,1\n").find("s.csv:1: the BRDF value -0.5 is negative"), std::string::npos);
    EXPECT_NE(error_of("0,0,1,0,0,1,1,nan,1\n").find("not finite"), std::string::npos);
    EXPECT_NE(error_of("0,0,1,0,0,1,1,inf,1\n").find("not finite"), std::string::npos);
    EXPECT_NE(error_of("0,0,1,0,0,1,1,1e999,1\n").find("s.csv:1"), std::string::npos);
    EXPECT_NE(error_of("a,0,0,1,0,0,1,1,1,1\n0,0,1,0,0,1,1,1,1\n").find("s.csv:2: has 9 values"), std::string::npos);
    EXPECT_NE(error_of("lx,ly\n").find("s.csv:1"), std::string::npos);
    EXPECT_NE(error_of("").find("no samples"), std::string::npos);
    EXPECT_NE(error_of("h1,h2,h3,h4,h5,h6,h7,h8,h9\nh1,h2,h3,h4,h5,h6,h7,h8,h9\n").find("s.csv:2"), std::string::npos);
    try {
        read_samples_csv("/nonexistent/samples.csv");
        FAIL();
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("/nonexistent/samples.csv"), std::string::npos);
    }
}

TEST(ClothSamples, DirectionsNeedAPointWhenTheModelHasSeveral) {
    const auto rows = parse_directions_csv("lx,ly,lz,vx,vy,vz\n0,0,1,1,0,1\n", "d.csv", {""});
    ASSERT_EQ(rows.size(), 1u);
    EXPECT_NEAR(rows[0].v.x, std::sqrt(0.5), 1e-15);
    const auto named = parse_directions_csv("b,0,0,1,0,0,1\n", "d.csv", {"a", "b"});
    EXPECT_EQ(named[0].point, 1);
    EXPECT_THROW(parse_directions_csv("0,0,1,0,0,1\n", "d.csv", {"a", "b"}), InputError);
    EXPECT_THROW(parse_directions_csv("c,0,0,1,0,0,1\n", "d.csv", {"a", "b"}), InputError);
    EXPECT_THROW(parse_directions_csv("0,0,1,0,0,-1\n", "d.csv", {""}), InputError);
}

TEST(ClothModelFile, RoundTripKeepsEveryValue) {
    ClothModel m;
    m.lobes = 2;
    m.names = {"p0", "p1"};
    for (int i = 0; i < 2; ++i) {
        ClothBrdf b;
        b.L.kd = dvec3(0.1 * i, 0.2, 1.0 / 3.0);
        for (int k = 0; k < 2; ++k) {
            LafortuneLobe l;
            l.Cx = dvec3(-0.9, -0.8 - k, 0.123456789012345), l.Cy = dvec3(-1.1), l.Cz = dvec3(0.7), l.n = dvec3(3.0 + k, 17.25, 1e4);
            b.L.lobes.push_back(l);
        }
        b.table.v = {dvec3(0, 0, 1), glm::normalize(dvec3(1, 0, 1))};
        b.table.T = {dvec4(1, 0.5, 0.25, 1), dvec4(0.9, 0.1, 0.2, 0.0)};
        m.brdfs.push_back(b);
        m.reports.push_back(FitReport{2, true, 0.01, 0.002, 6});
    }
    const std::string path = (std::filesystem::temp_directory_path() / "mesolab_cloth_model_test.json").string();
    write_model(path, m);
    const ClothModel r = read_model(path);
    std::filesystem::remove(path);
    ASSERT_EQ(r.brdfs.size(), 2u);
    EXPECT_EQ(r.names, m.names);
    for (size_t i = 0; i < 2; ++i) {
        EXPECT_EQ(r.brdfs[i].L.kd, m.brdfs[i].L.kd);
        for (size_t k = 0; k < 2; ++k) {
            EXPECT_EQ(r.brdfs[i].L.lobes[k].Cx, m.brdfs[i].L.lobes[k].Cx);
            EXPECT_EQ(r.brdfs[i].L.lobes[k].n, m.brdfs[i].L.lobes[k].n);
        }
        EXPECT_EQ(r.brdfs[i].table.T, m.brdfs[i].table.T);
        for (const dvec3 l : {dvec3(0, 0, 1), glm::normalize(dvec3(0.3, 0.2, 0.8))})
            EXPECT_EQ(r.brdfs[i].f(l, l), m.brdfs[i].f(l, l));
    }
}

TEST(ClothModelFile, BadModelsNameTheKey) {
    auto err = [](const std::string& text) {
        try {
            model_from_json(text, "m.json");
        } catch (const InputError& e) {
            return std::string(e.what());
        }
        return std::string();
    };
    EXPECT_NE(err("{").find("m.json: not JSON"), std::string::npos);
    EXPECT_NE(err("{\"kind\":\"other\"}").find("not a cloth model"), std::string::npos);
    const std::string head = "{\"schema\":1,\"kind\":\"mesolab.cloth.model\",\"lobes\":1,\"points\":[";
    EXPECT_NE(err(head + "{\"kd\":[0,0,0],\"lobes\":[]}]}").find("points[0].lobes: expected 1 lobes"), std::string::npos);
    EXPECT_NE(err(head + "{\"kd\":[0,0],\"lobes\":[]}]}").find("points[0].kd"), std::string::npos);
    EXPECT_NE(err(head + "{\"kd\":[0,0,0],\"lobes\":[{\"Cx\":[1,1,1],\"Cy\":[1,1,1],\"Cz\":[1,1,1],\"n\":[1,0,1]}]}]}").find(
                  "points[0].lobes[0].n"),
              std::string::npos);
    EXPECT_NE(err(head + "]}").find("\"points\" must be a non-empty array"), std::string::npos);
}

TEST(ClothSampleGridFile, RoundTripKeepsTheGridAndBadFilesNameThemselves) {
    SampleGrid g;
    g.res = 2;
    g.views = {dvec3(0, 0, 1), glm::normalize(dvec3(1, 0, 1))};
    for (int v = 0; v < 2; ++v)
        for (int l = 0; l < 3; ++l) g.l.push_back(glm::normalize(dvec3(0.1 * l, 0.2, 1.0))), g.v.push_back(g.views[size_t(v)]), g.view_of.push_back(v);
    for (int p = 0; p < 4; ++p) {
        std::vector<dvec3> f;
        for (int i = 0; i < 6; ++i) f.push_back(dvec3(0.25 * i, 0.5 + p, 0.125));  // exact in float
        g.f.push_back(f);
        g.alpha.push_back({1.0, 0.5});
        g.normal.push_back(glm::normalize(dvec3(0.1 * p, 0, 1))), g.tangent.push_back(dvec3(1, 0, 0));
    }
    const std::string path = (std::filesystem::temp_directory_path() / "mesolab_cloth_samples_test.bin").string();
    write_sample_grid(path, g);
    const SampleGrid r = read_sample_grid(path);
    EXPECT_EQ(r.res, 2);
    EXPECT_EQ(r.views, g.views);
    EXPECT_EQ(r.l, g.l);
    EXPECT_EQ(r.v, g.v);
    EXPECT_EQ(r.view_of, g.view_of);
    EXPECT_EQ(r.f, g.f);
    EXPECT_EQ(r.alpha, g.alpha);
    EXPECT_EQ(r.normal, g.normal);
    // Truncated, altered and foreign files: errors naming the file, never a crash.
    std::string bytes = sample_grid_bytes(g);
    for (size_t cut : {size_t(5), size_t(40), bytes.size() - 1}) {
        try {
            sample_grid_from_bytes(bytes.substr(0, cut), "g.bin");
            FAIL() << cut;
        } catch (const InputError& e) {
            EXPECT_EQ(std::string(e.what()).rfind("g.bin: ", 0), 0u) << e.what();
        }
    }
    std::string nan = bytes;
    const float q = std::nanf("");
    std::memcpy(nan.data() + nan.size() - 4, &q, 4);
    EXPECT_THROW(sample_grid_from_bytes(nan, "g.bin"), InputError);
    EXPECT_THROW(sample_grid_from_bytes("{\"kind\":\"json\"}", "g.bin"), InputError);
    std::filesystem::remove(path);
}
