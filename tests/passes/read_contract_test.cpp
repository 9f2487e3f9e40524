// The read contract beyond stages: a frame step (on its own thread and in tasks on TBB's worker
// threads, CPU and GPU paths) and a truth reading a key they do not declare are refused with an
// error naming them and the key (core/read_contract.h). The probe technique (probe.h) reads
// probe.blur where it does not declare it when told to.
#include "app/workbench.h"
#include "core/read_contract.h"
#include "core/scene_stages.h"
#include "core/truth/truth.h"
#include "passes/probe.h"

#include <gtest/gtest.h>
#include <stdexcept>
#include <string>

using namespace mesolab;
using namespace mesolab::test;

namespace {
struct SneakFor {
    explicit SneakFor(Sneak s) { g_sneak = s; }
    ~SneakFor() { g_sneak = Sneak::None; }
};

Scene probe_scene() {
    Scene s = default_scene("probe");
    apply_set(s, "geometry.resolution=16");
    apply_set(s, "probe.atlas_size=16");
    return s;
}

// The message of the std::logic_error `f` throws (empty when it throws none).
template <class F>
std::string refusal(F&& f) {
    try {
        f();
    } catch (const std::logic_error& e) {
        return e.what();
    } catch (const std::exception& e) {
        return std::string("another error: ") + e.what();
    }
    return {};
}
}  // namespace

TEST(ReadContract, IsCheckedInEveryTestRun) { EXPECT_TRUE(check_reads_by_default()) << "tests/CMakeLists.txt sets MESOLAB_CHECK_STAGE_READS=1"; }

TEST(ReadContract, AFrameStepReadingAnUndeclaredKeyIsRefusedOnBothPaths) {
    const Scene s = probe_scene();
    for (std::string b : {"cpu", "gpu"}) {
        SCOPED_TRACE(b == "cpu" ? "cpu" : "gpu");
        Workbench wb;
        RenderRequest req;
        req.renderer = b;
        req.width = req.height = 32;
        EXPECT_NO_THROW(wb.render(s, req)) << "declared reads pass";
        wb.forget_frame_steps();
        SneakFor sneak(Sneak::InStep);
        const std::string msg = refusal([&] { wb.render(s, req); });
        EXPECT_NE(msg.find("frame step probe.illumination read probe.blur"), std::string::npos) << msg;
    }
}

TEST(ReadContract, AFrameStepsReadOnTbbWorkerThreadsIsRefused) {
    const Scene s = probe_scene();
    Workbench wb;
    RenderRequest req;
    req.renderer = "cpu";
    req.width = req.height = 32;
    SneakFor sneak(Sneak::InStepWorkers);
    const std::string msg = refusal([&] { wb.render(s, req); });
    EXPECT_NE(msg.find("frame step probe.illumination read probe.blur"), std::string::npos)
        << "only tasks on other threads read the key: " << msg;
}

TEST(ReadContract, ATruthReadingAnUndeclaredKeyIsRefused) {
    const Scene s = probe_scene();
    Session session;
    const Evaluation ev = session.evaluate(s, truth_stages(s));
    TruthSettings st;
    st.spp = 1;
    EXPECT_NO_THROW(render_truth(s, ev, 16, 16, st)) << "declared reads pass";
    SneakFor sneak(Sneak::InTruth);
    const std::string msg = refusal([&] { render_truth(s, ev, 16, 16, st); });
    EXPECT_NE(msg.find("the truth read probe.blur"), std::string::npos) << msg;
}

TEST(ReadContract, TheTruthsKeyIsMadeOfWhatItDeclares) {
    // The same declaration the contract checks makes the truth's key: a declared key changes it,
    // an undeclared one (an accuracy knob) does not.
    const Scene s = probe_scene();
    Scene kd = s, blur = s;
    apply_set(kd, "probe.kd=0.5,0.5,0.5");
    apply_set(blur, "probe.blur=3");
    EXPECT_NE(truth_description(kd), truth_description(s));
    EXPECT_EQ(truth_description(blur), truth_description(s));
    bool kd_listed = false;
    for (const auto& [pattern, object] : truth_reads(s)) kd_listed = kd_listed || (pattern == "probe.kd" && object == 0);
    EXPECT_TRUE(kd_listed);
}
