#include "core/strings.h"
#include "core/param.h"
#include "core/hash.h"
#include "core/error.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <sys/stat.h>

namespace mesolab {
namespace {

std::string full_key(const ParamGroup* g, const ParamDecl& d) {
    return g && !g->name().empty() ? g->name() + "." + d.name : d.name;
}

std::string fmt_double(double v) {
    // Shortest text that parses back to the same double.
    char buf[64];
    auto r = std::to_chars(buf, buf + sizeof buf, v);
    return std::string(buf, r.ptr);
}

std::string prefix(const std::string& where) { return where.empty() ? std::string() : where + ": "; }

[[noreturn]] void fail(const std::string& where, const std::string& msg) { throw InputError(prefix(where) + msg); }

bool parse_double(std::string_view s, double& out) {
    while (!s.empty() && std::isspace(static_cast<unsigned char>(s.front()))) s.remove_prefix(1);
    while (!s.empty() && std::isspace(static_cast<unsigned char>(s.back()))) s.remove_suffix(1);
    if (s.empty()) return false;
    if (s.front() == '+') s.remove_prefix(1);
    auto r = std::from_chars(s.data(), s.data() + s.size(), out);
    return r.ec == std::errc() && r.ptr == s.data() + s.size();
}

const char* expected_text(const ParamDecl& d) {
    switch (d.type) {
        case ParamType::Bool: return "true or false";
        case ParamType::Int: return "an integer";
        case ParamType::Float: return "a number";
        case ParamType::Vec2: return "two numbers [a, b]";
        case ParamType::Vec3: return "three numbers [x, y, z]";
        case ParamType::Color: return "a colour [r, g, b]";
        case ParamType::Enum: return "one of the listed names";
        case ParamType::Path: return "a file path (string)";
        case ParamType::Text: return "a string";
    }
    return "?";
}

std::string choices_text(const ParamDecl& d) {
    std::string s;
    for (size_t i = 0; i < d.choices.size(); ++i) s += (i ? "|" : "") + d.choices[i];
    return s;
}
}  // namespace

const char* to_string(ParamType t) {
    switch (t) {
        case ParamType::Bool: return "bool";
        case ParamType::Int: return "int";
        case ParamType::Float: return "float";
        case ParamType::Vec2: return "vec2";
        case ParamType::Vec3: return "vec3";
        case ParamType::Color: return "color";
        case ParamType::Enum: return "enum";
        case ParamType::Path: return "path";
        case ParamType::Text: return "text";
    }
    return "?";
}

const char* to_string(Cost c) {
    switch (c) {
        case Cost::Redraw: return "redraw";
        case Cost::Recompute: return "recompute";
    }
    return "?";
}

bool ParamDecl::is_file(const Value& v) const {
    if (type != ParamType::Path) return false;
    const auto& s = std::get<std::string>(v);
    return !s.empty() && std::find(choices.begin(), choices.end(), s) == choices.end();
}

// [SECTION] ParamGroup
ParamDecl& ParamGroup::add(ParamDecl d) {
    if (find(d.name)) throw std::logic_error("parameter declared twice: " + name_ + "." + d.name);
    decls_.push_back(std::move(d));
    return decls_.back();
}
ParamDecl& ParamGroup::add_bool(std::string n, bool def) { return add({.name = std::move(n), .type = ParamType::Bool, .def = def}); }
ParamDecl& ParamGroup::add_int(std::string n, int64_t def) { return add({.name = std::move(n), .type = ParamType::Int, .def = def}); }
ParamDecl& ParamGroup::add_float(std::string n, double def) { return add({.name = std::move(n), .type = ParamType::Float, .def = def}); }
ParamDecl& ParamGroup::add_vec2(std::string n, std::array<double, 2> def) { return add({.name = std::move(n), .type = ParamType::Vec2, .def = def}); }
ParamDecl& ParamGroup::add_vec3(std::string n, std::array<double, 3> def) { return add({.name = std::move(n), .type = ParamType::Vec3, .def = def}); }
ParamDecl& ParamGroup::add_color(std::string n, std::array<double, 3> def) {
    return add({.name = std::move(n), .type = ParamType::Color, .def = def, .min = 0.0, .max = 1.0});
}
ParamDecl& ParamGroup::add_enum(std::string n, std::vector<std::string> choices, std::string def) {
    return add({.name = std::move(n), .type = ParamType::Enum, .def = std::move(def), .choices = std::move(choices)});
}
ParamDecl& ParamGroup::add_path(std::string n, std::string def) { return add({.name = std::move(n), .type = ParamType::Path, .def = std::move(def)}); }
ParamDecl& ParamGroup::add_text(std::string n, std::string def) { return add({.name = std::move(n), .type = ParamType::Text, .def = std::move(def)}); }

const ParamDecl* ParamGroup::find(std::string_view n) const {
    for (const auto& d : decls_)
        if (d.name == n) return &d;
    return nullptr;
}
int ParamGroup::index_of(std::string_view n) const {
    for (size_t i = 0; i < decls_.size(); ++i)
        if (decls_[i].name == n) return int(i);
    return -1;
}
std::vector<std::string> ParamGroup::names() const {
    std::vector<std::string> r;
    for (const auto& d : decls_) r.push_back(d.name);
    return r;
}
ParamTable ParamGroup::defaults() const { return ParamTable(this); }

// [SECTION] ParamTable
ParamTable::ParamTable(const ParamGroup* g) : group_(g) {
    for (const auto& d : g->decls()) values_.push_back(d.def);
}

namespace {
thread_local ParamReadWatch* t_read_watch = nullptr;
}

ParamReadScope::ParamReadScope(ParamReadWatch* watch) : previous_(t_read_watch) { t_read_watch = watch; }
ParamReadScope::~ParamReadScope() { t_read_watch = previous_; }
ParamReadWatch* current_read_watch() { return t_read_watch; }

const std::vector<Value>& ParamTable::values() const {
    if (t_read_watch) t_read_watch->read(*this, "*");
    return values_;
}

bool ParamTable::operator==(const ParamTable& o) const {
    if (t_read_watch) {
        t_read_watch->read(*this, "*");
        t_read_watch->read(o, "*");
    }
    return group_ == o.group_ && values_ == o.values_;
}

void ParamGroup::section(std::string title, std::vector<std::string> names, bool open, bool first) {
    for (const std::string& n : names) {
        if (index_of(n) < 0) throw std::logic_error("section " + title + ": no parameter " + name_ + "." + n);
        for (const ParamSection& sec : sections_)
            if (std::find(sec.names.begin(), sec.names.end(), n) != sec.names.end())
                throw std::logic_error("section " + title + ": " + name_ + "." + n + " is already in section " + sec.title);
    }
    sections_.insert(first ? sections_.begin() : sections_.end(), ParamSection{std::move(title), std::move(names), open});
}

void ParamGroup::set_cost(std::string_view name, Cost c) {
    const int i = index_of(name);
    if (i < 0) throw std::logic_error("no parameter " + name_ + "." + std::string(name));
    decls_[size_t(i)].cost = c;
}

const Value& ParamTable::get(std::string_view n) const {
    if (t_read_watch) t_read_watch->read(*this, n);
    const int i = group_ ? group_->index_of(n) : -1;
    if (i < 0) throw std::logic_error("no parameter " + (group_ ? group_->name() : std::string("?")) + "." + std::string(n));
    return values_[size_t(i)];
}
bool ParamTable::get_bool(std::string_view n) const { return std::get<bool>(get(n)); }
int64_t ParamTable::get_int(std::string_view n) const { return std::get<int64_t>(get(n)); }
double ParamTable::get_float(std::string_view n) const { return std::get<double>(get(n)); }
vec2 ParamTable::get_vec2(std::string_view n) const {
    const auto& a = std::get<std::array<double, 2>>(get(n));
    return {float(a[0]), float(a[1])};
}
vec3 ParamTable::get_vec3(std::string_view n) const {
    const auto& a = std::get<std::array<double, 3>>(get(n));
    return {float(a[0]), float(a[1]), float(a[2])};
}
const std::string& ParamTable::get_string(std::string_view n) const { return std::get<std::string>(get(n)); }

void ParamTable::set(std::string_view n, const Value& v, const std::string& where) {
    const int i = group_->index_of(n);
    if (i < 0) {
        const std::string hint = nearest_key(std::string(n), group_->names());
        fail(where, "unknown parameter '" + group_->name() + "." + std::string(n) + "'" +
                        (hint.empty() ? "" : " (did you mean '" + group_->name() + "." + hint + "'?)"));
    }
    const ParamDecl& d = group_->decls()[size_t(i)];
    if (v.index() != d.def.index())
        fail(where, full_key(group_, d) + ": wrong type, expected " + expected_text(d));
    validate_value(d, v, where.empty() ? full_key(group_, d) : where);
    values_[size_t(i)] = v;
}

bool ParamTable::is_used(const ParamDecl& d) const {
    if (d.used_when_key.empty()) return true;
    // A key used under another is unused wherever that one is (e.g. a method's sub-option).
    if (const ParamDecl* parent = group_->find(d.used_when_key); parent && !is_used(*parent)) return false;
    const Value& v = get(d.used_when_key);
    std::string s;
    if (auto* b = std::get_if<bool>(&v)) s = *b ? "true" : "false";
    else if (auto* str = std::get_if<std::string>(&v)) s = *str;
    for (const auto& w : d.used_when_values)
        if (w == s) return true;
    return false;
}

// [SECTION] Validation and conversions
std::string describe_range(const ParamDecl& d) {
    if (d.type == ParamType::Enum) return choices_text(d);
    if (d.type == ParamType::Path) return d.choices.empty() ? "" : choices_text(d) + " or a file";
    if (d.type == ParamType::Bool || d.type == ParamType::Text) return "";
    auto b = [](double v) { return std::isinf(v) ? std::string(v < 0 ? "-inf" : "inf") : fmt_double(v); };
    return "[" + b(d.min) + ", " + b(d.max) + "]";
}

void validate_value(const ParamDecl& d, const Value& v, const std::string& where) {
    auto check = [&](double x) {
        if (!std::isfinite(x)) fail(where, "value " + fmt_double(x) + " is not finite (expected " + std::string(expected_text(d)) + " in " + describe_range(d) + ")");
        if (x < d.min || x > d.max)
            fail(where, "value " + fmt_double(x) + " is out of range " + describe_range(d) + (d.unit.empty() ? "" : " " + d.unit));
    };
    switch (d.type) {
        case ParamType::Int:
            check(double(std::get<int64_t>(v)));
            if (d.odd_only && std::get<int64_t>(v) % 2 == 0) fail(where, "value " + std::to_string(std::get<int64_t>(v)) + " must be odd");
            if (d.pow2_only && (std::get<int64_t>(v) < 1 || (std::get<int64_t>(v) & (std::get<int64_t>(v) - 1)) != 0))
                fail(where, "value " + std::to_string(std::get<int64_t>(v)) + " must be a power of two");
            break;
        case ParamType::Float: check(std::get<double>(v)); break;
        case ParamType::Vec2: for (double x : std::get<std::array<double, 2>>(v)) check(x); break;
        case ParamType::Vec3:
        case ParamType::Color: for (double x : std::get<std::array<double, 3>>(v)) check(x); break;
        case ParamType::Enum: {
            const auto& s = std::get<std::string>(v);
            bool ok = false;
            for (const auto& c : d.choices) ok |= (c == s);
            if (!ok) {
                const std::string hint = nearest_key(s, d.choices);
                fail(where, "'" + s + "' is not one of " + choices_text(d) + (hint.empty() ? "" : " (did you mean '" + hint + "'?)"));
            }
            break;
        }
        case ParamType::Text:
            if (d.syntax)
                if (const std::string what = d.syntax(std::get<std::string>(v)); !what.empty()) fail(where, what);
            break;
        case ParamType::Bool:
        case ParamType::Path: break;
    }
}

Value value_from_json(const ParamDecl& d, const json& j, const std::string& where) {
    auto bad = [&]() -> Value { fail(where, "expected " + std::string(expected_text(d)) + ", got " + j.dump()); };
    auto num = [&](const json& x, double& out) {
        if (!x.is_number()) return false;
        out = x.get<double>();
        return true;
    };
    Value v;
    switch (d.type) {
        case ParamType::Bool:
            if (!j.is_boolean()) return bad();
            v = j.get<bool>();
            break;
        case ParamType::Int: {
            if (j.is_number_integer()) v = j.get<int64_t>();
            else if (j.is_number_float() && std::floor(j.get<double>()) == j.get<double>() && std::fabs(j.get<double>()) < 9e15) v = int64_t(j.get<double>());
            else return bad();
            break;
        }
        case ParamType::Float: {
            double x;
            if (!num(j, x)) return bad();
            v = x;
            break;
        }
        case ParamType::Vec2: {
            std::array<double, 2> a{};
            if (!j.is_array() || j.size() != 2 || !num(j[0], a[0]) || !num(j[1], a[1])) return bad();
            v = a;
            break;
        }
        case ParamType::Vec3:
        case ParamType::Color: {
            std::array<double, 3> a{};
            if (!j.is_array() || j.size() != 3 || !num(j[0], a[0]) || !num(j[1], a[1]) || !num(j[2], a[2])) return bad();
            v = a;
            break;
        }
        case ParamType::Enum:
        case ParamType::Path:
        case ParamType::Text:
            if (!j.is_string()) return bad();
            v = j.get<std::string>();
            break;
    }
    validate_value(d, v, where);
    return v;
}

json value_to_json(const ParamDecl& d, const Value& v) {
    switch (d.type) {
        case ParamType::Bool: return std::get<bool>(v);
        case ParamType::Int: return std::get<int64_t>(v);
        case ParamType::Float: return std::get<double>(v);
        case ParamType::Vec2: { const auto& a = std::get<std::array<double, 2>>(v); return json::array({a[0], a[1]}); }
        case ParamType::Vec3:
        case ParamType::Color: { const auto& a = std::get<std::array<double, 3>>(v); return json::array({a[0], a[1], a[2]}); }
        case ParamType::Enum:
        case ParamType::Path:
        case ParamType::Text: return std::get<std::string>(v);
    }
    return nullptr;
}

Value value_from_text(const ParamDecl& d, std::string_view text, const std::string& where) {
    auto bad = [&]() -> Value { fail(where, "expected " + std::string(expected_text(d)) + ", got '" + std::string(text) + "'"); };
    auto numbers = [&](size_t n, double* out) {
        std::string s(text);
        for (char& c : s)
            if (c == '[' || c == ']') c = ' ';
        const std::vector<std::string> parts = mesolab::split(s, ',');
        if (parts.size() != n) return false;
        for (size_t i = 0; i < n; ++i)
            if (!parse_double(parts[i], out[i])) return false;
        return true;
    };
    Value v;
    switch (d.type) {
        case ParamType::Bool:
            if (text == "true" || text == "1" || text == "on" || text == "yes") v = true;
            else if (text == "false" || text == "0" || text == "off" || text == "no") v = false;
            else return bad();
            break;
        case ParamType::Int: {
            int64_t x = 0;
            auto r = std::from_chars(text.data(), text.data() + text.size(), x);
            if (r.ec != std::errc() || r.ptr != text.data() + text.size()) return bad();
            v = x;
            break;
        }
        case ParamType::Float: {
            double x;
            if (!parse_double(text, x)) return bad();
            v = x;
            break;
        }
        case ParamType::Vec2: {
            std::array<double, 2> a{};
            if (!numbers(2, a.data())) return bad();
            v = a;
            break;
        }
        case ParamType::Vec3:
        case ParamType::Color: {
            std::array<double, 3> a{};
            if (!numbers(3, a.data())) return bad();
            v = a;
            break;
        }
        case ParamType::Enum:
        case ParamType::Path:
        case ParamType::Text: v = std::string(text); break;
    }
    validate_value(d, v, where);
    return v;
}

std::string value_to_text(const ParamDecl& d, const Value& v) {
    switch (d.type) {
        case ParamType::Bool: return std::get<bool>(v) ? "true" : "false";
        case ParamType::Int: return std::to_string(std::get<int64_t>(v));
        case ParamType::Float: return fmt_double(std::get<double>(v));
        case ParamType::Vec2: { const auto& a = std::get<std::array<double, 2>>(v); return fmt_double(a[0]) + "," + fmt_double(a[1]); }
        case ParamType::Vec3:
        case ParamType::Color: { const auto& a = std::get<std::array<double, 3>>(v); return fmt_double(a[0]) + "," + fmt_double(a[1]) + "," + fmt_double(a[2]); }
        case ParamType::Enum:
        case ParamType::Path:
        case ParamType::Text: return std::get<std::string>(v);
    }
    return {};
}

std::string value_canonical(const ParamDecl& d, const Value& v, const std::string& base_dir, FileIdentity files) {
    std::string s = d.name + "=" + value_to_text(d, v);
    if (d.is_file(v)) {
        namespace fs = std::filesystem;
        fs::path p = std::get<std::string>(v);
        if (p.is_relative() && !base_dir.empty()) p = fs::path(base_dir) / p;
        if (files == FileIdentity::Contents) {
            // The file's kind (its extension: the reader follows it) and bytes, not its name or
            // folder: a scene keeps its keys when its files move (a pack, another machine).
            s = d.name + "=*" + p.extension().string();
            std::ifstream in(p, std::ios::binary);
            if (!in) return s + "|missing";
            Fnv1a h;  // over the bytes
            char buf[1 << 16];
            while (in.read(buf, sizeof buf) || in.gcount() > 0) {
                h.add(buf, size_t(in.gcount()));
                if (!in) break;
            }
            return s + "|" + std::to_string(h.h);
        }
        // Size, modification time and file number (device, inode): file systems stamp times with
        // a coarse clock (several ms), so two atomic saves of one size within a tick differ only
        // by the new file that each rename puts in place.
        struct stat st {};
        if (::stat(p.c_str(), &st) != 0 || !S_ISREG(st.st_mode)) {
            s += "|missing";
        } else {
            s += "|" + std::to_string(st.st_size) + ":" + std::to_string(st.st_mtim.tv_sec) + "." + std::to_string(st.st_mtim.tv_nsec) + ":" +
                 std::to_string(st.st_dev) + ":" + std::to_string(st.st_ino);
        }
    }
    return s;
}

json group_schema(const ParamGroup& g) {
    json params = json::array();
    for (const auto& d : g.decls()) {
        json p;
        p["key"] = g.name() + "." + d.name;
        p["type"] = to_string(d.type);
        p["default"] = value_to_json(d, d.def);
        if (d.type == ParamType::Enum) p["choices"] = d.choices;
        if (d.type == ParamType::Path && !d.choices.empty()) p["builtins"] = d.choices;
        if (std::isfinite(d.min)) p["min"] = d.min;
        if (std::isfinite(d.max)) p["max"] = d.max;
        if (!d.unit.empty()) p["unit"] = d.unit;
        p["help"] = d.help;
        p["cost"] = to_string(d.cost);
        if (!d.used_when_key.empty()) p["used_when"] = g.name() + "." + d.used_when_key + " in " + json(d.used_when_values).dump();
        if (d.accuracy != Accuracy::None) p["more_accurate"] = d.accuracy == Accuracy::Higher ? "higher" : "lower";
        if (d.reference) p["reference"] = value_to_json(d, *d.reference);
        params.push_back(std::move(p));
    }
    json j;
    j["group"] = g.name();
    j["title"] = g.title();
    j["params"] = std::move(params);
    return j;
}
}  // namespace mesolab
