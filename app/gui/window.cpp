// The main window: GLFW, the OpenGL context, Dear ImGui and its style, the default layout.
#include "app/gui/window.h"
#include "core/error.h"
#include "gpu/context.h"

#include <epoxy/gl.h>
#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>
#include <backends/imgui_impl_glfw.h>
#include <backends/imgui_impl_opengl3.h>

#include <algorithm>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <utility>

namespace fs = std::filesystem;

namespace mesolab::gui {
namespace {
std::string g_glfw_error;  // the last GLFW error, for the messages below
}  // namespace

// [SECTION] GLFW and the window
GlfwLibrary::GlfwLibrary() {
    glfwSetErrorCallback([](int code, const char* text) { g_glfw_error = std::string(text ? text : "") + " (GLFW error " + std::to_string(code) + ")"; });
    if (!glfwInit())
        throw InputError("gui: there is no display to open a window on (" + (g_glfw_error.empty() ? std::string("glfwInit failed") : g_glfw_error) +
                         "). Render headless with `mesolab capture PRESET` instead, or run the window under a virtual display: "
                         "`xvfb-run -a mesolab gui ...`");
}

GlfwLibrary::~GlfwLibrary() { glfwTerminate(); }

Window::Window(int w, int h) {
    for (auto [major, minor] : {std::pair{4, 5}, std::pair{4, 3}}) {
        glfwDefaultWindowHints();
        glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, major);
        glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, minor);
        glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
        glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
        handle = glfwCreateWindow(w, h, "mesolab", nullptr, nullptr);
        if (handle) {
            gl_major = major;
            gl_minor = minor;
            break;
        }
    }
    if (!handle)
        throw InputError("gui: cannot open a window with an OpenGL 4.3 core context (" + g_glfw_error +
                         "). Render headless with `mesolab capture PRESET` instead");
    glfwMakeContextCurrent(handle);
    gpu::pin_loaded_objects();  // the GL driver stays loaded after glfwTerminate (LeakSanitizer)
}

Window::~Window() {
    if (handle) glfwDestroyWindow(handle);
}

// [SECTION] ImGui
ImGuiSession::ImGuiSession(GLFWwindow* w) {
    IMGUI_CHECKVERSION();
    ImGui::CreateContext();
    ImGui::GetIO().IniFilename = nullptr;  // deterministic layout, no imgui.ini next to the user's files
    ImGui::GetIO().LogFilename = nullptr;
    setup_style();
    if (!ImGui_ImplGlfw_InitForOpenGL(w, true)) throw std::runtime_error("ImGui GLFW backend failed to initialise");
    if (!ImGui_ImplOpenGL3_Init("#version 430")) throw std::runtime_error("ImGui OpenGL3 backend failed to initialise");
}

ImGuiSession::~ImGuiSession() {
    ImGui_ImplOpenGL3_Shutdown();
    ImGui_ImplGlfw_Shutdown();
    ImGui::DestroyContext();
}

// [SECTION] Style
void setup_style() {
    ImGuiIO& io = ImGui::GetIO();
    // DejaVu Sans when installed (fonts-dejavu-core), otherwise ImGui's built-in font.
    for (const char* f : {"/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf", "/usr/share/fonts/TTF/DejaVuSans.ttf"}) {
        std::error_code ec;
        if (fs::is_regular_file(f, ec) && io.Fonts->AddFontFromFileTTF(f, 15.0f)) break;
    }
    if (io.Fonts->Fonts.empty()) io.Fonts->AddFontDefault();

    ImGui::StyleColorsDark();
    ImGuiStyle& s = ImGui::GetStyle();
    s.WindowPadding = ImVec2(10, 8);
    s.FramePadding = ImVec2(6, 3);
    s.ItemSpacing = ImVec2(8, 5);
    s.ItemInnerSpacing = ImVec2(5, 4);
    s.IndentSpacing = 14;
    s.ScrollbarSize = 12;
    s.GrabMinSize = 9;
    s.WindowRounding = 0;
    s.ChildRounding = 3;
    s.FrameRounding = 3;
    s.PopupRounding = 3;
    s.ScrollbarRounding = 3;
    s.GrabRounding = 3;
    s.TabRounding = 3;
    s.WindowBorderSize = 1;
    s.FrameBorderSize = 0;
    s.WindowTitleAlign = ImVec2(0.0f, 0.5f);
    s.WindowMenuButtonPosition = ImGuiDir_Right;

    ImVec4* c = s.Colors;
    const ImVec4 bg(0.105f, 0.110f, 0.120f, 1.f), panel(0.135f, 0.140f, 0.152f, 1.f), frame(0.190f, 0.196f, 0.212f, 1.f);
    const ImVec4 accent(0.259f, 0.522f, 0.957f, 1.f), accent_hi(0.349f, 0.600f, 0.980f, 1.f);
    c[ImGuiCol_Text] = ImVec4(0.90f, 0.91f, 0.93f, 1.f);
    c[ImGuiCol_TextDisabled] = ImVec4(0.52f, 0.54f, 0.58f, 1.f);
    c[ImGuiCol_WindowBg] = panel;
    c[ImGuiCol_ChildBg] = ImVec4(0, 0, 0, 0);
    c[ImGuiCol_PopupBg] = ImVec4(0.150f, 0.155f, 0.168f, 0.98f);
    c[ImGuiCol_Border] = ImVec4(0.230f, 0.236f, 0.255f, 1.f);
    c[ImGuiCol_FrameBg] = frame;
    c[ImGuiCol_FrameBgHovered] = ImVec4(0.235f, 0.243f, 0.263f, 1.f);
    c[ImGuiCol_FrameBgActive] = ImVec4(0.270f, 0.280f, 0.305f, 1.f);
    c[ImGuiCol_TitleBg] = bg;
    c[ImGuiCol_TitleBgActive] = ImVec4(0.125f, 0.130f, 0.142f, 1.f);
    c[ImGuiCol_TitleBgCollapsed] = bg;
    c[ImGuiCol_MenuBarBg] = bg;
    c[ImGuiCol_ScrollbarBg] = ImVec4(0, 0, 0, 0);
    c[ImGuiCol_CheckMark] = accent_hi;
    c[ImGuiCol_SliderGrab] = accent;
    c[ImGuiCol_SliderGrabActive] = accent_hi;
    c[ImGuiCol_Button] = ImVec4(0.215f, 0.222f, 0.242f, 1.f);
    c[ImGuiCol_ButtonHovered] = ImVec4(0.275f, 0.285f, 0.312f, 1.f);
    c[ImGuiCol_ButtonActive] = accent;
    c[ImGuiCol_Header] = ImVec4(0.190f, 0.198f, 0.218f, 1.f);
    c[ImGuiCol_HeaderHovered] = ImVec4(0.245f, 0.255f, 0.282f, 1.f);
    c[ImGuiCol_HeaderActive] = ImVec4(0.259f, 0.522f, 0.957f, 0.55f);
    c[ImGuiCol_Separator] = c[ImGuiCol_Border];
    c[ImGuiCol_ResizeGrip] = ImVec4(0, 0, 0, 0);
    c[ImGuiCol_Tab] = frame;
    c[ImGuiCol_TableHeaderBg] = ImVec4(0.165f, 0.172f, 0.188f, 1.f);
    c[ImGuiCol_TableRowBgAlt] = ImVec4(1.f, 1.f, 1.f, 0.025f);
    c[ImGuiCol_PlotHistogram] = accent;
    c[ImGuiCol_TextSelectedBg] = ImVec4(0.259f, 0.522f, 0.957f, 0.35f);
    c[ImGuiCol_ModalWindowDimBg] = ImVec4(0.f, 0.f, 0.f, 0.45f);
}

// [SECTION] Layout
namespace layout {
Rects compute(ImVec2 ds) {
    Rects r;
    const float bar = ImGui::GetFrameHeight();
    r.top = bar;
    r.body_h = std::max(100.f, ds.y - 2.f * bar);
    r.side_w = std::clamp(ds.x * 0.27f, std::min(340.f, ds.x * 0.5f), 520.f);
    r.side_x = ds.x - r.side_w;
    const float timings_h = std::clamp(r.body_h * 0.27f, std::min(150.f, r.body_h * 0.4f), 340.f);
    r.view_pos = ImVec2(0, r.top);
    r.view_size = ImVec2(r.side_x, r.body_h - timings_h);
    r.timings_pos = ImVec2(0, r.top + r.body_h - timings_h);
    r.timings_size = ImVec2(r.side_x, timings_h);
    return r;
}
}  // namespace layout
}  // namespace mesolab::gui
