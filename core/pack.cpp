// Packs: write (zip or folder), check, unpack, read. See core/pack.h.
#include "core/pack.h"

#include "core/error.h"
#include "core/file.h"
#include "core/hash.h"
#include "core/session.h"
#include "core/stage_store.h"

#include <zip.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <sys/stat.h>
#include <unistd.h>

namespace fs = std::filesystem;

namespace mesolab {
namespace {

// [SECTION] Helpers
constexpr const char* kFilesDir = "files/";
// A fixed modification time for every member (1 January 1980, the zip format's first day), so that
// the same scene gives the same archive bytes.
constexpr time_t kMemberTime = 315532800 + 12 * 3600;

bool ends_with_zip(const std::string& path) {
    if (path.size() < 4) return false;
    std::string ext = path.substr(path.size() - 4);
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
    return ext == ".zip";
}

std::string read_whole(const std::string& path, const std::string& what) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw InputError(what + ": cannot open '" + path + "' for reading");
    std::ostringstream ss;
    ss << in.rdbuf();
    if (in.bad()) throw InputError(what + ": cannot read '" + path + "'");
    return ss.str();
}

std::string bytes_text(uint64_t n) {
    char b[64];
    if (n >= (1ull << 30)) std::snprintf(b, sizeof b, "%.2f GiB", double(n) / double(1ull << 30));
    else if (n >= (1ull << 20)) std::snprintf(b, sizeof b, "%.1f MiB", double(n) / double(1ull << 20));
    else std::snprintf(b, sizeof b, "%llu bytes", static_cast<unsigned long long>(n));
    return b;
}

uint64_t budget(const PackLimits& l) {
    if (l.max_bytes) return l.max_bytes;
    const uint64_t avail = available_memory();
    return avail ? avail : ~uint64_t(0);
}

[[noreturn]] void bad_member(const std::string& pack, const std::string& member, const std::string& what) {
    throw InputError(pack + ": member " + member + ": " + what);
}

// Whether a member's name stays inside the pack: relative, no "..", no backslash, no empty part.
bool stays_inside(const std::string& name) {
    if (name.empty() || name.front() == '/' || name.find('\\') != std::string::npos || name.find(':') != std::string::npos) return false;
    size_t start = 0;
    while (start <= name.size()) {
        const size_t end = std::min(name.find('/', start), name.size());
        const std::string part = name.substr(start, end - start);
        if (part == ".." || part == "." || (part.empty() && end != name.size())) return false;
        start = end + 1;
    }
    return true;
}

// "files/<16 hex>" with an optional ".<ext>" of letters and digits: the hash, else "".
std::string member_hash(const std::string& name) {
    if (name.rfind(kFilesDir, 0) != 0) return "";
    const std::string rest = name.substr(std::char_traits<char>::length(kFilesDir));
    if (rest.size() < 16) return "";
    const std::string hash = rest.substr(0, 16);
    if (!std::all_of(hash.begin(), hash.end(), [](char c) { return (c >= '0' && c <= '9') || (c >= 'a' && c <= 'f'); })) return "";
    const std::string ext = rest.substr(16);
    if (ext.empty()) return hash;
    if (ext[0] != '.' || ext.size() < 2 || ext.size() > 16) return "";
    if (!std::all_of(ext.begin() + 1, ext.end(), [](unsigned char c) { return std::isalnum(c); })) return "";
    return hash;
}

std::string member_name(const std::string& bytes, const std::string& source_path) {
    std::string ext = fs::path(source_path).extension().string();
    if (ext.size() > 16 || !std::all_of(ext.begin() + (ext.empty() ? 0 : 1), ext.end(), [](unsigned char c) { return std::isalnum(c); })) ext.clear();
    return kFilesDir + content_hash(bytes) + ext;
}

// Every table of a scene that may name files.
template <class F>
void for_each_table(Scene& s, F&& f) {
    f(s.camera, std::string("camera"));
    f(s.env, std::string("env"));
    f(s.effects, std::string("effects"));
    for (size_t i = 0; i < s.lights.size(); ++i) f(s.lights[i], "lights[" + std::to_string(i) + "]");
    for (size_t i = 0; i < s.objects.size(); ++i) {
        f(s.objects[i].geometry, "objects[" + std::to_string(i) + "].geometry");
        f(s.objects[i].material, "objects[" + std::to_string(i) + "].material");
    }
}

// [SECTION] Writing
struct PackPlan {
    std::string scene_text;
    std::map<std::string, std::string> members;  // name -> bytes (sorted: the archive's order)
};

PackPlan plan_pack(const Scene& scene) {
    PackPlan plan;
    Scene s = scene;
    for_each_table(s, [&](ParamTable& t, const std::string& where) {
        for (const auto& d : t.group().decls()) {
            if (!t.is_used(d) || !d.is_file(t.get(d.name))) continue;
            const std::string value = t.get_string(d.name);
            const std::string full = scene.resolve(value);
            std::string bytes;
            try {
                bytes = read_whole(full, where + "." + d.name);
            } catch (const InputError& e) {
                throw InputError(std::string(e.what()) + " (the scene names '" + value + "'; a pack holds every file its scene names)");
            }
            const std::string name = member_name(bytes, full);
            t.set(d.name, name);
            plan.members.emplace(name, std::move(bytes));
        }
    });
    plan.scene_text = scene_to_text(s);
    return plan;
}

std::string zip_error_text(zip_error_t* e) { return zip_error_strerror(e); }

void write_zip(const PackPlan& plan, const std::string& path) {
    int err = 0;
    zip_t* za = zip_open(path.c_str(), ZIP_CREATE | ZIP_TRUNCATE, &err);
    if (!za) {
        zip_error_t ze;
        zip_error_init_with_code(&ze, err);
        const std::string msg = zip_error_text(&ze);
        zip_error_fini(&ze);
        throw std::runtime_error(msg);
    }
    auto add = [&](const std::string& name, const std::string& bytes) {
        zip_source_t* src = zip_source_buffer(za, bytes.data(), bytes.size(), 0);
        if (!src) throw std::runtime_error(zip_strerror(za));
        const zip_int64_t i = zip_file_add(za, name.c_str(), src, ZIP_FL_ENC_UTF_8);
        if (i < 0) {
            zip_source_free(src);
            throw std::runtime_error(zip_strerror(za));
        }
        zip_file_set_mtime(za, zip_uint64_t(i), kMemberTime, 0);
        // Regular files, rw-r--r--, from a Unix system.
        zip_file_set_external_attributes(za, zip_uint64_t(i), 0, ZIP_OPSYS_UNIX, zip_uint32_t(S_IFREG | 0644) << 16);
    };
    try {
        add(kPackScene, plan.scene_text);
        for (const auto& [name, bytes] : plan.members) add(name, bytes);
    } catch (...) {
        zip_discard(za);
        throw;
    }
    if (zip_close(za) != 0) {
        const std::string msg = zip_strerror(za);
        zip_discard(za);
        throw std::runtime_error(msg);
    }
}

std::string temp_name(const std::string& path) { return path + ".tmp-" + std::to_string(::getpid()); }

void write_folder(const PackPlan& plan, const std::string& out) {
    std::string dir = out;
    while (dir.size() > 1 && dir.back() == '/') dir.pop_back();
    std::error_code ec;
    if (fs::exists(dir, ec)) {
        if (!fs::is_directory(dir, ec)) throw InputError(out + ": exists and is not a folder; a pack is written as a folder or as NAME.zip");
        if (!fs::is_empty(dir, ec) && !fs::exists(fs::path(dir) / kPackScene, ec))
            throw InputError(out + ": a folder that holds other files than a pack; choose a new or empty folder (the pack replaces the folder whole)");
    }
    const std::string tmp = temp_name(dir);
    fs::remove_all(tmp, ec);
    try {
        fs::create_directories(fs::path(tmp) / "files");
        auto put = [&](const std::string& name, const std::string& bytes) {
            std::ofstream f(fs::path(tmp) / name, std::ios::binary);
            f.write(bytes.data(), std::streamsize(bytes.size()));
            f.close();
            if (!f) throw InputError(out + ": cannot write member " + name);
        };
        for (const auto& [name, bytes] : plan.members) put(name, bytes);
        put(kPackScene, plan.scene_text);
        const std::string old = dir + ".old-" + std::to_string(::getpid());
        const bool had = fs::exists(dir, ec);
        if (had) fs::rename(dir, old);
        fs::rename(tmp, dir);
        if (had) fs::remove_all(old, ec);
    } catch (const fs::filesystem_error& e) {
        fs::remove_all(tmp, ec);
        throw InputError(out + ": cannot write the pack: " + e.code().message() + "; the existing folder is unchanged");
    } catch (...) {
        fs::remove_all(tmp, ec);
        throw;
    }
}

// [SECTION] Reading
// A folder pack: checks every member, then the scene (whose files must be the members).
Scene read_folder_pack(const std::string& dir, const std::string& name, const PackLimits& limits) {
    const uint64_t max = budget(limits);
    std::error_code ec;
    const fs::path root = fs::absolute(dir).lexically_normal();
    std::set<std::string> members;
    uint64_t total = 0;
    for (auto it = fs::recursive_directory_iterator(root, ec); !ec && it != fs::recursive_directory_iterator(); it.increment(ec)) {
        const std::string rel = it->path().lexically_relative(root).generic_string();
        const fs::file_status st = it->symlink_status(ec);
        if (fs::is_symlink(st)) bad_member(name, rel, "is a link (a pack holds plain files only)");
        if (fs::is_directory(st)) {
            if (rel + "/" != kFilesDir) bad_member(name, rel + "/", "a folder a pack does not have (a pack holds scene.json and files/)");
            continue;
        }
        if (!fs::is_regular_file(st)) bad_member(name, rel, "not a plain file");
        const uint64_t size = it->file_size(ec);
        if (size > max) bad_member(name, rel, bytes_text(size) + ", above the memory budget of " + bytes_text(max));
        total += size;
        if (total > max) throw InputError(name + ": members total more than the memory budget of " + bytes_text(max));
        if (rel != kPackScene && member_hash(rel).empty())
            bad_member(name, rel, "not named by scene.json (a pack holds scene.json and the files it names, as files/<hash>.<ext>)");
        members.insert(rel);
    }
    if (ec) throw InputError(name + ": cannot list the pack's folder: " + ec.message());
    if (!members.count(kPackScene)) throw InputError(name + ": no " + std::string(kPackScene) + " (a pack holds scene.json and the files it names)");
    const std::string source = name + "/" + kPackScene;
    const json j = preset_json_from_text(read_whole((root / kPackScene).string(), name), source);
    std::set<std::string> named;
    const PathCheck check = [&](const std::string& key, const std::string& value) {
        if (!stays_inside(value)) throw InputError(source + ": " + key + ": '" + value + "' leaves the pack (a pack's scene names only its members, files/<hash>.<ext>)");
        if (member_hash(value).empty())
            throw InputError(source + ": " + key + ": '" + value + "' is not a member's name (a pack's scene names only its members, files/<hash>.<ext>)");
        if (!members.count(value)) bad_member(name, value, "missing (scene.json names it at " + key + ")");
        named.insert(value);
    };
    Scene s = scene_from_json(j, source, root.string(), check);
    for (const auto& m : members) {
        if (m == kPackScene) continue;
        if (!named.count(m)) bad_member(name, m, "not named by scene.json (extra: a pack holds scene.json and the files it names)");
        const std::string hash = content_hash(read_whole((root / m).string(), name));
        if (hash != member_hash(m)) bad_member(name, m, "its bytes hash to " + hash + ", not to its name: the file was changed or damaged");
    }
    if (!j.contains("name")) s.name = fs::path(name).stem().string();
    return s;
}

struct ZipReader {
    zip_t* za = nullptr;
    ~ZipReader() {
        if (za) zip_discard(za);
    }
};

// Checks a zip pack's bytes and unpacks it into `dest` (through a temporary folder beside it).
void unpack_zip(const std::string& bytes, const std::string& name, const std::string& dest, uint64_t max) {
    zip_error_t ze;
    zip_error_init(&ze);
    zip_source_t* src = zip_source_buffer_create(bytes.data(), bytes.size(), 0, &ze);
    if (!src) {
        const std::string msg = zip_error_text(&ze);
        zip_error_fini(&ze);
        throw InputError(name + ": cannot read the archive: " + msg);
    }
    ZipReader r;
    r.za = zip_open_from_source(src, ZIP_RDONLY | ZIP_CHECKCONS, &ze);
    if (!r.za) {
        const std::string msg = zip_error_text(&ze);
        zip_error_fini(&ze);
        zip_source_free(src);
        throw InputError(name + ": not a complete zip archive (" + msg + "): truncated or damaged on the way?");
    }
    zip_error_fini(&ze);
    const zip_int64_t n = zip_get_num_entries(r.za, 0);
    struct Entry {
        zip_uint64_t index;
        std::string name;
        uint64_t size;
    };
    std::vector<Entry> entries;
    std::set<std::string> seen;
    uint64_t total = 0;
    for (zip_int64_t i = 0; i < n; ++i) {
        zip_stat_t st;
        zip_stat_init(&st);
        if (zip_stat_index(r.za, zip_uint64_t(i), 0, &st) != 0 || !(st.valid & ZIP_STAT_NAME) || !(st.valid & ZIP_STAT_SIZE))
            throw InputError(name + ": entry " + std::to_string(i) + " cannot be read: " + zip_strerror(r.za));
        const std::string m = st.name;
        if (!stays_inside(m) && !(m == kFilesDir)) bad_member(name, m, "leaves the pack (an absolute path or '..'; a pack holds scene.json and files/<hash>.<ext>)");
        zip_uint8_t opsys = 0;
        zip_uint32_t attr = 0;
        if (zip_file_get_external_attributes(r.za, zip_uint64_t(i), 0, &opsys, &attr) == 0 && opsys == ZIP_OPSYS_UNIX && S_ISLNK(attr >> 16))
            bad_member(name, m, "is a link (a pack holds plain files only)");
        if (m == kFilesDir) continue;  // the folder's own entry, as some zip tools write it
        if (!m.empty() && m.back() == '/') bad_member(name, m, "a folder a pack does not have (a pack holds scene.json and files/)");
        if (m != kPackScene && member_hash(m).empty())
            bad_member(name, m, "not named by scene.json (a pack holds scene.json and the files it names, as files/<hash>.<ext>)");
        if (!seen.insert(m).second) bad_member(name, m, "held twice");
        if (st.size > max) bad_member(name, m, bytes_text(st.size) + " unpacked, above the memory budget of " + bytes_text(max));
        total += st.size;
        if (total > max) throw InputError(name + ": members total more than the memory budget of " + bytes_text(max) + " unpacked");
        entries.push_back({zip_uint64_t(i), m, st.size});
    }
    if (!seen.count(kPackScene)) throw InputError(name + ": no " + std::string(kPackScene) + " (a pack holds scene.json and the files it names)");

    std::error_code ec;
    const std::string tmp = temp_name(dest);
    fs::remove_all(tmp, ec);
    try {
        fs::create_directories(fs::path(tmp) / "files");
        std::string buf;
        for (const auto& e : entries) {
            zip_file_t* zf = zip_fopen_index(r.za, e.index, 0);
            if (!zf) bad_member(name, e.name, std::string("cannot be read: ") + zip_strerror(r.za));
            buf.assign(e.size, '\0');
            zip_int64_t got = e.size ? zip_fread(zf, buf.data(), e.size) : 0;
            char extra = 0;
            // One byte more than declared must not come: the declared size bounds what is unpacked.
            const zip_int64_t more = got == zip_int64_t(e.size) ? zip_fread(zf, &extra, 1) : 0;
            std::string why;
            if (got < 0 || more < 0) why = zip_file_strerror(zf);
            zip_fclose(zf);
            if (!why.empty()) bad_member(name, e.name, "cannot be unpacked (" + why + "): truncated or damaged");
            if (got != zip_int64_t(e.size) || more != 0)
                bad_member(name, e.name, "unpacks to another size than the archive declares: truncated or damaged");
            std::ofstream f(fs::path(tmp) / e.name, std::ios::binary);
            f.write(buf.data(), std::streamsize(buf.size()));
            f.close();
            if (!f) throw InputError(name + ": cannot unpack member " + e.name + " into " + tmp);
        }
        fs::rename(tmp, dest, ec);
        if (ec) {
            // Another process unpacked the same archive first: its folder is the same bytes.
            std::error_code ec2;
            fs::remove_all(tmp, ec2);
            if (!fs::exists(fs::path(dest) / kPackScene, ec2)) throw InputError(name + ": cannot unpack into " + dest + ": " + ec.message());
        }
    } catch (...) {
        fs::remove_all(tmp, ec);
        throw;
    }
}

std::string packs_folder() {
    std::string f = cache_folder("packs");
    if (f.empty()) f = (fs::temp_directory_path() / ("mesolab-packs-" + std::to_string(::getuid()))).string();
    return f;
}
}  // namespace

// [SECTION] Public
std::string content_hash(const std::string& bytes) {
    char b[17];
    std::snprintf(b, sizeof b, "%016llx", static_cast<unsigned long long>(fnv1a(bytes)));
    return b;
}

bool is_pack(const std::string& path) {
    std::error_code ec;
    if (fs::is_directory(path, ec)) return fs::exists(fs::path(path) / kPackScene, ec);
    return ends_with_zip(path);
}

std::vector<std::string> write_pack(const Scene& s, const std::string& out) {
    const PackPlan plan = plan_pack(s);
    if (ends_with_zip(out)) {
        write_file_atomic(out, "pack", [&](const std::string& tmp) -> std::string {
            try {
                write_zip(plan, tmp);
            } catch (const std::exception& e) {
                return e.what();
            }
            return "";
        });
    } else {
        write_folder(plan, out);
    }
    std::vector<std::string> names{kPackScene};
    for (const auto& [name, bytes] : plan.members) names.push_back(name);
    return names;
}

std::string pack_bytes(const Scene& s) {
    const PackPlan plan = plan_pack(s);
    const std::string tmp = (fs::temp_directory_path() / ("mesolab-pack-" + std::to_string(::getpid()) + "-" + content_hash(plan.scene_text) + ".zip")).string();
    try {
        write_zip(plan, tmp);
    } catch (const std::exception& e) {
        std::error_code ec;
        fs::remove(tmp, ec);
        throw std::runtime_error(std::string("cannot write a pack: ") + e.what());
    }
    std::string bytes = read_whole(tmp, "pack");
    std::error_code ec;
    fs::remove(tmp, ec);
    return bytes;
}

Scene load_pack_bytes(const std::string& bytes, const std::string& name, const PackLimits& limits) {
    const uint64_t max = budget(limits);
    if (bytes.size() > max) throw InputError(name + ": " + bytes_text(bytes.size()) + ", above the memory budget of " + bytes_text(max));
    const std::string dest = (fs::path(packs_folder()) / content_hash(bytes)).string();
    std::error_code ec;
    const bool fresh = !fs::exists(fs::path(dest) / kPackScene, ec);
    if (fresh) {
        fs::create_directories(packs_folder(), ec);
        unpack_zip(bytes, name, dest, max);
    }
    // Read as a folder pack: every member checked. A pack that fails leaves nothing behind; an
    // earlier unpacked copy that fails (touched since) is unpacked again.
    try {
        return read_folder_pack(dest, name, limits);
    } catch (const InputError&) {
        fs::remove_all(dest, ec);
        if (fresh) throw;
    }
    unpack_zip(bytes, name, dest, max);
    try {
        return read_folder_pack(dest, name, limits);
    } catch (const InputError&) {
        fs::remove_all(dest, ec);
        throw;
    }
}

Scene load_pack(const std::string& path, const PackLimits& limits) {
    std::error_code ec;
    if (fs::is_directory(path, ec)) return read_folder_pack(path, path, limits);
    const uint64_t max = budget(limits);
    const uint64_t size = fs::file_size(path, ec);
    if (ec) throw InputError(path + ": cannot read: " + ec.message());
    if (size > max) throw InputError(path + ": " + bytes_text(size) + ", above the memory budget of " + bytes_text(max));
    Scene s = load_pack_bytes(read_whole(path, path), path, limits);
    return s;
}
}  // namespace mesolab
