#pragma once
// [SECTION] The GPU as a renderer (core/renderer.h): the GPU render path (gpu/renderer.h) in a
// headless OpenGL context (EGL, gpu/context.h) made on first use, its frame read back. The
// window draws its viewport with its own context and gpu::Renderer instead (app/gui/viewport.h).
#include "core/renderer.h"

namespace mesolab::gpu {
class Renderer;

// Registers the renderer "gpu" (idempotent); main() and the workbench call it.
void install_headless_renderer();
// The GPU render path of a headless renderer made by the registry (its GL context current):
// for tests and tools that look inside it (attachments, batches, resources).
Renderer& headless_internals(mesolab::Renderer& r);
}  // namespace mesolab::gpu
