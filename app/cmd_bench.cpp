// mesolab bench: timing tables laid out like the papers' tables, our CPU/GPU medians beside
// the paper's figures.
#include "app/commands.h"
#include "app/workbench.h"
#include "core/bench.h"
#include "core/error.h"
#include "core/profile.h"
#include "core/technique.h"

#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <thread>

namespace mesolab {
namespace {

struct Cell {
    std::string table, row, column, device;
    double median = 0, min = 0, max = 0;
    std::optional<double> paper;
    std::string info;  // report columns (BenchColumn::info): the text, no timing
};

std::string fmt_ms(double ms) {
    char b[64];
    if (ms >= 1000.0) std::snprintf(b, sizeof b, "%.3g s", ms / 1000.0);
    else if (ms >= 1.0) std::snprintf(b, sizeof b, "%.3g ms", ms);
    else std::snprintf(b, sizeof b, "%.3g µs", ms * 1000.0);
    return b;
}

std::string cpu_model() {
    std::ifstream in("/proc/cpuinfo");
    std::string line;
    while (std::getline(in, line))
        if (line.rfind("model name", 0) == 0) return line.substr(line.find(':') + 2);
    return "unknown CPU";
}

constexpr double kSlowMs = 10000;  // stage cells slower than this are measured once

std::vector<double> time_runs(int n, const std::function<double()>& once) {
    std::vector<double> v;
    for (int i = 0; i < n; ++i) v.push_back(once());
    return v;
}
}  // namespace

int run_bench(const BenchOptions& o) {
    if (o.format != "md" && o.format != "csv" && o.format != "json") throw InputError("--format: '" + o.format + "' is not one of md|csv|json");
    if (o.repeat < 1 || o.repeat > 1000) throw InputError("--repeat: " + std::to_string(o.repeat) + " is out of range [1, 1000]");
    if (o.backend != "cpu" && o.backend != "gpu" && o.backend != "both") throw InputError("--backend: '" + o.backend + "' is not one of cpu|gpu|both");
    const auto all = bench_tables();
    std::vector<BenchTable> tables;
    if (o.tables.empty()) tables = all;
    for (const auto& name : o.tables) {
        auto it = std::find_if(all.begin(), all.end(), [&](const BenchTable& t) { return t.name == name; });
        if (it == all.end()) {
            std::vector<std::string> names;
            for (const auto& t : all) names.push_back(t.name);
            const std::string hint = nearest_key(name, names);
            std::string list;
            for (const auto& n : names) list += (list.empty() ? "" : ", ") + n;
            throw InputError("bench: unknown table '" + name + "'" + (hint.empty() ? "" : " (did you mean '" + hint + "'?)") + "; tables: " + list);
        }
        tables.push_back(*it);
    }

    Workbench wb;
    const bool want_gpu = o.backend != "cpu", want_cpu = o.backend != "gpu";
    std::string gl = "none";
    if (want_gpu) {
        try {
            gl = wb.gl_renderer();
        } catch (const std::exception& e) {
            throw std::runtime_error(std::string("bench needs an OpenGL context for GPU columns (use --backend cpu): ") + e.what());
        }
    }
    const std::string machine = cpu_model() + ", " + std::to_string(std::thread::hardware_concurrency()) + " threads; GL: " + gl;
    StageGraph& graph = wb.stages();

    std::vector<Cell> cells;
    for (const auto& t : tables) {
        for (const auto& row : t.rows) {
            const Scene scene = row.scene();
            for (size_t ci = 0; ci < t.columns.size(); ++ci) {
                const BenchColumn& col = t.columns[ci];
                const std::optional<double> paper = ci < row.paper_ms.size() ? row.paper_ms[ci] : std::nullopt;
                auto add = [&](const char* device, const std::vector<double>& v) {
                    Cell c{t.name, row.name, col.name, device, median_of(v), *std::min_element(v.begin(), v.end()), *std::max_element(v.begin(), v.end()), paper};
                    cells.push_back(c);
                    std::fprintf(stderr, "  %-10s %-22s %-22s %-4s %s\n", t.name.c_str(), row.name.c_str(), col.name.c_str(), device, fmt_ms(c.median).c_str());
                };
                if (col.info) {
                    const Evaluation ev = graph.evaluate(scene, Registry::instance().frame_stages(scene));
                    Cell c{t.name, row.name, col.name, "-", 0, 0, 0, std::nullopt, col.info(scene, ev)};
                    std::fprintf(stderr, "  %-10s %-22s %-22s %s\n", t.name.c_str(), row.name.c_str(), col.name.c_str(), c.info.c_str());
                    cells.push_back(c);
                    continue;
                }
                if (!col.stage.empty()) {
                    // A stage from a cold cache; its upstream stays cached.
                    for (int dev = 0; dev < 2; ++dev) {
                        const bool gpu = dev == 1;
                        if ((gpu && (col.gpu_set.empty() || !want_gpu)) || (!gpu && !want_cpu)) continue;
                        Scene on = scene;
                        if (gpu) apply_set(on, col.gpu_set);
                        const Evaluation first = graph.evaluate(on, {col.stage});
                        if (gpu && !first.run(col.stage)->warnings.empty()) {
                            std::fprintf(stderr, "  %-10s %-22s %-22s gpu  not measured: %s\n", t.name.c_str(), row.name.c_str(), col.name.c_str(),
                                         first.run(col.stage)->warnings.front().c_str());
                            continue;
                        }
                        // A stage that took over kSlowMs on its first run is timed by that run alone.
                        const double first_ms = first.run(col.stage)->ms;
                        add(gpu ? "gpu" : "cpu", first_ms > kSlowMs ? std::vector<double>{first_ms} : time_runs(o.repeat, [&] {
                            graph.invalidate(col.stage);
                            const Evaluation ev = graph.evaluate(on, {col.stage});
                            return ev.run(col.stage)->ms;
                        }));
                    }
                    continue;
                }
                for (int dev = 0; dev < 2; ++dev) {
                    const bool gpu = dev == 1;
                    if ((gpu && (!col.gpu || !want_gpu)) || (!gpu && (!col.cpu || !want_cpu))) continue;
                    RenderRequest req;
                    req.backend = gpu ? Backend::Gpu : Backend::Cpu;
                    req.width = col.frame_width;
                    req.height = col.frame_height;
                    wb.render(scene, req);  // warm-up: stages cached, GPU resources built
                    add(gpu ? "gpu" : "cpu", time_runs(o.repeat, [&] { return wb.render(scene, req).render_ms; }));
                }
            }
        }
    }

    // [SECTION] Output
    std::ostringstream out;
    if (o.format == "csv") {
        out << "table,row,column,device,median_ms,min_ms,max_ms,paper_ms,paper_over_ours\n";
        for (const auto& c : cells)
            if (!c.info.empty()) out << c.table << ",\"" << c.row << "\",\"" << c.column << "\",info,,,,,\"" << c.info << "\"\n";
            else out << c.table << ",\"" << c.row << "\",\"" << c.column << "\"," << c.device << "," << c.median << "," << c.min << "," << c.max << ","
                << (c.paper ? std::to_string(*c.paper) : "") << "," << (c.paper ? std::to_string(*c.paper / c.median) : "") << "\n";
    } else if (o.format == "json") {
        json j;
        j["machine"] = machine;
        j["version"] = version_string();
        j["repeat"] = o.repeat;
        j["cells"] = json::array();
        for (const auto& c : cells) {
            json x{{"table", c.table}, {"row", c.row}, {"column", c.column}};
            if (!c.info.empty()) {
                x["info"] = c.info;
                j["cells"].push_back(x);
                continue;
            }
            x["device"] = c.device, x["median_ms"] = c.median, x["min_ms"] = c.min, x["max_ms"] = c.max;
            if (c.paper) {
                x["paper_ms"] = *c.paper;
                x["paper_over_ours"] = *c.paper / c.median;
            }
            j["cells"].push_back(x);
        }
        out << j.dump(2) << "\n";
    } else {
        for (const auto& t : tables) {
            out << "### " << t.title << "\n\n";
            out << "Ours: " << machine << "; median of " << o.repeat << " runs [min–max] (a stage over " << int(kSlowMs / 1000) << " s: its first run alone)." << (t.paper_machine.empty() ? "" : " Paper: " + t.paper_machine + ".")
                << "\n\n| |";
            for (const auto& c : t.columns) out << " " << c.name << " |";
            out << "\n|---|";
            for (size_t i = 0; i < t.columns.size(); ++i) out << "---|";
            out << "\n";
            for (const auto& row : t.rows) {
                out << "| " << row.name << " |";
                for (const auto& col : t.columns) {
                    std::string cell;
                    std::optional<double> paper;
                    for (const auto& c : cells) {
                        if (c.table != t.name || c.row != row.name || c.column != col.name) continue;
                        if (!c.info.empty()) {
                            cell = c.info;
                            continue;
                        }
                        cell += (cell.empty() ? "" : "<br>") + std::string(c.device == "gpu" ? "GPU " : "CPU ") + fmt_ms(c.median) + " [" + fmt_ms(c.min) + "–" +
                                fmt_ms(c.max) + "]";
                        paper = c.paper;
                    }
                    if (paper) {
                        double best = 1e300;
                        for (const auto& c : cells)
                            if (c.table == t.name && c.row == row.name && c.column == col.name && c.info.empty()) best = std::min(best, c.median);
                        char r[64];
                        std::snprintf(r, sizeof r, " (×%.3g faster)", *paper / best);
                        cell += "<br>paper " + fmt_ms(*paper) + r;
                    }
                    out << " " << (cell.empty() ? "—" : cell) << " |";
                }
                out << "\n";
            }
            out << "\n";
        }
    }
    if (o.profile) print_profile();
    if (o.out.empty()) {
        std::fputs(out.str().c_str(), stdout);
    } else {
        write_text_atomic(o.out, out.str());
        std::fprintf(stderr, "wrote %s\n", o.out.c_str());
    }
    return 0;
}
}  // namespace mesolab
