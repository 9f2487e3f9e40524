// Image I/O through OpenImageIO: float reading with optional sRGB decoding, atomic PNG/EXR writing.
#include "core/image.h"

#include "core/error.h"
#include "core/file.h"

#include <OpenImageIO/imageio.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <mutex>
#include <numeric>
#include <system_error>

namespace fs = std::filesystem;

namespace mesolab {

// sRGB transfer function (IEC 61966-2-1)
float linear_to_srgb(float v) {
    if (!(v > 0.f)) return 0.f;  // also maps NaN to 0
    if (v >= 1.f) return 1.f;
    const double d = v;
    return float(d <= 0.0031308 ? 12.92 * d : 1.055 * std::pow(d, 1.0 / 2.4) - 0.055);
}

float srgb_to_linear(float v) {
    if (!(v > 0.f)) return 0.f;
    if (v >= 1.f) return 1.f;
    const double d = v;
    return float(d <= 0.04045 ? d / 12.92 : std::pow((d + 0.055) / 1.055, 2.4));
}

uint8_t linear_to_srgb8(float v) {
    return uint8_t(std::lround(double(linear_to_srgb(v)) * 255.0));
}

static uint8_t unit_to_8(float v) {  // linear [0,1] -> [0,255], round to nearest, NaN -> 0
    if (!(v > 0.f)) return 0;
    if (v >= 1.f) return 255;
    return uint8_t(std::lround(double(v) * 255.0));
}

// Reading
static bool integer_format(OIIO::TypeDesc t) {
    const auto b = OIIO::TypeDesc::BASETYPE(t.basetype);
    return b == OIIO::TypeDesc::UINT8 || b == OIIO::TypeDesc::INT8 || b == OIIO::TypeDesc::UINT16 ||
           b == OIIO::TypeDesc::INT16 || b == OIIO::TypeDesc::UINT32 || b == OIIO::TypeDesc::INT32;
}

// Channels named c0, c1, ..., c10, ... (as written by write_exr) come back from OpenEXR in
// alphabetical order; returns the permutation that restores numeric order, or empty if the names
// are not all of that form.
static std::vector<int> numeric_channel_order(const std::vector<std::string>& names) {
    std::vector<long> index;
    for (const std::string& n : names) {
        if (n.size() < 2 || n.size() > 6 || n[0] != 'c') return {};
        if (!std::all_of(n.begin() + 1, n.end(), [](char ch) { return ch >= '0' && ch <= '9'; })) return {};
        index.push_back(std::strtol(n.c_str() + 1, nullptr, 10));
    }
    std::vector<int> order(names.size());
    std::iota(order.begin(), order.end(), 0);
    std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return index[a] < index[b]; });
    for (size_t i = 0; i < order.size(); ++i)
        if (order[i] != int(i)) return order;
    return {};  // already in order
}

Image read_image(const std::string& path, bool srgb_to_linear_8bit, bool reject_nonfinite) {
    std::error_code ec;
    if (!fs::exists(path, ec) && !ec) throw InputError(path + ": no such file");  // (other errors: OIIO reports)
    OIIO::ImageSpec config;
    config.attribute("oiio:UnassociatedAlpha", 1);  // keep straight alpha as stored (no premultiplication)
    auto in = OIIO::ImageInput::open(path, &config);
    if (!in) {
        std::string err = OIIO::geterror();
        if (err.empty()) err = "unknown format";
        throw InputError(path + ": cannot read image: " + err);
    }
    const OIIO::ImageSpec spec = in->spec();
    if (spec.width <= 0 || spec.height <= 0 || spec.nchannels <= 0 || spec.depth > 1 || spec.deep)
        throw InputError(path + ": cannot read image: unsupported layout (expected a flat 2D image)");

    Image img(spec.width, spec.height, spec.nchannels);
    if (!in->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::FLOAT, img.data.data())) {
        std::string err = in->geterror();
        if (err.empty()) err = OIIO::geterror();
        throw InputError(path + ": cannot read image: " + err);
    }
    in->close();

    if (std::vector<int> order = numeric_channel_order(spec.channelnames); !order.empty()) {
        const size_t c = size_t(img.channels);
        std::vector<float> px(c);
        for (size_t i = 0; i < img.data.size(); i += c) {
            for (size_t k = 0; k < c; ++k) px[k] = img.data[i + size_t(order[k])];
            std::copy(px.begin(), px.end(), img.data.begin() + long(i));
        }
    }

    if (reject_nonfinite) {
        const size_t c = size_t(img.channels);
        for (size_t i = 0; i < img.data.size(); ++i) {
            const float v = img.data[i];
            if (std::isfinite(v)) continue;
            const size_t p = i / c;
            throw InputError(path + ": texel (" + std::to_string(p % size_t(img.width)) + ", " +
                             std::to_string(p / size_t(img.width)) + ") channel " + std::to_string(i % c) +
                             " is " + (std::isnan(v) ? "NaN" : (v > 0 ? "+Inf" : "-Inf")) +
                             " (finite values expected)");
        }
    }

    if (srgb_to_linear_8bit && integer_format(spec.format)) {
        const int alpha = spec.alpha_channel;
        for (size_t i = 0; i < img.data.size(); ++i)
            if (int(i % size_t(img.channels)) != alpha) img.data[i] = srgb_to_linear(img.data[i]);
    }
    return img;
}

// ImageOutput::open with OIIO's debug messages off (Debian's build prints them by default, and
// the EXR writer would report the dropped int "DateTime" on every save); serialised so that the
// saved level is always restored.
static bool open_quietly(OIIO::ImageOutput& out, const std::string& file, const OIIO::ImageSpec& spec) {
    static std::mutex mutex;
    std::lock_guard<std::mutex> lock(mutex);
    int level = 0;
    OIIO::getattribute("debug", level);
    OIIO::attribute("debug", 0);
    const bool ok = out.open(file, spec);
    OIIO::attribute("debug", level);
    return ok;
}

// Writes an interleaved buffer of `spec.format` with the OIIO plugin `format`; returns an error or "".
static std::string write_oiio(const std::string& file, const char* format, const OIIO::ImageSpec& spec,
                              const void* pixels) {
    auto out = OIIO::ImageOutput::create(format);
    if (!out) {
        const std::string e = OIIO::geterror();
        return e.empty() ? std::string("no ") + format + " writer" : e;
    }
    if (!open_quietly(*out, file, spec)) return out->geterror();
    bool ok = out->write_image(spec.format, pixels);
    ok = out->close() && ok;
    return ok ? std::string() : out->geterror();
}

static void check_size(const std::string& path, int w, int h, int c) {
    if (w <= 0 || h <= 0 || c <= 0)
        throw InputError(path + ": cannot write image: empty image (" + std::to_string(w) + "x" +
                         std::to_string(h) + "x" + std::to_string(c) + ")");
}

// PNG and EXR writers
void write_png_srgb(const std::string& path, const Image& img) {
    check_size(path, img.width, img.height, img.channels);
    if (img.data.size() != size_t(img.width) * size_t(img.height) * size_t(img.channels))
        throw InputError(path + ": cannot write image: pixel buffer size does not match the image size");
    // 1 -> grey, 2 -> grey + alpha, 3 -> RGB, 4 -> RGBA, more -> RGB of the first three.
    const int in_c = img.channels;
    const int out_c = in_c > 4 ? 3 : in_c;
    const bool has_alpha = out_c == 2 || out_c == 4;
    const size_t n = size_t(img.width) * size_t(img.height);
    std::vector<uint8_t> px(n * size_t(out_c));
    for (size_t i = 0; i < n; ++i)
        for (int k = 0; k < out_c; ++k) {
            const float v = img.data[i * size_t(in_c) + size_t(k)];
            px[i * size_t(out_c) + size_t(k)] = (has_alpha && k == out_c - 1) ? unit_to_8(v) : linear_to_srgb8(v);
        }
    OIIO::ImageSpec spec(img.width, img.height, out_c, OIIO::TypeDesc::UINT8);
    if (has_alpha) {
        spec.alpha_channel = out_c - 1;
        spec.attribute("oiio:UnassociatedAlpha", 1);  // straight alpha: write the values as given
    }
    spec.attribute("oiio:ColorSpace", "sRGB");
    write_file_atomic(path, "image", [&](const std::string& tmp) { return write_oiio(tmp, "png", spec, px.data()); });
}

void write_exr(const std::string& path, const Image& img) {
    check_size(path, img.width, img.height, img.channels);
    if (img.data.size() != size_t(img.width) * size_t(img.height) * size_t(img.channels))
        throw InputError(path + ": cannot write image: pixel buffer size does not match the image size");
    OIIO::ImageSpec spec(img.width, img.height, img.channels, OIIO::TypeDesc::FLOAT);
    spec.channelnames.clear();
    if (img.channels == 1) {
        spec.channelnames = {"Y"};
    } else if (img.channels == 3 || img.channels == 4) {
        spec.channelnames = {"R", "G", "B"};
        if (img.channels == 4) spec.channelnames.push_back("A");
    } else {
        for (int k = 0; k < img.channels; ++k) {
            std::string name(1, 'c');  // (not "c" + ...: GCC 12 warns falsely with -Wrestrict)
            name += std::to_string(k);
            spec.channelnames.push_back(name);
        }
    }
    spec.alpha_channel = img.channels == 4 ? 3 : -1;
    spec.attribute("compression", "zip");
    // OIIO's EXR writer stamps the current time as "capDate" unless a "DateTime" attribute is
    // present; an int-typed one suppresses the stamp and is then dropped as the wrong type for
    // capDate (a string): no timestamp, so identical images give identical bytes.
    spec.attribute("DateTime", 0);
    write_file_atomic(path, "image", [&](const std::string& tmp) { return write_oiio(tmp, "openexr", spec, img.data.data()); });
}

void write_png_rgba8(const std::string& path, int width, int height, const uint8_t* rgba, bool flip_vertically) {
    check_size(path, width, height, 4);
    if (!rgba) throw InputError(path + ": cannot write image: no pixel data");
    const size_t row = size_t(width) * 4;
    std::vector<uint8_t> px(row * size_t(height));
    for (int y = 0; y < height; ++y) {
        const int src = flip_vertically ? height - 1 - y : y;
        std::copy_n(rgba + size_t(src) * row, row, px.data() + size_t(y) * row);
    }
    OIIO::ImageSpec spec(width, height, 4, OIIO::TypeDesc::UINT8);
    spec.alpha_channel = 3;
    spec.attribute("oiio:UnassociatedAlpha", 1);
    spec.attribute("oiio:ColorSpace", "sRGB");
    write_file_atomic(path, "image", [&](const std::string& tmp) { return write_oiio(tmp, "png", spec, px.data()); });
}

void write_png_raw(const std::string& path, int width, int height, int channels, int bits, const void* pixels) {
    check_size(path, width, height, channels);
    if (channels > 4) throw InputError(path + ": cannot write image: " + std::to_string(channels) + " channels (a PNG holds 1 to 4)");
    if (bits != 8 && bits != 16) throw InputError(path + ": cannot write image: " + std::to_string(bits) + " bits a channel (a PNG holds 8 or 16)");
    if (!pixels) throw InputError(path + ": cannot write image: no pixel data");
    const OIIO::ImageSpec spec(width, height, channels, bits == 8 ? OIIO::TypeDesc::UINT8 : OIIO::TypeDesc::UINT16);
    write_file_atomic(path, "image", [&](const std::string& tmp) { return write_oiio(tmp, "png", spec, pixels); });
}
}  // namespace mesolab
