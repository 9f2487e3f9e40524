#pragma once
// [SECTION] Timing tables laid out like the papers' tables.
// A technique declares its table once: the paper's rows and columns, the paper's figure for
// each cell where it has one, and what each cell measures (a stage of the graph, recomputed
// from a cold cache, or a whole frame on the CPU and/or GPU). `mesolab bench` measures every
// cell N times and prints median (min-max) beside the paper's figure and the ratio.
#include "core/scene.h"
#include "core/stage.h"
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace mesolab {

struct BenchColumn {
    std::string name;        // as in the paper ("S_i precompute")
    StageName stage;         // time this stage (cold cache) ...
    int frame_width = 0;     // ... or, when stage is empty, a whole frame of this size
    int frame_height = 0;
    bool cpu = true, gpu = false;  // devices measured (stages are CPU unless they say otherwise)
    // Stage columns: the `--set` that runs the stage on the GPU ("microgeom.device=gpu"); then it
    // is timed on both devices. A GPU run that fell back to the CPU (a stage warning) is not reported.
    std::string gpu_set;
    // A column that reports rather than times (memory per structure, say): called with the
    // row's scene after its frame stages ran; the text goes in the cell as it is.
    std::function<std::string(const Scene&, const Evaluation&)> info;
};

struct BenchRow {
    std::string name;                               // as in the paper ("Bricks 128x128")
    std::function<Scene()> scene;                   // the scene this row measures
    std::vector<std::optional<double>> paper_ms;    // one per column, empty where the paper has none
    std::map<std::string, double> paper_step_ms;    // the paper's figure for a frame step's row, by step name (FrameStepName::str)
};

struct BenchTable {
    std::string name;     // `mesolab bench NAME`
    std::string title;    // "Heidrich et al. 2000, Table 1"
    std::string paper_machine;  // "SGI Octane 300 MHz / GeForce 256"
    std::vector<BenchColumn> columns;
    std::vector<BenchRow> rows;
    // A row for a mesh file of the user's (`mesolab bench NAME --mesh FILE [--vertices N]`; N = 0:
    // the table's own choice), or null when the table takes none.
    std::function<BenchRow(const std::string& mesh, int vertices)> mesh_row;
};

// Tables registered by techniques (see Technique::bench_tables), and the truth's.
std::vector<BenchTable> bench_tables();
// The truth's table: every preset the truth renders, at 512 x 512. With noise = 0, a 32-sample pilot
// and the time to 1% noise extrapolated by the estimator's 1/√n law; with noise > 0, each preset's
// truth sampled until its noise_rel reaches `noise` or `time_limit_s` passes, the time measured.
BenchTable truth_bench_table(double noise = 0, double time_limit_s = 600);
}  // namespace mesolab
