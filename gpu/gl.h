#pragma once
// Thin RAII wrappers over OpenGL 4.3+ core objects, and shader programs built from the .glsl
// files embedded into the binary at build time (see shaders.h).
#include <epoxy/gl.h>

#include <chrono>
#include <cstdint>
#include <deque>
#include <functional>
#include <string>
#include <vector>

namespace mesolab::gpu {

// Move-only owner of one GL name.
template <void (*Delete)(GLuint)>
class GlName {
public:
    GlName() = default;
    explicit GlName(GLuint id) : id_(id) {}
    ~GlName() { reset(); }
    GlName(GlName&& o) noexcept : id_(o.id_) { o.id_ = 0; }
    GlName& operator=(GlName&& o) noexcept { if (this != &o) { reset(); id_ = o.id_; o.id_ = 0; } return *this; }
    GlName(const GlName&) = delete;
    GlName& operator=(const GlName&) = delete;
    GLuint get() const { return id_; }
    explicit operator bool() const { return id_ != 0; }
    void reset() { if (id_) Delete(id_); id_ = 0; }
private:
    GLuint id_ = 0;
};
void delete_buffer(GLuint);
void delete_texture(GLuint);
void delete_framebuffer(GLuint);
void delete_vertex_array(GLuint);
void delete_program(GLuint);
void delete_query(GLuint);
using Buffer = GlName<delete_buffer>;
using Texture = GlName<delete_texture>;
using Framebuffer = GlName<delete_framebuffer>;
using VertexArray = GlName<delete_vertex_array>;
using Query = GlName<delete_query>;

// A new shader storage buffer holding `bytes` (data may be null); leaves GL_SHADER_STORAGE_BUFFER unbound.
Buffer make_storage_buffer(const void* data, size_t bytes, GLenum usage = GL_STATIC_DRAW);
// A new shader storage buffer of `bytes`, written in place by fill(dst) through a write mapping:
// no host copy of the data is made first (for tens of MB, a fresh copy's page faults cost more
// than the writes), and fill may use every core. Mapped ranges over host memory on a discrete GPU
// are written sequentially, as fill should. Throws std::runtime_error naming `what` when the
// driver cannot map the buffer or loses its contents.
Buffer make_storage_buffer_filled(size_t bytes, const std::function<void(void* dst)>& fill, const std::string& what, GLenum usage = GL_STATIC_DRAW);
// The first `bytes` of buffer b, given to read(src) through a read mapping (waits for the GPU's
// writes to it); read may use every core. Throws like make_storage_buffer_filled.
void read_storage_buffer(GLuint b, size_t bytes, const std::function<void(const void* src)>& read, const std::string& what);

// A buffer texture (GL_TEXTURE_BUFFER, read with texelFetch) over `bytes` of `b` from `offset`
// (all of it when bytes is 0), whose texels have `format` (GL_RGBA32F, GL_RG32UI, ...). Shaders
// read their big read-only tables through these: on llvmpipe a texel fetch gathers all lanes at
// once, where a storage-buffer read goes lane by lane, component by component (about twice as fast).
Texture make_buffer_texture(const Buffer& b, GLenum format, GLintptr offset = 0, GLsizeiptr bytes = 0);

// [SECTION] Textures
// What a texture is made of: target, sized format, size, mip levels and sampling. make_texture
// creates it with immutable storage through direct state access, so no texture unit's binding
// changes: a texture made while a pass binds its inputs (a stage result uploaded on first use)
// can never unbind one of them.
struct TextureSpec {
    GLenum target = GL_TEXTURE_2D;   // GL_TEXTURE_2D or GL_TEXTURE_2D_ARRAY
    GLenum format = GL_RGBA32F;      // sized internal format: GL_RGBA32F, GL_RG32F, GL_R32UI, GL_DEPTH_COMPONENT32F, ...
    int width = 1, height = 1;
    int layers = 1;                  // GL_TEXTURE_2D_ARRAY only
    int levels = 1;                  // mip levels, level l is max(1, width >> l) x max(1, height >> l)
    GLenum min_filter = GL_NEAREST, mag_filter = GL_NEAREST;
    GLenum wrap_s = GL_CLAMP_TO_EDGE, wrap_t = GL_CLAMP_TO_EDGE;
};
// Texels of one mip level (every layer), rows tightly packed, first row at t = 0, as
// glTexSubImage reads them: `format` and `type` say how (GL_RGBA and GL_FLOAT, GL_RED_INTEGER and
// GL_UNSIGNED_INT, ...).
struct TexelData {
    GLenum format = GL_RGBA;
    GLenum type = GL_FLOAT;
    const void* pixels = nullptr;
};
// A new texture; `level0`, when given, fills level 0. Throws std::runtime_error on a GL error.
Texture make_texture(const TextureSpec& spec, const TexelData& level0 = {});
// Fills mip level `level` of a texture made from `spec` (client memory: whatever pixel-unpack
// buffer is bound is set aside for the call, and the unpack alignment is 1).
void upload_texture(const Texture& t, const TextureSpec& spec, int level, const TexelData& texels);

// A linked program. Sources are looked up by embedded name (e.g. "basic/basic.frag"); a line
// `#include "common.glsl"` is replaced by the embedded file of that name (recursively, once).
// `defines` lines ("NAME VALUE") are inserted after #version, then the fragment shader's
// `frag_prelude` (generated declarations, e.g. fragment_outputs()) or the compute shader's
// `prelude` (GLSL of the caller's own, ahead of the file's). Compile/link errors throw
// std::runtime_error with the file name and the driver's log.
class Program {
public:
    Program() = default;
    static Program graphics(const std::string& vert, const std::string& frag, const std::vector<std::string>& defines = {},
                            const std::string& frag_prelude = "");
    static Program compute(const std::string& comp, const std::vector<std::string>& defines = {}, const std::string& prelude = "");
    GLuint id() const { return id_.get(); }
    void use() const { glUseProgram(id_.get()); }
    GLint uniform(const char* name) const { return glGetUniformLocation(id_.get(), name); }
    // Bind texture `tex` (0: none) to unit `unit` and point the sampler uniform `sampler` at it.
    void bind_texture(int unit, GLenum target, GLuint tex, const char* sampler) const {
        glActiveTexture(GLenum(GL_TEXTURE0 + unit));
        glBindTexture(target, tex);
        glUniform1i(uniform(sampler), unit);
    }
    explicit operator bool() const { return bool(id_); }
private:
    GlName<delete_program> id_;
};

// Framebuffer with N RGBA32F colour attachments and a 32-bit float depth buffer.
class RenderTarget {
public:
    void resize(int width, int height, int color_attachments);
    void bind() const;  // binds the FBO, sets the viewport and draw buffers
    GLuint fbo() const { return fbo_.get(); }
    GLuint color(int i) const { return color_[size_t(i)].get(); }
    int width() const { return width_; }
    int height() const { return height_; }
    int attachments() const { return int(color_.size()); }
    // Read attachment i as float RGBA, top row first (flips GL's bottom-up order).
    std::vector<float> read_rgba(int i) const;
private:
    int width_ = 0, height_ = 0;
    Framebuffer fbo_;
    std::vector<Texture> color_;
    Texture depth_;
};

// [SECTION] GpuTimeline
// Named GPU time ranges, read without waiting for the GPU: a frame never stalls for its own
// timings. A range is one GL_TIME_ELAPSED query (ranges follow one another; they never nest).
// Its answer is taken once the driver has it: poll() hands over whatever is ready now (the window
// calls it at the start of each frame, so its timings arrive a frame late), wait() everything (for
// callers that have waited for the frame's fence anyway, such as bench and capture). Each answer
// goes to the range's callback, checked against the wall-clock time from begin() until it was
// read, which bounds it: Mesa 22.3's llvmpipe sometimes loses the start of a query (under load,
// or before a context's first draw) and reports roughly the system uptime. Such an impossible
// answer is never passed on: the callback gets NaN, so tables show a gap instead of a wrong figure.
//
// Software renderers (is_software_renderer: Mesa's llvmpipe, softpipe) do the work on the CPU,
// and their timer queries do not see it: llvmpipe 22.3 answers about 3% of a frame's wall time
// for draws and ~0 for compute dispatches. There a range is timed by the wall clock between two
// glFinish calls instead, and its callback runs at end(): the time the CPU spent on the work,
// which a software frame spends anyway.
class GpuTimeline {
public:
    using Done = std::function<void(double ms)>;
    explicit GpuTimeline(bool software = false) : software_(software) {}
    // A driver's answer is plausible when it is a number in [0, the wall-clock time around the
    // query + 1% + 1 ms of clock granularity].
    static bool plausible(double gpu_ms, double wall_ms) { return gpu_ms >= 0.0 && gpu_ms <= wall_ms * 1.01 + 1.0; }
    bool software() const { return software_; }
    void begin();
    void end(Done done);
    // Closes an open range without an answer (a frame that threw while its range was open).
    void abandon();
    void poll();  // callbacks of the ranges whose answers are ready, in order
    void wait();  // callbacks of all open ranges (waits for the GPU)
    size_t open() const { return open_.size(); }

private:
    struct Range {
        Query query;
        std::chrono::steady_clock::time_point wall0;
        Done done;
    };
    void take(Range& r);
    bool software_ = false;
    bool in_range_ = false;
    std::chrono::steady_clock::time_point wall0_{};
    Query current_;
    std::deque<Range> open_;
    std::vector<Query> spare_;  // query objects of answered ranges, reused
};

// Whether a GL_RENDERER string names a renderer that runs on the CPU (llvmpipe, softpipe, SwiftShader).
bool is_software_renderer(const std::string& gl_renderer);
// The same for the current context's GL_RENDERER.
bool current_renderer_is_software();

// Where the best layout of a pass differs between a renderer that runs on the CPU (llvmpipe:
// SIMD lanes of 8, no caches to coalesce into) and a hardware GPU (warps of 32, hundreds of
// thousands of invocations in flight), the pass asks tuned_for_hardware() when it dispatches:
// !current_renderer_is_software(), unless set_gpu_tuning forced one (the tests run the
// hardware layouts on llvmpipe to check their results). Which passes choose: the main README's
// "GPU timings".
enum class GpuTuning { Automatic, Software, Hardware };
void set_gpu_tuning(GpuTuning t);
bool tuned_for_hardware();

// Waits until every GL command issued so far has finished, through a fence (glFenceSync and
// glClientWaitSync, flushing once): what a caller that needs a finished frame waits for.
void wait_for_gpu();

// Throws std::runtime_error naming `where` if glGetError() reports an error.
void check_gl(const char* where);
}  // namespace mesolab::gpu
