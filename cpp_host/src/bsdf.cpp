// mfhost — BSDF implementations (see bsdf.h).
#include "bsdf.h"

#include <map>

namespace mf {

float fresnel_dielectric(float cos_i, float eta, float* cos_t_out) {
    if (cos_i < 0) {
        eta = 1.0f / eta;
        cos_i = -cos_i;
    }
    float sin2_t = (1.0f - cos_i * cos_i) / (eta * eta);
    if (sin2_t >= 1.0f) {
        if (cos_t_out) *cos_t_out = 0.0f;
        return 1.0f;
    }
    float cos_t = std::sqrt(1.0f - sin2_t);
    float rs = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    float rp = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    if (cos_t_out) *cos_t_out = cos_t;
    return 0.5f * (rs * rs + rp * rp);
}

// The unpolarised reflectance of a conductor with complex IOR eta + i k, in real arithmetic (the
// closed form of the complex amplitudes' squared moduli; Born & Wolf, Principles of Optics,
// 14.4). With a = Re sqrt(n^2 - sin^2) and a2b2 = |n^2 - sin^2|:
//   Rs = (a2b2 - 2 a c + c^2) / (a2b2 + 2 a c + c^2),
//   Rp = Rs (c^2 a2b2 - 2 a c sin^2 + sin^4) / (c^2 a2b2 + 2 a c sin^2 + sin^4).
// std::complex division went through libgcc's __divdc3 (9 % of a roughconductor render).
float fresnel_conductor(float cos_i, float eta, float k) {
    double c = std::clamp(double(std::fabs(cos_i)), 0.0, 1.0);
    double c2 = c * c, sin2 = 1.0 - c2;
    double e = double(eta), kk = double(k);
    double t = e * e - kk * kk - sin2;
    double a2b2 = std::sqrt(t * t + 4.0 * e * e * kk * kk);
    // a2b2 >= |t| exactly; its rounded square root may fall an ulp short (k = 0, t < 0).
    double a = std::sqrt(std::max(0.0, 0.5 * (a2b2 + t)));
    double s1 = a2b2 + c2, s2 = 2.0 * a * c;
    // 0/0 only for eta = 1, k = 0 at grazing incidence: an index-matched interface, which
    // reflects nothing at every other angle.
    if (s1 + s2 == 0.0) return 0.0f;
    double rs = (s1 - s2) / (s1 + s2);
    double p1 = c2 * a2b2 + sin2 * sin2, p2 = s2 * sin2;
    double rp = rs * (p1 - p2) / (p1 + p2);
    return float(0.5 * (rs + rp));
}

// RGB complex IORs: spectral measurements integrated against the CIE matching functions and
// converted to linear sRGB, as tabulated in Tungsten's ComplexIorData.hpp (B. Bitterli), which
// derives from the same measured data Mitsuba ships. Values are relative to vacuum/air.
bool conductor_preset(const std::string& name, ConductorIor* out) {
    static const std::map<std::string, std::pair<Rgb, Rgb>> table = {
        {"Ag", {Rgb(0.1552646489f, 0.1167232965f, 0.1383806959f), Rgb(4.8283433224f, 3.1222459278f, 2.1469504455f)}},
        {"Al", {Rgb(1.6574599595f, 0.8803689579f, 0.5212287346f), Rgb(9.2238691996f, 6.2695232477f, 4.8370012281f)}},
        {"Au", {Rgb(0.1431189557f, 0.3749570432f, 1.4424785571f), Rgb(3.9831604247f, 2.3857207478f, 1.6032152899f)}},
        {"Cr", {Rgb(4.3696828663f, 2.9167024892f, 1.6547005413f), Rgb(5.2064337956f, 4.2313645277f, 3.7549467933f)}},
        {"Cu", {Rgb(0.2004376970f, 0.9240334304f, 1.1022119527f), Rgb(3.9129485033f, 2.4528477015f, 2.1421879552f)}},
    };
    if (name == "none") {
        out->perfect = true;
        out->eta = Rgb(0.0f);
        out->k = Rgb(1.0f);
        return true;
    }
    auto it = table.find(name);
    if (it == table.end()) return false;
    out->perfect = false;
    out->eta = it->second.first;
    out->k = it->second.second;
    return true;
}

std::string conductor_preset_list() { return "none, Ag, Al, Au, Cr, Cu"; }

bool dielectric_ior_by_name(const std::string& name, float* ior) {
    // Mitsuba's table of named indices of refraction (at 589 nm).
    static const std::map<std::string, float> table = {
        {"vacuum", 1.0f},        {"helium", 1.00004f},        {"hydrogen", 1.00013f},   {"air", 1.00028f},
        {"carbon dioxide", 1.00045f}, {"water", 1.3330f},     {"acetone", 1.36f},       {"ethanol", 1.361f},
        {"carbon tetrachloride", 1.461f}, {"glycerol", 1.4729f}, {"benzene", 1.501f},   {"silicone oil", 1.52045f},
        {"bromine", 1.661f},     {"water ice", 1.31f},        {"fused quartz", 1.458f}, {"pyrex", 1.470f},
        {"acrylic glass", 1.49f}, {"polypropylene", 1.49f},   {"bk7", 1.5046f},         {"sodium chloride", 1.544f},
        {"amber", 1.55f},        {"pet", 1.5750f},            {"diamond", 2.419f},
    };
    auto it = table.find(name);
    if (it == table.end()) return false;
    *ior = it->second;
    return true;
}

namespace {

Vec3 cosine_hemisphere(const Vec2& u) {
    float r = std::sqrt(u.x), phi = 2.0f * kPi * u.y;
    return Vec3(r * std::cos(phi), r * std::sin(phi), safe_sqrt(1.0f - u.x));
}

Rgb conductor_fresnel(const ConductorIor& ior, float cos_i) {
    if (ior.perfect) return Rgb(1.0f);
    return Rgb(fresnel_conductor(cos_i, ior.eta.r, ior.k.r), fresnel_conductor(cos_i, ior.eta.g, ior.k.g),
               fresnel_conductor(cos_i, ior.eta.b, ior.k.b));
}

class Diffuse final : public Bsdf {
public:
    explicit Diffuse(std::shared_ptr<const Texture> r) : r_(std::move(r)) {}
    Rgb eval(const TexturePoint& uv, const Vec3& wo, const Vec3& wi) const override {
        if (wo.z <= 0 || wi.z <= 0) return Rgb(0.0f);
        return r_->eval(uv) * (kInvPi * wi.z);
    }
    float pdf(const TexturePoint&, const Vec3& wo, const Vec3& wi) const override {
        if (wo.z <= 0 || wi.z <= 0) return 0.0f;
        return wi.z * kInvPi;
    }
    bool sample(const TexturePoint& uv, const Vec3& wo, float, const Vec2& u, BsdfSample* s) const override {
        if (wo.z <= 0) return false;
        s->wi = cosine_hemisphere(u);
        if (s->wi.z <= 0) return false;
        s->pdf = s->wi.z * kInvPi;
        s->weight = r_->eval(uv);
        s->delta = false;
        s->transmission = false;
        s->eta = 1.0f;
        return true;
    }
    std::string name() const override { return "diffuse"; }

private:
    std::shared_ptr<const Texture> r_;
};

class Conductor final : public Bsdf {
public:
    Conductor(const ConductorIor& ior, std::shared_ptr<const Texture> spec) : ior_(ior), spec_(std::move(spec)) {}
    Rgb eval(const TexturePoint&, const Vec3&, const Vec3&) const override { return Rgb(0.0f); }
    float pdf(const TexturePoint&, const Vec3&, const Vec3&) const override { return 0.0f; }
    bool sample(const TexturePoint& uv, const Vec3& wo, float, const Vec2&, BsdfSample* s) const override {
        if (wo.z <= 0) return false;
        s->wi = Vec3(-wo.x, -wo.y, wo.z);
        s->pdf = 1.0f;
        s->weight = spec_->eval(uv) * conductor_fresnel(ior_, wo.z);
        s->delta = true;
        s->transmission = false;
        s->eta = 1.0f;
        return true;
    }
    bool is_delta() const override { return true; }
    std::string name() const override { return "conductor"; }

private:
    ConductorIor ior_;
    std::shared_ptr<const Texture> spec_;
};

/// The microfacet distribution of a rough conductor: mfrender's own Beckmann/GGX by value, or a
/// library distribution (GTR, transforms) shared by reference.
inline const Microfacet& distribution(const Microfacet& d) { return d; }
inline const LibraryMicrofacet& distribution(const std::shared_ptr<const LibraryMicrofacet>& d) { return *d; }
inline Vec3 sample_normal(const Microfacet& d, const Vec3& wo, const Vec2& u, float, float* pdf) { return d.sample(wo, u, pdf); }
inline Vec3 sample_normal(const LibraryMicrofacet& d, const Vec3& wo, const Vec2& u, float u3, float* pdf) {
    return d.sample(wo, u, u3, pdf);
}

template <class Holder>
class RoughConductor final : public Bsdf {
public:
    RoughConductor(const ConductorIor& ior, std::shared_ptr<const Texture> spec, Holder mf)
        : ior_(ior), spec_(std::move(spec)), mf_(std::move(mf)) {}
    Rgb eval(const TexturePoint& uv, const Vec3& wo, const Vec3& wi) const override {
        if (wo.z <= 0 || wi.z <= 0) return Rgb(0.0f);
        Vec3 h = normalize(wo + wi);
        float D = dist().D(h);
        if (D == 0) return Rgb(0.0f);
        float G = dist().G(wo, wi, h);
        return spec_->eval(uv) * conductor_fresnel(ior_, dot(wo, h)) * (D * G / (4.0f * wo.z));
    }
    float pdf(const TexturePoint&, const Vec3& wo, const Vec3& wi) const override {
        if (wo.z <= 0 || wi.z <= 0) return 0.0f;
        Vec3 h = normalize(wo + wi);
        float d = dot(wo, h);
        if (d <= 0) return 0.0f;
        return dist().pdf(wo, h) / (4.0f * d);
    }
    // u_lobe (one lobe here) is the third uniform of the library's visible-normal sampler.
    bool sample(const TexturePoint& uv, const Vec3& wo, float u_lobe, const Vec2& u, BsdfSample* s) const override {
        if (wo.z <= 0) return false;
        float mpdf;
        Vec3 m = sample_normal(dist(), wo, u, u_lobe, &mpdf);
        if (!(mpdf > 0)) return false;
        float d = dot(wo, m);
        if (d <= 0) return false;
        Vec3 wi = m * (2.0f * d) - wo;
        if (wi.z <= 0) return false;
        s->wi = wi;
        s->pdf = mpdf / (4.0f * d);
        if (!(s->pdf > 0) || !std::isfinite(s->pdf)) return false;
        s->weight = eval(uv, wo, wi) / s->pdf;
        s->delta = false;
        s->transmission = false;
        s->eta = 1.0f;
        return s->weight.finite();
    }
    std::string name() const override { return "roughconductor"; }

private:
    const auto& dist() const { return distribution(mf_); }

    ConductorIor ior_;
    std::shared_ptr<const Texture> spec_;
    Holder mf_;
};

class Dielectric final : public Bsdf {
public:
    Dielectric(float eta, const Rgb& r, const Rgb& t) : eta_(eta), r_(r), t_(t) {}
    Rgb eval(const TexturePoint&, const Vec3&, const Vec3&) const override { return Rgb(0.0f); }
    float pdf(const TexturePoint&, const Vec3&, const Vec3&) const override { return 0.0f; }
    bool sample(const TexturePoint&, const Vec3& wo, float u_lobe, const Vec2&, BsdfSample* s) const override {
        if (wo.z == 0) return false;
        float cos_t;
        float F = fresnel_dielectric(wo.z, eta_, &cos_t);
        s->delta = true;
        if (u_lobe < F) {
            s->wi = Vec3(-wo.x, -wo.y, wo.z);
            s->pdf = F;
            s->weight = r_;
            s->transmission = false;
            s->eta = 1.0f;
        } else {
            float eta_ti = wo.z > 0 ? eta_ : 1.0f / eta_;  // index on the wi side / wo side
            s->wi = Vec3(-wo.x / eta_ti, -wo.y / eta_ti, wo.z > 0 ? -cos_t : cos_t);
            s->pdf = 1.0f - F;
            // Radiance is compressed/expanded by the change of solid angle.
            s->weight = t_ / (eta_ti * eta_ti);
            s->transmission = true;
            s->eta = eta_ti;
        }
        return true;
    }
    bool is_delta() const override { return true; }
    std::string name() const override { return "dielectric"; }

private:
    float eta_;
    Rgb r_, t_;
};

/// Mitsuba's roughdielectric: microfacet reflection and refraction at a rough interface of
/// relative index eta = int_ior / ext_ior (Walter et al. 2007, "Microfacet Models for Refraction
/// through Rough Surfaces", Eqs. 20-21 for f, 14 and 17 for the half-vector Jacobians), two-sided
/// (wo.z < 0 is inside). Sampling: a visible normal m of the side wo is on, then reflection with
/// probability F(<wo, m>), else refraction; the weight of radiance crossing into the medium of
/// index ratio eta_t / eta_i is scaled by (eta_i / eta_t)^2 (solid angle compression).
class RoughDielectric final : public Bsdf {
public:
    RoughDielectric(float eta, std::shared_ptr<const Texture> r, std::shared_ptr<const Texture> t, MicrofacetType type,
                    float au, float av, bool vis)
        : eta_(eta), r_(std::move(r)), t_(std::move(t)), mf_(type, au, av, vis) {}
    Rgb eval(const TexturePoint& uv, const Vec3& wo, const Vec3& wi) const override {
        float pdf;
        return eval_pdf(uv, wo, wi, &pdf);
    }
    float pdf(const TexturePoint& uv, const Vec3& wo, const Vec3& wi) const override {
        float pdf;
        eval_pdf(uv, wo, wi, &pdf);
        return pdf;
    }
    bool sample(const TexturePoint& uv, const Vec3& wo, float u_lobe, const Vec2& u, BsdfSample* s) const override {
        if (wo.z == 0) return false;
        const float side = wo.z > 0 ? 1.0f : -1.0f;
        float mpdf;
        Vec3 m = mf_.sample(wo * side, u, &mpdf);  // on the +z side
        if (!(mpdf > 0)) return false;
        float cos_t;
        const float c = dot(wo, m);
        const float F = fresnel_dielectric(c, eta_, &cos_t);
        Vec3 wi;
        if (u_lobe <= F) {
            wi = m * (2.0f * c) - wo;
            if (wi.z * wo.z <= 0) return false;
        } else {
            // refraction about m: eta_ti = index on the wo side / index on the wi side
            float eta_ti = c > 0 ? 1.0f / eta_ : eta_;
            wi = m * (c * eta_ti - (c > 0 ? cos_t : -cos_t)) - wo * eta_ti;
            if (wi.z * wo.z >= 0) return false;
        }
        float pdf;
        Rgb f = eval_pdf(uv, wo, wi, &pdf);
        if (!(pdf > 0) || !std::isfinite(pdf)) return false;
        s->wi = wi;
        s->pdf = pdf;
        s->weight = f / pdf;
        s->delta = false;
        s->transmission = wi.z * wo.z < 0;
        // relative IOR crossed: index on the wi side / index on the wo side
        s->eta = s->transmission ? (wo.z > 0 ? eta_ : 1.0f / eta_) : 1.0f;
        return s->weight.finite();
    }
    std::string name() const override { return "roughdielectric"; }

private:
    /// f |cos wi| and the pdf of sample() (Mitsuba's eval / pdf, radiance transport).
    Rgb eval_pdf(const TexturePoint& uv, const Vec3& wo, const Vec3& wi, float* pdf_out) const {
        *pdf_out = 0.0f;
        if (wo.z == 0 || wi.z == 0) return Rgb(0.0f);
        const bool reflect = wo.z * wi.z > 0;
        const float eta = wo.z > 0 ? eta_ : 1.0f / eta_;  // index on the wi side / wo side when refracting
        Vec3 m = normalize(wo + wi * (reflect ? 1.0f : eta));
        if (m.z < 0) m = -m;
        const float cw = dot(wo, m), ci = dot(wi, m);
        // a microfacet seen from the back by either direction contributes nothing (Smith G1 = 0)
        if (cw * wo.z <= 0 || ci * wi.z <= 0) return Rgb(0.0f);
        const float D = mf_.D(m), G = mf_.G(wo, wi, m);
        const float F = fresnel_dielectric(cw, eta_, nullptr);
        const float side = wo.z > 0 ? 1.0f : -1.0f;
        float pdf_m = mf_.pdf(wo * side, m);
        Rgb value;
        if (reflect) {
            value = Rgb(F * D * G / (4.0f * std::fabs(wo.z)));
            if (r_) value *= r_->eval(uv);
            *pdf_out = pdf_m * F / (4.0f * std::fabs(ci));
        } else {
            const float denom = cw + eta * ci;
            const float jac = eta * eta * std::fabs(ci) / (denom * denom);  // dm / dwi (Walter Eq. 17)
            value = Rgb(std::fabs((1.0f - F) * D * G * cw * ci / (wo.z * denom * denom)));  // includes 1/eta^2
            if (t_) value *= t_->eval(uv);
            *pdf_out = pdf_m * (1.0f - F) * jac;
        }
        return value;
    }
    float eta_;
    std::shared_ptr<const Texture> r_, t_;
    Microfacet mf_;
};

/// Mitsuba's thindielectric: a thin slab with two parallel interfaces; light either reflects
/// (mirror) or passes straight through. With the Fresnel reflectance R of one interface, the
/// slab's total reflectance sums the inter-reflections: R' = R + T^2 R / (1 - R^2), T = 1 - R.
class ThinDielectric final : public Bsdf {
public:
    ThinDielectric(float eta, const Rgb& r, const Rgb& t) : eta_(eta), r_(r), t_(t) {}
    Rgb eval(const TexturePoint&, const Vec3&, const Vec3&) const override { return Rgb(0.0f); }
    float pdf(const TexturePoint&, const Vec3&, const Vec3&) const override { return 0.0f; }
    bool sample(const TexturePoint&, const Vec3& wo, float u_lobe, const Vec2&, BsdfSample* s) const override {
        if (wo.z == 0) return false;
        float R = fresnel_dielectric(std::fabs(wo.z), eta_, nullptr), T = 1.0f - R;
        if (R < 1.0f) R += T * T * R / (1.0f - R * R);
        s->delta = true;
        s->eta = 1.0f;
        if (u_lobe < R) {
            s->wi = Vec3(-wo.x, -wo.y, wo.z);
            s->pdf = R;
            s->weight = r_;
            s->transmission = false;
        } else {
            s->wi = -wo;
            s->pdf = 1.0f - R;
            s->weight = t_;
            s->transmission = true;
        }
        return true;
    }
    bool is_delta() const override { return true; }
    std::string name() const override { return "thindielectric"; }

private:
    float eta_;
    Rgb r_, t_;
};

/// Hemispherical average of the dielectric Fresnel reflectance for light arriving from the side
/// of relative index `eta` (2 ∫ F(cos) cos d cos; Simpson quadrature, exact to ~1e-6 — Mitsuba
/// uses polynomial fits of the same integral, accurate to ~0.1 %).
float fresnel_diffuse_reflectance(float eta) {
    const int n = 512;  // even
    double sum = 0;
    for (int i = 0; i <= n; ++i) {
        double c = double(i) / n;
        double w = (i == 0 || i == n) ? 1 : (i % 2 ? 4 : 2);
        sum += w * double(fresnel_dielectric(float(c), eta, nullptr)) * c;
    }
    return float(2.0 * sum / (3.0 * n));
}

/// Mitsuba's plastic: a smooth dielectric coating (delta specular reflection, Fresnel F) over a
/// diffuse base whose light is refracted in and out, with the base's internal reflections
/// summed: f_d = R_d / (1 - Fdr_int) (or R_d / (1 - R_d Fdr_int) with `nonlinear`) x
/// (1 - F(cos_o)) (1 - F(cos_i)) / (eta^2 pi). The specular lobe is picked with probability
/// F(cos_o) w_s / (F(cos_o) w_s + (1 - F(cos_o)) (1 - w_s)), w_s = mean specular / (mean
/// specular + mean diffuse reflectance), as Mitsuba does.
class Plastic final : public Bsdf {
public:
    Plastic(float eta, std::shared_ptr<const Texture> diffuse, const Rgb& specular, bool nonlinear, float spec_weight)
        : eta_(eta), diffuse_(std::move(diffuse)), specular_(specular), nonlinear_(nonlinear), spec_weight_(spec_weight),
          fdr_int_(fresnel_diffuse_reflectance(1.0f / eta)) {}
    Rgb eval(const TexturePoint& uv, const Vec3& wo, const Vec3& wi) const override {
        if (wo.z <= 0 || wi.z <= 0) return Rgb(0.0f);
        return diffuse_term(uv, wo.z, wi.z) * wi.z;
    }
    float pdf(const TexturePoint&, const Vec3& wo, const Vec3& wi) const override {
        if (wo.z <= 0 || wi.z <= 0) return 0.0f;
        return prob_diffuse(wo.z) * wi.z * kInvPi;
    }
    bool sample(const TexturePoint& uv, const Vec3& wo, float u_lobe, const Vec2& u, BsdfSample* s) const override {
        if (wo.z <= 0) return false;
        float F_o = fresnel_dielectric(wo.z, eta_, nullptr);
        float p_d = prob_diffuse(wo.z), p_s = 1.0f - p_d;
        s->transmission = false;
        s->eta = 1.0f;
        if (u_lobe < p_s) {
            s->wi = Vec3(-wo.x, -wo.y, wo.z);
            s->pdf = p_s;
            s->weight = specular_ * (F_o / p_s);
            s->delta = true;
            return true;
        }
        float r = std::sqrt(u.x), phi = 2.0f * kPi * u.y;
        s->wi = Vec3(r * std::cos(phi), r * std::sin(phi), safe_sqrt(1.0f - u.x));
        if (s->wi.z <= 0) return false;
        s->pdf = p_d * s->wi.z * kInvPi;
        s->weight = diffuse_term(uv, wo.z, s->wi.z) * (kPi / p_d);  // f cos / (p_d cos / pi)
        s->delta = false;
        return true;
    }
    std::string name() const override { return "plastic"; }

private:
    /// f_d without the cosine.
    Rgb diffuse_term(const TexturePoint& uv, float cos_o, float cos_i) const {
        Rgb d = diffuse_->eval(uv);
        for (int c = 0; c < 3; ++c) d[c] /= 1.0f - (nonlinear_ ? d[c] * fdr_int_ : fdr_int_);
        float F_o = fresnel_dielectric(cos_o, eta_, nullptr), F_i = fresnel_dielectric(cos_i, eta_, nullptr);
        return d * ((1.0f - F_o) * (1.0f - F_i) * kInvPi / (eta_ * eta_));
    }
    float prob_diffuse(float cos_o) const {
        float F_o = fresnel_dielectric(cos_o, eta_, nullptr);
        float ps = F_o * spec_weight_, pd = (1.0f - F_o) * (1.0f - spec_weight_);
        return ps + pd > 0 ? pd / (ps + pd) : 1.0f;
    }
    float eta_;
    std::shared_ptr<const Texture> diffuse_;
    Rgb specular_;
    bool nonlinear_;
    float spec_weight_;
    float fdr_int_;
};

/// Mitsuba's roughplastic: a rough dielectric coating (isotropic microfacet reflection, Fresnel
/// F, Smith G) over a diffuse base seen through it. The base's light is attenuated on the way in
/// and out by the coating's rough transmittance t(cos) (the directional transmittance of the
/// rough interface, Microfacet::eval_transmittance), tabulated at 64 cosines in [0, 1] (the first
/// at 1e-6) and interpolated linearly, and its internal reflections are summed with the
/// hemispherical average R_i = 2 mean(r(mu) mu) of the interface's reflectance from inside,
/// over the same 64 cosines, as Mitsuba does:
///   f = F D G / (4 cos_i cos_o) + R_d / (1 - R_i) (or R_d / (1 - R_d R_i), nonlinear)
///       t(cos_i) t(cos_o) / (eta^2 pi).
/// The glossy lobe is sampled with probability (1 - t_i) w_s / ((1 - t_i) w_s + t_i (1 - w_s)),
/// w_s = mean specular / (mean specular + mean diffuse reflectance).
class RoughPlastic final : public Bsdf {
public:
    static constexpr int kTableSize = 64;
    RoughPlastic(float eta, std::shared_ptr<const Texture> diffuse, std::shared_ptr<const Texture> specular, bool nonlinear,
                 MicrofacetType type, float alpha, bool sample_visible)
        : eta_(eta), diffuse_(std::move(diffuse)), specular_(std::move(specular)), nonlinear_(nonlinear),
          mf_(type, alpha, alpha, sample_visible) {
        float s_mean = specular_ ? specular_->mean() : 1.0f, d_mean = diffuse_->mean();
        spec_weight_ = s_mean + d_mean > 0 ? s_mean / (s_mean + d_mean) : 0.5f;
        double internal = 0;
        for (int i = 0; i < kTableSize; ++i) {
            float mu = std::max(1e-6f, float(i) / float(kTableSize - 1));
            Vec3 wi(std::sqrt(1 - mu * mu), 0.0f, mu);
            external_t_[i] = mf_.eval_transmittance(wi, eta_);
            internal += double(mf_.eval_reflectance(wi, 1.0f / eta_)) * mu;
        }
        internal_r_ = float(2.0 * internal / kTableSize);
    }
    Rgb eval(const TexturePoint& uv, const Vec3& wo, const Vec3& wi) const override {
        if (wo.z <= 0 || wi.z <= 0) return Rgb(0.0f);
        return eval_cos(uv, wo, wi);
    }
    float pdf(const TexturePoint&, const Vec3& wo, const Vec3& wi) const override {
        if (wo.z <= 0 || wi.z <= 0) return 0.0f;
        return pdf_cos(wo, wi);
    }
    bool sample(const TexturePoint& uv, const Vec3& wo, float u_lobe, const Vec2& u, BsdfSample* s) const override {
        if (wo.z <= 0) return false;
        Vec3 wi;
        if (u_lobe < prob_specular(wo.z)) {
            float mpdf;
            Vec3 m = mf_.sample(wo, u, &mpdf);
            wi = m * (2.0f * dot(wo, m)) - wo;
        } else {
            wi = cosine_hemisphere(u);
        }
        if (wi.z <= 0) return false;
        s->wi = wi;
        s->pdf = pdf_cos(wo, wi);
        if (!(s->pdf > 0) || !std::isfinite(s->pdf)) return false;
        s->weight = eval_cos(uv, wo, wi) / s->pdf;
        s->delta = false;
        s->transmission = false;
        s->eta = 1.0f;
        return s->weight.finite();
    }
    std::string name() const override { return "roughplastic"; }

private:
    /// t(cos) from the table (linear interpolation; cos in [0, 1]).
    float external_t(float c) const {
        float x = c * float(kTableSize - 1);
        int i = std::min(int(x), kTableSize - 2);
        float f = x - float(i);
        return (1.0f - f) * external_t_[i] + f * external_t_[i + 1];
    }
    float prob_specular(float cos_o) const {
        float t = external_t(cos_o);
        float ps = (1.0f - t) * spec_weight_, pd = t * (1.0f - spec_weight_);
        return ps + pd > 0 ? ps / (ps + pd) : 0.0f;
    }
    float pdf_cos(const Vec3& wo, const Vec3& wi) const {
        float p_s = prob_specular(wo.z);
        Vec3 h = normalize(wo + wi);
        float d = dot(wi, h);
        float spec = d > 0 ? mf_.pdf(wo, h) / (4.0f * d) : 0.0f;
        return p_s * spec + (1.0f - p_s) * wi.z * kInvPi;
    }
    Rgb eval_cos(const TexturePoint& uv, const Vec3& wo, const Vec3& wi) const {
        Vec3 h = normalize(wo + wi);
        float spec = fresnel_dielectric(dot(wo, h), eta_, nullptr) * mf_.D(h) * mf_.G(wo, wi, h) / (4.0f * wo.z);
        Rgb value = specular_ ? specular_->eval(uv) * spec : Rgb(spec);
        Rgb d = diffuse_->eval(uv);
        for (int c = 0; c < 3; ++c) d[c] /= 1.0f - (nonlinear_ ? d[c] * internal_r_ : internal_r_);
        return value + d * (kInvPi / (eta_ * eta_) * wi.z * external_t(wo.z) * external_t(wi.z));
    }
    float eta_;
    std::shared_ptr<const Texture> diffuse_, specular_;
    bool nonlinear_;
    Microfacet mf_;
    float spec_weight_ = 0.5f;
    float external_t_[kTableSize];
    float internal_r_ = 0;
};

class NullBsdf final : public Bsdf {
public:
    Rgb eval(const TexturePoint&, const Vec3&, const Vec3&) const override { return Rgb(0.0f); }
    float pdf(const TexturePoint&, const Vec3&, const Vec3&) const override { return 0.0f; }
    bool sample(const TexturePoint&, const Vec3&, float, const Vec2&, BsdfSample*) const override { return false; }
    bool is_delta() const override { return true; }
    bool is_null() const override { return true; }
    std::string name() const override { return "null"; }
};

class TwoSided final : public Bsdf {
public:
    TwoSided(std::shared_ptr<Bsdf> f, std::shared_ptr<Bsdf> b) : f_(std::move(f)), b_(std::move(b)) {}
    static Vec3 flip(const Vec3& v) { return Vec3(v.x, v.y, -v.z); }
    Rgb eval(const TexturePoint& uv, const Vec3& wo, const Vec3& wi) const override {
        return wo.z >= 0 ? f_->eval(uv, wo, wi) : b_->eval(uv, flip(wo), flip(wi));
    }
    float pdf(const TexturePoint& uv, const Vec3& wo, const Vec3& wi) const override {
        return wo.z >= 0 ? f_->pdf(uv, wo, wi) : b_->pdf(uv, flip(wo), flip(wi));
    }
    bool sample(const TexturePoint& uv, const Vec3& wo, float ul, const Vec2& u, BsdfSample* s) const override {
        if (wo.z >= 0) return f_->sample(uv, wo, ul, u, s);
        if (!b_->sample(uv, flip(wo), ul, u, s)) return false;
        s->wi = flip(s->wi);
        return true;
    }
    bool is_delta() const override { return f_->is_delta() && b_->is_delta(); }
    std::string name() const override { return "twosided"; }

private:
    std::shared_ptr<Bsdf> f_, b_;
};

class Mask final : public Bsdf {
public:
    Mask(std::shared_ptr<const Texture> opacity, std::shared_ptr<Bsdf> nested) : opacity_(std::move(opacity)), nested_(std::move(nested)) {}
    Rgb eval(const TexturePoint& uv, const Vec3& wo, const Vec3& wi) const override { return nested_->eval(uv, wo, wi); }
    float pdf(const TexturePoint& uv, const Vec3& wo, const Vec3& wi) const override { return nested_->pdf(uv, wo, wi); }
    bool sample(const TexturePoint& uv, const Vec3& wo, float ul, const Vec2& u, BsdfSample* s) const override {
        return nested_->sample(uv, wo, ul, u, s);
    }
    bool is_delta() const override { return nested_->is_delta(); }
    // Mitsuba clamps the opacity to [0, 1]
    float transparency(const TexturePoint& uv) const override { return 1.0f - std::clamp(opacity_->eval_1(uv), 0.0f, 1.0f); }
    std::string name() const override { return "mask"; }

private:
    std::shared_ptr<const Texture> opacity_;
    std::shared_ptr<Bsdf> nested_;
};

}  // namespace

std::shared_ptr<Bsdf> make_mask(std::shared_ptr<const Texture> opacity, std::shared_ptr<Bsdf> nested) {
    return std::make_shared<Mask>(std::move(opacity), std::move(nested));
}
std::shared_ptr<Bsdf> make_diffuse(const Rgb& r) { return std::make_shared<Diffuse>(make_constant_texture(r)); }
std::shared_ptr<Bsdf> make_diffuse(std::shared_ptr<const Texture> r) { return std::make_shared<Diffuse>(std::move(r)); }
std::shared_ptr<Bsdf> make_conductor(const ConductorIor& ior, std::shared_ptr<const Texture> s) {
    return std::make_shared<Conductor>(ior, std::move(s));
}
std::shared_ptr<Bsdf> make_rough_conductor(const ConductorIor& ior, std::shared_ptr<const Texture> s, MicrofacetType t,
                                           float au, float av, bool vis, bool hc) {
    return std::make_shared<RoughConductor<Microfacet>>(ior, s, Microfacet(t, au, av, vis, hc));
}
std::shared_ptr<Bsdf> make_rough_conductor(const ConductorIor& ior, std::shared_ptr<const Texture> s,
                                           std::shared_ptr<const LibraryMicrofacet> distribution) {
    return std::make_shared<RoughConductor<std::shared_ptr<const LibraryMicrofacet>>>(ior, s, std::move(distribution));
}
std::shared_ptr<Bsdf> make_dielectric(float int_ior, float ext_ior, const Rgb& r, const Rgb& t) {
    return std::make_shared<Dielectric>(int_ior / ext_ior, r, t);
}
std::shared_ptr<Bsdf> make_rough_dielectric(float int_ior, float ext_ior, std::shared_ptr<const Texture> r,
                                            std::shared_ptr<const Texture> t, MicrofacetType type, float au, float av, bool vis) {
    return std::make_shared<RoughDielectric>(int_ior / ext_ior, std::move(r), std::move(t), type, au, av, vis);
}
std::shared_ptr<Bsdf> make_thin_dielectric(float int_ior, float ext_ior, const Rgb& r, const Rgb& t) {
    return std::make_shared<ThinDielectric>(int_ior / ext_ior, r, t);
}
std::shared_ptr<Bsdf> make_plastic(float int_ior, float ext_ior, std::shared_ptr<const Texture> diffuse,
                                   const Rgb& specular, bool nonlinear, float specular_sampling_weight) {
    return std::make_shared<Plastic>(int_ior / ext_ior, std::move(diffuse), specular, nonlinear, specular_sampling_weight);
}
std::shared_ptr<Bsdf> make_rough_plastic(float int_ior, float ext_ior, std::shared_ptr<const Texture> diffuse,
                                        std::shared_ptr<const Texture> specular, bool nonlinear, MicrofacetType type,
                                        float alpha, bool sample_visible) {
    return std::make_shared<RoughPlastic>(int_ior / ext_ior, std::move(diffuse), std::move(specular), nonlinear, type, alpha,
                                          sample_visible);
}
std::shared_ptr<Bsdf> make_null_bsdf() { return std::make_shared<NullBsdf>(); }
std::shared_ptr<Bsdf> make_twosided(std::shared_ptr<Bsdf> f, std::shared_ptr<Bsdf> b) {
    return std::make_shared<TwoSided>(std::move(f), std::move(b));
}

}  // namespace mf
