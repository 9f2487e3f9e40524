#include "core/read_contract.h"

#include <cstdlib>
#include <stdexcept>

namespace mesolab {

bool pattern_covers(std::string_view p, std::string_view group, std::string_view name) {
    if (p.size() <= group.size() || p.compare(0, group.size(), group) != 0 || p[group.size()] != '.') return false;
    const std::string_view rest = p.substr(group.size() + 1);
    return rest == "*" || (name != "*" && rest == name);
}

DeclaredReads::DeclaredReads(std::string who, const Scene& scene, std::vector<std::string> patterns, int object, std::string remedy)
    : who_(std::move(who)), remedy_(std::move(remedy)), scene_(scene), patterns_(std::move(patterns)), object_(object) {}

void DeclaredReads::read(const ParamTable& t, std::string_view name) {
    if (!t.valid()) return;
    const std::string& group = t.group().name();
    const std::string key = group + "." + std::string(name);
    if (object_ >= 0)
        for (size_t j = 0; j < scene_.objects.size(); ++j)
            if (int(j) != object_ && (&t == &scene_.objects[j].material || &t == &scene_.objects[j].geometry))
                throw std::logic_error(who_ + " read " + key + " of object " + std::to_string(j) +
                                       ", not its own: an object stage's result may depend only on its own object");
    for (const std::string& p : patterns_)
        if (pattern_covers(p, group, name)) return;
    throw std::logic_error(who_ + " read " + key + (name == "*" ? " (every key of " + group + ")" : std::string()) + ", which " + remedy_);
}

void check_key_patterns(const std::string& who, const std::vector<std::string>& patterns,
                        const std::function<const ParamGroup*(std::string_view)>& group) {
    for (const std::string& p : patterns) {
        const auto dot = p.find('.');
        const std::string_view g = std::string_view(p).substr(0, dot == std::string::npos ? p.size() : dot);
        const ParamGroup* pg = dot == std::string::npos || dot == 0 ? nullptr : group(g);
        if (!pg) throw std::logic_error(who + " declares " + p + ": not a key (expected group.name or group.*, of an existing group)");
        const std::string name = p.substr(dot + 1);
        if (name != "*" && !pg->find(name)) throw std::logic_error(who + " declares " + p + ": " + std::string(g) + " has no key " + name);
    }
}

bool check_reads_by_default() {
    const char* v = std::getenv("MESOLAB_CHECK_STAGE_READS");
    return v && std::string(v) == "1";
}
}  // namespace mesolab
