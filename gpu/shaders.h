#pragma once
// Shader sources embedded into the binary at build time from gpu/**/*.glsl, *.vert, *.frag,
// *.comp (see embed_shaders.cmake). Names are paths relative to gpu/ ("shaders/common.glsl",
// "basic/basic.frag").
#include <string>
#include <string_view>
#include <vector>

namespace mesolab::gpu {
// Throws std::runtime_error if there is no embedded shader of that name.
std::string_view shader_source(const std::string& name);
std::vector<std::string> shader_names();
}  // namespace mesolab::gpu
