// mesolab sweep: accuracy vs time for one knob against a reference rendering.
#include "app/commands.h"
#include "app/workbench.h"
#include "core/error.h"
#include "core/image.h"
#include "core/plot.h"
#include "core/profile.h"
#include "core/scene.h"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <sstream>

namespace fs = std::filesystem;

namespace mesolab {
namespace {

std::vector<std::string> split(const std::string& s, char sep) {
    std::vector<std::string> r;
    std::stringstream ss(s);
    std::string item;
    while (std::getline(ss, item, sep)) r.push_back(item);
    return r;
}

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
}  // namespace

int run_sweep(const SweepOptions& o) {
    int w = 0, h = 0;
    parse_size(o.size, w, h);
    if (o.repeat < 1 || o.repeat > 100) throw InputError("--repeat: " + std::to_string(o.repeat) + " is out of range [1, 100]");
    Scene base = load_preset(o.preset);
    for (const auto& s : o.sets) apply_set(base, s);
    const auto eq = o.knob.find('=');
    if (eq == std::string::npos || eq == 0 || eq + 1 == o.knob.size())
        throw InputError("--knob expects KEY=V1,V2,... (e.g. geometry.resolution=8,16,32), got '" + o.knob + "'");
    const std::string key = o.knob.substr(0, eq);
    const std::vector<std::string> values = split(o.knob.substr(eq + 1), ',');
    const ParamDecl& decl = decl_of(base, key);
    for (const auto& v : values) {
        Scene probe = base;
        apply_set(probe, key, v);  // validates every value before any work
    }

    // Reference: --reference settings, else the knob's declared reference, else its most accurate value.
    Scene ref = base;
    std::string ref_text;
    if (!o.reference.empty()) {
        for (const auto& r : o.reference) {
            apply_set(ref, r);
            ref_text += (ref_text.empty() ? "" : ", ") + r;
        }
    } else if (decl.reference) {
        ref_text = key + "=" + value_to_text(decl, *decl.reference);
        apply_set(ref, key, value_to_text(decl, *decl.reference));
    } else if (decl.accuracy != Accuracy::None && (decl.type == ParamType::Int || decl.type == ParamType::Float)) {
        std::string best = values.front();
        for (const auto& v : values) {
            const bool better = decl.accuracy == Accuracy::Higher ? as_number(decl, v) > as_number(decl, best) : as_number(decl, v) < as_number(decl, best);
            if (better) best = v;
        }
        ref_text = key + "=" + best;
        apply_set(ref, key, best);
    } else {
        throw InputError("--knob " + key + ": this parameter declares no most-accurate setting; give one with --reference KEY=VALUE");
    }

    Workbench wb;
    RenderRequest req;
    req.backend = parse_backend(o.backend);
    req.width = w;
    req.height = h;
    std::fprintf(stderr, "reference: %s\n", ref_text.c_str());
    const Image reference = wb.render(ref, req).frame.aov("radiance");
    const double ref_mean = mean(reference);

    struct Point {
        std::string value;
        double ms, err, rel;
    };
    std::vector<Point> points;
    for (const auto& v : values) {
        Scene s = base;
        apply_set(s, key, v);
        std::vector<double> times;
        Image img;
        wb.render(s, req);  // untimed warm-up: first-touch allocations, GPU resources
        for (int r = 0; r < o.repeat; ++r) {
            wb.stages().clear_cache();  // the cost of this setting includes its stages
            RenderResult res = wb.render(s, req);
            times.push_back(res.stages_ms + res.render_ms);
            img = std::move(res.frame.aov("radiance"));
        }
        if (img.width != reference.width || img.height != reference.height)
            throw InputError("--knob " + key + "=" + v + ": the frame size changed (" + std::to_string(img.width) + "x" + std::to_string(img.height) +
                             "), so it cannot be compared with the reference");
        const double e = rmse(img, reference);
        points.push_back({v, median_of(times), e, ref_mean > 0 ? e / ref_mean : 0});
        std::fprintf(stderr, "  %s=%-10s %10.3f ms  rmse %.3e\n", key.c_str(), v.c_str(), points.back().ms, e);
    }

    // [SECTION] Outputs: CSV, Markdown, PNG plot
    const std::string stem = (fs::path(o.out_dir) / (base.name + "." + key)).string();
    std::ostringstream csv, md;
    csv << "value,time_ms,rmse,relative_rmse\n";
    md << "Sweep of `" << key << "` on `" << base.name << "` (" << o.backend << ", " << w << "x" << h << ", median of " << o.repeat
       << " cold-cache runs); reference " << ref_text << ".\n\n| " << key << " | time (ms) | RMSE | relative RMSE |\n|---|---|---|---|\n";
    PlotSeries series;
    series.label = key;
    for (const auto& p : points) {
        csv << p.value << "," << p.ms << "," << p.err << "," << p.rel << "\n";
        char line[256];
        std::snprintf(line, sizeof line, "| %s | %.3f | %.3e | %.3e |\n", p.value.c_str(), p.ms, p.err, p.rel);
        md << line;
        series.x.push_back(p.ms);
        series.y.push_back(p.err);
        series.point_labels.push_back(p.value);
    }
    write_text_atomic(stem + ".csv", csv.str());
    write_text_atomic(stem + ".md", md.str());
    PlotSpec spec;
    spec.title = "error vs time: " + key + " (" + base.name + ")";
    spec.xlabel = "time per frame incl. stages (ms)";
    spec.ylabel = "RMSE vs reference";
    spec.series.push_back(series);
    write_png_srgb(stem + ".png", render_plot(spec));
    std::printf("%s", md.str().c_str());
    std::printf("\nwrote %s.csv, %s.md, %s.png\n", stem.c_str(), stem.c_str(), stem.c_str());
    return 0;
}
}  // namespace mesolab
