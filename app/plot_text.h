#pragma once
// Text for plots: a TrueType font (DejaVu Sans from the Debian package fonts-dejavu-core by default)
// rasterised by FreeType (libfreetype-dev), anti-aliased, from UTF-8. Glyphs are hinted lightly
// (vertical only) and placed at whole pixels with the font's kerning, so the same text at the same
// size gives the same pixels.
//
// A missing font file is an error naming the file and the package, not a fallback: a built-in
// fallback would have no Greek letters or unit signs and would put placeholders in the labels
// without anyone noticing. `mesolab sweep` asks for the font before measuring, so the error comes
// before the work.
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <utility>
#include <vector>

namespace mesolab {

// The plot font's file: MESOLAB_PLOT_FONT at configure time,
// /usr/share/fonts/truetype/dejavu/DejaVuSans.ttf by default.
const char* plot_font_path();
// The Debian package that provides it.
inline constexpr const char* kPlotFontPackage = "fonts-dejavu-core";

// Unicode code points of UTF-8 text; a malformed or truncated sequence becomes one U+FFFD.
std::u32string decode_utf8(const std::string& text);

class Font {
public:
    // Loads a TrueType/OpenType file; std::runtime_error naming the file and kPlotFontPackage when
    // it is missing or unreadable.
    explicit Font(const std::string& path);
    ~Font();
    Font(const Font&) = delete;
    Font& operator=(const Font&) = delete;

    const std::string& path() const { return path_; }

    // Sizes are em sizes in pixels (clamped to [1, 1000]). The line box of a line of text is
    // ascent(px) + descent(px) tall: it holds the ascenders and descenders of Latin letters,
    // digits and brackets (accents on capitals may reach a pixel or two above it).
    int ascent(int px) const;
    int descent(int px) const;
    int line_height(int px) const { return ascent(px) + descent(px); }

    // Width of the text's box: from the left edge of its first glyph's ink to the right edge of
    // its last glyph's ink, the glyphs spaced by their advances and kerning (a blank glyph, such as
    // a space, counts with its advance). 0 for "".
    int width(const std::string& utf8, int px) const;
    // Where the box starts right of the pen's starting point (the first glyph's left bearing; may
    // be negative): a renderer that places text by its pen draws it at x - left_bearing.
    int left_bearing(const std::string& utf8, int px) const;

    // Calls ink(x, y, coverage) with coverage in (0, 1] for each pixel the text covers, the box's
    // top-left corner at (x, y) (the first glyph's ink starts at x, the baseline is at y + ascent).
    void rasterize(const std::string& utf8, int px, int x, int y,
                   const std::function<void(int, int, float)>& ink) const;

    // Whether the font has a glyph for code point c (otherwise the font's .notdef box is drawn).
    bool has_glyph(char32_t c) const;

private:
    struct Glyph {
        int left = 0, top = 0, width = 0, rows = 0, advance = 0;  // pixels; top: above the baseline
        std::vector<unsigned char> coverage;                       // width x rows, 0..255
    };
    struct Placed {
        const Glyph* glyph;
        int pen;  // pixels from the start of the line
    };
    struct Face;
    const Glyph& glyph(unsigned index, int px) const;  // with mutex_ held
    void set_size(int px) const;                        // with mutex_ held
    // Glyphs of one line and the box's left and right edges in pen space; with mutex_ held.
    std::vector<Placed> layout(const std::u32string& text, int px, int& box_left, int& box_right) const;
    std::pair<int, int> line_metrics(int px) const;     // with mutex_ held

    std::string path_;
    std::unique_ptr<Face> face_;
    mutable std::mutex mutex_;
    mutable int size_ = 0;
    mutable std::map<std::pair<int, unsigned>, Glyph> glyphs_;
    mutable std::map<int, std::pair<int, int>> metrics_;
};

// The plot font, loaded on first use (thread-safe); throws as Font() does, each time it is asked
// for while the file is missing.
const Font& plot_font();
}  // namespace mesolab
