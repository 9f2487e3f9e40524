#include "gpu/shaders.h"
#include "gpu/shader_table.h"

#include <algorithm>
#include <stdexcept>

namespace mesolab::gpu {

// [SECTION] Lookup in the generated table (sorted by name, see embed_shaders.cmake)
namespace {
const detail::EmbeddedShader* find(const std::string& name) {
    const auto* begin = detail::kEmbeddedShaders;
    const auto* end = begin + detail::kEmbeddedShaderCount;
    const auto* it = std::lower_bound(begin, end, name, [](const detail::EmbeddedShader& s, const std::string& n) {
        return std::string_view(s.name) < n;
    });
    return (it != end && name == it->name) ? it : nullptr;
}
}  // namespace

std::string_view shader_source(const std::string& name) {
    if (const auto* s = find(name))
        return {reinterpret_cast<const char*>(s->data), s->size};
    throw std::runtime_error("no embedded shader named \"" + name + "\" (shaders are embedded from gpu/ at build time; "
                             "names are relative to gpu/, e.g. \"shaders/common.glsl\")");
}

std::vector<std::string> shader_names() {
    std::vector<std::string> names;
    names.reserve(detail::kEmbeddedShaderCount);
    for (std::size_t i = 0; i < detail::kEmbeddedShaderCount; ++i)
        names.emplace_back(detail::kEmbeddedShaders[i].name);
    return names;
}
}  // namespace mesolab::gpu
