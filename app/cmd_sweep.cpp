// mesolab sweep: accuracy vs time for one knob against a reference setting, measured by the radiance
// RMSE against the reference rendering (default) or a technique's metric (--metric, Technique::sweep_metrics).
#include "core/strings.h"
#include "core/file.h"
#include "app/commands.h"
#include "app/workbench.h"
#include "core/error.h"
#include "core/image.h"
#include "app/plot.h"
#include "core/profile.h"
#include "core/scene.h"
#include "app/plot_text.h"
#include "core/technique.h"
#include "core/truth/truth.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <optional>
#include <set>
#include <sstream>

namespace fs = std::filesystem;

namespace mesolab {
namespace {

constexpr const char* kDefaultMetric = "rmse";
constexpr const char* kTruthMetric = "truth";

// Root-mean-square difference of the radiance AOVs.
double rmse(const Image& a, const Image& b) {
    double sum = 0;
    for (size_t i = 0; i < a.data.size(); ++i) {
        const double d = double(a.data[i]) - double(b.data[i]);
        sum += d * d;
    }
    return std::sqrt(sum / double(std::max<size_t>(1, a.data.size())));
}

double mean(const Image& a) {
    double sum = 0;
    for (float v : a.data) sum += v;
    return sum / double(std::max<size_t>(1, a.data.size()));
}

// Numeric ordering of knob values for "most accurate".
double as_number(const ParamDecl& d, const std::string& text) {
    const Value v = value_from_text(d, text, "--knob " + d.name);
    if (auto* i = std::get_if<int64_t>(&v)) return double(*i);
    if (auto* f = std::get_if<double>(&v)) return *f;
    return 0;
}

// [SECTION] Metrics
std::vector<SweepMetricDecl> technique_metrics() {
    std::vector<SweepMetricDecl> r;
    for (const Technique* t : Registry::instance().techniques())
        for (auto& m : t->sweep_metrics()) r.push_back(std::move(m));
    return r;
}

// The technique metric named `name`, or none for the default radiance RMSE; InputError naming the value otherwise.
std::optional<SweepMetricDecl> find_metric(const std::string& name) {
    if (name == kDefaultMetric || name == kTruthMetric) return std::nullopt;
    std::vector<std::string> known{kDefaultMetric, kTruthMetric};
    for (auto& m : technique_metrics()) {
        if (m.name == name) return m;
        known.push_back(m.name);
    }
    const std::string near = nearest_key(name, known);
    throw InputError("--metric: unknown metric '" + name + "'" + (near.empty() ? "" : " (did you mean '" + near + "'?)") + "; known: " + sweep_metric_names());
}

// [SECTION] Knob and reference
struct Knob {
    std::string key;
    std::vector<std::string> values;
    const ParamDecl* decl = nullptr;
    std::vector<std::string> stages;  // the stages whose cache key changes with the knob's value
};

// The stages a knob controls: those whose cache key differs between two of its values.
std::vector<std::string> knob_stages(const Scene& base, const Knob& k) {
    const StageGraph& g = Registry::instance().stages();
    std::vector<std::string> r;
    for (const StageDecl& d : g.stages()) {
        std::set<std::vector<uint64_t>> keys;  // the stage's keys over its objects, per value
        for (const auto& v : k.values) {
            Scene s = base;
            apply_set(s, k.key, v);
            std::vector<uint64_t> per_object;
            for (int o : g.subjects(s, d)) per_object.push_back(g.key(s, d.name, o));
            keys.insert(per_object);
        }
        if (keys.size() > 1) r.push_back(d.name);
    }
    return r;
}

// Checks the knob's key and every value before any work.
Knob check_knob(const Scene& base, const SweepKnob& in, const char* option) {
    if (in.key.empty() || in.values.empty())
        throw InputError(std::string(option) + " expects a key and its values (KEY=V1,V2,..., e.g. geometry.resolution=8,16,32), got '" + in.key + "' with " +
                         std::to_string(in.values.size()) + " values");
    Knob k{in.key, in.values, nullptr, {}};
    k.decl = &decl_of(base, k.key);
    for (const auto& v : k.values) {
        Scene probe = base;
        apply_set(probe, k.key, v);  // validates every value before any work
        check_set_used(probe, k.key);
    }
    k.stages = knob_stages(base, k);
    return k;
}

// The reference's settings: --reference settings, else the knob's declared reference, else its most accurate value.
std::vector<std::pair<std::string, std::string>> reference_settings(const Knob& k, const std::vector<std::pair<std::string, std::string>>& settings) {
    const ParamDecl& decl = *k.decl;
    if (!settings.empty()) return settings;
    if (decl.reference) return {{k.key, value_to_text(decl, *decl.reference)}};
    if (decl.accuracy != Accuracy::None && (decl.type == ParamType::Int || decl.type == ParamType::Float)) {
        std::string best = k.values.front();
        for (const auto& v : k.values) {
            const bool better = decl.accuracy == Accuracy::Higher ? as_number(decl, v) > as_number(decl, best) : as_number(decl, v) < as_number(decl, best);
            if (better) best = v;
        }
        return {{k.key, best}};
    }
    throw InputError("--knob " + k.key + ": this parameter declares no most-accurate setting; give one with --reference KEY=VALUE");
}

// The reference scene, and its settings as text ("KEY=VALUE, ...").
Scene reference_scene(const Scene& base, const Knob& k, const std::vector<std::pair<std::string, std::string>>& settings, std::string& text) {
    Scene ref = base;
    for (const auto& [key, value] : reference_settings(k, settings)) {
        apply_set(ref, key, value);
        text += (text.empty() ? "" : ", ") + key + "=" + value;
    }
    return ref;
}

// [SECTION] Measuring
using Point = SweepPoint;

double stages_ms(const Evaluation& ev, const std::vector<std::string>& names) {
    double ms = 0;
    for (const StageRun& r : ev.runs)
        if (r.status == StageStatus::Ran && std::find(names.begin(), names.end(), r.name) != names.end()) ms += r.ms;
    return ms;
}

// The error of one setting against the reference: the radiance RMSE (and relative RMSE), or the technique metric's.
struct Measure {
    std::optional<SweepMetricDecl> metric;
    SweepMeasure technique;
    Image reference;
    double ref_mean = 0;
    // --metric truth: the truth of each physical description met (one for a sweep over accuracy
    // knobs; --by over a physical key needs one per value), its settings and render times.
    bool vs_truth = false;
    TruthSettings truth_settings;
    std::map<std::string, Frame> truths;
    double truth_noise = 0, truth_ms = 0;
    int truth_cached_spp = 0, truth_spp = 0;
    const std::atomic<bool>* cancel = nullptr;
    bool quiet = false;

    // Truths are kept by description and size: in texture mode a knob may change the native size
    // (bumpsynth's noise texture), and each size has its own truth.
    static std::string truth_key(const std::string& d, int w, int h) { return d + "@" + std::to_string(w) + "x" + std::to_string(h); }
    const Frame& truth_of(Workbench& wb, const Scene& s, int w, int h) {
        const std::string d = truth_description(s);
        if (auto it = truths.find(truth_key(d, w, h)); it != truths.end()) return it->second;
        RenderRequest tr;
        tr.renderer = truth_error_aov().reference;
        tr.width = w, tr.height = h;
        tr.truth = truth_settings;
        tr.aovs = {"truth_stderr"};
        tr.cancel = cancel;
        if (!quiet)
            tr.progress = [](const std::string& stage, double f) {
                if (stage.rfind("truth", 0) == 0) std::fprintf(stderr, "\r  %-72s %3d%%", stage.c_str(), int(100.0 * f + 0.5));
            };
        RenderResult r = wb.render(s, tr);
        const std::string k = truth_key(d, r.frame.width, r.frame.height);  // texture mode: the native size, not w x h
        if (auto it = truths.find(k); it != truths.end()) return it->second;
        const SampledRun& run = *r.sampled;
        if (!quiet)
            std::fprintf(stderr, "\r  truth: %d spp (%d from the cache), noise_rel %.4f, %.0f ms, ended by %s%30s\n", run.spp, run.cached_spp,
                         truth_noise_rel(r.frame), r.render_ms, to_string(run.ended), "");
        truth_noise = std::max(truth_noise, truth_noise_rel(r.frame));
        truth_ms += r.render_ms;
        truth_cached_spp = run.cached_spp;
        truth_spp = std::max(truth_spp, run.spp);
        return truths.emplace(k, std::move(r.frame)).first->second;
    }

    void prepare(const Scene& ref, RenderResult& rr) {
        if (metric) {
            technique = metric->prepare(ref, rr.eval);
        } else {
            reference = std::move(rr.frame.aov("radiance"));
            ref_mean = mean(reference);
        }
    }
    Point measure(Workbench& wb, const Scene& s, const std::string& key, const std::string& v, RenderResult& res) {
        if (metric) return {v, 0, technique.error(s, res.eval), 0, 0, false, ""};
        if (vs_truth) {
            const TruthComparison c = compare_to_truth(res.frame, truth_of(wb, s, res.frame.width, res.frame.height), truth_settings);
            Point p{v, 0, c.rmse_rel, c.rmse_rel, 0, false, ""};
            p.below_noise = c.below_noise;
            return p;
        }
        const Image& img = res.frame.aov("radiance");
        if (img.width != reference.width || img.height != reference.height)
            throw InputError("--knob " + key + "=" + v + ": the frame size changed (" + std::to_string(img.width) + "x" + std::to_string(img.height) +
                             "), so it cannot be compared with the reference");
        const double e = rmse(img, reference);
        return {v, 0, e, ref_mean > 0 ? e / ref_mean : 0, 0, false, ""};
    }
};

Point sweep_point(Workbench& wb, const Scene& base, const Knob& k, const std::string& v, const RenderRequest& req, int repeat, Measure& m) {
    Scene s = base;
    apply_set(s, k.key, v);
    std::vector<double> times, knob_times;
    RenderResult res = wb.render(s, req);  // untimed warm-up: first-touch allocations, GPU resources
    for (int r = 0; r < repeat; ++r) {
        if (req.cancel && req.cancel->load()) throw Cancelled();
        wb.session().cache().clear();  // the cost of this setting includes its stages
        res = wb.render(s, req);
        times.push_back(res.stages_ms + res.render_ms);
        knob_times.push_back(stages_ms(res.eval, k.stages));
    }
    Point p = m.measure(wb, s, k.key, v, res);
    p.ms = median_of(times);
    p.knob_ms = median_of(knob_times);
    return p;
}

// [SECTION] Outputs: CSV, Markdown, PNG and SVG plot
struct Report {
    std::string csv, md;
    PlotSpec plot;
};

std::string header_md(const SweepOptions& o, const Scene& base, const Knob& k, const std::string& ref_text, int w, int h, const Measure& m) {
    std::ostringstream md;
    if (m.vs_truth) {
        md << "Sweep of `" << k.key << "`" << (o.by.key.empty() ? "" : " by `" + o.by.key + "`") << " on `" << base.name << "` (" << o.backend << ", " << w
           << "x" << h << ", median of " << o.repeat << " cold-cache runs) against the truth (" << m.truth_spp << " spp, seed " << m.truth_settings.seed
           << ", noise_rel " << strprintf("%.4f", m.truth_noise) << "). Error: `rmse_rel`, the RMS of the real-time radiance minus the truth's over the object's "
              "pixels, over the truth's mean there; an error within twice the truth's noise is reported as unresolved, not as a number.\n\n| "
           << k.key << (o.by.key.empty() ? "" : " | " + o.by.key) << " | time (ms) | rmse_rel vs truth |\n|---|" << (o.by.key.empty() ? "" : "---|")
           << "---|---|\n";
        return md.str();
    }
    md << "Sweep of `" << k.key << "` on `" << base.name << "` (" << o.backend << ", " << w << "x" << h << ", median of " << o.repeat
       << " cold-cache runs); reference " << ref_text << ".";
    if (m.metric) {
        std::string names;
        for (const auto& st : k.stages) names += (names.empty() ? "" : ", ") + st;
        md << " Time: the frame's stages from a cold cache plus the frame; of which the stages the knob changes ("
           << (names.empty() ? "none" : names + "; the plot's time axis") << "). Error: `" << m.metric->name << "`, " << m.metric->help << " (" << m.metric->unit
           << ").\n\n| " << k.key << " | time (ms) | of which knob's stages (ms) | " << m.metric->label << " |\n|---|---|---|---|\n";
    } else
        md << "\n\n| " << k.key << " | time (ms) | RMSE | relative RMSE |\n|---|---|---|---|\n";
    return md.str();
}

Report report(const SweepOptions& o, const Scene& base, const Knob& k, const std::string& ref_text, int w, int h, const Measure& m,
              const std::vector<Point>& points) {
    std::ostringstream csv, md;
    md << header_md(o, base, k, ref_text, w, h, m);
    if (m.vs_truth) {
        csv << "value,by,time_ms,rmse_rel,below_noise\n";
        Report r;
        r.plot.title = "error vs time against the truth: " + k.key + (o.by.key.empty() ? "" : " by " + o.by.key) + " (" + base.name + ")";
        r.plot.xlabel = "time per frame incl. stages, cold cache (ms)";
        r.plot.ylabel = "relative RMSE vs the truth";
        double lo = 1e300, hi = 0;
        for (const auto& p : points) {
            csv << p.value << "," << p.by << "," << p.ms << "," << p.rel << "," << (p.below_noise ? "true" : "false") << "\n";
            md << "| " << p.value << (o.by.key.empty() ? "" : " | " + p.by) << " | " << strprintf("%.3f", p.ms) << " | "
               << (p.below_noise ? strprintf("below the noise (%.2e)", p.rel) : strprintf("%.3e", p.rel)) << " |\n";
            if (r.plot.series.empty() || r.plot.series.back().label != (o.by.key.empty() ? k.key : o.by.key + "=" + p.by))
                r.plot.series.push_back({o.by.key.empty() ? k.key : o.by.key + "=" + p.by, {}, {}, {}});
            PlotSeries& sr = r.plot.series.back();
            sr.x.push_back(p.ms), sr.y.push_back(p.rel), sr.point_labels.push_back(p.value);
            lo = std::min(lo, p.ms), hi = std::max(hi, p.ms);
        }
        if (hi > 0) r.plot.series.push_back({"truth's noise floor (2 noise_rel)", {lo, hi}, {2.0 * m.truth_noise, 2.0 * m.truth_noise}, {}});
        md << "\nThe truth took " << strprintf("%.1f s", m.truth_ms / 1000.0) << (m.truth_cached_spp ? " (read from the truth cache)" : "") << ".\n";
        r.csv = csv.str(), r.md = md.str();
        return r;
    }
    csv << (m.metric ? "value,time_ms,knob_stages_ms," + m.metric->name + "\n" : "value,time_ms,rmse,relative_rmse\n");
    // A technique metric is plotted against the time of the stages the knob changes (when there are
    // any): the whole frame's time is dominated by what every setting shares.
    const bool knob_time = m.metric && !k.stages.empty();
    PlotSeries series;
    series.label = k.key;
    for (const auto& p : points) {
        char line[256];
        if (m.metric) {
            csv << p.value << "," << p.ms << "," << p.knob_ms << "," << p.err << "\n";
            std::snprintf(line, sizeof line, "| %s | %.3f | %.3f | %.3e |\n", p.value.c_str(), p.ms, p.knob_ms, p.err);
        } else {
            csv << p.value << "," << p.ms << "," << p.err << "," << p.rel << "\n";
            std::snprintf(line, sizeof line, "| %s | %.3f | %.3e | %.3e |\n", p.value.c_str(), p.ms, p.err, p.rel);
        }
        md << line;
        series.x.push_back(knob_time ? p.knob_ms : p.ms);
        series.y.push_back(p.err);
        series.point_labels.push_back(p.value);
    }
    if (m.metric && !m.technique.notes.empty()) md << "\n" << m.technique.notes;
    Report r{csv.str(), md.str(), {}};
    r.plot.title = "error vs time: " + k.key + " (" + base.name + ")";
    r.plot.xlabel = knob_time ? "time of the knob's stages, cold cache (ms)" : "time per frame incl. stages (ms)";
    r.plot.ylabel = (m.metric ? m.metric->label : std::string("RMSE")) + " vs reference";
    r.plot.series.push_back(series);
    const auto [lo, hi] = std::minmax_element(series.x.begin(), series.x.end());
    for (const auto& [label, value] : m.metric ? m.technique.levels : std::vector<std::pair<std::string, double>>{})
        if (lo != series.x.end()) r.plot.series.push_back({label, {*lo, *hi}, {value, value}, {}});
    return r;
}
}  // namespace

std::string sweep_metric_names() {
    std::string r = std::string(kDefaultMetric) + " (default: radiance RMSE against the reference rendering), " + kTruthMetric +
                    " (relative RMSE against the truth, --backend truth's path tracer, --spp and --seed)";
    for (const auto& m : technique_metrics()) r += ", " + m.name;
    return r;
}

namespace {
// KEY=V1,V2,... as the command line gives a knob.
SweepKnob knob_text(const std::string& text, const char* option) {
    const auto eq = text.find('=');
    if (eq == std::string::npos || eq == 0 || eq + 1 == text.size())
        throw InputError(std::string(option) + " expects KEY=V1,V2,... (e.g. geometry.resolution=8,16,32), got '" + text + "'");
    return {text.substr(0, eq), split(text.substr(eq + 1), ',')};
}
}  // namespace

int run_sweep(const SweepCommand& c) {
    Scene base = load_preset(c.preset);
    apply_sets(base, c.sets);
    SweepOptions o;
    o.knob = knob_text(c.knob, "--knob");
    if (!c.by.empty()) o.by = knob_text(c.by, "--by");
    for (const auto& r : c.reference) {
        const auto eq = r.find('=');
        if (eq == std::string::npos || eq == 0) throw InputError("--reference expects KEY=VALUE, got '" + r + "'");
        o.reference.emplace_back(r.substr(0, eq), r.substr(eq + 1));
    }
    parse_size(c.size, o.width, o.height);
    o.backend = c.backend;
    o.repeat = c.repeat;
    o.metric = c.metric;
    o.truth = truth_sampling(c.spp, c.spp_given, c.noise, c.time_limit, c.seed);
    o.memory_limit = memory_limit_bytes(c.memory_limit);
    o.out_dir = c.out_dir;
    o.source = c.preset;
    const SweepResult r = sweep_scene(base, o, true);
    std::printf("%s", r.markdown.c_str());
    std::printf("\nwrote");
    for (size_t i = 0; i < r.written.size(); ++i) std::printf("%s %s", i ? "," : "", r.written[i].c_str());
    std::printf("\n");
    return 0;
}

SweepResult sweep_scene(const Scene& base, const SweepOptions& o, bool write_files) {
    const int w = o.width, h = o.height;
    if (w < 1 || h < 1 || w > 16384 || h > 16384) throw InputError("--size: " + std::to_string(w) + "x" + std::to_string(h) + " is out of range (1..16384 per side)");
    if (o.repeat < 1 || o.repeat > 100) throw InputError("--repeat: " + std::to_string(o.repeat) + " is out of range [1, 100]");
    if (write_files) plot_font();  // the plot's font (fonts-dejavu-core): an error now rather than after the measurements
    Measure m;
    m.cancel = o.cancel;
    m.quiet = o.quiet;
    m.metric = find_metric(o.metric);
    if (m.metric) {
        try {
            m.metric->check(base);
        } catch (const InputError& e) {
            throw InputError("--metric " + m.metric->name + ": " + (o.source.empty() ? base.name : o.source) + ": " + e.what());
        }
    }
    m.vs_truth = o.metric == kTruthMetric;
    if (!o.by.key.empty() && !m.vs_truth) throw InputError("--by: a sweep over two knobs measures against the truth; add --metric truth");
    m.truth_settings = o.truth;
    const Knob k = check_knob(base, o.knob, "--knob");
    std::optional<Knob> by;
    if (!o.by.key.empty()) {
        by = check_knob(base, o.by, "--by");
        if (by->key == k.key) throw InputError("--by " + by->key + ": the same key as --knob");
    }
    std::string ref_text = m.vs_truth ? "the truth" : "";

    std::optional<Workbench> own;
    Workbench& wb = o.workbench ? *o.workbench : own.emplace();
    if (wb.session().store()) throw std::logic_error("sweep_scene: the workbench's stage store is set; set it aside to time from a cold cache");
    if (!o.workbench || o.memory_limit) wb.session().set_memory_limit(o.memory_limit);
    RenderRequest req;
    req.aovs = {"radiance"};
    req.renderer = o.backend;
    req.width = w;
    req.height = h;
    req.cancel = o.cancel;
    const RendererDecl& renderer = RendererRegistry::instance().find(req.renderer);
    if (m.vs_truth && renderer.traits.sampled)
        throw InputError("--metric truth: compares a real-time backend (cpu or gpu) with the truth; --backend " + req.renderer +
                         " measures against a reference of its own with --metric rmse");
    req.truth = m.truth_settings;
    if (!m.vs_truth) {
        const Scene ref = reference_scene(base, k, o.reference, ref_text);
        if (!o.quiet) std::fprintf(stderr, "reference: %s\n", ref_text.c_str());
        RenderResult rr = wb.render(ref, req);
        m.prepare(ref, rr);
    }

    std::vector<Point> points;
    const size_t total = (by ? by->values.size() : 1) * k.values.size();
    const std::string err_name = m.metric ? m.metric->name : m.vs_truth ? "rmse_rel" : "rmse";
    for (const std::string& b : by ? by->values : std::vector<std::string>{""}) {
        Scene sb = base;
        if (by) apply_set(sb, by->key, b);
        if (m.vs_truth) {
            Scene probe = sb;
            apply_set(probe, k.key, k.values.front());
            m.truth_of(wb, probe, w, h);
            for (const auto& v : k.values) {  // a knob that changes the physical description needs a truth per value
                Scene sv = sb;
                apply_set(sv, k.key, v);
                m.truth_of(wb, sv, w, h);
            }
        }
        for (const auto& v : k.values) {
            if (o.progress) o.progress("sweep " + k.key + "=" + v + (by ? " " + by->key + "=" + b : ""), double(points.size()) / double(total));
            points.push_back(sweep_point(wb, sb, k, v, req, o.repeat, m));
            points.back().by = b;
            if (!o.quiet)
                std::fprintf(stderr, "  %s=%-10s%s %10.3f ms  %s %.3e%s\n", k.key.c_str(), v.c_str(), by ? (" " + by->key + "=" + b).c_str() : "", points.back().ms,
                         err_name.c_str(), points.back().err, points.back().below_noise ? " (below the truth's noise)" : "");
        }
    }
    if (m.vs_truth && m.truths.size() > 1 && !o.quiet) std::fprintf(stderr, "  %zu truths: the knobs change what the truth reads\n", m.truths.size());

    // A technique metric's outputs are named after it too, so they do not replace the RMSE sweep's.
    const std::string metric_suffix = m.metric ? "." + m.metric->name : m.vs_truth ? std::string(".truth") : std::string();
    const std::string stem =
        (fs::path(o.out_dir) / (base.name + "." + k.key + (by ? "." + by->key : "") + metric_suffix)).string();
    const Report r = report(o, base, k, ref_text, w, h, m, points);
    SweepResult result{points, err_name, ref_text, r.md, {}};
    if (write_files) {
        write_text_atomic(stem + ".csv", r.csv);
        write_text_atomic(stem + ".md", r.md);
        write_png_srgb(stem + ".png", render_plot(r.plot));
        write_text_atomic(stem + ".svg", render_plot_svg(r.plot));
        result.written = {stem + ".csv", stem + ".md", stem + ".png", stem + ".svg"};
    }
    return result;
}
std::vector<std::pair<std::string, std::string>> sweep_reference(const Scene& base, const SweepKnob& knob,
                                                                 const std::vector<std::pair<std::string, std::string>>& reference) {
    return reference_settings(check_knob(base, knob, "--knob"), reference);
}
}  // namespace mesolab
