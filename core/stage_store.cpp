#include "core/stage_store.h"
#include "core/blob.h"
#include "core/error.h"
#include "core/file.h"
#include "core/hash.h"
#include "core/session.h"

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <mutex>
#include <system_error>

namespace fs = std::filesystem;

namespace mesolab {

// [SECTION] Folders
std::string cache_root() {
    if (const char* d = std::getenv("MESOLAB_CACHE_DIR"); d && *d) return d;
    if (const char* x = std::getenv("XDG_CACHE_HOME"); x && *x) return std::string(x) + "/mesolab";
    if (const char* home = std::getenv("HOME"); home && *home) return std::string(home) + "/.cache/mesolab";
    return {};
}

std::string cache_folder(const std::string& kind) {
    const std::string root = cache_root();
    return root.empty() ? root : root + "/" + kind;
}

uint64_t cache_size_limit() {
    const char* v = std::getenv("MESOLAB_CACHE_SIZE");
    if (!v || !*v) return uint64_t(8) << 30;
    if (std::string(v) == "0") return 0;
    try {
        return parse_memory_size(v);
    } catch (const InputError&) {
        throw InputError(std::string("MESOLAB_CACHE_SIZE: '") + v + "' is not a size (expected e.g. 512M, 20G, or 0 for no limit)");
    }
}

// [SECTION] Entries
// An entry's file: magic, the payload's FNV-1a, then a blob of (fingerprint, warnings, payload).
namespace {
constexpr char kMagic[8] = {'M', 'L', 'S', 'T', 'A', 'G', 'E', '1'};

std::string hex(uint64_t h) {
    char b[17];
    std::snprintf(b, sizeof b, "%016llx", static_cast<unsigned long long>(h));
    return b;
}
}  // namespace

StageStore::StageStore(std::string folder, std::string version, uint64_t max_bytes, std::vector<std::string> evict_roots)
    : folder_(std::move(folder)), version_(std::move(version)), max_bytes_(max_bytes), evict_roots_(std::move(evict_roots)) {
    if (evict_roots_.empty()) evict_roots_ = {folder_};
}

std::shared_ptr<StageStore> StageStore::from_environment(const std::string& version) {
    const std::string stages = cache_folder("stages");
    if (stages.empty()) return nullptr;
    return std::make_shared<StageStore>(stages, version, cache_size_limit(), std::vector<std::string>{stages, cache_folder("truth")});
}

std::string StageStore::path(const std::string& stage, const std::string& fingerprint) const {
    return folder_ + "/" + stage + "/" + hex(fnv1a(version_ + '\n' + fingerprint)) + ".stage";
}

std::optional<StageStore::Entry> StageStore::load(const std::string& stage, const std::string& fingerprint) const {
    const std::string p = path(stage, fingerprint);
    std::error_code ec;
    if (!fs::exists(p, ec)) return std::nullopt;
    std::ifstream in(p, std::ios::binary);
    std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    if (!in.good() && !in.eof()) return std::nullopt;
    try {
        if (bytes.size() < sizeof kMagic + 8 || bytes.compare(0, sizeof kMagic, kMagic, sizeof kMagic) != 0) return std::nullopt;
        uint64_t h = 0;
        std::memcpy(&h, bytes.data() + sizeof kMagic, 8);
        const std::string_view body = std::string_view(bytes).substr(sizeof kMagic + 8);
        if (fnv1a(body) != h) return std::nullopt;  // corrupt or truncated
        BlobReader r(body);
        if (r.get_string() != version_ || r.get_string() != fingerprint) return std::nullopt;  // another program, or a collision
        Entry e;
        const size_t nw = r.get_count(8);
        for (size_t i = 0; i < nw; ++i) e.warnings.push_back(r.get_string());
        e.payload = r.get_string();
        if (!r.done()) return std::nullopt;
        fs::last_write_time(p, fs::file_time_type::clock::now(), ec);  // recently used
        return e;
    } catch (const BlobError&) {
        return std::nullopt;
    }
}

bool StageStore::save(const std::string& stage, const std::string& fingerprint, const Entry& e) const {
    BlobWriter w;
    w.put_string(version_);
    w.put_string(fingerprint);
    w.put(uint64_t(e.warnings.size()));
    for (const std::string& s : e.warnings) w.put_string(s);
    w.put_string(e.payload);
    const uint64_t h = fnv1a(w.bytes());
    std::string file(kMagic, sizeof kMagic);
    file.append(reinterpret_cast<const char*>(&h), 8);
    file += w.bytes();
    try {
        // The temporary file is named by the process: two threads of one process write in turn,
        // two processes each their own temporary file, and one complete entry wins the rename.
        static std::mutex writing;
        std::lock_guard lock(writing);
        write_text_atomic(path(stage, fingerprint), file);
    } catch (const std::exception&) {
        return false;
    }
    evict();
    return true;
}

uint64_t StageStore::evict() const {
    if (max_bytes_ == 0) return 0;
    struct File {
        fs::path path;
        uint64_t bytes;
        fs::file_time_type time;
    };
    std::vector<File> files;
    uint64_t total = 0;
    std::error_code ec;
    for (const std::string& root : evict_roots_) {
        if (root.empty() || !fs::is_directory(root, ec)) continue;
        for (auto it = fs::recursive_directory_iterator(root, ec); !ec && it != fs::recursive_directory_iterator(); it.increment(ec)) {
            if (!it->is_regular_file(ec)) continue;
            const std::string name = it->path().filename().string();
            if (name.find(".tmp-") != std::string::npos) continue;  // another process's write under way
            const uint64_t n = it->file_size(ec);
            files.push_back({it->path(), n, it->last_write_time(ec)});
            total += n;
        }
    }
    if (total <= max_bytes_) return 0;
    std::sort(files.begin(), files.end(), [](const File& a, const File& b) { return a.time < b.time; });
    uint64_t removed = 0;
    for (const File& f : files) {
        if (total - removed <= max_bytes_) break;
        if (fs::remove(f.path, ec)) removed += f.bytes;
    }
    return removed;
}
}  // namespace mesolab
