#include "gpu/gl.h"
#include "gpu/dispatch_timer.h"
#include "gpu/shaders.h"

#include <cmath>
#include <limits>

#include <dlfcn.h>
#include <epoxy/egl.h>

#include <algorithm>
#include <atomic>
#include <cstdio>
#include <cstring>
#include <filesystem>
// GCC 12 reports -Wmaybe-uninitialized inside libstdc++'s <regex> automaton (GCC bug 105562),
// not in this file's code.
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#endif
#include <regex>
#include <set>
#include <stdexcept>

namespace mesolab::gpu {

// [SECTION] Deleters for GlName
//
// A GlName may outlive its context (a member destroyed after the HeadlessContext, a window
// closed first). The objects are gone with the context then, and calling GL would be worse than
// useless: libepoxy resolves each entry point on its first call and abort()s when no context is
// current. So deleters do nothing unless an EGL or GLX context is current on this thread.
namespace {
bool gl_context_current() {
    if (eglGetCurrentContext() != EGL_NO_CONTEXT) return true;
    // GLX (GLFW on X11): only if libGLX/libGL is already loaded; never loads it.
    using GetCurrentContext = void* (*)();
    static std::atomic<GetCurrentContext> glx_get_current{nullptr};
    GetCurrentContext f = glx_get_current.load(std::memory_order_relaxed);
    if (!f) {
        for (const char* lib : {"libGLX.so.0", "libGL.so.1"}) {
            void* handle = dlopen(lib, RTLD_LAZY | RTLD_NOLOAD);
            if (!handle) continue;
            f = reinterpret_cast<GetCurrentContext>(dlsym(handle, "glXGetCurrentContext"));
            dlclose(handle);  // drops the reference RTLD_NOLOAD added; the library stays loaded
            if (f) break;
        }
        if (f) glx_get_current.store(f, std::memory_order_relaxed);
    }
    return f && f() != nullptr;
}
}  // namespace

Buffer make_storage_buffer(const void* data, size_t bytes, GLenum usage) {
    GLuint id = 0;
    glGenBuffers(1, &id);
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, id);
    glBufferData(GL_SHADER_STORAGE_BUFFER, GLsizeiptr(bytes), data, usage);
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, 0);
    return Buffer(id);
}

namespace {
// f(pointer) on storage buffer b's first `bytes`, mapped with `access`: the buffer unmapped and
// unbound again whatever f does. runtime_error naming `what` where the driver cannot map it, or
// where its storage was lost while mapped (`use`: "for writing" or "for reading"; `done`:
// "written" or "read").
void with_mapped_storage(GLuint b, size_t bytes, GLbitfield access, const std::string& what, const char* use, const char* done, const std::function<void(void*)>& f) {
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, b);
    void* p = glMapBufferRange(GL_SHADER_STORAGE_BUFFER, 0, GLsizeiptr(bytes), access);
    if (!p) {
        glBindBuffer(GL_SHADER_STORAGE_BUFFER, 0);
        check_gl(what.c_str());
        throw std::runtime_error(what + ": the driver could not map a buffer of " + std::to_string(bytes) + " bytes " + use);
    }
    try {
        f(p);
    } catch (...) {
        glUnmapBuffer(GL_SHADER_STORAGE_BUFFER);
        glBindBuffer(GL_SHADER_STORAGE_BUFFER, 0);
        throw;
    }
    const GLboolean intact = glUnmapBuffer(GL_SHADER_STORAGE_BUFFER);
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, 0);
    check_gl(what.c_str());
    if (!intact) throw std::runtime_error(what + ": a buffer's storage was lost while it was " + done + " (GL_FALSE from glUnmapBuffer)");
}
}  // namespace

Buffer make_storage_buffer_filled(size_t bytes, const std::function<void(void* dst)>& fill, const std::string& what, GLenum usage) {
    Buffer b = make_storage_buffer(nullptr, bytes, usage);
    if (bytes == 0) return b;
    with_mapped_storage(b.get(), bytes, GL_MAP_WRITE_BIT | GL_MAP_INVALIDATE_BUFFER_BIT, what, "for writing", "written", fill);
    return b;
}

void read_storage_buffer(GLuint b, size_t bytes, const std::function<void(const void* src)>& read, const std::string& what) {
    if (bytes == 0) return;
    with_mapped_storage(b, bytes, GL_MAP_READ_BIT, what, "for reading", "read", [&read](void* src) { read(src); });
}

Texture make_buffer_texture(const Buffer& b, GLenum format, GLintptr offset, GLsizeiptr bytes) {
    // Direct state access: no texture unit's binding changes.
    GLuint id = 0;
    glCreateTextures(GL_TEXTURE_BUFFER, 1, &id);
    if (offset == 0 && bytes == 0) glTextureBuffer(id, format, b.get());
    else glTextureBufferRange(id, format, b.get(), offset, bytes);
    return Texture(id);
}

// [SECTION] Textures
Texture make_texture(const TextureSpec& spec, const TexelData& level0) {
    if (spec.width < 1 || spec.height < 1 || spec.layers < 1 || spec.levels < 1)
        throw std::invalid_argument("make_texture: size " + std::to_string(spec.width) + "x" + std::to_string(spec.height) + "x" +
                                    std::to_string(spec.layers) + " with " + std::to_string(spec.levels) + " levels");
    GLuint id = 0;
    glCreateTextures(spec.target, 1, &id);
    Texture t(id);
    if (spec.target == GL_TEXTURE_2D_ARRAY) glTextureStorage3D(id, spec.levels, spec.format, spec.width, spec.height, spec.layers);
    else glTextureStorage2D(id, spec.levels, spec.format, spec.width, spec.height);
    glTextureParameteri(id, GL_TEXTURE_MIN_FILTER, GLint(spec.min_filter));
    glTextureParameteri(id, GL_TEXTURE_MAG_FILTER, GLint(spec.mag_filter));
    glTextureParameteri(id, GL_TEXTURE_WRAP_S, GLint(spec.wrap_s));
    glTextureParameteri(id, GL_TEXTURE_WRAP_T, GLint(spec.wrap_t));
    if (level0.pixels) upload_texture(t, spec, 0, level0);
    check_gl("make_texture");
    return t;
}

void upload_texture(const Texture& t, const TextureSpec& spec, int level, const TexelData& texels) {
    GLint unpack_buffer = 0, alignment = 4;
    glGetIntegerv(GL_PIXEL_UNPACK_BUFFER_BINDING, &unpack_buffer);
    glGetIntegerv(GL_UNPACK_ALIGNMENT, &alignment);
    if (unpack_buffer) glBindBuffer(GL_PIXEL_UNPACK_BUFFER, 0);
    glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
    const int w = std::max(1, spec.width >> level), h = std::max(1, spec.height >> level);
    if (spec.target == GL_TEXTURE_2D_ARRAY)
        glTextureSubImage3D(t.get(), level, 0, 0, 0, w, h, spec.layers, texels.format, texels.type, texels.pixels);
    else
        glTextureSubImage2D(t.get(), level, 0, 0, w, h, texels.format, texels.type, texels.pixels);
    glPixelStorei(GL_UNPACK_ALIGNMENT, alignment);
    if (unpack_buffer) glBindBuffer(GL_PIXEL_UNPACK_BUFFER, GLuint(unpack_buffer));
}

void delete_buffer(GLuint id) { if (gl_context_current()) glDeleteBuffers(1, &id); }
void delete_texture(GLuint id) { if (gl_context_current()) glDeleteTextures(1, &id); }
void delete_framebuffer(GLuint id) { if (gl_context_current()) glDeleteFramebuffers(1, &id); }
void delete_vertex_array(GLuint id) { if (gl_context_current()) glDeleteVertexArrays(1, &id); }
void delete_program(GLuint id) { if (gl_context_current()) glDeleteProgram(id); }
void delete_query(GLuint id) { if (gl_context_current()) glDeleteQueries(1, &id); }

// [SECTION] Errors
namespace {
const char* gl_error_name(GLenum e) {
    switch (e) {
    case GL_INVALID_ENUM: return "GL_INVALID_ENUM";
    case GL_INVALID_VALUE: return "GL_INVALID_VALUE";
    case GL_INVALID_OPERATION: return "GL_INVALID_OPERATION";
    case GL_INVALID_FRAMEBUFFER_OPERATION: return "GL_INVALID_FRAMEBUFFER_OPERATION";
    case GL_OUT_OF_MEMORY: return "GL_OUT_OF_MEMORY";
    case GL_STACK_UNDERFLOW: return "GL_STACK_UNDERFLOW";
    case GL_STACK_OVERFLOW: return "GL_STACK_OVERFLOW";
    default: return "unknown GL error";
    }
}

std::string hex(GLenum e) {
    char buf[16];
    std::snprintf(buf, sizeof buf, "0x%04x", unsigned(e));
    return buf;
}
}  // namespace

void check_gl(const char* where) {
    std::string errors;
    for (int i = 0; i < 16; ++i) {  // bounded: a lost context can report errors forever
        const GLenum e = glGetError();
        if (e == GL_NO_ERROR) break;
        errors += (errors.empty() ? "" : ", ") + std::string(gl_error_name(e)) + " (" + hex(e) + ")";
    }
    if (!errors.empty()) throw std::runtime_error(std::string("OpenGL error in ") + where + ": " + errors);
}

// [SECTION] Shader source assembly: #include resolution, defines, #line
namespace {

bool has_shader(const std::string& name) {
    static const std::vector<std::string> names = [] {
        auto n = shader_names();
        std::sort(n.begin(), n.end());
        return n;
    }();
    return std::binary_search(names.begin(), names.end(), name);
}

std::string normalise(const std::filesystem::path& p) { return p.lexically_normal().generic_string(); }

// Embedded name for `#include "target"` inside `from`: first beside `from`, then under shaders/.
std::string resolve_include(const std::string& from, const std::string& target) {
    const std::filesystem::path dir = std::filesystem::path(from).parent_path();
    for (const std::string& candidate : {normalise(dir / target), normalise(std::filesystem::path("shaders") / target)})
        if (has_shader(candidate)) return candidate;
    return {};
}

// `#include "x"` -> x, or empty when the line is not an include.
std::string include_target(const std::string& line) {
    static const std::regex re(R"(^\s*#\s*include\s*"([^"]+)\"\s*(//.*)?$)");
    std::smatch m;
    return std::regex_match(line, m, re) ? m[1].str() : std::string();
}

bool is_version_line(const std::string& line) {
    static const std::regex re(R"(^\s*#\s*version\b.*$)");
    return std::regex_match(line, re);
}

// Source strings of one shader stage. Each file gets a GLSL source-string number (its index in
// `files`) that `#line` directives use, so driver logs can be mapped back to file names.
struct Assembler {
    std::vector<std::string> files;
    std::set<std::string> included;
    std::string out;

    int file_index(const std::string& name) {
        files.push_back(name);
        return int(files.size()) - 1;
    }

    void append(const std::string& name, const std::vector<std::string>& defines, bool top_level, const std::string& prelude = "") {
        const int index = file_index(name);
        included.insert(name);
        const std::string_view src = shader_source(name);
        if (!top_level) out += "#line 1 " + std::to_string(index) + "\n";

        bool saw_version = false;
        size_t pos = 0;
        int line_no = 0;
        while (pos < src.size()) {
            size_t end = src.find('\n', pos);
            if (end == std::string_view::npos) end = src.size();
            std::string line(src.substr(pos, end - pos));
            if (!line.empty() && line.back() == '\r') line.pop_back();
            pos = end + 1;
            ++line_no;

            if (top_level && !saw_version && is_version_line(line)) {
                saw_version = true;
                out += line + "\n";
                for (const std::string& d : defines) out += "#define " + define_text(d) + "\n";
                out += prelude;
                if (!prelude.empty() && prelude.back() != '\n') out += "\n";
                out += "#line " + std::to_string(line_no + 1) + " " + std::to_string(index) + "\n";
                continue;
            }
            const std::string target = include_target(line);
            if (target.empty()) {
                out += line + "\n";
                continue;
            }
            const std::string resolved = resolve_include(name, target);
            if (resolved.empty())
                throw std::runtime_error(name + ":" + std::to_string(line_no) + ": cannot find #include \"" + target +
                                         "\" (looked beside the file and under shaders/)");
            if (included.count(resolved)) {
                out += "// (already included: " + resolved + ")\n";
                continue;
            }
            append(resolved, {}, false);
            out += "#line " + std::to_string(line_no + 1) + " " + std::to_string(index) + "\n";
        }
        if (top_level && !saw_version)
            throw std::runtime_error(name + ": no #version line (needed before defines can be inserted)");
    }

    // "NAME VALUE" stays as is; "NAME=VALUE" becomes "NAME VALUE".
    static std::string define_text(std::string d) {
        const auto eq = d.find('=');
        if (eq != std::string::npos && d.find_first_of(" \t") > eq) d[eq] = ' ';
        return d;
    }

    // Rewrites "N:L(C)" (Mesa) and "N(L)" (NVIDIA) log prefixes into "file:L".
    std::string annotate_log(const std::string& log) const {
        static const std::regex re(R"((^|\n)(\d+)(?::(\d+)\((\d+)\)|\((\d+)\)))");
        std::string result;
        auto begin = log.cbegin();
        std::smatch m;
        while (std::regex_search(begin, log.cend(), m, re)) {
            result.append(begin, m[0].first);
            const size_t idx = std::stoul(m[2].str());
            if (idx < files.size()) {
                result += m[1].str() + files[idx] + ":" + (m[3].matched ? m[3].str() + ":" + m[4].str() : m[5].str());
            } else {
                result += m[0].str();
            }
            begin = m[0].second;
        }
        result.append(begin, log.cend());
        return result;
    }
};

std::string shader_log(GLuint shader) {
    GLint len = 0;
    glGetShaderiv(shader, GL_INFO_LOG_LENGTH, &len);
    std::string log(size_t(std::max(len, 1)), '\0');
    glGetShaderInfoLog(shader, GLsizei(log.size()), nullptr, log.data());
    log.resize(std::strlen(log.c_str()));
    return log;
}

std::string program_log(GLuint program) {
    GLint len = 0;
    glGetProgramiv(program, GL_INFO_LOG_LENGTH, &len);
    std::string log(size_t(std::max(len, 1)), '\0');
    glGetProgramInfoLog(program, GLsizei(log.size()), nullptr, log.data());
    log.resize(std::strlen(log.c_str()));
    return log;
}

// Compiles one stage; the returned shader object must be deleted by the caller.
GLuint compile(GLenum stage, const std::string& name, const std::vector<std::string>& defines, const std::string& prelude = "") {
    Assembler a;
    a.append(name, defines, true, prelude);
    const GLuint shader = glCreateShader(stage);
    if (!shader) throw std::runtime_error(name + ": glCreateShader failed (is a GL context current?)");
    const char* text = a.out.c_str();
    glShaderSource(shader, 1, &text, nullptr);
    glCompileShader(shader);
    GLint ok = GL_FALSE;
    glGetShaderiv(shader, GL_COMPILE_STATUS, &ok);
    if (!ok) {
        const std::string log = a.annotate_log(shader_log(shader));
        glDeleteShader(shader);
        std::string files;
        for (size_t i = 0; i < a.files.size(); ++i) files += (i ? ", " : "") + std::to_string(i) + " = " + a.files[i];
        throw std::runtime_error("failed to compile shader " + name + " (source strings: " + files + "):\n" + log);
    }
    return shader;
}

// Links and deletes `shaders`.
GlName<delete_program> link(const std::vector<GLuint>& shaders, const std::string& what) {
    GlName<delete_program> id(glCreateProgram());
    for (GLuint s : shaders) glAttachShader(id.get(), s);
    glLinkProgram(id.get());
    for (GLuint s : shaders) {
        glDetachShader(id.get(), s);
        glDeleteShader(s);
    }
    GLint ok = GL_FALSE;
    glGetProgramiv(id.get(), GL_LINK_STATUS, &ok);
    if (!ok) throw std::runtime_error("failed to link program " + what + ":\n" + program_log(id.get()));
    return id;
}
}  // namespace

// [SECTION] Program
Program Program::graphics(const std::string& vert, const std::string& frag, const std::vector<std::string>& defines, const std::string& frag_prelude) {
    const GLuint vs = compile(GL_VERTEX_SHADER, vert, defines);
    GLuint fs = 0;
    try {
        fs = compile(GL_FRAGMENT_SHADER, frag, defines, frag_prelude);
    } catch (...) {
        glDeleteShader(vs);
        throw;
    }
    Program p;
    p.id_ = link({vs, fs}, vert + " + " + frag);
    return p;
}

Program Program::compute(const std::string& comp, const std::vector<std::string>& defines, const std::string& prelude) {
    Program p;
    p.id_ = link({compile(GL_COMPUTE_SHADER, comp, defines, prelude)}, comp);
    return p;
}

// [SECTION] RenderTarget
void RenderTarget::resize(int width, int height, int color_attachments) {
    if (width <= 0 || height <= 0)
        throw std::invalid_argument("RenderTarget::resize: size must be positive, got " + std::to_string(width) + "x" +
                                    std::to_string(height));
    GLint max_attachments = 0;
    glGetIntegerv(GL_MAX_COLOR_ATTACHMENTS, &max_attachments);
    if (color_attachments < 0 || color_attachments > max_attachments)
        throw std::invalid_argument("RenderTarget::resize: " + std::to_string(color_attachments) +
                                    " colour attachments (this GL allows 0.." + std::to_string(max_attachments) + ")");
    if (fbo_ && width == width_ && height == height_ && color_attachments == attachments()) return;

    GLint old_fbo = 0;
    glGetIntegerv(GL_FRAMEBUFFER_BINDING, &old_fbo);

    const auto attachment = [&](GLenum format) { return make_texture({.format = format, .width = width, .height = height}); };

    GLuint fbo = 0;
    glGenFramebuffers(1, &fbo);
    Framebuffer new_fbo(fbo);
    glBindFramebuffer(GL_FRAMEBUFFER, fbo);
    std::vector<Texture> new_color;
    for (int i = 0; i < color_attachments; ++i) {
        new_color.push_back(attachment(GL_RGBA32F));
        glFramebufferTexture2D(GL_FRAMEBUFFER, GLenum(GL_COLOR_ATTACHMENT0 + i), GL_TEXTURE_2D, new_color.back().get(), 0);
    }
    Texture new_depth = attachment(GL_DEPTH_COMPONENT32F);
    glFramebufferTexture2D(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_TEXTURE_2D, new_depth.get(), 0);
    std::vector<GLenum> buffers;
    for (int i = 0; i < color_attachments; ++i) buffers.push_back(GLenum(GL_COLOR_ATTACHMENT0 + i));
    if (buffers.empty()) {
        glDrawBuffer(GL_NONE);
        glReadBuffer(GL_NONE);
    } else {
        glDrawBuffers(GLsizei(buffers.size()), buffers.data());
    }
    const GLenum status = glCheckFramebufferStatus(GL_FRAMEBUFFER);

    glBindFramebuffer(GL_FRAMEBUFFER, GLuint(old_fbo));
    check_gl("RenderTarget::resize");
    if (status != GL_FRAMEBUFFER_COMPLETE)
        throw std::runtime_error("RenderTarget::resize: framebuffer incomplete (status " + hex(status) + ")");

    // Commit only once everything succeeded; the old objects are deleted here.
    fbo_ = std::move(new_fbo);
    color_ = std::move(new_color);
    depth_ = std::move(new_depth);
    width_ = width;
    height_ = height;
}

void RenderTarget::bind() const {
    glBindFramebuffer(GL_FRAMEBUFFER, fbo_.get());
    glViewport(0, 0, width_, height_);
    if (!fbo_) return;
    GLenum buffers[32];
    const int n = std::min(attachments(), 32);
    for (int i = 0; i < n; ++i) buffers[i] = GLenum(GL_COLOR_ATTACHMENT0 + i);
    if (n > 0) glDrawBuffers(n, buffers);
}

std::vector<float> RenderTarget::read_rgba(int i) const {
    if (i < 0 || i >= attachments())
        throw std::out_of_range("RenderTarget::read_rgba: attachment " + std::to_string(i) + " of " +
                                std::to_string(attachments()));
    GLint old_read_fbo = 0, old_pack_buffer = 0, old_alignment = 4;
    glGetIntegerv(GL_READ_FRAMEBUFFER_BINDING, &old_read_fbo);
    glGetIntegerv(GL_PIXEL_PACK_BUFFER_BINDING, &old_pack_buffer);
    glGetIntegerv(GL_PACK_ALIGNMENT, &old_alignment);

    glBindFramebuffer(GL_READ_FRAMEBUFFER, fbo_.get());
    glBindBuffer(GL_PIXEL_PACK_BUFFER, 0);
    glReadBuffer(GLenum(GL_COLOR_ATTACHMENT0 + i));
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    const size_t row = size_t(width_) * 4;
    std::vector<float> pixels(row * size_t(height_));
    glReadPixels(0, 0, width_, height_, GL_RGBA, GL_FLOAT, pixels.data());

    glPixelStorei(GL_PACK_ALIGNMENT, old_alignment);
    glBindBuffer(GL_PIXEL_PACK_BUFFER, GLuint(old_pack_buffer));
    glBindFramebuffer(GL_READ_FRAMEBUFFER, GLuint(old_read_fbo));
    check_gl("RenderTarget::read_rgba");

    // GL returns the bottom row first; swap rows so that row 0 is the top.
    for (int y = 0; y < height_ / 2; ++y)
        std::swap_ranges(pixels.begin() + std::ptrdiff_t(size_t(y) * row), pixels.begin() + std::ptrdiff_t(size_t(y + 1) * row),
                         pixels.begin() + std::ptrdiff_t(size_t(height_ - 1 - y) * row));
    return pixels;
}

// [SECTION] GpuTimeline
void GpuTimeline::begin() {
    if (in_range_) throw std::logic_error("GpuTimeline::begin: the previous range is still open (ranges do not nest)");
    in_range_ = true;
    if (software_) glFinish();  // what came before is not this range's
    wall0_ = std::chrono::steady_clock::now();
    if (software_) return;
    if (!spare_.empty()) {
        current_ = std::move(spare_.back());
        spare_.pop_back();
    } else {
        GLuint id = 0;
        glGenQueries(1, &id);
        current_ = Query(id);
    }
    glBeginQuery(GL_TIME_ELAPSED, current_.get());
}

void GpuTimeline::end(Done done) {
    if (!in_range_) throw std::logic_error("GpuTimeline::end: no range is open");
    in_range_ = false;
    if (software_) {
        glFinish();
        const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - wall0_).count();
        if (done) done(ms);
        return;
    }
    glEndQuery(GL_TIME_ELAPSED);
    open_.push_back(Range{std::move(current_), wall0_, std::move(done)});
}

void GpuTimeline::abandon() {
    if (!in_range_) return;
    in_range_ = false;
    if (software_) return;
    glEndQuery(GL_TIME_ELAPSED);
    spare_.push_back(std::move(current_));  // its answer is never read; the object is reused
}

void GpuTimeline::take(Range& r) {
    GLuint64 ns = 0;
    glGetQueryObjectui64v(r.query.get(), GL_QUERY_RESULT, &ns);
    const double wall_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - r.wall0).count();
    const double gpu_ms = double(ns) * 1e-6;
    spare_.push_back(std::move(r.query));
    if (r.done) r.done(plausible(gpu_ms, wall_ms) ? gpu_ms : std::numeric_limits<double>::quiet_NaN());
}

void GpuTimeline::poll() {
    // Queries finish in order: stop at the first that is not ready.
    while (!open_.empty()) {
        GLint ready = 0;
        glGetQueryObjectiv(open_.front().query.get(), GL_QUERY_RESULT_AVAILABLE, &ready);
        if (!ready) return;
        Range r = std::move(open_.front());
        open_.pop_front();
        take(r);
    }
}

void GpuTimeline::wait() {
    while (!open_.empty()) {
        Range r = std::move(open_.front());
        open_.pop_front();
        take(r);
    }
}

bool is_software_renderer(const std::string& gl_renderer) {
    for (const char* name : {"llvmpipe", "softpipe", "SwiftShader", "swrast"})
        if (gl_renderer.find(name) != std::string::npos) return true;
    return false;
}

bool current_renderer_is_software() {
    const GLubyte* name = glGetString(GL_RENDERER);
    return is_software_renderer(name ? reinterpret_cast<const char*>(name) : "");
}

namespace {
std::atomic<GpuTuning> g_tuning{GpuTuning::Automatic};
}
void set_gpu_tuning(GpuTuning t) { g_tuning = t; }
bool tuned_for_hardware() {
    const GpuTuning t = g_tuning;
    return t == GpuTuning::Automatic ? !current_renderer_is_software() : t == GpuTuning::Hardware;
}

void wait_for_gpu() {
    GLsync fence = glFenceSync(GL_SYNC_GPU_COMMANDS_COMPLETE, 0);
    if (!fence) {
        glFinish();
        return;
    }
    GLbitfield flags = GL_SYNC_FLUSH_COMMANDS_BIT;
    for (;;) {
        const GLenum r = glClientWaitSync(fence, flags, GLuint64(1000000000));  // 1 s per try
        if (r == GL_ALREADY_SIGNALED || r == GL_CONDITION_SATISFIED || r == GL_WAIT_FAILED) break;
        flags = 0;  // flushed once
    }
    glDeleteSync(fence);
}

// [SECTION] DispatchTimer

DispatchTimer::DispatchTimer(const std::string& name)
    : timeline_(current_renderer_is_software()),
      path_((ProfileScope::current_path().empty() ? "" : ProfileScope::current_path() + "/") + name + "/gpu"),
      profiler_(&Profiler::current()) {}

DispatchTimer::~DispatchTimer() {
    if (timeline_.open() > 0) {
        try {
            timeline_.wait();
        } catch (...) {
        }
    }
    timeline_.abandon();
}

void DispatchTimer::end() {
    timeline_.end([path = path_, profiler = profiler_](double ms) {
        if (std::isfinite(ms)) profiler->record(path, ms, Device::Gpu);
    });
}
}  // namespace mesolab::gpu
