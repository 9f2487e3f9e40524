#pragma once
// [SECTION] Cloth sample and model files: measured BRDF samples in, fitted models out.
//
// Samples (CSV): each row `lx,ly,lz,vx,vy,vz,r,g,b`: light and view directions in the local frame
// (z = the normal; normalised on reading) and f_r per channel in sr⁻¹; an optional first column
// `point` groups rows by sample point (any token). One header line is allowed. Malformed rows,
// directions below the horizon or of zero length, negative or non-finite values are InputErrors
// naming the file and line.
//
// Directions (CSV, for evaluating a model): rows `lx,ly,lz,vx,vy,vz`, with a first column `point`
// when the model has several points.
//
// Acquired samples (binary, `mesolab export cloth-samples`): a line "mesolab cloth samples", a
// JSON header line {"schema": 1, "res", "pairs", "views"}, then little-endian arrays: the views
// (f64 × 3 each), the pairs' l and v (f64 × 3) and view indices (i32), and per point its normal
// and tangent (f64 × 3), alpha per view (f32) and f_r per pair (f32 × 3). Written atomically;
// reading checks every size and value and names the file.
//
// Model (JSON): {"schema": 1, "kind": "mesolab.cloth.model", "lobes": N, "lookup_table": bool,
//   "points": [{"point": ID, "kd": [r,g,b], "lobes": [{"Cx": [..], "Cy": [..], "Cz": [..],
//   "n": [..]}, ...], "f_max": [r,g,b] (optional: the bound on f_r), "table": {"v": [[x,y,z], ...], "T": [[r,g,b,alpha], ...]},
//   "fit": {"rounds", "converged", "rms", "rel_rms"}}, ...]}: the units of lafortune.h.
#include "core/cloth/fit.h"
#include "core/cloth/pyramid.h"

#include <string>
#include <vector>

namespace mesolab::cloth {

struct SampleSet {
    std::vector<std::string> names;      // per point, in order of first appearance ("" without a point column)
    std::vector<PointSamples> points;
    size_t rows = 0;
};
SampleSet parse_samples_csv(const std::string& text, const std::string& source);
SampleSet read_samples_csv(const std::string& path);  // InputError naming an unreadable file

struct DirectionRow {
    int point = 0;  // index into the model's points
    dvec3 l{0.0}, v{0.0};
};
// `names`: the model's point names (a point column is required when there are several).
std::vector<DirectionRow> parse_directions_csv(const std::string& text, const std::string& source, const std::vector<std::string>& names);
std::vector<DirectionRow> read_directions_csv(const std::string& path, const std::vector<std::string>& names);

struct ClothModel {
    int lobes = 2;
    bool lookup_table = true;
    std::vector<std::string> names;
    std::vector<ClothBrdf> brdfs;
    std::vector<FitReport> reports;
};
std::string model_to_json(const ClothModel& m);
ClothModel model_from_json(const std::string& text, const std::string& source);  // InputError naming the key
void write_model(const std::string& path, const ClothModel& m);                  // atomically
ClothModel read_model(const std::string& path);
void write_sample_grid(const std::string& path, const SampleGrid& g);
SampleGrid read_sample_grid(const std::string& path);
std::string sample_grid_bytes(const SampleGrid& g);
SampleGrid sample_grid_from_bytes(const std::string& bytes, const std::string& source);
}  // namespace mesolab::cloth
