// The truth's timing table (`mesolab bench truth`): for every preset the truth can render, a pilot
// truth, the samples and time it needs for 1% noise, and the real-time default's error against it.
#include "core/bench.h"
#include "core/error.h"
#include "core/render.h"
#include "core/session.h"
#include "core/strings.h"
#include "core/technique.h"
#include "core/truth/truth.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <limits>
#include <map>
#include <memory>

namespace mesolab {
namespace {
constexpr int kSize = 512, kPilotSpp = 32;

// One preset's measurements, made once for the row's three columns.
struct TruthRow {
    double ms = 0, sampling_ms = 0, noise = 0, rmse_rel = 0;  // ms: the whole truth; sampling_ms: its samples alone
    int spp = 0, spp_1pct = 0;
    bool below_noise = false;
    TruthEnd ended = TruthEnd::Samples;
};

// A pilot of kPilotSpp samples (noise = 0), or samples until `noise` or the time limit.
TruthRow measure(const Scene& s, double noise, double time_limit_s) {
    Session session;
    const auto t0 = std::chrono::steady_clock::now();
    const Evaluation ev = session.evaluate(s, truth_stages(s));
    TruthSettings st;
    st.spp = kPilotSpp;
    if (noise > 0.0) st.spp = std::numeric_limits<int>::max() / 2, st.noise = noise, st.time_limit_s = time_limit_s;
    const ivec2 size = frame_size(s, ev, {kSize, kSize});  // texture mode: the native size
    const TruthAccumulator a = accumulate_truth(s, ev, size.x, size.y, st);
    const Frame truth = truth_frame(a);
    TruthRow r;
    r.ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    r.sampling_ms = 1000.0 * a.seconds;
    r.noise = truth_noise_rel(truth);
    r.spp = a.samples();
    r.ended = a.ended;
    r.spp_1pct = int(std::ceil(double(r.spp) * (r.noise / 0.01) * (r.noise / 0.01)));
    const Evaluation fev = session.evaluate_frame(s);
    const TruthComparison c = compare_to_truth(render_cpu(s, fev, size.x, size.y), truth, st);
    r.rmse_rel = c.rmse_rel, r.below_noise = c.below_noise;
    return r;
}

std::string seconds(double ms) { return ms >= 1000.0 ? strprintf("%.3g s", ms / 1000.0) : strprintf("%.3g ms", ms); }
}  // namespace

BenchTable truth_bench_table(double noise, double time_limit_s) {
    BenchTable t;
    t.name = noise > 0.0 ? "truth-noise" : "truth";  // the pages' block: the extrapolated table and the measured one are both kept
    const std::string target = strprintf("%g%%", 100.0 * noise);
    t.title = noise > 0.0 ? "The truth: time to " + target + " noise per preset, measured (path tracer on the CPU, " + std::to_string(kSize) + "x" +
                                std::to_string(kSize) + "; texture mode at the texture's size; at most " + seconds(1000.0 * time_limit_s) + " each)"
                          : "The truth: time to 1% noise per preset (path tracer on the CPU, " + std::to_string(kSize) + "x" + std::to_string(kSize) +
                                "; texture mode at the texture's size)";
    // Rows measured once for the three columns (the bench calls a row's columns in order).
    auto rows = std::make_shared<std::map<std::string, TruthRow>>();
    auto row_of = [rows, noise, time_limit_s](const Scene& s) -> const TruthRow& {
        auto it = rows->find(s.name);
        if (it == rows->end()) it = rows->emplace(s.name, measure(s, noise, time_limit_s)).first;
        return it->second;
    };
    if (noise > 0.0) {
        BenchColumn reached;
        reached.name = "time to " + target + " noise (measured)";
        reached.info = [row_of, noise](const Scene& s, const Evaluation&) {
            const TruthRow& r = row_of(s);
            if (r.ended == TruthEnd::Noise) return seconds(r.ms);
            return "not reached in " + seconds(r.ms) + ": " + strprintf("%.2f%%", 100.0 * r.noise) + " (about " +
                   seconds(r.ms - r.sampling_ms + r.sampling_ms * (r.noise / noise) * (r.noise / noise)) + " to " + strprintf("%g%%", 100.0 * noise) +
                   ", extrapolated)";
        };
        BenchColumn samples;
        samples.name = "samples (noise_rel)";
        samples.info = [row_of](const Scene& s, const Evaluation&) {
            const TruthRow& r = row_of(s);
            return std::to_string(r.spp) + " spp (" + strprintf("%.2f%%", 100.0 * r.noise) + ")";
        };
        BenchColumn err;
        err.name = "default's error (rmse_rel vs that truth)";
        err.info = [row_of](const Scene& s, const Evaluation&) {
            const TruthRow& r = row_of(s);
            return r.below_noise ? "below the noise (" + strprintf("%.2f%%", 100.0 * r.rmse_rel) + " ≤ 2 × noise)" : strprintf("%.2f%%", 100.0 * r.rmse_rel);
        };
        t.columns = {reached, samples, err};
    } else {
        BenchColumn pilot;
        pilot.name = "pilot: " + std::to_string(kPilotSpp) + " spp (time, noise_rel)";
        pilot.info = [row_of](const Scene& s, const Evaluation&) {
            const TruthRow& r = row_of(s);
            return seconds(r.ms) + ", " + strprintf("%.2f%%", 100.0 * r.noise);
        };
        BenchColumn one;
        one.name = "1% noise (spp, time; extrapolated)";
        one.info = [row_of](const Scene& s, const Evaluation&) {
            const TruthRow& r = row_of(s);
            if (r.spp_1pct <= kPilotSpp) return std::to_string(kPilotSpp) + " spp or fewer, " + seconds(r.ms);
            // What is paid once (the stages, the ray tracer's build) once; the samples in proportion.
            return std::to_string(r.spp_1pct) + " spp, " + seconds(r.ms - r.sampling_ms + r.sampling_ms * double(r.spp_1pct) / kPilotSpp);
        };
        BenchColumn err;
        err.name = "default's error (rmse_rel vs the pilot)";
        err.info = [row_of](const Scene& s, const Evaluation&) {
            const TruthRow& r = row_of(s);
            return r.below_noise ? "below the noise (" + strprintf("%.2f%%", 100.0 * r.rmse_rel) + " ≤ 2 × noise)" : strprintf("%.2f%%", 100.0 * r.rmse_rel);
        };
        t.columns = {pilot, one, err};
    }
    // Every preset whose objects all have a truth.
    namespace fs = std::filesystem;
    std::vector<fs::path> files;
    std::error_code ec;
    for (const auto& e : fs::recursive_directory_iterator(fs::path(MESOLAB_SOURCE_DIR) / "presets", ec))
        if (e.is_regular_file() && e.path().extension() == ".json") files.push_back(e.path());
    std::sort(files.begin(), files.end());
    for (const fs::path& f : files) {
        Scene s;
        try {
            s = load_preset(f.string());
        } catch (const std::exception&) {
            continue;  // not a preset (a mesh's metadata, say)
        }
        if (s.objects.empty()) continue;
        const bool all_truth = std::all_of(s.objects.begin(), s.objects.end(), [](const SceneObject& o) {
            const Technique* tech = Registry::instance().technique(o.technique);
            return tech && tech->truth().has_value();
        });
        if (!all_truth) continue;
        const std::string path = f.string();
        t.rows.push_back({f.parent_path().filename().string() + "/" + f.stem().string(), [path] { return load_preset(path); }, {}});
    }
    return t;
}
}  // namespace mesolab
