// mesolab frontier: the accuracy-time frontier of a scene's methods against one truth per viewing
// distance (app/api.h, FrontierOptions).
#include "app/api.h"
#include "app/commands.h"
#include "app/plot.h"
#include "app/plot_text.h"
#include "core/error.h"
#include "core/file.h"
#include "core/image.h"
#include "core/profile.h"
#include "core/renderer.h"
#include "core/scene.h"
#include "core/strings.h"
#include "core/technique.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <numeric>
#include <sstream>
#include <atomic>
#include <thread>

namespace fs = std::filesystem;

namespace mesolab {
namespace {

// [SECTION] Knobs
struct AccuracyKnob {
    std::string key;
    const ParamDecl* decl = nullptr;
    double value = 0;  // the preset's
};

// Every numeric accuracy knob the scene uses: its techniques' (TECHNIQUE.*) and its geometry's.
std::vector<AccuracyKnob> accuracy_knobs(const Scene& s) {
    std::vector<AccuracyKnob> r;
    std::vector<std::string> groups = {"geometry"};
    for (const auto& o : s.objects) groups.push_back(o.technique);
    for (const std::string& key : public_keys(s)) {
        // TECHNIQUE.* of the scene's techniques and geometry.* (the same parameters addressed per object are left out)
        if (std::find(groups.begin(), groups.end(), key.substr(0, key.find('.'))) == groups.end()) continue;
        const ParamDecl& d = decl_of(s, key);
        if (d.accuracy == Accuracy::None || (d.type != ParamType::Int && d.type != ParamType::Float)) continue;
        try {
            check_set_used(s, key);
        } catch (const InputError&) {
            continue;  // not used with these settings (e.g. geometry.resolution of a mesh)
        }
        const Value v = get_public_value(s, key);
        const double x = d.type == ParamType::Int ? double(std::get<int64_t>(v)) : std::get<double>(v);
        if (std::find_if(r.begin(), r.end(), [&](const AccuracyKnob& k) { return k.key == key; }) == r.end()) r.push_back({key, &d, x});
    }
    return r;
}

// An integer setting within the knob's range, odd where the knob takes only odd values (a kernel
// width), the nearest power of two (in log2) where it takes only those (a texture's size).
std::string int_setting(const AccuracyKnob& k, double x, double hi) {
    int64_t n = std::max<int64_t>(int64_t(std::llround(x)), int64_t(std::ceil(k.decl->min)));
    if (k.decl->odd_only && n % 2 == 0) n += double(n + 1) <= hi ? 1 : -1;
    if (k.decl->pow2_only) {
        n = int64_t(1) << int(std::lround(std::log2(std::max(1.0, x))));
        while (double(n) > hi && n > 1) n /= 2;
        while (double(n) < k.decl->min) n *= 2;
    }
    return std::to_string(n);
}

// The knob's setting `f` times more accurate than the preset's (f < 1: cheaper), within its range
// and no further than its converged setting; as preset text.
std::string knob_value(const AccuracyKnob& k, double f) {
    const ParamDecl& d = *k.decl;
    double x = d.accuracy == Accuracy::Higher ? k.value * f : k.value / f;
    if (k.value == 0.0 && d.accuracy == Accuracy::Lower) x = f >= 1.0 ? 0.0 : 1e-4 / f;  // a threshold at 0: coarser is a small positive one
    double hi = d.max, lo = d.min;
    if (d.reference) {
        const double ref = d.type == ParamType::Int ? double(std::get<int64_t>(*d.reference)) : std::get<double>(*d.reference);
        if (d.accuracy == Accuracy::Higher) hi = std::min(hi, std::max(ref, k.value));
        else lo = std::max(lo, std::min(ref, k.value));
    }
    x = std::clamp(x, lo, hi);
    if (d.type == ParamType::Int) return int_setting(k, x, hi);
    return strprintf("%.6g", x);
}

// [SECTION] Methods
// One way of computing the scene: `<technique>.method` set for each of its techniques.
struct MethodChoice {
    std::string label;  // the methods, "+"-joined in object order ("heidrich", "pom")
    std::vector<std::pair<std::string, std::string>> sets;  // TECHNIQUE.method, VALUE
};

std::string method_label(const Scene& s) {
    std::vector<std::string> m;
    for (const auto& o : s.objects) {
        const Technique* t = Registry::instance().technique(o.technique);
        const std::string name = t && !t->paper_method().empty() ? o.material.get_string("method") : o.technique;
        if (std::find(m.begin(), m.end(), name) == m.end()) m.push_back(name);
    }
    return join(m, "+");
}

// The scene's own methods first, then, for each of its techniques with other methods, each other
// method with the rest as the scene has them.
std::vector<MethodChoice> method_choices(const Scene& base) {
    std::vector<const Technique*> techniques;
    for (const auto& o : base.objects) {
        const Technique* t = Registry::instance().technique(o.technique);
        if (t && !t->paper_method().empty() && std::find(techniques.begin(), techniques.end(), t) == techniques.end()) techniques.push_back(t);
    }
    std::vector<MethodChoice> r{{method_label(base), {}}};
    for (const Technique* t : techniques) {
        const std::string key = t->name() + ".method", current = get_public(base, key);
        r.front().sets.emplace_back(key, current);
        for (const std::string& m : t->method_names()) {
            if (m == current) continue;
            Scene s = base;
            apply_set(s, key, m);
            MethodChoice c{method_label(s), {}};
            for (const Technique* u : techniques) c.sets.emplace_back(u->name() + ".method", u == t ? m : get_public(base, u->name() + ".method"));
            r.push_back(std::move(c));
        }
    }
    return r;
}
}  // namespace

// [SECTION] The frontier
void mark_frontier(std::vector<FrontierPoint>& points) {
    std::map<double, std::vector<size_t>> by_distance;
    for (size_t i = 0; i < points.size(); ++i) by_distance[points[i].distance].push_back(i);
    for (auto& [d, idx] : by_distance) {
        std::sort(idx.begin(), idx.end(), [&](size_t a, size_t b) {
            return points[a].frame_ms != points[b].frame_ms ? points[a].frame_ms < points[b].frame_ms : points[a].rmse_rel < points[b].rmse_rel;
        });
        double best = std::numeric_limits<double>::infinity();
        for (size_t i : idx) {
            points[i].on_frontier = points[i].rmse_rel < best;
            best = std::min(best, points[i].rmse_rel);
        }
    }
}

namespace {
// The scene's methods, and each method's accuracy knobs (with the method's keys set).
struct MethodKnobs {
    std::vector<MethodChoice> methods;
    std::vector<std::vector<AccuracyKnob>> knobs_of;  // per method
    size_t index(const std::string& label) const {
        for (size_t i = 0; i < methods.size(); ++i)
            if (methods[i].label == label) return i;
        throw InputError("frontier: this scene has no method " + label + " (its methods: " + [&] {
            std::vector<std::string> n;
            for (const auto& m : methods) n.push_back(m.label);
            return join(n, ", ");
        }() + ")");
    }
    std::vector<std::pair<std::string, std::string>> all(size_t mi, const std::vector<std::pair<std::string, std::string>>& values) const {
        std::vector<std::pair<std::string, std::string>> r = methods[mi].sets;
        r.insert(r.end(), values.begin(), values.end());
        return r;
    }
};

MethodKnobs method_knobs(const Scene& base) {
    MethodKnobs r;
    r.methods = method_choices(base);
    for (const MethodChoice& m : r.methods) {
        Scene sm = base;
        for (const auto& [k, v] : m.sets) apply_set(sm, k, v);
        r.knobs_of.push_back(accuracy_knobs(sm));
    }
    return r;
}

std::vector<double> frontier_distances(const Scene& base, const FrontierOptions& o) {
    if (o.distances.empty()) return {std::get<double>(get_public_value(base, "camera.distance"))};
    return o.distances;
}
}  // namespace

std::vector<FrontierSetting> frontier_settings(const Scene& base, const FrontierOptions& o) {
    if (o.width < 1 || o.height < 1 || o.width > 16384 || o.height > 16384)
        throw InputError("--size: " + std::to_string(o.width) + "x" + std::to_string(o.height) + " is out of range (1..16384 per side)");
    if (o.repeat < 1 || o.repeat > 100) throw InputError("--repeat: " + std::to_string(o.repeat) + " is out of range [1, 100]");
    if (!(o.budget_s >= 0.0)) throw InputError("--budget: expected minutes, 0 or more");
    const RendererDecl& renderer = RendererRegistry::instance().find(o.backend);
    if (!renderer.traits.realtime) throw InputError("--backend " + o.backend + ": the frontier times a real-time renderer (" + [] {
        std::vector<std::string> n;
        for (const auto& name : RendererRegistry::instance().names())
            if (RendererRegistry::instance().get(name)->traits.realtime) n.push_back(name);
        return join(n, ", ");
    }() + ") against the truth");
    truth_stages(base);  // every technique of the scene has a truth
    if (!o.distances.empty() && get_public(base, "camera.mode") != "orbit")
        throw InputError("--distance: moves an orbit camera; this scene's camera.mode is " + get_public(base, "camera.mode"));

    // Per method: its settings, most informative first: the preset, the diagonal, then each knob
    // alone. The methods take turns, so that a budget cuts them alike.
    const MethodKnobs mk = method_knobs(base);
    std::vector<std::vector<FrontierSetting>> per_method(mk.methods.size());
    for (size_t mi = 0; mi < mk.methods.size(); ++mi) {
        const std::vector<AccuracyKnob>& knobs = mk.knobs_of[mi];
        if (knobs.empty() && mi == 0)
            throw InputError((o.source.empty() ? base.name : o.source) + ": the scene uses no accuracy knob (none to trade against time)");
        std::vector<FrontierSetting>& settings = per_method[mi];
        const std::string& label = mk.methods[mi].label;
        std::vector<std::pair<std::string, std::string>> preset;
        for (const auto& k : knobs) preset.emplace_back(k.key, knob_value(k, 1.0));
        settings.push_back({label, "preset", mk.all(mi, preset)});
        for (double f : {0.25, 0.5, 2.0, 4.0}) {
            std::vector<std::pair<std::string, std::string>> values;
            for (const auto& k : knobs) values.emplace_back(k.key, knob_value(k, f));
            if (values != preset) settings.push_back({label, "all x" + strprintf("%g", f), mk.all(mi, values)});
        }
        for (size_t i = 0; i < knobs.size(); ++i)
            for (double f : {0.25, 0.5, 2.0, 4.0}) {
                std::vector<std::pair<std::string, std::string>> values = preset;
                values[i].second = knob_value(knobs[i], f);
                FrontierSetting st{label, knobs[i].key + "=" + values[i].second, mk.all(mi, values)};
                const bool seen = std::any_of(settings.begin(), settings.end(), [&](const FrontierSetting& x) { return x.settings == st.settings; });
                if (!seen) settings.push_back(st);
            }
        Scene sm = base;
        for (const auto& [k, v] : mk.methods[mi].sets) apply_set(sm, k, v);
        for (const auto& st : settings) {  // every value checked before any work
            Scene probe = sm;
            for (const auto& [k, v] : st.settings) apply_set(probe, k, v);
        }
    }
    std::vector<FrontierSetting> settings;
    for (size_t i = 0;; ++i) {
        bool any = false;
        for (const auto& list : per_method)
            if (i < list.size()) settings.push_back(list[i]), any = true;
        if (!any) break;
    }
    return settings;
}

std::vector<FrontierSetting> frontier_between(const Scene& base, const std::vector<FrontierPoint>& here) {
    // Between two neighbours on a method's frontier, every knob at the geometric mean of their
    // values (once; a setting already measured is not measured again).
    const MethodKnobs mk = method_knobs(base);
    const auto knob_of = [](const FrontierPoint& p, const std::string& key) {
        for (const auto& [k, v] : p.settings)
            if (k == key) return std::stod(v);
        throw InputError("frontier: the point " + p.method + " " + p.varied + " has no setting of " + key);
    };
    std::vector<FrontierSetting> between;
    for (size_t mi = 0; mi < mk.methods.size(); ++mi) {
        std::vector<FrontierPoint> mine;
        for (const auto& p : here)
            if (p.method == mk.methods[mi].label) mine.push_back(p);
        mark_frontier(mine);
        std::vector<const FrontierPoint*> front;
        for (const auto& p : mine)
            if (p.on_frontier) front.push_back(&p);
        std::sort(front.begin(), front.end(), [](auto* x, auto* y) { return x->frame_ms < y->frame_ms; });
        const std::vector<AccuracyKnob>& knobs = mk.knobs_of[mi];
        for (size_t i = 1; i < front.size(); ++i) {
            std::vector<std::pair<std::string, std::string>> values;
            for (const AccuracyKnob& k : knobs) {
                const double x = knob_of(*front[i - 1], k.key), y = knob_of(*front[i], k.key);
                const double mid = x > 0.0 && y > 0.0 ? std::sqrt(x * y) : 0.5 * (x + y);
                values.emplace_back(k.key, k.decl->type == ParamType::Int ? int_setting(k, mid, k.decl->max) : strprintf("%.6g", mid));
            }
            FrontierSetting st{mk.methods[mi].label, "between " + front[i - 1]->varied + " and " + front[i]->varied, mk.all(mi, values)};
            const bool seen = std::any_of(here.begin(), here.end(), [&](const FrontierPoint& p) { return p.settings == st.settings; }) ||
                              std::any_of(between.begin(), between.end(), [&](const FrontierSetting& x) { return x.settings == st.settings; });
            if (!seen) between.push_back(st);
        }
    }
    return between;
}

FrontierMeasurement frontier_measure(Workbench& wb, const Scene& base, const FrontierOptions& o, double d, const FrontierSetting& st,
                                     FrontierTruths& truths, const std::function<bool()>& budget_over) {
    FrontierMeasurement m;
    if (o.cancel && o.cancel->load()) throw Cancelled();
    const bool preset = st.preset();
    if (!preset && budget_over && budget_over()) {
        m.stopped = true;
        return m;
    }
    Scene s = base;
    if (!o.distances.empty()) apply_set(s, "camera.distance", strprintf("%.9g", d));
    for (const auto& [k, v] : st.settings) apply_set(s, k, v);
    const std::string what = st.method + " " + st.varied;
    // A setting still running when the budget ends is stopped (the preset is always measured).
    std::atomic<bool> stop{false};
    std::jthread watch([&](std::stop_token done_token) {
        while (!done_token.stop_requested()) {
            if ((o.cancel && o.cancel->load()) || (!preset && budget_over && budget_over())) {
                stop = true;
                return;
            }
            std::this_thread::sleep_for(std::chrono::milliseconds(20));
        }
    });
    RenderRequest req;
    req.renderer = o.backend;
    req.width = o.width, req.height = o.height;
    req.aovs = {"radiance"};
    req.cancel = &stop;
    // Its precomputation from a cold cache, read from nowhere.
    if (wb.session().store()) throw std::logic_error("frontier_measure: the workbench's stage store is set; set it aside to time the precomputation");
    wb.session().cache().clear();
    wb.forget_frame_steps();
    RenderResult r;
    try {
        r = wb.render(s, req);
    } catch (const Cancelled&) {
        if (o.cancel && o.cancel->load()) throw;
        m.stopped = true;  // stopped by the budget: not measured
        return m;
    } catch (const InputError& e) {
        // A combination a stage refuses (e.g. an even kernel width): said, and the run goes on.
        if (preset) throw;
        m.skipped = what + ": " + e.what();
        if (!o.quiet) std::fprintf(stderr, "  d=%-6g %-36s not a valid setting: %s\n", d, what.c_str(), e.what());
        return m;
    }
    watch.request_stop();
    req.cancel = o.cancel;  // measured: its frames and its truth finish
    FrontierPoint p;
    p.distance = d;
    p.method = st.method;
    p.settings = st.settings;
    p.varied = st.varied;
    p.precompute_ms = r.stages_ms;
    std::vector<double> frames;
    for (int i = 0; i < o.repeat; ++i) {
        if (o.cancel && o.cancel->load()) throw Cancelled();
        wb.forget_frame_steps();  // a frame's steps are part of its time
        r = wb.render(s, req);
        frames.push_back(r.render_ms);
    }
    p.frame_ms = median_of(frames);
    // The truth of what this setting's scene describes, at the frame's size (texture mode: its native size).
    const std::string tkey = truth_description(s) + "@" + std::to_string(r.frame.width) + "x" + std::to_string(r.frame.height);
    auto it = truths.frames.find(tkey);
    if (it == truths.frames.end()) {
        RenderRequest tr;
        tr.renderer = truth_error_aov().reference;
        tr.width = r.frame.width, tr.height = r.frame.height;
        tr.truth = o.truth;
        tr.aovs = {"truth_stderr"};
        tr.cancel = o.cancel;
        it = truths.frames.emplace(tkey, wb.render(s, tr).frame).first;
    }
    m.truth_noise = truth_noise_rel(it->second);
    const TruthComparison c = compare_to_truth(r.frame, it->second, o.truth);
    p.rmse_rel = c.rmse_rel;
    p.below_noise = c.below_noise;
    if (!o.quiet)
        std::fprintf(stderr, "  d=%-6g %-36s frame %9.3f ms  precompute %9.1f ms  rmse_rel %.4f%s\n", d, what.c_str(), p.frame_ms, p.precompute_ms,
                     p.rmse_rel, p.below_noise ? " (below the truth's noise)" : "");
    m.point = std::move(p);
    return m;
}

FrontierResult frontier_scene(const Scene& base, const FrontierOptions& o, bool write_files) {
    using Clock = std::chrono::steady_clock;
    const std::vector<FrontierSetting> settings = frontier_settings(base, o);
    if (write_files) plot_font();
    const std::vector<double> distances = frontier_distances(base, o);
    FrontierResult res;
    Workbench wb;
    wb.session().set_memory_limit(o.memory_limit);
    const RendererDecl& renderer = RendererRegistry::instance().find(o.backend);
    res.machine = cpu_model() + ", " + std::to_string(std::thread::hardware_concurrency()) + " threads" +
                  (renderer.traits.needs_gl ? "; GL: " + wb.renderer(o.backend).device() : "");
    const size_t total = distances.size() * settings.size();
    size_t done = 0;
    for (double d : distances) {
        FrontierTruths truths;
        double noise = 0;
        const size_t first = res.points.size();
        // The budget is shared evenly by the distances; a distance's clock starts with it.
        const auto deadline = Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(o.budget_s / double(distances.size())));
        const auto budget_over = [&] { return Clock::now() > deadline; };
        const auto measure = [&](const FrontierSetting& st) {
            if (o.progress) o.progress("frontier d=" + strprintf("%g", d) + ": " + st.method + " " + st.varied, std::min(1.0, double(done) / double(total)));
            FrontierMeasurement m = frontier_measure(wb, base, o, d, st, truths, budget_over);
            if (m.stopped) res.budget_reached = true;
            if (!m.skipped.empty()) res.skipped.push_back(m.skipped);
            if (m.point) {
                noise = std::max(noise, m.truth_noise);
                res.points.push_back(*m.point);
                if (o.on_point) o.on_point(*m.point);
            }
        };
        for (const FrontierSetting& st : settings) measure(st), ++done;
        const std::vector<FrontierPoint> here(res.points.begin() + std::ptrdiff_t(first), res.points.end());
        for (const FrontierSetting& st : frontier_between(base, here)) measure(st);
        res.truth_noise.push_back(noise);
    }
    return frontier_report(base, o, std::move(res), write_files);
}

FrontierResult frontier_report(const Scene& base, const FrontierOptions& o, FrontierResult partial, bool write_files) {
    FrontierResult res = std::move(partial);
    const std::vector<double> distances = frontier_distances(base, o);
    if (res.truth_noise.size() != distances.size())
        throw InputError("frontier: " + std::to_string(res.truth_noise.size()) + " truth noise values for " + std::to_string(distances.size()) + " distances");
    const MethodKnobs mk = method_knobs(base);
    const std::vector<MethodChoice>& methods = mk.methods;
    res.scene = base.name;
    res.backend = o.backend;
    res.distances = distances;
    res.knobs.clear();
    for (const auto& m : methods)
        for (const auto& [k, v] : m.sets)
            if (std::find(res.knobs.begin(), res.knobs.end(), k) == res.knobs.end()) res.knobs.push_back(k);
    for (const auto& knobs : mk.knobs_of)
        for (const auto& k : knobs)
            if (std::find(res.knobs.begin(), res.knobs.end(), k.key) == res.knobs.end()) res.knobs.push_back(k.key);
    for (const FrontierPoint& p : res.points) {
        mk.index(p.method);  // a point of this scene's methods
        if (std::find(distances.begin(), distances.end(), p.distance) == distances.end())
            throw InputError("frontier: a point at distance " + strprintf("%g", p.distance) + ", not one of the frontier's");
    }
    mark_frontier(res.points);
    if (write_files) plot_font();

    // [SECTION] Outputs
    std::ostringstream md, csv;
    md << "Frontier of `" << base.name << "` (" << o.backend << ", " << o.width << "x" << o.height << "; " << res.machine << "): for each method, each accuracy knob ("
       << join(res.knobs, ", ") << ") on a coarse grid around the preset and all of them together, then between neighbours on the method's frontier; frame time the median of " << o.repeat
       << " frames with the stages cached, precomputation the stages from a cold cache; error `rmse_rel` against the truth (" << o.truth.seed
       << " seed). ★: on the frontier (no point as fast or faster has a lower error).";
    if (res.budget_reached) md << " The budget ended the run before every setting was measured.";
    for (const auto& k : res.skipped) md << " Not a valid setting, left out: " << k << ".";
    md << "\n\n| distance | method | setting | frame (ms) | precompute (ms) | rmse_rel | |\n|---|---|---|---|---|---|---|\n";
    csv << "distance,method,setting," << join(res.knobs, ",") << ",frame_ms,precompute_ms,rmse_rel,below_noise,on_frontier\n";
    json j;
    j["scene"] = base.name, j["machine"] = res.machine, j["backend"] = o.backend, j["size"] = json::array({o.width, o.height});
    j["knobs"] = res.knobs, j["distances"] = distances, j["truth_noise_rel"] = res.truth_noise, j["budget_reached"] = res.budget_reached;
    j["skipped"] = res.skipped;
    j["points"] = json::array();
    for (const auto& p : res.points) {
        md << "| " << strprintf("%g", p.distance) << " | " << p.method << " | `" << p.varied << "` | " << strprintf("%.3f", p.frame_ms) << " | "
           << strprintf("%.1f", p.precompute_ms) << " | " << (p.below_noise ? strprintf("below the noise (%.4f)", p.rmse_rel) : strprintf("%.4f", p.rmse_rel))
           << " | " << (p.on_frontier ? "★" : "") << " |\n";
        csv << p.distance << "," << p.method << ",\"" << p.varied << "\"";
        json x{{"distance", p.distance}, {"method", p.method}, {"setting", p.varied}, {"frame_ms", p.frame_ms}, {"precompute_ms", p.precompute_ms},
               {"rmse_rel", p.rmse_rel}, {"below_noise", p.below_noise}, {"on_frontier", p.on_frontier}};
        json knobs_json = json::object();
        for (const auto& [k, v] : p.settings) knobs_json[k] = v;
        for (const std::string& key : res.knobs) {  // a column per knob of any method, empty where this method has none
            const auto it = std::find_if(p.settings.begin(), p.settings.end(), [&](const auto& kv) { return kv.first == key; });
            csv << "," << (it == p.settings.end() ? std::string() : it->second);
        }
        x["knobs"] = knobs_json;
        j["points"].push_back(x);
        csv << "," << p.frame_ms << "," << p.precompute_ms << "," << p.rmse_rel << "," << (p.below_noise ? "true" : "false") << ","
            << (p.on_frontier ? "true" : "false") << "\n";
    }
    res.markdown = md.str();
    if (write_files) {
        fs::create_directories(o.out_dir);
        const std::string stem = (fs::path(o.out_dir) / (base.name + ".frontier")).string();
        write_text_atomic(stem + ".md", res.markdown);
        write_text_atomic(stem + ".csv", csv.str());
        write_text_atomic(stem + ".json", j.dump(2) + "\n");
        res.written = {stem + ".md", stem + ".csv", stem + ".json"};
        for (size_t di = 0; di < distances.size(); ++di) {
            const double d = distances[di];
            PlotSpec plot;
            plot.title = "accuracy against time: " + base.name + " at distance " + strprintf("%g", d) + " (" + o.backend + ")";
            plot.xlabel = "frame time, stages cached (ms)";
            plot.ylabel = "relative RMSE vs the truth";
            // One colour per method.
            std::vector<PlotSeries> per_method;
            for (const auto& m : methods) per_method.push_back({m.label, {}, {}, {}, false});
            PlotSeries below{"below the truth's noise", {}, {}, {}, false}, front{"frontier", {}, {}, {}, true};
            std::vector<const FrontierPoint*> fp;
            double lo = 1e300, hi = 0;
            for (const auto& p : res.points) {
                if (p.distance != d) continue;
                const auto mi = size_t(std::find_if(methods.begin(), methods.end(), [&](const MethodChoice& m) { return m.label == p.method; }) - methods.begin());
                PlotSeries& s = p.below_noise ? below : per_method.at(mi);
                s.x.push_back(p.frame_ms), s.y.push_back(p.rmse_rel), s.point_labels.push_back(p.varied == "preset" ? "preset" : "");
                if (p.on_frontier) fp.push_back(&p);
                lo = std::min(lo, p.frame_ms), hi = std::max(hi, p.frame_ms);
            }
            std::sort(fp.begin(), fp.end(), [](auto* a, auto* b) { return a->frame_ms < b->frame_ms; });
            for (auto* p : fp) front.x.push_back(p->frame_ms), front.y.push_back(p->rmse_rel), front.point_labels.push_back("");
            plot.series.clear();  // the frontier last of the points: drawn over them
            for (auto& m : per_method)
                if (!m.x.empty()) plot.series.push_back(std::move(m));
            if (!below.x.empty()) plot.series.push_back(below);
            plot.series.push_back(front);
            if (hi > 0) plot.series.push_back({"truth's noise floor (2 noise_rel)", {lo, hi}, {2.0 * res.truth_noise[di], 2.0 * res.truth_noise[di]}, {}});
            const std::string ps = stem + (distances.size() > 1 ? ".d" + strprintf("%g", d) : std::string());
            write_png_srgb(ps + ".png", render_plot(plot));
            write_text_atomic(ps + ".svg", render_plot_svg(plot));
            res.written.push_back(ps + ".png");
            res.written.push_back(ps + ".svg");
        }
    }
    return res;
}

// [SECTION] The command
int run_frontier(const FrontierCommand& c) {
    Scene base = load_preset(c.preset);
    apply_sets(base, c.sets);
    FrontierOptions o;
    parse_size(c.size, o.width, o.height);
    o.backend = c.backend;
    o.distances = c.distances;
    o.truth = truth_sampling(c.spp, c.spp_given, c.noise, c.time_limit, c.seed);
    if (!(c.budget_min >= 0.0)) throw InputError("--budget " + strprintf("%g", c.budget_min) + ": expected minutes, 0 or more");
    o.budget_s = c.budget_min * 60.0;
    o.repeat = c.repeat;
    o.memory_limit = memory_limit_bytes(c.memory_limit);
    o.out_dir = c.out_dir;
    o.source = c.preset;
    const FrontierResult r = frontier_scene(base, o, true);
    std::printf("%s\nwrote", r.markdown.c_str());
    for (size_t i = 0; i < r.written.size(); ++i) std::printf("%s %s", i ? "," : "", r.written[i].c_str());
    std::printf("\n");
    return 0;
}
}  // namespace mesolab
