#pragma once
// A test technique, `probe`, registered in this test executable only: it exercises the
// render-pass contract the way translucency will, with two frame steps (offscreen work before the
// frame) on the CPU and the GPU:
//   probe.illumination  the lights' irradiance at each texel of the object's (u,v) square, drawn in
//                       texture space into an atlas_size^2 target (reads light.*, scene.geometry)
//   probe.blurred       a (2 blur + 1)^2 box filter of that map (a compute dispatch on the GPU)
// and a frame that shades radiance = kd / pi * the blurred map at the pixel's texel, with an AOV
// `texel` holding the texel's (x, y), so that CPU and GPU can be compared texel for texel.
#include "core/technique.h"

#include <atomic>

namespace mesolab::test {
// Registers `probe` with the registry and its GPU pass; call before the registry is first used
// (the test executable does it from a static initialiser).
bool register_probe();

// What the probe reads besides its declarations, to show the read contract refusing it
// (tests/passes/read_contract_test.cpp): none, probe.blur in the illumination step (on the
// step's thread, or only in tasks on TBB's worker threads), or probe.blur in its truth's object.
enum class Sneak { None, InStep, InStepWorkers, InTruth };
extern std::atomic<Sneak> g_sneak;
}  // namespace mesolab::test
