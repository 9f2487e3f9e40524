#pragma once
// Subcommands of `mesolab`. Each returns the process exit status: 0 success, 2 bad input,
// 1 internal failure (main() maps exceptions: InputError -> 2, anything else -> 1).
#include <atomic>
#include <cstdint>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "app/api.h"
#include "core/truth/truth.h"

namespace mesolab {

class Profiler;
class ParamGroup;
struct Scene;

struct CaptureOptions {
    std::string memory_limit;  // --memory-limit: a stage above it stops with exit status 2 (empty: the available memory)
    std::vector<std::string> presets;  // files or folders (every *.json below)
    std::string out_dir = "screenshots";
    std::string size = "512x512";
    std::string backend = "gpu";
    std::vector<std::string> sets;
    std::vector<std::string> aovs;
    bool profile = false;
    int spp = 64;        // --backend truth: samples per pixel
    bool spp_given = false;  // --spp was given (with --noise: the most samples; else unlimited)
    uint64_t seed = 1;   // --backend truth: the random streams' seed
    std::string samples;     // --samples A:B: a partial truth of samples [A, B), written as NAME.samples-A-B.truth
    double noise = 0;        // --noise: sample until the truth's noise_rel reaches it
    std::string time_limit;  // --time-limit: stop sampling after this long (600, 90s, 10m, 1.5h)
    bool no_cache = false;   // --no-cache: compute every stage and truth, read and keep nothing on disk
};
int run_capture(const CaptureOptions& o);

// The truth's sampling options as the command line gives them (capture, sweep, bench): --spp and
// whether it was given, --noise (0: none), --time-limit (text, "" none), --seed; core's
// truth_sampling (core/renderer.h) checks them.
TruthSettings truth_sampling(int spp, bool spp_given, double noise, const std::string& time_limit, uint64_t seed);
double parse_duration_s(const std::string& text, const std::string& option);  // "600", "90s", "10m", "1.5h"

struct MergeOptions {
    std::vector<std::string> parts;  // partial truths (NAME.samples-A-B.truth)
    std::string out_dir = ".";
    std::vector<std::string> aovs;
};
int run_truth_merge(const MergeOptions& o);

// `mesolab bench`: the library's measure_bench (app/api.h) with the command line's text and outputs.
struct BenchCommand {
    BenchOptions run;          // what is measured (typed)
    std::string memory_limit;  // --memory-limit: a stage above it stops with exit status 2 (empty: the available memory)
    std::string time_limit;    // --time-limit (600, 90s, 10m, 1.5h)
    std::string format = "md";
    std::string out;
    bool update_pages = false;       // write each table into the pages' <!-- bench NAME --> blocks
    std::string pages_root = ".";    // where README.md and core/*/README.md are
    std::string label;               // --label: this machine's short name in the JSON ("H100"), shown in the pages when merged from bench/NAME.json
    std::string* output = nullptr;   // in-process callers (tests): the output here instead of standard output or a file
};
int run_bench(const BenchCommand& o);

// `mesolab sweep`: the library's sweep_scene (app/api.h) from the command line's text.
struct SweepCommand {
    std::string memory_limit;  // --memory-limit: a stage above it stops with exit status 2 (empty: the available memory)
    std::string preset;
    std::string knob;                     // KEY=V1,V2,...
    std::vector<std::string> reference;   // KEY=V
    std::string out_dir = "screenshots/sweeps";
    std::string size = "256x256";
    std::string backend = "cpu";
    std::vector<std::string> sets;
    int repeat = 3;
    std::string metric = "rmse";          // rmse, truth or a technique's (Technique::sweep_metrics)
    std::string by;                       // --by KEY=V1,V2,...: a second knob (a grid; --metric truth)
    int spp = 64;                         // the truth's samples per pixel (--metric truth, --backend truth)
    bool spp_given = false;               // with noise: --spp is the most samples
    uint64_t seed = 1;
    double noise = 0;                     // --noise: the truth samples until its noise_rel reaches it
    std::string time_limit;               // --time-limit for the truth
};
int run_sweep(const SweepCommand& o);

// `mesolab frontier`: the library's frontier_scene (app/api.h) from the command line's text.
struct FrontierCommand {
    std::string preset;
    std::string out_dir = "screenshots/frontier";
    std::string size = "128x128";
    std::string backend = "cpu";
    std::vector<double> distances;
    std::vector<std::string> sets;
    int spp = 64;
    bool spp_given = false;
    uint64_t seed = 1;
    double noise = 0;
    std::string time_limit;
    double budget_min = 10;
    int repeat = 3;
    std::string memory_limit;
};
int run_frontier(const FrontierCommand& o);

struct ExportOptions {
    std::string memory_limit;  // --memory-limit: a stage above it stops with exit status 2 (empty: the available memory)
    std::string name;                  // a technique's export, e.g. btf
    std::string preset;
    std::string out;                   // output file
    std::string object;                // scene object (default: the first using the technique)
    std::vector<std::string> options;  // KEY=VALUE
    std::vector<std::string> sets;
};
int run_export(const ExportOptions& o);

int run_preset_validate(const std::vector<std::string>& files);
int run_preset_schema(const std::string& technique, bool as_json);
int run_preset_show(const std::string& file, const std::vector<std::string>& sets);
int run_preset_pack(const std::string& file, const std::vector<std::string>& sets, const std::string& out);
int run_info();

struct GuiOptions {
    std::string memory_limit;  // --memory-limit: a stage above it stops with exit status 2 (empty: the available memory)
    std::string preset;
    std::string script;          // scripted mode: one command per line
    int frames = 0;              // > 0: render N frames then exit
    std::string screenshot;      // with --frames: viewport screenshot path
    std::string window_screenshot;  // with --frames: whole-window screenshot path
    std::string size = "1600x900";
};
int run_gui(const GuiOptions& o);

// Helpers shared by the commands.
// A profiler's hierarchy (PROFILE_SCOPE paths) as a table on stderr.
void print_profile(const Profiler& profiler);
// --memory-limit's value in bytes (0: none given, the machine's available memory applies).
uint64_t memory_limit_bytes(const std::string& text);
void parse_size(const std::string& s, int& w, int& h);  // "WxH", InputError otherwise
std::vector<std::string> expand_presets(const std::vector<std::string>& args);  // folders -> *.json
}  // namespace mesolab
