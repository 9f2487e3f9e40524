#include "core/truth/renderer.h"
#include "core/error.h"
#include "core/truth/cache.h"

#include <algorithm>
#include <chrono>
#include <optional>

namespace mesolab {
namespace {
using Clock = std::chrono::steady_clock;
double ms_since(Clock::time_point t0) { return std::chrono::duration<double, std::milli>(Clock::now() - t0).count(); }

class TruthRenderer final : public Renderer {
public:
    explicit TruthRenderer(const RendererSetup& setup) : version_(setup.version), cache_(setup.truth_folder, setup.version) {}

    RenderResult render(Session& session, const Scene& s, const RenderRequest& req) override {
        RenderResult r;
        auto t0 = Clock::now();
        r.eval = session.evaluate(s, truth_stages(s), req.progress, req.cancel);  // only the physical description's stages
        r.stages_ms = ms_since(t0);
        const ivec2 size = frame_size(s, r.eval, {req.width, req.height});  // texture mode: the techniques' native size, as the real-time frame
        // The exact sums (radiance, its square, exitance, irradiance: 16 bytes a channel), the
        // normals and the frame's five AOVs.
        session.check_memory("a " + std::to_string(size.x) + "x" + std::to_string(size.y) + " truth",
                             {double(size.x) * double(size.y) * (4.0 * 3.0 * 16.0 + 3.0 * sizeof(float) + 15.0 * sizeof(float)), "its sums and 5 AOVs", {"--size"}});
        t0 = Clock::now();
        const TruthSettings& st = req.truth;
        check_truth_request(s, size.x, size.y, st, req.aovs);
        SampledRun run;
        run.key = truth_cache_key(version_, s, size.x, size.y, st.seed);
        std::optional<TruthAccumulator> from;
        if (!req.partial) {
            if (last_ && last_key_ == run.key) from = std::move(last_);
            else from = cache_.load(run.key);
            last_.reset();
        }
        const bool keep_file = from && from->spp > st.spp;  // a truth of more samples than asked stays on disk
        if (from && !from->continues(size.x, size.y, st.seed, st.first, st.spp)) from.reset();
        run.cached_spp = from ? from->spp : 0;
        const int held = run.cached_spp;

        // Keeps a finished truth: in memory (the next, larger request continues it) and on disk.
        auto keep = [&](const TruthAccumulator& a) {
            if (req.partial) return;
            if (a.spp != held && !keep_file) cache_.store(run.key, a);
            if (cache_.folder().empty()) {  // no disk: the next, larger request continues it from memory
                last_ = a;
                last_key_ = run.key;
            }
        };
        TruthAccumulator a;
        if (!req.on_pass || req.partial) {
            a = accumulate_truth(s, r.eval, size.x, size.y, st, from ? &*from : nullptr, req.progress, req.cancel);
            if (a.ended == TruthEnd::Cancelled) throw Cancelled();
        } else {
            // Passes of 1, 2, 4, ... samples: each doubles what the frame holds, up to the target
            // (or the noise target, or the time limit over all passes).
            const auto start = Clock::now();
            int spp = from ? from->spp : 0;
            if (from) {
                a = std::move(*from);
                req.on_pass(truth_frame(a), a.spp);
            }
            while (spp < st.spp) {
                TruthSettings pass = st;
                pass.spp = std::min(st.spp, std::max(1, 2 * spp));
                if (st.time_limit_s > 0.0) {
                    pass.time_limit_s = st.time_limit_s - std::chrono::duration<double>(Clock::now() - start).count();
                    if (pass.time_limit_s <= 0.0) {
                        a.ended = TruthEnd::TimeLimit;
                        break;
                    }
                }
                TruthAccumulator next = accumulate_truth(s, r.eval, size.x, size.y, pass, spp > 0 ? &a : nullptr, req.progress, req.cancel);
                if (next.ended == TruthEnd::Cancelled) {
                    if (spp > held) keep(a);  // the last finished pass stays
                    throw Cancelled();
                }
                a = std::move(next);
                spp = a.spp;
                req.on_pass(truth_frame(a), a.spp);
                if (a.ended != TruthEnd::Samples) break;
            }
        }
        keep(a);
        r.frame = truth_frame(a);
        r.render_ms = ms_since(t0);
        r.renderer = "truth";
        run.spp = a.samples();
        run.ended = a.ended;
        if (req.partial) run.sums = std::make_shared<const TruthAccumulator>(std::move(a));
        r.sampled = std::move(run);
        if (req.coverage) r.frame.coverage = frame_coverage(s, r.eval, size.x, size.y);
        return r;
    }
    std::string device() override { return "truth"; }

private:
    std::string version_;
    TruthCache cache_;
    std::optional<TruthAccumulator> last_;  // without a disk cache: the last truth rendered (not a partial one)
    std::string last_key_;
};

void check_truth_renderer_request(const Scene& s, const RenderRequest& r) {
    truth_stages(s);  // every object's technique has a truth
    for (const auto& a : r.aovs)
        if (std::find(truth_aovs().begin(), truth_aovs().end(), a) == truth_aovs().end())
            throw InputError("--aov " + a + ": the truth does not write it (it writes radiance, normal, truth_stderr, exitance, irradiance)");
}
}  // namespace

RendererDecl truth_renderer_decl() {
    return {"truth", "the Monte-Carlo truth of the explicit meso-geometry (--spp, --seed, --noise, --time-limit)", {true, false, false},
            [](const RendererSetup& setup) { return std::make_unique<TruthRenderer>(setup); }, check_truth_renderer_request};
}
}  // namespace mesolab
