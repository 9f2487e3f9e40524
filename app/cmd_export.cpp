// mesolab export NAME PRESET -o FILE: a technique's data export (Technique::exports).
#include "app/commands.h"
#include "app/workbench.h"
#include "core/error.h"
#include "core/technique.h"

#include <chrono>
#include <cstdio>

namespace mesolab {

std::string export_names() {
    std::string r;
    for (const Technique* t : Registry::instance().techniques())
        for (const auto& e : t->exports()) r += (r.empty() ? "" : ", ") + e.name + " (" + t->name() + ")";
    return r.empty() ? "none" : r;
}

int run_export(const ExportOptions& o) {
    // The export and its technique.
    const Technique* tech = nullptr;
    ExportDecl decl;
    for (const Technique* t : Registry::instance().techniques())
        for (auto& e : t->exports())
            if (e.name == o.name) tech = t, decl = e;
    if (!tech) throw InputError("export: unknown export '" + o.name + "' (known: " + export_names() + ")");

    Scene s = load_preset(o.preset);
    apply_sets(s, o.sets);
    int object = -1;
    for (size_t i = 0; i < s.objects.size() && object < 0; ++i)
        if (s.objects[i].technique == tech->name() && (o.object.empty() || s.objects[i].name == o.object)) object = int(i);
    if (object < 0)
        throw InputError(o.preset + ": " + (o.object.empty() ? "no object uses technique " + tech->name() : "no object named '" + o.object + "' uses technique " + tech->name()) +
                         " (needed by export " + o.name + ")");
    std::map<std::string, std::string> options;
    for (const auto& kv : o.options) {
        const auto eq = kv.find('=');
        if (eq == std::string::npos || eq == 0) throw InputError("--option expects KEY=VALUE, got '" + kv + "' (" + o.name + " accepts " + decl.options_help + ")");
        options[kv.substr(0, eq)] = kv.substr(eq + 1);
    }

    const auto t0 = std::chrono::steady_clock::now();
    Workbench wb;
    wb.session().set_store(StageStore::from_environment(version_string()));  // expensive stages kept between runs
    wb.session().set_memory_limit(memory_limit_bytes(o.memory_limit));
    ProgressFn progress = tty_progress();
    const Evaluation ev = wb.evaluate(s, decl.stages, progress);
    const std::string summary = decl.run(s, ev, object, options, o.out, progress);
    tty_progress_done();
    const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    std::printf("%s\nwrote %s in %.0f ms (stages included)\n", summary.c_str(), o.out.c_str(), ms);
    return 0;
}
}  // namespace mesolab
