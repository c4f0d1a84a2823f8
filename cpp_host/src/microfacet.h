// mfhost — anisotropic Beckmann and GGX microfacet distributions (local frame, normal = +z).
//
// Smith masking-shadowing: separable G = G1(wi) G1(wo) as Mitsuba 3's roughconductor (default),
// or height-correlated G2 = 1 / (1 + Lambda(wi) + Lambda(wo)) (Heitz 2014, Eq. 99; exact for the
// thin-shell limit of a macrofacet medium) — an mfrender extension (`shadowing`). Visible-normal
// sampling: GGX by Heitz 2018 ("Sampling the GGX Distribution of Visible Normals"); Beckmann
// by exact inversion of the visible-slope marginal CDF (Newton–bisection on the closed-form CDF
// of Heitz & d'Eon 2014's 1D visible slope density), then the conditional slope is Gaussian.
#pragma once

#include "math.h"

namespace mf {

enum class MicrofacetType { Beckmann, GGX };

class Microfacet {
public:
    Microfacet(MicrofacetType type, float alpha_u, float alpha_v, bool sample_visible, bool height_correlated = false)
        : type_(type), au_(std::max(alpha_u, 1e-4f)), av_(std::max(alpha_v, 1e-4f)), visible_(sample_visible),
          height_correlated_(height_correlated) {}

    float D(const Vec3& m) const;
    float Lambda(const Vec3& w) const;
    /// Smith G1 for direction w and microfacet normal m (0 if w is on the back side of m).
    float G1(const Vec3& w, const Vec3& m) const;
    /// Masking-shadowing for the pair (wi, wo) and microfacet normal m: separable G1·G1 or
    /// height-correlated 1 / (1 + Lambda(wi) + Lambda(wo)) (0 if either is behind m).
    float G(const Vec3& wi, const Vec3& wo, const Vec3& m) const {
        if (!height_correlated_) return G1(wi, m) * G1(wo, m);
        if (dot(wi, m) * wi.z <= 0 || dot(wo, m) * wo.z <= 0) return 0.0f;
        return 1.0f / (1.0f + Lambda(wi) + Lambda(wo));
    }
    bool height_correlated() const { return height_correlated_; }
    /// Sample a microfacet normal for incident direction wi (wi.z > 0); returns its pdf.
    Vec3 sample(const Vec3& wi, const Vec2& u, float* pdf) const;
    float pdf(const Vec3& wi, const Vec3& m) const;
    MicrofacetType type() const { return type_; }
    float alpha_u() const { return au_; }
    float alpha_v() const { return av_; }

    /// Directional albedo of the rough dielectric interface of relative index eta seen from wi
    /// (wi.z > 0): the integral of F(<wi, m>) G1(wo, m) over the visible normals m of wi, with
    /// wo the mirror direction of wi about m (Mitsuba's eval_reflectance: the unit square of
    /// visible-normal samples integrated by an n x n Gauss-Legendre rule, n = 32 for eta > 1
    /// and 128 otherwise, where total internal reflection makes the integrand kinked).
    /// Uses visible-normal sampling whatever sample_visible is.
    float eval_reflectance(const Vec3& wi, float eta) const;
    /// The same for the light refracted through the interface: the integral of
    /// (1 - F(<wi, m>)) G1(wt, m) with wt the refraction of wi about m (Mitsuba's
    /// eval_transmittance, same quadrature).
    float eval_transmittance(const Vec3& wi, float eta) const;

private:
    Vec3 sample_visible_ggx(const Vec3& wi, const Vec2& u) const;
    Vec3 sample_visible_beckmann(const Vec3& wi, const Vec2& u) const;

    MicrofacetType type_;
    float au_, av_;
    bool visible_;
    bool height_correlated_;
};

}  // namespace mf
