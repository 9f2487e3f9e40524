#pragma once
// [SECTION] The GPU resource cache.
// One cache for every GL object made from a stage result (textures, storage buffers, uploaded
// meshes), shared by the renderer and all technique passes. An entry is keyed by the result it
// was made from and a slot name (one result may feed several GL objects: "normals", "albedo").
// The key holds the result weakly, by its control block, not by its address:
//  - an entry lives as long as its result does (the session's stage cache or the evaluation on
//    screen holds it), and collect() frees the GL objects of results that are gone;
//  - a new result that happens to reuse a freed result's address never finds the old entry.
// Needs a current GL context for make() and for collect().
#include <any>
#include <map>
#include <memory>
#include <stdexcept>
#include <string>
#include <string_view>
#include <typeinfo>
#include <utility>

namespace mesolab::gpu {

class GpuResources {
public:
    // The GL object of type GL made from `owner` for `slot`, made by make() (returning a GL) the
    // first time. Throws std::logic_error when the slot holds another type.
    template <class GL, class T, class Make>
    GL& get(const std::shared_ptr<const T>& owner, std::string_view slot, Make&& make) {
        if (!owner) throw std::logic_error("GpuResources: no result for slot " + std::string(slot));
        auto key = std::make_pair(static_cast<const void*>(owner.get()), std::string(slot));
        auto it = entries_.find(key);
        if (it != entries_.end() && !same_owner(it->second.owner, owner)) {
            entries_.erase(it);  // the address was reused by another result: the old entry is stale
            it = entries_.end();
        }
        if (it == entries_.end()) {
            Entry e;
            e.owner = std::weak_ptr<const void>(owner);
            e.gl = std::make_shared<GL>(make());
            e.type = &typeid(GL);
            it = entries_.emplace(std::move(key), std::move(e)).first;
            ++made_;
        }
        if (*it->second.type != typeid(GL)) throw std::logic_error("GpuResources: slot " + std::string(slot) + " holds another type");
        return *static_cast<GL*>(it->second.gl.get());
    }
    // Frees the GL objects of results that no longer exist. Returns how many entries went.
    size_t collect() {
        size_t n = 0;
        for (auto it = entries_.begin(); it != entries_.end();)
            if (it->second.owner.expired()) it = entries_.erase(it), ++n;
            else ++it;
        return n;
    }
    void clear() { entries_.clear(); }
    size_t size() const { return entries_.size(); }
    // GL objects made so far (tests: a cache hit makes none).
    size_t made() const { return made_; }

private:
    struct Entry {
        std::weak_ptr<const void> owner;
        std::shared_ptr<void> gl;
        const std::type_info* type = nullptr;
    };
    template <class T>
    static bool same_owner(const std::weak_ptr<const void>& w, const std::shared_ptr<const T>& s) {
        return !w.expired() && !w.owner_before(s) && !s.owner_before(w);
    }
    std::map<std::pair<const void*, std::string>, Entry> entries_;
    size_t made_ = 0;
};
}  // namespace mesolab::gpu
