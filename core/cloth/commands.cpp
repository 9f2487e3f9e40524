// Technique cloth: its commands, mesolab cloth fit (measured samples in, one fitted model per
// point out) and mesolab cloth eval (a fitted model at given directions).
#include "core/file.h"
#include "core/parallel.h"
#include "core/cloth/samples.h"
#include "core/cloth/stages.h"
#include "core/cloth/technique.h"
#include "core/error.h"
#include "core/strings.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <map>
#include <mutex>
#include <sstream>
#include <string>

namespace mesolab::cloth {
namespace {

// [SECTION] Fitting commands: option values
int parse_int_option(const std::map<std::string, std::string>& a, const std::string& key, int def, int lo, int hi) {
    auto it = a.find(key);
    if (it == a.end()) return def;
    try {
        size_t used = 0;
        const int v = std::stoi(it->second, &used);
        if (used == it->second.size() && v >= lo && v <= hi) return v;
    } catch (const std::exception&) {
    }
    throw InputError("--" + key + " " + it->second + ": expected an integer in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
}

double parse_float_option(const std::map<std::string, std::string>& a, const std::string& key, double def) {
    auto it = a.find(key);
    if (it == a.end()) return def;
    try {
        size_t used = 0;
        const double v = std::stod(it->second, &used);
        if (used == it->second.size() && std::isfinite(v) && v > 0.0) return v;
    } catch (const std::exception&) {
    }
    throw InputError("--" + key + " " + it->second + ": expected a positive number");
}
}  // namespace

// [SECTION] Commands: fit and evaluate measured samples
std::vector<CommandDecl> ClothTechnique::commands() const {
    CommandDecl fit;
    fit.name = "fit";
    fit.help = "Fit the cloth model (Lafortune lobes x view table) to measured BRDF samples, one model per point";
    fit.positionals = {{"samples", "CSV rows [point,]lx,ly,lz,vx,vy,vz,r,g,b: directions in the local frame (z = normal), f_r in 1/sr", true}};
    fit.options = {{"-o,--output", "Model file to write (JSON)", true},
                   {"--lobes", "Lafortune lobes per channel, 1-3 (default 2)", false},
                   {"--lookup-table", "on or off (default on): fit the view-dependent table", false},
                   {"--tolerance", "Stop when the table changes less than this (default 0.1)", false}};
    fit.run = [](const std::map<std::string, std::string>& a, const ProgressFn& progress) {
        FitOptions o;
        o.lobes = parse_int_option(a, "lobes", 2, 1, 3);
        if (auto it = a.find("lookup-table"); it != a.end()) {
            if (it->second != "on" && it->second != "off") throw InputError("--lookup-table " + it->second + ": expected on or off");
            o.lookup_table = it->second == "on";
        }
        o.tolerance = parse_float_option(a, "tolerance", 0.1);
        const SampleSet set = read_samples_csv(a.at("samples"));
        ClothModel m;
        m.lobes = o.lobes;
        m.lookup_table = o.lookup_table;
        m.names = set.names;
        m.brdfs.resize(set.points.size());
        m.reports.resize(set.points.size());
        std::atomic<size_t> done{0};
        std::mutex progress_mutex;
        mesolab::parallel_for(size_t(0), set.points.size(), [&](size_t i) {
            m.brdfs[i] = fit_brdf(set.points[i], o, &m.reports[i]);
            const size_t d = ++done;
            if (progress) {
                std::lock_guard<std::mutex> lock(progress_mutex);
                progress(std::string(stages::fit.name), double(d) / double(set.points.size()));
            }
        });
        write_model(a.at("output"), m);
        std::vector<double> rel;
        for (const FitReport& r : m.reports) rel.push_back(r.rel_rms);
        std::sort(rel.begin(), rel.end());
        return "fitted " + std::to_string(m.brdfs.size()) + " point(s) from " + std::to_string(set.rows) + " samples (" + std::to_string(o.lobes) +
               " lobes, lookup table " + (o.lookup_table ? "on" : "off") + "): relative RMS median " + strprintf("%.3g", rel[rel.size() / 2]) + ", max " +
               strprintf("%.3g", rel.back()) + "\nwrote " + a.at("output");
    };
    CommandDecl eval;
    eval.name = "eval";
    eval.help = "Evaluate a fitted cloth model at given directions: f_r per channel";
    eval.positionals = {{"model", "Model file (JSON) written by mesolab cloth fit", true},
                        {"directions", "CSV rows [point,]lx,ly,lz,vx,vy,vz (point: when the model has several)", true}};
    eval.options = {{"-o,--output", "CSV file to write: rows r,g,b (f_r in 1/sr)", true}};
    eval.run = [](const std::map<std::string, std::string>& a, const ProgressFn&) {
        const ClothModel m = read_model(a.at("model"));
        const std::vector<DirectionRow> rows = read_directions_csv(a.at("directions"), m.names);
        std::ostringstream out;
        char line[128];
        for (const DirectionRow& r : rows) {
            const dvec3 f = m.brdfs[size_t(r.point)].f(r.l, r.v);
            std::snprintf(line, sizeof line, "%.9g,%.9g,%.9g\n", f.x, f.y, f.z);
            out << line;
        }
        write_text_atomic(a.at("output"), out.str());
        return "evaluated " + std::to_string(rows.size()) + " direction pair(s) of " + std::to_string(m.brdfs.size()) + " point(s)\nwrote " +
               a.at("output");
    };
    return {fit, eval};
}
}  // namespace mesolab::cloth
