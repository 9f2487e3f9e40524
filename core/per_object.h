#pragma once
// [SECTION] Per-object stage results.
// A technique's stage computes one result per scene object that uses it (null for the others),
// once per distinct value of the material keys it reads: objects with equal keys share it.
#include "core/param.h"
#include "core/scene.h"
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace mesolab {

template <class T>
struct PerObject {
    std::vector<std::shared_ptr<const T>> items;
    const T* get(int object) const { return size_t(object) < items.size() ? items[size_t(object)].get() : nullptr; }
};

// Runs `make(index, object)` once per distinct fingerprint of the material `keys` among the objects
// using `technique` (and for which `wanted(object)` holds, when given).
template <class T, class Make>
PerObject<T> per_object(const Scene& s, const std::string& technique, const std::vector<std::string>& keys, const Make& make,
                        const std::function<bool(const SceneObject&)>& wanted = {}) {
    PerObject<T> out;
    out.items.resize(s.objects.size());
    std::map<std::string, std::shared_ptr<const T>> done;
    for (size_t i = 0; i < s.objects.size(); ++i) {
        const SceneObject& o = s.objects[i];
        if (o.technique != technique || (wanted && !wanted(o))) continue;
        std::string fp;
        for (const auto& k : keys) fp += value_canonical(*o.material.group().find(k), o.material.get(k), s.base_dir) + ";";
        auto it = done.find(fp);
        if (it == done.end()) it = done.emplace(fp, std::make_shared<const T>(make(int(i), o))).first;
        out.items[i] = it->second;
    }
    return out;
}
}  // namespace mesolab
