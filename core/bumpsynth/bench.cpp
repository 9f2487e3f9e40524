// Technique bumpsynth: its timing tables (Kautz 2001, §6).
#include "core/bumpsynth/stages.h"
#include "core/bumpsynth/technique.h"

#include <cstdio>

namespace mesolab::bumpsynth {

// Kautz et al. 2001, §6: the paper's frame time, about 30 Hz (its only timing).
constexpr double kPaperFrameMs = 33.0;

std::vector<BenchTable> BumpsynthTechnique::bench_tables() const {
    auto scene = [](const char* geometry, std::vector<std::pair<const char*, const char*>> extra) {
        return [=] {
            Scene s = default_scene("bumpsynth");
            s.name = std::string("bumpsynth-") + geometry;
            apply_set(s, "geometry.type", geometry);
            apply_set(s, "bumpsynth.alpha_x", "0.1");
            apply_set(s, "bumpsynth.alpha_y", "0.4");
            apply_set(s, "bumpsynth.rotation", "30");
            for (const auto& [k, v] : extra) apply_set(s, k, v);
            return s;
        };
    };
    BenchTable pre;
    pre.name = "bumpsynth";
    pre.title = "Kautz et al. 2001: NDF tabulation, look-up table and noise CDFs (anisotropic Beckmann 0.1 x 0.4, 30 degrees)";
    pre.paper_machine = "the paper gives no precomputation times (\"done once for every NDF in a preprocessing step\")";
    pre.columns = {{"NDF", stages::ndf}, {"LUT L(r1, r2)", stages::lut}, {"noise CDFs G_1..G_8", stages::noise_cdf},
                   {"Smith table", stages::masking}};
    for (const char* size : {"64", "128", "256", "512", "1024"})
        pre.rows.push_back({std::string("LUT ") + size + "^2, NDF 128^2", scene("sphere", {{"bumpsynth.lut_size", size}, {"bumpsynth.masking", "true"}}), {}});
    pre.rows.push_back({"LUT 256^2, NDF 512^2", scene("sphere", {{"bumpsynth.ndf_resolution", "512"}, {"bumpsynth.masking", "true"}}), {}});

    BenchTable frame;
    frame.name = "bumpsynth-frame";
    frame.title = "Kautz et al. 2001, §6 / Fig. 5: frame time at 1280x720 (teapot: ~17,000 triangles in the paper)";
    frame.paper_machine = "AMD Athlon 1 GHz + NVIDIA GeForce 3 (about 30 Hz = " + std::to_string(int(kPaperFrameMs)) + " ms)";
    frame.columns = {{"frame 1280x720", {}, 1280, 720, true, true}};
    // The teapot at 16,384 triangles (the paper's ~17,000) filling the frame; detail_distance puts
    // the camera at full detail (8 octaves) or beyond it (NDF only).
    const auto teapot = [&](std::vector<std::pair<const char*, const char*>> extra) {
        extra.insert(extra.begin(), {{"geometry.resolution", "128"}, {"camera.distance", "3.4"}, {"bumpsynth.noise_frequency", "48"}, {"bumpsynth.detail_distance", "1000"}});
        return scene("teapot", extra);
    };
    frame.rows = {{"teapot, procedural noise, 8 octaves", teapot({}), {kPaperFrameMs}},
                  {"teapot, noise texture (the paper's path)", teapot({{"bumpsynth.noise", "texture"}}), {kPaperFrameMs}},
                  {"teapot, far (NDF only)", teapot({{"bumpsynth.detail_distance", "1"}}), {}},
                  {"teapot, masking + Fresnel", teapot({{"bumpsynth.masking", "true"}, {"bumpsynth.fresnel", "true"}}), {}}};
    return {pre, frame};
}
}  // namespace mesolab::bumpsynth
