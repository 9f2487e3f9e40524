// Text for plots: FreeType faces, a glyph cache per pixel size, UTF-8 decoding and line layout.
#include "app/plot_text.h"

#include <ft2build.h>
#include FT_FREETYPE_H

#include <algorithm>
#include <climits>
#include <cstddef>
#include <cstring>
#include <stdexcept>

#ifndef MESOLAB_PLOT_FONT
#define MESOLAB_PLOT_FONT "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf"
#endif

namespace mesolab {

const char* plot_font_path() { return MESOLAB_PLOT_FONT; }

std::u32string decode_utf8(const std::string& text) {
    std::u32string out;
    out.reserve(text.size());
    const size_t n = text.size();
    for (size_t i = 0; i < n;) {
        const unsigned char b = static_cast<unsigned char>(text[i]);
        int len = 0;
        char32_t c = 0, min = 0;
        if (b < 0x80) len = 1, c = b;
        else if ((b & 0xE0) == 0xC0) len = 2, c = b & 0x1Fu, min = 0x80;
        else if ((b & 0xF0) == 0xE0) len = 3, c = b & 0x0Fu, min = 0x800;
        else if ((b & 0xF8) == 0xF0) len = 4, c = b & 0x07u, min = 0x10000;
        else {  // a stray continuation byte or an invalid lead byte
            out.push_back(U'\uFFFD');
            ++i;
            continue;
        }
        size_t k = 1;
        for (; k < size_t(len) && i + k < n; ++k) {
            const unsigned char cb = static_cast<unsigned char>(text[i + k]);
            if ((cb & 0xC0) != 0x80) break;
            c = (c << 6) | (cb & 0x3Fu);
        }
        if (k < size_t(len)) {  // truncated: the bytes read so far are one bad character
            out.push_back(U'\uFFFD');
            i += k;
            continue;
        }
        const bool bad = c < min || c > 0x10FFFF || (c >= 0xD800 && c <= 0xDFFF);
        out.push_back(bad ? U'\uFFFD' : c);
        i += k;
    }
    return out;
}

namespace {
FT_Library library() {
    // One library for the process; FreeType libraries are not thread-safe, every use is under a
    // Font's mutex or this function's initialisation.
    static FT_Library lib = [] {
        FT_Library l = nullptr;
        if (FT_Init_FreeType(&l) != 0) throw std::runtime_error("FreeType: cannot initialise the library");
        return l;
    }();
    return lib;
}
std::mutex& library_mutex() {
    static std::mutex m;
    return m;
}

int clamp_px(int px) { return std::clamp(px, 1, 1000); }
}  // namespace

struct Font::Face {
    FT_Face face = nullptr;
    ~Face() {
        if (face) {
            std::lock_guard lock(library_mutex());
            FT_Done_Face(face);
        }
    }
};

Font::Font(const std::string& path) : path_(path), face_(std::make_unique<Face>()) {
    std::lock_guard lock(library_mutex());
    const FT_Error err = FT_New_Face(library(), path.c_str(), 0, &face_->face);
    if (err != 0 || !face_->face || !FT_IS_SCALABLE(face_->face)) {
        const char* what = FT_Error_String(err);
        throw std::runtime_error("font " + path + ": " +
                                 (FT_ERROR_BASE(err) == FT_Err_Cannot_Open_Resource ? std::string("cannot open the file")
                                  : err != 0 ? std::string(what ? what : "unreadable")
                                             : std::string("not a scalable font")) +
                                 "; plots need DejaVu Sans: install the Debian package " + kPlotFontPackage);
    }
}

Font::~Font() = default;

void Font::set_size(int px) const {
    if (size_ == px) return;
    if (FT_Set_Pixel_Sizes(face_->face, 0, FT_UInt(px)) != 0)
        throw std::runtime_error("font " + path_ + ": cannot set the size " + std::to_string(px) + " px");
    size_ = px;
}

const Font::Glyph& Font::glyph(unsigned index, int px) const {
    const auto key = std::pair{px, index};
    if (auto it = glyphs_.find(key); it != glyphs_.end()) return it->second;
    set_size(px);
    Glyph g;
    FT_Face f = face_->face;
    if (FT_Load_Glyph(f, index, FT_LOAD_TARGET_LIGHT) == 0 && FT_Render_Glyph(f->glyph, FT_RENDER_MODE_NORMAL) == 0) {
        const FT_GlyphSlot s = f->glyph;
        g.advance = int((s->advance.x + 32) >> 6);
        const FT_Bitmap& bm = s->bitmap;
        if (bm.pixel_mode == FT_PIXEL_MODE_GRAY && bm.width > 0 && bm.rows > 0) {
            g.left = s->bitmap_left, g.top = s->bitmap_top;
            g.width = int(bm.width), g.rows = int(bm.rows);
            g.coverage.resize(size_t(g.width) * size_t(g.rows));
            const int levels = std::max(1, int(bm.num_grays) - 1);
            for (int r = 0; r < g.rows; ++r)
                for (int c = 0; c < g.width; ++c) {
                    const int v = bm.buffer[std::ptrdiff_t(r) * bm.pitch + c];
                    g.coverage[size_t(r) * size_t(g.width) + size_t(c)] = (unsigned char)(v * 255 / levels);
                }
        }
    }
    return glyphs_.emplace(key, std::move(g)).first->second;
}

std::pair<int, int> Font::line_metrics(int px) const {
    if (auto it = metrics_.find(px); it != metrics_.end()) return it->second;
    // The extent of tall and deep reference glyphs: ascenders, descenders, brackets.
    int asc = 1, desc = 0;
    for (char32_t c : std::u32string(U"Hbdfhkl0(|)[]gjpqy\u00B5")) {
        const unsigned index = FT_Get_Char_Index(face_->face, FT_ULong(c));
        if (index == 0) continue;
        const Glyph& g = glyph(index, px);
        if (g.rows == 0) continue;
        asc = std::max(asc, g.top), desc = std::max(desc, g.rows - g.top);
    }
    return metrics_.emplace(px, std::pair{asc, desc}).first->second;
}

int Font::ascent(int px) const {
    std::lock_guard lock(mutex_);
    return line_metrics(clamp_px(px)).first;
}

int Font::descent(int px) const {
    std::lock_guard lock(mutex_);
    return line_metrics(clamp_px(px)).second;
}

bool Font::has_glyph(char32_t c) const {
    std::lock_guard lock(mutex_);
    return FT_Get_Char_Index(face_->face, FT_ULong(c)) != 0;
}

std::vector<Font::Placed> Font::layout(const std::u32string& text, int px, int& box_left, int& box_right) const {
    std::vector<Placed> placed;
    placed.reserve(text.size());
    box_left = INT_MAX, box_right = INT_MIN;
    FT_Face f = face_->face;
    const bool kerning = FT_HAS_KERNING(f);
    int pen = 0;
    unsigned prev = 0;
    for (char32_t c : text) {
        const unsigned index = FT_Get_Char_Index(f, FT_ULong(c));
        if (kerning && prev != 0 && index != 0) {
            set_size(px);
            FT_Vector k{};
            if (FT_Get_Kerning(f, prev, index, FT_KERNING_DEFAULT, &k) == 0) pen += int((k.x + 32) >> 6);
        }
        const Glyph& g = glyph(index, px);
        if (g.rows > 0) box_left = std::min(box_left, pen + g.left), box_right = std::max(box_right, pen + g.left + g.width);
        else box_left = std::min(box_left, pen), box_right = std::max(box_right, pen + g.advance);
        placed.push_back({&g, pen});
        pen += g.advance;
        prev = index;
    }
    if (placed.empty()) box_left = box_right = 0;
    return placed;
}

int Font::width(const std::string& utf8, int px) const {
    std::lock_guard lock(mutex_);
    int l = 0, r = 0;
    layout(decode_utf8(utf8), clamp_px(px), l, r);
    return std::max(0, r - l);
}

int Font::left_bearing(const std::string& utf8, int px) const {
    std::lock_guard lock(mutex_);
    int l = 0, r = 0;
    layout(decode_utf8(utf8), clamp_px(px), l, r);
    return l;
}

void Font::rasterize(const std::string& utf8, int px, int x, int y, const std::function<void(int, int, float)>& ink) const {
    std::lock_guard lock(mutex_);
    px = clamp_px(px);
    int l = 0, r = 0;
    const std::vector<Placed> placed = layout(decode_utf8(utf8), px, l, r);
    const int baseline = y + line_metrics(px).first;
    for (const Placed& p : placed) {
        const Glyph& g = *p.glyph;
        const int gx = x - l + p.pen + g.left, gy = baseline - g.top;
        for (int row = 0; row < g.rows; ++row)
            for (int col = 0; col < g.width; ++col) {
                const unsigned char v = g.coverage[size_t(row) * size_t(g.width) + size_t(col)];
                if (v) ink(gx + col, gy + row, float(v) / 255.f);
            }
    }
}

const Font& plot_font() {
    static std::mutex m;
    static std::unique_ptr<Font> font;
    std::lock_guard lock(m);
    if (!font) font = std::make_unique<Font>(plot_font_path());
    return *font;
}
}  // namespace mesolab
