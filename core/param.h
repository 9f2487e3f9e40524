#pragma once
// [SECTION] Parameters declared once.
// Each technique (and each scene-level group: camera, light, env, geometry, effects) declares
// its parameters exactly once as a ParamGroup: name, type, default, range, unit, help, and what
// a change costs. Everything else is derived from that declaration: the ImGui widgets
// (panels/widgets.cpp), the preset JSON (core/scene.cpp), `--set group.param=value`, the
// `preset schema` listing, and the stage graph's cache keys (core/stage.cpp).
#include "core/math.h"
#include <array>
#include <cstdint>
#include <limits>
#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <variant>
#include <vector>
#include <nlohmann/json.hpp>

namespace mesolab {

using json = nlohmann::ordered_json;

enum class ParamType { Bool, Int, Float, Vec2, Vec3, Color, Enum, Path, Text };
// What a change costs: only a redraw of the frame, or a recompute of the stages that read it. The
// GUI redraws after any edit and the stage graph's cache keys decide what recomputes; the cost is
// what the widgets' tooltips and `preset schema` tell. It is derived from the stage graph, never
// written by hand: a key that a stage declares (StageDecl::params, exactly or as "group.*"), or an
// effect that a stage needs, costs a recompute (Registry).
enum class Cost { Redraw, Recompute };
// Which way of a knob is more accurate (used by `sweep` to pick its reference).
enum class Accuracy { None, Higher, Lower };

// Value storage per type: Bool->bool, Int->int64_t, Float->double, Vec2->array<double,2>,
// Vec3/Color->array<double,3>, Enum/Path->string.
using Value = std::variant<bool, int64_t, double, std::array<double, 2>, std::array<double, 3>, std::string>;

const char* to_string(ParamType t);
const char* to_string(Cost c);

struct ParamDecl {
    std::string name;  // short name inside its group ("kd"); the public key is "group.name"
    ParamType type = ParamType::Float;
    Value def;
    double min = -std::numeric_limits<double>::infinity();  // per component for vectors
    double max = std::numeric_limits<double>::infinity();
    std::string unit;
    std::string help;
    Cost cost = Cost::Redraw;          // derived from the stage graph by the registry
    std::vector<std::string> choices;  // Enum values; for Path: built-in names accepted instead of a file
    Accuracy accuracy = Accuracy::None;
    std::optional<Value> reference;    // the converged setting of this knob, for sweeps
    bool log_scale = false;            // widget hint: logarithmic slider
    // Only used when sibling `used_when_key` has one of `used_when_values` (e.g. geometry.path
    // only when geometry.type is mesh). A preset that sets an unused key is an error.
    std::string used_when_key;
    std::vector<std::string> used_when_values;
    // Text only: the syntax check of a value (returns what is wrong, empty when it is fine), so a
    // bad value is refused where it is set (preset, --set, widget) with the key named.
    std::function<std::string(const std::string&)> syntax;
    bool odd_only = false;             // Int: only odd values (ParamDecl::odd)
    bool pow2_only = false;            // Int: only powers of two (ParamDecl::power_of_two)

    // Fluent setters for concise declarations.
    ParamDecl& range(double lo, double hi) { min = lo; max = hi; return *this; }
    ParamDecl& in(std::string u) { unit = std::move(u); return *this; }
    ParamDecl& doc(std::string h) { help = std::move(h); return *this; }
    ParamDecl& log() { log_scale = true; return *this; }
    ParamDecl& more_accurate(Accuracy a, std::optional<Value> ref = std::nullopt) { accuracy = a; reference = std::move(ref); return *this; }
    ParamDecl& builtins(std::vector<std::string> names) { choices = std::move(names); return *this; }
    // A Path value that names a file (not one of the built-in names, not empty).
    bool is_file(const Value& v) const;
    ParamDecl& checked(std::function<std::string(const std::string&)> f) { syntax = std::move(f); return *this; }
    // Int only: odd values only (a kernel width), refused where set with the key named.
    ParamDecl& odd() { odd_only = true; return *this; }
    ParamDecl& power_of_two() { pow2_only = true; return *this; }
    ParamDecl& used_when(std::string key, std::vector<std::string> values) { used_when_key = std::move(key); used_when_values = std::move(values); return *this; }
};

class ParamTable;

// A titled group of a ParamGroup's parameters, as the panels show them (a tree node each).
struct ParamSection {
    std::string title;
    std::vector<std::string> names;  // in the order shown
    bool open = true;                // open when first shown
};

class ParamGroup {
public:
    ParamGroup() = default;
    ParamGroup(std::string name, std::string title) : name_(std::move(name)), title_(std::move(title)) {}

    ParamDecl& add_bool(std::string name, bool def);
    ParamDecl& add_int(std::string name, int64_t def);
    ParamDecl& add_float(std::string name, double def);
    ParamDecl& add_vec2(std::string name, std::array<double, 2> def);
    ParamDecl& add_vec3(std::string name, std::array<double, 3> def);
    ParamDecl& add_color(std::string name, std::array<double, 3> def);
    ParamDecl& add_enum(std::string name, std::vector<std::string> choices, std::string def);
    ParamDecl& add_path(std::string name, std::string def = "");
    ParamDecl& add_text(std::string name, std::string def = "");  // free text, e.g. a small expression (see ParamDecl::syntax)

    const std::string& name() const { return name_; }
    const std::string& title() const { return title_; }
    const std::vector<ParamDecl>& decls() const { return decls_; }
    const ParamDecl* find(std::string_view name) const;
    int index_of(std::string_view name) const;  // -1 if absent
    std::vector<std::string> names() const;

    // A table holding every default.
    ParamTable defaults() const;
    // The derived cost of a change of `name` (the registry sets it once every stage is declared).
    void set_cost(std::string_view name, Cost c);
    // Declares a section of already declared parameters (std::logic_error for an unknown name or
    // one already in a section). Parameters in no section are shown after the sections.
    void section(std::string title, std::vector<std::string> names, bool open = true, bool first = false);
    const std::vector<ParamSection>& sections() const { return sections_; }

private:
    ParamDecl& add(ParamDecl d);
    std::string name_, title_;
    std::vector<ParamDecl> decls_;
    std::vector<ParamSection> sections_;
};

// [SECTION] Values of one group (one object's material, one light, the camera...).
class ParamTable {
public:
    ParamTable() = default;
    explicit ParamTable(const ParamGroup* g);

    const ParamGroup& group() const { return *group_; }
    bool valid() const { return group_ != nullptr; }
    // Every value, in declaration order: a read of every key of the group (a watch sees "*").
    const std::vector<Value>& values() const;

    const Value& get(std::string_view name) const;
    bool get_bool(std::string_view name) const;
    int64_t get_int(std::string_view name) const;
    double get_float(std::string_view name) const;
    vec2 get_vec2(std::string_view name) const;
    vec3 get_vec3(std::string_view name) const;
    const std::string& get_string(std::string_view name) const;

    // Checks type, range and choices; throws InputError naming "group.name" (and `where`).
    void set(std::string_view name, const Value& v, const std::string& where = "");
    // Whether a declaration is in use given the current values (see ParamDecl::used_when).
    bool is_used(const ParamDecl& d) const;

    // Compares every value: a read of every key of both tables (a watch sees "*").
    bool operator==(const ParamTable& o) const;

private:
    const ParamGroup* group_ = nullptr;
    std::vector<Value> values_;
};

// [SECTION] Watching reads
// While a ParamReadScope is alive on a thread, every value read through a ParamTable on that
// thread (get, the typed getters; values() and == as a read of "*", every key) is reported to its
// watch. mesolab's parallel loops carry the watch into their tasks (core/parallel.h). A session uses it to check that a
// stage reads only the keys it declares (core/session.h): a key read but not declared would not
// be part of the stage's cache key, and its cached result would go stale when the key changes.
class ParamReadWatch {
public:
    virtual ~ParamReadWatch() = default;
    virtual void read(const ParamTable& table, std::string_view key) = 0;
};

class ParamReadScope {
public:
    explicit ParamReadScope(ParamReadWatch* watch);  // null: no watch on this thread meanwhile
    ~ParamReadScope();
    ParamReadScope(const ParamReadScope&) = delete;
    ParamReadScope& operator=(const ParamReadScope&) = delete;

private:
    ParamReadWatch* previous_;
};
// The watch of the calling thread (null when none), to carry into work on other threads.
ParamReadWatch* current_read_watch();

// [SECTION] Conversions, each naming `where` (file and key) in its InputError.
// JSON value -> Value with type/range/choice checks.
Value value_from_json(const ParamDecl& d, const json& j, const std::string& where);
json value_to_json(const ParamDecl& d, const Value& v);
// Text from `--set` ("0.5", "true", "1,2,3", "orbit", a path) -> Value with checks.
Value value_from_text(const ParamDecl& d, std::string_view text, const std::string& where);
// Human text ("0.5", "1, 2, 3"); parses back with value_from_text.
std::string value_to_text(const ParamDecl& d, const Value& v);
// Throws InputError if v is out of range or not one of the choices.
void validate_value(const ParamDecl& d, const Value& v, const std::string& where);
// Canonical bytes for cache keys. Paths include the file's size, modification time and file
// number (device, inode), so editing a file on disk invalidates the stages that read it, and so
// does an atomic re-save (a new file renamed over the old) within one tick of the file clock.
// FileIdentity::Contents (for keys kept between runs and machines) puts a hash of the file's bytes
// in their place.
enum class FileIdentity { Stat, Contents };
std::string value_canonical(const ParamDecl& d, const Value& v, const std::string& base_dir, FileIdentity files = FileIdentity::Stat);
// The schema of one group as JSON (every parameter with type, default, range, unit, help, cost).
json group_schema(const ParamGroup& g);
std::string describe_range(const ParamDecl& d);
}  // namespace mesolab
