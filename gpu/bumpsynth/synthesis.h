#pragma once
// The uniforms of gpu/bumpsynth/synthesis.glsl (a pixel's look-up-table inputs and entry), set from
// the CPU's synthesis of an object, so that the shader computes the CPU's bits (bumpsynth.frag and
// the test shader shaders/test/bumpsynth_inputs.comp).
#include "core/bumpsynth/brdf.h"
#include "gpu/gl.h"

namespace mesolab::gpu {

// GL objects of the synthesis: the resampled input CDFs (storage buffer, binding 0), the noise
// texture and the index texture (0 where the synthesis has none).
struct SynthesisObjects {
    GLuint cdf = 0, noise = 0, index = 0;
};
// Sets the uniforms of `prog` (in use) for `syn`; binds the noise texture to texture unit
// `noise_unit` and the index texture to `index_unit`.
void set_synthesis_uniforms(const Program& prog, const bumpsynth::Synthesis& syn, const SynthesisObjects& objects, int noise_unit, int index_unit);
}  // namespace mesolab::gpu
