// mfhost — a microfacet distribution owned by the macrofacet library (mf_ndf): GTR (seeds/001
// Appendix A) and the tangent-plane transforms of Beckmann/GGX/GTR (seeds/001 §4), so that a
// `roughconductor` and a thin macrofacet shell share D, Smith's Lambda and the exact
// visible-normal sampler. Same interface as Microfacet (local frame, normal = +z, tangent = +x).
#pragma once

#include <memory>
#include <string>

#include "math.h"

struct mf_ndf;
struct mf_params;

namespace mf {

class LibraryMicrofacet {
public:
    /// Takes ownership of `ndf` (from mf_ndf_new).
    LibraryMicrofacet(mf_ndf* ndf, bool height_correlated);
    ~LibraryMicrofacet();
    LibraryMicrofacet(const LibraryMicrofacet&) = delete;
    LibraryMicrofacet& operator=(const LibraryMicrofacet&) = delete;

    float D(const Vec3& m) const;
    float Lambda(const Vec3& w) const;
    float G1(const Vec3& w, const Vec3& m) const {
        if (dot(w, m) * w.z <= 0) return 0.0f;
        return 1.0f / (1.0f + Lambda(w));
    }
    /// Separable G1·G1 (Mitsuba's roughconductor) or height-correlated 1/(1 + Λi + Λo).
    float G(const Vec3& wi, const Vec3& wo, const Vec3& m) const {
        if (!height_correlated_) return G1(wi, m) * G1(wo, m);
        if (dot(wi, m) * wi.z <= 0 || dot(wo, m) * wo.z <= 0) return 0.0f;
        return 1.0f / (1.0f + Lambda(wi) + Lambda(wo));
    }
    /// A visible normal for wi (exact sampling of <wi, m> D(m)) and its density; the library
    /// takes three uniforms, the third from `u3`.
    Vec3 sample(const Vec3& wi, const Vec2& u, float u3, float* pdf) const;
    float pdf(const Vec3& wi, const Vec3& m) const;

private:
    mf_ndf* ndf_;
    bool height_correlated_;
};

/// Builds the library distribution from a filled parameter set (mf_ndf_new); throws Error with
/// the library's message (which names the parameter) on failure.
std::shared_ptr<LibraryMicrofacet> make_library_microfacet(const mf_params* params, bool height_correlated,
                                                           const std::string& what);

}  // namespace mf
