// mfhost — host types at the library's C ABI: vectors in and out, unit directions, the last
// error message. Shared by the media the library implements (medium_macrofacet, medium_gpis).
#pragma once

#include <macrofacet.h>

#include <cmath>
#include <string>
#include <vector>

#include "math.h"

namespace mf {

inline mf_vec3 to_mf(const Vec3& v) { return mf_vec3{v.x, v.y, v.z}; }
inline Vec3 from_mf(const mf_vec3& v) { return Vec3(float(v.x), float(v.y), float(v.z)); }

/// A unit direction in double precision: the library checks |v| = 1 to 1e-6, so the host's float
/// directions are renormalised here rather than rejected (a zero vector becomes +z).
inline mf_vec3 to_mf_unit(const Vec3& v) {
    double x = v.x, y = v.y, z = v.z, l = std::sqrt(x * x + y * y + z * z);
    if (!(l > 0)) return mf_vec3{0, 0, 1};
    return mf_vec3{x / l, y / l, z / l};
}

/// mf_last_error_message() of this thread as a string ("unknown error" when it is empty).
inline std::string mf_last_error() {
    size_t len = 0;
    mf_last_error_message(nullptr, 0, &len);
    std::vector<char> buf(len + 1, '\0');
    mf_last_error_message(buf.data(), buf.size(), nullptr);
    std::string s(buf.data());
    return s.empty() ? std::string("unknown error") : s;
}

}  // namespace mf
