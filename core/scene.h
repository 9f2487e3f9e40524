#pragma once
// [SECTION] Scenes and presets.
// A preset is a JSON scene, shared between users, that holds every parameter:
//   {
//     "schema": 1,
//     "name": "...", "description": "...",
//     "camera":  { camera.* },
//     "lights":  [ { light.* }, ... ],           // "light.X" on the command line = lights[0]
//     "env":     { env.* },
//     "effects": { "environment": true, ... },  // effect switches: stages no enabled effect needs never run
//     "objects": [ { "name": "...", "geometry": { geometry.* },
//                    "material": { "technique": "basic", basic.* } }, ... ]
//   }
// Loading checks every key against the declarations (core/param.h): unknown keys (with the
// nearest valid key), wrong types, out-of-range values and keys that the current settings do
// not use are errors naming the file and the key. Saving writes every used parameter in
// declaration order, atomically (temporary file, then rename); load(save(s)) == s.
#include "core/param.h"
#include <string>
#include <vector>

namespace mesolab {

struct SceneObject {
    std::string name;
    ParamTable geometry;
    std::string technique;
    ParamTable material;
};

struct Scene {
    int schema = 1;
    std::string name;         // preset name: used for capture file names
    std::string description;
    std::string base_dir;     // folder that relative paths in the scene are relative to
    ParamTable camera, env, effects;
    std::vector<ParamTable> lights;
    std::vector<SceneObject> objects;

    bool operator==(const Scene& o) const;

    // Path parameter resolved against base_dir ("" stays "").
    std::string resolve(const std::string& path) const;
    bool effect(const std::string& name) const { return effects.get_bool(name); }
    bool uses_technique(const std::string& t) const;
};

inline constexpr int kPresetSchema = 1;

// A scene with one sphere using `technique`, one directional light and a grey environment.
Scene default_scene(const std::string& technique = "basic");

// Parse / load. `source` names the file in messages.
Scene scene_from_json(const json& j, const std::string& source, const std::string& base_dir);
Scene load_preset(const std::string& path);
// Serialise every used parameter in declaration order.
json scene_to_json(const Scene& s);
std::string scene_to_text(const Scene& s);  // pretty JSON with a trailing newline
// Saved through a temporary file renamed over `path` (core/file.h): the old file survives any failure.
void save_preset(const Scene& s, const std::string& path);

// `--set KEY=VALUE`. KEY is a public name: camera.*, env.*, effects.*, light.* (the first
// light), lights.N.*, geometry.* (the first object), objects.N.geometry.*, TECHNIQUE.* (every
// object using that technique), objects.N.material.*. Errors name the key and suggest the
// nearest valid key.
void apply_set(Scene& s, const std::string& assignment);
void apply_set(Scene& s, const std::string& key, const std::string& value);
// Several `--set`s, then the check a preset gets: a key the final settings do not use is an error
// naming it and the setting it depends on (so the order of the --sets does not matter).
void apply_sets(Scene& s, const std::vector<std::string>& assignments);
// InputError when no table `key` addresses uses it with the scene's current settings.
void check_set_used(const Scene& s, const std::string& key);
// Read a public key ("camera.distance", "basic.kd", ...) as text, for display and sweeps.
std::string get_public(const Scene& s, const std::string& key);
// The same as its stored value (TECHNIQUE.*: the first object using the technique).
Value get_public_value(const Scene& s, const std::string& key);
// The declaration behind a public key (throws InputError with a suggestion if unknown).
const ParamDecl& decl_of(const Scene& s, const std::string& key);
// Every public key valid for this scene, for suggestions and listings.
std::vector<std::string> public_keys(const Scene& s);
}  // namespace mesolab
