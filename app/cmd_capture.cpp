// mesolab capture: headless render of presets to PNG + AOV EXRs + a JSON sidecar.
#include "core/file.h"
#include "app/commands.h"
#include "app/gui/truth_view.h"
#include "app/workbench.h"
#include "core/error.h"
#include "core/image.h"
#include "core/profile.h"
#include "core/scene.h"
#include "core/technique.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>

namespace fs = std::filesystem;

namespace mesolab {

// [SECTION] Shared helpers
void parse_size(const std::string& s, int& w, int& h) {
    const auto x = s.find('x');
    try {
        if (x == std::string::npos) throw std::invalid_argument("");
        size_t a = 0, b = 0;
        w = std::stoi(s.substr(0, x), &a);
        h = std::stoi(s.substr(x + 1), &b);
        if (a != x || b != s.size() - x - 1) throw std::invalid_argument("");
    } catch (const std::exception&) {
        throw InputError("--size: expected WxH (e.g. 512x512), got '" + s + "'");
    }
    if (w < 1 || h < 1 || w > 16384 || h > 16384) throw InputError("--size: " + s + " is out of range (1..16384 per side)");
}

std::vector<std::string> expand_presets(const std::vector<std::string>& args) {
    std::vector<std::string> files;
    for (const auto& a : args) {
        std::error_code ec;
        if (fs::is_directory(a, ec)) {
            std::vector<std::string> found;
            for (const auto& e : fs::recursive_directory_iterator(a))
                if (e.is_regular_file() && e.path().extension() == ".json") found.push_back(e.path().string());
            std::sort(found.begin(), found.end());
            if (found.empty()) throw InputError(a + ": folder holds no preset (*.json)");
            files.insert(files.end(), found.begin(), found.end());
        } else {
            files.push_back(a);
        }
    }
    return files;
}

uint64_t memory_limit_bytes(const std::string& text) { return text.empty() ? 0 : parse_memory_size(text); }

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
    if (r.renderer == "truth") {
        json tr;
        tr["spp"] = req_truth.spp;
        tr["seed"] = req_truth.seed;
        tr["noise_rel"] = truth_noise_rel(r.frame);
        tr["cached_spp"] = r.truth_cached_spp;  // samples read from the truth cache (all of them: nothing rendered)
        j["truth"] = tr;
    } else if (r.truth) {  // the frame against its truth (--aov truth_error)
        json tr;
        tr["spp"] = r.truth->spp;
        tr["seed"] = r.truth->seed;
        tr["noise_rel"] = r.truth->noise_rel;
        tr["rmse_rel"] = r.truth->rmse_rel;
        tr["below_noise"] = r.truth->below_noise;
        tr["ms"] = r.truth_ms;
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
        write_png_srgb(epng, gui::error_figure(r.truth->error, *r.truth_frame));
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
    req.backend = parse_backend(o.backend);
    req.width = w;
    req.height = h;
    req.progress = tty_progress();
    req.aovs = o.aovs.empty() ? std::vector<std::string>{"radiance"} : o.aovs;  // radiance and the requested AOVs only
    req.truth.spp = o.spp;
    req.truth.seed = o.seed;
    if (req.backend == Backend::Truth && o.spp < 1) throw InputError("--spp " + std::to_string(o.spp) + ": expected at least 1 sample per pixel");
    const auto files = expand_presets(o.presets);
    // Validate everything first, so that bad input fails before any work.
    std::vector<Scene> scenes;
    for (const auto& f : files) {
        Scene s = load_preset(f);
        apply_sets(s, o.sets);
        try {
            if (req.backend == Backend::Truth) {
                truth_stages(s);  // every object's technique has a truth
                for (const auto& a : o.aovs)
                    if (std::find(truth_aovs().begin(), truth_aovs().end(), a) == truth_aovs().end())
                        throw InputError("--aov " + a + ": the truth does not write it (it writes radiance, normal, truth_stderr, exitance)");
            } else {
                std::vector<std::string> realtime;  // truth_error is made from the frame and the truth
                for (const auto& a : o.aovs)
                    if (a != "truth_error") realtime.push_back(a);
                if (realtime.size() != o.aovs.size()) truth_stages(s);  // every object's technique has a truth
                frame_layout(s, realtime);  // every requested AOV exists in this scene
            }
        } catch (const InputError& e) {
            throw InputError(f + ": " + e.what());
        }
        scenes.push_back(std::move(s));
    }
    Workbench wb;
    wb.session().set_memory_limit(memory_limit_bytes(o.memory_limit));
    if (req.backend == Backend::Gpu) {
        try {
            wb.gpu();
        } catch (const std::exception& e) {
            throw std::runtime_error(std::string("no OpenGL context for --backend gpu: ") + e.what());
        }
    }
    for (size_t i = 0; i < scenes.size(); ++i) {
        const Scene& s = scenes[i];
        RenderResult r = wb.render(s, req);
        tty_progress_done();
        const std::string png = write_capture(o.out_dir, s, files[i], r, o.aovs, req.truth).front();
        int ran = 0, cached = 0, skipped = 0;
        for (const auto& run : r.eval.runs)
            for (const auto& w : run.warnings)
                std::fprintf(stderr, "mesolab: warning: %s: stage %s: %s\n", files[i].c_str(), run.label(s).c_str(), w.c_str());
        for (const auto& run : r.eval.runs) {
            ran += run.status == StageStatus::Ran;
            cached += run.status == StageStatus::Cached;
            skipped += run.status == StageStatus::Skipped;
        }
        std::printf("%-28s %4dx%-4d %-6s stages %7.2f ms (%d ran, %d cached, %d skipped)  render %7.2f ms  -> %s\n", s.name.c_str(), r.frame.width,
                    r.frame.height, req.backend == Backend::Cpu ? "cpu" : req.backend == Backend::Gpu ? "gpu" : "truth", r.stages_ms, ran, cached, skipped, r.render_ms, png.c_str());
    }
    if (o.profile) print_profile(wb.session().profiler());
    return 0;
}
}  // namespace mesolab
