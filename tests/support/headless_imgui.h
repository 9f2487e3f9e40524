#pragma once
// A headless Dear ImGui context for panel tests: no backend, nothing drawn on screen; widgets are
// driven by setting io.MousePos / io.MouseDown between frames.
#include <imgui.h>
#include <functional>

namespace mesolab::test {

struct HeadlessImGui {
    HeadlessImGui() {
        ImGui::CreateContext();
        ImGuiIO& io = ImGui::GetIO();
        io.DisplaySize = ImVec2(900, 700);
        io.DeltaTime = 1.f / 60.f;
        io.IniFilename = nullptr;
        unsigned char* pixels = nullptr;
        int w = 0, h = 0;
        io.Fonts->GetTexDataAsRGBA32(&pixels, &w, &h);
    }
    ~HeadlessImGui() { ImGui::DestroyContext(); }
    HeadlessImGui(const HeadlessImGui&) = delete;
    HeadlessImGui& operator=(const HeadlessImGui&) = delete;
    void frame(const std::function<void()>& body) {
        ImGui::NewFrame();
        ImGui::SetNextWindowPos(ImVec2(0, 0));
        ImGui::SetNextWindowSize(ImVec2(900, 700));
        ImGui::Begin("test");
        body();
        ImGui::End();
        ImGui::Render();
    }
};
}  // namespace mesolab::test
