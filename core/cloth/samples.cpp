// Cloth sample and model files (see samples.h).
#include "core/strings.h"
#include "core/file.h"
#include "core/cloth/samples.h"
#include "core/error.h"
#include "core/scene.h"

#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdlib>
#include <bit>
#include <cstring>
#include <fstream>
#include <functional>
#include <map>
#include <sstream>

namespace mesolab::cloth {

namespace {
// [SECTION] CSV rows
std::vector<std::string> split_row(const std::string& line) {
    std::vector<std::string> out = split(line, ',');
    for (std::string& cell : out) {
        const size_t a = cell.find_first_not_of(" \t\r"), b = cell.find_last_not_of(" \t\r");
        cell = a == std::string::npos ? "" : cell.substr(a, b - a + 1);
    }
    return out;
}

bool parse_number(const std::string& s, double& x) {
    if (s.empty()) return false;
    char* end = nullptr;
    x = std::strtod(s.c_str(), &end);  // out of range: ±inf or 0, which the checks below name
    return end == s.c_str() + s.size();
}

bool blank(const std::string& line) { return line.find_first_not_of(" \t\r") == std::string::npos; }

std::string where(const std::string& source, size_t line) { return source + ":" + std::to_string(line) + ": "; }

// A direction of the local frame, normalised; InputError naming the line when it is zero,
// not finite or below the horizon.
dvec3 direction(const double* x, const char* what, const std::string& at) {
    const dvec3 d(x[0], x[1], x[2]);
    const double len = glm::length(d);
    if (!std::isfinite(len) || !(len > 0.0)) throw InputError(at + what + " direction has zero length or is not finite");
    const dvec3 u = d / len;
    if (u.z < -1e-9)
        throw InputError(at + what + " direction (" + std::to_string(x[0]) + ", " + std::to_string(x[1]) + ", " + std::to_string(x[2]) +
                         ") is below the horizon (z < 0 in the local frame, z = the normal)");
    return dvec3(u.x, u.y, std::max(u.z, 0.0));
}

std::string read_all(const std::string& path, const char* what) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw InputError(path + ": cannot read the " + std::string(what) + " file");
    std::ostringstream s;
    s << in.rdbuf();
    return s.str();
}

// Every row of numbers in a CSV text: `values` numbers, optionally preceded by a point column;
// blank lines skipped, one header line allowed, every row as wide as the first. `fn(cells, x, at)`
// gets the row's cells, its numbers and "SOURCE:LINE: " for its errors.
void for_each_row(const std::string& text, const std::string& source, int values, const std::string& names,
                  const std::function<void(const std::vector<std::string>&, const double*, const std::string&)>& fn) {
    std::istringstream in(text);
    std::string line;
    size_t n = 0;
    int columns = 0;
    bool header_allowed = true;
    std::vector<double> x(static_cast<size_t>(values));
    while (std::getline(in, line)) {
        ++n;
        if (blank(line)) continue;
        const std::vector<std::string> cells = split_row(line);
        const int c = int(cells.size());
        const std::string at = where(source, n);
        if (c != values && c != values + 1)
            throw InputError(at + "expected " + std::to_string(values) + " values (" + names + ") or " + std::to_string(values + 1) + " (point first), found " +
                             std::to_string(c));
        bool numeric = true;
        for (int k = 0; k < values; ++k) numeric = numeric && parse_number(cells[size_t(c - values + k)], x[size_t(k)]);
        if (!numeric) {
            if (header_allowed) {
                header_allowed = false;
                continue;
            }
            throw InputError(at + "a value is not a number: \"" + line + "\"");
        }
        header_allowed = false;
        if (columns == 0) columns = c;
        if (c != columns) throw InputError(at + "has " + std::to_string(c) + " values; the rows above have " + std::to_string(columns));
        fn(cells, x.data(), at);
    }
}
}  // namespace

// [SECTION] Samples
SampleSet parse_samples_csv(const std::string& text, const std::string& source) {
    SampleSet set;
    std::map<std::string, size_t> point_of;
    std::vector<std::vector<BrdfSample>> rows;
    for_each_row(text, source, 9, "lx,ly,lz,vx,vy,vz,r,g,b", [&](const std::vector<std::string>& cells, const double* x, const std::string& at) {
        const size_t c = cells.size();
        for (size_t k = 6; k < 9; ++k) {
            if (!std::isfinite(x[k])) throw InputError(at + "the BRDF value " + cells[c - 9 + k] + " is not finite");
            if (x[k] < 0.0) throw InputError(at + "the BRDF value " + cells[c - 9 + k] + " is negative (f_r >= 0, in 1/sr)");
        }
        const std::string name = c == 10 ? cells[0] : "";
        auto [it, fresh] = point_of.try_emplace(name, set.names.size());
        if (fresh) set.names.push_back(name), rows.emplace_back();
        BrdfSample s;
        s.l = direction(x, "the light", at);
        s.v = direction(x + 3, "the view", at);
        s.f = dvec3(x[6], x[7], x[8]);
        s.w = s.l.z;  // the fit weighs radiance: f_r cos θ_l
        rows[it->second].push_back(s);
        ++set.rows;
    });
    if (set.rows == 0) throw InputError(source + ": no samples (rows lx,ly,lz,vx,vy,vz,r,g,b)");
    for (auto& r : rows) set.points.push_back(group_by_view(std::move(r)));
    return set;
}

SampleSet read_samples_csv(const std::string& path) { return parse_samples_csv(read_all(path, "samples"), path); }

// [SECTION] Directions to evaluate
std::vector<DirectionRow> parse_directions_csv(const std::string& text, const std::string& source, const std::vector<std::string>& names) {
    std::map<std::string, int> index;
    for (size_t i = 0; i < names.size(); ++i) index[names[i]] = int(i);
    std::vector<DirectionRow> out;
    for_each_row(text, source, 6, "lx,ly,lz,vx,vy,vz", [&](const std::vector<std::string>& cells, const double* x, const std::string& at) {
        DirectionRow r;
        if (cells.size() == 7) {
            auto it = index.find(cells[0]);
            if (it == index.end()) throw InputError(at + "the model has no point \"" + cells[0] + "\"");
            r.point = it->second;
        } else if (names.size() > 1) {
            throw InputError(at + "the model has " + std::to_string(names.size()) + " points: start each row with the point");
        }
        r.l = direction(x, "the light", at);
        r.v = direction(x + 3, "the view", at);
        out.push_back(r);
    });
    return out;
}

std::vector<DirectionRow> read_directions_csv(const std::string& path, const std::vector<std::string>& names) {
    return parse_directions_csv(read_all(path, "directions"), path, names);
}

// [SECTION] Models
namespace {
using nlohmann::json;
json j3(dvec3 v) { return json::array({v.x, v.y, v.z}); }

dvec3 d3(const json& j, const std::string& at) {
    if (!j.is_array() || j.size() != 3) throw InputError(at + ": expected [r, g, b]");
    dvec3 v;
    for (int c = 0; c < 3; ++c) {
        if (!j[size_t(c)].is_number()) throw InputError(at + ": expected numbers");
        v[c] = j[size_t(c)].get<double>();
        if (!std::isfinite(v[c])) throw InputError(at + ": not finite");
    }
    return v;
}

const json& key(const json& j, const char* k, const std::string& at) {
    if (!j.is_object() || !j.contains(k)) throw InputError(at + ": missing \"" + k + "\"");
    return j.at(k);
}
}  // namespace

std::string model_to_json(const ClothModel& m) {
    json points = json::array();
    for (size_t i = 0; i < m.brdfs.size(); ++i) {
        const ClothBrdf& b = m.brdfs[i];
        json lobes = json::array();
        for (const LafortuneLobe& l : b.L.lobes) lobes.push_back({{"Cx", j3(l.Cx)}, {"Cy", j3(l.Cy)}, {"Cz", j3(l.Cz)}, {"n", j3(l.n)}});
        json p = {{"point", i < m.names.size() ? m.names[i] : ""}, {"kd", j3(b.L.kd)}, {"lobes", lobes}};
        if (std::isfinite(b.f_max.x) && std::isfinite(b.f_max.y) && std::isfinite(b.f_max.z)) p["f_max"] = j3(b.f_max);
        if (!b.table.empty()) {
            json v = json::array(), T = json::array();
            for (size_t k = 0; k < b.table.v.size(); ++k) {
                v.push_back(j3(b.table.v[k]));
                const dvec4 t = b.table.T[k];
                T.push_back(json::array({t.x, t.y, t.z, t.w}));
            }
            p["table"] = {{"v", v}, {"T", T}};
        }
        if (i < m.reports.size()) {
            const FitReport& r = m.reports[i];
            p["fit"] = {{"rounds", r.rounds}, {"converged", r.converged}, {"rms", r.rms}, {"rel_rms", r.rel_rms}};
        }
        points.push_back(p);
    }
    const json j = {{"schema", 1}, {"kind", "mesolab.cloth.model"}, {"lobes", m.lobes}, {"lookup_table", m.lookup_table}, {"points", points}};
    return j.dump(1) + "\n";
}

ClothModel model_from_json(const std::string& text, const std::string& source) {
    json j;
    try {
        j = json::parse(text);
    } catch (const json::parse_error& e) {
        throw InputError(source + ": not JSON (" + e.what() + ")");
    }
    if (!j.is_object() || j.value("kind", "") != "mesolab.cloth.model")
        throw InputError(source + ": not a cloth model (expected \"kind\": \"mesolab.cloth.model\")");
    if (j.value("schema", 0) != 1) throw InputError(source + ": schema " + j.value("schema", json(0)).dump() + " is not 1");
    ClothModel m;
    const json& lobes = key(j, "lobes", source);
    if (!lobes.is_number_integer() || lobes.get<int>() < 1 || lobes.get<int>() > 3) throw InputError(source + ": \"lobes\" must be 1, 2 or 3");
    m.lobes = lobes.get<int>();
    m.lookup_table = j.value("lookup_table", true);
    const json& points = key(j, "points", source);
    if (!points.is_array() || points.empty()) throw InputError(source + ": \"points\" must be a non-empty array");
    for (size_t i = 0; i < points.size(); ++i) {
        const std::string at = source + ": points[" + std::to_string(i) + "]";
        const json& p = points[i];
        ClothBrdf b;
        m.names.push_back(p.value("point", ""));
        b.L.kd = d3(key(p, "kd", at), at + ".kd");
        const json& ls = key(p, "lobes", at);
        if (!ls.is_array() || int(ls.size()) != m.lobes)
            throw InputError(at + ".lobes: expected " + std::to_string(m.lobes) + " lobes");
        for (size_t k = 0; k < ls.size(); ++k) {
            const std::string lk = at + ".lobes[" + std::to_string(k) + "]";
            LafortuneLobe l;
            l.Cx = d3(key(ls[k], "Cx", lk), lk + ".Cx"), l.Cy = d3(key(ls[k], "Cy", lk), lk + ".Cy");
            l.Cz = d3(key(ls[k], "Cz", lk), lk + ".Cz"), l.n = d3(key(ls[k], "n", lk), lk + ".n");
            for (int c = 0; c < 3; ++c)
                if (!(l.n[c] > 0.0)) throw InputError(lk + ".n: exponents must be > 0");
            b.L.lobes.push_back(l);
        }
        if (p.contains("f_max")) {
            b.f_max = d3(p.at("f_max"), at + ".f_max");
            for (int c = 0; c < 3; ++c)
                if (!(b.f_max[c] >= 0.0)) throw InputError(at + ".f_max: must be >= 0");
        }
        if (p.contains("table")) {
            const json& t = p.at("table");
            const json& v = key(t, "v", at + ".table");
            const json& T = key(t, "T", at + ".table");
            if (!v.is_array() || !T.is_array() || v.size() != T.size() || v.empty())
                throw InputError(at + ".table: \"v\" and \"T\" must be arrays of the same non-zero length");
            for (size_t k = 0; k < v.size(); ++k) {
                const dvec3 d = d3(v[k], at + ".table.v[" + std::to_string(k) + "]");
                if (!(glm::length(d) > 0.0)) throw InputError(at + ".table.v[" + std::to_string(k) + "]: zero direction");
                b.table.v.push_back(std::abs(glm::length(d) - 1.0) > 1e-12 ? glm::normalize(d) : d);
                const json& e = T[k];
                if (!e.is_array() || e.size() != 4) throw InputError(at + ".table.T[" + std::to_string(k) + "]: expected [r, g, b, alpha]");
                const dvec3 rgb = d3(json::array({e[0], e[1], e[2]}), at + ".table.T[" + std::to_string(k) + "]");
                if (!e[3].is_number()) throw InputError(at + ".table.T[" + std::to_string(k) + "]: alpha is not a number");
                b.table.T.push_back(dvec4(rgb, e[3].get<double>()));
            }
        }
        m.brdfs.push_back(std::move(b));
    }
    return m;
}

// [SECTION] Acquired samples (binary)
namespace {
static_assert(std::endian::native == std::endian::little, "cloth sample files are little-endian");
constexpr const char* kSamplesMagic = "mesolab cloth samples\n";

template <class T>
void put(std::string& out, T x) {
    char b[sizeof(T)];
    std::memcpy(b, &x, sizeof(T));
    out.append(b, sizeof(T));
}
void put3(std::string& out, dvec3 v) { put(out, v.x), put(out, v.y), put(out, v.z); }

struct Reader {
    const std::string& bytes;
    const std::string& source;
    size_t at = 0;
    template <class T>
    T get() {
        if (at + sizeof(T) > bytes.size()) throw InputError(source + ": the file ends early (truncated at byte " + std::to_string(at) + ")");
        T x;
        std::memcpy(&x, bytes.data() + at, sizeof(T));
        at += sizeof(T);
        return x;
    }
    double finite(double x, const char* what) {
        if (!std::isfinite(x)) throw InputError(source + ": a non-finite " + std::string(what) + " at byte " + std::to_string(at));
        return x;
    }
    dvec3 get3(const char* what) {
        const double x = get<double>(), y = get<double>(), z = get<double>();
        return dvec3(finite(x, what), finite(y, what), finite(z, what));
    }
};
}  // namespace

std::string sample_grid_bytes(const SampleGrid& g) {
    std::string out = kSamplesMagic;
    out += nlohmann::json{{"schema", 1}, {"res", g.res}, {"pairs", g.l.size()}, {"views", g.views.size()}}.dump() + "\n";
    for (const dvec3& v : g.views) put3(out, v);
    for (size_t i = 0; i < g.l.size(); ++i) put3(out, g.l[i]), put3(out, g.v[i]), put(out, int32_t(g.view_of[i]));
    for (size_t p = 0; p < g.f.size(); ++p) {
        put3(out, g.normal[p]), put3(out, g.tangent[p]);
        for (size_t k = 0; k < g.views.size(); ++k) put(out, float(g.alpha.empty() || g.alpha[p].empty() ? 1.0 : g.alpha[p][k]));
        for (const dvec3& f : g.f[p]) put(out, float(f.x)), put(out, float(f.y)), put(out, float(f.z));
    }
    return out;
}

SampleGrid sample_grid_from_bytes(const std::string& bytes, const std::string& source) {
    const std::string magic = kSamplesMagic;
    if (bytes.compare(0, magic.size(), magic) != 0) throw InputError(source + ": not a cloth sample file (expected it to start with \"mesolab cloth samples\")");
    const size_t eol = bytes.find('\n', magic.size());
    if (eol == std::string::npos) throw InputError(source + ": the header line is missing");
    nlohmann::json h;
    try {
        h = nlohmann::json::parse(bytes.substr(magic.size(), eol - magic.size()));
    } catch (const nlohmann::json::parse_error& e) {
        throw InputError(source + ": the header is not JSON (" + e.what() + ")");
    }
    if (h.value("schema", 0) != 1) throw InputError(source + ": schema " + h.value("schema", nlohmann::json(0)).dump() + " is not 1");
    const long long res = h.value("res", -1LL), pairs = h.value("pairs", -1LL), views = h.value("views", -1LL);
    if (res < 1 || res > 1024 || (res & (res - 1)) != 0) throw InputError(source + ": res " + std::to_string(res) + " is not a power of two in [1, 1024]");
    if (views < 1 || views > 1 << 16 || pairs < 1 || pairs > views * (1LL << 16))
        throw InputError(source + ": " + std::to_string(pairs) + " pairs over " + std::to_string(views) + " views is not a sample grid");
    const size_t R2 = size_t(res) * size_t(res), P = size_t(pairs), V = size_t(views);
    const size_t expect = eol + 1 + V * 24 + P * 52 + R2 * (48 + V * 4 + P * 12);
    if (bytes.size() != expect)
        throw InputError(source + ": " + std::to_string(bytes.size()) + " bytes, expected " + std::to_string(expect) + " for its header (truncated or not this format)");
    Reader r{bytes, source, eol + 1};
    SampleGrid g;
    g.res = int(res);
    for (size_t k = 0; k < V; ++k) g.views.push_back(r.get3("view direction"));
    for (size_t i = 0; i < P; ++i) {
        g.l.push_back(r.get3("light direction"));
        g.v.push_back(r.get3("view direction"));
        const int32_t vi = r.get<int32_t>();
        if (vi < 0 || size_t(vi) >= V) throw InputError(source + ": pair " + std::to_string(i) + " names view " + std::to_string(vi) + " of " + std::to_string(V));
        g.view_of.push_back(vi);
    }
    g.f.resize(R2), g.alpha.resize(R2), g.normal.resize(R2), g.tangent.resize(R2);
    for (size_t p = 0; p < R2; ++p) {
        g.normal[p] = r.get3("normal"), g.tangent[p] = r.get3("tangent");
        g.alpha[p].resize(V);
        for (size_t k = 0; k < V; ++k) g.alpha[p][k] = r.finite(double(r.get<float>()), "alpha");
        g.f[p].resize(P);
        for (size_t i = 0; i < P; ++i) {
            const double x = r.get<float>(), y = r.get<float>(), z = r.get<float>();
            g.f[p][i] = dvec3(r.finite(x, "value"), r.finite(y, "value"), r.finite(z, "value"));
        }
    }
    return g;
}

void write_sample_grid(const std::string& path, const SampleGrid& g) { write_text_atomic(path, sample_grid_bytes(g)); }

SampleGrid read_sample_grid(const std::string& path) { return sample_grid_from_bytes(read_all(path, "sample"), path); }

void write_model(const std::string& path, const ClothModel& m) { write_text_atomic(path, model_to_json(m)); }

ClothModel read_model(const std::string& path) { return model_from_json(read_all(path, "model"), path); }
}  // namespace mesolab::cloth
