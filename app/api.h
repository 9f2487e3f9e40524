#pragma once
// [SECTION] mesolab as a C++ library
// What the command line (app/main.cpp, app/commands.h) and the Python module (python/mesolab.cpp)
// both call, with typed values: no option text goes in, no printed text comes back.
//  - Scenes: core/scene.h (load_preset, apply_set: the one place where a text value becomes a
//    typed one), core/param.h.
//  - Rendering: Workbench (app/workbench.h) over the renderers of core/renderer.h, a
//    RenderRequest in, a RenderResult out; write_capture for the files `capture` writes.
//  - Timing tables: measure_bench -> BenchResult (cells as values; bench_markdown and the JSON
//    writer format them).
//  - Accuracy against time: sweep_scene -> SweepResult, frontier_scene -> FrontierResult (points as values).
// This library does not link the window, the panels or ImGui (the target mesolab_lib).
#include "app/bench_pages.h"
#include "app/workbench.h"
#include "core/bench.h"
#include "core/param.h"
#include "core/scene.h"
#include "core/truth/truth.h"

#include <atomic>
#include <cstdint>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace mesolab {

class ParamGroup;

// [SECTION] Timing tables
// The CPU's model name as the system gives it (/proc/cpuinfo), named beside every figure measured.
std::string cpu_model();

struct BenchOptions {
    std::vector<std::string> tables;  // bench_tables() names; empty: all
    int repeat = 5;                   // runs per cell, 1..1000
    std::string backend = "both";     // the devices of the columns: cpu, gpu or both
    bool profile = false;             // the scoped CPU/GPU timing hierarchy (print_profile) at the end
    std::string mesh;                 // a row for this mesh in the tables that take one ("" : none)
    int vertices = 0;                 // simplify it to this many vertices (0: the table's choice)
    double noise = 0;                 // table truth: measure each preset's time to this noise_rel (0: a pilot, extrapolated)
    double time_limit_s = 600;        // table truth with noise: the most time per preset (seconds)
    std::vector<std::string> rows, columns;  // only the rows and columns whose names contain one of these
    std::vector<std::string> presets;        // table truth: a row for each of these presets or packs (named after its scene) instead of the shipped presets
    uint64_t memory_limit = 0;        // bytes; a stage above it stops (InputError); 0: the available memory
    // Progress per cell ("bench TABLE: ROW / COLUMN", fraction of cells done), a flag that stops
    // between runs (Cancelled), no per-cell lines on stderr.
    std::function<void(const std::string&, double)> progress;
    const std::atomic<bool>* cancel = nullptr;
    bool quiet = false;
    // Run on this workbench (its GL context and truth cache; memory_limit, when not 0, is set on
    // it) instead of a fresh one. It must have no stage store set: the times are from a cold cache.
    Workbench* workbench = nullptr;
};

struct BenchResult {
    std::string machine;   // CPU model, threads, GL renderer
    int repeat = 0;
    double slow_ms = 0;    // stage cells slower than this were measured once
    std::string gpu_note;  // what the GPU cells mean on this GL ("" without GPU cells)
    std::vector<BenchTable> tables;  // as measured (rows and columns filtered)
    std::vector<BenchCell> cells;
};
// Measures the tables. InputError for an unknown table, a filter that matches nothing, bad
// settings; Cancelled when o.cancel was set.
BenchResult measure_bench(const BenchOptions& o);
// `bench --format json`'s document: {machine, label, version, repeat, cells: [...]}.
json bench_json(const BenchResult& r, const std::string& label = "");

// [SECTION] Accuracy against time
// A parameter and its settings, each as preset text (apply_set reads them; e.g. "16", "true").
struct SweepKnob {
    std::string key;
    std::vector<std::string> values;
};

struct SweepOptions {
    SweepKnob knob;
    SweepKnob by;                         // a second knob (a grid; metric "truth"); key "": none
    std::vector<std::pair<std::string, std::string>> reference;  // KEY, VALUE of the reference rendering (default: the knob's most accurate setting)
    int width = 256, height = 256;
    std::string backend = "cpu";          // a renderer's name (core/renderer.h)
    int repeat = 3;                       // timed runs per value (median), 1..100
    std::string metric = "rmse";          // rmse, truth or a technique's (Technique::sweep_metrics)
    TruthSettings truth;                  // the truth's sampling (metric "truth", backend "truth"): core's truth_sampling
    uint64_t memory_limit = 0;            // bytes; 0: the available memory
    std::string out_dir = "screenshots/sweeps";  // where sweep_scene writes its files (write_files)
    std::string source;                   // the preset's file, for messages ("": the scene's name)
    std::function<void(const std::string&, double)> progress;
    const std::atomic<bool>* cancel = nullptr;
    bool quiet = false;
    // Run on this workbench (its GL context and truth cache; memory_limit, when not 0, is set on
    // it) instead of a fresh one. It must have no stage store set: the times are from a cold cache.
    Workbench* workbench = nullptr;
};

// One measured setting of a sweep.
struct SweepPoint {
    std::string value;
    double ms = 0;       // median time per frame including its stages, from a cold cache
    double err = 0;      // the metric's error (rmse: radiance RMSE; truth: rmse_rel; a technique's metric)
    double rel = 0;      // relative RMSE (rmse, truth)
    double knob_ms = 0;  // of ms: the stages the knob controls
    bool below_noise = false;  // metric truth: the truth cannot resolve the error
    std::string by;            // the second knob's value
};
struct SweepResult {
    std::vector<SweepPoint> points;
    std::string metric;      // the error's name: rmse, rmse_rel or the technique metric's
    std::string reference;   // what the errors are measured against ("camera.x=..." or "the truth")
    std::string markdown;    // the table `mesolab sweep` prints
    std::vector<std::string> written;  // files written (with write_files): CSV, Markdown, PNG and SVG plot
};
// The sweep of `base`; the files go to o.out_dir only when write_files.
SweepResult sweep_scene(const Scene& base, const SweepOptions& o, bool write_files);
std::string sweep_metric_names();
// What a sweep of `knob` measures against (metric rmse or a technique's): `reference` when given,
// else the knob's declared reference setting, else its most accurate value among knob.values, as
// (KEY, VALUE) pairs. InputError as sweep_scene's for the knob.
std::vector<std::pair<std::string, std::string>> sweep_reference(const Scene& base, const SweepKnob& knob,
                                                                 const std::vector<std::pair<std::string, std::string>>& reference);  // "rmse (default: ...), bumpsynth.ndf_histogram" for help texts and errors

// [SECTION] The accuracy-time frontier
// For every method of the scene's techniques (`<technique>.method`: the scene's own, then each
// other with the rest as the scene has them), every accuracy knob (ParamDecl::accuracy) that the
// method uses and of the scene's geometry, each on
// a coarse grid around the preset's value with the others as the preset has them, then all of them
// together a step cheaper or dearer at a time (the diagonal, where the frontier usually runs),
// then, between each two neighbours on the frontier, every knob at the geometric mean of theirs;
// all within a time budget; each setting rendered and timed (its precomputation, the stages from a cold
// cache, once; the frame, the median of `repeat` frames with the stages cached) and measured
// against one truth per viewing distance (the truth cache keeps it). The frontier is the lower
// envelope of error against frame time.
struct FrontierOptions {
    int width = 128, height = 128;
    std::string backend = "cpu";          // a real-time renderer's name
    std::vector<double> distances;        // camera.distance values (orbit camera); empty: the preset's
    TruthSettings truth;                  // the truth's sampling (core's truth_sampling)
    double budget_s = 600;                // stops starting new settings after this long, shared evenly by the distances (each starts with its preset)
    int repeat = 3;                       // frames per setting (median), 1..100
    uint64_t memory_limit = 0;            // bytes; 0: the available memory
    std::string out_dir;                  // where frontier_scene writes its files (write_files)
    std::string source;                   // the preset's file, for messages
    std::function<void(const std::string&, double)> progress;
    std::function<void(const struct FrontierPoint&)> on_point;  // each point as it is measured (the window draws them as they come)
    const std::atomic<bool>* cancel = nullptr;
    bool quiet = false;
};

struct FrontierPoint {
    double distance = 0;      // camera.distance
    std::string method;       // its methods (`<technique>.method` of the scene's techniques, "+"-joined; a technique without methods by name)
    std::vector<std::pair<std::string, std::string>> settings;  // KEY, VALUE: each TECHNIQUE.method, then the method's accuracy knobs
    std::string varied;       // what this point changes from the preset: "KEY=VALUE", "all x0.5", "between A and B" or "preset"
    double frame_ms = 0;      // median frame time with its stages cached
    double precompute_ms = 0; // the stages from a cold cache (read from nowhere: the store is not used)
    double rmse_rel = 0;      // against the truth at this distance
    bool below_noise = false; // within twice the truth's noise: not resolved
    bool on_frontier = false; // no faster-or-equal point has a lower error
};

struct FrontierResult {
    std::string scene, machine, backend;
    std::vector<std::string> knobs;    // the method keys and the accuracy knobs varied (of any method)
    std::vector<FrontierPoint> points; // in the order measured
    std::vector<double> truth_noise;   // per distance (as `distances`), the truth's noise_rel
    std::vector<double> distances;
    bool budget_reached = false;       // settings were left out for the budget
    std::vector<std::string> skipped;  // settings a stage refused ("SETTING: why"), left out
    std::string markdown;              // the table the command prints
    std::vector<std::string> written;  // Markdown, CSV, JSON, and a PNG and SVG plot per distance (write_files)
};
FrontierResult frontier_scene(const Scene& base, const FrontierOptions& o, bool write_files);
// Marks the lower envelope: a point is on the frontier when no point of the same distance that is
// as fast or faster has a lower error.
void mark_frontier(std::vector<FrontierPoint>& points);

// The frontier in its parts, for running its points elsewhere (mesolab/cluster.py spreads them over
// a Dask cluster); frontier_scene is these in order: the first round's settings at each distance,
// then the second round's between the first round's frontier, then the report.
struct FrontierSetting {
    std::string method;  // as FrontierPoint::method
    std::string varied;  // as FrontierPoint::varied
    std::vector<std::pair<std::string, std::string>> settings;  // as FrontierPoint::settings
    bool preset() const { return varied == "preset"; }  // each method's preset is always measured, whatever the budget
};
// The first round: for each method its preset, the diagonal (all knobs x0.25 .. x4) and each knob
// alone, the methods taking turns (a budget cuts them alike). Checks the options and every value
// (InputError) before any work.
std::vector<FrontierSetting> frontier_settings(const Scene& base, const FrontierOptions& o);
// The second round at one distance: between each two neighbours on each method's frontier among
// `measured` (that distance's points), every knob at the geometric mean of theirs; none already
// measured or listed twice.
std::vector<FrontierSetting> frontier_between(const Scene& base, const std::vector<FrontierPoint>& measured);
// One setting at one distance, on `wb` (its stage cache is cleared first: the precomputation is
// timed from a cold cache; `wb` must have no stage store set). Its truth (o.truth) comes from `truths` when
// that holds it, else from the workbench's truth cache or is rendered, and is added to `truths`.
// `budget_over` (polled every 20 ms; not for a preset) stops the setting: `stopped`. o.cancel
// throws Cancelled. A setting a stage refuses is `skipped` with why (a preset's refusal throws).
struct FrontierTruths {
    std::map<std::string, Frame> frames;  // by what the truth reads and the frame size
};
struct FrontierMeasurement {
    std::optional<FrontierPoint> point;
    std::string skipped;       // "METHOD SETTING: why"
    bool stopped = false;      // by budget_over
    double truth_noise = 0;    // the truth's noise_rel (with a point)
};
FrontierMeasurement frontier_measure(Workbench& wb, const Scene& base, const FrontierOptions& o, double distance, const FrontierSetting& setting,
                                     FrontierTruths& truths, const std::function<bool()>& budget_over = {});
// The result of measured points (`partial`: points, truth_noise per distance, budget_reached,
// skipped, machine): the frontier marked, the Markdown, and with write_files the files in o.out_dir.
FrontierResult frontier_report(const Scene& base, const FrontierOptions& o, FrontierResult partial, bool write_files);

// [SECTION] Descriptions
// The parameter groups `preset schema TECHNIQUE` lists: all for "", else the technique's or the
// scene group's (camera, light, env, geometry, effects); InputError starting with `what` otherwise.
std::vector<const ParamGroup*> schema_groups(const std::string& technique, const std::string& what);
// What `mesolab info` prints, as (name, value) pairs in its order: version, cpu threads, techniques,
// renderers, the headless GL context's platform, vendor, renderer and versions (or "gl": why there
// is none), library versions.
std::vector<std::pair<std::string, std::string>> info_fields();
std::string export_names();  // "btf (microgeom), ..." for help texts
}  // namespace mesolab
