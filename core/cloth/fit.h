#pragma once
// [SECTION] Fitting the cloth model to samples (Daubert et al. 2001, §5).
// For one sample point, alternately:
//   1. the lobes (k_d and C_x, C_y, C_z, n of every lobe, each colour channel its own problem) by
//      Levenberg–Marquardt (Ceres), minimising Σ w_s² (T(v_s) f_L(l_s, v_s) − r_s)² over the
//      samples (w = cos θ_l: radiance, see BrdfSample::w), with T held fixed (1 in the first round);
//   2. every table entry in closed form, per channel (Eq. 4): T(v) = ⟨w r, w f⟩ / ⟨w f, w f⟩
//      over the samples of view direction v (the best factor in the least-squares sense);
// until the table's entries change by less than `tolerance` on average (the paper: 0.1, usually
// two rounds). Without a lookup table only step 1 runs.
//
// Robustness: the exponents are kept in [n_min, n_max] and k_d >= 0 by bounds; a lobe value that
// would overflow rejects the step; the lobes start from several shapes (forward, retro, grazing,
// the paper's slightly anisotropic grey start) and exponents: each runs a few iterations, the two
// lowest continue to convergence, and the lowest cost wins. Samples
// with no energy or a table direction without samples leave T at 1.
#include "core/cloth/lafortune.h"

#include <functional>
#include <string>
#include <vector>

namespace mesolab::cloth {

// One BRDF value: light and view directions (unit, local frame, z >= 0) and f_r per channel (sr⁻¹).
struct BrdfSample {
    dvec3 l{0.0, 0.0, 1.0}, v{0.0, 0.0, 1.0};
    dvec3 f{0.0};
    int view = 0;  // index of v in PointSamples::views
    // Weight of the sample's residual: cos θ_l, so that the fit minimises the error in reflected
    // radiance under unit irradiance (the paper fits radiance samples), not in f_r, whose values
    // towards grazing light are large but reach the image multiplied by a small cosine.
    double w = 1.0;
};

// The samples of one sample point (or of a group of points, for a mip level).
struct PointSamples {
    std::vector<dvec3> views;  // the distinct view directions (the table's directions)
    std::vector<BrdfSample> s;
    // Alpha per view direction from the acquisition (empty: 1).
    std::vector<double> alpha;
};

// Groups samples by view direction: directions within 1e-6 of each other are one table entry.
PointSamples group_by_view(std::vector<BrdfSample> samples);

struct FitOptions {
    int lobes = 2;              // 1–3
    bool lookup_table = true;
    double tolerance = 0.1;     // stop when the mean |ΔT| of a round is below this
    int max_rounds = 8;
    int max_iterations = 60;    // Levenberg–Marquardt iterations per solve
    int screen_iterations = 12; // iterations every start gets before the best two continue
    double n_min = 0.1, n_max = 1e4;
    double C_max = 1e3;         // |C| bound
    // Extra starting points for the lobes (tried besides the built-in ones); their lobe count
    // must equal `lobes`.
    std::vector<Lafortune> starts;
    bool builtin_starts = true;
    // The sheen model instead of the lobes (cloth.method = sheen, sheen.h): lobes and starts are
    // not used; r is fitted within [r_min, 1].
    bool sheen = false;
    double r_min = 0.01;
};

struct FitReport {
    int rounds = 0;               // lobe fits (1 + table updates)
    bool converged = false;       // the table met the tolerance (always true without a table)
    double rms = 0.0;             // weighted RMS of f_r − r over all samples and channels (w (f_r − r): radiance per unit irradiance, sr⁻¹)
    double rel_rms = 0.0;         // rms / weighted RMS of r (0 when r is all zero)
    int starts_tried = 0;
};

// The model of one point. InputError naming the option for lobes outside [1, 3], a non-positive
// tolerance, or starts with the wrong lobe count (the sheen: a non-positive tolerance or r_min
// outside (0, 1)).
ClothBrdf fit_brdf(const PointSamples& samples, const FitOptions& options, FitReport* report = nullptr);
// The sheen's fit (sheen.h), which fit_brdf calls when options.sheen is set.
ClothBrdf fit_sheen(const PointSamples& samples, const FitOptions& options, FitReport* report = nullptr);

// The lobes alone for a fixed table (step 1): per channel, the best of `starts` after LM.
Lafortune fit_lobes(const PointSamples& samples, const ViewTable& table, const std::vector<Lafortune>& starts, const FitOptions& options,
                    int* starts_tried = nullptr);

// The table for fixed lobes (step 2, Eq. 4), alpha from the samples (1 without).
ViewTable fit_table(const PointSamples& samples, const Lafortune& L);

// The same for any model of f_L (another method's BRDF, sheen.h), and the table of ones with the
// samples' directions and alpha (the first round's).
using ModelFn = std::function<dvec3(dvec3 l, dvec3 v)>;
ViewTable fit_table(const PointSamples& samples, const ModelFn& model);
ViewTable unit_table(const PointSamples& samples);
// FitReport::rms (returned) and rel_rms (in *rel) of model × table over the samples.
double rms_of(const PointSamples& samples, const ModelFn& model, const ViewTable& table, double* rel);

// The alternation of steps 1 and 2 after a first fit of the model under the table of ones
// (`ones`): without options.lookup_table, no table; with it, the table for the model (fit_table),
// the model refitted under that table (`refit`) and the table again, until the table's mean
// absolute change a view and channel is below options.tolerance (report.converged) or
// options.max_rounds fits of the model are made (report.rounds, the first counted). Then b.f_max
// (twice the largest sample) and report.rms and rel_rms of model × table. `model` evaluates b's
// current model.
void alternate(const PointSamples& samples, const FitOptions& options, const ViewTable& ones, const ModelFn& model,
               const std::function<void(const ViewTable&)>& refit, ClothBrdf& b, FitReport& report);

// The built-in starting points for `lobes` lobes, scaled to the samples' magnitude.
std::vector<Lafortune> default_starts(const PointSamples& samples, int lobes);
}  // namespace mesolab::cloth
