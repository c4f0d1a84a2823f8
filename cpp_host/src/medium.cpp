// mfhost — media and phase functions (see medium.h).
#include "medium.h"

namespace mf {

namespace {
Vec3 uniform_sphere(const Vec2& u) {
    float z = 1.0f - 2.0f * u.x;
    float r = safe_sqrt(1.0f - z * z), phi = 2.0f * kPi * u.y;
    return Vec3(r * std::cos(phi), r * std::sin(phi), z);
}
}  // namespace

bool IsotropicPhase::sample(const MediumInteraction&, const Vec3&, Sampler& sampler, Vec3* wi, float* pdf,
                            Rgb* weight) const {
    Vec2 u = sampler.next_2d();
    *wi = uniform_sphere(u);
    *pdf = kInv4Pi;
    *weight = Rgb(1.0f);
    return true;
}

float HenyeyGreenstein::value(float cos_theta) const {
    float denom = 1.0f + g_ * g_ - 2.0f * g_ * cos_theta;
    return kInv4Pi * (1.0f - g_ * g_) / (denom * std::sqrt(std::max(denom, 1e-12f)));
}

bool HenyeyGreenstein::sample(const MediumInteraction&, const Vec3& wo, Sampler& sampler, Vec3* wi, float* pdf,
                              Rgb* weight) const {
    Vec2 u = sampler.next_2d();
    float cos_theta;
    if (std::fabs(g_) < 1e-3f) {
        cos_theta = 1.0f - 2.0f * u.x;
    } else {
        float s = (1.0f - g_ * g_) / (1.0f - g_ + 2.0f * g_ * u.x);
        cos_theta = (1.0f + g_ * g_ - s * s) / (2.0f * g_);
    }
    cos_theta = std::clamp(cos_theta, -1.0f, 1.0f);
    float sin_theta = safe_sqrt(1.0f - cos_theta * cos_theta), phi = 2.0f * kPi * u.y;
    Frame f(-wo);  // cos_theta measured from the propagation direction
    *wi = f.to_world(Vec3(sin_theta * std::cos(phi), sin_theta * std::sin(phi), cos_theta));
    *pdf = value(cos_theta);
    *weight = Rgb(1.0f);
    return true;
}

bool HomogeneousMedium::sample_free_flight(const Ray& ray, float t_max, const MediumInteraction*, int channel,
                                           Sampler& sampler, MediumInteraction* mi, Rgb* weight, Rgb* pdf_ratio) const {
    float ut = sampler.next_1d();
    float sc = sigma_t_[channel];
    float t = sc > 0 ? -std::log1p(-ut) / sc : kInf;
    if (t < t_max) {
        Rgb T(std::exp(-sigma_t_.r * t), std::exp(-sigma_t_.g * t), std::exp(-sigma_t_.b * t));
        Rgb pdf = sigma_t_ * T;  // density of scattering at t for each choice of hero channel
        float ph = pdf[channel];
        if (!(ph > 0)) {
            *weight = Rgb(0.0f);
            *pdf_ratio = Rgb(1.0f);
            return false;
        }
        *weight = albedo_ * sigma_t_ * T / ph;
        *pdf_ratio = pdf / ph;
        mi->t = t;
        mi->p = ray.at(t);
        mi->wo = -ray.d;
        mi->frame_n = Vec3(0, 0, 1);
        mi->medium = this;
        return true;
    }
    Rgb T = transmittance(ray, t_max, sampler);  // probability of passing, per hero channel
    float ph = T[channel];
    if (!(ph > 0)) {
        *weight = Rgb(0.0f);
        *pdf_ratio = Rgb(1.0f);
        return false;
    }
    *weight = T / ph;
    *pdf_ratio = T / ph;
    return false;
}

bool Medium::sample_free_flight_to_exit(const Ray&, float, const MediumInteraction*, Sampler&, MediumInteraction*, float*) const {
    throw Error(name() + " medium: does not find its region's exit");
}

Rgb Medium::transmittance_to_exit(const Ray&, float, const MediumInteraction*, Sampler&, float*) const {
    throw Error(name() + " medium: does not find its region's exit");
}

Rgb HomogeneousMedium::transmittance(const Ray&, float t_max, Sampler&) const {
    if (!std::isfinite(t_max))
        return Rgb(sigma_t_.r > 0 ? 0.0f : 1.0f, sigma_t_.g > 0 ? 0.0f : 1.0f, sigma_t_.b > 0 ? 0.0f : 1.0f);
    return Rgb(std::exp(-sigma_t_.r * t_max), std::exp(-sigma_t_.g * t_max), std::exp(-sigma_t_.b * t_max));
}

}  // namespace mf
