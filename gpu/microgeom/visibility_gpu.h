#pragma once
// Visibility textures S_i (microgeom, Heidrich et al. 2000 §3) computed on the GPU by the compute
// shader microgeom/visibility.comp: the same exact first hits as microgeom::compute_visibility
// (core/microgeom/visibility.h: same origin lift, kBelow/kNoHit rules, periodic wrap and reach
// cap, packing), walked in float instead of double. Results agree with the CPU except for rays
// that graze the surface within float rounding (see tests/microgeom/visibility_gpu_test.cpp for
// the measured agreement); hit points agree to well within the 1/16-texel packing.
//
// Needs a current OpenGL 4.3 core context (compute shaders, SSBOs); nothing beyond 4.3.
// Host work: per-texel normals and lifted origins, per-cell heights, the min/max pyramid and
// per-direction constants (all O(W H + N), in double as on the CPU), then one invocation per
// (texel, direction), dispatched in batches of directions.
#include "core/heightfield/heightfield.h"
#include "core/microgeom/directions.h"
#include "core/microgeom/visibility.h"
#include "gpu/gl.h"

namespace mesolab::gpu {

// The compiled program; keep one around to avoid recompiling for every field. Must be used and
// destroyed with the context it was created in current.
class VisibilityProgram {
public:
    VisibilityProgram();  // compiles microgeom/visibility.comp (throws std::runtime_error on failure)

    // All N textures, read back: same layout and encoding as microgeom::compute_visibility.
    // Throws std::invalid_argument for a heightfield whose h has the wrong size (as the CPU does).
    // keep_on_gpu: the result also keeps them in this context's buffers (Visibility::device, a
    // ResidentHits: gpu/microgeom/chunks.h) for the passes that read them next; only on the
    // compute context (gpu/context.h), where those passes run.
    microgeom::Visibility compute(const Heightfield& hf, const microgeom::DirectionSet& dirs, bool keep_on_gpu = false) const;

    // All N textures as a new R32UI GL_TEXTURE_2D_ARRAY (width x height x N, layer = direction,
    // nearest filtering), as gpu/microgeom/microgeom_pass.cpp uploads S_i, filled on the GPU with
    // no read-back. Empty (no texture) when W, H or N is 0. Throws std::runtime_error when N
    // exceeds GL_MAX_ARRAY_TEXTURE_LAYERS. Leaves the texture bound to GL_TEXTURE_2D_ARRAY on the
    // active unit restored to what it was.
    Texture compute_texture(const Heightfield& hf, const microgeom::DirectionSet& dirs) const;

    // How the directions are dispatched: at most `invocations` (texel, direction) pairs and
    // `batch_bytes` of output per dispatch, and `in_flight_bytes` of dispatched batches ahead of
    // their read-back (each in a buffer of its own). The defaults suit llvmpipe and hardware alike
    // (a hardware GPU holds ~2·10^5 invocations at once: 4M per dispatch keep it full); tests make
    // them small to reuse buffers.
    struct Batching {
        size_t invocations = size_t(1) << 22;
        size_t batch_bytes = size_t(64) << 20;
        size_t in_flight_bytes = size_t(256) << 20;
        size_t kept_chunk_bytes = 0;  // with keep_on_gpu: the kept copy's chunks (plan_direction_chunks; 0: the limit)
    };
    void set_batching(const Batching& b) { batching_ = b; }

private:
    Program program_;
    Batching batching_;
};

// Whether microgeom's S_i stage on the GPU (microgeom.device = gpu) keeps S_i on the compute
// context for the passes that read it next (VisibilityProgram::compute's keep_on_gpu).
// Automatic: on a hardware GPU, where the scattering and the light images then skip their upload
// of S_i over the host link; not on a renderer that runs on the CPU (llvmpipe), where the kept
// copy is as large again in the host's memory and costs about what the upload it saves costs.
enum class KeepOnGpu { Automatic, Always, Never };
void set_keep_visibility_on_gpu(KeepOnGpu k);
KeepOnGpu keep_visibility_on_gpu();

// Needs a current GL context. Same layout and encoding as microgeom::compute_visibility.
// Compiles the program for each call (~tens of ms on llvmpipe); use VisibilityProgram to reuse it.
microgeom::Visibility compute_visibility_gpu(const Heightfield& hf, const microgeom::DirectionSet& dirs);
}  // namespace mesolab::gpu
