#pragma once
// [SECTION] The truth as a renderer (core/renderer.h): the Monte-Carlo truth of the explicit
// meso-geometry (core/truth/truth.h) behind the same interface as the cpu and gpu renderers.
// It evaluates only the stages of the scene's physical description (truth_stages), continues
// what it holds (on disk: the truth cache, core/truth/cache.h; without one, its last truth in
// memory) when asked for more samples of the same truth, keeps what it rendered, and renders
// progressively
// (RenderRequest::on_pass: passes of 1, 2, 4, ... samples per pixel, each continuing the last,
// the same bytes as one render of as many). A cancelled render keeps the last finished pass.
#include "core/renderer.h"

namespace mesolab {
RendererDecl truth_renderer_decl();
}  // namespace mesolab
