#include "core/strings.h"
#include "core/scene.h"
#include "core/error.h"
#include "core/file.h"
#include "core/pack.h"
#include "core/technique.h"

#include <filesystem>
#include <fstream>
#include <sstream>
#include <unistd.h>

namespace fs = std::filesystem;

namespace mesolab {
namespace {

[[noreturn]] void fail(const std::string& source, const std::string& key, const std::string& msg) {
    throw InputError(source + ": " + (key.empty() ? "" : key + ": ") + msg);
}

std::string suggestion(const std::string& key, const std::vector<std::string>& candidates) {
    const std::string hint = nearest_key(key, candidates);
    return hint.empty() ? "" : " (did you mean '" + hint + "'?)";
}

std::string list_text(const std::vector<std::string>& v) {
    std::string s;
    for (size_t i = 0; i < v.size(); ++i) s += (i ? ", " : "") + v[i];
    return s;
}

// One group's table from a JSON object: every key must be declared and used.
ParamTable parse_table(const ParamGroup& g, const json& j, const std::string& source, const std::string& path,
                       const PathCheck& check_file, const std::vector<std::string>& skip = {}) {
    ParamTable t(&g);
    if (!j.is_object()) fail(source, path, "expected a JSON object of " + g.name() + " parameters, got " + j.dump());
    std::vector<const ParamDecl*> given;
    for (auto it = j.begin(); it != j.end(); ++it) {
        if (std::find(skip.begin(), skip.end(), it.key()) != skip.end()) continue;
        const std::string key = path + "." + it.key();
        const ParamDecl* d = g.find(it.key());
        if (!d) fail(source, key, "unknown key" + suggestion(it.key(), g.names()) + "; " + g.name() + " parameters are: " + list_text(g.names()));
        const std::string where = source + ": " + key + (key == g.name() + "." + d->name ? "" : " (" + g.name() + "." + d->name + ")");
        t.set(d->name, value_from_json(*d, it.value(), where));
        given.push_back(d);
    }
    for (const ParamDecl* d : given)
        if (!t.is_used(*d))
            fail(source, path + "." + d->name,
                 "not used when " + g.name() + "." + d->used_when_key + " is '" + value_to_text(*g.find(d->used_when_key), t.get(d->used_when_key)) +
                     "' (it applies to " + d->used_when_key + " = " + list_text(d->used_when_values) + "); remove it");
    for (const ParamDecl* d : given)
        if (d->is_file(t.get(d->name))) check_file(path + "." + d->name, t.get_string(d->name));
    return t;
}

json table_to_json(const ParamTable& t) {
    json j = json::object();
    for (const auto& d : t.group().decls())
        if (t.is_used(d)) j[d.name] = value_to_json(d, t.get(d.name));
    return j;
}

size_t parse_index(const std::string& s, size_t count, const std::string& key, const std::string& what) {
    size_t n = 0;
    bool ok = !s.empty();
    for (char c : s) ok &= (c >= '0' && c <= '9');
    if (ok) n = std::stoul(s);
    if (!ok || n >= count)
        throw InputError("--set " + key + ": " + what + " index '" + s + "' is out of range (the scene has " + std::to_string(count) + " " + what + (count == 1 ? "" : "s") + ")");
    return n;
}

// Targets of a public key: the tables it addresses and the short parameter name.
struct Target {
    std::vector<ParamTable*> tables;
    std::string param;
};

Target resolve_key(Scene& s, const std::string& key) {
    const Registry& reg = Registry::instance();
    const auto parts = split(key, '.');
    auto unknown = [&]() -> Target {
        throw InputError("--set " + key + ": unknown key" + suggestion(key, public_keys(s)) + "; `mesolab preset schema` lists every key");
    };
    if (parts.size() < 2) return unknown();
    const std::string& g = parts[0];
    if ((g == "camera" || g == "env" || g == "effects") && parts.size() == 2)
        return {{g == "camera" ? &s.camera : g == "env" ? &s.env : &s.effects}, parts[1]};
    if (g == "light" && parts.size() == 2) {
        if (s.lights.empty()) throw InputError("--set " + key + ": the scene has no light (add one to \"lights\" in the preset)");
        return {{&s.lights[0]}, parts[1]};
    }
    if (g == "lights" && parts.size() == 3) return {{&s.lights[parse_index(parts[1], s.lights.size(), key, "light")]}, parts[2]};
    if (g == "geometry" && parts.size() == 2) {
        if (s.objects.empty()) throw InputError("--set " + key + ": the scene has no object");
        return {{&s.objects[0].geometry}, parts[1]};
    }
    if (g == "objects" && parts.size() == 4 && (parts[2] == "geometry" || parts[2] == "material")) {
        SceneObject& o = s.objects[parse_index(parts[1], s.objects.size(), key, "object")];
        return {{parts[2] == "geometry" ? &o.geometry : &o.material}, parts[3]};
    }
    if (reg.technique(g) && parts.size() == 2) {
        Target t{{}, parts[1]};
        for (auto& o : s.objects)
            if (o.technique == g) t.tables.push_back(&o.material);
        if (t.tables.empty()) throw InputError("--set " + key + ": no object in this scene uses technique '" + g + "'");
        return t;
    }
    return unknown();
}
}  // namespace

// [SECTION] Scene helpers
// Tables are equal when every value is; paths compare by the file they name, so a preset saved
// into another folder (its relative paths rebased) equals the original.
static bool tables_equal(const Scene& sa, const ParamTable& a, const Scene& sb, const ParamTable& b) {
    if (!(a.valid() && b.valid() && &a.group() == &b.group())) return a.valid() == b.valid() && !a.valid();
    for (const auto& d : a.group().decls()) {
        if (d.is_file(a.get(d.name)) || d.is_file(b.get(d.name))) {
            if (sa.resolve(a.get_string(d.name)) != sb.resolve(b.get_string(d.name))) return false;
        } else if (a.get(d.name) != b.get(d.name)) {
            return false;
        }
    }
    return true;
}

bool Scene::operator==(const Scene& o) const {
    if (schema != o.schema || name != o.name || description != o.description || !tables_equal(*this, camera, o, o.camera) ||
        !tables_equal(*this, env, o, o.env) || !tables_equal(*this, effects, o, o.effects) || lights.size() != o.lights.size() ||
        objects.size() != o.objects.size())
        return false;
    for (size_t i = 0; i < lights.size(); ++i)
        if (!tables_equal(*this, lights[i], o, o.lights[i])) return false;
    for (size_t i = 0; i < objects.size(); ++i) {
        const auto &a = objects[i], &b = o.objects[i];
        if (a.name != b.name || a.technique != b.technique || !tables_equal(*this, a.geometry, o, b.geometry) || !tables_equal(*this, a.material, o, b.material))
            return false;
    }
    return true;
}

std::string Scene::resolve(const std::string& path) const {
    if (path.empty()) return path;
    fs::path p = path;
    if (p.is_relative() && !base_dir.empty()) p = fs::path(base_dir) / p;
    return p.lexically_normal().string();
}

bool Scene::uses_technique(const std::string& t) const {
    for (const auto& o : objects)
        if (o.technique == t) return true;
    return false;
}

Scene default_scene(const std::string& technique) {
    const Registry& reg = Registry::instance();
    const Technique* t = reg.technique(technique);
    if (!t) throw InputError("unknown technique '" + technique + "'" + suggestion(technique, reg.technique_names()));
    Scene s;
    s.name = "default";
    s.camera = reg.camera().defaults();
    s.env = reg.env().defaults();
    s.effects = reg.effects().defaults();
    s.lights.push_back(reg.light().defaults());
    s.objects.push_back({"object", reg.geometry().defaults(), technique, t->params().defaults()});
    return s;
}

// [SECTION] JSON -> Scene
Scene scene_from_json(const json& j, const std::string& source, const std::string& base_dir) {
    const PathCheck exists = [&](const std::string& key, const std::string& value) {
        fs::path full = value;
        if (full.is_relative() && !base_dir.empty()) full = fs::path(base_dir) / full;
        std::error_code ec;
        if (!fs::is_regular_file(full, ec)) fail(source, key, "file '" + value + "' not found (looked for " + full.lexically_normal().string() + ")");
    };
    return scene_from_json(j, source, base_dir, exists);
}

Scene scene_from_json(const json& j, const std::string& source, const std::string& base_dir, const PathCheck& check_file) {
    const Registry& reg = Registry::instance();
    if (!j.is_object()) fail(source, "", "expected a JSON object at the top level, got " + std::string(j.type_name()));
    static const std::vector<std::string> top{"schema", "name", "description", "camera", "lights", "env", "effects", "objects"};
    for (auto it = j.begin(); it != j.end(); ++it)
        if (std::find(top.begin(), top.end(), it.key()) == top.end())
            fail(source, it.key(), "unknown key" + suggestion(it.key(), top) + "; top-level keys are: " + list_text(top));
    if (!j.contains("schema")) fail(source, "schema", "missing (expected \"schema\": " + std::to_string(kPresetSchema) + ")");
    if (!j["schema"].is_number_integer() || j["schema"].get<int64_t>() != kPresetSchema)
        fail(source, "schema", "unsupported schema " + j["schema"].dump() + " (this mesolab reads schema " + std::to_string(kPresetSchema) + ")");

    Scene s;
    s.base_dir = base_dir;
    s.name = fs::path(source).stem().string();
    auto str = [&](const char* k, std::string& out) {
        if (!j.contains(k)) return;
        if (!j[k].is_string()) fail(source, k, "expected a string, got " + j[k].dump());
        out = j[k].get<std::string>();
    };
    str("name", s.name);
    str("description", s.description);
    s.camera = j.contains("camera") ? parse_table(reg.camera(), j["camera"], source, "camera", check_file) : reg.camera().defaults();
    s.env = j.contains("env") ? parse_table(reg.env(), j["env"], source, "env", check_file) : reg.env().defaults();
    s.effects = j.contains("effects") ? parse_table(reg.effects(), j["effects"], source, "effects", check_file) : reg.effects().defaults();
    if (j.contains("lights")) {
        if (!j["lights"].is_array()) fail(source, "lights", "expected an array of lights, got " + j["lights"].dump());
        for (size_t i = 0; i < j["lights"].size(); ++i)
            s.lights.push_back(parse_table(reg.light(), j["lights"][i], source, "lights[" + std::to_string(i) + "]", check_file));
    } else {
        s.lights.push_back(reg.light().defaults());
    }
    if (!j.contains("objects")) fail(source, "objects", "missing (expected an array of objects, each with \"geometry\" and \"material\")");
    if (!j["objects"].is_array() || j["objects"].empty()) fail(source, "objects", "expected a non-empty array of objects, got " + j["objects"].dump());
    for (size_t i = 0; i < j["objects"].size(); ++i) {
        const json& o = j["objects"][i];
        const std::string path = "objects[" + std::to_string(i) + "]";
        if (!o.is_object()) fail(source, path, "expected an object with \"geometry\" and \"material\", got " + o.dump());
        static const std::vector<std::string> okeys{"name", "geometry", "material"};
        for (auto it = o.begin(); it != o.end(); ++it)
            if (std::find(okeys.begin(), okeys.end(), it.key()) == okeys.end())
                fail(source, path + "." + it.key(), "unknown key" + suggestion(it.key(), okeys) + "; object keys are: " + list_text(okeys));
        SceneObject obj;
        obj.name = "object" + std::to_string(i);
        if (o.contains("name")) {
            if (!o["name"].is_string()) fail(source, path + ".name", "expected a string, got " + o["name"].dump());
            obj.name = o["name"].get<std::string>();
        }
        obj.geometry = o.contains("geometry") ? parse_table(reg.geometry(), o["geometry"], source, path + ".geometry", check_file) : reg.geometry().defaults();
        if (!o.contains("material") || !o["material"].is_object())
            fail(source, path + ".material", "missing (expected {\"technique\": one of " + list_text(reg.technique_names()) + ", ...parameters})");
        const json& m = o["material"];
        if (!m.contains("technique") || !m["technique"].is_string())
            fail(source, path + ".material.technique", "missing (expected one of " + list_text(reg.technique_names()) + ")");
        obj.technique = m["technique"].get<std::string>();
        const Technique* t = reg.technique(obj.technique);
        if (!t)
            fail(source, path + ".material.technique", "unknown technique '" + obj.technique + "'" + suggestion(obj.technique, reg.technique_names()) +
                                                           "; known techniques: " + list_text(reg.technique_names()));
        obj.material = parse_table(t->params(), m, source, path + ".material", check_file, {"technique"});
        s.objects.push_back(std::move(obj));
    }
    return s;
}

json preset_json_from_text(const std::string& text, const std::string& source) {
    try {
        return json::parse(text);
    } catch (const json::parse_error& e) {
        // Turn the byte offset into line:column.
        size_t line = 1, col = 1;
        for (size_t i = 0; i + 1 < e.byte && i < text.size(); ++i) {
            if (text[i] == '\n') { ++line; col = 1; } else ++col;
        }
        std::string what = e.what();
        const auto p = what.find("parse error");
        if (p != std::string::npos) what = what.substr(p);
        throw InputError(source + ": line " + std::to_string(line) + ", column " + std::to_string(col) + ": invalid JSON (" + what + ")");
    }
}

Scene load_preset(const std::string& path) {
    std::error_code ec;
    if (!fs::exists(path, ec)) throw InputError(path + ": no such file");
    if (is_pack(path)) return load_pack(path);
    if (fs::is_directory(path, ec))
        throw InputError(path + ": is a folder without " + std::string(kPackScene) + ", expected a preset file (.json) or a pack (.zip, or a folder holding " +
                         kPackScene + ")");
    std::ifstream in(path, std::ios::binary);
    if (!in) throw InputError(path + ": cannot open for reading");
    std::stringstream ss;
    ss << in.rdbuf();
    const json j = preset_json_from_text(ss.str(), path);
    const fs::path abs = fs::absolute(path).lexically_normal();
    return scene_from_json(j, path, abs.parent_path().string());
}

// [SECTION] Scene -> JSON
json scene_to_json(const Scene& s) {
    json j;
    j["schema"] = s.schema;
    j["name"] = s.name;
    if (!s.description.empty()) j["description"] = s.description;
    j["camera"] = table_to_json(s.camera);
    j["lights"] = json::array();
    for (const auto& l : s.lights) j["lights"].push_back(table_to_json(l));
    j["env"] = table_to_json(s.env);
    j["effects"] = table_to_json(s.effects);
    j["objects"] = json::array();
    for (const auto& o : s.objects) {
        json jo;
        jo["name"] = o.name;
        jo["geometry"] = table_to_json(o.geometry);
        json m;
        m["technique"] = o.technique;
        const json params = table_to_json(o.material);
        for (auto it = params.begin(); it != params.end(); ++it) m[it.key()] = it.value();
        jo["material"] = std::move(m);
        j["objects"].push_back(std::move(jo));
    }
    return j;
}

std::string scene_to_text(const Scene& s) { return scene_to_json(s).dump(2) + "\n"; }

void save_preset(const Scene& s, const std::string& path) {
    // Rebase relative paths from the scene's folder to the new file's folder.
    Scene out = s;
    const fs::path dir = fs::absolute(path).lexically_normal().parent_path();
    auto rebase = [&](ParamTable& t) {
        for (const auto& d : t.group().decls()) {
            if (!d.is_file(t.get(d.name))) continue;
            const std::string& p = t.get_string(d.name);
            fs::path full = s.resolve(p);
            t.set(d.name, fs::path(full).lexically_proximate(dir).string());
        }
    };
    rebase(out.env);
    for (auto& l : out.lights) rebase(l);
    for (auto& o : out.objects) { rebase(o.geometry); rebase(o.material); }
    write_text_atomic(path, scene_to_text(out));
}

// [SECTION] Public keys (--set)
void apply_set(Scene& s, const std::string& assignment) {
    const auto eq = assignment.find('=');
    if (eq == std::string::npos || eq == 0) throw InputError("--set expects KEY=VALUE (e.g. camera.distance=4), got '" + assignment + "'");
    apply_set(s, assignment.substr(0, eq), assignment.substr(eq + 1));
}

void apply_set(Scene& s, const std::string& key, const std::string& value) {
    Target t = resolve_key(s, key);
    const ParamGroup& g = t.tables.front()->group();
    const ParamDecl* d = g.find(t.param);
    if (!d) throw InputError("--set " + key + ": unknown key" + suggestion(key, public_keys(s)) + "; " + g.name() + " parameters are: " + list_text(g.names()));
    Value v = value_from_text(*d, value, "--set " + key);
    if (d->is_file(v)) {
        // A path typed on the command line is relative to the working folder.
        const fs::path abs = fs::absolute(value).lexically_normal();
        if (!fs::is_regular_file(abs)) throw InputError("--set " + key + ": file '" + value + "' not found");
        v = s.base_dir.empty() ? abs.string() : abs.lexically_proximate(s.base_dir).string();
    }
    for (ParamTable* table : t.tables) table->set(d->name, v, "--set " + key);
}

void apply_sets(Scene& s, const std::vector<std::string>& assignments) {
    for (const auto& a : assignments) apply_set(s, a);
    for (const auto& a : assignments) check_set_used(s, a.substr(0, a.find('=')));
}

void check_set_used(const Scene& s, const std::string& key) {
    Scene copy = s;
    Target t = resolve_key(copy, key);
    const ParamGroup& g = t.tables.front()->group();
    const ParamDecl* d = g.find(t.param);
    if (!d) return;  // apply_set has named it
    for (const ParamTable* table : t.tables)
        if (table->is_used(*d)) return;
    const ParamTable& first = *t.tables.front();
    throw InputError("--set " + key + ": not used when " + g.name() + "." + d->used_when_key + " is '" +
                     value_to_text(*g.find(d->used_when_key), first.get(d->used_when_key)) + "' (it applies to " + d->used_when_key + " = " +
                     list_text(d->used_when_values) + "); set " + g.name() + "." + d->used_when_key + " too, or leave it out");
}

const ParamDecl& decl_of(const Scene& s, const std::string& key) {
    Scene copy = s;
    Target t = resolve_key(copy, key);
    const ParamDecl* d = t.tables.front()->group().find(t.param);
    if (!d) throw InputError(key + ": unknown key" + suggestion(key, public_keys(s)));
    return *d;
}

std::string get_public(const Scene& s, const std::string& key) {
    Scene copy = s;
    Target t = resolve_key(copy, key);
    const ParamDecl& d = decl_of(s, key);
    return value_to_text(d, t.tables.front()->get(d.name));
}

Value get_public_value(const Scene& s, const std::string& key) {
    Scene copy = s;
    Target t = resolve_key(copy, key);
    const ParamDecl& d = decl_of(s, key);
    return t.tables.front()->get(d.name);
}

std::vector<std::string> public_keys(const Scene& s) {
    std::vector<std::string> r;
    for (const ParamGroup* g : Registry::instance().groups())
        for (const auto& d : g->decls()) r.push_back(g->name() + "." + d.name);
    for (size_t i = 0; i < s.lights.size(); ++i)
        for (const auto& d : s.lights[i].group().decls()) r.push_back("lights." + std::to_string(i) + "." + d.name);
    for (size_t i = 0; i < s.objects.size(); ++i) {
        for (const auto& d : s.objects[i].geometry.group().decls()) r.push_back("objects." + std::to_string(i) + ".geometry." + d.name);
        for (const auto& d : s.objects[i].material.group().decls()) r.push_back("objects." + std::to_string(i) + ".material." + d.name);
    }
    return r;
}
}  // namespace mesolab
