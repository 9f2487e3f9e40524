#pragma once
// [SECTION] Results as bytes: what a stage kept on disk is written as (core/stage_store.h).
// Plain values are copied as their bytes (the same build on the same machine reads them back
// exactly: a stored result is the same bytes as a computed one), vectors and strings with their
// length first. A reader never reads past its end: a truncated or foreign blob throws BlobError,
// which the store treats as an absent entry, never as data.
#include <algorithm>
#include <cstdint>
#include <cstring>
#include <memory>
#include <stdexcept>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

namespace mesolab {

struct BlobError : std::runtime_error {
    using std::runtime_error::runtime_error;
};

class BlobWriter {
public:
    template <class T>
    void put(const T& v) {
        static_assert(std::is_trivially_copyable_v<T>, "put: plain values only (write members one by one)");
        bytes_.append(reinterpret_cast<const char*>(&v), sizeof v);
    }
    template <class T, class A>
    void put_vector(const std::vector<T, A>& v) {
        static_assert(std::is_trivially_copyable_v<T>, "put_vector: plain values only");
        put(uint64_t(v.size()));
        bytes_.append(reinterpret_cast<const char*>(v.data()), v.size() * sizeof(T));
    }
    void put_string(std::string_view s) {
        put(uint64_t(s.size()));
        bytes_.append(s.data(), s.size());
    }
    const std::string& bytes() const { return bytes_; }
    std::string take() { return std::move(bytes_); }

private:
    std::string bytes_;
};

class BlobReader {
public:
    explicit BlobReader(std::string_view bytes) : p_(bytes) {}
    template <class T>
    T get() {
        static_assert(std::is_trivially_copyable_v<T>, "get: plain values only");
        T v;
        std::memcpy(&v, take(sizeof v), sizeof v);
        return v;
    }
    template <class T, class A = std::allocator<T>>
    std::vector<T, A> get_vector() {
        static_assert(std::is_trivially_copyable_v<T>, "get_vector: plain values only");
        const uint64_t n = get<uint64_t>();
        if (n > p_.size() / std::max<size_t>(sizeof(T), 1)) throw BlobError("blob truncated (a vector of " + std::to_string(n) + " values)");
        std::vector<T, A> v(n);
        if (n) std::memcpy(v.data(), take(n * sizeof(T)), n * sizeof(T));
        return v;
    }
    std::string get_string() {
        const uint64_t n = get<uint64_t>();
        if (n > p_.size()) throw BlobError("blob truncated (a string of " + std::to_string(n) + " bytes)");
        return std::string(take(n), n);
    }
    // A count of items that follow, each at least `min_bytes` long: more than the rest holds is
    // a corrupt blob, not a reason to allocate.
    size_t get_count(size_t min_bytes = 1) {
        const uint64_t n = get<uint64_t>();
        if (n > p_.size() / std::max<size_t>(min_bytes, 1)) throw BlobError("blob truncated (a count of " + std::to_string(n) + ")");
        return size_t(n);
    }
    bool done() const { return p_.empty(); }

private:
    const char* take(size_t n) {
        if (n > p_.size()) throw BlobError("blob truncated");
        const char* q = p_.data();
        p_.remove_prefix(n);
        return q;
    }
    std::string_view p_;
};
}  // namespace mesolab
