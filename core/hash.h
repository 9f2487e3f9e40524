#pragma once
// [SECTION] Hashes written once: FNV-1a over bytes (the stages' and the truths' keys, the
// fingerprints of files' contents) and splitmix64 (Steele, Lea and Flood 2014: the random
// streams and the fixed jitter). Neither is cryptographic; both are fixed forever, since the
// caches' keys on disk depend on their values.
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

namespace mesolab {

// FNV-1a, 64 bits: add bytes in order, read h.
struct Fnv1a {
    static constexpr uint64_t kOffset = 0xcbf29ce484222325ull, kPrime = 0x100000001b3ull;
    uint64_t h = kOffset;
    void add(const void* p, size_t n) {
        const auto* b = static_cast<const unsigned char*>(p);
        for (size_t i = 0; i < n; ++i) h = (h ^ b[i]) * kPrime;
    }
    void add(std::string_view s) { add(s.data(), s.size()); }
    // The string's length (8 bytes) and then its bytes: a list of strings hashes unambiguously.
    void add_sized(const std::string& s) {
        const uint64_t n = s.size();
        add(&n, sizeof n);
        add(s.data(), s.size());
    }
};

inline uint64_t fnv1a(std::string_view s) {
    Fnv1a f;
    f.add(s);
    return f.h;
}

// splitmix64's output function: a bijection of 64-bit words that mixes every bit into every other.
inline uint64_t splitmix64_mix(uint64_t z) {
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
}
// splitmix64's increment: the golden ratio's 64-bit fraction, odd.
constexpr uint64_t kSplitmix64Gamma = 0x9e3779b97f4a7c15ull;
// One step of splitmix64 from state x: mix(x + γ).
inline uint64_t splitmix64(uint64_t x) { return splitmix64_mix(x + kSplitmix64Gamma); }

}  // namespace mesolab
