// One declaration per parameter: its default, JSON form, --set form, schema entry and the stage
// graph's dependencies all agree.
#include "core/error.h"
#include "core/scene.h"
#include "core/technique.h"

#include <gtest/gtest.h>
#include <set>

using namespace mesolab;

namespace {
std::string key(const ParamGroup& g, const ParamDecl& d) { return g.name() + "." + d.name; }
}

TEST(Declarations, DefaultsAreValidAndRoundTripThroughJsonAndText) {
    // The scene's groups and one per technique (basic, microgeom, bumpsynth at least).
    for (const char* name : {"camera", "light", "env", "effects", "geometry", "basic", "microgeom", "bumpsynth"})
        ASSERT_NE(Registry::instance().group(name), nullptr) << name;
    for (const ParamGroup* g : Registry::instance().groups()) {
        EXPECT_FALSE(g->decls().empty()) << g->name();
        for (const ParamDecl& d : g->decls()) {
            SCOPED_TRACE(key(*g, d));
            EXPECT_FALSE(d.help.empty()) << "every parameter needs help text";
            EXPECT_NO_THROW(validate_value(d, d.def, key(*g, d)));
            EXPECT_EQ(value_from_json(d, value_to_json(d, d.def), "t"), d.def);
            EXPECT_EQ(value_from_text(d, value_to_text(d, d.def), "t"), d.def);
            if (d.type == ParamType::Enum) {
                EXPECT_FALSE(d.choices.empty());
            }
            if (d.reference) {
                EXPECT_NO_THROW(validate_value(d, *d.reference, "reference"));
            }
            if (!d.used_when_key.empty()) {
                EXPECT_NE(g->find(d.used_when_key), nullptr);
            }
        }
    }
}

TEST(Declarations, SchemaListsEveryParameterWithItsAttributes) {
    for (const ParamGroup* g : Registry::instance().groups()) {
        const json s = group_schema(*g);
        ASSERT_EQ(s["params"].size(), g->decls().size());
        for (size_t i = 0; i < g->decls().size(); ++i) {
            const ParamDecl& d = g->decls()[i];
            const json& p = s["params"][i];
            EXPECT_EQ(p["key"], key(*g, d));
            EXPECT_EQ(p["type"], to_string(d.type));
            EXPECT_EQ(p["default"], value_to_json(d, d.def));
            EXPECT_EQ(p["cost"], to_string(d.cost));
            EXPECT_EQ(p["help"], d.help);
        }
    }
}

TEST(Declarations, EveryKeyIsSettableFromTheCommandLine) {
    // One scene holding every group (a technique's group needs an object using it).
    for (const Technique* t : Registry::instance().techniques()) {
        Scene s = default_scene(t->name());
        for (const ParamGroup* g : Registry::instance().groups()) {
            if (g != &t->params() && Registry::instance().technique(g->name())) continue;
            const std::string prefix = g->name() == "light" ? "light" : g->name();
            for (const ParamDecl& d : g->decls()) {
                if (d.type == ParamType::Path) continue;  // needs an existing file
                SCOPED_TRACE(key(*g, d));
                Value v = d.reference ? *d.reference : d.def;
                const std::string text = value_to_text(d, v);
                EXPECT_NO_THROW(apply_set(s, prefix + "." + d.name, text));
                EXPECT_EQ(get_public(s, prefix + "." + d.name), text);
            }
        }
    }
}

TEST(Declarations, RecomputeCostsMatchTheStageGraph) {
    // Parameters whose change costs a recompute are read by a stage (or, for a technique's
    // method, choose which stages run), and stages only read declared parameters.
    const StageGraph& graph = Registry::instance().stages();
    std::set<std::string> read;
    for (const StageDecl& st : graph.stages())
        for (const std::string& p : st.params) {
            read.insert(p);
            const auto dot = p.find('.');
            const ParamGroup* g = Registry::instance().group(p.substr(0, dot));
            ASSERT_NE(g, nullptr) << st.name << " reads " << p;
            const std::string name = p.substr(dot + 1);
            if (name != "*") {
                ASSERT_NE(g->find(name), nullptr) << st.name << " reads undeclared " << p;
                EXPECT_EQ(g->find(name)->cost, Cost::Recompute) << st.name << " reads " << p << " whose change is declared as cheaper";
            }
        }
    for (const ParamGroup* g : Registry::instance().groups())
        for (const ParamDecl& d : g->decls())
            if (d.cost == Cost::Recompute && g->name() != "effects" && d.name != "method") {
                EXPECT_TRUE(read.count(key(*g, d)) || read.count(g->name() + ".*")) << key(*g, d) << " costs a recompute but no stage reads it";
            }
    for (const Technique* t : Registry::instance().techniques())
        if (const ParamDecl* m = t->params().find("method")) {
            EXPECT_EQ(m->cost, Cost::Recompute) << t->name() << ".method";
        }
}

TEST(Declarations, ValueChecksNameTheKeyAndRange) {
    const ParamGroup& cam = Registry::instance().camera();
    try {
        value_from_text(*cam.find("fov"), "200", "--set camera.fov");
        FAIL();
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("--set camera.fov"), std::string::npos);
        EXPECT_NE(std::string(e.what()).find("[1, 150]"), std::string::npos);
    }
    EXPECT_THROW(value_from_text(*cam.find("fov"), "nan", "x"), InputError);
    EXPECT_THROW(value_from_text(*cam.find("fov"), "inf", "x"), InputError);
    EXPECT_THROW(value_from_text(*cam.find("fov"), "12abc", "x"), InputError);
    EXPECT_THROW(value_from_json(*cam.find("fov"), json(true), "x"), InputError);
}

// A knob that takes only odd values (translucency.kernel) refuses an even one where it is set,
// naming the key; odd values in range pass.
TEST(Declarations, OddOnlyKnobsRefuseEvenValues) {
    const ParamDecl& kernel = *Registry::instance().technique("translucency")->params().find("kernel");
    try {
        value_from_text(kernel, "8", "--set translucency.kernel");
        FAIL() << "an even kernel was accepted";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("--set translucency.kernel"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("must be odd"), std::string::npos) << e.what();
    }
    EXPECT_NO_THROW(value_from_text(kernel, "9", "x"));
}
