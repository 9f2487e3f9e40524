#pragma once
// [SECTION] Packs: a scene that travels.
// A preset names files (meshes, heightfields, albedo and NDF images, environment maps, cloth's
// acquired samples, the arrays given from Python, which live in the giver's cache), and those
// files live wherever the preset's author had them. A pack holds the preset with every file it
// names, so that it renders the same bytes in another folder or on another machine:
//
//   scene.json                 the preset; each file it names is "files/<hash>.<ext>"
//   files/<hash>.<ext>         the file's bytes; <hash>: 16 hex digits of FNV-1a 64 of them
//
// as a zip archive (NAME.zip) or as a folder. The member names are their contents' hashes, so a
// file named twice is held once, and a member whose bytes do not match its name (changed or
// damaged on the way) is refused. The hash guards against accidents, not against an adversary.
//
// Reading a pack checks it before anything of it is used, with an error naming the pack and the
// member: no scene.json; a member scene.json names that the pack lacks (missing); a member it
// does not name (extra); a name that leaves the pack (`..`, an absolute path) or a link; a
// member whose bytes do not match its name; the archive, a member or all members together larger
// than the memory budget; a truncated or damaged archive. A zip pack is unpacked, once, into the
// cache's packs/ folder under its own hash (cache_folder("packs"); like arrays/, never evicted),
// and read from there as a folder pack; the scene's paths then point there.
#include "core/scene.h"

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace mesolab {

// [SECTION] Reading scenes (core/scene.cpp): load_preset reads a pack as it reads a preset file.
// How a value that names a file is checked while a scene is read: `key` is where it stands
// ("objects[0].geometry.path"); throws InputError. scene_from_json(j, source, base_dir) checks that
// the file exists (relative to base_dir); a pack checks that it is one of the pack's members.
using PathCheck = std::function<void(const std::string& key, const std::string& value)>;
Scene scene_from_json(const json& j, const std::string& source, const std::string& base_dir, const PathCheck& check_file);
// The JSON of a preset's text; InputError "SOURCE: line L, column C: invalid JSON (...)".
json preset_json_from_text(const std::string& text, const std::string& source);

// [SECTION] Packs
inline constexpr const char* kPackScene = "scene.json";

struct PackLimits {
    // The most bytes the archive, one member or all members together may hold; 0: the memory
    // available (/proc/meminfo's MemAvailable), as a workbench's default budget.
    uint64_t max_bytes = 0;
};

// A .zip file (any case of the suffix), or a folder holding scene.json.
bool is_pack(const std::string& path);

// Writes `s` with every file it names as a pack at `out`: a zip archive when `out` ends in .zip,
// else a folder. Saved without losing (core/file.h): the archive through a temporary file and a
// rename; the folder built beside `out` and renamed over it (an existing folder there must be a
// pack or empty). The same scene and files give the same bytes. Returns the members, scene.json
// first. InputError naming the key and the file when a file the scene names cannot be read.
std::vector<std::string> write_pack(const Scene& s, const std::string& out);

// The pack's scene; its paths point at the pack's folder (a zip's: where it was unpacked).
// InputError naming the pack, the member and what is wrong (see above).
Scene load_pack(const std::string& path, const PackLimits& limits = {});

// A zip pack's bytes as write_pack writes them (for sending), and the scene of such bytes
// (unpacked into the cache's packs/ folder as a file's); `name` names them in errors.
std::string pack_bytes(const Scene& s);
Scene load_pack_bytes(const std::string& bytes, const std::string& name, const PackLimits& limits = {});

// FNV-1a 64 of `bytes` as 16 hex digits: a member's name, and a zip pack's folder in the cache.
std::string content_hash(const std::string& bytes);
}  // namespace mesolab
