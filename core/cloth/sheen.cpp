// The microfacet sheen BRDF plus Lambert and its fit (see sheen.h).
#include "core/cloth/sheen.h"
#include "core/cloth/fit.h"

#include "core/cloth/technique.h"
#include "core/error.h"
#include "core/technique.h"

#include <ceres/ceres.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

namespace mesolab::cloth {
namespace {
constexpr double kPiD = 3.14159265358979323846;
constexpr int kGrid = 48;

// Estevez and Kulla's Table 1: (a, b, c, d, e) of L at r = 0 and r = 1.
constexpr double kL0[5] = {25.3245, 3.32435, 0.16801, -1.27393, -4.85967};
constexpr double kL1[5] = {21.5473, 3.82987, 0.19823, -1.97760, -4.32054};

double L(double x, double r) {
    const double t = (1.0 - r) * (1.0 - r);
    double p[5];
    for (int i = 0; i < 5; ++i) p[i] = kL1[i] + (kL0[i] - kL1[i]) * t;
    return p[0] / (1.0 + p[1] * std::pow(x, p[2])) + p[3] * x + p[4];
}

// The per-sample data of a fit: g_r's arguments and the weighted target per channel.
struct FitData {
    const PointSamples* ps = nullptr;
    std::vector<dvec3> t;  // w T(v) per channel
    std::vector<dvec3> y;  // w r per channel
};

FitData fit_data(const PointSamples& ps, const ViewTable& table) {
    FitData d;
    d.ps = &ps;
    for (const BrdfSample& s : ps.s) {
        d.t.push_back(s.w * (table.empty() ? dvec3(1.0) : dvec3(table.T[size_t(s.view)])));
        d.y.push_back(s.w * s.f);
    }
    return d;
}

// The best (k_d, S) ≥ 0 of channel c for fixed lobe values g (2 x 2 normal equations; on a
// negative solution the better of the two one-variable fits on the boundary), and its cost.
double best_pair(const FitData& d, const std::vector<double>& g, int c, double& kd, double& S) {
    double aa = 0, ab = 0, bb = 0, ay = 0, by = 0, yy = 0;
    for (size_t s = 0; s < g.size(); ++s) {
        const double a = d.t[s][c], b = d.t[s][c] * g[s], y = d.y[s][c];
        aa += a * a, ab += a * b, bb += b * b, ay += a * y, by += b * y, yy += y * y;
    }
    const auto cost = [&](double x0, double x1) { return yy - 2 * (x0 * ay + x1 * by) + x0 * x0 * aa + 2 * x0 * x1 * ab + x1 * x1 * bb; };
    const double det = aa * bb - ab * ab;
    if (det > 1e-12 * aa * bb) {
        kd = (ay * bb - by * ab) / det, S = (by * aa - ay * ab) / det;
        if (kd >= 0 && S >= 0) return cost(kd, S);
    }
    const double kd_only = aa > 0 ? std::max(0.0, ay / aa) : 0.0, S_only = bb > 0 ? std::max(0.0, by / bb) : 0.0;
    const double c_kd = cost(kd_only, 0.0), c_S = cost(0.0, S_only);
    if (c_kd <= c_S) kd = kd_only, S = 0.0;
    else kd = 0.0, S = S_only;
    return std::min(c_kd, c_S);
}

std::vector<double> lobe_values(const PointSamples& ps, double r) {
    std::vector<double> g(ps.s.size());
    for (size_t s = 0; s < g.size(); ++s) g[s] = sheen_lobe(ps.s[s].l, ps.s[s].v, r);
    return g;
}

// Residuals w (T f − r) per sample and channel; parameters (k_d rgb, S rgb) and r, the latter's
// derivative by central differences (Λ's fit has no convenient closed-form derivative).
class SheenCost final : public ceres::CostFunction {
public:
    explicit SheenCost(const FitData& d) : d_(d) {
        set_num_residuals(int(3 * d.t.size()));
        mutable_parameter_block_sizes()->push_back(6);
        mutable_parameter_block_sizes()->push_back(1);
    }
    bool Evaluate(double const* const* p, double* residual, double** jacobian) const override {
        const double* x = p[0];
        const double r = p[1][0];
        const std::vector<double> g = lobe_values(*d_.ps, r);
        std::vector<double> gp, gm;
        double h = 0;
        if (jacobian && jacobian[1]) {
            h = 1e-6 * std::max(r, 1e-3);
            gp = lobe_values(*d_.ps, std::min(1.0, r + h));
            gm = lobe_values(*d_.ps, r - h);
            h = std::min(1.0, r + h) - (r - h);
        }
        for (size_t s = 0; s < g.size(); ++s)
            for (int c = 0; c < 3; ++c) {
                const size_t i = 3 * s + size_t(c);
                const double t = d_.t[s][c];
                residual[i] = t * (x[c] + x[3 + c] * g[s]) - d_.y[s][c];
                if (!std::isfinite(residual[i])) return false;
                if (jacobian && jacobian[0]) {
                    double* J = jacobian[0] + 6 * i;
                    std::fill(J, J + 6, 0.0);
                    J[c] = t, J[3 + c] = t * g[s];
                }
                if (jacobian && jacobian[1]) jacobian[1][i] = t * x[3 + c] * (gp[s] - gm[s]) / h;
            }
        return true;
    }

private:
    const FitData& d_;
};

// Fits (k_d, S, r) for a fixed table: the variable-projection grid over r, then LM from its best.
void fit_model(const PointSamples& ps, const ViewTable& table, const FitOptions& o, dvec3& kd, SheenLobe& b, bool from_current) {
    const FitData d = fit_data(ps, table);
    double x[6], r = b.r;
    if (from_current) {
        for (int c = 0; c < 3; ++c) x[c] = kd[c], x[3 + c] = b.S[c];
    } else {
        double best = std::numeric_limits<double>::infinity();
        for (int k = 0; k < kGrid; ++k) {
            const double rk = std::exp(std::log(o.r_min) * (1.0 - double(k) / double(kGrid - 1)));
            const std::vector<double> g = lobe_values(ps, rk);
            double cost = 0, kd[3], S[3];
            for (int c = 0; c < 3; ++c) cost += best_pair(d, g, c, kd[c], S[c]);
            if (cost < best) {
                best = cost, r = rk;
                for (int c = 0; c < 3; ++c) x[c] = kd[c], x[3 + c] = S[c];
            }
        }
    }
    ceres::Problem problem;
    problem.AddResidualBlock(new SheenCost(d), nullptr, x, &r);
    for (int i = 0; i < 6; ++i) problem.SetParameterLowerBound(x, i, 0.0);
    problem.SetParameterLowerBound(&r, 0, o.r_min);
    problem.SetParameterUpperBound(&r, 0, 1.0);
    ceres::Solver::Options so;
    so.max_num_iterations = o.max_iterations;
    so.linear_solver_type = ceres::DENSE_QR;
    so.function_tolerance = 1e-14, so.gradient_tolerance = 1e-16, so.parameter_tolerance = 1e-12;
    so.num_threads = 1;
    ceres::Solver::Summary summary;
    ceres::Solve(so, &problem, &summary);
    for (int c = 0; c < 3; ++c) kd[c] = x[c], b.S[c] = x[3 + c];
    b.r = r;
}
}  // namespace

double sheen_D(double cos_h, double r) {
    const double c = std::clamp(cos_h, 0.0, 1.0), sin2 = std::max(0.0, 1.0 - c * c);
    return (2.0 + 1.0 / r) * std::pow(sin2, 0.5 / r) / (2.0 * kPiD);
}

double sheen_lambda(double mu, double r) {
    mu = std::clamp(mu, 0.0, 1.0);
    return mu < 0.5 ? std::exp(L(mu, r)) : std::exp(2.0 * L(0.5, r) - L(1.0 - mu, r));
}

double sheen_lobe(dvec3 l, dvec3 v, double r) {
    if (!(l.z > 0.0) || !(v.z > 0.0)) return 0.0;
    const dvec3 h = glm::normalize(l + v);
    const double G = 1.0 / (1.0 + sheen_lambda(l.z, r) + sheen_lambda(v.z, r));
    return sheen_D(h.z, r) * G / (4.0 * l.z * v.z);
}

ClothBrdf fit_sheen(const PointSamples& ps, const FitOptions& o, FitReport* report) {
    if (!(o.tolerance > 0.0)) throw InputError("cloth.tolerance: " + std::to_string(o.tolerance) + " must be > 0");
    if (!(o.r_min > 0.0 && o.r_min < 1.0)) throw InputError("sheen fit: r_min " + std::to_string(o.r_min) + " must lie in (0, 1)");
    FitReport rep;
    ClothBrdf b;
    b.sheen = SheenLobe{};
    const ViewTable ones = o.lookup_table ? unit_table(ps) : ViewTable{};
    fit_model(ps, ones, o, b.L.kd, *b.sheen, false);
    rep.starts_tried = kGrid;
    const auto model = [&b](dvec3 l, dvec3 v) { return b.f_model(l, v); };
    alternate(ps, o, ones, model, [&](const ViewTable& table) { fit_model(ps, table, o, b.L.kd, *b.sheen, true); }, b, rep);
    if (report) *report = rep;
    return b;
}

// [SECTION] The method: the paper's pipeline (acquisition, pyramid, shading, GPU pass) with the
// sheen fitted to each entry instead of the lobes; cloth.fit reads cloth.method.
namespace {
class SheenMethod final : public Method {
public:
    SheenMethod() : Method("cloth", "sheen", "the microfacet sheen BRDF plus Lambert (Estevez and Kulla 2017), fitted per sample point") {}
    // Its knobs are the paper's acquisition and fit keys but cloth.lobes: no keys of its own.
    void declare_params(ParamGroup&) const override {}
    std::vector<StageName> frame_stages() const override { return ClothTechnique::pipeline_stages(); }
    bool shares_paper_pipeline() const override { return true; }
    void shade_cpu(const ShadeContext&) const override {
        throw std::logic_error("cloth/sheen shares the paper's pipeline: its objects are shaded by the technique");
    }
};
}  // namespace
}  // namespace mesolab::cloth

namespace mesolab {
void register_cloth_sheen(Registry& r) { r.add_method(std::make_unique<cloth::SheenMethod>()); }
}  // namespace mesolab
