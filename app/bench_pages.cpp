// mesolab bench's pages: the Markdown of its tables, other machines' figures merged beside this
// machine's, and the pages' generated blocks replaced (see bench_pages.h).
#include "app/bench_pages.h"
#include "core/error.h"
#include "core/file.h"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace mesolab {

std::string fmt_ms(double ms) {
    char b[64];
    if (ms >= 1000.0) std::snprintf(b, sizeof b, "%.3g s", ms / 1000.0);
    else if (ms >= 1.0) std::snprintf(b, sizeof b, "%.3g ms", ms);
    else std::snprintf(b, sizeof b, "%.3g µs", ms * 1000.0);
    return b;
}

// [SECTION] Other machines' figures
// A run on another machine (`bench --format json --label NAME -o bench/NAME.json` there), kept in
// the repository and merged into the pages by --update-pages, beside this machine's figures.
std::vector<OtherMachine> load_other_machines(const std::string& root, const std::string& this_machine) {
    namespace fs = std::filesystem;
    std::vector<fs::path> files;
    std::error_code ec;
    for (const auto& e : fs::directory_iterator(fs::path(root) / "bench", ec))
        if (e.path().extension() == ".json") files.push_back(e.path());
    std::sort(files.begin(), files.end());
    std::vector<OtherMachine> out;
    for (const auto& f : files) {
        const std::string where = f.string();
        json j;
        try {
            std::ifstream in(f);
            if (!in) throw InputError(where + ": cannot be read");
            j = json::parse(in);
        } catch (const json::exception& e) {
            throw InputError(where + ": not a bench JSON file (" + e.what() + ")");
        }
        const auto need = [&](const json& o, const char* key, json::value_t type, const std::string& at) -> const json& {
            if (!o.contains(key) || (o[key].type() != type && !(type == json::value_t::number_float && o[key].is_number())))
                throw InputError(where + ": " + at + "\"" + key + "\" is missing or not a " + (type == json::value_t::string ? "string" : type == json::value_t::array ? "list" : "number"));
            return o[key];
        };
        OtherMachine m;
        m.file = where;
        m.machine = need(j, "machine", json::value_t::string, "").get<std::string>();
        if (m.machine == this_machine) continue;  // this run's figures replace that file's
        m.label = j.contains("label") && j["label"].is_string() ? j["label"].get<std::string>() : f.stem().string();
        m.repeat = j.contains("repeat") && j["repeat"].is_number_integer() ? j["repeat"].get<int>() : 0;
        size_t k = 0;
        for (const json& c : need(j, "cells", json::value_t::array, "")) {
            const std::string at = "cells[" + std::to_string(k++) + "]: ";
            if (c.contains("info")) continue;  // reports (sizes, counts) are the same anywhere
            BenchCell x;
            x.table = need(c, "table", json::value_t::string, at).get<std::string>();
            x.row = need(c, "row", json::value_t::string, at).get<std::string>();
            x.column = need(c, "column", json::value_t::string, at).get<std::string>();
            x.device = need(c, "device", json::value_t::string, at).get<std::string>();
            if (x.device != "cpu" && x.device != "gpu") throw InputError(where + ": " + at + "\"device\" is '" + x.device + "', expected cpu or gpu");
            x.step = c.contains("step") && c["step"].is_string() ? c["step"].get<std::string>() : "";
            x.median = need(c, "median_ms", json::value_t::number_float, at).get<double>();
            x.min = need(c, "min_ms", json::value_t::number_float, at).get<double>();
            x.max = need(c, "max_ms", json::value_t::number_float, at).get<double>();
            if (c.contains("gpu_time_ms") && c["gpu_time_ms"].is_number()) x.gpu_time = c["gpu_time_ms"].get<double>();
            x.label = m.label;
            m.cells.push_back(x);
        }
        out.push_back(std::move(m));
    }
    return out;
}

// [SECTION] Pages
std::vector<std::string> update_pages(const std::string& root, const std::map<std::string, std::string>& markdown) {
    namespace fs = std::filesystem;
    std::vector<fs::path> pages{fs::path(root) / "README.md"};
    std::error_code ec;
    for (const auto& e : fs::directory_iterator(fs::path(root) / "core", ec))
        if (e.is_directory() && fs::exists(e.path() / "README.md")) pages.push_back(e.path() / "README.md");
    std::sort(pages.begin() + 1, pages.end());
    std::vector<std::string> changed;
    size_t markers = 0;
    for (const auto& page : pages) {
        std::ifstream in(page);
        if (!in) continue;
        std::stringstream ss;
        ss << in.rdbuf();
        const std::string text = ss.str();
        std::string result;
        size_t pos = 0;
        // A marker is a whole line: `<!-- bench NAME -->` ... `<!-- /bench -->`.
        const auto line_at = [&](const std::string& prefix, size_t from) {
            for (size_t at = text.find(prefix, from); at != std::string::npos; at = text.find(prefix, at + 1))
                if (at == 0 || text[at - 1] == '\n') return at;
            return std::string::npos;
        };
        for (;;) {
            const size_t open = line_at("<!-- bench ", pos);
            if (open == std::string::npos) break;
            const size_t eol = std::min(text.find('\n', open), text.size());
            const std::string line = text.substr(open, eol - open);
            const size_t open_end = line.rfind("-->");
            if (open_end == std::string::npos || open_end < 11)
                throw InputError(page.string() + ": a line starting `<!-- bench ` must be `<!-- bench NAME -->`");
            std::string name = line.substr(11, open_end - 11);
            name.erase(name.find_last_not_of(' ') + 1);
            const size_t body = std::min(eol + 1, text.size());
            const size_t close = line_at("<!-- /bench -->", body);
            if (close == std::string::npos) throw InputError(page.string() + ": `<!-- bench " + name + " -->` has no `<!-- /bench -->` line after it");
            ++markers;
            result += text.substr(pos, body - pos);
            auto it = markdown.find(name);
            result += it != markdown.end() ? it->second : text.substr(body, close - body);
            pos = close;
        }
        result += text.substr(pos);
        if (result != text) {
            write_text_atomic(page.string(), result);
            changed.push_back(page.string());
        }
    }
    if (markers == 0) throw InputError("--update-pages: no `<!-- bench NAME -->` marker in " + root + "/README.md or " + root + "/core/*/README.md");
    return changed;
}

// [SECTION] Markdown
std::map<std::string, std::string> bench_markdown(const std::vector<BenchTable>& tables, const std::vector<BenchCell>& own,
                                                  const std::vector<OtherMachine>& others, const BenchPageInfo& info) {
    std::vector<BenchCell> cells = own;
    for (const OtherMachine& m : others) cells.insert(cells.end(), m.cells.begin(), m.cells.end());
    std::map<std::string, std::string> markdown;
    for (const auto& t : tables) {
        std::ostringstream md;
        {
            md << "### " << t.title << "\n\n";
            md << "Ours: " << info.machine << "; median of " << info.repeat << " runs [min–max] (a stage over " << int(info.slow_ms / 1000) << " s: its first run alone)." << (t.paper_machine.empty() ? "" : " Paper: " + t.paper_machine + ".") << info.gpu_note;
            for (const OtherMachine& m : others)
                if (std::any_of(m.cells.begin(), m.cells.end(), [&](const BenchCell& c) { return c.table == t.name; }))
                    md << " **" << m.label << ":** " << m.machine << "; median of " << m.repeat << " runs; GPU frame cells give the wall time to a finished frame, then the GPU time (timer queries); from `" << std::filesystem::path(m.file).filename().string() << "`.";
            md << "\n\n| |";
            for (const auto& c : t.columns) md << " " << c.name << " |";
            md << "\n|---|";
            for (size_t i = 0; i < t.columns.size(); ++i) md << "---|";
            md << "\n";
            // One line per row, then one per frame step of that row ("↳ step NAME"), its time under the frame column.
            for (const auto& row : t.rows) {
                std::vector<std::string> row_steps{""};
                for (const auto& c : cells)
                    if (c.table == t.name && c.row == row.name && !c.step.empty() &&
                        std::find(row_steps.begin(), row_steps.end(), c.step) == row_steps.end())
                        row_steps.push_back(c.step);
                for (const std::string& step : row_steps) {
                    md << "| " << (step.empty() ? row.name : "↳ step " + step) << " |";
                    for (const auto& col : t.columns) {
                        std::string cell;
                        std::optional<double> paper;
                        for (const auto& c : cells) {
                            if (c.table != t.name || c.row != row.name || c.column != col.name || c.step != step) continue;
                            if (!c.info.empty()) {
                                cell = c.info;
                                continue;
                            }
                            cell += (cell.empty() ? "" : "<br>") + (c.label.empty() ? "" : "**" + c.label + "** ") + std::string(c.device == "gpu" ? "GPU " : "CPU ") +
                                    fmt_ms(c.median) + " [" + fmt_ms(c.min) + "–" + fmt_ms(c.max) + "]";
                            if (c.gpu_time) cell += " (GPU time " + fmt_ms(*c.gpu_time) + ")";
                            if (c.label.empty()) paper = c.paper;
                        }
                        if (paper) {
                            double best = 1e300;
                            for (const auto& c : cells)
                                if (c.table == t.name && c.row == row.name && c.column == col.name && c.step == step && c.info.empty() && c.label.empty())
                                    best = std::min(best, c.median);
                            char r[64];
                            std::snprintf(r, sizeof r, " (×%.3g faster)", *paper / best);
                            cell += "<br>paper " + fmt_ms(*paper) + r;
                        }
                        md << " " << (cell.empty() ? (step.empty() ? "—" : "") : cell) << " |";
                    }
                    md << "\n";
                }
            }
            md << "\n";
        }
        markdown[t.name] = md.str();
    }
    return markdown;
}
}  // namespace mesolab
