// mfhost — anisotropic Beckmann and GGX microfacet distributions (local frame, normal = +z).
//
// Separable Smith masking G = G1(wi) G1(wo) as Mitsuba 3's roughconductor. Visible-normal
// sampling: GGX by Heitz 2018 ("Sampling the GGX Distribution of Visible Normals"); Beckmann
// by exact inversion of the visible-slope marginal CDF (Newton–bisection on the closed-form CDF
// of Heitz & d'Eon 2014's 1D visible slope density), then the conditional slope is Gaussian.
#pragma once

#include "math.h"

namespace mf {

enum class MicrofacetType { Beckmann, GGX };

class Microfacet {
public:
    Microfacet(MicrofacetType type, float alpha_u, float alpha_v, bool sample_visible)
        : type_(type), au_(std::max(alpha_u, 1e-4f)), av_(std::max(alpha_v, 1e-4f)), visible_(sample_visible) {}

    float D(const Vec3& m) const;
    float Lambda(const Vec3& w) const;
    /// Smith G1 for direction w and microfacet normal m (0 if w is on the back side of m).
    float G1(const Vec3& w, const Vec3& m) const;
    float G(const Vec3& wi, const Vec3& wo, const Vec3& m) const { return G1(wi, m) * G1(wo, m); }
    /// Sample a microfacet normal for incident direction wi (wi.z > 0); returns its pdf.
    Vec3 sample(const Vec3& wi, const Vec2& u, float* pdf) const;
    float pdf(const Vec3& wi, const Vec3& m) const;
    MicrofacetType type() const { return type_; }

private:
    Vec3 sample_visible_ggx(const Vec3& wi, const Vec2& u) const;
    Vec3 sample_visible_beckmann(const Vec3& wi, const Vec2& u) const;

    MicrofacetType type_;
    float au_, av_;
    bool visible_;
};

}  // namespace mf
