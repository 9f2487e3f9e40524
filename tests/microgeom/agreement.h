#pragma once
// Shared by the microgeom GPU tests (frame agreement itself: support/frames.h).
#include "app/workbench.h"
#include "core/heightfield/heightfield.h"
#include "core/scene.h"
#include "core/render.h"
#include "gpu/context.h"
#include "support/cli.h"
#include "support/frames.h"

#include <gtest/gtest.h>
#include <cmath>
#include <initializer_list>
#include <string>
#include <stdexcept>

namespace mesolab::test {

// Whether the shared compute context (gpu/context.h) can be made: the GPU tests skip without it.
inline bool have_compute_gl() {
    try {
        gpu::ComputeScope scope;
        return true;
    } catch (const std::runtime_error&) {
        return false;
    }
}

// A procedural heightfield by name at res x res texels, periodic or not (default: the procedural default).
inline Heightfield procedural_field(const char* name, int res, bool periodic = ProceduralParams{}.periodic) {
    ProceduralParams p;
    p.name = name;
    p.resolution = res;
    Heightfield hf = make_procedural(p);
    hf.periodic = periodic;
    return hf;
}

// presets/microgeom/bricks-texture.json with `sets` applied, rendered on `backend` with
// microgeom.device = cpu and then = gpu (one Workbench: the second render recomputes what the
// device change invalidates).
struct DeviceRenders {
    RenderResult cpu, gpu;
};
inline DeviceRenders render_on_both_devices(std::initializer_list<const char*> sets, const std::string& backend) {
    Scene s = load_preset(source_path("presets/microgeom/bricks-texture.json"));
    for (const char* kv : sets) apply_set(s, kv);
    Workbench wb;
    RenderRequest req;
    req.renderer = backend;
    req.coverage = true;
    DeviceRenders r;
    r.cpu = wb.render(s, req);
    apply_set(s, "microgeom.device=gpu");
    r.gpu = wb.render(s, req);
    return r;
}

// Each stage ran in `r` and none fell back to the CPU ("... computed on the CPU ..." warnings).
inline void expect_ran_on_the_gpu(const RenderResult& r, const std::vector<StageName>& stages) {
    for (const StageName& stage : stages) {
        const StageRun* run = r.eval.run(stage);
        ASSERT_NE(run, nullptr) << stage;
        EXPECT_EQ(run->status, StageStatus::Ran) << stage;
        for (const std::string& w : run->warnings) EXPECT_EQ(w.find("computed on the CPU"), std::string::npos) << stage << ": " << w;
    }
}
}  // namespace mesolab::test
