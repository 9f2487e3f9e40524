// Plots of sweeps (app/plot.h) and their text (app/plot_text.h): never NaN, text drawn with real
// glyphs and measured by its ink, the same pixels from several threads, SVG with the same chart.
#include "app/plot.h"
#include "app/plot_text.h"
#include "core/image.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <climits>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

namespace fs = std::filesystem;
using namespace mesolab;

namespace {
bool all_finite(const Image& img) {
    for (float v : img.data)
        if (!std::isfinite(v)) return false;
    return true;
}
}  // namespace

// Plot
namespace {
bool pixels_ok(const Image& img) {
    for (float v : img.data)
        if (!std::isfinite(v) || v < 0.f || v > 1.f) return false;
    return true;
}

// Ink of text drawn on a white canvas: the pixels that changed, their bounding box.
struct Ink {
    Image img;
    int count = 0, partial = 0;  // inked pixels; of which neither white nor the full text colour
    int x0 = INT_MAX, y0 = INT_MAX, x1 = INT_MIN, y1 = INT_MIN;  // [x0, x1) x [y0, y1)
    int width() const { return count ? x1 - x0 : 0; }
};
Ink ink_of(const std::string& text, int scale, int w = 400, int h = 120, int x = 20, int y = 20) {
    Ink k{Image(w, h, 3, 1.f)};
    draw_text(k.img, x, y, text, 0.f, 0.f, 0.f, scale);
    for (int py = 0; py < h; ++py)
        for (int px = 0; px < w; ++px) {
            const float v = k.img.at(px, py)[0];
            if (v >= 1.f) continue;
            ++k.count;
            k.partial += v > 0.02f;
            k.x0 = std::min(k.x0, px), k.x1 = std::max(k.x1, px + 1);
            k.y0 = std::min(k.y0, py), k.y1 = std::max(k.y1, py + 1);
        }
    return k;
}
bool same_pixels(const Image& a, const Image& b) { return a.width == b.width && a.height == b.height && a.data == b.data; }

}  // namespace

TEST(Plot, DegenerateInputsNeverProduceNaN) {
    const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
    PlotSpec spec;
    spec.title = "degenerate";
    spec.xlabel = "time [ms]";
    spec.ylabel = "error";
    spec.series.push_back({"empty", {}, {}, {}});
    spec.series.push_back({"single", {3.0}, {0.5}, {"k=1"}});
    spec.series.push_back({"equal", {2, 2, 2}, {1, 1, 1}, {}});
    spec.series.push_back({"bad", {-1, 0, nan, inf, 5, 1e-320}, {1, 2, 3, 4, -inf, 7}, {"a"}});
    spec.series.push_back({"", {1, 10, 100}, {1e-3, 1e-4}, {"x", "y", "z", "w"}});  // lengths differ
    spec.series.push_back({"huge", {1e300, -1e300}, {1e-300, 1e300}, {}});
    for (bool lx : {false, true})
        for (bool ly : {false, true})
            for (auto [w, h] : {std::pair{900, 600}, std::pair{320, 200}, std::pair{40, 30}, std::pair{1, 1},
                                std::pair{3000, 2000}}) {
                spec.log_x = lx, spec.log_y = ly;
                const Image img = render_plot(spec, w, h);
                ASSERT_EQ(img.width, w);
                ASSERT_EQ(img.height, h);
                ASSERT_EQ(img.channels, 3);
                EXPECT_TRUE(pixels_ok(img)) << lx << ly << " " << w << "x" << h;
            }
    EXPECT_TRUE(render_plot(PlotSpec{}, 0, 0).empty());
    EXPECT_TRUE(pixels_ok(render_plot(PlotSpec{})));
    PlotSpec only_bad;
    only_bad.series.push_back({"bad", {nan, -1}, {1, 1}, {}});
    EXPECT_TRUE(pixels_ok(render_plot(only_bad)));
}

TEST(Plot, TitleTextIsDrawn) {
    // Title area at the default size: the top 40 rows, the middle third of the width.
    auto title_ink = [](const Image& img) {
        int n = 0;
        for (int y = 0; y < 40; ++y)
            for (int x = img.width / 3; x < 2 * img.width / 3; ++x) {
                const float* p = img.at(x, y);
                n += p[0] < 0.1f && p[1] < 0.1f && p[2] < 0.1f;
            }
        return n;
    };
    PlotSpec spec;
    spec.title = "Error against time";
    EXPECT_GT(title_ink(render_plot(spec, 900, 600)), 50);
    spec.title.clear();
    EXPECT_EQ(title_ink(render_plot(spec, 900, 600)), 0);

    spec.title = "Error against time";
    spec.series.push_back({"bdpt", {1, 2, 4, 8}, {0.1, 0.05, 0.03, 0.012}, {"1", "2", "4", "8"}});
    const Image with = render_plot(spec, 900, 600);
    EXPECT_GT(title_ink(with), 50);
    EXPECT_TRUE(pixels_ok(with));
    // The series colour (palette blue) appears: markers and line.
    int coloured = 0;
    for (size_t i = 0; i < with.data.size(); i += 3) coloured += with.data[i + 2] > 0.3f && with.data[i] < 0.1f;
    EXPECT_GT(coloured, 50);
}


TEST(Plot, DrawTextAndWidth) {
    EXPECT_EQ(text_width(""), 0);
    EXPECT_GT(text_width("Hi"), 0);
    EXPECT_GT(text_width("Hi", 3), 2 * text_width("Hi"));  // sizes scale with the plot
    EXPECT_GT(text_height(2), text_height(1));
    EXPECT_EQ(text_em_px(2), 2 * text_em_px(1));
    Image img(40, 40, 4, 0.f);
    draw_text(img, 2, 3, "A", 1.f, 0.f, 0.f, 2);
    int inside = 0, outside = 0, opaque = 0;
    for (int y = 0; y < 40; ++y)
        for (int x = 0; x < 40; ++x) {
            const float* p = img.at(x, y);
            const bool ink = p[0] > 0.f;
            const bool in_box = x >= 2 && x < 2 + text_width("A", 2) && y >= 3 && y < 3 + text_height(2);
            (in_box ? inside : outside) += ink;
            if (ink) {
                EXPECT_GT(p[3], 0.f);
                EXPECT_LE(p[3], 1.f);
            }
            opaque += p[3] == 1.f;
        }
    EXPECT_GT(inside, 20);
    EXPECT_EQ(outside, 0);
    EXPECT_GT(opaque, 5);  // fully covered pixels are opaque
    draw_text(img, -5, 15, "clipped \x01\x7f \xce\xb1\xff", 0.f, 1.f, 0.f, 4);  // partly outside, control bytes, bad UTF-8
    EXPECT_TRUE(all_finite(img));
    Image grey(30, 20, 1, 1.f);
    draw_text(grey, 1, 1, "\xce\xb8", 0.f, 0.f, 0.f, 2);  // θ into a single-channel image
    EXPECT_TRUE(all_finite(grey));
    EXPECT_LT(*std::min_element(grey.data.begin(), grey.data.end()), 0.5f);
}

TEST(Plot, TextWidthIsTheInkedExtent) {
    // The box text_width x text_height at (x, y) holds the ink; its width matches the ink's.
    for (int scale : {1, 2, 3, 5})
        for (const char* t : {"Hi", "0.005", "time per frame incl. stages (ms)", "\xce\xb1 = 0.08 rad",
                              "\xce\xb8 [\xc2\xb0]", "t [\xc2\xb5s]", "area [m\xc2\xb2]", "2 \xc3\x97 3 \xe2\x80\x93 4",
                              "\xce\xa3 \xce\xb4 \xcf\x80 \xce\xa9", "WAVE,jy"}) {
            const Ink k = ink_of(t, scale, 1400, 200, 20, 30);
            ASSERT_GT(k.count, 0) << t;
            EXPECT_NEAR(k.width(), text_width(t, scale), 1) << t << " scale " << scale;
            EXPECT_NEAR(k.x0, 20, 1) << t << " scale " << scale;
            EXPECT_GE(k.y0, 30 - 2) << t << " scale " << scale;  // accents may reach a little above the box
            EXPECT_LE(k.y1, 30 + text_height(scale)) << t << " scale " << scale;
        }
    // The width grows with the string, by the real advance of each glyph.
    int prev = 0;
    std::string s;
    for (const char* piece : {"\xce\xb1", "\xce\xb2", "\xce\xb3", " ", "\xce\xb4", "\xce\xb5", "M", "i"}) {
        s += piece;
        const int w = text_width(s, 2);
        EXPECT_GT(w, prev) << s;
        prev = w;
    }
    // Proportional, not monospaced: "i" is narrower than "M", and "iii" than "MMM".
    EXPECT_LT(text_width("i", 3), text_width("M", 3));
    EXPECT_LT(text_width("iii", 3), text_width("MMM", 3));
}

TEST(Plot, NonAsciiDrawsRealGlyphs) {
    // Greek letters and unit signs draw their own glyphs: ink, anti-aliased, different from the
    // '?' placeholder and from each other, and the font has every one of them (no missing-glyph box).
    const std::vector<std::string> letters = {"\xce\xb1", "\xce\xb2", "\xce\xb8", "\xc2\xb5", "\xc2\xb2",  "\xc2\xb0",
                                              "\xc3\x97", "\xe2\x80\x93", "\xce\xa3", "\xcf\x80", "\xce\xa9", "?"};
    std::vector<Ink> inks;
    for (const std::string& l : letters) {
        inks.push_back(ink_of(l, 3, 80, 80, 10, 10));
        EXPECT_GT(inks.back().count, 3) << l;
        EXPECT_GT(inks.back().partial, 0) << l << ": anti-aliased edges";
        const std::u32string cps = decode_utf8(l);
        ASSERT_EQ(cps.size(), 1u) << l;
        EXPECT_TRUE(plot_font().has_glyph(cps[0])) << l;
    }
    for (size_t i = 0; i < letters.size(); ++i)
        for (size_t j = i + 1; j < letters.size(); ++j)
            EXPECT_FALSE(same_pixels(inks[i].img, inks[j].img)) << letters[i] << " vs " << letters[j];
    // A whole unit: "µs" is not "?s", and not one '?' per byte either.
    EXPECT_FALSE(same_pixels(ink_of("t [\xc2\xb5s]", 2).img, ink_of("t [?s]", 2).img));
    EXPECT_FALSE(same_pixels(ink_of("t [\xc2\xb5s]", 2).img, ink_of("t [??s]", 2).img));
    // In a plot: the title's ink depends on which Greek letter it names.
    PlotSpec spec;
    spec.series.push_back({"s", {1, 2}, {1, 2}, {}});
    spec.title = "roughness \xce\xb1";
    const Image alpha = render_plot(spec, 600, 400);
    spec.title = "roughness \xce\xb2";
    const Image beta = render_plot(spec, 600, 400);
    spec.title = "roughness ?";
    const Image question = render_plot(spec, 600, 400);
    EXPECT_FALSE(same_pixels(alpha, beta));
    EXPECT_FALSE(same_pixels(alpha, question));
}

TEST(Plot, TwoThreadsDrawingAtOnceGiveTheFirstDrawingsPixels) {
    // The font's glyph caches are shared: two plots drawn at once on two threads (cached glyphs,
    // concurrent look-ups) must equal the first one, drawn alone.
    PlotSpec spec;
    spec.title = "error vs time: \xce\xb1 (\xce\xb8 = 30\xc2\xb0)";
    spec.xlabel = "time [\xc2\xb5s]";
    spec.ylabel = "\xc2\xbd \xce\xa3 |p \xe2\x88\x92 q|";
    spec.series.push_back({"\xce\xb1_x", {1, 2, 4, 8}, {0.1, 0.05, 0.03, 0.012}, {"1", "2", "4", "8"}});
    const Image a = render_plot(spec, 900, 600);
    Image b, c;
    std::thread t1([&] { b = render_plot(spec, 900, 600); });
    std::thread t2([&] { c = render_plot(spec, 900, 600); });
    t1.join();
    t2.join();
    EXPECT_TRUE(same_pixels(a, b));
    EXPECT_TRUE(same_pixels(a, c));
    EXPECT_TRUE(pixels_ok(a));
}

TEST(Plot, SvgHasTheSameChartWithTextAsText) {
    auto count = [](const std::string& s, const std::string& what) {
        size_t n = 0;
        for (size_t at = s.find(what); at != std::string::npos; at = s.find(what, at + 1)) ++n;
        return n;
    };
    PlotSpec spec;
    spec.title = "error vs time: \xce\xb1 < \xce\xb2 & \xc2\xb5s";
    spec.xlabel = "time [\xc2\xb5s]";
    spec.ylabel = "RMSE \xe2\x80\x93 m\xc2\xb2";
    spec.series.push_back({"\xce\xb8 sweep", {1, 2, 4, 8}, {0.1, 0.05, 0.03, 0.012}, {"1", "2", "4", "8"}});
    spec.series.push_back({"floor", {1, 8}, {0.02, 0.02}, {}});
    spec.series.push_back({"bad \xff\x01", {1}, {0.5}, {}});  // one point: no line
    const std::string svg = render_plot_svg(spec, 900, 600);
    EXPECT_EQ(svg.rfind("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<svg ", 0), 0u);
    EXPECT_NE(svg.find("width=\"900\" height=\"600\""), std::string::npos);
    EXPECT_EQ(svg.substr(svg.size() - 7), "</svg>\n");
    // Text as text, UTF-8 kept, markup escaped, malformed bytes and control characters replaced.
    EXPECT_NE(svg.find(">error vs time: \xce\xb1 &lt; \xce\xb2 &amp; \xc2\xb5s</text>"), std::string::npos) << svg;
    EXPECT_NE(svg.find(">time [\xc2\xb5s]</text>"), std::string::npos);
    EXPECT_NE(svg.find(">RMSE \xe2\x80\x93 m\xc2\xb2</text>"), std::string::npos);
    EXPECT_NE(svg.find(">\xce\xb8 sweep</text>"), std::string::npos);
    EXPECT_NE(svg.find(">bad \xef\xbf\xbd\xef\xbf\xbd</text>"), std::string::npos);
    for (char c = 1; c < 0x20; ++c) {
        if (c != '\n') {
            EXPECT_EQ(svg.find(c), std::string::npos) << int(c);
        }
    }
    // One line per series with two or more points, each clipped to the plot area; four point labels.
    EXPECT_EQ(count(svg, "<polyline"), 2u);
    EXPECT_EQ(count(svg, "<clipPath"), 2u);
    for (const char* l : {">1</text>", ">2</text>", ">4</text>", ">8</text>"}) EXPECT_GE(count(svg, l), 1u) << l;
    EXPECT_EQ(count(svg, "<text"), count(svg, "</text>"));
    // The title sits where the PNG's is (scale 3, 12 px down at 900x600): centred by its inked width,
    // the pen left of the ink by its bearing.
    const int ts = 3, x = (900 - text_width(spec.title, ts)) / 2;
    const int pen = x - plot_font().left_bearing(spec.title, text_em_px(ts));
    EXPECT_NE(svg.find("<text x=\"" + std::to_string(pen) + "\" y=\"" + std::to_string(12 + plot_font().ascent(text_em_px(ts))) +
                       "\" font-size=\"" + std::to_string(text_em_px(ts)) + "\""),
              std::string::npos)
        << svg;
    // The same text on another thread, after other sizes and glyphs went through the font's caches.
    std::string again;
    std::thread other([&] {
        PlotSpec before;
        before.title = "\xce\xa3 \xce\xb4 \xcf\x80 \xce\xa9 WAVE";
        before.series.push_back({"x", {1, 3}, {2, 1}, {}});
        render_plot(before, 320, 200);
        render_plot_svg(before, 2000, 1500);
        again = render_plot_svg(spec, 900, 600);
    });
    other.join();
    EXPECT_EQ(svg, again);
    const std::string empty = render_plot_svg(spec, 0, 0);
    EXPECT_EQ(count(empty, "<text"), 0u);
    EXPECT_EQ(empty.substr(empty.size() - 7), "</svg>\n");
}

TEST(Plot, Utf8Decoding) {
    EXPECT_EQ(decode_utf8("a\xce\xb1\xe2\x80\x93\xf0\x9f\x98\x80"), std::u32string(U"a\u03B1\u2013\U0001F600"));
    EXPECT_EQ(decode_utf8("\xff"), std::u32string(U"\uFFFD"));
    EXPECT_EQ(decode_utf8("\x80x"), std::u32string(U"\uFFFDx"));        // stray continuation byte
    EXPECT_EQ(decode_utf8("\xce"), std::u32string(U"\uFFFD"));          // truncated
    EXPECT_EQ(decode_utf8("\xe2\x80x"), std::u32string(U"\uFFFDx"));    // truncated before an ASCII byte
    EXPECT_EQ(decode_utf8("\xc0\xaf"), std::u32string(U"\uFFFD"));      // overlong
    EXPECT_EQ(decode_utf8("\xed\xa0\x80"), std::u32string(U"\uFFFD"));  // surrogate
    EXPECT_EQ(decode_utf8(""), std::u32string());
}

TEST(Plot, MissingFontNamesTheFileAndThePackage) {
    const std::string path = "/nonexistent/mesolab-test/NoSuchFont.ttf";
    try {
        Font f(path);
        FAIL() << "no error for a missing font";
    } catch (const std::runtime_error& e) {
        const std::string msg = e.what();
        EXPECT_NE(msg.find(path), std::string::npos) << msg;
        EXPECT_NE(msg.find("fonts-dejavu-core"), std::string::npos) << msg;
    }
    // Not a font at all: the same kind of message.
    const std::string not_font = (fs::temp_directory_path() / ("mesolab_not_a_font_" + std::to_string(long(::getpid())) + ".ttf")).string();
    { std::ofstream(not_font) << "plain text"; }
    try {
        Font f(not_font);
        ADD_FAILURE() << "no error for a file that is not a font";
    } catch (const std::runtime_error& e) {
        EXPECT_NE(std::string(e.what()).find(not_font), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("fonts-dejavu-core"), std::string::npos) << e.what();
    }
    fs::remove(not_font);
    // The plot font itself is the configured file and loads.
    EXPECT_EQ(plot_font().path(), std::string(plot_font_path()));
    EXPECT_GT(plot_font().line_height(12), 12);
}
