// mesolab capture: headless render of presets to PNG + AOV EXRs + a JSON sidecar.
#include "core/file.h"
#include "app/commands.h"
#include "app/truth_figures.h"
#include "app/workbench.h"
#include "core/error.h"
#include "core/image.h"
#include "core/profile.h"
#include "core/pack.h"
#include "core/scene.h"
#include "core/strings.h"
#include "core/technique.h"
#include "core/truth/cache.h"
#include "core/truth/truth.h"
#include "core/stage_store.h"

#include <algorithm>
#include <limits>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <tuple>

namespace fs = std::filesystem;

namespace mesolab {

// [SECTION] Shared helpers
void parse_size(const std::string& s, int& w, int& h) {
    const auto wh = parse_wxh(s);
    if (!wh) throw InputError("--size: expected WxH (e.g. 512x512), got '" + s + "'");
    std::tie(w, h) = *wh;
    if (w < 1 || h < 1 || w > 16384 || h > 16384) throw InputError("--size: " + s + " is out of range (1..16384 per side)");
}

std::vector<std::string> expand_presets(const std::vector<std::string>& args) {
    std::vector<std::string> files;
    for (const auto& a : args) {
        std::error_code ec;
        if (fs::is_directory(a, ec) && !is_pack(a)) {
            std::vector<std::string> found;
            for (const auto& e : fs::recursive_directory_iterator(a))
                if (e.is_regular_file() && (e.path().extension() == ".json" || e.path().extension() == ".zip")) found.push_back(e.path().string());
            std::sort(found.begin(), found.end());
            if (found.empty()) throw InputError(a + ": folder holds no preset (*.json) or pack (*.zip)");
            files.insert(files.end(), found.begin(), found.end());
        } else {
            files.push_back(a);
        }
    }
    return files;
}

uint64_t memory_limit_bytes(const std::string& text) { return text.empty() ? 0 : parse_memory_size(text); }

double parse_duration_s(const std::string& text, const std::string& option) {
    double scale = 1.0;
    std::string number = text;
    if (!number.empty() && (number.back() == 's' || number.back() == 'm' || number.back() == 'h')) {
        scale = number.back() == 'h' ? 3600.0 : number.back() == 'm' ? 60.0 : 1.0;
        number.pop_back();
    }
    double v = 0.0;
    size_t used = 0;
    try {
        v = std::stod(number, &used);
    } catch (const std::exception&) {
        used = 0;
    }
    if (number.empty() || used != number.size() || !std::isfinite(v) || v <= 0.0)
        throw InputError(option + " " + text + ": expected a duration above 0: seconds, or a number with s, m or h (600, 90s, 10m, 1.5h)");
    return v * scale;
}

TruthSettings truth_sampling(int spp, bool spp_given, double noise, const std::string& time_limit, uint64_t seed) {
    return truth_sampling(spp_given ? std::optional<int>(spp) : std::nullopt, noise, time_limit.empty() ? 0.0 : parse_duration_s(time_limit, "--time-limit"),
                          seed);
}

namespace {
// --samples A:B
void parse_samples(const std::string& text, int& first, int& end) {
    const auto colon = text.find(':');
    try {
        size_t a = 0, b = 0;
        if (colon == std::string::npos) throw std::invalid_argument("");
        first = std::stoi(text.substr(0, colon), &a);
        end = std::stoi(text.substr(colon + 1), &b);
        if (a != colon || b != text.size() - colon - 1) throw std::invalid_argument("");
    } catch (const std::exception&) {
        throw InputError("--samples: expected A:B, the samples [A, B) of the truth (e.g. 0:256), got '" + text + "'");
    }
    if (first < 0 || end <= first) throw InputError("--samples " + text + ": expected 0 <= A < B");
}
}  // namespace

namespace {

Image radiance_rgb(const Frame& f) { return f.aov("radiance"); }

}  // namespace

json capture_sidecar(const Scene& s, const std::string& file, const RenderResult& r, const std::vector<std::string>& written, const TruthSettings& req_truth) {
    json j;
    j["preset"] = s.name;
    j["file"] = file;
    j["version"] = version_string();
    j["renderer"] = r.renderer;
    j["size"] = json::array({r.frame.width, r.frame.height});
    j["parameters"] = scene_to_json(s);
    json stages = json::array();
    for (const auto& run : r.eval.runs) {
        json st;
        st["name"] = run.name;
        if (run.object >= 0) {
            st["object"] = run.object;
            st["object_name"] = s.objects[size_t(run.object)].name;
        }
        st["status"] = to_string(run.status);
        st["ms"] = run.ms;
        if (!run.reason.empty()) st["reason"] = run.reason;
        if (!run.warnings.empty()) st["warnings"] = run.warnings;
        stages.push_back(st);
    }
    j["stages"] = stages;
    json steps = json::array();
    for (const auto& st : r.frame.steps) {
        json x;
        x["name"] = st.name;
        x["status"] = to_string(st.status);
        if (std::isfinite(st.ms)) x["ms"] = st.ms;
        steps.push_back(x);
    }
    j["frame_steps"] = steps;
    json t;
    t["stages_ms"] = r.stages_ms;
    t["render_ms"] = r.render_ms;
    if (r.renderer != "cpu") t["gpu_ms"] = r.gpu_ms;
    j["timings"] = t;
    json aovs = json::array(), rendered = json::array();
    for (const auto& a : Registry::instance().aovs(s)) aovs.push_back(a.name);
    for (const auto& a : r.frame.layout) rendered.push_back(a.name);
    j["aovs_available"] = aovs;
    j["aovs_rendered"] = rendered;
    j["outputs"] = written;
    if (r.sampled) {
        json tr;
        tr["spp"] = r.sampled->spp;
        tr["seed"] = req_truth.seed;
        tr["noise_rel"] = truth_noise_rel(r.frame);
        tr["cached_spp"] = r.sampled->cached_spp;  // samples read from the truth cache (all of them: nothing rendered)
        if (req_truth.noise > 0.0) tr["noise_target"] = req_truth.noise;
        if (req_truth.time_limit_s > 0.0) tr["time_limit_s"] = req_truth.time_limit_s;
        tr["ended"] = to_string(r.sampled->ended);  // samples, noise or time limit: what ended the sampling
        j["truth"] = tr;
    } else if (r.truth) {  // the frame against its truth (--aov truth_error)
        json tr;
        tr["spp"] = r.truth->spp;
        tr["seed"] = r.truth->seed;
        tr["noise_rel"] = r.truth->noise_rel;
        tr["rmse_rel"] = r.truth->rmse_rel;
        tr["below_noise"] = r.truth->below_noise;
        tr["ms"] = r.truth_ms;
        tr["cached_spp"] = r.truth_run ? r.truth_run->cached_spp : 0;
        if (req_truth.noise > 0.0) tr["noise_target"] = req_truth.noise;
        if (req_truth.time_limit_s > 0.0) tr["time_limit_s"] = req_truth.time_limit_s;
        tr["ended"] = to_string(r.truth_run ? r.truth_run->ended : TruthEnd::Samples);
        j["truth"] = tr;
    }
    return j;
}

std::vector<std::string> write_capture(const std::string& out_dir, const Scene& s, const std::string& file, const RenderResult& r,
                                       const std::vector<std::string>& aovs, const TruthSettings& truth) {
    const fs::path dir = out_dir;
    std::vector<std::string> written;
    const std::string png = (dir / (s.name + ".png")).string();
    write_png_srgb(png, radiance_rgb(r.frame));
    written.push_back(png);
    if (r.truth && r.truth_frame) {  // truth_error: the truth and the error beside the frame, as pictures too
        const std::string tpng = (dir / (s.name + ".truth.png")).string(), epng = (dir / (s.name + ".truth_error.png")).string();
        write_png_srgb(tpng, radiance_rgb(*r.truth_frame));
        write_png_srgb(epng, error_figure(r.truth->error, *r.truth_frame));
        written.push_back(tpng);
        written.push_back(epng);
    }
    for (const auto& a : aovs) {
        const std::string exr = (dir / (s.name + "." + a + ".exr")).string();
        write_exr(exr, r.frame.aov(a));
        written.push_back(exr);
    }
    const std::string side = (dir / (s.name + ".json")).string();
    written.push_back(side);
    write_text_atomic(side, capture_sidecar(s, file, r, written, truth).dump(2) + "\n");
    return written;
}

// [SECTION] truth merge
int run_truth_merge(const MergeOptions& o) {
    if (o.parts.empty()) throw InputError("truth merge: name the partial truths to join (NAME.samples-A-B.truth)");
    for (const std::string& a : o.aovs)
        if (std::find(truth_aovs().begin(), truth_aovs().end(), a) == truth_aovs().end())
            throw InputError("--aov " + a + ": the truth does not write it (it writes radiance, normal, truth_stderr, exitance, irradiance)");
    std::vector<std::pair<std::string, TruthPart>> parts;
    for (const std::string& f : o.parts) parts.emplace_back(f, read_truth_part(f));
    const TruthPart merged = merge_truth_parts(parts);
    const std::string here = truth_build(version_string());
    if (merged.build != here)
        std::fprintf(stderr, "mesolab: note: the parts were made by another build (%s); this one is %s. The merged sums are theirs.\n", merged.build.c_str(), here.c_str());
    const TruthAccumulator& a = merged.sums;
    fs::create_directories(o.out_dir);
    const fs::path dir = o.out_dir;
    const std::string name = merged.scene;
    const std::string part = (dir / (name + ".samples-" + std::to_string(a.first) + "-" + std::to_string(a.spp) + ".truth")).string();
    write_truth_part(part, merged);
    const Frame f = truth_frame(a);
    std::vector<std::string> written = {(dir / (name + ".png")).string()};
    write_png_srgb(written.back(), f.aov("radiance"));
    for (const std::string& aov : o.aovs) {
        written.push_back((dir / (name + "." + aov + ".exr")).string());
        write_exr(written.back(), f.aov(aov));
    }
    written.push_back(part);
    // A merged truth from sample 0 is kept in the truth cache too: a capture of the same scene, size
    // and seed reads it, or continues it.
    bool cached = false;
    if (a.first == 0 && merged.build == here) cached = TruthCache(cache_folder("truth"), version_string()).store(merged.key, a);
    json j;
    j["preset"] = name;
    j["version"] = version_string();
    j["renderer"] = "truth";
    j["size"] = json::array({a.width, a.height});
    json tr;
    tr["spp"] = a.samples();
    tr["samples"] = json::array({a.first, a.spp});
    tr["seed"] = a.seed;
    tr["noise_rel"] = truth_noise_rel(f);
    tr["build"] = merged.build;
    tr["key"] = merged.key;
    tr["parts"] = o.parts;
    tr["kept_in_cache"] = cached;
    j["truth"] = tr;
    j["outputs"] = written;
    const std::string side = (dir / (name + ".json")).string();
    write_text_atomic(side, j.dump(2) + "\n");
    std::printf("%s: %d parts, samples %d:%d (%d spp), noise_rel %.4f -> %s%s\n", name.c_str(), int(parts.size()), a.first, a.spp, a.samples(),
                truth_noise_rel(f), written.front().c_str(), cached ? " (and the truth cache)" : "");
    return 0;
}

void print_profile(const Profiler& profiler) {
    std::fprintf(stderr, "\n%-44s %-4s %10s %10s %10s %10s %6s\n", "scope", "dev", "last ms", "median", "min", "max", "n");
    for (const auto& s : profiler.stats()) {
        // Indent by depth so the hierarchy reads at a glance.
        // A GPU range "a/b/gpu" reads as "b (GPU)" beside its CPU scope "a/b", which may not exist.
        std::string path = s.path;
        bool gpu_range = false;
        if (path.size() > 4 && path.compare(path.size() - 4, 4, "/gpu") == 0) path.resize(path.size() - 4), gpu_range = true;
        const size_t depth = size_t(std::count(path.begin(), path.end(), '/'));
        const std::string name = std::string(2 * depth, ' ') + path.substr(path.rfind('/') == std::string::npos ? 0 : path.rfind('/') + 1) + (gpu_range ? " (GPU)" : "");
        std::fprintf(stderr, "%-44s %-4s %10.3f %10.3f %10.3f %10.3f %6zu\n", name.c_str(), s.device == Device::Gpu ? "gpu" : "cpu", s.last, s.median,
                     s.min, s.max, s.count);
    }
}

// [SECTION] capture
int run_capture(const CaptureOptions& o) {
    int w = 0, h = 0;
    parse_size(o.size, w, h);
    RenderRequest req;
    req.renderer = o.backend;
    req.width = w;
    req.height = h;
    req.progress = tty_progress();
    req.aovs = o.aovs.empty() ? std::vector<std::string>{"radiance"} : o.aovs;  // radiance and the requested AOVs only
    req.truth = truth_sampling(o.spp, o.spp_given, o.noise, o.time_limit, o.seed);
    const RendererDecl& renderer = RendererRegistry::instance().find(req.renderer);
    if (!o.samples.empty()) {
        if (o.noise > 0.0 || !o.time_limit.empty()) throw InputError("--samples: a partial truth renders exactly its samples; leave out --noise and --time-limit");
        parse_samples(o.samples, req.truth.first, req.truth.spp);
        req.partial = true;
    }
    const auto files = expand_presets(o.presets);
    // Validate everything first, so that bad input fails before any work.
    std::vector<Scene> scenes;
    for (const auto& f : files) {
        Scene s = load_preset(f);
        apply_sets(s, o.sets);
        try {
            check_render_request(s, req);
        } catch (const InputError& e) {
            if (req.partial && !renderer.traits.sampled) throw;  // not about the file
            throw InputError(f + ": " + e.what());
        }
        scenes.push_back(std::move(s));
    }
    RendererSetup setup = default_renderer_setup();
    if (o.no_cache) setup.truth_folder.clear();
    Workbench wb(setup);
    if (!o.no_cache) wb.session().set_store(StageStore::from_environment(version_string()));
    wb.session().set_memory_limit(memory_limit_bytes(o.memory_limit));
    if (renderer.traits.needs_gl) wb.renderer(req.renderer).device();  // its context, before any work
    for (size_t i = 0; i < scenes.size(); ++i) {
        const Scene& s = scenes[i];
        RenderResult r = wb.render(s, req);
        tty_progress_done();
        if (req.partial) {  // the part's sums, to be joined by `mesolab truth merge`
            const std::string path = (fs::path(o.out_dir) / (s.name + ".samples-" + std::to_string(req.truth.first) + "-" + std::to_string(req.truth.spp) + ".truth")).string();
            write_truth_part(path, TruthPart{s.name, r.sampled->key, truth_build(version_string()), *r.sampled->sums});
            std::printf("%-28s %4dx%-4d truth  samples %d:%d  noise_rel %.4f  render %7.2f ms  -> %s\n", s.name.c_str(), r.frame.width, r.frame.height,
                        req.truth.first, req.truth.spp, truth_noise_rel(r.frame), r.render_ms, path.c_str());
            continue;
        }
        const std::string png = write_capture(o.out_dir, s, files[i], r, o.aovs, req.truth).front();
        int ran = 0, cached = 0, stored = 0, skipped = 0;
        for (const auto& run : r.eval.runs)
            for (const auto& w : run.warnings)
                std::fprintf(stderr, "mesolab: warning: %s: stage %s: %s\n", files[i].c_str(), run.label(s).c_str(), w.c_str());
        for (const auto& run : r.eval.runs) {
            ran += run.status == StageStatus::Ran;
            cached += run.status == StageStatus::Cached;
            stored += run.status == StageStatus::Stored;
            skipped += run.status == StageStatus::Skipped;
        }
        std::printf("%-28s %4dx%-4d %-6s stages %7.2f ms (%d ran, %d cached, %d cached (disk), %d skipped)  render %7.2f ms  -> %s\n", s.name.c_str(),
                    r.frame.width, r.frame.height, req.renderer.c_str(), r.stages_ms, ran,
                    cached, stored, skipped, r.render_ms, png.c_str());
        if (r.sampled)
            std::printf("%-28s %s: %d spp (%d from the cache), noise_rel %.4f, ended by %s\n", "", req.renderer.c_str(), r.sampled->spp, r.sampled->cached_spp,
                        truth_noise_rel(r.frame), to_string(r.sampled->ended));
    }
    if (o.profile) print_profile(wb.session().profiler());
    return 0;
}
}  // namespace mesolab
