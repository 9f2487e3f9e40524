// NDF editor: the editing logic without ImGui (image, brush, symmetry, undo, lobe handles, files).
#include "panels/bumpsynth/ndf_editor.h"

#include "core/bumpsynth/bumpsynth.h"
#include "core/error.h"
#include "core/image.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <limits>

namespace mesolab::panels::ndf_editor {
namespace fs = std::filesystem;

// [SECTION] Image
vec2 NdfImage::centre(int c, int r) const {
    const double h = 2.0 / size;
    return vec2(float(-1.0 + (c + 0.5) * h), float(1.0 - (r + 0.5) * h));
}

NdfImage image_from_ndf(const bumpsynth::Ndf& ndf) {
    const int R = ndf.resolution();
    NdfImage img(R);
    for (int j = 0; j < R; ++j)
        for (int i = 0; i < R; ++i) img.at(i, R - 1 - j) = ndf.value(i, j);
    return img;
}

double image_mass(const NdfImage& img) {
    const double h = 2.0 / img.size;
    double m = 0.0;
    for (int r = 0; r < img.size; ++r)
        for (int c = 0; c < img.size; ++c) {
            const float v = img.at(c, r);
            if (v > 0.f) m += double(v) * bumpsynth::disk_rect_area(-1.0 + c * h, -1.0 + (c + 1) * h, 1.0 - (r + 1) * h, 1.0 - r * h);
        }
    return m;
}

// [SECTION] Brush
float falloff(float d, float radius) {
    if (!(radius > 0.f)) return 0.f;
    const float t = d / radius;
    if (!(t < 1.f)) return 0.f;
    static const float e4 = std::exp(-4.f);
    return std::max(0.f, (std::exp(-4.f * t * t) - e4) / (1.f - e4));
}

std::vector<vec2> symmetric_points(vec2 p, Symmetry s, int fold) {
    switch (s) {
        case Symmetry::none: return {p};
        case Symmetry::mirror_x: return {p, {-p.x, p.y}};
        case Symmetry::mirror_y: return {p, {p.x, -p.y}};
        case Symmetry::both: return {p, {-p.x, p.y}, {p.x, -p.y}, {-p.x, -p.y}};
        case Symmetry::rotational: {
            const int n = std::clamp(fold, 2, 32);
            std::vector<vec2> out;
            for (int k = 0; k < n; ++k) {
                const double a = 2.0 * 3.14159265358979323846 * k / n, c = std::cos(a), sn = std::sin(a);
                out.push_back(k == 0 ? p : vec2(float(c * p.x - sn * p.y), float(sn * p.x + c * p.y)));
            }
            return out;
        }
    }
    return {p};
}

void Painter::reset(NdfImage img) {
    img_ = std::move(img);
    undo_.clear();
    redo_.clear();
    stroking_ = false;
    cover_.clear();
}

void Painter::push_undo(NdfImage before) {
    undo_.push_back(std::move(before));
    while (undo_.size() > kHistory) undo_.pop_front();
    redo_.clear();
}

void Painter::replace(NdfImage img) {
    if (stroking_) end_stroke();
    if (img == img_) return;
    push_undo(std::move(img_));
    img_ = std::move(img);
}

void Painter::begin_stroke(const Brush& b) {
    if (stroking_) end_stroke();
    brush_ = b;
    brush_.radius = std::isfinite(b.radius) ? std::clamp(b.radius, 1e-3f, 2.f) : 0.1f;
    brush_.strength = std::isfinite(b.strength) ? std::max(0.f, b.strength) : 0.f;
    brush_.fold = std::clamp(b.fold, 2, 32);
    start_ = img_;
    cover_.assign(img_.px.size(), 0.f);
    last_.reset();
    stroking_ = !img_.empty();
}

void Painter::stroke_to(vec2 p) {
    if (!stroking_ || !std::isfinite(p.x) || !std::isfinite(p.y)) return;
    if (!last_) {
        dab(p);
    } else {
        const vec2 a = *last_;
        const float dist = glm::length(p - a), step = 0.25f * brush_.radius;
        const int n = int(std::ceil(dist / step));
        for (int k = 1; k <= n; ++k) dab(a + (p - a) * (float(k) / float(n)));
    }
    last_ = p;
}

bool Painter::end_stroke() {
    if (!stroking_) return false;
    stroking_ = false;
    cover_.clear();
    const bool changed = !(img_ == start_);
    if (changed) push_undo(std::move(start_));
    start_ = {};
    return changed;
}

void Painter::dab(vec2 p) {
    switch (brush_.symmetry) {
        case Symmetry::none: stamp(p, false, false); break;
        case Symmetry::mirror_x: stamp(p, true, false); break;
        case Symmetry::mirror_y: stamp(p, false, true); break;
        case Symmetry::both: stamp(p, true, true); break;
        case Symmetry::rotational:
            for (vec2 q : symmetric_points(p, Symmetry::rotational, brush_.fold)) stamp(q, false, false);
            break;
    }
}

// The falloff of one dab on the pixels around it, applied to their mirror images too (same value,
// combined by max: the coverage stays exactly symmetric whatever the order of the dabs).
void Painter::stamp(vec2 p, bool mirror_x, bool mirror_y) {
    const int R = img_.size;
    const float h = 2.f / float(R), rad = brush_.radius, sign = brush_.erase ? -1.f : 1.f;
    const int c0 = std::max(0, int(std::floor((p.x - rad + 1.f) / h - 0.5f)));
    const int c1 = std::min(R - 1, int(std::ceil((p.x + rad + 1.f) / h - 0.5f)));
    const int r0 = std::max(0, int(std::floor((1.f - (p.y + rad)) / h - 0.5f)));
    const int r1 = std::min(R - 1, int(std::ceil((1.f - (p.y - rad)) / h - 0.5f)));
    auto apply = [&](int c, int r, float w) {
        const size_t i = size_t(r) * size_t(R) + size_t(c);
        if (!(w > cover_[i])) return;
        cover_[i] = w;
        img_.px[i] = std::max(0.f, start_.px[i] + sign * brush_.strength * w);
    };
    for (int r = r0; r <= r1; ++r)
        for (int c = c0; c <= c1; ++c) {
            const float w = falloff(glm::length(img_.centre(c, r) - p), rad);
            if (!(w > 0.f)) continue;
            apply(c, r, w);
            if (mirror_x) apply(R - 1 - c, r, w);
            if (mirror_y) apply(c, R - 1 - r, w);
            if (mirror_x && mirror_y) apply(R - 1 - c, R - 1 - r, w);
        }
}

bool Painter::undo() {
    if (stroking_ || undo_.empty()) return false;
    redo_.push_back(std::move(img_));
    img_ = std::move(undo_.back());
    undo_.pop_back();
    return true;
}

bool Painter::redo() {
    if (stroking_ || redo_.empty()) return false;
    undo_.push_back(std::move(img_));
    img_ = std::move(redo_.back());
    redo_.pop_back();
    return true;
}

// [SECTION] Lobes and handles
namespace {

constexpr double kDeg = 180.0 / 3.14159265358979323846;

double round_significant(double v, int digits) {
    if (!(v != 0.0) || !std::isfinite(v)) return v;
    const double p = std::pow(10.0, digits - 1 - int(std::floor(std::log10(std::fabs(v)))));
    return std::round(v * p) / p;
}

float phong_alpha(double e) { return float(std::sqrt(2.0 / (std::max(e, 0.0) + 2.0))); }

// Sets a parameter if the value differs; marks its declared cost (recompute for every NDF key).
bool set_if_changed(ParamTable& m, const char* name, const Value& v, Dirty& dirty) {
    if (m.get(name) == v) return false;
    m.set(name, v);
    dirty.mark(m.group().find(name)->cost);
    return true;
}

double clamp_to(const ParamTable& m, const char* name, double v) {
    const ParamDecl& d = *m.group().find(name);
    return std::clamp(v, d.min, d.max);
}
}  // namespace

namespace {
// The lobes of an NDF parameter set as a list: a single analytic lobe from its keys, or the parsed
// bumpsynth.lobes (empty while it does not parse, or for image NDFs).
std::vector<bumpsynth::Lobe> lobe_list(const ParamTable& m) {
    using bumpsynth::Lobe;
    const std::string kind = m.get_string("ndf");
    const float ax = float(m.get_float("alpha_x")), ay = float(m.get_float("alpha_y")), rot = float(m.get_float("rotation"));
    try {
        if (kind == "lobes") return bumpsynth::parse_lobes(m.get_string("lobes"));
        bumpsynth::LobeKind k = bumpsynth::LobeKind::beckmann;
        if (!bumpsynth::lobe_kind(kind, k)) return {};  // image, normal_map, heightfield: no lobes
        if (k == bumpsynth::LobeKind::blinn_phong) return {Lobe::blinn_phong(float(m.get_float("exponent")))};
        return {Lobe::anisotropic(k, ax, ay, rot)};
    } catch (const InputError&) {
    }
    return {};
}

// The lobe a new one starts from: a narrow anisotropic GGX at half weight.
bumpsynth::Lobe new_lobe() { return bumpsynth::Lobe::ggx(0.05f, 0.5f, 45.f, 0.5f); }

// Writes a list back: `lobes` for two or more, the single lobe's own keys for one.
void set_lobe_list(ParamTable& m, const std::vector<bumpsynth::Lobe>& lobes) {
    if (lobes.size() >= 2) {
        m.set("lobes", bumpsynth::format_lobes(lobes));
        m.set("ndf", std::string("lobes"));
        return;
    }
    const bumpsynth::Lobe& l = lobes.front();
    // The list's text holds 6 significant digits: so do the keys (no float noise like 0.1199999973).
    const auto exact = [](float v) { return round_significant(double(v), 6); };
    m.set("ndf", std::string(bumpsynth::lobe_name(l.kind())));
    if (l.kind() == bumpsynth::LobeKind::blinn_phong) {
        m.set("exponent", exact(l.exponent()));
        return;
    }
    m.set("alpha_x", clamp_to(m, "alpha_x", exact(l.alpha_x())));
    m.set("alpha_y", clamp_to(m, "alpha_y", exact(l.alpha_y())));
    m.set("rotation", clamp_to(m, "rotation", exact(l.rotation_deg())));
}
}  // namespace

std::vector<LobeShape> lobes_of(const ParamTable& m) {
    std::vector<LobeShape> out;
    for (const bumpsynth::Lobe& l : lobe_list(m)) {
        if (l.kind() == bumpsynth::LobeKind::blinn_phong) out.push_back({"phong", vec2(phong_alpha(l.exponent())), 0.f});
        else out.push_back({bumpsynth::lobe_name(l.kind()), vec2(l.alpha_x(), l.alpha_y()), l.rotation_deg()});
    }
    return out;
}

std::vector<Handle> handles_of(const ParamTable& m) {
    std::vector<Handle> out;
    const auto lobes = lobes_of(m);
    for (size_t k = 0; k < lobes.size(); ++k) {
        const LobeShape& l = lobes[k];
        if (l.kind == "phong") {
            out.push_back({int(k), HandleKind::alpha_x, vec2(l.alpha.x, 0.f)});
            continue;
        }
        const float r = radians(l.rotation_deg);
        const vec2 ex(std::cos(r), std::sin(r)), ey(-std::sin(r), std::cos(r));
        out.push_back({int(k), HandleKind::alpha_x, ex * l.alpha.x});
        out.push_back({int(k), HandleKind::alpha_y, ey * l.alpha.y});
        out.push_back({int(k), HandleKind::rotation, ex * (1.08f + 0.1f * float(k))});
    }
    return out;
}

bool drag_handle(ParamTable& m, const Handle& h, vec2 p, Dirty& dirty) {
    std::vector<bumpsynth::Lobe> lobes = lobe_list(m);
    if (h.lobe < 0 || size_t(h.lobe) >= lobes.size() || !std::isfinite(p.x) || !std::isfinite(p.y)) return false;
    const bumpsynth::Lobe& l = lobes[size_t(h.lobe)];
    const bool single = m.get_string("ndf") != "lobes";
    // A single lobe: the key itself; in a list: the term, rewritten in bumpsynth.lobes.
    const auto commit = [&](const char* key, double v, const bumpsynth::Lobe& changed) {
        if (single) return set_if_changed(m, key, v, dirty);
        lobes[size_t(h.lobe)] = changed;
        return set_if_changed(m, "lobes", bumpsynth::format_lobes(lobes), dirty);
    };
    if (l.kind() == bumpsynth::LobeKind::blinn_phong) {
        if (h.kind != HandleKind::alpha_x) return false;
        const double a = std::clamp(double(glm::length(p)), 1e-4, 1.0);
        const double e = clamp_to(m, "exponent", round_significant(2.0 / (a * a) - 2.0, 4));
        return commit("exponent", e, bumpsynth::Lobe::blinn_phong(float(e), l.weight()));
    }
    const double r = radians(l.rotation_deg());
    const vec2 ex(float(std::cos(r)), float(std::sin(r))), ey(float(-std::sin(r)), float(std::cos(r)));
    if (h.kind == HandleKind::rotation) {
        if (glm::length(p) < 1e-6f) return false;
        double deg = std::round(std::atan2(double(p.y), double(p.x)) * kDeg * 10.0) / 10.0;
        // The turn nearest the current angle, within the declared range.
        const double cur = single ? m.get_float("rotation") : double(l.rotation_deg());
        deg += 360.0 * std::round((cur - deg) / 360.0);
        const ParamDecl& d = *m.group().find("rotation");
        while (deg > d.max) deg -= 360.0;
        while (deg < d.min) deg += 360.0;
        return commit("rotation", deg, bumpsynth::Lobe::anisotropic(l.kind(), l.alpha_x(), l.alpha_y(), float(deg), l.weight()));
    }
    const bool along_x = h.kind == HandleKind::alpha_x;
    const double along = std::fabs(double(glm::dot(p, along_x ? ex : ey)));
    const double a = clamp_to(m, "alpha_x", round_significant(std::max(along, 1e-4), 4));
    return commit(along_x ? "alpha_x" : "alpha_y", a,
                  bumpsynth::Lobe::anisotropic(l.kind(), along_x ? float(a) : l.alpha_x(), along_x ? l.alpha_y() : float(a), l.rotation_deg(), l.weight()));
}

bool can_add_lobe(const ParamTable& m) { return !lobe_list(m).empty(); }
bool can_remove_lobe(const ParamTable& m) { return m.get_string("ndf") == "lobes" && lobe_list(m).size() >= 2; }

void add_lobe(ParamTable& m, Dirty& dirty) {
    std::vector<bumpsynth::Lobe> lobes = lobe_list(m);
    if (lobes.empty()) return;
    lobes.push_back(new_lobe());
    set_lobe_list(m, lobes);
    dirty.mark(Cost::Recompute);
}

void remove_lobe(ParamTable& m, Dirty& dirty) {
    if (!can_remove_lobe(m)) return;
    std::vector<bumpsynth::Lobe> lobes = lobe_list(m);
    lobes.pop_back();
    set_lobe_list(m, lobes);
    dirty.mark(Cost::Recompute);
}

// [SECTION] Files
namespace {
std::string sanitize(const std::string& s, const std::string& fallback) {
    std::string out;
    for (char c : s) out += (std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_' || c == '.') ? c : '_';
    while (!out.empty() && out.front() == '.') out.erase(out.begin());  // no hidden files, no ".."
    return out.empty() ? fallback : out;
}
}  // namespace

std::string painted_file_name(const Scene& s, int object) {
    const std::string obj = size_t(object) < s.objects.size() ? s.objects[size_t(object)].name : "";
    return sanitize(s.name, "scene") + "." + sanitize(obj, "object" + std::to_string(object)) + ".ndf.exr";
}

std::string painted_file_path(const Scene& s, int object) {
    const std::string name = painted_file_name(s, object);
    return s.base_dir.empty() ? name : (fs::path(s.base_dir) / name).string();
}

void write_ndf_exr(const std::string& path, const NdfImage& img) {
    if (img.empty()) throw InputError(path + ": there is no NDF image to save");
    Image out(img.size, img.size, 1);
    out.data = img.px;
    write_exr(path, out);
}

std::string apply_painted(Scene& s, int object, const NdfImage& img, Dirty& dirty) {
    if (size_t(object) >= s.objects.size()) throw InputError("no object " + std::to_string(object));
    for (float v : img.px)
        if (!(v >= 0.f) || !std::isfinite(v)) throw InputError("the painted image has a negative or non-finite value");
    if (!(image_mass(img) > 0.0))
        throw InputError("the painted image is empty inside the disk: paint something before it can be the NDF (not applied)");
    const std::string path = painted_file_path(s, object);
    write_ndf_exr(path, img);
    ParamTable& m = s.objects[size_t(object)].material;
    m.set("ndf_image", painted_file_name(s, object));
    m.set("ndf", std::string("image"));
    dirty.mark(Cost::Recompute);
    return path;
}

bumpsynth::Ndf load_ndf_file(Scene& s, int object, const std::string& path, Dirty& dirty) {
    if (size_t(object) >= s.objects.size()) throw InputError("no object " + std::to_string(object));
    if (path.empty()) throw InputError("enter the path of an NDF image (EXR, PNG, ...) to load");
    ParamTable m = s.objects[size_t(object)].material;
    m.set("ndf", std::string("image"));
    m.set("ndf_image", path);
    bumpsynth::Ndf ndf = bumpsynth::ndf_from_material(s, m);  // the stage's own reading: same checks, same messages
    s.objects[size_t(object)].material = std::move(m);
    dirty.mark(Cost::Recompute);
    return ndf;
}

// [SECTION] Display
namespace {
struct Rgb {
    unsigned char r, g, b;
};
// Ten stops of matplotlib's viridis and inferno.
constexpr Rgb kViridis[] = {{68, 1, 84},    {72, 40, 120},  {62, 73, 137},  {49, 104, 142}, {38, 130, 142},
                            {31, 158, 137}, {53, 183, 121}, {110, 206, 88}, {181, 222, 43}, {253, 231, 37}};
constexpr Rgb kInferno[] = {{0, 0, 4},     {27, 12, 65},  {74, 12, 107}, {120, 28, 109}, {165, 44, 96},
                            {207, 68, 70}, {237, 105, 37}, {251, 155, 6}, {247, 209, 61}, {252, 255, 164}};
}  // namespace

uint32_t color_of(ColorMap m, float t) {
    t = std::isfinite(t) ? std::clamp(t, 0.f, 1.f) : 0.f;
    float r, g, b;
    if (m == ColorMap::grey) {
        r = g = b = 255.f * t;
    } else {
        const Rgb* s = m == ColorMap::inferno ? kInferno : kViridis;
        const float f = t * 9.f;
        const int i = std::min(8, int(f));
        const float u = f - float(i);
        r = float(s[i].r) + u * float(s[i + 1].r - s[i].r);
        g = float(s[i].g) + u * float(s[i + 1].g - s[i].g);
        b = float(s[i].b) + u * float(s[i + 1].b - s[i].b);
    }
    auto byte = [](float v) { return uint32_t(std::clamp(int(std::lround(v)), 0, 255)); };
    return byte(r) | (byte(g) << 8) | (byte(b) << 16) | (0xFFu << 24);
}

DisplayGrid display_grid(const NdfImage& img, int max_cells) {
    DisplayGrid g;
    const int R = img.size;
    if (R <= 0) return g;
    g.n = std::min(R, std::max(1, max_cells));
    g.v.assign(size_t(g.n) * size_t(g.n), std::numeric_limits<float>::quiet_NaN());
    const double h = 2.0 / R;
    // Whether pixel (c, r) meets the disk: its point nearest the origin is inside.
    auto meets = [&](int c, int r) {
        const double x0 = -1.0 + c * h, x1 = x0 + h, y1 = 1.0 - r * h, y0 = y1 - h;
        const double nx = std::clamp(0.0, x0, x1), ny = std::clamp(0.0, y0, y1);
        return nx * nx + ny * ny < 1.0;
    };
    for (int b = 0; b < g.n; ++b)
        for (int a = 0; a < g.n; ++a) {
            double sum = 0.0;
            int count = 0;
            for (int r = b * R / g.n; r < (b + 1) * R / g.n; ++r)
                for (int c = a * R / g.n; c < (a + 1) * R / g.n; ++c)
                    if (meets(c, r)) sum += double(img.at(c, r)), ++count;
            if (count == 0) continue;
            const float v = float(sum / count);
            g.v[size_t(b) * size_t(g.n) + size_t(a)] = v;
            if (v > g.vmax) g.vmax = v;
        }
    return g;
}

float display_t(const ViewOptions& o, float v, float vmax) {
    if (!(vmax > 0.f) || !(v > 0.f)) return 0.f;
    if (!o.log) return std::clamp(v / vmax, 0.f, 1.f);
    const float dec = std::max(o.decades, 0.1f);
    return std::clamp((std::log10(v) - (std::log10(vmax) - dec)) / dec, 0.f, 1.f);
}
}  // namespace mesolab::panels::ndf_editor
