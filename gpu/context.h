#pragma once
// Headless OpenGL through EGL, with no window and no X server. Tries, in order, the EGL device
// platform (EGL_EXT_platform_device: real NVIDIA/AMD drivers and Mesa), the Mesa surfaceless
// platform (EGL_PLATFORM_SURFACELESS_MESA) and the default display; asks for an OpenGL 4.5
// core context, falling back to 4.3. GL entry points come through libepoxy.
#include <memory>
#include <string>
#include <vector>

namespace mesolab::gpu {

struct GlInfo {
    std::string vendor, renderer, version, glsl_version, platform;  // platform: "egl-device", "egl-surfaceless", "egl-default", "glfw"
};

// Keep every shared object loaded now (e.g. the GL driver a GLFW window loaded) until exit, so
// that unloading it at glfwTerminate() does not turn its static allocations into leaks with
// unresolvable stacks under LeakSanitizer (see context.cpp).
void pin_loaded_objects();

// Query GL strings of the current context.
GlInfo query_gl_info(const std::string& platform);

class HeadlessContext {
public:
    // Throws std::runtime_error with a message that says what failed (and that `--backend cpu`
    // works without GL) when no context can be made.
    static std::unique_ptr<HeadlessContext> create();
    ~HeadlessContext();
    HeadlessContext(const HeadlessContext&) = delete;
    HeadlessContext& operator=(const HeadlessContext&) = delete;

    void make_current();
    const GlInfo& info() const { return info_; }

private:
    HeadlessContext() = default;
    struct Impl;
    std::unique_ptr<Impl> impl_;
    GlInfo info_;
};
// A process-wide headless context for compute work (gpu/microgeom/scatter_gpu.h), made current
// on the calling thread for the scope's lifetime and the thread's previous EGL context restored
// after. One scope at a time (a mutex): stages may run on a worker thread while the UI thread
// draws with its own context. Created on first use and kept until exit. Throws
// std::runtime_error (HeadlessContext::create's message) when no context can be made; that
// failure is remembered, so later scopes fail at once.
class ComputeScope {
public:
    ComputeScope();
    ~ComputeScope();
    ComputeScope(const ComputeScope&) = delete;
    ComputeScope& operator=(const ComputeScope&) = delete;
    const GlInfo& info() const;

private:
    struct Saved;
    std::unique_ptr<Saved> saved_;
};

// Whether the calling thread holds a ComputeScope (the compute context is current on it).
bool in_compute_scope();

// Deletes buffers made on the compute context: at once when the calling thread holds a
// ComputeScope, else when the next scope starts. For GPU copies owned by results that may be
// released on any thread (a stage cache's eviction, a Python object's collection).
void delete_compute_buffers(const std::vector<unsigned>& buffers);
}  // namespace mesolab::gpu
