// Levels of detail (Heidrich et al. 2000, §6, Fig. 9): displaced geometry, bump map and simulated
// BRDF of one heightfield agree; the BTF export's tiles are the goniometer's images; both render
// paths agree on the new levels.
#include "app/workbench.h"
#include "core/microgeom/stages.h"
#include "core/error.h"
#include "core/image.h"
#include "core/microgeom/btf.h"
#include "core/microgeom/lod.h"
#include "core/microgeom/microgeom.h"
#include "core/scene.h"
#include "core/session.h"
#include "agreement.h"
#include "support/cli.h"
#include "support/frames.h"

#include <gtest/gtest.h>
#include <cmath>
#include <cstdio>

using namespace mesolab;
using namespace mesolab::microgeom;
using namespace mesolab::test;

namespace {
double mean_channel(const Image& img, int c) {
    double s = 0;
    for (int y = 0; y < img.height; ++y)
        for (int x = 0; x < img.width; ++x) s += img.at(x, y)[c];
    return s / double(img.width) / double(img.height);
}

Scene texture_scene(const char* lod, const char* field, int res) {
    Scene s = default_scene("microgeom");
    apply_set(s, "camera.mode", "texture");
    apply_set(s, "camera.orbit", "0,0");
    apply_set(s, "geometry.type", "plane");
    apply_set(s, "effects.environment", "false");
    apply_set(s, "env.color", "0,0,0");
    apply_set(s, "microgeom.heightfield", field);
    apply_set(s, "microgeom.resolution", std::to_string(res));
    apply_set(s, "microgeom.lod", lod);
    return s;
}
}  // namespace

// A flat field displaces nothing; a bumpy one moves vertices along the normal by (h - mean h) in
// texel lengths, keeping uv, normals and tangents.
TEST(Lod, DisplacementFollowsTheHeightsInTexelLengths) {
    const TriMesh base = make_primitive(Primitive::Plane, 64);
    ProceduralParams p;
    p.name = "flat";
    p.resolution = 32;
    const TriMesh flat = displace(base, make_procedural(p), 2.f);
    for (size_t v = 0; v < base.vertex_count(); ++v) EXPECT_EQ(flat.position[v], base.position[v]);

    p.name = "bumps";
    const Heightfield hf = make_procedural(p);
    const float tiling = 2.f;
    const TriMesh m = displace(base, hf, tiling);
    double mean = 0;
    for (float h : hf.h) mean += h;
    mean /= double(hf.h.size());
    const float texel = 2.f / (32.f * tiling);  // the plane spans 2 units per uv unit
    float max_dz = -1e9f, min_dz = 1e9f;
    for (size_t v = 0; v < m.vertex_count(); ++v) {
        EXPECT_FLOAT_EQ(m.position[v].x, base.position[v].x);
        EXPECT_FLOAT_EQ(m.position[v].y, base.position[v].y);
        EXPECT_EQ(m.uv[v], base.uv[v]);
        EXPECT_EQ(m.normal[v], base.normal[v]);
        max_dz = std::max(max_dz, m.position[v].z);
        min_dz = std::min(min_dz, m.position[v].z);
    }
    // Vertices sample the field between texel centres (bilinear), so the extremes are within the field's.
    EXPECT_LE(max_dz, (hf.max_height() - float(mean)) * texel + 1e-5f);
    EXPECT_GE(min_dz, (hf.min_height() - float(mean)) * texel - 1e-5f);
    EXPECT_GT(max_dz - min_dz, 0.5f * (hf.max_height() - hf.min_height()) * texel);
    bool capped = true;
    EXPECT_EQ(displacement_resolution("sphere", 64, 128, 128, 4.f, 2048, &capped), 1024);
    EXPECT_FALSE(capped);
    EXPECT_EQ(displacement_resolution("teapot", 64, 128, 128, 4.f, 2048, &capped), 1024);  // 4 patch cells along v, 8 along u
    EXPECT_FALSE(capped);
    EXPECT_EQ(displacement_resolution("torus", 64, 128, 128, 4.f, 2048, &capped), 512);
    EXPECT_EQ(displacement_resolution("plane", 64, 1024, 1024, 4.f, 2048, &capped), 2048);
    EXPECT_TRUE(capped);
}

// Texture space seen straight down: the bump level's image averaged equals the BRDF level's value
// (the goniometer's average of the same image, with masking, which is ~1 straight down), for a
// light at a table node (no interpolation error) and between nodes (bilinear error only).
TEST(Lod, BumpImageAverageEqualsTheSimulatedBrdf) {
    Workbench wb;
    for (const char* field : {"bricks", "triangles"}) {
        SCOPED_TRACE(field);
        // Node theta_3 of 8 = 3/7 * 90 degrees, phi_1 = 45 degrees; and a light between nodes.
        for (const char* light : {"38.571428571,45", "33,20"}) {
            SCOPED_TRACE(light);
            Scene bump = texture_scene("bump", field, 32), brdf = texture_scene("brdf", field, 32);
            for (Scene* s : {&bump, &brdf}) apply_set(*s, "light.direction", light);
            RenderRequest req;
            req.renderer = "cpu";
            const Frame fa = wb.render(bump, req).frame, fb = wb.render(brdf, req).frame;
            const Image &a = fa.aov("radiance"), &b = fb.aov("radiance");
            const bool node = std::string(light).rfind("38.57", 0) == 0;
            for (int c = 0; c < 3; ++c) {
                const double ma = mean_channel(a, c), mb = mean_channel(b, c);
                EXPECT_NEAR(mb, ma, (node ? 0.02 : 0.06) * ma) << "channel " << c;
            }
            // The shadow AOV: the bump level's per-texel fraction averaged = the BRDF's shadow table.
            const double sa = mean_channel(fa.aov("shadow"), 0), sb = mean_channel(fb.aov("shadow"), 0);
            EXPECT_NEAR(sb, sa, (node ? 0.02 : 0.06) * sa);
            EXPECT_GT(sa, 0.3);
        }
    }
}

// The geometry level equals the bump level on average over the pixels both cover: displacement
// adds parallax and real masking (faces turned to the viewer cover more pixels, which bump
// mapping ignores) but does not change the radiance each texel sends. Measured on the Fig. 9
// ridges: red +6%, green/blue -7% (the real geometry shows more of the red faces), total -1%.
TEST(Lod, GeometryAndBumpAgreeOnAverage) {
    Workbench wb;
    Scene bump = load_preset(source_path("presets/microgeom/fig9-geometry-vs-brdf.json"));
    bump.objects.resize(2);  // the geometry row
    Scene geo = bump;
    for (auto& o : bump.objects) o.material.set("lod", std::string("bump"));
    RenderRequest req;
    req.renderer = "cpu";
    req.width = req.height = 256;
    const Frame fa = wb.render(geo, req).frame, fb = wb.render(bump, req).frame;
    const Image &a = fa.aov("radiance"), &b = fb.aov("radiance"), &na = fa.aov("normal"), &nb = fb.aov("normal");
    double sa[3] = {0, 0, 0}, sb[3] = {0, 0, 0};
    size_t both = 0;
    for (int y = 0; y < a.height; ++y)
        for (int x = 0; x < a.width; ++x) {
            auto covered = [&](const Image& n) { return n.at(x, y)[0] != 0.f || n.at(x, y)[1] != 0.f || n.at(x, y)[2] != 0.f; };
            if (!covered(na) || !covered(nb)) continue;
            ++both;
            for (int c = 0; c < 3; ++c) sa[c] += a.at(x, y)[c], sb[c] += b.at(x, y)[c];
        }
    ASSERT_GT(both, size_t(5000));
    for (int c = 0; c < 3; ++c) {
        std::printf("channel %d: geometry %.5f bump %.5f (%.1f%%)\n", c, sa[c] / double(both), sb[c] / double(both), 100.0 * (sa[c] / sb[c] - 1.0));
        EXPECT_NEAR(sa[c], sb[c], 0.10 * sb[c]) << "channel " << c;
    }
    // The total (sum of channels) agrees closer: masking shifts the colour (more red faces seen), not the energy.
    EXPECT_NEAR(sa[0] + sa[1] + sa[2], sb[0] + sb[1] + sb[2], 0.03 * (sb[0] + sb[1] + sb[2]));
}

// Every tile of the BTF mosaic is the goniometer image for its (light, view) pair.
TEST(Lod, BtfTilesAreGoniometerImages) {
    ProceduralParams p;
    p.name = "bumps";
    p.resolution = 16;
    const Heightfield hf = make_procedural(p);
    const DirectionSet dirs = make_direction_set(64);
    const Visibility vis = compute_visibility(hf, dirs);
    GonioSettings gs;
    gs.scatter.depth = 2;
    gs.phong = true;
    gs.ks = vec3(0.1f);
    const std::vector<vec3> lights = btf_directions(2, 3), views = btf_directions(2, 2);
    const Image mosaic = btf_mosaic(hf, dirs, vis, gs, lights, views);
    ASSERT_EQ(mosaic.width, 16 * 4);
    ASSERT_EQ(mosaic.height, 16 * 6);
    for (size_t li = 0; li < lights.size(); li += 2)
        for (size_t vi = 0; vi < views.size(); ++vi) {
            const Image tile = goniometer_image(hf, dirs, vis, gs, lights[li], views[vi]);
            for (int y = 0; y < 16; ++y)
                for (int x = 0; x < 16; ++x)
                    for (int c = 0; c < 3; ++c)
                        ASSERT_NEAR(mosaic.at(int(vi) * 16 + x, int(li) * 16 + y)[c], tile.at(x, y)[c], 1e-5f + 1e-4f * std::fabs(tile.at(x, y)[c]))
                            << "light " << li << " view " << vi << " texel " << x << "," << y;
        }
    EXPECT_THROW(btf_mosaic(hf, dirs, vis, gs, btf_directions(64, 128), views), InputError);
}

// The export command writes the mosaic and its sidecar; a bad option names itself.
TEST(Lod, BtfExportCommand) {
    TempDir dir("btf");
    const std::string out = dir / "btf.exr";
    const std::string preset = "presets/microgeom/fig1a-no-scattering.json";
    const auto r = run_mesolab("export btf " + preset + " -o '" + out + "' --option grid=2x3 --set microgeom.resolution=16");
    ASSERT_EQ(r.status, 0) << r.out << r.err;
    const Image img = read_image(out);
    EXPECT_EQ(img.width, 16 * 6);
    EXPECT_EQ(img.height, 16 * 6);
    EXPECT_NE(slurp(out + ".json").find("views_theta_phi_deg"), std::string::npos);
    const auto bad = run_mesolab("export btf " + preset + " -o '" + out + "' --option gird=2x3");
    EXPECT_EQ(bad.status, 2);
    EXPECT_NE(bad.err.find("gird"), std::string::npos) << bad.err;
    const auto bad2 = run_mesolab("export btf " + preset + " -o '" + out + "' --option grid=0x3");
    EXPECT_EQ(bad2.status, 2);
    EXPECT_NE(bad2.err.find("grid=0x3"), std::string::npos) << bad2.err;
    const auto bad3 = run_mesolab("export nope " + preset + " -o '" + out + "'");
    EXPECT_EQ(bad3.status, 2);
    EXPECT_NE(bad3.err.find("btf"), std::string::npos) << "the error lists the known exports: " << bad3.err;
}

// CPU and GPU agree on the geometry and BRDF levels (Fig. 9 preset): same tolerances as the bump
// level's orbit views (silhouettes of the displaced spheres differ by rasterisation).
TEST(Lod, CpuAndGpuAgreeOnGeometryAndBrdf) {
    Workbench wb;
    Scene s = load_preset(source_path("presets/microgeom/fig9-geometry-vs-brdf.json"));
    const auto [cpu, gpu] = render_cpu_and_gpu(wb, s, 160, 160);
    expect_frames_agree(cpu, gpu, {"radiance", "normal", "direct", "indirect", "shadow"}, agreement_of("microgeom"));
}

// Physical scale and albedo images: an image heightfield's values are heights in the unit of
// texel_size (height in texels = value * height_scale / texel_size); an albedo image is resampled
// onto the texels and multiplies microgeom.albedo; a missing or NaN image is an InputError naming it.
TEST(Lod, TexelSizeAndAlbedoMap) {
    TempDir dir("albedo");
    Image h(8, 8, 1, 0.f), a(2, 2, 3, 0.f);
    for (int y = 0; y < 8; ++y)
        for (int x = 0; x < 8; ++x) h.at(x, y)[0] = float(x % 2);
    for (int c = 0; c < 3; ++c) a.at(0, 0)[c] = a.at(1, 0)[c] = a.at(0, 1)[c] = a.at(1, 1)[c] = 0.5f;
    write_exr(dir / "h.exr", h);
    write_exr(dir / "a.exr", a);
    const StageGraph& g = Registry::instance().stages();
    auto field = [&](const char* texel_size, const std::string& albedo_map) {
        Scene s = texture_scene("bump", "bricks", 8);
        apply_set(s, "microgeom.heightfield", dir / "h.exr");
        apply_set(s, "microgeom.texel_size", texel_size);
        apply_set(s, "microgeom.albedo", "1,1,1");
        apply_set(s, "microgeom.albedo_map", albedo_map);
        Session session(g);
        const Evaluation ev = session.evaluate(s, {microgeom::stages::heightfield});
        return *ev.get(microgeom::stages::heightfield, 0);
    };
    const Heightfield h1 = field("1", ""), h05 = field("0.5", dir / "a.exr");
    EXPECT_FLOAT_EQ(h1.max_height() / h1.texel_size, 1.f);
    EXPECT_FLOAT_EQ(h05.max_height() / h05.texel_size, 2.f) << "half the texel size doubles the height in texels";
    EXPECT_NEAR(h05.albedo[0].x, 0.5f, 1e-6f);
    EXPECT_NEAR(h1.albedo[0].x, 1.f, 1e-6f) << "no map: the albedo parameter";
    try {
        field("1", dir / "missing.png");
        FAIL() << "a missing albedo map must be an InputError";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("missing.png"), std::string::npos) << e.what();
    }
}
