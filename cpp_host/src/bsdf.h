// mfhost — BSDFs. All directions are in the local shading frame (normal = +z); `wo` points
// towards the previous path vertex (the camera side), `wi` is the sampled/evaluated direction.
// Like Mitsuba 3, diffuse and (rough) conductors are one-sided (black from the back side; wrap
// them in `twosided`), dielectrics are two-sided by nature, `null` is an index-matched interface
// that only delimits media.
#pragma once

#include <memory>
#include <string>

#include "math.h"
#include "microfacet.h"
#include "microfacet_library.h"
#include "texture.h"

namespace mf {

struct BsdfSample {
    Vec3 wi;
    float pdf = 0;          // solid-angle pdf (for delta lobes: the discrete lobe probability)
    Rgb weight;             // f * |cos wi| / pdf
    bool delta = false;     // sampled a Dirac lobe
    bool transmission = false;
    float eta = 1.0f;       // relative IOR crossed (n_wi side / n_wo side); 1 for reflection
};

class Bsdf {
public:
    virtual ~Bsdf() = default;
    /// f(wo, wi) |cos wi| for the non-Dirac part, at texture coordinates uv (SurfaceHit::uv).
    virtual Rgb eval(const TexturePoint& uv, const Vec3& wo, const Vec3& wi) const = 0;
    virtual float pdf(const TexturePoint& uv, const Vec3& wo, const Vec3& wi) const = 0;
    virtual bool sample(const TexturePoint& uv, const Vec3& wo, float u_lobe, const Vec2& u, BsdfSample* s) const = 0;
    /// The same at uv = (0, 0) (untextured BSDFs, tests).
    Rgb eval(const Vec3& wo, const Vec3& wi) const { return eval(Vec2(), wo, wi); }
    float pdf(const Vec3& wo, const Vec3& wi) const { return pdf(Vec2(), wo, wi); }
    bool sample(const Vec3& wo, float u_lobe, const Vec2& u, BsdfSample* s) const { return sample(Vec2(), wo, u_lobe, u, s); }
    /// True when every lobe is a Dirac delta (next-event estimation is skipped).
    virtual bool is_delta() const { return false; }
    /// The `null` BSDF: the surface only delimits media and is skipped by rays.
    virtual bool is_null() const { return false; }
    /// Mitsuba's `mask`: the probability that the surface is absent at uv (1 - opacity). The
    /// integrator decides presence first; eval, pdf and sample describe the surface when present.
    virtual float transparency(const TexturePoint& uv) const {
        (void)uv;
        return 0.0f;
    }
    virtual std::string name() const = 0;
};

float fresnel_dielectric(float cos_i, float eta, float* cos_t);  // eta = n_inside / n_outside
float fresnel_conductor(float cos_i, float eta, float k);       // exact, complex IOR

struct ConductorIor {
    Rgb eta, k;
    bool perfect = false;  // material "none": F = 1
};
/// Conductor presets (RGB eta/k). Returns false for an unknown name.
bool conductor_preset(const std::string& name, ConductorIor* out);
std::string conductor_preset_list();
/// Named dielectric IORs (Mitsuba's table). Returns false for an unknown name.
bool dielectric_ior_by_name(const std::string& name, float* ior);

std::shared_ptr<Bsdf> make_diffuse(const Rgb& reflectance);
std::shared_ptr<Bsdf> make_diffuse(std::shared_ptr<const Texture> reflectance);
std::shared_ptr<Bsdf> make_conductor(const ConductorIor& ior, std::shared_ptr<const Texture> specular_reflectance);
std::shared_ptr<Bsdf> make_rough_conductor(const ConductorIor& ior, std::shared_ptr<const Texture> specular_reflectance,
                                           MicrofacetType type, float alpha_u, float alpha_v, bool sample_visible,
                                           bool height_correlated = false);
/// A rough conductor over a library distribution (GTR, transformed microsurfaces; seeds/001).
std::shared_ptr<Bsdf> make_rough_conductor(const ConductorIor& ior, std::shared_ptr<const Texture> specular_reflectance,
                                           std::shared_ptr<const LibraryMicrofacet> distribution);
std::shared_ptr<Bsdf> make_dielectric(float int_ior, float ext_ior, const Rgb& refl, const Rgb& trans);
/// Mitsuba's roughdielectric (microfacet reflection and refraction, Walter et al. 2007);
/// `reflectance` / `transmittance` may be null (no factor).
std::shared_ptr<Bsdf> make_rough_dielectric(float int_ior, float ext_ior, std::shared_ptr<const Texture> reflectance,
                                            std::shared_ptr<const Texture> transmittance, MicrofacetType type, float alpha_u,
                                            float alpha_v, bool sample_visible);
/// Mitsuba's thindielectric (a thin slab: mirror reflection or straight transmission).
std::shared_ptr<Bsdf> make_thin_dielectric(float int_ior, float ext_ior, const Rgb& refl, const Rgb& trans);
/// Mitsuba's plastic (smooth coating over a diffuse base; see bsdf.cpp).
std::shared_ptr<Bsdf> make_plastic(float int_ior, float ext_ior, std::shared_ptr<const Texture> diffuse,
                                   const Rgb& specular, bool nonlinear, float specular_sampling_weight);
float fresnel_diffuse_reflectance(float eta);
/// Mitsuba's roughplastic (rough coating over a diffuse base; see bsdf.cpp). `specular` may be
/// null (Mitsuba's default: no factor, mean 1).
std::shared_ptr<Bsdf> make_rough_plastic(float int_ior, float ext_ior, std::shared_ptr<const Texture> diffuse,
                                         std::shared_ptr<const Texture> specular, bool nonlinear, MicrofacetType type,
                                         float alpha, bool sample_visible);
std::shared_ptr<Bsdf> make_null_bsdf();
std::shared_ptr<Bsdf> make_twosided(std::shared_ptr<Bsdf> front, std::shared_ptr<Bsdf> back);
/// Mitsuba's mask: `nested` where present, absent with probability 1 - opacity (the texture's
/// eval_1, clamped to [0, 1]).
std::shared_ptr<Bsdf> make_mask(std::shared_ptr<const Texture> opacity, std::shared_ptr<Bsdf> nested);
/// Mitsuba's normalmap: `nested` in the shading frame tilted by the `normals` texture (values
/// 2 c - 1), with Mitsuba 3.9.1's side rules and optional shadowing (bsdf_normalmap.cpp).
std::shared_ptr<Bsdf> make_normal_map(std::shared_ptr<const Texture> normals, std::shared_ptr<Bsdf> nested, bool shadowing);

}  // namespace mf
