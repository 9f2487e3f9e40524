// No input crashes the preset reader: random mutations of real presets either load or raise
// InputError (exit status 2), never anything else.
#include "core/error.h"
#include "core/scene.h"
#include "support/cli.h"

#include <gtest/gtest.h>
#include <filesystem>
#include <random>

using namespace mesolab;
using namespace mesolab::test;

TEST(PresetFuzz, MutationsLoadOrFailCleanly) {
    std::mt19937 rng(12345);
    const char* alphabet = "{}[]\":,0123456789.-+eE truefalsnul\\abc";
    int loaded = 0, rejected = 0;
    for (const auto& e : std::filesystem::recursive_directory_iterator(source_path("presets"))) {
        if (e.path().extension() != ".json") continue;
        const std::string original = slurp(e.path().string());
        for (int i = 0; i < 300; ++i) {
            std::string text = original;
            const int edits = 1 + int(rng() % 4);
            for (int k = 0; k < edits; ++k) {
                const size_t at = rng() % text.size();
                switch (rng() % 3) {
                    case 0: text[at] = alphabet[rng() % std::strlen(alphabet)]; break;
                    case 1: text.erase(at, 1 + rng() % 8); break;
                    default: text.insert(text.begin() + std::ptrdiff_t(at), alphabet[rng() % std::strlen(alphabet)]); break;
                }
                if (text.empty()) text.push_back('{');
            }
            try {
                const json j = json::parse(text);
                scene_from_json(j, "fuzz.json", e.path().parent_path().string());
                ++loaded;
            } catch (const json::exception&) {
                ++rejected;  // load_preset turns these into InputError with line and column
            } catch (const InputError& err) {
                ++rejected;
                EXPECT_NE(std::string(err.what()).find("fuzz.json"), std::string::npos) << err.what();
            }
        }
    }
    EXPECT_GT(rejected, 0);
    EXPECT_GT(loaded, 0);
}
