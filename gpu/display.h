#pragma once
// [SECTION] Display pass of the GUI.
// Converts one float AOV texture of the renderer (RGBA32F, bottom row first as GL draws it) into
// an RGBA8 texture ready to be shown with ImGui::Image: colour AOVs through the sRGB transfer
// function (shaders/common.glsl, linear_to_srgb) after an exposure scale, normals as n*0.5+0.5.
// Alpha is always 1. The output texture keeps its GL name across resizes, so a draw list that
// references it stays valid when the frame is re-rendered at another size.
#include "gpu/gl.h"

namespace mesolab::gpu {

enum class DisplayMode { Color, Normal };

class DisplayPass {
public:
    DisplayPass();  // needs a current GL 4.3+ context
    // Convert `source` (width x height) into texture(); `channels` of the AOV (1: grey).
    void run(GLuint source, int width, int height, DisplayMode mode, int channels, float exposure = 1.f);
    GLuint texture() const { return texture_.get(); }
    int width() const { return width_; }
    int height() const { return height_; }
    bool valid() const { return width_ > 0 && height_ > 0; }

private:
    Program program_;
    Framebuffer fbo_;
    Texture texture_;
    VertexArray vao_;
    int width_ = 0, height_ = 0;
};
}  // namespace mesolab::gpu
