#pragma once
// Many lights' images of the heightfield at once on the GPU (microgeom.device = gpu): the light
// solves of the virtual goniometer and the BTF export (core/microgeom/goniometer.h, btf.h), each
// exactly scatter() with one light (direct light with exact or ellipse shadows, K bounces of
// dependent-test scattering, no sky), in microgeom/lights.comp, a batch of lights per dispatch
// (one invocation per texel and light). The CPU code is the reference:
// tests/microgeom/lights_gpu_test.cpp checks the two agree.
#include "core/microgeom/scatter.h"
#include <cstddef>
#include <memory>
#include <string>

namespace mesolab::gpu {

// A LightSolver (core/microgeom/scatter.h) for these inputs and settings (S_i, normals, albedo,
// the curved base's weights and the ellipses uploaded once). Holds the compute scope (the shared
// context current, other users waiting) from construction to destruction, so make it where the
// solves happen and drop it after. S_i and the weights go up in chunks of directions of at most
// max_chunk_bytes (0: GL_MAX_SHADER_STORAGE_BLOCK_SIZE; gpu/microgeom/chunks.h). Throws
// std::runtime_error without OpenGL, or when one direction's texture alone exceeds that limit.
// shader_prelude: GLSL compiled in ahead of lights.comp's own (after its #version line) into a
// program of this solver's; empty: the shared program. The tests use it to make one driver do
// what another conformant one may, e.g. fuse multiply-adds as NVIDIA's compiler does.
std::unique_ptr<microgeom::LightSolver> make_gpu_light_solver(const Heightfield& hf, const microgeom::DirectionSet& dirs,
                                                              const microgeom::Visibility& vis, const microgeom::ScatterSettings& s,
                                                              size_t max_chunk_bytes = 0, const std::string& shader_prelude = "");
}  // namespace mesolab::gpu
