// mesolab bench: timing tables laid out like the papers' tables, our CPU/GPU medians beside
// the paper's figures: the measurements and the output formats (the pages: bench_pages.h).
#include "core/file.h"
#include "app/bench_pages.h"
#include "app/commands.h"
#include "app/workbench.h"
#include "core/bench.h"
#include "core/truth/truth.h"
#include "core/error.h"
#include "core/profile.h"
#include "core/technique.h"

#include <cmath>
#include <cstdlib>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <sstream>
#include <thread>

namespace mesolab {

std::string cpu_model() {
    std::ifstream in("/proc/cpuinfo");
    std::string line;
    while (std::getline(in, line))
        if (line.rfind("model name", 0) == 0) return line.substr(line.find(':') + 2);
    return "unknown CPU";
}

namespace {

constexpr double kSlowMs = 10000;  // stage cells slower than this are measured once

std::vector<double> time_runs(int n, const std::function<double()>& once, const std::atomic<bool>* cancel) {
    std::vector<double> v;
    for (int i = 0; i < n; ++i) {
        if (cancel && cancel->load()) throw Cancelled();
        v.push_back(once());
    }
    return v;
}
}  // namespace

BenchResult measure_bench(const BenchOptions& o) {
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
    // --noise: the truth table measures each preset's time to that noise.
    if (o.noise != 0.0) {
        const TruthSettings st = truth_sampling(std::nullopt, o.noise, o.time_limit_s, 1);
        bool found = false;
        for (auto& t : tables)
            if (t.name == "truth") t = truth_bench_table(st.noise, st.time_limit_s), found = true;
        if (!found) throw InputError("--noise: only the table truth takes it (mesolab bench truth --noise 0.01)");
    }
    // --preset: the truth table's rows are the user's presets or packs.
    if (!o.presets.empty()) {
        bool found = false;
        for (auto& t : tables) {
            if (t.name != "truth") continue;
            found = true;
            t.rows.clear();
            for (const std::string& path : o.presets) {
                const Scene s = load_preset(path);  // a bad preset or pack fails before any work
                check_truth_request(s, 64, 64, TruthSettings{}, {});
                std::string name = s.name;
                for (int k = 2; std::any_of(t.rows.begin(), t.rows.end(), [&](const BenchRow& r) { return r.name == name; }); ++k)
                    name = s.name + " #" + std::to_string(k);
                t.rows.push_back({name, [path] { return load_preset(path); }, {}});
            }
        }
        if (!found) throw InputError("--preset: only the table truth takes presets (mesolab bench truth --preset FILE)");
    }
    // --row / --column: the cells asked for; a filter that matches nothing is an error, naming what there is.
    const auto contains_any = [](const std::string& name, const std::vector<std::string>& parts) {
        return parts.empty() || std::any_of(parts.begin(), parts.end(), [&](const std::string& p) { return name.find(p) != std::string::npos; });
    };
    if (!o.rows.empty() || !o.columns.empty()) {
        std::string row_names, column_names;
        for (auto& t : tables) {
            for (const auto& r : t.rows) row_names += (row_names.empty() ? "'" : ", '") + r.name + "'";
            for (const auto& c : t.columns) column_names += (column_names.empty() ? "'" : ", '") + c.name + "'";
            std::erase_if(t.rows, [&](const BenchRow& r) { return !contains_any(r.name, o.rows); });
            std::vector<BenchColumn> columns;
            for (size_t ci = 0; ci < t.columns.size(); ++ci)
                if (contains_any(t.columns[ci].name, o.columns)) columns.push_back(t.columns[ci]);
            // The paper's figures follow their columns.
            for (auto& r : t.rows) {
                std::vector<std::optional<double>> paper;
                for (size_t ci = 0; ci < t.columns.size(); ++ci)
                    if (contains_any(t.columns[ci].name, o.columns)) paper.push_back(ci < r.paper_ms.size() ? r.paper_ms[ci] : std::nullopt);
                r.paper_ms = paper;
            }
            t.columns = columns;
        }
        std::erase_if(tables, [](const BenchTable& t) { return t.rows.empty() || t.columns.empty(); });
        if (tables.empty())
            throw InputError("bench: no cell matches --row/--column; rows: " + row_names + "; columns: " + column_names);
    }
    if (o.vertices < 0) throw InputError("--vertices: " + std::to_string(o.vertices) + " must be >= 0");
    if (!o.mesh.empty() || o.vertices > 0) {
        if (o.mesh.empty()) throw InputError("--vertices: needs --mesh FILE");
        // The user's mesh: only its row, in the tables that take one.
        std::vector<BenchTable> with_mesh;
        for (auto& t : tables)
            if (t.mesh_row) {
                t.rows = {t.mesh_row(std::filesystem::absolute(o.mesh).string(), o.vertices)};
                with_mesh.push_back(std::move(t));
            }
        if (with_mesh.empty()) throw InputError("--mesh: none of the tables asked for takes a mesh (translucency does)");
        tables = std::move(with_mesh);
    }

    std::optional<Workbench> own;
    Workbench& wb = o.workbench ? *o.workbench : own.emplace();
    if (wb.session().store()) throw std::logic_error("measure_bench: the workbench's stage store is set; set it aside to time from a cold cache");
    if (!o.workbench || o.memory_limit) wb.session().set_memory_limit(o.memory_limit);
    Session& session = wb.session();
    const bool want_gpu = o.backend != "cpu", want_cpu = o.backend != "gpu";
    std::string gl = "none";
    if (want_gpu) {
        try {
            gl = wb.renderer("gpu").device();
            wb.renderer("gpu").set_pass_timing(o.profile);  // a software renderer times each pass only when asked
        } catch (const std::exception& e) {
            throw std::runtime_error(std::string("bench needs an OpenGL context for GPU columns (use --backend cpu): ") + e.what());
        }
    }
    std::string machine = cpu_model() + ", " + std::to_string(std::thread::hardware_concurrency()) + " threads; GL: " + gl;
    // Large stage results on transparent huge pages (run.sh sets this): said, since it changes
    // the cost of fresh allocations of tens of MB several-fold on machines with slow page faults.
    if (const char* t = std::getenv("GLIBC_TUNABLES"); t && std::string(t).find("glibc.malloc.hugetlb=1") != std::string::npos)
        machine += "; malloc on huge pages";
    // A stage's time in an evaluation: the sum over the objects it ran for.
    const auto stage_ms = [](const Evaluation& ev, const StageName& stage) {
        double ms = 0;
        for (const StageRun* r : ev.runs_of(stage)) ms += r->ms;
        return ms;
    };
    const auto stage_warning = [](const Evaluation& ev, const StageName& stage) -> std::string {
        for (const StageRun* r : ev.runs_of(stage))
            if (!r->warnings.empty()) return r->warnings.front();
        return {};
    };

    // What a GPU frame cell holds on this GL.
    std::string gpu_note;
    if (want_gpu) gpu_note = " " + wb.renderer("gpu").timing_note();
    std::vector<BenchCell> cells;
    size_t cells_total = 0, cells_done = 0;
    for (const auto& t : tables) cells_total += t.rows.size() * t.columns.size();
    const auto stopped = [&] {
        if (o.cancel && o.cancel->load()) throw Cancelled();
    };
    for (const auto& t : tables) {
        for (const auto& row : t.rows) {
            stopped();
            const Scene scene = row.scene();
            for (size_t ci = 0; ci < t.columns.size(); ++ci, ++cells_done) {
                const BenchColumn& col = t.columns[ci];
                stopped();
                if (o.progress) o.progress("bench " + t.name + ": " + row.name + " / " + col.name, double(cells_done) / double(std::max<size_t>(1, cells_total)));
                const std::optional<double> paper = ci < row.paper_ms.size() ? row.paper_ms[ci] : std::nullopt;
                auto add = [&](const char* device, const std::vector<double>& v, const std::string& step = "", const std::vector<double>& gpu_times = {}) {
                    if (v.empty()) return;
                    BenchCell c{t.name, row.name, col.name, device, step, median_of(v), *std::min_element(v.begin(), v.end()), *std::max_element(v.begin(), v.end()),
                           step.empty() ? paper : (row.paper_step_ms.count(step) ? std::optional<double>(row.paper_step_ms.at(step)) : std::nullopt)};
                    if (!gpu_times.empty()) c.gpu_time = median_of(gpu_times);
                    cells.push_back(c);
                    if (!o.quiet)
                        std::fprintf(stderr, "  %-10s %-22s %-22s %-4s %s%s\n", t.name.c_str(), (step.empty() ? row.name : row.name + " / " + step).c_str(), col.name.c_str(),
                                 device, fmt_ms(c.median).c_str(), c.gpu_time ? (" (GPU time " + fmt_ms(*c.gpu_time) + ")").c_str() : "");
                };
                if (col.info) {
                    const Evaluation ev = session.evaluate_frame(scene, {}, o.cancel);
                    BenchCell c{t.name, row.name, col.name, "-", "", 0, 0, 0, std::nullopt, col.info(scene, ev)};
                    if (!o.quiet) std::fprintf(stderr, "  %-10s %-22s %-22s %s\n", t.name.c_str(), row.name.c_str(), col.name.c_str(), c.info.c_str());
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
                        session.cache().invalidate(col.stage);
                        const Evaluation first = session.evaluate(on, {col.stage}, {}, o.cancel);
                        if (first.runs_of(col.stage).empty() || first.run(col.stage)->status != StageStatus::Ran) {
                            if (!o.quiet)
                                std::fprintf(stderr, "  %-10s %-22s %-22s %-4s not measured: the stage did not run for this row\n", t.name.c_str(), row.name.c_str(),
                                         col.name.c_str(), gpu ? "gpu" : "cpu");
                            continue;
                        }
                        if (gpu && !stage_warning(first, col.stage).empty()) {
                            if (!o.quiet)
                                std::fprintf(stderr, "  %-10s %-22s %-22s gpu  not measured: %s\n", t.name.c_str(), row.name.c_str(), col.name.c_str(),
                                         stage_warning(first, col.stage).c_str());
                            continue;
                        }
                        // A stage that took over kSlowMs on its first run is timed by that run alone.
                        const double first_ms = stage_ms(first, col.stage);
                        add(gpu ? "gpu" : "cpu", first_ms > kSlowMs ? std::vector<double>{first_ms} : time_runs(o.repeat, [&] {
                            session.cache().invalidate(col.stage);
                            return stage_ms(session.evaluate(on, {col.stage}, {}, o.cancel), col.stage);
                        }, o.cancel));
                    }
                    continue;
                }
                for (int dev = 0; dev < 2; ++dev) {
                    const bool gpu = dev == 1;
                    if ((gpu && (!col.gpu || !want_gpu)) || (!gpu && (!col.cpu || !want_cpu))) continue;
                    RenderRequest req;
                    req.renderer = gpu ? "gpu" : "cpu";
                    req.width = col.frame_width;
                    req.height = col.frame_height;
                    req.aovs = {"radiance"};
                    req.cancel = o.cancel;
                    wb.render(scene, req);  // warm-up: stages cached, GPU resources built
                    // Frame steps (offscreen work before the frame) get rows of their own. They are
                    // timed from scratch in every run: their reuse between frames is disabled here.
                    std::vector<std::pair<std::string, std::vector<double>>> steps;  // in the order they run
                    std::vector<double> gpu_times;  // the frames' GPU time (timer queries, hardware GL only)
                    const std::vector<double> wall = time_runs(o.repeat, [&] {
                        wb.forget_frame_steps();
                        const RenderResult r = wb.render(scene, req);
                        if (gpu && !r.gpu_ms_is_wall && std::isfinite(r.gpu_ms)) gpu_times.push_back(r.gpu_ms);
                        for (const auto& st : r.frame.steps) {
                            auto it = std::find_if(steps.begin(), steps.end(), [&](const auto& x) { return x.first == st.name; });
                            if (it == steps.end()) it = steps.insert(steps.end(), {st.name, {}});
                            if (std::isfinite(st.ms)) it->second.push_back(st.ms);
                        }
                        return r.render_ms;
                    }, o.cancel);
                    add(gpu ? "gpu" : "cpu", wall, "", gpu_times);
                    for (const auto& [name, v] : steps) add(gpu ? "gpu" : "cpu", v, name);
                }
            }
        }
    }

    if (o.profile) print_profile(session.profiler());
    return {machine, o.repeat, kSlowMs, want_gpu ? gpu_note : "", tables, cells};
}

json bench_json(const BenchResult& r, const std::string& label) {
    json j;
    j["machine"] = r.machine;
    if (!label.empty()) j["label"] = label;
    j["version"] = version_string();
    j["repeat"] = r.repeat;
    j["cells"] = json::array();
    for (const auto& c : r.cells) {
        json x{{"table", c.table}, {"row", c.row}, {"column", c.column}};
        if (!c.step.empty()) x["step"] = c.step;
        if (!c.info.empty()) {
            x["info"] = c.info;
            j["cells"].push_back(x);
            continue;
        }
        x["device"] = c.device, x["median_ms"] = c.median, x["min_ms"] = c.min, x["max_ms"] = c.max;
        if (c.gpu_time) x["gpu_time_ms"] = *c.gpu_time;
        if (c.paper) {
            x["paper_ms"] = *c.paper;
            x["paper_over_ours"] = *c.paper / c.median;
        }
        j["cells"].push_back(x);
    }
    return j;
}

// [SECTION] The command: text in, formats out
int run_bench(const BenchCommand& cmd) {
    if (cmd.format != "md" && cmd.format != "csv" && cmd.format != "json") throw InputError("--format: '" + cmd.format + "' is not one of md|csv|json");
    if (cmd.update_pages && (!cmd.run.rows.empty() || !cmd.run.columns.empty()))
        throw InputError("--update-pages writes whole tables: it does not take --row or --column");
    if (cmd.run.noise == 0.0 && !cmd.time_limit.empty()) throw InputError("--time-limit: with bench it bounds the truth table's --noise runs; add --noise");
    BenchOptions o = cmd.run;
    o.memory_limit = memory_limit_bytes(cmd.memory_limit);
    if (!cmd.time_limit.empty()) o.time_limit_s = parse_duration_s(cmd.time_limit, "--time-limit");
    const BenchResult r = measure_bench(o);
    std::ostringstream out;
    if (cmd.format == "csv") {
        out << "table,row,column,device,median_ms,min_ms,max_ms,paper_ms,paper_over_ours,gpu_time_ms\n";
        for (const auto& c : r.cells)
            if (!c.info.empty()) out << c.table << ",\"" << c.row << "\",\"" << c.column << "\",info,,,,,\"" << c.info << "\"\n";
            else out << c.table << ",\"" << (c.step.empty() ? c.row : c.row + " / step " + c.step) << "\",\"" << c.column << "\"," << c.device << "," << c.median << "," << c.min << "," << c.max << ","
                << (c.paper ? std::to_string(*c.paper) : "") << "," << (c.paper ? std::to_string(*c.paper / c.median) : "") << ","
                << (c.gpu_time ? std::to_string(*c.gpu_time) : "") << "\n";
    } else if (cmd.format == "json") {
        out << bench_json(r, cmd.label).dump(2) << "\n";
    }
    // Markdown, one block per table (also what --update-pages writes into the pages, with the
    // figures of other machines kept in bench/*.json beside this run's).
    const std::vector<OtherMachine> others = cmd.update_pages ? load_other_machines(cmd.pages_root, r.machine) : std::vector<OtherMachine>{};
    const std::map<std::string, std::string> markdown = bench_markdown(r.tables, r.cells, others, {r.machine, r.repeat, r.slow_ms, r.gpu_note});
    if (cmd.format == "md")
        for (const auto& t : r.tables) out << markdown.at(t.name);
    if (cmd.update_pages) {
        for (const auto& page : update_pages(cmd.pages_root, markdown)) std::fprintf(stderr, "updated %s\n", page.c_str());
    } else if (cmd.output) {
        *cmd.output = out.str();
    } else if (cmd.out.empty()) {
        std::fputs(out.str().c_str(), stdout);
    } else {
        write_text_atomic(cmd.out, out.str());
        std::fprintf(stderr, "wrote %s\n", cmd.out.c_str());
    }
    return 0;
}
}  // namespace mesolab
