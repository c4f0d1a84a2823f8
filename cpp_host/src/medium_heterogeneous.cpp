// mfhost — Mitsuba 3's heterogeneous medium (see medium_heterogeneous.h).
#include "medium_heterogeneous.h"

#include <algorithm>
#include <cmath>

namespace mf {

HeterogeneousMedium::HeterogeneousMedium(std::shared_ptr<const Volume> sigma_t, float scale, std::shared_ptr<const Volume> albedo,
                                         const Aabb& box, std::shared_ptr<PhaseFunction> phase)
    : sigma_t_(std::move(sigma_t)), albedo_(std::move(albedo)), scale_(scale), box_(box), phase_(std::move(phase)) {
    ValueRange r = sigma_t_->range();
    // Mitsuba's majorant: scale times the largest value of any channel, at least 1e-6
    majorant_ = std::max(1e-6f, scale_ * std::max(r.hi[0], std::max(r.hi[1], r.hi[2])));
}

Rgb HeterogeneousMedium::sigma_t(const Vec3& p) const {
    float v[3];
    sigma_t_->eval(p, v);
    // trilinear values of non-negative samples stay within the majorant, up to rounding
    return Rgb(std::min(scale_ * v[0], majorant_), std::min(scale_ * v[1], majorant_), std::min(scale_ * v[2], majorant_));
}

bool HeterogeneousMedium::clip(const Ray& ray, float t_max, float* t0, float* t1) const {
    float lo = 0, hi = t_max;
    for (int a = 0; a < 3; ++a) {
        float inv = 1.0f / ray.d[a];
        float ta = (box_.lo[a] - ray.o[a]) * inv, tb = (box_.hi[a] - ray.o[a]) * inv;
        if (std::isnan(ta) || std::isnan(tb)) {  // parallel to the slab, on its plane
            if (ray.o[a] < box_.lo[a] || ray.o[a] > box_.hi[a]) return false;
            continue;
        }
        lo = std::max(lo, std::min(ta, tb));
        hi = std::min(hi, std::max(ta, tb));
    }
    *t0 = lo;
    *t1 = hi;
    return lo < hi;
}

bool HeterogeneousMedium::sample_free_flight(const Ray& ray, float t_max, const MediumInteraction*, int channel, Sampler& sampler,
                                             MediumInteraction* mi, Rgb* weight, Rgb* pdf_ratio) const {
    *weight = Rgb(1.0f);
    *pdf_ratio = Rgb(1.0f);
    float t, t1;
    if (!clip(ray, t_max, &t, &t1)) return false;
    for (;;) {
        t -= std::log1p(-sampler.next_1d()) / majorant_;
        const float u = sampler.next_1d();
        if (!(t < t1)) return false;
        const Vec3 p = ray.at(t);
        const Rgb st = sigma_t(p);
        if (u * majorant_ < st[channel]) {  // a real collision for the hero channel
            float a[3];
            albedo_->eval(p, a);
            *weight = *weight * st * Rgb(a[0], a[1], a[2]) / st[channel];
            *pdf_ratio = *pdf_ratio * st / st[channel];
            mi->t = t;
            mi->p = p;
            mi->wo = -ray.d;
            mi->frame_n = Vec3(0, 0, 1);
            mi->medium = this;
            return true;
        }
        const Rgb sn = Rgb(majorant_) - st;  // sn[channel] > 0: a null collision was drawn
        *weight = *weight * sn / sn[channel];
        *pdf_ratio = *pdf_ratio * sn / sn[channel];
    }
}

Rgb HeterogeneousMedium::transmittance(const Ray& ray, float t_max, Sampler& sampler) const {
    float t, t1;
    if (!clip(ray, t_max, &t, &t1)) return Rgb(1.0f);
    Rgb T(1.0f);
    for (;;) {
        t -= std::log1p(-sampler.next_1d()) / majorant_;
        if (!(t < t1)) return T;
        T = T * (Rgb(1.0f) - sigma_t(ray.at(t)) / majorant_);
        if (T.max() <= 0) return Rgb(0.0f);
    }
}

}  // namespace mf
