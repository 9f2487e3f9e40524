// mesolab preset validate | schema | show, and mesolab info.
#include "app/commands.h"
#include "app/workbench.h"
#include "core/error.h"
#include "core/pack.h"
#include "core/scene.h"
#include "core/technique.h"
#include "gpu/context.h"
#include "gpu/headless.h"
#include "core/renderer.h"
#include "core/strings.h"

#include <OpenImageIO/oiioversion.h>
#include <tbb/version.h>
#include <cstdio>
#include <thread>

namespace mesolab {

// [SECTION] preset validate
int run_preset_validate(const std::vector<std::string>& args) {
    int bad = 0;
    std::vector<std::string> files;
    try {
        files = expand_presets(args);
    } catch (const InputError& e) {
        std::fprintf(stderr, "mesolab: error: %s\n", e.what());
        return 2;
    }
    for (const auto& f : files) {
        try {
            const Scene s = load_preset(f);
            std::printf("ok     %s (%zu object%s)\n", f.c_str(), s.objects.size(), s.objects.size() == 1 ? "" : "s");
        } catch (const InputError& e) {
            std::fprintf(stderr, "mesolab: error: %s\n", e.what());
            ++bad;
        }
    }
    return bad ? 2 : 0;
}

// [SECTION] preset schema
std::vector<const ParamGroup*> schema_groups(const std::string& technique, const std::string& what) {
    const Registry& reg = Registry::instance();
    if (technique.empty()) return reg.groups();
    if (const ParamGroup* g = reg.group(technique)) return {g};
    std::vector<std::string> names;
    for (auto* gg : reg.groups()) names.push_back(gg->name());
    const std::string hint = nearest_key(technique, names);
    throw InputError(what + ": unknown technique or group '" + technique + "'" + (hint.empty() ? "" : " (did you mean '" + hint + "'?)"));
}

int run_preset_schema(const std::string& technique, bool as_json) {
    const std::vector<const ParamGroup*> groups = schema_groups(technique, "preset schema");
    if (as_json) {
        json j;
        j["schema"] = kPresetSchema;
        j["groups"] = json::array();
        for (auto* g : groups) j["groups"].push_back(group_schema(*g));
        std::printf("%s\n", j.dump(2).c_str());
        return 0;
    }
    for (auto* g : groups) {
        std::printf("%s — %s\n", g->name().c_str(), g->title().c_str());
        for (const auto& d : g->decls()) {
            const std::string key = g->name() + "." + d.name;
            const std::string range = describe_range(d);
            std::printf("  %-26s %-6s default %-18s %-22s %-10s %-9s %s\n", key.c_str(), to_string(d.type), value_to_text(d, d.def).c_str(),
                        range.c_str(), d.unit.c_str(), to_string(d.cost), d.help.c_str());
        }
        std::printf("\n");
    }
    return 0;
}

// [SECTION] preset show
int run_preset_show(const std::string& file, const std::vector<std::string>& sets) {
    Scene s = load_preset(file);
    apply_sets(s, sets);
    std::printf("%s", scene_to_text(s).c_str());
    return 0;
}

// [SECTION] preset pack
int run_preset_pack(const std::string& file, const std::vector<std::string>& sets, const std::string& out) {
    Scene s = load_preset(file);
    apply_sets(s, sets);
    const std::vector<std::string> members = write_pack(s, out);
    std::printf("packed %s into %s: %s", file.c_str(), out.c_str(), members.front().c_str());
    if (members.size() > 1) std::printf(" and %zu file%s", members.size() - 1, members.size() == 2 ? "" : "s");
    std::printf("\n");
    return 0;
}

// [SECTION] info
std::vector<std::pair<std::string, std::string>> info_fields() {
    std::vector<std::pair<std::string, std::string>> r;
    r.emplace_back("version", version_string());
    r.emplace_back("cpu threads", std::to_string(std::thread::hardware_concurrency()));
    std::string techniques;
    for (const auto& t : Registry::instance().technique_names()) techniques += (techniques.empty() ? "" : " ") + t;
    r.emplace_back("techniques", techniques);
    gpu::install_headless_renderer();
    r.emplace_back("renderers", join(RendererRegistry::instance().names(), " "));
    try {
        auto ctx = gpu::HeadlessContext::create();
        const auto& i = ctx->info();
        r.emplace_back("gl platform", i.platform);
        r.emplace_back("gl vendor", i.vendor);
        r.emplace_back("gl renderer", i.renderer);
        r.emplace_back("gl version", i.version);
        r.emplace_back("glsl version", i.glsl_version);
    } catch (const std::exception& e) {
        r.emplace_back("gl", std::string("unavailable: ") + e.what());
    }
    r.emplace_back("openimageio", OIIO_VERSION_STRING);
    r.emplace_back("tbb", std::to_string(TBB_VERSION_MAJOR) + "." + std::to_string(TBB_VERSION_MINOR));
    return r;
}

}  // namespace mesolab
