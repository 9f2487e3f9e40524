#pragma once
// Subcommands of `mesolab`. Each returns the process exit status: 0 success, 2 bad input,
// 1 internal failure (main() maps exceptions: InputError -> 2, anything else -> 1).
#include <atomic>
#include <cstdint>
#include <functional>
#include <string>
#include <utility>
#include <vector>

namespace mesolab {

class Profiler;
class ParamGroup;
struct Scene;
struct TruthSettings;

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

// The truth's sampling options shared by capture, sweep and bench: `noise` (0: none), `time_limit`
// (text, as --time-limit), `spp` and whether it was given, into `st`; InputError naming the option.
void truth_sampling(double noise, const std::string& time_limit, int spp, bool spp_given, TruthSettings& st);
double parse_duration_s(const std::string& text, const std::string& option);  // "600", "90s", "10m", "1.5h"

struct MergeOptions {
    std::vector<std::string> parts;  // partial truths (NAME.samples-A-B.truth)
    std::string out_dir = ".";
    std::vector<std::string> aovs;
};
int run_truth_merge(const MergeOptions& o);

struct BenchOptions {
    std::string memory_limit;  // --memory-limit: a stage above it stops with exit status 2 (empty: the available memory)
    std::vector<std::string> tables;
    std::string format = "md";
    int repeat = 5;
    std::string out;
    std::string backend = "both";  // cpu|gpu|both
    bool profile = false;
    bool update_pages = false;       // write each table into the pages' <!-- bench NAME --> blocks
    std::string pages_root = ".";    // where README.md and core/*/README.md are
    std::string mesh;                // --mesh FILE: a row for this mesh in the tables that take one
    int vertices = 0;                // --vertices N: simplify it to N vertices (0: the table's choice)
    double noise = 0;                // table truth: measure the time to this noise_rel (0: a pilot, extrapolated)
    std::string time_limit;          // table truth with noise: the most time per preset
    std::vector<std::string> rows, columns;  // --row / --column: only the rows and columns whose names contain one of these
    std::string label;               // --label: this machine's short name in the JSON ("H100"), shown in the pages when merged from bench/NAME.json
    // In-process callers (the Python module): progress per cell ("bench TABLE: ROW / COLUMN",
    // fraction of cells done), a flag that stops between runs (Cancelled), no per-cell lines on
    // stderr, and the output in *output instead of standard output or a file.
    std::function<void(const std::string&, double)> progress;
    const std::atomic<bool>* cancel = nullptr;
    bool quiet = false;
    std::string* output = nullptr;
};
int run_bench(const BenchOptions& o);

struct SweepOptions {
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
    // In-process callers (the Python module), as BenchOptions.
    std::function<void(const std::string&, double)> progress;
    const std::atomic<bool>* cancel = nullptr;
    bool quiet = false;
};
int run_sweep(const SweepOptions& o);

// One measured setting of a sweep.
struct SweepPoint {
    std::string value;
    double ms = 0;       // median time per frame including its stages, from a cold cache
    double err = 0;      // the metric's error (rmse: radiance RMSE; truth: rmse_rel; a technique's metric)
    double rel = 0;      // relative RMSE (rmse, truth)
    double knob_ms = 0;  // of ms: the stages the knob controls
    bool below_noise = false;  // --metric truth: the truth cannot resolve the error
    std::string by;            // --by: the second knob's value
};
struct SweepResult {
    std::vector<SweepPoint> points;
    std::string metric;      // the error's name: rmse, rmse_rel or the technique metric's
    std::string reference;   // what the errors are measured against ("camera.x=..." or "the truth")
    std::string markdown;    // the table `mesolab sweep` prints
    std::vector<std::string> written;  // files written (with out_dir): CSV, Markdown, PNG and SVG plot
};
// The sweep of `base` (o.preset and o.sets are not read: the caller loaded and set the scene);
// the files go to o.out_dir only when write_files.
SweepResult sweep_scene(const Scene& base, const SweepOptions& o, bool write_files);
std::string sweep_metric_names();  // "rmse (default: ...), bumpsynth.ndf_histogram" for help texts and errors

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
// The parameter groups `preset schema TECHNIQUE` lists: all for "", else the technique's or the
// scene group's (camera, light, env, geometry, effects); InputError starting with `what` otherwise.
std::vector<const ParamGroup*> schema_groups(const std::string& technique, const std::string& what);
int run_preset_show(const std::string& file, const std::vector<std::string>& sets);
int run_info();
// What `mesolab info` prints, as (name, value) pairs in its order: version, cpu threads, techniques,
// the headless GL context's platform, vendor, renderer and versions (or "gl": why there is none),
// library versions.
std::vector<std::pair<std::string, std::string>> info_fields();
std::string export_names();  // "btf (microgeom), ..." for help texts

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
