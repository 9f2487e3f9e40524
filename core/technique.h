#pragma once
// [SECTION] Techniques and the registry.
// A technique (basic, microgeom, bumpsynth, translucency, cloth) declares its parameters, the
// effect switches it adds, its AOVs and its stages, and shades the pixels of its objects on the
// CPU. Its GPU pass lives in gpu/<technique>, its panel in panels/<technique>. Techniques are
// listed once, in the top-level CMakeLists.txt (MESOLAB_TECHNIQUES); each layer generates a
// registration call per technique, so the app never names a technique.
#include "core/bench.h"
#include "core/mesh.h"
#include "core/param.h"
#include "core/stage.h"
#include "core/truth/truth.h"
#include <any>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace mesolab {

struct ShadeContext;      // core/render.h
struct FrameStepContext;  // core/render.h

struct EffectDecl {
    std::string name;  // public key "effects.<name>"
    bool def = true;
    std::string help;
};

struct AovDecl {
    std::string name;  // "radiance", "normal", "shadow", ...
    int channels = 3;
    std::string help;
};

// [SECTION] Frame steps
// Offscreen work a technique's frame needs before its objects are shaded, with its own render
// targets or compute dispatches on the GPU and its CPU twin (e.g. an illumination map in atlas
// space, its filtering, a product with precomputed factors). Each step is timed as its own row
// (the Timings panel, `mesolab bench`, the capture sidecar) on the CPU and the GPU alike. Its
// declared inputs decide when its result can be reused from the previous frame: the public keys
// it reads ("light.*", "camera.*", "env.*", a technique's keys) and the stages whose results it
// reads; a frame whose inputs have the same fingerprint reuses the step's output (reported
// cached). One scheduler runs them for both backends (FrameStepScheduler, core/render.h).
//
// A step is declared once, like a stage, by a typed handle (FrameStep, core/stage.h: its name and
// the type of its CPU output) in its technique's stages.h; the CPU work (FrameStepDecl::run_cpu) and the GPU pass's
// (TechniquePass::frame_steps, gpu/renderer.h) are bound to the handle, and later steps and the
// shading read an output through it (FrameStepContext::step, ShadeContext::step).
struct FrameStepDecl {
    std::string name;                  // from the handle
    std::string help;
    std::vector<std::string> params;   // public keys or "group.*" (scene-wide: every object's)
    std::vector<StageName> stages;     // stage results it reads (every object's, for object stages)
    // The CPU side: reads ctx's inputs, returns the output (std::shared_ptr<const T> in a std::any).
    std::function<std::any(const FrameStepContext&)> run_cpu;
};

// A frame step's declaration, its CPU work returning the handle's output type.
template <class T, class F>
FrameStepDecl frame_step(const FrameStep<T>& step, std::string help, std::vector<std::string> params, std::vector<StageName> stages, F run_cpu) {
    return {std::string(step.name), std::move(help), std::move(params), std::move(stages), [run_cpu](const FrameStepContext& ctx) -> std::any {
                return std::any(std::shared_ptr<const T>(std::make_shared<T>(run_cpu(ctx))));
            }};
}

// A data export of a technique (`mesolab export NAME PRESET -o FILE`), e.g. microgeom's BTF.
struct ExportDecl {
    std::string name;
    std::string help;
    std::string options_help;           // "KEY=VALUE ...": what --option accepts
    std::vector<StageName> stages;      // evaluated before run
    // Writes `path` (atomically) for scene object `object`; unknown or bad options are
    // InputErrors naming them. Returns a one-paragraph summary for the terminal.
    std::function<std::string(const Scene&, const Evaluation&, int object, const std::map<std::string, std::string>& options,
                              const std::string& path, const ProgressFn& progress)> run;
};

// [SECTION] Technique commands
// A terminal command of a technique, `mesolab TECHNIQUE COMMAND ARGS...` (cloth's `fit` and
// `eval` on measured samples). The app builds the command line from the declaration and names
// no technique.
struct CommandArgDecl {
    std::string name;   // positional: "samples"; option: "-o,--output", "--lobes"
    std::string help;
    bool required = false;
};

struct CommandDecl {
    std::string name;   // "fit"
    std::string help;
    std::vector<CommandArgDecl> positionals, options;
    // Runs the command with the given values: positionals by name, options by their long name
    // without dashes ("output", "lobes"; options not given are absent). Returns the summary for
    // the terminal; InputError for bad input (exit status 2, naming the file, line or option).
    std::function<std::string(const std::map<std::string, std::string>& args, const ProgressFn& progress)> run;
};

// [SECTION] Sweep metrics
// An error metric of a technique for `mesolab sweep --metric NAME`: a distance between what a knob
// setting computes and what the reference setting computes, for a quantity the default metric (the
// radiance RMSE against the reference rendering) sees only indirectly, e.g. bumpsynth's distribution
// of synthesised normals against its NDF. The sweep still times every setting as its frame's stages
// (cold cache) plus the frame; measuring is not timed. Both functions get the scene and the
// evaluation of a rendered frame, so they read the results of the technique's frame_stages().
struct SweepMeasure {
    // The error of one knob setting (its scene and its frame's evaluation).
    std::function<double(const Scene&, const Evaluation&)> error;
    std::string notes;  // Markdown printed under the sweep's table (e.g. the metric's noise floor)
    // Reference levels drawn as horizontal lines in the plot: (legend, value), e.g. noise floors.
    std::vector<std::pair<std::string, double>> levels;
};

struct SweepMetricDecl {
    std::string name;   // the value of --metric: "<technique>.<metric>"
    std::string label;  // column header and plot axis, e.g. "TV distance"
    std::string unit;   // what the values are in ("" when dimensionless)
    std::string help;   // what it measures, one sentence
    // Before any work: InputError when the metric cannot apply to the scene (no object uses the technique).
    std::function<void(const Scene&)> check;
    // The measure against the reference setting, from the reference's scene and frame evaluation.
    std::function<SweepMeasure(const Scene& ref, const Evaluation& ref_eval)> prepare;
};

// [SECTION] CPU and GPU agreement
// How closely the GPU pass reproduces the CPU reference (absolute differences, value by value, in
// each AOV's own units), over the pixels the objects cover (Coverage, core/render.h); the
// background is not counted. Edges are pixels next to another triangle, another object or the
// background: silhouettes, where the two rasterisers' coverage can differ by sub-pixel rounding,
// and triangle edges, where the GPU's derivatives come from helper invocations outside the
// triangle. Off edges every value must be within `interior_max`, but for a fraction
// `interior_outliers` that a technique allows only where a discrete choice (a table entry, a
// shadow texel, a direction) can fall either way between two float evaluations: a few
// arbitrarily wrong pixels inside a face fail. A technique states its tolerances, with the
// reasons, in Technique::agreement(); every preset is held to them (tests/gallery).
// A technique whose discrete choices can be told apart from everything else can instead name the
// AOVs that record them (`choices`: integer indices per channel, e.g. a table entry's (a, b)): off
// edges, a pixel whose indices differ between the two frames by at most 1 each (an input a float
// rounding away from a cell edge, on its other side on the other backend) is a flip, whose values
// are held to nothing; flips may make up at most `interior_flips` of the off-edge pixels, and every
// other off-edge value must be within interior_max (but interior_outliers).
struct FrameAgreement {
    double tight = 1e-3;            // most values agree to this
    double frac_tight = 0.99;       // the fraction of covered values within `tight`
    double loose = 2e-2;            // nearly all values agree to this
    double frac_loose = 0.995;      // the fraction of covered values within `loose`
    double interior_max = 2e-2;     // every value off edges...
    double interior_outliers = 0;   // ...but this fraction of them
    std::vector<std::string> choices;  // AOVs of the technique's discrete choices (none: no flips)
    double interior_flips = 0;      // the fraction of off-edge pixels that may be flips
    std::string why;                // where the differences come from
};

// The AOVs every technique writes: radiance and normal.
const std::vector<AovDecl>& common_aovs();

// [SECTION] Methods
// A technique names an effect; a method is one way of computing it. The paper's method is the
// technique's own (its shade_cpu, frame_stages and GPU pass); every other method is a Method
// registered under the technique and chosen per object by `<technique>.method`. A method reads
// the same physical description (heightfield, NDF, translucent material, fabric) as the paper's
// and the truth, so one truth serves all; it declares its own keys (each used only under it), the
// stages it needs (the technique's stages it reads run only for the objects whose method reads
// them, its own are declared beside them) and shades its objects on the CPU; its GPU pass is
// registered under "<technique>/<method>" (gpu/renderer.h) and follows the technique's
// outputs. Adding one: core/<technique>/<method>.cpp, gpu/<technique>/<method>_pass.cpp (and its
// shader), and TECHNIQUE:METHOD in MESOLAB_METHODS (CMakeLists.txt).
class Method {
public:
    Method(std::string technique, std::string name, std::string title)
        : technique_(std::move(technique)), name_(std::move(name)), title_(std::move(title)) {}
    virtual ~Method() = default;
    const std::string& technique() const { return technique_; }
    const std::string& name() const { return name_; }    // the value of <technique>.method
    const std::string& title() const { return title_; }  // "Parallax occlusion mapping (Tatarchuk 2006)"

    // Its keys, in the technique's group, each .used_when("method", {name()}) (checked at start-up).
    virtual void declare_params(ParamGroup& p) const = 0;
    // Stages of its own (object stages of the technique).
    virtual void declare_stages(StageGraph&) const {}
    // Stages a frame of this method needs (the technique's and its own).
    virtual std::vector<StageName> frame_stages() const { return {}; }
    // CPU shading of the pixels of the objects that use this method (ctx.objects), writing the
    // technique's outputs.
    virtual void shade_cpu(const ShadeContext& ctx) const = 0;
    // How closely its GPU pass follows its CPU shading (FrameAgreement).
    virtual FrameAgreement agreement() const { return {}; }
    // Whether shade_cpu reads GBuffer::uv_dx and uv_dy (as Technique::uses_uv_derivatives).
    virtual bool uses_uv_derivatives() const { return false; }
    // A method that is the paper's pipeline with other data: the technique's stages read
    // `<technique>.method` and build that data (translucency's lensch-burley: the dipole's
    // kernels, factors and blending made from another diffusion profile). Its objects are the
    // paper method's for everything a frame runs (method_objects(s, t, nullptr): its frame stages,
    // frame steps, CPU shading, GPU pass and agreement); it has no shade_cpu or GPU pass of its own
    // (those are never called), and its keys, if any, are read by the technique's stages.
    virtual bool shares_paper_pipeline() const { return false; }

private:
    std::string technique_, name_, title_;
};

class Technique {
public:
    Technique(std::string name, std::string title) : params_(std::move(name), std::move(title)) {}
    virtual ~Technique() = default;

    const std::string& name() const { return params_.name(); }
    const std::string& title() const { return params_.title(); }
    const ParamGroup& params() const { return params_; }
    const std::vector<EffectDecl>& effects() const { return effects_; }
    const std::vector<AovDecl>& aovs() const { return aovs_; }  // beyond radiance and normal
    // Everything the technique writes, declared once: radiance, normal, then aovs(). The GPU
    // pass's fragment outputs are generated from this list (location k = outputs()[k]) and the
    // CPU shading writes through an AovWriter made from it (core/render.h).
    std::vector<AovDecl> outputs() const;

    virtual void declare_stages(StageGraph&) const {}
    // Stages a frame of this technique needs (their results reach shade_cpu and the GPU pass).
    virtual std::vector<StageName> frame_stages() const { return {}; }
    // CPU shading of the pixels covered by this technique's objects.
    virtual void shade_cpu(const ShadeContext& ctx) const = 0;
    // Offscreen work before the frame (see FrameStepDecl), in order, with its CPU side; the GPU
    // pass implements each step too (gpu/renderer.h TechniquePass::frame_steps).
    virtual std::vector<FrameStepDecl> frame_steps() const { return {}; }
    // Texture-space resolution for camera.mode=texture when the technique has a native one.
    virtual std::optional<ivec2> texture_size(const Scene&, const Evaluation&) const { return std::nullopt; }
    // Geometry drawn for `object` instead of scene.geometry's tessellation (a displaced level of
    // detail, say), or null for the tessellation. Computed by stages listed in frame_stages().
    virtual std::shared_ptr<const TriMesh> object_mesh(const Scene&, const Evaluation&, int /*object*/) const { return nullptr; }
    // Data exports (mesolab export NAME).
    virtual std::vector<ExportDecl> exports() const { return {}; }
    // Terminal commands (mesolab NAME COMMAND).
    virtual std::vector<CommandDecl> commands() const { return {}; }
    // Timing tables reproducing the paper's (bench NAME).
    virtual std::vector<BenchTable> bench_tables() const { return {}; }
    // Error metrics for `mesolab sweep --metric NAME`, besides the default radiance RMSE.
    virtual std::vector<SweepMetricDecl> sweep_metrics() const { return {}; }
    // How closely its GPU frames follow the CPU reference (see FrameAgreement).
    virtual FrameAgreement agreement() const { return {}; }
    // Whether shade_cpu reads GBuffer::uv_dx and uv_dy (uv's differences across each pixel's
    // 2 x 2 quad, as a fragment shader's dFdxFine / dFdyFine): the CPU path fills them for this
    // technique's objects only (they add about a fifth to the rasterisation).
    virtual bool uses_uv_derivatives() const { return false; }

    // The truth (core/truth/truth.h): what it reads and how it makes the objects it traces, or
    // nothing when the technique has no truth yet.
    virtual std::optional<TruthDecl> truth() const { return std::nullopt; }

    // The paper's method: its value of `<technique>.method` ("" : no method key, e.g. basic).
    const std::string& paper_method() const { return paper_method_; }
    // The registered methods besides the paper's, in registration order.
    const std::vector<const Method*>& methods() const { return methods_; }
    // Every value of `<technique>.method`, the paper's first (empty without a method key).
    std::vector<std::string> method_names() const;
    // The method an object uses: null for the paper's (or a technique without methods).
    const Method* method_of(const SceneObject& o) const;
    // The agreement its GPU frames keep for an object (its method's, or the technique's).
    FrameAgreement agreement_for(const SceneObject& o) const;

protected:
    friend class Registry;  // derives the parameters' costs from the stage graph
    std::string paper_method_;  // set by a technique that has a paper method
    std::vector<const Method*> methods_;  // owned by the registry
    ParamGroup params_;
    std::vector<EffectDecl> effects_;
    std::vector<AovDecl> aovs_;
};

class Registry {
public:
    // The process-wide registry with every technique and the scene-level groups.
    static Registry& instance();

    const Technique* technique(const std::string& name) const;
    std::vector<const Technique*> techniques() const;
    std::vector<std::string> technique_names() const;

    const ParamGroup& camera() const { return camera_; }
    const ParamGroup& light() const { return light_; }
    const ParamGroup& env() const { return env_; }
    const ParamGroup& geometry() const { return geometry_; }
    const ParamGroup& effects() const { return effects_; }
    // Any group by name: a scene group or a technique.
    const ParamGroup* group(const std::string& name) const;
    std::vector<const ParamGroup*> groups() const;

    // The stage declarations (immutable; sessions evaluate them, core/session.h).
    const StageGraph& stages() const { return stages_; }
    // Stages every frame needs (scene.geometry, env.*) plus those of the scene's techniques.
    std::vector<StageName> frame_stages(const Scene& s) const;
    // AOVs of a scene: radiance, normal, then the techniques' own, without duplicates.
    std::vector<AovDecl> aovs(const Scene& s) const;

    // Called by the generated registration code (core/registry.cpp) for each technique.
    void add(std::unique_ptr<Technique> t);
    // ...and for each method (after every technique): declares its keys and stages.
    void add_method(std::unique_ptr<Method> m);

private:
    Registry();
    void finish();
    // Every declared key exists, every effect a stage needs is declared, and no stage or frame
    // step has the name of a key (std::logic_error naming it: the program stops at start-up).
    void check_declarations() const;
    void derive_costs();
    ParamGroup camera_, light_, env_, geometry_, effects_;
    std::vector<EffectDecl> scene_effects_;
    // `<technique>.method` for each technique with a paper method, and which methods each of a
    // technique's object stages serves (StageDecl::methods).
    void declare_methods();
    std::vector<std::unique_ptr<Technique>> techniques_;
    std::vector<std::unique_ptr<Method>> methods_;
    StageGraph stages_;
};

// Generated by CMake: calls register_<technique>(Registry&) for each listed technique.
void register_core_techniques(Registry& r);
// Generated too: register_<technique>_<method>(Registry&) for each entry of MESOLAB_METHODS.
void register_core_methods(Registry& r);
// A method added besides the generated list, before the registry is first used (tests register
// a probe method to show what a new method gets from one registration). std::logic_error once
// the registry exists.
void register_extra_method(std::function<std::unique_ptr<Method>()> make);
// The objects of technique t that use method m (null: the paper's, with those of the methods that
// share its pipeline; such a method itself gets none), in scene order.
std::vector<int> method_objects(const Scene& s, const Technique& t, const Method* m);
// A technique added besides the generated list, before the registry is first used (tests use a
// probe technique to exercise contracts no shipped technique exercises yet). std::logic_error
// once the registry exists.
void register_extra_technique(std::function<std::unique_ptr<Technique>()> make);
}  // namespace mesolab
