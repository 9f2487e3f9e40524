#include "core/stage.h"
#include "core/hash.h"
#include "core/error.h"
#include "core/scene.h"
#include "core/strings.h"

#include <algorithm>

namespace mesolab {
namespace {

void append_table(std::string& out, const Scene& s, const ParamTable& t, const std::string& param, FileIdentity files) {
    for (const auto& d : t.group().decls()) {
        if (param != "*" && d.name != param) continue;
        out += value_canonical(d, t.get(d.name), s.base_dir, files);
        out += ';';
    }
}
}  // namespace

const char* to_string(StageStatus s) {
    switch (s) {
        case StageStatus::Ran: return "ran";
        case StageStatus::Cached: return "cached";
        case StageStatus::Skipped: return "skipped";
        case StageStatus::Failed: return "failed";
        case StageStatus::Cancelled: return "cancelled";
        case StageStatus::Stored: return "cached (disk)";
    }
    return "?";
}

std::string StageRun::label(const Scene& s) const {
    if (object < 0) return name;
    const std::string o = size_t(object) < s.objects.size() && !s.objects[size_t(object)].name.empty() ? s.objects[size_t(object)].name
                                                                                                      : "objects." + std::to_string(object);
    return name + " [" + o + "]";
}

// [SECTION] Evaluation
const std::any* Evaluation::find(const std::string& stage, int object) const {
    auto it = results.find(stage);
    if (it == results.end()) return nullptr;
    if (it->second.scene.has_value() || it->second.objects.empty()) return &it->second.scene;
    if (object < 0 || size_t(object) >= it->second.objects.size()) return nullptr;
    return &it->second.objects[size_t(object)];
}

StageName StageName::of(const StageDecl& d) {
    StageName n;
    n.name_ = d.name;
    return n;
}

const StageRun* Evaluation::run(const StageName& stage, int object) const {
    for (const auto& r : runs)
        if (r.name == stage.str() && (object < 0 || r.object == object)) return &r;
    return nullptr;
}

std::vector<const StageRun*> Evaluation::runs_of(const StageName& stage) const {
    std::vector<const StageRun*> r;
    for (const auto& x : runs)
        if (x.name == stage.str()) r.push_back(&x);
    return r;
}

void StageContext::progress(double fraction) const {
    if (cancelled()) throw Cancelled();
    if (progress_) progress_(name_, fraction);
}

// [SECTION] Fingerprints of parameter values
std::string param_fingerprint(const Scene& s, const std::string& pattern, int object, FileIdentity files) {
    const auto dot = pattern.find('.');
    const std::string group = pattern.substr(0, dot), param = dot == std::string::npos ? "*" : pattern.substr(dot + 1);
    std::string out = pattern + "{";
    if (group == "camera") append_table(out, s, s.camera, param, files);
    else if (group == "env") append_table(out, s, s.env, param, files);
    else if (group == "effects") append_table(out, s, s.effects, param, files);
    else if (group == "light") {
        out.append(std::to_string(s.lights.size())).append(":");
        for (const auto& l : s.lights) append_table(out, s, l, param, files);
    } else if (group == "geometry") {
        if (object >= 0) {
            append_table(out, s, s.objects.at(size_t(object)).geometry, param, files);
        } else {
            out.append(std::to_string(s.objects.size())).append(":");
            for (const auto& o : s.objects) append_table(out, s, o.geometry, param, files);
        }
    } else if (object >= 0) {
        // A technique, for one object: its material when it uses that technique.
        const SceneObject& o = s.objects.at(size_t(object));
        if (o.technique == group) append_table(out, s, o.material, param, files);
        else out += "-";
    } else {
        // A technique: every object using it, in order (the object index is part of the text).
        for (size_t i = 0; i < s.objects.size(); ++i)
            if (s.objects[i].technique == group) {
                out.append("#").append(std::to_string(i)).append(":");
                append_table(out, s, s.objects[i].material, param, files);
            }
    }
    return out + "}";
}

// [SECTION] Declarations
void StageGraph::add_decl(StageDecl d) {
    if (find(d.name)) throw std::logic_error("stage declared twice: " + d.name);
    for (const auto& in : d.inputs)
        if (!find(in)) throw std::logic_error("stage " + d.name + " reads unknown stage " + in.str() + " (declare upstream stages first)");
    if (d.scope == StageScope::Scene && d.applies) throw std::logic_error("stage " + d.name + ": `applies` is for object stages (use `when`)");
    if (d.scope == StageScope::Object && d.when) throw std::logic_error("stage " + d.name + ": `when` is for scene stages (use `applies`)");
    if (d.scope == StageScope::Object)
        for (const auto& in : d.inputs)
            if (find(in)->scope == StageScope::Object && !find(in)->technique.empty() && find(in)->technique != d.technique)
                throw std::logic_error("stage " + d.name + " reads " + in.str() + ", an object stage of another technique");
    stages_.push_back(std::move(d));
}

const StageDecl* StageGraph::find(const std::string& name) const {
    for (const auto& s : stages_)
        if (s.name == name) return &s;
    return nullptr;
}

const StageDecl& StageGraph::at(const std::string& name) const {
    const StageDecl* d = find(name);
    if (!d) throw std::logic_error("unknown stage " + name);
    return *d;
}

StageDecl& StageGraph::at_mut(const std::string& name) {
    for (StageDecl& d : stages_)
        if (d.name == name) return d;
    throw std::logic_error("unknown stage " + name);
}

bool StageGraph::covers(const Scene& scene, const StageDecl& d, int object) const {
    if (d.scope == StageScope::Scene) return true;
    if (object < 0 || size_t(object) >= scene.objects.size()) return false;
    const SceneObject& o = scene.objects[size_t(object)];
    if (!d.technique.empty() && o.technique != d.technique) return false;
    if (d.methods.empty()) return true;
    // Read outside any stage's read contract: which objects a stage computes for is the graph's
    // business, not the stage's input.
    ParamReadScope quiet(nullptr);
    return std::find(d.methods.begin(), d.methods.end(), o.material.get_string("method")) != d.methods.end();
}

std::vector<int> StageGraph::subjects(const Scene& scene, const StageDecl& d) const {
    if (d.scope == StageScope::Scene) return {-1};
    std::vector<int> r;
    for (size_t i = 0; i < scene.objects.size(); ++i)
        if (covers(scene, d, int(i))) r.push_back(int(i));
    return r;
}

void StageGraph::for_each_input(const Scene& scene, const StageDecl& d, int object, const std::function<void(const StageDecl&, int)>& f) const {
    for (const auto& in : d.inputs) {
        const StageDecl& u = at(in);
        if (u.scope == StageScope::Scene) f(u, -1);
        else if (object >= 0) f(u, object);
        else
            for (int o : subjects(scene, u)) f(u, o);
    }
}

bool StageGraph::enabled(const Scene& scene, const StageDecl& d, int object, std::string* reason) const {
    if (d.scope == StageScope::Object) {
        if (!covers(scene, d, object)) {
            if (reason) {
                const SceneObject& o = scene.objects[size_t(object)];
                *reason = o.technique != d.technique ? "the object does not use " + d.technique
                                                     : "the object's " + d.technique + ".method is not " + join(d.methods, " or ");
            }
            return false;
        }
        if (d.applies && !d.applies(scene, scene.objects[size_t(object)])) {
            if (reason) *reason = "not needed unless " + d.when_text;
            return false;
        }
    } else if (d.when && !d.when(scene)) {
        if (reason) *reason = "not needed unless " + d.when_text;
        return false;
    }
    if (d.effects.empty()) return true;
    for (const auto& e : d.effects)
        if (scene.effects.group().find(e) && scene.effect(e)) return true;
    if (reason) {
        *reason = "no enabled effect needs it (";
        for (size_t i = 0; i < d.effects.size(); ++i) *reason += (i ? ", effects." : "effects.") + d.effects[i];
        *reason += d.effects.size() == 1 ? " is off)" : " are off)";
    }
    return false;
}

std::vector<std::string> StageGraph::params_upstream(const StageDecl& d) const {
    std::vector<std::string> out = d.params;
    for (const StageName& in : d.inputs)
        for (std::string& p : params_upstream(at(in)))
            if (std::find(out.begin(), out.end(), p) == out.end()) out.push_back(std::move(p));
    return out;
}

// [SECTION] Fingerprints and keys
uint64_t StageGraph::hash(std::string_view s) {
    const uint64_t h = fnv1a(s);
    return h == 0 ? 1 : h;
}

const std::string& StageGraph::fingerprint(const Scene& scene, const StageDecl& d, int object, Memo& memo, FileIdentity files) const {
    const int subject = d.scope == StageScope::Object ? object : -1;
    const std::string memo_key = d.name + "#" + std::to_string(subject);
    if (auto it = memo.find(memo_key); it != memo.end()) return it->second;
    std::string fp;
    if (enabled(scene, d, subject)) {
        fp = d.name;
        fp += d.scope == StageScope::Object ? "(object)" : "(scene)";
        for (const auto& p : d.params) fp += param_fingerprint(scene, p, subject, files);
        for (const auto& in : d.inputs) {
            const StageDecl& u = at(in);
            fp += "<";
            if (u.scope == StageScope::Object && subject < 0) {
                // A scene stage reading an object stage: every object's fingerprint.
                for (int o : subjects(scene, u)) fp.append("#").append(std::to_string(o)).append(":").append(fingerprint(scene, u, o, memo, files)).append(";");
            } else {
                fp += fingerprint(scene, u, subject, memo, files);
            }
            fp += ">";
        }
    }
    return memo[memo_key] = std::move(fp);
}

std::string StageGraph::fingerprint(const Scene& scene, const std::string& stage, int object) const {
    const StageDecl& d = at(stage);
    if (d.scope == StageScope::Object && object < 0) {
        // The first object the stage computes for (convenient with one object).
        const std::vector<int> objs = subjects(scene, d);
        if (objs.empty()) return {};
        object = objs.front();
    }
    Memo memo;
    return fingerprint(scene, d, object, memo);
}

uint64_t StageGraph::key(const Scene& scene, const std::string& stage, int object) const {
    const std::string fp = fingerprint(scene, stage, object);
    return fp.empty() ? 0 : hash(fp);
}
}  // namespace mesolab
