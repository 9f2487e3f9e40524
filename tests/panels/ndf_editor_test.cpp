// The bumpsynth panel's NDF editor: the brush paints exactly symmetric images under the mirror
// symmetries and never below 0, undo / redo restore images exactly, a stroke is saved as an EXR
// that the bumpsynth.ndf stage reads back with the mass where it was painted, the lobe handles and
// the add / remove lobe buttons edit the material, bad files are reported and change nothing, and
// the ImGui editor does all of it from simulated mouse and keyboard input in a headless context.
#include "core/bumpsynth/bumpsynth.h"
#include "core/bumpsynth/stages.h"
#include "core/image.h"
#include "core/scene.h"
#include "core/session.h"
#include "core/stage.h"
#include "core/technique.h"
#include "panels/bumpsynth/ndf_editor.h"
#include "panels/panel.h"
#include "support/cli.h"
#include "support/errors.h"
#include "support/headless_imgui.h"

#include <gtest/gtest.h>
#include <imgui.h>
#include <filesystem>

using namespace mesolab;
using namespace mesolab::panels;
using namespace mesolab::panels::ndf_editor;
using mesolab::test::HeadlessImGui;
using mesolab::test::TempDir;

namespace {

// A stroke along the points, from an empty R x R image.
NdfImage painted(Symmetry s, std::initializer_list<vec2> points, int R = 64, float strength = 2.f, int fold = 6) {
    Painter p(NdfImage{R});
    Brush b;
    b.radius = 0.2f;
    b.strength = strength;
    b.symmetry = s;
    b.fold = fold;
    p.begin_stroke(b);
    for (vec2 q : points) p.stroke_to(q);
    p.end_stroke();
    return p.image();
}

// Mass-weighted centroid and total of the tabulated NDF.
struct Moments {
    double x = 0, y = 0, mass = 0;
};
Moments moments(const bumpsynth::Ndf& d) {
    Moments m;
    for (int j = 0; j < d.resolution(); ++j)
        for (int i = 0; i < d.resolution(); ++i) {
            const vec2 c = d.cell_centre(i, j);
            m.x += d.mass(i, j) * double(c.x);
            m.y += d.mass(i, j) * double(c.y);
            m.mass += d.mass(i, j);
        }
    return m;
}
Moments moments_in_half(const bumpsynth::Ndf& d, bool right) {
    Moments m;
    for (int j = 0; j < d.resolution(); ++j)
        for (int i = 0; i < d.resolution(); ++i)
            if ((d.cell_centre(i, j).x > 0.f) == right) m.mass += d.mass(i, j);
    return m;
}

bumpsynth::Ndf read_back(const std::string& path, int R) {
    const Image img = read_image(path, false, true);
    EXPECT_EQ(img.channels, 1);
    return bumpsynth::Ndf::from_image(img.data, img.width, img.height, R);
}

Scene bumpsynth_scene(const std::string& base_dir) {
    Scene s = default_scene("bumpsynth");
    s.name = "my scene";
    s.objects[0].name = "ball";
    s.base_dir = base_dir;
    s.objects[0].material.set("ndf_resolution", int64_t(64));
    return s;
}

std::vector<std::string> files_in(const std::filesystem::path& dir) {
    std::vector<std::string> out;
    for (const auto& e : std::filesystem::directory_iterator(dir)) out.push_back(e.path().filename().string());
    std::sort(out.begin(), out.end());
    return out;
}
}  // namespace

// [SECTION] Brush
TEST(NdfEditorBrush, MirrorSymmetriesAreExact) {
    const std::initializer_list<vec2> stroke = {{0.31f, 0.17f}, {0.52f, -0.08f}, {0.12f, 0.63f}, {-0.05f, 0.4f}};
    const int R = 64;
    const NdfImage plain = painted(Symmetry::none, stroke);
    const NdfImage mx = painted(Symmetry::mirror_x, stroke), my = painted(Symmetry::mirror_y, stroke), both = painted(Symmetry::both, stroke);
    int asymmetric = 0;
    for (int r = 0; r < R; ++r)
        for (int c = 0; c < R; ++c) {
            asymmetric += plain.at(c, r) != plain.at(R - 1 - c, r);
            EXPECT_EQ(mx.at(c, r), mx.at(R - 1 - c, r)) << c << "," << r;
            EXPECT_EQ(my.at(c, r), my.at(c, R - 1 - r)) << c << "," << r;
            EXPECT_EQ(both.at(c, r), both.at(R - 1 - c, r)) << c << "," << r;
            EXPECT_EQ(both.at(c, r), both.at(c, R - 1 - r)) << c << "," << r;
            EXPECT_EQ(both.at(c, r), both.at(R - 1 - c, R - 1 - r)) << c << "," << r;
            // Each symmetric image covers at least what the plain stroke did.
            EXPECT_GE(mx.at(c, r), plain.at(c, r));
            EXPECT_GE(both.at(c, r), my.at(c, r));
        }
    EXPECT_GT(asymmetric, 100) << "the stroke itself is not symmetric, so the symmetry comes from the brush";
    EXPECT_GT(image_mass(plain), 0.0);
    EXPECT_NEAR(image_mass(mx), 2.0 * image_mass(plain), 0.2 * image_mass(plain)) << "two copies of a stroke that barely meets its mirror";
}

TEST(NdfEditorBrush, RotationalSymmetryPaintsEveryCopy) {
    const int R = 128, fold = 5;
    const vec2 p(0.55f, 0.1f);
    const NdfImage img = painted(Symmetry::rotational, {p}, R, 3.f, fold);
    const auto pts = symmetric_points(p, Symmetry::rotational, fold);
    ASSERT_EQ(pts.size(), size_t(fold));
    for (vec2 q : pts) {
        const int c = int((q.x + 1.f) * 0.5f * R), r = int((1.f - q.y) * 0.5f * R);
        EXPECT_GT(img.at(c, r), 0.9f * 3.f) << "the copy at " << q.x << "," << q.y;
    }
    const NdfImage one = painted(Symmetry::none, {p}, R, 3.f);
    EXPECT_NEAR(image_mass(img), fold * image_mass(one), 0.05 * fold * image_mass(one)) << "five equal copies";
}

TEST(NdfEditorBrush, EraseNeverGoesNegative) {
    const int R = 64;
    Painter p(NdfImage(R, 0.5f));
    Brush b;
    b.radius = 0.3f;
    b.strength = 100.f;
    b.erase = true;
    b.symmetry = Symmetry::both;
    p.begin_stroke(b);
    for (float x = -0.9f; x <= 0.9f; x += 0.05f) p.stroke_to({x, 0.2f * x});
    EXPECT_TRUE(p.end_stroke());
    int zeros = 0;
    for (float v : p.image().px) {
        EXPECT_GE(v, 0.f);
        EXPECT_TRUE(v == 0.f || v == 0.5f || (v > 0.f && v < 0.5f));
        zeros += v == 0.f;
    }
    EXPECT_GT(zeros, 200);
    EXPECT_EQ(p.image().at(0, 0), 0.5f) << "a corner far from the stroke is untouched";

    // Erasing an empty image changes nothing and leaves no undo step.
    Painter e(NdfImage{R});
    e.begin_stroke(b);
    e.stroke_to({0.f, 0.f});
    EXPECT_FALSE(e.end_stroke());
    EXPECT_FALSE(e.can_undo());
    ASSERT_EQ(e.image().px.size(), size_t(R) * size_t(R));
    for (float v : e.image().px) EXPECT_EQ(v, 0.f);
}

TEST(NdfEditorBrush, OneStrokeAddsAtMostItsStrengthWhateverTheDabSpacing) {
    Painter p(NdfImage{64});
    Brush b;
    b.strength = 2.f;
    p.begin_stroke(b);
    for (int k = 0; k < 20; ++k) p.stroke_to({0.1f, 0.1f});  // the same point, over and over
    p.stroke_to({0.12f, 0.1f});
    p.stroke_to({0.1f, 0.1f});
    p.end_stroke();
    const float peak = *std::max_element(p.image().px.begin(), p.image().px.end());
    EXPECT_LE(peak, 2.f);
    EXPECT_GT(peak, 1.8f);
    // A second stroke over the same spot adds again.
    p.begin_stroke(b);
    p.stroke_to({0.1f, 0.1f});
    p.end_stroke();
    EXPECT_GT(*std::max_element(p.image().px.begin(), p.image().px.end()), 3.6f);
}

// [SECTION] Undo
TEST(NdfEditorUndo, UndoRedoRoundTripsTheImageExactly) {
    const NdfImage start = image_from_ndf(bumpsynth::Ndf::from_lobe(bumpsynth::Lobe::beckmann(0.2f, 0.4f, 20.f), 64));
    Painter p(start);
    std::vector<NdfImage> after;
    Brush b;
    b.strength = 5.f;
    for (int k = 0; k < 3; ++k) {
        b.erase = k == 1;
        b.symmetry = k == 2 ? Symmetry::rotational : Symmetry::none;
        p.begin_stroke(b);
        p.stroke_to({0.1f * float(k), 0.3f});
        p.stroke_to({0.4f, -0.2f * float(k)});
        ASSERT_TRUE(p.end_stroke());
        after.push_back(p.image());
    }
    EXPECT_EQ(p.undo_steps(), 3u);
    for (int k = 2; k >= 0; --k) {
        EXPECT_EQ(p.image(), after[size_t(k)]);
        ASSERT_TRUE(p.undo());
    }
    EXPECT_EQ(p.image(), start) << "three undos give back the NDF's own values, bit for bit";
    EXPECT_FALSE(p.undo());
    for (int k = 0; k < 3; ++k) {
        ASSERT_TRUE(p.redo());
        EXPECT_EQ(p.image(), after[size_t(k)]);
    }
    EXPECT_FALSE(p.redo());
    // A new stroke after an undo drops the redo branch.
    p.undo();
    p.begin_stroke(b);
    p.stroke_to({-0.5f, -0.5f});
    p.end_stroke();
    EXPECT_FALSE(p.can_redo());
    // Clear is one step too.
    p.replace(NdfImage{64});
    ASSERT_TRUE(p.undo());
    EXPECT_NE(p.image(), NdfImage{64});
}

TEST(NdfEditorUndo, KeepsAtLeast32Steps) {
    Painter p(NdfImage{64});
    Brush b;
    b.strength = 0.1f;
    for (int k = 0; k < 100; ++k) {
        p.begin_stroke(b);
        p.stroke_to({0.f, 0.f});
        p.end_stroke();
    }
    EXPECT_EQ(p.undo_steps(), Painter::kHistory);
    EXPECT_GE(Painter::kHistory, 32u);
    int undone = 0;
    while (p.undo()) ++undone;
    EXPECT_EQ(undone, int(Painter::kHistory));
    EXPECT_GT(p.image().at(32, 32), 0.f) << "the oldest strokes are forgotten, not undone";
}

// [SECTION] Files
TEST(NdfEditorFiles, AStrokeSavesAnExrWithTheMassWherePainted) {
    TempDir dir("ndfeditor-stroke");
    Scene s = bumpsynth_scene(dir.path.string());
    Painter p(NdfImage{64});
    Brush b;
    b.radius = 0.1f;
    p.begin_stroke(b);
    p.stroke_to({0.5f, 0.f});
    ASSERT_TRUE(p.end_stroke());
    Dirty dirty;
    const std::string path = apply_painted(s, 0, p.image(), dirty);
    EXPECT_EQ(path, dir / "my_scene.ball.ndf.exr");
    EXPECT_EQ(files_in(dir.path), std::vector<std::string>{"my_scene.ball.ndf.exr"}) << "no temporary file left behind";
    EXPECT_TRUE(dirty.recompute);
    const ParamTable& m = s.objects[0].material;
    EXPECT_EQ(m.get_string("ndf"), "image");
    EXPECT_EQ(m.get_string("ndf_image"), "my_scene.ball.ndf.exr") << "relative: it resolves against base_dir";
    EXPECT_EQ(s.resolve(m.get_string("ndf_image")), path);

    const Moments a = moments(read_back(path, 64));
    EXPECT_NEAR(a.x, 0.5, 0.02);
    EXPECT_NEAR(a.y, 0.0, 0.02);
    EXPECT_NEAR(a.mass, 1.0, 1e-9);

    // The stage reads it too; a second stroke re-saves the same file and the stage follows.
    Session session;
    const Evaluation e0 = session.evaluate(s, {bumpsynth::stages::ndf});
    EXPECT_NEAR(moments(*e0.get(bumpsynth::stages::ndf, 0)).x, 0.5, 0.02);
    p.begin_stroke(b);
    p.stroke_to({-0.5f, 0.f});
    ASSERT_TRUE(p.end_stroke());
    EXPECT_EQ(apply_painted(s, 0, p.image(), dirty), path);
    const Evaluation e1 = session.evaluate(s, {bumpsynth::stages::ndf});
    EXPECT_EQ(e1.run(bumpsynth::stages::ndf)->status, StageStatus::Ran) << "the re-saved file is a new input";
    const bumpsynth::Ndf& d1 = *e1.get(bumpsynth::stages::ndf, 0);
    EXPECT_NEAR(moments(d1).x, 0.0, 0.02);
    EXPECT_NEAR(moments_in_half(d1, false).mass, 0.5, 0.02);
}

TEST(NdfEditorFiles, PaintedFileNamesAreSafeAndLandInTheCurrentFolderWithoutAPreset) {
    Scene s = default_scene("bumpsynth");
    s.name = "../a b";
    s.objects[0].name = "x/y";
    EXPECT_EQ(painted_file_name(s, 0), "_a_b.x_y.ndf.exr");
    EXPECT_EQ(painted_file_path(s, 0), "_a_b.x_y.ndf.exr");
    s.name.clear();
    s.objects[0].name.clear();
    EXPECT_EQ(painted_file_name(s, 0), "scene.object0.ndf.exr");
}

TEST(NdfEditorFiles, AnEmptyImageIsNotApplied) {
    TempDir dir("ndfeditor-empty");
    Scene s = bumpsynth_scene(dir.path.string());
    const ParamTable before = s.objects[0].material;
    Dirty dirty;
    test::expect_input_error([&] { apply_painted(s, 0, NdfImage{64}, dirty); }, {"empty inside the disk"});
    EXPECT_EQ(s.objects[0].material, before);
    EXPECT_FALSE(dirty.any());
    EXPECT_TRUE(files_in(dir.path).empty());
}

TEST(NdfEditorFiles, LoadReportsBadFilesAndChangesNothing) {
    TempDir dir("ndfeditor-load");
    Scene s = bumpsynth_scene(dir.path.string());
    const ParamTable before = s.objects[0].material;
    Dirty dirty;
    test::expect_input_error([&] { load_ndf_file(s, 0, "missing.exr", dirty); }, {"missing.exr", "no such file"});
    test::write_file(dir / "garbage.exr", "this is not an image");
    test::expect_input_error([&] { load_ndf_file(s, 0, "garbage.exr", dirty); }, {"garbage.exr"});
    Image neg(8, 8, 1, 1.f);
    *neg.at(3, 3) = -1.f;
    write_exr(dir / "negative.exr", neg);
    test::expect_input_error([&] { load_ndf_file(s, 0, "negative.exr", dirty); }, {"negative.exr", ">= 0"});
    write_exr(dir / "zero.exr", Image(8, 8, 1, 0.f));
    test::expect_input_error([&] { load_ndf_file(s, 0, "zero.exr", dirty); }, {"zero.exr"});
    test::expect_input_error([&] { load_ndf_file(s, 0, "", dirty); }, {"path"});
    EXPECT_EQ(s.objects[0].material, before);
    EXPECT_FALSE(dirty.any());

    // A PNG (8-bit, any OpenImageIO format) with a bright spot at the top: the NDF's mass is at y > 0.
    Image png(32, 32, 3, 0.f);
    for (int y = 2; y < 8; ++y)
        for (int x = 13; x < 19; ++x) std::fill(png.at(x, y), png.at(x, y) + 3, 1.f);
    write_png_srgb(dir / "spot.png", png);
    const bumpsynth::Ndf d = load_ndf_file(s, 0, "spot.png", dirty);
    EXPECT_TRUE(dirty.recompute);
    EXPECT_EQ(s.objects[0].material.get_string("ndf"), "image");
    EXPECT_EQ(s.objects[0].material.get_string("ndf_image"), "spot.png");
    EXPECT_GT(moments(d).y, 0.6);
}

TEST(NdfEditorFiles, SaveWritesTheTabulatedValues) {
    TempDir dir("ndfeditor-save");
    const bumpsynth::Ndf d = bumpsynth::Ndf::from_lobe(bumpsynth::Lobe::ggx(0.1f, 0.3f, 60.f), 64);
    write_ndf_exr(dir / "ggx.exr", image_from_ndf(d));
    const bumpsynth::Ndf back = read_back(dir / "ggx.exr", 64);
    for (int j = 0; j < 64; ++j)
        for (int i = 0; i < 64; ++i) EXPECT_NEAR(back.value(i, j), d.value(i, j), 1e-5 * (1.0 + d.value(i, j))) << i << "," << j;
    test::expect_input_error([&] { write_ndf_exr(dir / "empty.exr", NdfImage{}); }, {"no NDF image"});
}

// [SECTION] Lobes
TEST(NdfEditorLobes, DraggingHandlesSetsAlphaAndRotation) {
    ParamTable m = Registry::instance().technique("bumpsynth")->params().defaults();
    m.set("alpha_x", 0.3);
    m.set("alpha_y", 0.2);
    m.set("rotation", 30.0);
    const auto hs = handles_of(m);
    ASSERT_EQ(hs.size(), 3u);
    EXPECT_NEAR(hs[0].pos.x, 0.3 * std::cos(radians(30.f)), 1e-6);
    EXPECT_NEAR(hs[0].pos.y, 0.3 * std::sin(radians(30.f)), 1e-6);
    Dirty dirty;
    const vec2 ex(std::cos(radians(30.f)), std::sin(radians(30.f))), ey(-ex.y, ex.x);
    EXPECT_TRUE(drag_handle(m, hs[0], 0.55f * ex + 0.1f * ey, dirty));  // off the axis: its projection counts
    EXPECT_NEAR(m.get_float("alpha_x"), 0.55, 1e-4);
    EXPECT_DOUBLE_EQ(m.get_float("alpha_y"), 0.2);
    EXPECT_TRUE(dirty.recompute);
    drag_handle(m, hs[1], -0.07f * ey, dirty);
    EXPECT_NEAR(m.get_float("alpha_y"), 0.07, 1e-4);
    drag_handle(m, hs[1], vec2(0.f), dirty);
    EXPECT_DOUBLE_EQ(m.get_float("alpha_y"), 1e-4) << "clamped to the declared range";
    drag_handle(m, hs[2], vec2(0.f, 1.1f), dirty);
    EXPECT_DOUBLE_EQ(m.get_float("rotation"), 90.0);
    Dirty none;
    EXPECT_FALSE(drag_handle(m, hs[2], vec2(0.f, 1.1f), none)) << "no change, nothing dirty";
    EXPECT_FALSE(none.any());

    // The second term of 'lobes': dragging rewrites that term only.
    m.set("ndf", std::string("lobes"));
    m.set("lobes", std::string("beckmann(0.3) + 0.5 * ggx(0.05, 0.5, 45)"));
    const auto h2 = handles_of(m);
    ASSERT_EQ(h2.size(), 6u);
    EXPECT_EQ(h2[3].lobe, 1);
    drag_handle(m, h2[3], vec2(0.f, 0.25f), dirty);  // rotation 45: project onto (cos 45, sin 45)
    EXPECT_EQ(m.get_string("lobes"), "beckmann(0.3) + 0.5 * ggx(0.1768, 0.5, 45)");
    drag_handle(m, h2[5], vec2(-1.1f, 0.f), dirty);
    EXPECT_EQ(m.get_string("lobes"), "beckmann(0.3) + 0.5 * ggx(0.1768, 0.5, 180)");
    EXPECT_EQ(lobes_of(m)[1].kind, "ggx");
    EXPECT_FLOAT_EQ(lobes_of(m)[1].rotation_deg, 180.f);

    // Phong: one handle, the equivalent width sqrt(2 / (e + 2)).
    m.set("ndf", std::string("phong"));
    const auto hp = handles_of(m);
    ASSERT_EQ(hp.size(), 1u);
    drag_handle(m, hp[0], vec2(0.2f, 0.f), dirty);
    EXPECT_NEAR(m.get_float("exponent"), 2.0 / 0.04 - 2.0, 0.01);
    m.set("ndf", std::string("image"));
    EXPECT_TRUE(handles_of(m).empty());
}

TEST(NdfEditorLobes, AddingAndRemovingLobesSwitchesTheNdf) {
    const ParamGroup& g = Registry::instance().technique("bumpsynth")->params();
    ParamTable m = g.defaults();
    m.set("ndf", std::string("ggx"));
    m.set("alpha_x", 0.12);
    Dirty dirty;
    ASSERT_TRUE(can_add_lobe(m));
    EXPECT_FALSE(can_remove_lobe(m));
    add_lobe(m, dirty);
    EXPECT_EQ(m.get_string("ndf"), "lobes");
    EXPECT_TRUE(dirty.recompute);
    EXPECT_EQ(m.get_string("lobes"), "ggx(0.12, 0.3) + 0.5 * ggx(0.05, 0.5, 45)") << "the single lobe keeps its kind";
    EXPECT_EQ(lobes_of(m).size(), 2u);
    ASSERT_TRUE(can_add_lobe(m)) << "any number of lobes";
    add_lobe(m, dirty);
    EXPECT_EQ(lobes_of(m).size(), 3u);
    EXPECT_TRUE(can_remove_lobe(m));
    remove_lobe(m, dirty);
    EXPECT_EQ(lobes_of(m).size(), 2u);
    remove_lobe(m, dirty);
    EXPECT_EQ(m.get_string("ndf"), "ggx") << "one lobe left: back to its own keys";
    EXPECT_DOUBLE_EQ(m.get_float("alpha_x"), 0.12);
    EXPECT_EQ(lobes_of(m).size(), 1u);

    m.set("ndf", std::string("phong"));
    m.set("exponent", 48.0);
    add_lobe(m, dirty);
    EXPECT_EQ(m.get_string("ndf"), "lobes");
    EXPECT_EQ(m.get_string("lobes"), "phong(48) + 0.5 * ggx(0.05, 0.5, 45)");
    EXPECT_NEAR(lobes_of(m)[0].alpha.x, 0.2, 1e-4) << "Phong's circle: the equivalent width sqrt(2 / 50)";
    remove_lobe(m, dirty);
    EXPECT_EQ(m.get_string("ndf"), "phong");
    EXPECT_DOUBLE_EQ(m.get_float("exponent"), 48.0);
    m.set("ndf", std::string("image"));
    EXPECT_FALSE(can_add_lobe(m));
    EXPECT_FALSE(can_remove_lobe(m));
}

// [SECTION] Display
TEST(NdfEditorDisplay, GridAveragesDownToTheDrawLimitAndMapsColours) {
    const NdfImage img = image_from_ndf(bumpsynth::Ndf::from_lobe(bumpsynth::Lobe::beckmann(0.3f, 0.3f), 256));
    const DisplayGrid g = display_grid(img, 128);
    EXPECT_EQ(g.n, 128);
    EXPECT_TRUE(std::isnan(g.v[0])) << "the corner is outside the disk";
    EXPECT_NEAR(g.vmax, 1.0 / (3.14159265 * 0.09), 0.05 * 1.0 / (3.14159265 * 0.09));
    ViewOptions lin;
    lin.log = false;
    EXPECT_FLOAT_EQ(display_t(lin, g.vmax, g.vmax), 1.f);
    EXPECT_FLOAT_EQ(display_t(lin, 0.5f * g.vmax, g.vmax), 0.5f);
    ViewOptions lg;
    lg.decades = 4.f;
    EXPECT_FLOAT_EQ(display_t(lg, g.vmax * 1e-2f, g.vmax), 0.5f);
    EXPECT_FLOAT_EQ(display_t(lg, g.vmax * 1e-6f, g.vmax), 0.f);
    EXPECT_FLOAT_EQ(display_t(lg, 0.f, g.vmax), 0.f);
    EXPECT_NE(color_of(ColorMap::viridis, 0.f), color_of(ColorMap::viridis, 1.f));
    EXPECT_EQ(color_of(ColorMap::grey, 1.f), 0xFFFFFFFFu);
}

// [SECTION] The ImGui editor, headless
namespace {
// One evaluation of the NDF stage for the scene.
Evaluation evaluate_ndf(const Scene& s) {
    Session session;
    return session.evaluate(s, {bumpsynth::stages::ndf});
}

void mouse_to(HeadlessImGui& ui, const std::function<void()>& draw, std::array<float, 2> p) {
    ImGui::GetIO().MousePos = ImVec2(p[0], p[1]);
    ui.frame(draw);
}
}  // namespace

TEST(NdfEditorGui, DraggingTheAlphaXHandleInTheViewChangesAlphaX) {
    HeadlessImGui ui;
    Scene s = bumpsynth_scene("");
    s.objects[0].material.set("alpha_x", 0.3);
    s.objects[0].material.set("alpha_y", 0.3);
    const Evaluation ev = evaluate_ndf(s);
    Dirty dirty;
    PanelContext ctx{s, dirty, &ev, 0};
    NdfEditor ed;
    auto draw = [&] { ed.draw(ctx, 0); };
    ui.frame(draw);
    ui.frame(draw);
    EXPECT_FALSE(dirty.any()) << "drawing alone changes nothing";
    ImGuiIO& io = ImGui::GetIO();
    mouse_to(ui, draw, ed.screen_of({0.3f, 0.f}));  // the alpha_x handle (rotation 0: on +x)
    io.MouseDown[0] = true;
    ui.frame(draw);
    mouse_to(ui, draw, ed.screen_of({0.45f, 0.02f}));
    mouse_to(ui, draw, ed.screen_of({0.6f, 0.05f}));
    io.MouseDown[0] = false;
    ui.frame(draw);
    const float px = 1.f / (ed.screen_of({1.f, 0.f})[0] - ed.screen_of({0.f, 0.f})[0]);  // one pixel in disk units
    EXPECT_NEAR(s.objects[0].material.get_float("alpha_x"), 0.6, 2.0 * px);
    EXPECT_DOUBLE_EQ(s.objects[0].material.get_float("alpha_y"), 0.3);
    EXPECT_TRUE(dirty.recompute);

    // Pressing away from every handle changes nothing.
    Dirty d2;
    PanelContext ctx2{s, d2, &ev, 0};
    auto draw2 = [&] { ed.draw(ctx2, 0); };
    mouse_to(ui, draw2, ed.screen_of({-0.5f, -0.5f}));
    io.MouseDown[0] = true;
    ui.frame(draw2);
    mouse_to(ui, draw2, ed.screen_of({-0.2f, -0.6f}));
    io.MouseDown[0] = false;
    ui.frame(draw2);
    EXPECT_FALSE(d2.any());
}

TEST(NdfEditorGui, APaintStrokeIsAppliedAndCtrlZUndoesIt) {
    TempDir dir("ndfeditor-gui");
    HeadlessImGui ui;
    Scene s = bumpsynth_scene(dir.path.string());
    const Evaluation ev = evaluate_ndf(s);
    Dirty dirty;
    PanelContext ctx{s, dirty, &ev, 0};
    NdfEditor ed;
    auto draw = [&] { ed.draw(ctx, 0); };
    ui.frame(draw);
    ed.start_empty(64);
    ed.brush.radius = 0.1f;
    ed.brush.strength = 1.f;
    ui.frame(draw);
    ImGuiIO& io = ImGui::GetIO();
    mouse_to(ui, draw, ed.screen_of({0.5f, 0.f}));
    io.MouseDown[0] = true;
    ui.frame(draw);
    mouse_to(ui, draw, ed.screen_of({0.5f, 0.05f}));
    io.MouseDown[0] = false;
    ui.frame(draw);
    EXPECT_TRUE(ed.error().empty()) << ed.error();
    EXPECT_TRUE(dirty.recompute);
    EXPECT_EQ(s.objects[0].material.get_string("ndf"), "image");
    const std::string path = dir / "my_scene.ball.ndf.exr";
    ASSERT_TRUE(std::filesystem::exists(path));
    EXPECT_NEAR(moments(read_back(path, 64)).x, 0.5, 0.03);
    const NdfImage stroke = ed.painter().image();

    // A right-button stroke erases.
    mouse_to(ui, draw, ed.screen_of({0.5f, 0.f}));
    io.MouseDown[1] = true;
    ui.frame(draw);
    io.MouseDown[1] = false;
    ui.frame(draw);
    EXPECT_LT(image_mass(ed.painter().image()), image_mass(stroke));
    EXPECT_EQ(ed.painter().undo_steps(), 2u);

    // Ctrl+Z twice: back to the empty image, which is not applied (and said so); Ctrl+Y: the stroke again, applied.
    io.KeyMap[ImGuiKey_Z] = 90;
    io.KeyMap[ImGuiKey_Y] = 89;
    auto key = [&](int k) {
        io.KeyCtrl = true;
        io.KeysDown[k] = true;
        ui.frame(draw);
        io.KeysDown[k] = false;
        io.KeyCtrl = false;
        ui.frame(draw);
    };
    key(90);
    EXPECT_EQ(ed.painter().image(), stroke);
    key(90);
    EXPECT_EQ(ed.painter().image(), NdfImage{64});
    EXPECT_NE(ed.error().find("empty"), std::string::npos) << ed.error();
    key(89);
    EXPECT_EQ(ed.painter().image(), stroke);
    EXPECT_TRUE(ed.error().empty()) << ed.error();
    EXPECT_NEAR(moments(read_back(path, 64)).x, 0.5, 0.03);
    EXPECT_EQ(files_in(dir.path), std::vector<std::string>{"my_scene.ball.ndf.exr"});
}

TEST(NdfEditorGui, TheRegisteredPanelDrawsThePresetAndReportsBadLoads) {
    HeadlessImGui ui;
    Scene s = load_preset(test::source_path("presets/bumpsynth/fig1-sphere-distances.json"));
    const Evaluation ev = evaluate_ndf(s);
    PanelRegistry reg;
    register_technique_panels(reg);
    ASSERT_NE(reg.find("bumpsynth"), nullptr);
    const std::unique_ptr<TechniquePanel> entry = reg.find("bumpsynth")->make();
    Dirty dirty;
    PanelContext ctx{s, dirty, &ev, 0};
    for (int k = 0; k < 3; ++k) ui.frame([&] { entry->draw(ctx); });
    EXPECT_FALSE(dirty.any());
    ASSERT_NE(ImGui::GetDrawData(), nullptr);
    EXPECT_GT(ImGui::GetDrawData()->TotalVtxCount, 4 * 1000) << "the NDF is drawn as rectangles";

    // The worst case for drawing: no two neighbouring cells of one colour, 128 x 128 of them. The view is a
    // child window with its own draw list, which stays within 16-bit indices without the renderer's
    // vertex offsets (a headless context has none).
    NdfEditor noisy;
    noisy.start_empty(128);
    NdfImage noise(128);
    for (size_t i = 0; i < noise.px.size(); ++i) noise.px[i] = float((i * 2654435761u) % 1000u) + 1.f;
    noisy.painter().reset(noise);
    ui.frame([&] { noisy.draw(ctx, 0); });
    ASSERT_NE(ImGui::GetDrawData(), nullptr);
    int biggest = 0;
    for (int k = 0; k < ImGui::GetDrawData()->CmdListsCount; ++k) biggest = std::max(biggest, ImGui::GetDrawData()->CmdLists[k]->VtxBuffer.Size);
    EXPECT_GT(biggest, 4 * 10000);
    EXPECT_LT(biggest, 1 << 16);

    // A bad file through the editor's own Load: an error in the panel, the material untouched.
    NdfEditor ed;
    std::snprintf(ed.path, sizeof ed.path, "%s", "no/such/ndf.exr");
    const ParamTable before = s.objects[0].material;
    ImVec2 row(0, 0);
    auto draw = [&] {
        ed.draw(ctx, 0);
        row = ImGui::GetItemRectMin();  // the last item: the Save button's help marker, on the row of Load and Save
    };
    ui.frame(draw);
    ImGuiIO& io = ImGui::GetIO();
    io.MousePos = ImVec2(ImGui::GetStyle().WindowPadding.x + 8.f, row.y + 5.f);  // Load: the first item of that row
    ui.frame(draw);
    io.MouseDown[0] = true;
    ui.frame(draw);
    io.MouseDown[0] = false;
    ui.frame(draw);
    EXPECT_NE(ed.error().find("no such file"), std::string::npos) << ed.error();
    EXPECT_EQ(s.objects[0].material, before);
}
