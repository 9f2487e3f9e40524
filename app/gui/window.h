#pragma once
// [SECTION] The main window and its look
//  - GlfwLibrary, Window: GLFW and the window with an OpenGL 4.5 (else 4.3) core context; they
//    throw InputError explaining what to do instead when there is no display or no such context.
//  - ImGuiSession: the Dear ImGui context with its GLFW and OpenGL backends, styled by
//    setup_style (DejaVu Sans when installed, a dark theme with a blue accent).
//  - layout::compute: where the viewport, the side windows and the timings go.
#include <imgui.h>

struct GLFWwindow;

namespace mesolab::gui {

// [SECTION] Lifetimes, in the order they are created
struct GlfwLibrary {
    GlfwLibrary();
    ~GlfwLibrary();
    GlfwLibrary(const GlfwLibrary&) = delete;
    GlfwLibrary& operator=(const GlfwLibrary&) = delete;
};

struct Window {
    GLFWwindow* handle = nullptr;
    int gl_major = 0, gl_minor = 0;
    Window(int w, int h);  // made current on this thread
    ~Window();
    Window(const Window&) = delete;
    Window& operator=(const Window&) = delete;
};

struct ImGuiSession {
    explicit ImGuiSession(GLFWwindow* w);
    ~ImGuiSession();
    ImGuiSession(const ImGuiSession&) = delete;
    ImGuiSession& operator=(const ImGuiSession&) = delete;
};

// Fonts, sizes and colours of the ImGui style (ImGuiSession calls it).
void setup_style();

// [SECTION] Layout
// The default places of the windows for a display size: the viewport top left, the timings
// under it, the side windows (Scene, the techniques', Presets) in a column on the right.
namespace layout {
struct Rects {
    ImVec2 view_pos, view_size, timings_pos, timings_size;
    float side_x, side_w, top, body_h;
};
Rects compute(ImVec2 display);
}  // namespace layout
}  // namespace mesolab::gui
