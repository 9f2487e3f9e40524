#pragma once
// [SECTION] NDF editor of the bumpsynth panel.
// Shows the selected object's tabulated NDF (the last evaluation's bumpsynth.ndf) over the
// normal's (x, y) unit disk, lets the analytic lobes be reshaped by handles, and paints an NDF
// image with a brush (symmetries, undo / redo), saved as an EXR that the material then points at
// (ndf = image). Every parameter change goes through the material's ParamTable and marks a
// recompute, so the look-up table and the frame follow live.
//
// The editing logic (image, brush, symmetry, undo, lobe handles, files) is plain C++ below, usable
// without ImGui; NdfEditor draws it with ImDrawList rectangles (no GL texture), so it also runs in
// a headless ImGui context.
#include "core/bumpsynth/ndf.h"
#include "core/math.h"
#include "panels/panel.h"

#include <array>
#include <cstdint>
#include <deque>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace mesolab::panels::ndf_editor {

// [SECTION] Image
// An R x R grid of D values over [-1, 1]² in image order, the layout Ndf::from_image reads: row 0
// at the top (y = +1), column 0 at x = -1. Pixel (c, r) is centred at (-1 + (c + ½) h, 1 - (r + ½) h),
// h = 2 / R. Values are D up to any positive scale (from_image normalises).
struct NdfImage {
    int size = 0;
    std::vector<float> px;  // size * size, row-major

    NdfImage() = default;
    explicit NdfImage(int resolution, float fill = 0.f) : size(resolution), px(size_t(resolution) * size_t(resolution), fill) {}
    float& at(int c, int r) { return px[size_t(r) * size_t(size) + size_t(c)]; }
    float at(int c, int r) const { return px[size_t(r) * size_t(size) + size_t(c)]; }
    vec2 centre(int c, int r) const;
    bool empty() const { return px.empty(); }
    bool operator==(const NdfImage& o) const = default;
};

// The tabulated values of an NDF (Ndf::value, sr^-1) as an image: cell (i, j) -> column i, row R-1-j.
NdfImage image_from_ndf(const bumpsynth::Ndf& ndf);
// Σ value · |pixel ∩ disk|: the integral of the image over the disk (0: nothing an NDF can be made of).
double image_mass(const NdfImage& img);

// [SECTION] Brush
enum class Symmetry { none, mirror_x, mirror_y, both, rotational };
inline constexpr const char* kSymmetryNames[] = {"none", "mirror x", "mirror y", "both (4-fold)", "rotational"};

struct Brush {
    float radius = 0.15f;  // disk units; the falloff reaches 0 there
    float strength = 1.f;  // D added (erase: removed) under the centre by one stroke
    bool erase = false;
    Symmetry symmetry = Symmetry::none;
    int fold = 6;          // rotational: copies at every 360/fold degrees (2..32)
};

// Falloff at distance d from a dab's centre: a Gaussian shifted and scaled to go from 1 at the
// centre to exactly 0 at the radius (smooth inside, 0 outside).
float falloff(float d, float radius);
// Where a dab at p lands under a symmetry (p first): mirror x mirrors across the y axis (x -> -x),
// mirror y across the x axis, both gives the 4 images, rotational `fold` rotated copies.
std::vector<vec2> symmetric_points(vec2 p, Symmetry s, int fold);

// The image being painted, with its strokes and undo / redo.
// A stroke is one undo step. While it lasts, each pixel's coverage is the largest falloff of any
// dab of the stroke (of any of their symmetric images), and the pixel is
//     max(0, value at the start of the stroke ± strength · coverage)
// so the result depends neither on the dab spacing nor on the frame rate, and never goes negative.
// Mirror symmetries apply each dab's falloff to the mirrored pixel indices too (combined by max, which
// is exact), so an image painted from a symmetric one (e.g. empty) is exactly symmetric.
class Painter {
public:
    static constexpr size_t kHistory = 64;  // undo steps kept

    Painter() = default;
    explicit Painter(NdfImage img) : img_(std::move(img)) {}

    const NdfImage& image() const { return img_; }
    // A new image, forgetting the history (entering paint mode).
    void reset(NdfImage img);
    // Replace the image as one undo step (Clear, a loaded file).
    void replace(NdfImage img);

    void begin_stroke(const Brush& b);
    // Dabs along the segment from the last point (none: just p) to p, every radius / 4.
    void stroke_to(vec2 p);
    // Ends the stroke; true when it changed the image (otherwise it leaves no undo step).
    bool end_stroke();
    bool stroking() const { return stroking_; }

    bool can_undo() const { return !undo_.empty(); }
    bool can_redo() const { return !redo_.empty(); }
    size_t undo_steps() const { return undo_.size(); }
    bool undo();
    bool redo();

private:
    void dab(vec2 p);
    void stamp(vec2 centre, bool mirror_x, bool mirror_y);
    void push_undo(NdfImage before);

    NdfImage img_, start_;
    std::vector<float> cover_;
    Brush brush_;
    bool stroking_ = false;
    std::optional<vec2> last_;
    std::deque<NdfImage> undo_, redo_;
};

// [SECTION] Analytic lobes and their handles
// The lobes an NDF parameter set draws as ellipses: the q = 1 contour x'²/α_x² + y'²/α_y² = 1 in
// the lobe frame (rotated by `rotation` from +x towards +y). Phong has one circular lobe of the
// equivalent width α = sqrt(2 / (e + 2)); image has none; lobes has one per term of bumpsynth.lobes.
struct LobeShape {
    std::string kind;  // phong, beckmann, ggx, ward
    vec2 alpha{0.f};
    float rotation_deg = 0.f;
};
std::vector<LobeShape> lobes_of(const ParamTable& m);

enum class HandleKind { alpha_x, alpha_y, rotation };
struct Handle {
    int lobe = 0;  // index in lobes_of(): the single lobe's keys, or a term of bumpsynth.lobes
    HandleKind kind = HandleKind::alpha_x;
    vec2 pos{0.f};  // in disk coordinates; rotation handles sit just outside the rim
};
// The handles of an NDF parameter set: per lobe the ends of its two axes and a rotation knob on
// the lobe's x axis outside the disk (Phong: only its radius, which sets the exponent).
std::vector<Handle> handles_of(const ParamTable& m);
// Drag a handle to the disk point p: an axis handle sets that α to |p · axis| (clamped to the
// declared range, 4 significant digits), a rotation handle sets the rotation to p's angle (0.1°).
// Changes go through ParamTable::set and mark a recompute; returns whether anything changed.
bool drag_handle(ParamTable& m, const Handle& h, vec2 p, Dirty& dirty);

// Add a lobe: the lobes so far (a single analytic lobe, Phong included, or the terms of
// bumpsynth.lobes) plus a narrow GGX at weight 0.5, as ndf = lobes. Remove: the last term goes; when
// one is left, ndf becomes that lobe's kind with its own keys (alpha_x, ... or exponent).
bool can_add_lobe(const ParamTable& m);
bool can_remove_lobe(const ParamTable& m);
void add_lobe(ParamTable& m, Dirty& dirty);
void remove_lobe(ParamTable& m, Dirty& dirty);

// [SECTION] Files
// "<scene name>.<object name>.ndf.exr", characters other than letters, digits, '-', '_' and '.'
// replaced by '_' ("scene" / "object<i>" for empty names).
std::string painted_file_name(const Scene& s, int object);
// Next to the preset (Scene::base_dir), or in the current directory without one.
std::string painted_file_path(const Scene& s, int object);
// A one-channel 32-bit float EXR of the image (core/image.h's write_exr: temporary file, then rename).
void write_ndf_exr(const std::string& path, const NdfImage& img);
// Saves a painted image for `object` (painted_file_path) and points its material at it: ndf = image,
// ndf_image = the file name (relative, so it resolves against base_dir like any path parameter), then
// marks a recompute. InputError (nothing changed) for an image without mass in the disk or a failed
// write. Returns the path written.
std::string apply_painted(Scene& s, int object, const NdfImage& img, Dirty& dirty);
// Loads an NDF image file (EXR, PNG, anything OpenImageIO reads; relative to base_dir like
// ndf_image) into the object's material: checks it the way the bumpsynth.ndf stage reads it
// (InputError naming the file, nothing changed), then sets ndf = image, ndf_image = path. Returns
// the NDF it tabulates at the object's ndf_resolution.
bumpsynth::Ndf load_ndf_file(Scene& s, int object, const std::string& path, Dirty& dirty);

// [SECTION] Display
enum class ColorMap { viridis, inferno, grey };
inline constexpr const char* kColorMapNames[] = {"viridis", "inferno", "grey"};
// RGBA (ImU32 layout: R in the low byte) of t in [0, 1].
uint32_t color_of(ColorMap m, float t);

struct ViewOptions {
    bool log = true;
    float decades = 4.f;  // log: the range shown below the maximum
    ColorMap map = ColorMap::viridis;
};

// An image averaged down to at most `max_cells` per side (pixels whose centres lie in the disk;
// NaN for display cells with none), for drawing.
struct DisplayGrid {
    int n = 0;
    std::vector<float> v;  // n * n, row 0 at the top
    float vmax = 0.f;
};
DisplayGrid display_grid(const NdfImage& img, int max_cells = 128);
// Colour-map coordinate in [0, 1] of a value (linear: v / vmax; log: over `decades` below vmax).
float display_t(const ViewOptions& o, float v, float vmax);

// [SECTION] The ImGui editor
class NdfEditor {
public:
    // Draws the editor for scene object `object` (which must use bumpsynth) into the current window.
    void draw(PanelContext& ctx, int object);

    bool painting() const { return painting_; }
    // Enter paint mode with the values of an NDF, or with an empty image of R x R pixels.
    void start_painting(const bumpsynth::Ndf& ndf);
    void start_empty(int resolution);
    void stop_painting() { painting_ = false; }
    // After a stroke, undo or redo: save the image and point the material at it (errors shown).
    void apply(Scene& s, int object, Dirty& dirty);
    Painter& painter() { return painter_; }
    const std::string& error() const { return error_; }
    const std::string& note() const { return note_; }

    Brush brush;
    ViewOptions view;
    char path[1024] = "";  // the Load / Save field

    // The view's mapping of the last frame (tests): screen position of a disk point and back.
    std::array<float, 2> screen_of(vec2 xy) const { return {cx_ + xy.x * scale_, cy_ - xy.y * scale_}; }
    vec2 disk_of(float sx, float sy) const { return {(sx - cx_) / scale_, -(sy - cy_) / scale_}; }

private:
    void draw_view(PanelContext& ctx, int object, const bumpsynth::Ndf* ndf);
    void draw_lobe_buttons(PanelContext& ctx, SceneObject& o);
    void draw_paint_controls(PanelContext& ctx, int object, const bumpsynth::Ndf* ndf);
    void draw_files(PanelContext& ctx, int object, const bumpsynth::Ndf* ndf);
    void undo_redo(PanelContext& ctx, int object, bool undo);

    std::string owner_;  // scene name / object index / object name the state belongs to
    bool painting_ = false, stroke_erase_ = false;
    Painter painter_;
    std::optional<Handle> dragging_;
    std::string error_, note_;
    std::shared_ptr<const bumpsynth::Ndf> shown_;  // the evaluation's NDF the cache below is of
    NdfImage shown_image_;
    float cx_ = 0.f, cy_ = 0.f, scale_ = 1.f;
};
}  // namespace mesolab::panels::ndf_editor
