#include "gpu/context.h"

#include <epoxy/egl.h>
#include <epoxy/gl.h>

#include <dlfcn.h>
#include <link.h>

#include <cstdlib>
#include <map>
#include <mutex>
#include <set>
#include <sstream>
#include <stdexcept>
#include <vector>

// Notes beyond context.h:
//  * MESOLAB_EGL_PLATFORM=device|surfaceless|default (comma-separated list allowed) narrows the
//    platforms tried, for debugging; unset means all three, in that order.
//  * The shared objects the first successful create() loads (the vendor's EGL/GL driver, e.g.
//    Mesa's swrast_dri.so and libLLVM) stay loaded until exit (RTLD_NODELETE), although
//    eglTerminate() would unload them. Re-creating a context is then cheap, and LeakSanitizer
//    does not report the driver's static allocations as leaks with unresolvable stacks (memory
//    reachable only from an unloaded library's globals; no suppression can match those frames).

namespace mesolab::gpu {

// [SECTION] EGL error names and display reference counts
namespace {

const char* egl_error_name(EGLint e) {
    switch (e) {
    case EGL_SUCCESS: return "EGL_SUCCESS";
    case EGL_NOT_INITIALIZED: return "EGL_NOT_INITIALIZED";
    case EGL_BAD_ACCESS: return "EGL_BAD_ACCESS";
    case EGL_BAD_ALLOC: return "EGL_BAD_ALLOC";
    case EGL_BAD_ATTRIBUTE: return "EGL_BAD_ATTRIBUTE";
    case EGL_BAD_CONFIG: return "EGL_BAD_CONFIG";
    case EGL_BAD_CONTEXT: return "EGL_BAD_CONTEXT";
    case EGL_BAD_CURRENT_SURFACE: return "EGL_BAD_CURRENT_SURFACE";
    case EGL_BAD_DISPLAY: return "EGL_BAD_DISPLAY";
    case EGL_BAD_MATCH: return "EGL_BAD_MATCH";
    case EGL_BAD_NATIVE_PIXMAP: return "EGL_BAD_NATIVE_PIXMAP";
    case EGL_BAD_NATIVE_WINDOW: return "EGL_BAD_NATIVE_WINDOW";
    case EGL_BAD_PARAMETER: return "EGL_BAD_PARAMETER";
    case EGL_BAD_SURFACE: return "EGL_BAD_SURFACE";
    case EGL_CONTEXT_LOST: return "EGL_CONTEXT_LOST";
    case EGL_BAD_DEVICE_EXT: return "EGL_BAD_DEVICE_EXT";
    default: return "unknown EGL error";
    }
}

// One step of context creation failed; the message names the step and the EGL error.
struct EglFailure : std::runtime_error {
    using std::runtime_error::runtime_error;
};

[[noreturn]] void fail(const std::string& step) {
    const EGLint e = eglGetError();
    std::ostringstream os;
    os << step << " failed (" << egl_error_name(e) << ", 0x" << std::hex << e << ")";
    throw EglFailure(os.str());
}

// EGL displays are per-process singletons: eglTerminate() would destroy every context on the
// display, so it is only called when the last HeadlessContext on that display goes away.
std::mutex g_display_mutex;
std::map<EGLDisplay, int> g_display_refs;

void retain_display(EGLDisplay d) {
    std::lock_guard lock(g_display_mutex);
    ++g_display_refs[d];
}

void release_display(EGLDisplay d) {
    std::unique_lock lock(g_display_mutex);
    auto it = g_display_refs.find(d);
    if (it == g_display_refs.end()) {
        eglTerminate(d);  // never retained: initialised by a failed attempt
        return;
    }
    if (--it->second == 0) {
        g_display_refs.erase(it);
        eglTerminate(d);
    }
}

// Paths of all shared objects in the process.
std::set<std::string> loaded_objects() {
    std::set<std::string> names;
    dl_iterate_phdr(
        [](dl_phdr_info* info, size_t, void* data) {
            if (info->dlpi_name && *info->dlpi_name) static_cast<std::set<std::string>*>(data)->insert(info->dlpi_name);
            return 0;
        },
        &names);
    return names;
}

// Marks every shared object loaded since `before` as never to be unloaded.
void pin_new_objects(const std::set<std::string>& before) {
    for (const std::string& name : loaded_objects()) {
        if (before.count(name)) continue;
        if (void* handle = dlopen(name.c_str(), RTLD_LAZY | RTLD_NOLOAD | RTLD_NODELETE))
            dlclose(handle);  // drops the reference dlopen just added; the NODELETE flag stays
    }
}

}  // namespace

void pin_loaded_objects() { pin_new_objects({}); }

namespace {

bool platform_enabled(const char* name) {
    const char* env = std::getenv("MESOLAB_EGL_PLATFORM");
    if (!env || !*env) return true;
    std::string list = std::string(",") + env + ",";
    return list.find(std::string(",") + name + ",") != std::string::npos;
}

}  // namespace

// [SECTION] Impl: one display, config, context and optional 1x1 pbuffer
struct HeadlessContext::Impl {
    EGLDisplay display = EGL_NO_DISPLAY;
    EGLContext context = EGL_NO_CONTEXT;
    EGLSurface surface = EGL_NO_SURFACE;  // only when EGL_KHR_surfaceless_context is missing
    bool retained = false;

    ~Impl() { release(); }

    void release() {
        if (display == EGL_NO_DISPLAY) return;
        if (context != EGL_NO_CONTEXT && eglGetCurrentContext() == context)
            eglMakeCurrent(display, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
        if (surface != EGL_NO_SURFACE) eglDestroySurface(display, surface);
        if (context != EGL_NO_CONTEXT) eglDestroyContext(display, context);
        if (retained) {
            release_display(display);
        } else {
            eglTerminate(display);
        }
        // Frees EGL's per-thread state, unless another context is still current on this thread.
        if (eglGetCurrentContext() == EGL_NO_CONTEXT) eglReleaseThread();
        display = EGL_NO_DISPLAY;
        context = EGL_NO_CONTEXT;
        surface = EGL_NO_SURFACE;
        retained = false;
    }

    // Initialises `d` and makes a GL >= 4.3 core context current on it, or throws EglFailure.
    void init(EGLDisplay d) {
        if (d == EGL_NO_DISPLAY) fail("getting the EGL display");
        display = d;
        EGLint major = 0, minor = 0;
        if (!eglInitialize(display, &major, &minor)) fail("eglInitialize");
        retain_display(display);
        retained = true;
        if (!eglBindAPI(EGL_OPENGL_API)) fail("eglBindAPI(EGL_OPENGL_API)");

        const bool surfaceless = epoxy_has_egl_extension(display, "EGL_KHR_surfaceless_context");
        EGLConfig config = nullptr;
        EGLint count = 0;
        EGLint attribs[] = {EGL_SURFACE_TYPE, EGL_PBUFFER_BIT, EGL_RENDERABLE_TYPE, EGL_OPENGL_BIT, EGL_NONE};
        if (!eglChooseConfig(display, attribs, &config, 1, &count)) fail("eglChooseConfig");
        if (count == 0) {
            if (!surfaceless) throw EglFailure("no EGL config with EGL_PBUFFER_BIT and no EGL_KHR_surfaceless_context");
            attribs[1] = 0;  // any surface type: we never create one
            if (!eglChooseConfig(display, attribs, &config, 1, &count)) fail("eglChooseConfig");
            if (count == 0) throw EglFailure("eglChooseConfig found no OpenGL-renderable config");
        }

        for (const EGLint minor_version : {5, 3}) {
            const EGLint ctx_attribs[] = {EGL_CONTEXT_MAJOR_VERSION, 4, EGL_CONTEXT_MINOR_VERSION, minor_version,
                                          EGL_CONTEXT_OPENGL_PROFILE_MASK, EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT, EGL_NONE};
            context = eglCreateContext(display, config, EGL_NO_CONTEXT, ctx_attribs);
            if (context != EGL_NO_CONTEXT) break;
        }
        if (context == EGL_NO_CONTEXT) fail("eglCreateContext(OpenGL 4.5 or 4.3 core)");

        if (!surfaceless) {
            const EGLint pb_attribs[] = {EGL_WIDTH, 1, EGL_HEIGHT, 1, EGL_NONE};
            surface = eglCreatePbufferSurface(display, config, pb_attribs);
            if (surface == EGL_NO_SURFACE) fail("eglCreatePbufferSurface(1x1)");
        }
        if (!eglMakeCurrent(display, surface, surface, context)) fail("eglMakeCurrent");
        if (epoxy_gl_version() < 43) throw EglFailure("context reports OpenGL " + std::to_string(epoxy_gl_version()) + ", need 43");
    }
};

// [SECTION] GL strings
GlInfo query_gl_info(const std::string& platform) {
    auto str = [](GLenum name) {
        const auto* s = reinterpret_cast<const char*>(glGetString(name));
        return std::string(s ? s : "");
    };
    return {str(GL_VENDOR), str(GL_RENDERER), str(GL_VERSION), str(GL_SHADING_LANGUAGE_VERSION), platform};
}

// [SECTION] Creation: device platform, then Mesa surfaceless, then the default display
std::unique_ptr<HeadlessContext> HeadlessContext::create() {
    std::unique_ptr<HeadlessContext> ctx(new HeadlessContext());
    std::vector<std::string> failures;
    const std::set<std::string> objects_before = loaded_objects();

    // Tries one display; on success ctx holds it and info is filled.
    auto attempt = [&](const std::string& label, const std::string& platform, auto get_display) {
        auto impl = std::make_unique<Impl>();
        try {
            impl->init(get_display());
        } catch (const EglFailure& e) {
            failures.push_back(label + ": " + e.what());
            return false;
        }
        ctx->impl_ = std::move(impl);
        ctx->info_ = query_gl_info(platform);
        pin_new_objects(objects_before);
        return true;
    };

    const bool has_platform_base = epoxy_has_egl_extension(EGL_NO_DISPLAY, "EGL_EXT_platform_base");
    if (platform_enabled("device")) {
        if (has_platform_base && epoxy_has_egl_extension(EGL_NO_DISPLAY, "EGL_EXT_platform_device")) {
            auto query_devices = reinterpret_cast<PFNEGLQUERYDEVICESEXTPROC>(eglGetProcAddress("eglQueryDevicesEXT"));
            EGLint n = 0;
            if (!query_devices || !query_devices(0, nullptr, &n)) {
                failures.push_back(std::string("egl-device: eglQueryDevicesEXT failed (") + egl_error_name(eglGetError()) + ")");
            } else {
                std::vector<EGLDeviceEXT> devices(size_t(n > 0 ? n : 0));
                if (n > 0 && !query_devices(n, devices.data(), &n)) n = 0;
                if (n == 0) failures.push_back("egl-device: no EGL devices");
                for (EGLint i = 0; i < n; ++i) {
                    auto get = [&] { return eglGetPlatformDisplayEXT(EGL_PLATFORM_DEVICE_EXT, devices[size_t(i)], nullptr); };
                    if (attempt("egl-device[" + std::to_string(i) + "]", "egl-device", get)) return ctx;
                }
            }
        } else {
            failures.push_back("egl-device: EGL_EXT_platform_device not supported");
        }
    }
    if (platform_enabled("surfaceless")) {
        if (has_platform_base && epoxy_has_egl_extension(EGL_NO_DISPLAY, "EGL_MESA_platform_surfaceless")) {
            auto get = [] { return eglGetPlatformDisplayEXT(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr); };
            if (attempt("egl-surfaceless", "egl-surfaceless", get)) return ctx;
        } else {
            failures.push_back("egl-surfaceless: EGL_MESA_platform_surfaceless not supported");
        }
    }
    if (platform_enabled("default")) {
        auto get = [] { return eglGetDisplay(EGL_DEFAULT_DISPLAY); };
        if (attempt("egl-default", "egl-default", get)) return ctx;
    }

    std::string msg = "could not create a headless OpenGL 4.3+ context through EGL";
    if (failures.empty()) msg += " (no platform enabled by MESOLAB_EGL_PLATFORM)";
    for (const auto& f : failures) msg += "\n  " + f;
    msg += "\nuse --backend cpu to render without OpenGL";
    throw std::runtime_error(msg);
}

// [SECTION] Lifetime
HeadlessContext::~HeadlessContext() = default;

void HeadlessContext::make_current() {
    if (!eglMakeCurrent(impl_->display, impl_->surface, impl_->surface, impl_->context))
        throw std::runtime_error(std::string("eglMakeCurrent failed (") + egl_error_name(eglGetError()) + ")");
}

// [SECTION] Compute scope: a shared context for compute work, any thread, one at a time
namespace {
struct ComputeShared {
    std::mutex mutex;
    std::unique_ptr<HeadlessContext> context;
    std::string failure;
    std::mutex pending_mutex;    // guards pending (taken without `mutex`: any thread may add)
    std::vector<GLuint> pending;  // buffers to delete at the next scope's start
};
thread_local bool t_in_compute_scope = false;
ComputeShared& compute_shared() {
    static ComputeShared* shared = new ComputeShared();  // kept until exit: no destruction-order issues with EGL
    return *shared;
}
}  // namespace

struct ComputeScope::Saved {
    std::unique_lock<std::mutex> lock;
    EGLDisplay display = EGL_NO_DISPLAY;
    EGLContext context = EGL_NO_CONTEXT;
    EGLSurface draw = EGL_NO_SURFACE, read = EGL_NO_SURFACE;
};

ComputeScope::ComputeScope() : saved_(std::make_unique<Saved>()) {
    ComputeShared& cs = compute_shared();
    saved_->lock = std::unique_lock<std::mutex>(cs.mutex);
    if (!cs.failure.empty()) throw std::runtime_error(cs.failure);
    saved_->display = eglGetCurrentDisplay();
    saved_->context = eglGetCurrentContext();
    saved_->draw = eglGetCurrentSurface(EGL_DRAW);
    saved_->read = eglGetCurrentSurface(EGL_READ);
    try {
        if (!cs.context) {
            cs.context = HeadlessContext::create();  // current on creation
        } else {
            cs.context->make_current();
        }
    } catch (const std::runtime_error& e) {
        cs.failure = e.what();
        throw;
    }
    t_in_compute_scope = true;
    std::vector<GLuint> doomed;
    {
        const std::lock_guard<std::mutex> pending_lock(cs.pending_mutex);
        doomed.swap(cs.pending);
    }
    if (!doomed.empty()) glDeleteBuffers(GLsizei(doomed.size()), doomed.data());
}

ComputeScope::~ComputeScope() {
    t_in_compute_scope = false;
    glFinish();
    if (saved_->context != EGL_NO_CONTEXT) {
        eglMakeCurrent(saved_->display, saved_->draw, saved_->read, saved_->context);
    } else {
        eglMakeCurrent(eglGetCurrentDisplay(), EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
    }
}

const GlInfo& ComputeScope::info() const { return compute_shared().context->info(); }

bool in_compute_scope() { return t_in_compute_scope; }

void delete_compute_buffers(const std::vector<GLuint>& buffers) {
    if (buffers.empty()) return;
    if (t_in_compute_scope) {
        glDeleteBuffers(GLsizei(buffers.size()), buffers.data());
        return;
    }
    ComputeShared& cs = compute_shared();
    const std::lock_guard<std::mutex> pending_lock(cs.pending_mutex);
    cs.pending.insert(cs.pending.end(), buffers.begin(), buffers.end());
}
}  // namespace mesolab::gpu
