// macrofacet for Mitsuba 3 — small helpers around the library's C ABI (include/macrofacet.h):
// error messages, unit directions, and the hashing that turns a ray into a tracking seed.
#pragma once

#include <macrofacet.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <stdexcept>
#include <string>
#include <vector>

namespace mfmi {

/// mf_last_error_message() of this thread.
inline std::string library_error() {
    size_t len = 0;
    mf_last_error_message(nullptr, 0, &len);
    std::vector<char> buf(len + 1, '\0');
    mf_last_error_message(buf.data(), buf.size(), nullptr);
    return buf[0] ? std::string(buf.data()) : std::string("unknown error");
}

/// Throws std::runtime_error("<what>: <library message>") unless `st` is MF_OK.
inline void check(mf_status st, const std::string& what) {
    if (st != MF_OK) throw std::runtime_error(what + ": " + library_error());
}

/// A unit vector in double precision (the library checks |v| = 1 to 1e-6; Mitsuba's float
/// directions are renormalised here rather than rejected).
inline mf_vec3 unit(double x, double y, double z) {
    double l = std::sqrt(x * x + y * y + z * z);
    if (!(l > 0) || !std::isfinite(l)) return mf_vec3{0, 0, 1};
    return mf_vec3{x / l, y / l, z / l};
}

/// splitmix64's finaliser: a bijective mix of 64 bits.
inline uint64_t mix64(uint64_t x) {
    x += 0x9e3779b97f4a7c15ull;
    x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
    x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
    return x ^ (x >> 31);
}

/// A 64-bit hash of float bit patterns (each word is mixed in, so every bit matters).
inline uint64_t hash_floats(const float* values, size_t n, uint64_t salt) {
    uint64_t h = mix64(salt);
    for (size_t i = 0; i < n; ++i) {
        uint32_t bits;
        std::memcpy(&bits, &values[i], sizeof(bits));
        h = mix64(h ^ bits);
    }
    return h;
}

/// A uniform number in [0, 1) from 64 bits.
inline double uniform_from_bits(uint64_t x) { return double(mix64(x) >> 11) * 0x1.0p-53; }

}  // namespace mfmi
