// mesolab: interactive workbench for meso-scale appearance. Subcommands: gui (default),
// capture, bench, sweep, preset validate|schema|show, info, export, and the techniques' own
// commands (`mesolab TECHNIQUE COMMAND`, declared by Technique::commands()).
#include "gpu/headless.h"
#include "gpu/renderer.h"
#include "core/renderer.h"
#include "app/commands.h"
#include "app/workbench.h"
#include "core/bench.h"
#include "core/error.h"

#include "core/technique.h"

#include <CLI/CLI.hpp>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <deque>
#include <iostream>
#include <new>

using namespace mesolab;

int main(int argc, char** argv) {
    mesolab::gpu::install_gpu_compute();  // stages may run their GPU variants (e.g. microgeom.device=gpu)
    mesolab::gpu::install_headless_renderer();  // --backend gpu
    // `mesolab PRESET` and `mesolab` alone mean `mesolab gui ...`.
    std::vector<std::string> commands = {"gui", "capture", "bench", "sweep", "frontier", "preset", "truth", "info", "export", "-h", "--help", "--version"};
    for (const Technique* t : Registry::instance().techniques())
        if (!t->commands().empty()) commands.push_back(t->name());
    std::vector<char*> args(argv, argv + argc);
    bool known = argc > 1 && std::any_of(commands.begin(), commands.end(), [&](const std::string& c) { return c == argv[1]; });
    static char gui_word[] = "gui";
    if (!known) args.insert(args.begin() + 1, gui_word);

    // --memory-limit, for every command that evaluates stages.
    const auto add_memory_limit = [](CLI::App* cmd, std::string& value) {
        cmd->add_option("--memory-limit", value,
                        "Largest allocation a stage may make, e.g. 2G or 512M (default: the available memory); above it the stage stops "
                        "with exit status 2 naming the parameters to lower");
    };
    CLI::App app{"mesolab: interactive workbench for meso-scale appearance (micro-geometry, bump synthesis, translucency, cloth)"};
    app.set_version_flag("--version", std::string(version_string()));
    app.require_subcommand(1);

    GuiOptions gui;
    auto* g = app.add_subcommand("gui", "Open the window (default). Scripted: --script FILE, or --frames N with --screenshot/--window-screenshot");
    g->add_option("preset", gui.preset, "Preset to load");
    g->add_option("--script", gui.script, "Run the commands in FILE (load, set, frames, screenshot, window-screenshot, quit), then exit");
    g->add_option("--frames", gui.frames, "Render N frames, take the requested screenshots, then exit");
    g->add_option("--screenshot", gui.screenshot, "With --frames: save the viewport to this PNG");
    g->add_option("--window-screenshot", gui.window_screenshot, "With --frames: save the whole window with its panels to this PNG");
    g->add_option("--size", gui.size, "Window size WxH")->capture_default_str();
    add_memory_limit(g, gui.memory_limit);

    CaptureOptions cap;
    auto* c = app.add_subcommand("capture", "Render presets headless: DIR/<name>.png (8-bit sRGB), DIR/<name>.<aov>.exr (float), DIR/<name>.json (parameters, renderer, timings, stages, version)");
    c->add_option("presets", cap.presets, "Preset files or folders (every *.json below)")->required();
    c->add_option("-o,--output", cap.out_dir, "Output folder")->capture_default_str();
    c->add_option("--size", cap.size, "Frame size WxH (texture mode may use the technique's native size)")->capture_default_str();
    std::string renderers;  // every registered renderer with its line of help
    for (const auto& n : RendererRegistry::instance().names()) renderers += (renderers.empty() ? "" : "; ") + n + ": " + RendererRegistry::instance().get(n)->help;
    c->add_option("--backend", cap.backend, "The renderer: " + renderers)->capture_default_str();
    auto* cap_spp = c->add_option("--spp", cap.spp, "--backend truth: samples per pixel (with --noise or --time-limit: the most, unlimited when not given)")->capture_default_str();
    c->add_option("--noise", cap.noise, "--backend truth: sample until the truth's noise_rel reaches this (e.g. 0.01), continuing the cached truth; the sidecar says what ended it");
    c->add_option("--time-limit", cap.time_limit, "--backend truth: stop sampling after this long (600, 90s, 10m, 1.5h); the samples done are kept");
    c->add_option("--samples", cap.samples, "--backend truth: render samples A:B only, as a partial truth DIR/NAME.samples-A-B.truth (join parts with `mesolab truth merge`)");
    c->add_option("--seed", cap.seed, "--backend truth: seed of the random streams (the same seed gives the same bytes)")->capture_default_str();
    c->add_option("--set", cap.sets, "Override a parameter: KEY=VALUE (repeatable), e.g. camera.distance=4");
    c->add_flag("--profile", cap.profile, "Print the scoped CPU/GPU timing hierarchy at the end");
    c->add_flag("--no-cache", cap.no_cache,
                "Compute every stage and truth: read nothing from the disk cache and keep nothing there (else expensive stages and truths are kept in "
                "$MESOLAB_CACHE_DIR, ~/.cache/mesolab by default)");
    c->add_option("--aov", cap.aovs, "Also render this AOV and write it as 32-bit float EXR (repeatable): radiance, normal, ...; truth_error also "
                  "renders the truth (--spp, --seed) and writes it and the error, colour-mapped with its legend, as NAME.truth.png and NAME.truth_error.png");
    add_memory_limit(c, cap.memory_limit);

    ExportOptions exp;
    auto* x = app.add_subcommand("export", "Write a technique's data export for a preset's object (e.g. btf: microgeom's view x light grid of heightfield images, EXR)");
    x->add_option("name", exp.name, "Export name: " + export_names())->required();
    x->add_option("preset", exp.preset, "Preset file")->required();
    x->add_option("-o,--output", exp.out, "Output file")->required();
    x->add_option("--object", exp.object, "Scene object (default: the first that uses the export's technique)");
    x->add_option("--option", exp.options, "Export option KEY=VALUE (repeatable), e.g. grid=4x8");
    x->add_option("--set", exp.sets, "Override a parameter: KEY=VALUE (repeatable)");
    add_memory_limit(x, exp.memory_limit);

    BenchCommand bench;
    auto* b = app.add_subcommand("bench", "Timing tables laid out like the papers' tables (all tables when none is named)");
    std::string table_names;
    for (const auto& t : bench_tables()) table_names += (table_names.empty() ? "" : ", ") + t.name;
    b->add_option("tables", bench.run.tables, "Table names: " + table_names);
    b->add_option("--format", bench.format, "md, csv or json")->capture_default_str();
    b->add_option("--repeat", bench.run.repeat, "Runs per cell (median, min, max)")->capture_default_str();
    b->add_option("--label", bench.label, "With --format json: this machine's short name (e.g. H100); a file bench/NAME.json of such a run is merged into the pages by --update-pages, beside this machine's figures");
    b->add_option("--row", bench.run.rows, "Only the rows whose names contain TEXT (repeatable), e.g. --row 'Bricks 1024'");
    b->add_option("--column", bench.run.columns, "Only the columns whose names contain TEXT (repeatable), e.g. --column frame");
    b->add_option("-o,--output", bench.out, "Write to FILE instead of standard output");
    b->add_option("--backend", bench.run.backend, "cpu, gpu or both")->capture_default_str();
    b->add_flag("--profile", bench.run.profile, "Print the scoped CPU/GPU timing hierarchy at the end");
    b->add_flag("--update-pages", bench.update_pages,
                "Write each table (Markdown) between its `<!-- bench NAME -->` and `<!-- /bench -->` lines in README.md and core/*/README.md");
    b->add_option("--pages-root", bench.pages_root, "With --update-pages: the repository's root")->capture_default_str();
    b->add_option("--mesh", bench.run.mesh, "A mesh file (OBJ, PLY, OFF, STL, OM) measured as its own row by the tables that take one (translucency)");
    b->add_option("--vertices", bench.run.vertices, "With --mesh: simplify it to N vertices first (0: the table's default)");
    b->add_option("--preset", bench.run.presets, "Table truth: a row for this preset or pack (repeatable), named after its scene, instead of the shipped presets");
    b->add_option("--noise", bench.run.noise, "Table truth: measure each preset's time to this noise_rel (e.g. 0.01) instead of extrapolating a 32-sample pilot");
    b->add_option("--time-limit", bench.time_limit, "Table truth with --noise: give up on a preset after this long (600, 90s, 10m, 1.5h; default 10m)");
    add_memory_limit(b, bench.memory_limit);

    SweepCommand sweep;
    auto* s = app.add_subcommand("sweep", "Accuracy vs time: render a preset at each value of a knob, measure time and error against a reference");
    s->add_option("preset", sweep.preset, "Preset file")->required();
    s->add_option("--knob", sweep.knob, "KEY=V1,V2,... (e.g. geometry.resolution=8,16,32,64)")->required();
    s->add_option("--reference", sweep.reference, "KEY=V settings of the reference rendering (default: the knob's most accurate setting)");
    s->add_option("-o,--output", sweep.out_dir, "Output folder for CSV, Markdown and the plot (PNG and SVG)")->capture_default_str();
    s->add_option("--size", sweep.size, "Frame size WxH")->capture_default_str();
    s->add_option("--backend", sweep.backend, "The renderer: " + RendererRegistry::instance().names_text())->capture_default_str();
    s->add_option("--set", sweep.sets, "Override a parameter: KEY=VALUE (repeatable)");
    s->add_option("--repeat", sweep.repeat, "Timed runs per value (median)")->capture_default_str();
    s->add_option("--metric", sweep.metric, "Error measure: " + sweep_metric_names())->capture_default_str();
    s->add_option("--by", sweep.by, "KEY=V1,V2,...: a second knob, one curve per value (a grid; with --metric truth)");
    auto* sweep_spp = s->add_option("--spp", sweep.spp, "The truth's samples per pixel (--metric truth, --backend truth; with --noise: the most)")->capture_default_str();
    s->add_option("--noise", sweep.noise, "The truth samples until its noise_rel reaches this (e.g. 0.01)");
    s->add_option("--time-limit", sweep.time_limit, "The truth stops sampling after this long (600, 90s, 10m, 1.5h)");
    s->add_option("--seed", sweep.seed, "The truth's seed")->capture_default_str();
    add_memory_limit(s, sweep.memory_limit);

    FrontierCommand frontier;
    auto* f = app.add_subcommand("frontier", "Accuracy against time: every accuracy knob of the scene's methods on a coarse grid and all together, "
                                             "timed and measured against one truth per distance; the lower envelope drawn (PNG, SVG) and tabled (Markdown, CSV, JSON)");
    f->add_option("preset", frontier.preset, "Preset file")->required();
    f->add_option("-o,--output", frontier.out_dir, "Output folder")->capture_default_str();
    f->add_option("--size", frontier.size, "Frame size WxH")->capture_default_str();
    f->add_option("--backend", frontier.backend, "The real-time renderer timed: cpu or gpu")->capture_default_str();
    f->add_option("--distance", frontier.distances, "camera.distance (orbit camera), repeatable: one truth and one plot per distance (default: the preset's)");
    f->add_option("--set", frontier.sets, "Override a parameter: KEY=VALUE (repeatable)");
    auto* frontier_spp = f->add_option("--spp", frontier.spp, "The truth's samples per pixel (with --noise: the most)")->capture_default_str();
    f->add_option("--noise", frontier.noise, "The truth samples until its noise_rel reaches this (e.g. 0.01)");
    f->add_option("--time-limit", frontier.time_limit, "The truth stops sampling after this long (600, 90s, 10m, 1.5h)");
    f->add_option("--seed", frontier.seed, "The truth's seed")->capture_default_str();
    f->add_option("--budget", frontier.budget_min, "Minutes: no new setting starts after this, shared evenly by the distances (the truth's time included)")->capture_default_str();
    f->add_option("--repeat", frontier.repeat, "Frames per setting (median)")->capture_default_str();
    add_memory_limit(f, frontier.memory_limit);

    auto* p = app.add_subcommand("preset", "Validate, describe and show presets");
    p->require_subcommand(1);
    std::vector<std::string> validate_files;
    auto* pv = p->add_subcommand("validate", "Check preset files; exit 2 naming the file and key of the first problem in each");
    pv->add_option("files", validate_files, "Preset files or folders")->required();
    std::string schema_tech;
    bool schema_json = false;
    auto* ps = p->add_subcommand("schema", "Every parameter with type, default, range, unit, help and cost");
    ps->add_option("technique", schema_tech, "Only this technique (or group: camera, light, env, geometry, effects)");
    ps->add_flag("--json", schema_json, "JSON output");
    std::string show_file;
    std::vector<std::string> show_sets;
    auto* psh = p->add_subcommand("show", "Print the fully resolved preset JSON");
    psh->add_option("file", show_file, "Preset file")->required();
    psh->add_option("--set", show_sets, "Override a parameter: KEY=VALUE (repeatable)");
    std::string pack_file, pack_out;
    std::vector<std::string> pack_sets;
    auto* ppk = p->add_subcommand("pack", "Write a preset with every file it names (meshes, images, samples, arrays from Python) as a pack to share: "
                                          "NAME.zip or a folder; capture, sweep, bench, frontier, gui and Python read a pack as a preset");
    ppk->add_option("file", pack_file, "Preset file (or pack)")->required();
    ppk->add_option("-o,--output", pack_out, "NAME.zip, or a folder (new, empty, or a pack it replaces)")->required();
    ppk->add_option("--set", pack_sets, "Override a parameter first: KEY=VALUE (repeatable)");

    auto* tr = app.add_subcommand("truth", "Partial truths (capture --backend truth --samples A:B): merge");
    tr->require_subcommand(1);
    MergeOptions merge;
    auto* tm = tr->add_subcommand("merge", "Join partial truths of one scene, size, seed and build into one: DIR/NAME.png, NAME.json, NAME.<aov>.exr and the "
                                           "joined NAME.samples-A-B.truth (from sample 0: also kept in the truth cache)");
    tm->add_option("parts", merge.parts, "Partial truths (NAME.samples-A-B.truth), in any order")->required();
    tm->add_option("-o,--output", merge.out_dir, "Output folder")->required();
    tm->add_option("--aov", merge.aovs, "Also write this AOV as 32-bit float EXR (repeatable): normal, truth_stderr, exitance, irradiance");

    auto* info = app.add_subcommand("info", "GL vendor/renderer/version of the headless context, CPU threads, versions");

    // The techniques' commands: `mesolab TECHNIQUE COMMAND ...`, built from their declarations.
    struct TechniqueCommand {
        CLI::App* app;
        CommandDecl decl;
        std::map<std::string, std::string> values;  // by positional name / long option name
        std::vector<std::pair<std::string, CLI::Option*>> given;
    };
    std::deque<TechniqueCommand> technique_commands;  // stable addresses for CLI11's bindings
    for (const Technique* t : Registry::instance().techniques()) {
        const std::vector<CommandDecl> decls = t->commands();
        if (decls.empty()) continue;
        auto* tc = app.add_subcommand(t->name(), t->title() + ": commands of the technique");
        tc->require_subcommand(1);
        for (const CommandDecl& d : decls) {
            TechniqueCommand& c = technique_commands.emplace_back(TechniqueCommand{tc->add_subcommand(d.name, d.help), d, {}});
            for (const CommandArgDecl& a : d.positionals) {
                auto* opt = c.app->add_option(a.name, c.values[a.name], a.help);
                if (a.required) opt->required();
                c.given.emplace_back(a.name, opt);
            }
            for (const CommandArgDecl& a : d.options) {
                std::string key = a.name.substr(a.name.rfind(',') == std::string::npos ? 0 : a.name.rfind(',') + 1);
                key.erase(0, key.find_first_not_of('-'));  // "-o,--output" -> "output", "--lookup-table" -> "lookup-table"
                auto* opt = c.app->add_option(a.name, c.values[key], a.help);
                if (a.required) opt->required();
                c.given.emplace_back(key, opt);
            }
        }
    }

    try {
        app.parse(int(args.size()), args.data());
    } catch (const CLI::CallForHelp& e) {
        return app.exit(e);
    } catch (const CLI::CallForAllHelp& e) {
        return app.exit(e);
    } catch (const CLI::CallForVersion& e) {
        return app.exit(e);
    } catch (const CLI::ParseError& e) {
        app.exit(e);
        return 2;
    }

    try {
        if (g->parsed()) return run_gui(gui);
        if (c->parsed()) {
            cap.spp_given = cap_spp->count() > 0;
            return run_capture(cap);
        }
        if (tm->parsed()) return run_truth_merge(merge);
        if (b->parsed()) return run_bench(bench);
        if (s->parsed()) {
            sweep.spp_given = sweep_spp->count() > 0;
            return run_sweep(sweep);
        }
        if (f->parsed()) {
            frontier.spp_given = frontier_spp->count() > 0;
            return run_frontier(frontier);
        }
        if (pv->parsed()) return run_preset_validate(validate_files);
        if (ps->parsed()) return run_preset_schema(schema_tech, schema_json);
        if (psh->parsed()) return run_preset_show(show_file, show_sets);
        if (ppk->parsed()) return run_preset_pack(pack_file, pack_sets, pack_out);
        if (info->parsed()) return run_info();
        if (x->parsed()) return run_export(exp);
        for (TechniqueCommand& c : technique_commands) {
            if (!c.app->parsed()) continue;
            std::map<std::string, std::string> values;
            for (const auto& [key, opt] : c.given)
                if (opt->count() > 0) values[key] = c.values[key];
            const auto t0 = std::chrono::steady_clock::now();
            const std::string summary = c.decl.run(values, tty_progress());
            tty_progress_done();
            const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
            std::printf("%s\n(%.0f ms)\n", summary.c_str(), ms);
            return 0;
        }
    } catch (const InputError& e) {
        tty_progress_done();
        std::fprintf(stderr, "mesolab: error: %s\n", e.what());
        return 2;
    } catch (const std::bad_alloc&) {
        // A stage's estimate should have caught this first (core/session.h); settings still too large.
        tty_progress_done();
        std::fprintf(stderr, "mesolab: error: out of memory: the settings need more memory than this machine has; lower the resolutions, "
                             "direction counts or frame size (mesolab preset schema lists them)\n");
        return 2;
    } catch (const std::exception& e) {
        tty_progress_done();
        std::fprintf(stderr, "mesolab: internal error: %s\n", e.what());
        return 1;
    }
    return 1;
}
