#include "core/technique.h"
#include "core/error.h"
#include "core/read_contract.h"
#include "core/scene_stages.h"

#include <algorithm>
#include <set>

namespace mesolab {

namespace {
std::vector<std::function<std::unique_ptr<Technique>()>>& extra_techniques() {
    static std::vector<std::function<std::unique_ptr<Technique>()>> v;
    return v;
}
std::vector<std::function<std::unique_ptr<Method>()>>& extra_methods() {
    static std::vector<std::function<std::unique_ptr<Method>()>> v;
    return v;
}
bool g_registry_built = false;
}  // namespace

void register_extra_method(std::function<std::unique_ptr<Method>()> make) {
    if (g_registry_built) throw std::logic_error("register_extra_method: the registry is already built");
    extra_methods().push_back(std::move(make));
}

void register_extra_technique(std::function<std::unique_ptr<Technique>()> make) {
    if (g_registry_built) throw std::logic_error("register_extra_technique: the registry is already built");
    extra_techniques().push_back(std::move(make));
}

// [SECTION] Scene-level declarations (camera, light, env, geometry, effects)
Registry::Registry()
    : camera_("camera", "Camera"), light_("light", "Light"), env_("env", "Environment"), geometry_("geometry", "Geometry"), effects_("effects", "Effects") {
    camera_.add_enum("mode", {"orbit", "texture"}, "orbit")
        .doc("orbit: perspective view around camera.target (drag to orbit, wheel to zoom, right-drag to pan). "
             "texture: the object's texture (u,v) space 1:1, one pixel per texel, seen from direction camera.orbit");
    camera_.add_float("distance", 3.0).range(1e-3, 1e6).in("scene units").log().doc("Distance from the eye to camera.target");
    camera_.add_vec2("orbit", {60.0, -90.0}).range(-360.0, 360.0).in("degrees")
        .doc("THETA,PHI of the eye seen from the target: theta from +z, phi from +x towards +y. In texture mode, the view direction");
    camera_.add_vec3("target", {0.0, 0.0, 0.0}).range(-1e6, 1e6).in("scene units").doc("Point the orbit camera looks at");
    camera_.add_float("fov", 40.0).range(1.0, 150.0).in("degrees").doc("Vertical field of view of the orbit camera");

    light_.add_enum("type", {"directional", "point"}, "directional").doc("Directional (sun-like) or point light");
    light_.add_vec2("direction", {45.0, 30.0}).range(-360.0, 360.0).in("degrees").used_when("type", {"directional"})
        .doc("THETA,PHI towards the light: theta from the surface normal / the z axis, phi from +x towards +y");
    light_.add_vec3("position", {2.0, -2.0, 3.0}).range(-1e6, 1e6).in("scene units").used_when("type", {"point"}).doc("Point light position");
    light_.add_float("intensity", 3.0).range(0.0, 1e6).log()
        .doc("Directional: irradiance at normal incidence (W/m^2). Point: radiant intensity (W/sr)");
    light_.add_color("color", {1.0, 1.0, 1.0}).doc("Light colour (linear RGB), multiplies the intensity");

    env_.add_color("color", {0.05, 0.05, 0.06}).doc("Constant environment radiance (linear RGB), used where there is no env.map");
    env_.add_path("map", "").doc("Lat-long environment map (EXR, linear radiance); relative paths are relative to the preset's folder");
    env_.add_float("intensity", 1.0).range(0.0, 1e6).log().doc("Scale of the environment radiance");

    geometry_.add_enum("type", {"sphere", "plane", "torus", "cylinder", "teapot", "mesh"}, "sphere")
        .doc("Procedural shape (teapot: the Utah teapot, Newell's 32 Bezier patches) or a mesh file (geometry.path)");
    geometry_.add_path("path", "").used_when("type", {"mesh"})
        .doc("Mesh file read with OpenMesh (OBJ, OFF, PLY, STL, OM); relative to the preset's folder");
    geometry_.add_int("resolution", 64).range(3, 4096).used_when("type", {"sphere", "plane", "torus", "cylinder", "teapot"})
        .more_accurate(Accuracy::Higher, int64_t(1024)).doc("Tessellation: segments around u (teapot: resolution/8 per side of each of its 32 patches)");
    geometry_.add_float("minor_ratio", 0.35).range(0.01, 0.99).used_when("type", {"torus"})
        .doc("Torus tube radius relative to the major radius");
    geometry_.add_float("scale", 1.0).range(1e-6, 1e6).log()
        .doc("Uniform scale (object -> world); translucency reads it: an object's size in mm changes how light travels inside");
    geometry_.add_vec3("position", {0.0, 0.0, 0.0}).range(-1e6, 1e6).in("scene units").doc("Translation (object -> world)");

    scene_effects_.push_back({"environment", true, "Environment light on surfaces (diffuse irradiance from env.color / env.map)"});

    declare_scene_stages(stages_);
    register_core_techniques(*this);
    for (const auto& make : extra_techniques()) add(make());
    register_core_methods(*this);
    for (const auto& make : extra_methods()) add_method(make());
    finish();
    g_registry_built = true;
}

Registry& Registry::instance() {
    static Registry r;
    return r;
}

void Registry::add(std::unique_ptr<Technique> t) {
    if (technique(t->name())) throw std::logic_error("technique registered twice: " + t->name());
    for (const auto& a : t->aovs())
        for (const auto& c : common_aovs())
            if (a.name == c.name) throw std::logic_error("technique " + t->name() + " declares the AOV " + a.name + ", which every technique writes");
    for (const auto& st : t->frame_steps())
        if (st.name.rfind(t->name() + ".", 0) != 0) throw std::logic_error("frame step " + st.name + " must be named " + t->name() + ".<step>");
    t->declare_stages(stages_);
    techniques_.push_back(std::move(t));
}

void Registry::add_method(std::unique_ptr<Method> m) {
    Technique* t = nullptr;
    for (const auto& x : techniques_)
        if (x->name() == m->technique()) t = x.get();
    if (!t) throw std::logic_error("method " + m->name() + ": no technique " + m->technique());
    if (t->paper_method_.empty()) throw std::logic_error("method " + m->name() + ": technique " + t->name() + " names no paper method");
    for (const std::string& n : t->method_names())
        if (n == m->name()) throw std::logic_error("method " + t->name() + "/" + m->name() + " registered twice");
    const size_t before = t->params_.decls().size();
    m->declare_params(t->params_);
    for (size_t i = before; i < t->params_.decls().size(); ++i) {
        const ParamDecl& d = t->params_.decls()[i];
        if (d.used_when_key != "method" || d.used_when_values != std::vector<std::string>{m->name()})
            throw std::logic_error("method " + t->name() + "/" + m->name() + " declares " + t->name() + "." + d.name +
                                   " without .used_when(\"method\", {\"" + m->name() + "\"})");
    }
    m->declare_stages(stages_);
    t->methods_.push_back(m.get());
    methods_.push_back(std::move(m));
}

void Registry::declare_methods() {
    for (const auto& t : techniques_) {
        if (t->paper_method_.empty()) continue;
        std::string doc = "How the effect is computed: " + t->paper_method_ + " (the paper's, " + t->title() + ")";
        for (const Method* m : t->methods_) doc += "; " + m->name() + " (" + m->title() + ")";
        t->params_.add_enum("method", t->method_names(), t->paper_method_).doc(doc + ". One truth serves them all");
        t->params_.section("Method", {"method"}, true, /*first=*/true);
        if (t->methods_.empty()) continue;
        // Which methods each of the technique's object stages serves: those whose frame stages
        // reach it upstream. A stage no method's frame reaches (an export's) serves all, and so does
        // every stage the truth reads (one truth serves every method, whichever method also reads it).
        const auto reach = [&](const std::vector<StageName>& roots) {
            std::set<std::string> seen;
            std::vector<std::string> todo(roots.begin(), roots.end());
            while (!todo.empty()) {
                const std::string n = todo.back();
                todo.pop_back();
                if (!seen.insert(n).second) continue;
                for (const StageName& in : stages_.at(n).inputs) todo.push_back(in.str());
            }
            return seen;
        };
        std::vector<std::pair<std::string, std::set<std::string>>> reached{{t->paper_method_, reach(t->frame_stages())}};
        for (const Method* m : t->methods_) reached.emplace_back(m->name(), reach(m->frame_stages()));
        std::set<std::string> truth;
        if (const auto decl = t->truth()) {
            std::vector<StageName> roots(decl->stages.begin(), decl->stages.end());
            truth = reach(roots);
        }
        for (const StageDecl& d : stages_.stages()) {
            if (d.scope != StageScope::Object || d.technique != t->name() || truth.count(d.name)) continue;
            std::vector<std::string> serves;
            for (const auto& [name, set] : reached)
                if (set.count(d.name)) serves.push_back(name);
            if (serves.empty() || serves.size() == reached.size()) continue;
            stages_.at_mut(d.name).methods = serves;
        }
    }
}

void Registry::finish() {
    declare_methods();
    // The effects group is the union of the scene's and the techniques' effect switches.
    std::vector<EffectDecl> all = scene_effects_;
    for (const auto& t : techniques_)
        for (const auto& e : t->effects())
            if (std::none_of(all.begin(), all.end(), [&](const EffectDecl& x) { return x.name == e.name; })) all.push_back(e);
    for (const auto& e : all) effects_.add_bool(e.name, e.def).doc(e.help);
    check_declarations();
    derive_costs();
}

void Registry::check_declarations() const {
    const auto find_group = [this](std::string_view name) { return group(std::string(name)); };
    const auto is_key = [&](const std::string& name) {
        const auto dot = name.find('.');
        const ParamGroup* g = dot == std::string::npos ? nullptr : group(name.substr(0, dot));
        return g && g->find(name.substr(dot + 1));
    };
    for (const StageDecl& d : stages_.stages()) {
        check_key_patterns("stage " + d.name, d.params, find_group);
        for (const std::string& e : d.effects)
            if (!effects_.find(e)) throw std::logic_error("stage " + d.name + " needs effect " + e + ", which nothing declares");
        if (is_key(d.name)) throw std::logic_error("stage " + d.name + " has the name of a key: a name is either a stage or a key");
    }
    for (const auto& t : techniques_) {
        for (const FrameStepDecl& f : t->frame_steps()) {
            check_key_patterns("frame step " + f.name, f.params, find_group);
            if (is_key(f.name)) throw std::logic_error("frame step " + f.name + " has the name of a key: a name is either a step or a key");
        }
        if (const std::optional<TruthDecl> truth = t->truth()) {
            check_key_patterns("the truth of " + t->name(), truth->params, find_group);
            for (const StageName& n : truth->stages)
                if (!stages_.find(n)) throw std::logic_error("the truth of " + t->name() + " reads unknown stage " + n.str());
        }
    }
}

// A key costs a recompute when a stage declares it (exactly or as "group.*"), an effect when a
// stage needs it; every other key only a redraw.
void Registry::derive_costs() {
    std::set<std::string> read;
    for (const StageDecl& d : stages_.stages()) {
        for (const std::string& p : d.params) read.insert(p);
        for (const std::string& e : d.effects) read.insert("effects." + e);
    }
    // A method decides which stages run for its objects.
    for (const auto& t : techniques_)
        if (!t->paper_method_.empty()) read.insert(t->name() + ".method");
    std::vector<ParamGroup*> groups{&camera_, &light_, &env_, &geometry_, &effects_};
    for (const auto& t : techniques_) groups.push_back(&t->params_);
    for (ParamGroup* g : groups)
        for (const std::string& name : g->names())
            g->set_cost(name, read.count(g->name() + "." + name) || read.count(g->name() + ".*") ? Cost::Recompute : Cost::Redraw);
}

// [SECTION] Look-ups
const Technique* Registry::technique(const std::string& name) const {
    for (const auto& t : techniques_)
        if (t->name() == name) return t.get();
    return nullptr;
}
std::vector<const Technique*> Registry::techniques() const {
    std::vector<const Technique*> r;
    for (const auto& t : techniques_) r.push_back(t.get());
    return r;
}
std::vector<std::string> Registry::technique_names() const {
    std::vector<std::string> r;
    for (const auto& t : techniques_) r.push_back(t->name());
    return r;
}
const ParamGroup* Registry::group(const std::string& name) const {
    for (const ParamGroup* g : groups())
        if (g->name() == name) return g;
    return nullptr;
}
std::vector<const ParamGroup*> Registry::groups() const {
    std::vector<const ParamGroup*> r{&camera_, &light_, &env_, &geometry_, &effects_};
    for (const auto& t : techniques_) r.push_back(&t->params());
    return r;
}

std::vector<StageName> Registry::frame_stages(const Scene& s) const {
    std::vector<StageName> r{stages::geometry, stages::env_map, stages::env_irradiance};
    for (const auto& t : techniques_) {
        if (!method_objects(s, *t, nullptr).empty())
            for (auto& st : t->frame_stages()) r.push_back(st);
        for (const Method* m : t->methods())
            if (!method_objects(s, *t, m).empty())
                for (auto& st : m->frame_stages()) r.push_back(st);
    }
    return r;
}

// [SECTION] Methods
std::vector<std::string> Technique::method_names() const {
    if (paper_method_.empty()) return {};
    std::vector<std::string> r{paper_method_};
    for (const Method* m : methods_) r.push_back(m->name());
    return r;
}

const Method* Technique::method_of(const SceneObject& o) const {
    if (methods_.empty() || o.technique != name()) return nullptr;
    const std::string& v = o.material.get_string("method");
    for (const Method* m : methods_)
        if (m->name() == v) return m;
    return nullptr;
}

FrameAgreement Technique::agreement_for(const SceneObject& o) const {
    if (const Method* m = method_of(o); m && !m->shares_paper_pipeline()) return m->agreement();
    return agreement();
}

std::vector<int> method_objects(const Scene& s, const Technique& t, const Method* m) {
    std::vector<int> r;
    if (m && m->shares_paper_pipeline()) return r;
    for (size_t i = 0; i < s.objects.size(); ++i) {
        if (s.objects[i].technique != t.name()) continue;
        const Method* u = t.method_of(s.objects[i]);
        if (u == m || (!m && u && u->shares_paper_pipeline())) r.push_back(int(i));
    }
    return r;
}

const std::vector<AovDecl>& common_aovs() {
    static const std::vector<AovDecl> r{{"radiance", 3, "Outgoing radiance towards the eye (linear RGB)"},
                                        {"normal", 3, "Shading normal, world space (texture mode: tangent space)"}};
    return r;
}

std::vector<AovDecl> Technique::outputs() const {
    std::vector<AovDecl> r = common_aovs();
    r.insert(r.end(), aovs_.begin(), aovs_.end());
    return r;
}

std::vector<AovDecl> Registry::aovs(const Scene& s) const {
    std::vector<AovDecl> r = common_aovs();
    for (const auto& t : techniques_) {
        if (!s.uses_technique(t->name())) continue;
        for (const auto& a : t->aovs())
            if (std::none_of(r.begin(), r.end(), [&](const AovDecl& x) { return x.name == a.name; })) r.push_back(a);
    }
    return r;
}

std::vector<BenchTable> bench_tables() {
    std::vector<BenchTable> r;
    for (const Technique* t : Registry::instance().techniques())
        for (auto& b : t->bench_tables()) r.push_back(std::move(b));
    r.push_back(truth_bench_table());
    return r;
}
}  // namespace mesolab
