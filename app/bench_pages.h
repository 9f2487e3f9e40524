#pragma once
// [SECTION] mesolab bench's pages.
// The Markdown of the timing tables (one block per table: our medians beside the paper's figures,
// a frame step's own row under its frame), other machines' figures (`bench --format json --label
// NAME -o bench/NAME.json` there, kept in the repository) merged beside this machine's, and the
// pages' generated blocks (`<!-- bench NAME -->` ... `<!-- /bench -->`) replaced by
// `bench --update-pages`. app/cmd_bench.cpp measures; this file writes.
#include "core/bench.h"
#include "core/param.h"

#include <map>
#include <optional>
#include <string>
#include <vector>

namespace mesolab {

// One measured cell (or a report column's text).
struct BenchCell {
    std::string table, row, column, device;
    std::string step;  // a frame step's own row under the frame column ("" for the cell itself)
    double median = 0, min = 0, max = 0;
    std::optional<double> paper;
    std::string info;  // report columns (BenchColumn::info): the text, no timing
    // GPU frame cells on a hardware GL: the median of the frame's GPU time (timer queries), beside
    // its wall time to a finished frame (median).
    std::optional<double> gpu_time;
    std::string label;  // another machine's cells (bench/*.json): its short name, e.g. "H100"; "" for this run's
};

// A run on another machine, read from bench/NAME.json.
struct OtherMachine {
    std::string file, label, machine;
    int repeat = 0;
    std::vector<BenchCell> cells;
};
// Every bench/*.json under `root` but this machine's own (its figures replace that file's);
// InputError naming the file and key of a bad one.
std::vector<OtherMachine> load_other_machines(const std::string& root, const std::string& this_machine);

// "1.23 ms", "456 µs", "7.8 s".
std::string fmt_ms(double ms);

struct BenchPageInfo {
    std::string machine;   // this machine, as the tables' header says it
    int repeat = 1;        // runs per cell
    double slow_ms = 0;    // stage cells slower than this were measured once
    std::string gpu_note;  // what the GPU cells mean on this GL ("" without GPU cells)
};
// The Markdown of each table, by name: this run's cells and the other machines'.
std::map<std::string, std::string> bench_markdown(const std::vector<BenchTable>& tables, const std::vector<BenchCell>& cells,
                                                  const std::vector<OtherMachine>& others, const BenchPageInfo& info);

// Replaces, in README.md and core/*/README.md under `root`, the text between the lines
// `<!-- bench NAME -->` and `<!-- /bench -->` by table NAME's Markdown (tables not measured this
// run are left as they are). Each page is written atomically. Returns the pages changed.
std::vector<std::string> update_pages(const std::string& root, const std::map<std::string, std::string>& markdown);
}  // namespace mesolab
