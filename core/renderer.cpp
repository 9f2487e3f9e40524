#include "core/renderer.h"
#include "core/error.h"
#include "core/strings.h"
#include "core/truth/renderer.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>

namespace mesolab {

// [SECTION] The CPU reference
namespace {
using Clock = std::chrono::steady_clock;
double ms_since(Clock::time_point t0) { return std::chrono::duration<double, std::milli>(Clock::now() - t0).count(); }

class CpuRenderer final : public Renderer {
public:
    RenderResult render(Session& session, const Scene& s, const RenderRequest& req) override {
        RenderResult r;
        auto t0 = Clock::now();
        r.eval = session.evaluate_frame(s, req.progress, req.cancel);
        ProfilerBinding bind(session.profiler());
        r.stages_ms = ms_since(t0);
        const ivec2 size = frame_size(s, r.eval, {req.width, req.height});
        // The frame's images and the G-buffer (about 52 bytes a pixel) before allocating them.
        const auto layout = frame_layout(s, req.aovs);
        double per_pixel = 52.0;
        for (const auto& a : layout) per_pixel += double(a.channels) * sizeof(float);
        session.check_memory("a " + std::to_string(size.x) + "x" + std::to_string(size.y) + " frame",
                             {double(size.x) * double(size.y) * per_pixel, std::to_string(layout.size()) + " AOVs", {"--size", "the AOVs requested (--aov)"}});
        t0 = Clock::now();
        r.frame = render_cpu(s, r.eval, size.x, size.y, req.aovs, &steps_);
        r.render_ms = ms_since(t0);
        r.renderer = "cpu";
        if (req.coverage) r.frame.coverage = frame_coverage(s, r.eval, size.x, size.y);
        return r;
    }
    std::string device() override { return "cpu"; }
    void forget_frame_steps() override { steps_.forget(); }

private:
    FrameStepScheduler steps_;
};
}  // namespace

void check_realtime_request(const Scene& s, const RenderRequest& r) { frame_layout(s, r.aovs); }

// [SECTION] Registry
RendererRegistry::RendererRegistry() {
    add({"cpu", "the CPU reference of each technique's real-time frame", {false, true, false},
         [](const RendererSetup&) { return std::make_unique<CpuRenderer>(); }, check_realtime_request});
    add(truth_renderer_decl());
}

RendererRegistry& RendererRegistry::instance() {
    static RendererRegistry r;
    return r;
}

void RendererRegistry::add(RendererDecl d) {
    if (d.name.empty() || !d.make || !d.check) throw std::logic_error("RendererRegistry::add: a renderer needs a name, a factory and a check");
    for (auto& x : decls_)
        if (x->name == d.name) {
            *x = std::move(d);
            return;
        }
    // The GPU first: it is the command line's default.
    const bool first = d.traits.needs_gl;
    auto p = std::make_unique<RendererDecl>(std::move(d));
    decls_.insert(first ? decls_.begin() : decls_.end(), std::move(p));
}

const RendererDecl* RendererRegistry::get(const std::string& name) const {
    for (const auto& d : decls_)
        if (d->name == name) return d.get();
    return nullptr;
}

const RendererDecl& RendererRegistry::find(const std::string& name, const std::string& what) const {
    if (const RendererDecl* d = get(name)) return *d;
    throw InputError(what + ": '" + name + "' is not one of " + names_text());
}

std::vector<std::string> RendererRegistry::names() const {
    std::vector<std::string> n;
    for (const auto& d : decls_) n.push_back(d->name);
    return n;
}

std::string RendererRegistry::names_text() const { return join(names(), "|"); }

Renderer& Renderers::get(const std::string& name) {
    auto it = made_.find(name);
    if (it == made_.end()) it = made_.emplace(name, RendererRegistry::instance().find(name).make(setup_)).first;
    return *it->second;
}

void Renderers::for_each(const std::function<void(Renderer&)>& f) {
    for (auto& [name, r] : made_) f(*r);
}

void Renderers::set_setup(RendererSetup s) {
    setup_ = std::move(s);
    made_.clear();
}

// [SECTION] Comparison AOVs
const std::vector<ComparisonAov>& comparison_aovs() {
    static const std::vector<ComparisonAov> c = {{"truth_error", "truth", "Real-time radiance minus the truth's"}};
    return c;
}

const ComparisonAov& truth_error_aov() { return comparison_aovs().front(); }

const ComparisonAov* comparison_aov(const std::string& name) {
    for (const auto& c : comparison_aovs())
        if (name == c.name) return &c;
    return nullptr;
}

std::vector<std::string> rendered_aovs(const std::vector<std::string>& aovs) {
    std::vector<std::string> r;
    for (const auto& a : aovs)
        if (!comparison_aov(a)) r.push_back(a);
    return r;
}

namespace {
// The request as the renderer itself sees it: without comparison AOVs (radiance at least when
// only comparisons were asked for).
RenderRequest own_request(const RenderRequest& r) {
    RenderRequest own = r;
    own.aovs = rendered_aovs(r.aovs);
    if (own.aovs.empty() && !r.aovs.empty()) own.aovs = {"radiance"};
    return own;
}
}  // namespace

void check_render_request(const Scene& s, const RenderRequest& r) {
    const RendererDecl& d = RendererRegistry::instance().find(r.renderer);
    if (r.partial && !d.traits.sampled) {
        std::vector<std::string> sampled;
        for (const auto& name : RendererRegistry::instance().names())
            if (RendererRegistry::instance().get(name)->traits.sampled) sampled.push_back("--backend " + name);
        throw InputError("--samples: a partial render needs " + join(sampled, " or ") + " (a renderer that samples), not --backend " + r.renderer);
    }
    for (const auto& a : r.aovs)
        if (const ComparisonAov* c = comparison_aov(a)) {
            if (r.renderer == c->reference || d.traits.sampled)
                throw InputError("--aov " + a + ": compares a real-time frame with the " + c->reference + "; --backend " + r.renderer + " is itself a reference");
            RenderRequest ref;
            ref.renderer = c->reference;
            ref.aovs = {"radiance"};
            RendererRegistry::instance().find(c->reference).check(s, ref);
        }
    d.check(s, own_request(r));
}

RenderResult render_frame(Session& session, Renderers& renderers, const Scene& s, const RenderRequest& req) {
    std::vector<const ComparisonAov*> comparisons;
    for (const auto& a : req.aovs)
        if (const ComparisonAov* c = comparison_aov(a)) comparisons.push_back(c);
    if (comparisons.empty()) return renderers.get(req.renderer).render(session, s, req);
    const RendererDecl& d = RendererRegistry::instance().find(req.renderer);
    if (d.traits.sampled) throw InputError("--aov " + std::string(comparisons.front()->name) + ": --backend " + req.renderer + " is itself a reference");
    RenderResult r = renderers.get(req.renderer).render(session, s, own_request(req));
    for (const ComparisonAov* c : comparisons) {
        RenderRequest tr = req;
        tr.renderer = c->reference;
        tr.width = r.frame.width, tr.height = r.frame.height;  // texture mode: the native size the frame was rendered at
        tr.aovs = {"truth_stderr"};
        tr.coverage = false;
        tr.partial = false;
        const RenderResult t = renderers.get(c->reference).render(session, s, tr);
        r.truth = compare_to_truth(r.frame, t.frame, req.truth);
        r.truth->spp = t.sampled ? t.sampled->spp : 0;
        r.truth_frame = t.frame;
        r.truth_run = t.sampled;
        r.truth_ms = t.render_ms;
        r.frame.layout.push_back({c->name, 3, c->help});
        r.frame.aovs[c->name] = r.truth->error;
    }
    return r;
}

// [SECTION] Truth sampling
TruthSettings truth_sampling(std::optional<int> spp, double noise, double time_limit_s, uint64_t seed, const TruthOptionNames& names) {
    TruthSettings st;
    st.noise = noise;
    st.time_limit_s = time_limit_s;
    st.seed = seed;
    // With a noise target or a time limit, spp bounds the samples only when it is given.
    st.spp = spp ? *spp : (noise > 0.0 || time_limit_s > 0.0) ? std::numeric_limits<int>::max() / 2 : 64;
    check_truth_settings(st, names);
    return st;
}
}  // namespace mesolab
