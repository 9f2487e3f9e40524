// Plotting: text in the plot font, anti-aliased polylines and an XY chart with linear or log axes.
#include "app/plot.h"

#include "app/plot_text.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <sstream>
#include <string>
#include <vector>

namespace mesolab {

namespace {

// Text: the em size in pixels per unit of text scale (capitals about 6.6 px tall per unit, which
// the chart's spacing is laid out for).
constexpr int kEmPerScale = 9;

// Pixel primitives
struct Rgb {
    float r, g, b;
};

// sRGB 8-bit colour (as designers pick them) to the linear values stored in the image.
Rgb srgb(int r, int g, int b) {
    return {srgb_to_linear(float(r) / 255.f), srgb_to_linear(float(g) / 255.f), srgb_to_linear(float(b) / 255.f)};
}

bool valid_canvas(const Image& img) {
    return img.width > 0 && img.height > 0 && img.channels > 0 &&
           img.data.size() >= size_t(img.width) * size_t(img.height) * size_t(img.channels);
}

// Blend `c` over pixel (x, y) with coverage a in [0, 1]; out-of-image pixels are ignored.
void blend(Image& img, int x, int y, const Rgb& c, float a) {
    if (x < 0 || y < 0 || x >= img.width || y >= img.height || !(a > 0.f)) return;
    a = std::min(a, 1.f);
    float* p = img.at(x, y);
    if (img.channels >= 3) {
        p[0] += (c.r - p[0]) * a;
        p[1] += (c.g - p[1]) * a;
        p[2] += (c.b - p[2]) * a;
        if (img.channels >= 4) p[3] += (1.f - p[3]) * a;
    } else {
        const float grey = 0.2126f * c.r + 0.7152f * c.g + 0.0722f * c.b;
        p[0] += (grey - p[0]) * a;
        if (img.channels == 2) p[1] += (1.f - p[1]) * a;
    }
}

// Fill the pixel rectangle [x0, x1) x [y0, y1), clipped to the image.
void fill_rect(Image& img, int x0, int y0, int x1, int y1, const Rgb& c) {
    x0 = std::max(x0, 0), y0 = std::max(y0, 0);
    x1 = std::min(x1, img.width), y1 = std::min(y1, img.height);
    for (int y = y0; y < y1; ++y)
        for (int x = x0; x < x1; ++x) blend(img, x, y, c, 1.f);
}

// Clamp a pixel coordinate before converting to int (keeps far-off geometry well defined).
int to_px(double v) { return int(std::lround(std::clamp(v, -1.0e6, 1.0e6))); }

struct Rect {
    int x0, y0, x1, y1;  // [x0, x1) x [y0, y1)
};

// Anti-aliased polyline of width `w` (pixels) through points in pixel coordinates, clipped to
// `clip`. Coverage is accumulated with max() so joints are not blended twice.
void draw_polyline(Image& img, const std::vector<std::array<double, 2>>& pts, double w, const Rgb& c,
                   const Rect& clip, std::vector<float>& cov) {
    if (pts.size() < 2) return;
    const Rect r{std::max(clip.x0, 0), std::max(clip.y0, 0), std::min(clip.x1, img.width),
                 std::min(clip.y1, img.height)};
    if (r.x0 >= r.x1 || r.y0 >= r.y1) return;
    cov.assign(size_t(img.width) * size_t(img.height), 0.f);
    const double half = 0.5 * w;
    int bx0 = r.x1, by0 = r.y1, bx1 = r.x0, by1 = r.y0;  // bounding box of touched pixels
    for (size_t i = 0; i + 1 < pts.size(); ++i) {
        const double ax = pts[i][0], ay = pts[i][1], dx = pts[i + 1][0] - ax, dy = pts[i + 1][1] - ay;
        const double len2 = dx * dx + dy * dy;
        const int x0 = std::max(r.x0, to_px(std::floor(std::min(ax, ax + dx) - half - 1)));
        const int x1 = std::min(r.x1, to_px(std::ceil(std::max(ax, ax + dx) + half + 1)));
        const int y0 = std::max(r.y0, to_px(std::floor(std::min(ay, ay + dy) - half - 1)));
        const int y1 = std::min(r.y1, to_px(std::ceil(std::max(ay, ay + dy) + half + 1)));
        for (int y = y0; y < y1; ++y)
            for (int x = x0; x < x1; ++x) {
                const double px = x + 0.5 - ax, py = y + 0.5 - ay;
                const double t = len2 > 0 ? std::clamp((px * dx + py * dy) / len2, 0.0, 1.0) : 0.0;
                const double ex = px - t * dx, ey = py - t * dy;
                const double a = std::clamp(half + 0.5 - std::sqrt(ex * ex + ey * ey), 0.0, 1.0);
                float& v = cov[size_t(y) * size_t(img.width) + size_t(x)];
                v = std::max(v, float(a));
            }
        bx0 = std::min(bx0, x0), by0 = std::min(by0, y0), bx1 = std::max(bx1, x1), by1 = std::max(by1, y1);
    }
    for (int y = by0; y < by1; ++y)
        for (int x = bx0; x < bx1; ++x) blend(img, x, y, c, cov[size_t(y) * size_t(img.width) + size_t(x)]);
}

// Axes and ticks
struct Tick {
    double u;           // position in axis space (log10 of the value on log axes)
    std::string label;  // empty: unlabelled
    bool major;
};

struct Axis {
    bool log = false;
    double lo = 0, hi = 1;  // axis-space range, lo < hi
    std::vector<Tick> ticks;
    double frac(double value) const {  // value -> [0, 1] along the axis
        const double u = log ? std::log10(value) : value;
        return (u - lo) / (hi - lo);
    }
};

// Tick values as short numbers: "0", "0.25", "120", "0.001", "1e-5", "2.5e6".
std::string format_number(double v) {
    if (v == 0 || !std::isfinite(v)) return "0";
    char buf[64];
    int e = int(std::floor(std::log10(std::fabs(v))));
    if (e >= -3 && e < 5) {
        std::snprintf(buf, sizeof buf, "%.6g", v);
        return buf;
    }
    double m = v / std::pow(10.0, e);
    if (std::fabs(m) >= 9.9995) m /= 10, ++e;
    if (std::fabs(m) < 0.99995) m *= 10, --e;
    std::snprintf(buf, sizeof buf, "%.4ge%d", m, e);
    return buf;
}

// 1-2-5 step not smaller than `raw`.
double nice_step(double raw) {
    const double mag = std::pow(10.0, std::floor(std::log10(raw)));
    const double n = raw / mag;
    return (n <= 1.0 ? 1.0 : n <= 2.0 ? 2.0 : n <= 5.0 ? 5.0 : 10.0) * mag;
}

// Linear ticks over [lo, hi] (value space) at multiples of a 1-2-5 step, about `target` of them.
void linear_ticks(Axis& ax, double lo, double hi, int target) {
    const double step = nice_step((hi - lo) / std::max(target, 1));
    if (!(step > 0) || !std::isfinite(step)) return;
    const double first = std::ceil(lo / step - 1e-9), last = std::floor(hi / step + 1e-9);
    if (!(last - first < 1000)) return;
    for (double i = first; i <= last; i += 1) {
        double v = i * step;
        if (std::fabs(v) < step * 1e-9) v = 0;
        if (ax.log && !(v > 0)) continue;
        ax.ticks.push_back({ax.log ? std::log10(v) : v, format_number(v), true});
    }
}

// Axis through the given (already filtered) values, padded a little, with ticks for an axis of
// `length_px` pixels on which labels need about `spacing_px` pixels each.
Axis make_axis(const std::vector<double>& values, bool log, double length_px, double spacing_px) {
    Axis ax;
    ax.log = log;
    double lo = HUGE_VAL, hi = -HUGE_VAL;
    for (double v : values) {
        const double u = log ? std::log10(v) : v;
        lo = std::min(lo, u), hi = std::max(hi, u);
    }
    if (values.empty()) {
        lo = 0, hi = 1;
    } else if (hi - lo <= 1e-9 * std::max(std::fabs(lo), std::fabs(hi))) {
        const double d = log ? 0.5 : (lo == 0 ? 1.0 : 0.1 * std::fabs(lo));
        lo -= d, hi += d;
    }
    const double pad = 0.05 * (hi - lo);
    ax.lo = lo - pad, ax.hi = hi + pad;

    const int target = std::max(2, int(length_px / std::max(spacing_px, 1.0)));
    if (!log) {
        linear_ticks(ax, ax.lo, ax.hi, target);
        return ax;
    }
    // Log axis: labelled decades (every `ds`-th one when there are many), 2 and 5 in between.
    const double d0 = std::ceil(ax.lo - 1e-9), d1 = std::floor(ax.hi + 1e-9);
    const double ndec = std::max(0.0, d1 - d0 + 1);
    const double ds = ndec > target ? nice_step(ndec / target) : 1;
    int labelled = 0;
    for (double d = std::floor(ax.lo); d <= ax.hi && d - std::floor(ax.lo) < 400; d += 1) {
        const bool in = d >= ax.lo - 1e-9;
        if (in) {
            const bool major = std::fmod(std::fabs(d), ds) == 0;
            ax.ticks.push_back({d, major ? format_number(std::pow(10.0, d)) : std::string(), major});
            labelled += major;
        }
        if (ds == 1)
            for (double m : {2.0, 5.0}) {
                const double u = d + std::log10(m);
                if (u >= ax.lo && u <= ax.hi) ax.ticks.push_back({u, std::string(), false});
            }
    }
    // Few decades: label 2 and 5 as well (when there is room); none at all: linear ticks.
    const double px_per_decade = length_px / (ax.hi - ax.lo);
    if (labelled < 3 && ds == 1 && px_per_decade > 2.5 * spacing_px)
        for (Tick& t : ax.ticks)
            if (!t.major) t.label = format_number(std::pow(10.0, t.u));
    int n = 0;
    for (const Tick& t : ax.ticks) n += !t.label.empty();
    if (n < 2) {
        ax.ticks.clear();
        linear_ticks(ax, std::pow(10.0, ax.lo), std::pow(10.0, ax.hi), target);
    }
    std::sort(ax.ticks.begin(), ax.ticks.end(), [](const Tick& a, const Tick& b) { return a.u < b.u; });
    return ax;
}

// Drop labels that would overlap: minor ones first, then every other major one.
// `extent` gives a label's size along the axis in pixels; `pos` maps axis space to pixels.
template <typename Extent, typename Pos>
void thin_labels(std::vector<Tick>& ticks, double gap, Extent extent, Pos pos) {
    auto overlaps = [&]() {
        double end = -HUGE_VAL;
        for (const Tick& t : ticks) {
            if (t.label.empty()) continue;
            const double p = pos(t.u), e = 0.5 * extent(t.label);
            if (p - e < end + gap) return true;
            end = p + e;
        }
        return false;
    };
    if (!overlaps()) return;
    for (Tick& t : ticks)
        if (!t.major) t.label.clear();
    for (int keep = 2; keep < 1000 && overlaps(); keep *= 2) {
        int i = 0;
        for (Tick& t : ticks)
            if (!t.label.empty() || t.major) {
                if (i % keep != 0) t.label.clear();
                ++i;
            }
    }
}

struct Point {
    double x, y;
    std::string label;
};
}  // namespace

// Text
int text_em_px(int scale) { return kEmPerScale * std::clamp(scale, 1, 100); }
int text_width(const std::string& text, int scale) { return plot_font().width(text, text_em_px(scale)); }
int text_height(int scale) { return plot_font().line_height(text_em_px(scale)); }

void draw_text(Image& img, int x, int y, const std::string& text, float r, float g, float b, int scale) {
    if (!valid_canvas(img) || text.empty()) return;
    const float lin[3] = {r, g, b}, enc[3] = {linear_to_srgb(r), linear_to_srgb(g), linear_to_srgb(b)};
    plot_font().rasterize(text, text_em_px(scale), x, y, [&](int px, int py, float a) {
        if (px < 0 || py < 0 || px >= img.width || py >= img.height) return;
        if (img.channels < 3) {
            blend(img, px, py, {r, g, b}, a);
            return;
        }
        // Coverage is mixed in sRGB-encoded values, as text renderers and displays expect (mixed
        // in linear light, dark text on white looks thin and washed out).
        float* p = img.at(px, py);
        for (int k = 0; k < 3; ++k) {
            const float e = linear_to_srgb(p[k]);
            p[k] = a >= 1.f ? lin[k] : srgb_to_linear(e + (enc[k] - e) * a);
        }
        if (img.channels >= 4) p[3] += (1.f - p[3]) * a;
    });
}

// Canvases: the chart's layout drawn into an image or written as SVG.
namespace {
class Canvas {
public:
    virtual ~Canvas() = default;
    // Opaque pixel rectangle [x0, x1) x [y0, y1).
    virtual void rect(int x0, int y0, int x1, int y1, const Rgb& c) = 0;
    // Polyline of width w through points in pixel coordinates, clipped to `clip`.
    virtual void polyline(const std::vector<std::array<double, 2>>& pts, double w, const Rgb& c, const Rect& clip) = 0;
    // Text with its box's top-left corner at (x, y), as draw_text.
    virtual void text(int x, int y, const std::string& t, float r, float g, float b, int scale) = 0;
};

class RasterCanvas final : public Canvas {
public:
    explicit RasterCanvas(Image& img) : img_(img) {}
    void rect(int x0, int y0, int x1, int y1, const Rgb& c) override { fill_rect(img_, x0, y0, x1, y1, c); }
    void polyline(const std::vector<std::array<double, 2>>& pts, double w, const Rgb& c, const Rect& clip) override {
        draw_polyline(img_, pts, w, c, clip, coverage_);
    }
    void text(int x, int y, const std::string& t, float r, float g, float b, int scale) override {
        draw_text(img_, x, y, t, r, g, b, scale);
    }

private:
    Image& img_;
    std::vector<float> coverage_;
};

// UTF-8 of one code point.
void append_utf8(std::string& out, char32_t c) {
    if (c < 0x80) {
        out += char(c);
    } else if (c < 0x800) {
        out += char(0xC0 | (c >> 6)), out += char(0x80 | (c & 0x3F));
    } else if (c < 0x10000) {
        out += char(0xE0 | (c >> 12)), out += char(0x80 | ((c >> 6) & 0x3F)), out += char(0x80 | (c & 0x3F));
    } else {
        out += char(0xF0 | (c >> 18)), out += char(0x80 | ((c >> 12) & 0x3F)), out += char(0x80 | ((c >> 6) & 0x3F)),
            out += char(0x80 | (c & 0x3F));
    }
}

// Text as XML character data: valid UTF-8 (malformed bytes as U+FFFD), markup escaped, control
// characters (not allowed in XML 1.0) as U+FFFD.
std::string xml_text(const std::string& text) {
    std::string out;
    for (char32_t c : decode_utf8(text)) {
        if (c == U'&') out += "&amp;";
        else if (c == U'<') out += "&lt;";
        else if (c == U'>') out += "&gt;";
        else if (c == U'"') out += "&quot;";
        else if ((c < 0x20 && c != U'\t') || c == 0x7F || c == 0xFFFE || c == 0xFFFF) append_utf8(out, U'\uFFFD');
        else append_utf8(out, c);
    }
    return out;
}

std::string hex(const Rgb& c) {
    char buf[8];
    std::snprintf(buf, sizeof buf, "#%02x%02x%02x", unsigned(linear_to_srgb8(c.r)), unsigned(linear_to_srgb8(c.g)),
                  unsigned(linear_to_srgb8(c.b)));
    return buf;
}

std::string num(double v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.2f", v);
    std::string r = buf;
    while (r.back() == '0') r.pop_back();
    if (r.back() == '.') r.pop_back();
    return r == "-0" ? "0" : r;
}

class SvgCanvas final : public Canvas {
public:
    SvgCanvas(int width, int height) : w_(width), h_(height) {}
    void rect(int x0, int y0, int x1, int y1, const Rgb& c) override {
        x0 = std::max(x0, 0), y0 = std::max(y0, 0), x1 = std::min(x1, w_), y1 = std::min(y1, h_);
        if (x0 >= x1 || y0 >= y1) return;
        body_ << "<rect x=\"" << x0 << "\" y=\"" << y0 << "\" width=\"" << x1 - x0 << "\" height=\"" << y1 - y0
              << "\" fill=\"" << hex(c) << "\"/>\n";
    }
    void polyline(const std::vector<std::array<double, 2>>& pts, double w, const Rgb& c, const Rect& clip) override {
        if (pts.size() < 2 || clip.x0 >= clip.x1 || clip.y0 >= clip.y1) return;
        const int id = clips_++;
        defs_ << "<clipPath id=\"c" << id << "\"><rect x=\"" << clip.x0 << "\" y=\"" << clip.y0 << "\" width=\""
              << clip.x1 - clip.x0 << "\" height=\"" << clip.y1 - clip.y0 << "\"/></clipPath>\n";
        body_ << "<polyline clip-path=\"url(#c" << id << ")\" fill=\"none\" stroke=\"" << hex(c) << "\" stroke-width=\""
              << num(w) << "\" stroke-linecap=\"round\" stroke-linejoin=\"round\" shape-rendering=\"auto\" points=\"";
        for (size_t i = 0; i < pts.size(); ++i)
            body_ << (i ? " " : "") << num(std::clamp(pts[i][0], -1e6, 1e6)) << "," << num(std::clamp(pts[i][1], -1e6, 1e6));
        body_ << "\"/>\n";
    }
    void text(int x, int y, const std::string& t, float r, float g, float b, int scale) override {
        if (t.empty()) return;
        // The same box as the raster text: the pen starts left of the first glyph's ink by its bearing.
        const int px = text_em_px(scale);
        const Font& f = plot_font();
        body_ << "<text x=\"" << x - f.left_bearing(t, px) << "\" y=\"" << y + f.ascent(px) << "\" font-size=\"" << px
              << "\" fill=\"" << hex(Rgb{r, g, b}) << "\">" << xml_text(t) << "</text>\n";
    }
    std::string str() const {
        std::ostringstream o;
        o << "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
          << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << w_ << "\" height=\"" << h_ << "\" viewBox=\"0 0 "
          << w_ << " " << h_ << "\" font-family=\"DejaVu Sans, sans-serif\" shape-rendering=\"crispEdges\" xml:space=\"preserve\">\n";
        if (!defs_.str().empty()) o << "<defs>\n" << defs_.str() << "</defs>\n";
        if (w_ > 0 && h_ > 0) o << "<rect width=\"" << w_ << "\" height=\"" << h_ << "\" fill=\"#ffffff\"/>\n";
        o << body_.str() << "</svg>\n";
        return o.str();
    }

private:
    int w_, h_, clips_ = 0;
    std::ostringstream defs_, body_;
};

void draw_chart(Canvas& cv, const PlotSpec& spec, int width, int height);
}  // namespace

Image render_plot(const PlotSpec& spec, int width, int height) {
    if (width <= 0 || height <= 0) return Image(std::max(width, 0), std::max(height, 0), 3);
    Image img(width, height, 3, 1.f);
    RasterCanvas cv(img);
    draw_chart(cv, spec, width, height);
    return img;
}

std::string render_plot_svg(const PlotSpec& spec, int width, int height) {
    width = std::max(width, 0), height = std::max(height, 0);
    SvgCanvas cv(width, height);
    if (width > 0 && height > 0) draw_chart(cv, spec, width, height);
    return cv.str();
}

// Chart
namespace {
void draw_chart(Canvas& cv, const PlotSpec& spec, int width, int height) {

    const Rgb black = srgb(30, 30, 30), text_c = srgb(40, 40, 40), axis_c = srgb(90, 90, 90),
              grid_major = srgb(222, 222, 222), grid_minor = srgb(240, 240, 240), muted = srgb(150, 150, 150),
              white{1.f, 1.f, 1.f};
    static const int kPalette[10][3] = {{31, 119, 180}, {255, 127, 14}, {44, 160, 44},  {214, 39, 40},
                                        {148, 103, 189}, {140, 86, 75},  {227, 119, 194}, {127, 127, 127},
                                        {188, 189, 34},  {23, 190, 207}};

    // Scale: text and marks grow with the image (2 at the default 900x600).
    const int s = std::clamp(std::min(width, height) / 300, 1, 8);
    const int ts = s + 1;  // title
    const int ls = std::max(1, s - 1);  // point labels
    const int pad = 6 * s, tick_len = 3 * s, line_h = text_height(s);
    const int marker = 3 + 2 * s;

    // Valid points per series (finite, and positive on log axes).
    auto usable = [](double v, bool log) { return std::isfinite(v) && std::fabs(v) <= 1e300 && (!log || v >= 1e-300); };
    std::vector<std::vector<Point>> pts(spec.series.size());
    std::vector<double> xs, ys;
    for (size_t si = 0; si < spec.series.size(); ++si) {
        const PlotSeries& ser = spec.series[si];
        const size_t n = std::min(ser.x.size(), ser.y.size());
        for (size_t i = 0; i < n; ++i) {
            if (!usable(ser.x[i], spec.log_x) || !usable(ser.y[i], spec.log_y)) continue;
            pts[si].push_back({ser.x[i], ser.y[i], i < ser.point_labels.size() ? ser.point_labels[i] : std::string()});
            xs.push_back(ser.x[i]);
            ys.push_back(ser.y[i]);
        }
    }

    // Layout: title, y-axis title (horizontal, above the plot), plot area, x tick labels, x title.
    int top = pad;
    if (!spec.title.empty()) top += text_height(ts) + 3 * s;
    if (!spec.ylabel.empty()) top += line_h + 3 * s;
    else top += 2 * s;
    int bottom = height - pad - line_h - 2 * s - tick_len;
    if (!spec.xlabel.empty()) bottom -= line_h + 5 * s;
    bottom = std::max(bottom, top + 1);

    Axis ay = make_axis(ys, spec.log_y, bottom - top, 4.0 * line_h);
    int label_w = 0;
    for (const Tick& t : ay.ticks) label_w = std::max(label_w, text_width(t.label, s));
    const int left = std::min(pad + label_w + 2 * s + tick_len, width - 2);
    const int right = std::max(width - 4 * pad, left + 1);
    Axis ax = make_axis(xs, spec.log_x, right - left, double(text_width("0.0005", s)) + 6.0 * s);

    auto px = [&](double x) { return left + ax.frac(x) * (right - left); };
    auto py = [&](double y) { return bottom - ay.frac(y) * (bottom - top); };
    auto upx = [&](double u) { return left + (u - ax.lo) / (ax.hi - ax.lo) * (right - left); };
    auto upy = [&](double u) { return bottom - (u - ay.lo) / (ay.hi - ay.lo) * (bottom - top); };
    thin_labels(ax.ticks, 3.0 * s, [&](const std::string& l) { return double(text_width(l, s)); }, upx);
    // (y labels are thinned bottom-up with their height as extent; positions grow upwards.)
    thin_labels(ay.ticks, 1.0 * s, [&](const std::string&) { return double(line_h); },
                [&](double u) { return -upy(u); });

    // Grid: minor first, then major.
    for (int pass = 0; pass < 2; ++pass) {
        const bool want_major = pass == 1;
        for (const Tick& t : ax.ticks)
            if (t.major == want_major) {
                const int x = to_px(upx(t.u) - 0.5);
                cv.rect(x, top, x + 1, bottom, want_major ? grid_major : grid_minor);
            }
        for (const Tick& t : ay.ticks)
            if (t.major == want_major) {
                const int y = to_px(upy(t.u) - 0.5);
                cv.rect(left, y, right, y + 1, want_major ? grid_major : grid_minor);
            }
    }

    // Series: anti-aliased polylines, then square markers with a white rim, then point labels.
    const Rect plot_clip{left, top, right, bottom};
    auto color_of = [&](size_t i) {
        const int* p = kPalette[i % 10];
        return srgb(p[0], p[1], p[2]);
    };
    for (size_t si = 0; si < pts.size(); ++si) {
        if (!spec.series[si].line) continue;
        std::vector<std::array<double, 2>> line;
        for (const Point& p : pts[si]) line.push_back({px(p.x), py(p.y)});
        cv.polyline(line, 0.75 * s + 0.5, color_of(si), plot_clip);
    }
    for (size_t si = 0; si < pts.size(); ++si)
        for (const Point& p : pts[si]) {
            const int cx = to_px(px(p.x) - 0.5), cy = to_px(py(p.y) - 0.5), h = marker / 2;
            cv.rect(cx - h - 1, cy - h - 1, cx + h + 2, cy + h + 2, white);
            cv.rect(cx - h, cy - h, cx + h + 1, cy + h + 1, color_of(si));
        }
    for (size_t si = 0; si < pts.size(); ++si)
        for (const Point& p : pts[si]) {
            if (p.label.empty()) continue;
            const int cx = to_px(px(p.x)), cy = to_px(py(p.y)), w = text_width(p.label, ls);
            int tx = cx + marker / 2 + 2 * ls, ty = cy - marker / 2 - text_height(ls) - ls;
            if (tx + w > right) tx = cx - marker / 2 - 2 * ls - w;
            if (ty < top + 1) ty = cy + marker / 2 + 2 * ls;
            const Rgb c = color_of(si);
            cv.text(tx, ty, p.label, 0.6f * c.r, 0.6f * c.g, 0.6f * c.b, ls);
        }

    // Frame, ticks and tick labels.
    cv.rect(left - 1, top - 1, right + 1, top, axis_c);
    cv.rect(left - 1, bottom, right + 1, bottom + 1, axis_c);
    cv.rect(left - 1, top - 1, left, bottom + 1, axis_c);
    cv.rect(right, top - 1, right + 1, bottom + 1, axis_c);
    for (const Tick& t : ax.ticks) {
        const int x = to_px(upx(t.u) - 0.5), len = t.major || !t.label.empty() ? tick_len : tick_len / 2;
        cv.rect(x, bottom + 1, x + 1, bottom + 1 + len, axis_c);
        if (!t.label.empty())
            cv.text(x - text_width(t.label, s) / 2, bottom + 1 + tick_len + 2 * s, t.label, text_c.r, text_c.g,
                      text_c.b, s);
    }
    for (const Tick& t : ay.ticks) {
        const int y = to_px(upy(t.u) - 0.5), len = t.major || !t.label.empty() ? tick_len : tick_len / 2;
        cv.rect(left - 1 - len, y, left - 1, y + 1, axis_c);
        if (!t.label.empty())
            cv.text(left - 1 - tick_len - 2 * s - text_width(t.label, s), y - line_h / 2, t.label, text_c.r,
                      text_c.g, text_c.b, s);
    }
    if (xs.empty())
        cv.text((left + right - text_width("no data", s)) / 2, (top + bottom - line_h) / 2, "no data", muted.r,
                  muted.g, muted.b, s);

    // Legend: the plot corner that hides the fewest points.
    if (!spec.series.empty()) {
        const int row_h = line_h + 3 * s, swatch = 8 * s;
        int lw = 0;
        std::vector<std::string> names;
        for (size_t si = 0; si < spec.series.size(); ++si) {
            std::string n = spec.series[si].label.empty() ? "series " + std::to_string(si + 1) : spec.series[si].label;
            if (pts[si].empty()) n += " (no data)";
            lw = std::max(lw, text_width(n, s));
            names.push_back(std::move(n));
        }
        const int bw = 3 * s + swatch + 3 * s + lw + 3 * s, bh = 2 * s + row_h * int(names.size()) + s;
        const int m = 2 * s;
        const std::array<std::array<int, 2>, 4> corners = {{{right - m - bw, top + m},
                                                            {left + m, top + m},
                                                            {right - m - bw, bottom - m - bh},
                                                            {left + m, bottom - m - bh}}};
        int best = 0;
        size_t best_hidden = SIZE_MAX;
        for (int k = 0; k < 4; ++k) {
            size_t hidden = 0;
            for (const auto& ser : pts)
                for (const Point& p : ser) {
                    const double x = px(p.x), y = py(p.y);
                    hidden += x >= corners[k][0] - marker && x <= corners[k][0] + bw + marker &&
                              y >= corners[k][1] - marker && y <= corners[k][1] + bh + marker;
                }
            if (hidden < best_hidden) best_hidden = hidden, best = k;
        }
        const int bx = corners[size_t(best)][0], by = corners[size_t(best)][1];
        cv.rect(bx, by, bx + bw, by + bh, srgb(200, 200, 200));
        cv.rect(bx + 1, by + 1, bx + bw - 1, by + bh - 1, white);
        for (size_t si = 0; si < names.size(); ++si) {
            const int ry = by + 2 * s + row_h * int(si), cy = ry + line_h / 2;
            const Rgb c = color_of(si);
            const int lt = std::max(1, to_px(0.75 * s + 0.5));
            cv.rect(bx + 3 * s, cy - lt / 2, bx + 3 * s + swatch, cy - lt / 2 + lt, c);
            const int mx = bx + 3 * s + swatch / 2, h = marker / 2;
            cv.rect(mx - h, cy - h, mx + h + 1, cy + h + 1, c);
            cv.text(bx + 6 * s + swatch, ry, names[si], text_c.r, text_c.g, text_c.b, s);
        }
    }

    // Titles.
    if (!spec.title.empty()) {
        const int sc = text_width(spec.title, ts) <= width - 2 * pad ? ts : s;
        cv.text(std::max(pad, (width - text_width(spec.title, sc)) / 2), pad, spec.title, black.r, black.g,
                  black.b, sc);
    }
    if (!spec.ylabel.empty())
        cv.text(std::max(pad, left - tick_len - 2 * s - label_w), top - 3 * s - line_h, spec.ylabel, text_c.r,
                  text_c.g, text_c.b, s);
    if (!spec.xlabel.empty())
        cv.text(std::max(pad, (left + right - text_width(spec.xlabel, s)) / 2), height - pad - line_h,
                  spec.xlabel, text_c.r, text_c.g, text_c.b, s);
}
}  // namespace
}  // namespace mesolab
