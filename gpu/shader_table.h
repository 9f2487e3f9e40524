#pragma once
// Internal: the table of embedded shader files. The definitions are generated at build time by
// gpu/embed_shaders.cmake (one generated .cpp per target that calls mesolab_embed_shaders());
// shaders.cpp is the only reader. Everything is constant-initialised, so shader_source() is safe
// to call during static initialisation of other translation units.
#include <cstddef>

namespace mesolab::gpu::detail {

struct EmbeddedShader {
    const char* name;           // path relative to the base dir, '/' separated ("shaders/common.glsl")
    const unsigned char* data;  // file bytes followed by one extra '\0' (not counted in size)
    std::size_t size;           // byte size of the file
};

// Sorted by name. kEmbeddedShaderCount may be 0 (then kEmbeddedShaders points at a dummy entry).
extern const EmbeddedShader kEmbeddedShaders[];
extern const std::size_t kEmbeddedShaderCount;
}  // namespace mesolab::gpu::detail
