#pragma once
// Float images (linear), N channels interleaved, row 0 at the top. Reading and writing through
// OpenImageIO: PNG is 8-bit sRGB-encoded, EXR is 32-bit float linear.
#include <cstdint>
#include <string>
#include <vector>

namespace mesolab {

struct Image {
    int width = 0, height = 0, channels = 0;
    std::vector<float> data;  // width*height*channels, row-major, top row first

    Image() = default;
    Image(int w, int h, int c, float fill = 0.f)
        : width(w), height(h), channels(c), data(size_t(w) * size_t(h) * size_t(c), fill) {}
    float* at(int x, int y) { return data.data() + (size_t(y) * size_t(width) + size_t(x)) * size_t(channels); }
    const float* at(int x, int y) const { return data.data() + (size_t(y) * size_t(width) + size_t(x)) * size_t(channels); }
    bool empty() const { return data.empty(); }
};

// sRGB transfer function (IEC 61966-2-1) on one linear value clamped to [0,1].
float linear_to_srgb(float v);
float srgb_to_linear(float v);
// 8-bit sRGB encoding with round-to-nearest, deterministic.
uint8_t linear_to_srgb8(float v);

// Read any image OpenImageIO can read, as float. 8/16-bit PNG/JPEG data in sRGB is converted to
// linear when `srgb_to_linear_8bit` is set (colour textures; the alpha channel stays linear);
// data images keep their values normalised to [0,1]. Alpha is returned as stored (straight, not
// premultiplied). EXR channels named c0..cN (see write_exr) come back in numeric order. Throws
// InputError naming the file if it is missing ("<path>: no such file") or unreadable
// ("<path>: cannot read image: <reason>"); with `reject_nonfinite`, a NaN or Inf texel is an
// InputError naming the file and the texel ("<path>: texel (x, y) channel c is NaN ...").
Image read_image(const std::string& path, bool srgb_to_linear_8bit = false, bool reject_nonfinite = true);

// Write an 8-bit sRGB PNG of the first 3 channels (or 1 channel as grey; 4 keeps alpha linear).
// 2 channels are written as grey + alpha, more than 4 as RGB of the first three. Values are
// clamped to [0,1], NaN writes 0. Atomic: written to "<path>.tmp-<pid>" in the same folder (created
// if missing), then renamed over `path`; on failure the temporary file is removed, an existing
// file at `path` is left untouched, and InputError names the path and the reason.
void write_png_srgb(const std::string& path, const Image& img);
// Write a 32-bit float EXR with all channels (named R,G,B[,A] for 3/4 channels, Y for 1,
// otherwise c0..cN), ZIP-compressed, no timestamp. Atomic like write_png_srgb. Deterministic bytes
// for identical input.
void write_exr(const std::string& path, const Image& img);
// Write raw 8-bit RGBA pixels (e.g. a GL read-back, already display-encoded) as PNG. Atomic.
void write_png_rgba8(const std::string& path, int width, int height, const uint8_t* rgba, bool flip_vertically);
// Write raw 8- or 16-bit (`bits`) pixels of 1 to 4 channels, interleaved, row 0 at the top, as a
// PNG of the values as stored (no encoding; a data image or one already encoded). Atomic.
void write_png_raw(const std::string& path, int width, int height, int channels, int bits, const void* pixels);
}  // namespace mesolab
