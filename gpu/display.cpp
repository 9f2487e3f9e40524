#include "gpu/display.h"
#include "core/profile.h"

#include <stdexcept>
#include <string>

namespace mesolab::gpu {

DisplayPass::DisplayPass() : program_(Program::graphics("shaders/fullscreen.vert", "shaders/display.frag")) {
    // The one texture made without make_texture (gpu/gl.h): its storage is mutable so that it keeps
    // its name across resizes.
    GLuint ids[1] = {0};
    glCreateTextures(GL_TEXTURE_2D, 1, ids);
    texture_ = Texture(ids[0]);
    glTextureParameteri(ids[0], GL_TEXTURE_MIN_FILTER, GL_LINEAR);
    glTextureParameteri(ids[0], GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    glTextureParameteri(ids[0], GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    glTextureParameteri(ids[0], GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
    glGenFramebuffers(1, ids);
    fbo_ = Framebuffer(ids[0]);
    glGenVertexArrays(1, ids);
    vao_ = VertexArray(ids[0]);
    check_gl("DisplayPass()");
}

void DisplayPass::run(GLuint source, int width, int height, DisplayMode mode, int channels, float exposure) {
    PROFILE_SCOPE("frame.display");
    if (!source) throw std::logic_error("DisplayPass::run: no source texture");
    if (width < 1 || height < 1) throw std::logic_error("DisplayPass::run: empty frame " + std::to_string(width) + "x" + std::to_string(height));
    if (width != width_ || height != height_) {
        // Mutable storage: the texture keeps its name (ImGui draw lists may hold it).
        GLint previous = 0;
        glGetIntegerv(GL_TEXTURE_BINDING_2D, &previous);
        glBindTexture(GL_TEXTURE_2D, texture_.get());
        glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA8, width, height, 0, GL_RGBA, GL_UNSIGNED_BYTE, nullptr);
        glBindTexture(GL_TEXTURE_2D, GLuint(previous));
        glBindFramebuffer(GL_FRAMEBUFFER, fbo_.get());
        glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, texture_.get(), 0);
        const GLenum status = glCheckFramebufferStatus(GL_FRAMEBUFFER);
        glBindFramebuffer(GL_FRAMEBUFFER, 0);
        if (status != GL_FRAMEBUFFER_COMPLETE) throw std::runtime_error("DisplayPass: framebuffer incomplete");
        width_ = width;
        height_ = height;
    }
    glBindFramebuffer(GL_FRAMEBUFFER, fbo_.get());
    const GLenum buf = GL_COLOR_ATTACHMENT0;
    glDrawBuffers(1, &buf);
    glViewport(0, 0, width, height);
    glDisable(GL_DEPTH_TEST);
    glDisable(GL_BLEND);
    glDisable(GL_SCISSOR_TEST);
    glDisable(GL_CULL_FACE);
    program_.use();
    glActiveTexture(GL_TEXTURE0);
    glBindTexture(GL_TEXTURE_2D, source);
    glUniform1i(program_.uniform("u_source"), 0);
    glUniform1i(program_.uniform("u_mode"), mode == DisplayMode::Normal ? 1 : 0);
    glUniform1i(program_.uniform("u_channels"), channels);
    glUniform1f(program_.uniform("u_exposure"), exposure);
    glBindVertexArray(vao_.get());
    glDrawArrays(GL_TRIANGLES, 0, 3);
    glBindVertexArray(0);
    glBindTexture(GL_TEXTURE_2D, 0);
    glUseProgram(0);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    check_gl("DisplayPass::run");
}
}  // namespace mesolab::gpu
