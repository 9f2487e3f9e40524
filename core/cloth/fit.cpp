// Fitting the cloth model (see fit.h).
#include "core/cloth/fit.h"
#include "core/error.h"

#include <ceres/ceres.h>
#include <glog/logging.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <memory>
#include <string>
#include <tuple>

namespace mesolab::cloth {

// [SECTION] Grouping by view
PointSamples group_by_view(std::vector<BrdfSample> samples) {
    PointSamples out;
    std::map<std::tuple<long long, long long, long long>, int> index;
    for (BrdfSample& s : samples) {
        const auto key = std::make_tuple(std::llround(s.v.x * 1e6), std::llround(s.v.y * 1e6), std::llround(s.v.z * 1e6));
        auto [it, fresh] = index.try_emplace(key, int(out.views.size()));
        if (fresh) out.views.push_back(s.v);
        s.view = it->second;
    }
    out.s = std::move(samples);
    return out;
}

namespace {
// [SECTION] The lobe problem of one channel
// Parameters: k_d, then C_x, C_y, C_z, n per lobe. Per sample the products l_x v_x, l_y v_y,
// l_z v_z, the table's factor t and the value r.
struct ChannelData {
    std::vector<std::array<double, 3>> a;  // l_x v_x, l_y v_y, l_z v_z
    std::vector<double> t, r;              // t and r already times the sample's weight
};

// Below this base a lobe contributes nothing (and no gradient): a^n is below 1e-4.5 for n >= 0.5.
constexpr double kMinBase = 1e-9;
// exp(700) is near double's limit: beyond it a step is rejected.
constexpr double kMaxLog = 700.0;

class LobeCost final : public ceres::CostFunction {
public:
    LobeCost(const ChannelData& d, int lobes) : d_(d), lobes_(lobes) {
        set_num_residuals(int(d.r.size()));
        mutable_parameter_block_sizes()->push_back(1 + 4 * lobes);
    }
    bool Evaluate(double const* const* p, double* residual, double** jacobian) const override {
        const double* x = p[0];
        const int P = 1 + 4 * lobes_;
        for (size_t s = 0; s < d_.r.size(); ++s) {
            const double t = d_.t[s];
            double val = x[0];
            double* J = jacobian && jacobian[0] ? jacobian[0] + s * size_t(P) : nullptr;
            if (J) J[0] = t;
            for (int i = 0; i < lobes_; ++i) {
                const double* c = x + 1 + 4 * i;
                const double a = c[0] * d_.a[s][0] + c[1] * d_.a[s][1] + c[2] * d_.a[s][2];
                double* Ji = J ? J + 1 + 4 * i : nullptr;
                if (!(a > kMinBase)) {
                    if (Ji) Ji[0] = Ji[1] = Ji[2] = Ji[3] = 0.0;
                    continue;
                }
                const double la = std::log(a), n = c[3];
                if (n * la > kMaxLog) return false;
                const double pw = std::exp(n * la);
                val += pw;
                if (Ji) {
                    const double dpa = t * n * pw / a;  // d(t a^n)/da
                    Ji[0] = dpa * d_.a[s][0], Ji[1] = dpa * d_.a[s][1], Ji[2] = dpa * d_.a[s][2];
                    Ji[3] = t * pw * la;
                }
            }
            residual[s] = t * val - d_.r[s];
            if (!std::isfinite(residual[s])) return false;
        }
        return true;
    }

private:
    const ChannelData& d_;
    int lobes_;
};

ChannelData channel_data(const PointSamples& ps, const ViewTable& table, int c) {
    ChannelData d;
    d.a.reserve(ps.s.size()), d.t.reserve(ps.s.size()), d.r.reserve(ps.s.size());
    for (const BrdfSample& s : ps.s) {
        d.a.push_back({s.l.x * s.v.x, s.l.y * s.v.y, s.l.z * s.v.z});
        d.t.push_back(s.w * (table.empty() ? 1.0 : table.T[size_t(s.view)][c]));
        d.r.push_back(s.w * s.f[c]);
    }
    return d;
}

std::vector<double> pack(const Lafortune& L, int c) {
    std::vector<double> x{L.kd[c]};
    for (const LafortuneLobe& lobe : L.lobes) x.insert(x.end(), {lobe.Cx[c], lobe.Cy[c], lobe.Cz[c], lobe.n[c]});
    return x;
}

void unpack(const std::vector<double>& x, Lafortune& L, int c) {
    L.kd[c] = x[0];
    for (size_t i = 0; i < L.lobes.size(); ++i) {
        LafortuneLobe& lobe = L.lobes[i];
        lobe.Cx[c] = x[1 + 4 * i], lobe.Cy[c] = x[2 + 4 * i], lobe.Cz[c] = x[3 + 4 * i], lobe.n[c] = x[4 + 4 * i];
    }
}

// A start made feasible and of the data's magnitude: clamped into the bounds (Ceres needs a
// feasible start), k_d at most the data's peak, and each lobe whose largest value over the
// samples is far from the peak rescaled to it (C times (peak / max)^(1/n)), so that a start
// whose lobes are a hundred orders of magnitude off still gives LM a useful gradient.
void sanitise(const ChannelData& d, int lobes, std::vector<double>& x, const FitOptions& o) {
    double peak = 0.0;
    for (size_t s = 0; s < d.r.size(); ++s) peak = std::max(peak, d.t[s] > 0.0 ? d.r[s] / d.t[s] : d.r[s]);
    if (!(peak > 0.0)) peak = 1.0;
    x[0] = std::clamp(std::isfinite(x[0]) ? x[0] : 0.0, 0.0, peak);
    for (int i = 0; i < lobes; ++i) {
        double* c = x.data() + 1 + 4 * i;
        for (int k = 0; k < 3; ++k) c[k] = std::clamp(std::isfinite(c[k]) ? c[k] : 0.0, -o.C_max, o.C_max);
        c[3] = std::clamp(std::isfinite(c[3]) ? c[3] : 1.0, o.n_min, o.n_max);
        // The lobe's largest value, in logs (it may not fit in a double).
        double log_max = -std::numeric_limits<double>::infinity();
        for (size_t s = 0; s < d.r.size(); ++s) {
            const double a = c[0] * d.a[s][0] + c[1] * d.a[s][1] + c[2] * d.a[s][2];
            if (a > kMinBase) log_max = std::max(log_max, c[3] * std::log(a));
        }
        if (!std::isfinite(log_max)) continue;  // never positive here: nothing to scale
        const double log_peak = std::log(peak);
        if (std::abs(log_max - log_peak) > std::log(100.0)) {
            const double k = std::exp((log_peak - log_max) / c[3]);
            for (int j = 0; j < 3; ++j) c[j] = std::clamp(c[j] * k, -o.C_max, o.C_max);
        }
    }
}

// Levenberg–Marquardt from x (in place, kept within the bounds); returns the final cost, or +inf
// when the start itself cannot be evaluated.
double solve(const ChannelData& d, int lobes, std::vector<double>& x, const FitOptions& o, int iterations) {
    // Ceres reports its line searches' numerical trouble through glog; the fit's own report
    // (rms, rounds, converged) says how it went, so only fatal messages are kept.
    static const bool quiet = [] {
        FLAGS_minloglevel = google::GLOG_FATAL;
        return true;
    }();
    (void)quiet;
    ceres::Problem::Options po;
    po.cost_function_ownership = ceres::TAKE_OWNERSHIP;
    ceres::Problem problem(po);
    problem.AddResidualBlock(new LobeCost(d, lobes), nullptr, x.data());
    problem.SetParameterLowerBound(x.data(), 0, 0.0);
    for (int i = 0; i < lobes; ++i) {
        for (int k = 0; k < 3; ++k) {
            problem.SetParameterLowerBound(x.data(), 1 + 4 * i + k, -o.C_max);
            problem.SetParameterUpperBound(x.data(), 1 + 4 * i + k, o.C_max);
        }
        problem.SetParameterLowerBound(x.data(), 4 + 4 * i, o.n_min);
        problem.SetParameterUpperBound(x.data(), 4 + 4 * i, o.n_max);
    }
    double cost0 = 0.0;
    if (!problem.Evaluate(ceres::Problem::EvaluateOptions(), &cost0, nullptr, nullptr, nullptr) || !std::isfinite(cost0))
        return std::numeric_limits<double>::infinity();
    ceres::Solver::Options so;
    so.trust_region_strategy_type = ceres::LEVENBERG_MARQUARDT;
    so.linear_solver_type = ceres::DENSE_NORMAL_CHOLESKY;
    so.max_num_iterations = iterations;
    so.function_tolerance = 1e-9;
    so.gradient_tolerance = 1e-14;
    so.parameter_tolerance = 1e-10;
    so.num_threads = 1;
    so.logging_type = ceres::SILENT;
    so.minimizer_progress_to_stdout = false;
    ceres::Solver::Summary sum;
    ceres::Solve(so, &problem, &sum);
    return std::isfinite(sum.final_cost) ? sum.final_cost : std::numeric_limits<double>::infinity();
}

LafortuneLobe lobe_of(dvec3 shape, double n, double peak) {
    // Scaled so that the lobe's value where its base is |shape|_max is about `peak`.
    const double m = std::max({std::abs(shape.x), std::abs(shape.y), std::abs(shape.z)});
    const double scale = std::pow(std::max(peak, 1e-12), 1.0 / n) / m;
    LafortuneLobe l;
    l.Cx = dvec3(shape.x * scale), l.Cy = dvec3(shape.y * scale), l.Cz = dvec3(shape.z * scale), l.n = dvec3(n);
    return l;
}
}  // namespace

// [SECTION] Starts
std::vector<Lafortune> default_starts(const PointSamples& ps, int lobes) {
    double mean = 0.0, peak = 0.0;
    for (const BrdfSample& s : ps.s)
        for (int c = 0; c < 3; ++c) mean += s.f[c], peak = std::max(peak, s.f[c]);
    mean /= std::max<double>(1.0, 3.0 * double(ps.s.size()));
    if (!(peak > 0.0)) peak = 1.0, mean = 0.3;
    // Lobe shapes: forward (specular), retro, grazing forward scattering, the paper's
    // slightly anisotropic grey lobes (C_x = 1.22 C_y, then C_y = 1.22 C_x).
    const dvec3 fwd(-1.0, -1.0, 1.0), retro(1.0, 1.0, 1.0), graze(-1.0, -1.0, 0.2), ax(-1.22, -1.0, 1.0), ay(-1.0, -1.22, 1.0);
    const std::vector<std::vector<std::pair<dvec3, double>>> plans = {
        {{ax, 10.0}, {ay, 10.0}, {retro, 3.0}},  {{fwd, 20.0}, {retro, 3.0}, {graze, 5.0}}, {{fwd, 3.0}, {graze, 20.0}, {retro, 10.0}},
        {{retro, 20.0}, {fwd, 5.0}, {graze, 2.0}}, {{graze, 3.0}, {fwd, 50.0}, {retro, 20.0}}, {{fwd, 100.0}, {graze, 3.0}, {retro, 3.0}},
    };
    std::vector<Lafortune> out;
    for (const auto& plan : plans) {
        Lafortune L;
        L.kd = dvec3(0.3 * mean);
        for (int i = 0; i < lobes; ++i) L.lobes.push_back(lobe_of(plan[size_t(i)].first, plan[size_t(i)].second, 0.5 * peak / double(lobes)));
        out.push_back(L);
    }
    return out;
}

// [SECTION] Step 1: lobes
Lafortune fit_lobes(const PointSamples& ps, const ViewTable& table, const std::vector<Lafortune>& starts, const FitOptions& o, int* tried) {
    const int lobes = starts.empty() ? o.lobes : int(starts[0].lobes.size());
    Lafortune best;
    best.lobes.resize(size_t(lobes));
    if (tried) *tried = 0;
    for (int c = 0; c < 3; ++c) {
        const ChannelData d = channel_data(ps, table, c);
        // Every start a few iterations; the two lowest on to convergence.
        std::vector<std::pair<double, std::vector<double>>> tried_x;
        for (const Lafortune& s : starts) {
            std::vector<double> x = pack(s, c);
            sanitise(d, lobes, x, o);
            const double cost = starts.size() > 2 ? solve(d, lobes, x, o, o.screen_iterations) : 0.0;
            if (tried && c == 0) ++*tried;
            if (std::isfinite(cost)) tried_x.emplace_back(cost, std::move(x));
        }
        std::sort(tried_x.begin(), tried_x.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
        double best_cost = std::numeric_limits<double>::infinity();
        std::vector<double> best_x;
        for (size_t k = 0; k < tried_x.size() && k < 2; ++k) {
            std::vector<double> x = tried_x[k].second;
            const double cost = solve(d, lobes, x, o, o.max_iterations);
            if (cost < best_cost) best_cost = cost, best_x = x;
        }
        if (best_x.empty()) {
            // No start could be evaluated (every one overflowed): the diffuse mean alone.
            double m = 0.0;
            for (size_t s = 0; s < d.r.size(); ++s) m += d.r[s];
            best_x.assign(size_t(1 + 4 * lobes), 0.0);
            best_x[0] = d.r.empty() ? 0.0 : std::max(0.0, m / double(d.r.size()));
            for (int i = 0; i < lobes; ++i) best_x[size_t(4 + 4 * i)] = 1.0;
        }
        unpack(best_x, best, c);
    }
    return best;
}

// [SECTION] Step 2: the table (Eq. 4)
ViewTable fit_table(const PointSamples& ps, const ModelFn& model) {
    ViewTable t;
    t.v = ps.views;
    std::vector<dvec3> num(ps.views.size(), dvec3(0.0)), den(ps.views.size(), dvec3(0.0));
    for (const BrdfSample& s : ps.s) {
        const dvec3 f = model(s.l, s.v);
        const double w2 = s.w * s.w;
        num[size_t(s.view)] += w2 * s.f * f;
        den[size_t(s.view)] += w2 * f * f;
    }
    t.T.resize(ps.views.size());
    for (size_t i = 0; i < ps.views.size(); ++i) {
        dvec3 T(1.0);
        for (int c = 0; c < 3; ++c)
            if (den[i][c] > 1e-300) T[c] = num[i][c] / den[i][c];
        const double a = i < ps.alpha.size() ? ps.alpha[i] : 1.0;
        t.T[i] = dvec4(T, a);
    }
    return t;
}

ViewTable fit_table(const PointSamples& ps, const Lafortune& L) {
    return fit_table(ps, [&L](dvec3 l, dvec3 v) { return L.f(l, v); });
}

ViewTable unit_table(const PointSamples& ps) {
    ViewTable t = fit_table(ps, [](dvec3, dvec3) { return dvec3(0.0); });  // directions and alpha
    for (dvec4& T : t.T) T = dvec4(1.0, 1.0, 1.0, T.w);
    return t;
}

double rms_of(const PointSamples& ps, const ModelFn& model, const ViewTable& table, double* rel) {
    double e2 = 0.0, r2 = 0.0;
    for (const BrdfSample& s : ps.s) {
        const dvec3 f = model(s.l, s.v) * (table.empty() ? dvec3(1.0) : dvec3(table.T[size_t(s.view)]));
        const double w2 = s.w * s.w;
        for (int c = 0; c < 3; ++c) e2 += w2 * (f[c] - s.f[c]) * (f[c] - s.f[c]), r2 += w2 * s.f[c] * s.f[c];
    }
    const double n = std::max<double>(1.0, 3.0 * double(ps.s.size()));
    if (rel) *rel = r2 > 0.0 ? std::sqrt(e2 / r2) : 0.0;
    return std::sqrt(e2 / n);
}

// [SECTION] Alternation
void alternate(const PointSamples& ps, const FitOptions& o, const ViewTable& ones, const ModelFn& model, const std::function<void(const ViewTable&)>& refit,
               ClothBrdf& b, FitReport& rep) {
    rep.rounds = 1;
    rep.converged = !o.lookup_table;
    if (o.lookup_table) {
        b.table = fit_table(ps, model);
        ViewTable prev = ones;
        for (int round = 1; round < o.max_rounds; ++round) {
            double change = 0.0;
            for (size_t i = 0; i < b.table.T.size(); ++i)
                for (int c = 0; c < 3; ++c) change += std::abs(b.table.T[i][c] - prev.T[i][c]);
            change /= std::max<double>(1.0, 3.0 * double(b.table.T.size()));
            if (change < o.tolerance) {
                rep.converged = true;
                break;
            }
            prev = b.table;
            refit(b.table);
            b.table = fit_table(ps, model);
            ++rep.rounds;
        }
    }
    // The bound on f_r: twice the largest sample.
    dvec3 peak(0.0);
    for (const BrdfSample& s : ps.s) peak = glm::max(peak, s.f);
    b.f_max = 2.0 * peak;
    rep.rms = rms_of(ps, model, b.table, &rep.rel_rms);
}

ClothBrdf fit_brdf(const PointSamples& ps, const FitOptions& o, FitReport* report) {
    if (o.sheen) return fit_sheen(ps, o, report);
    if (o.lobes < 1 || o.lobes > 3) throw InputError("cloth.lobes: " + std::to_string(o.lobes) + " must be 1, 2 or 3");
    if (!(o.tolerance > 0.0)) throw InputError("cloth.tolerance: " + std::to_string(o.tolerance) + " must be > 0");
    for (const Lafortune& s : o.starts)
        if (int(s.lobes.size()) != o.lobes)
            throw InputError("cloth fit: a starting point has " + std::to_string(s.lobes.size()) + " lobes, the fit " + std::to_string(o.lobes));
    std::vector<Lafortune> starts = o.starts;
    if (o.builtin_starts || starts.empty()) {
        const std::vector<Lafortune> d = default_starts(ps, o.lobes);
        starts.insert(starts.end(), d.begin(), d.end());
    }
    FitReport rep;
    ClothBrdf b;
    ViewTable ones;  // T = 1
    if (o.lookup_table) {
        ones = unit_table(ps);
    }
    b.L = fit_lobes(ps, ones, starts, o, &rep.starts_tried);
    const auto model = [&b](dvec3 l, dvec3 v) { return b.L.f(l, v); };
    // Later rounds start from the current lobes only.
    alternate(ps, o, ones, model, [&](const ViewTable& table) { b.L = fit_lobes(ps, table, {b.L}, o); }, b, rep);
    if (report) *report = rep;
    return b;
}
}  // namespace mesolab::cloth
