// mfhost — Mitsuba 3's `heterogeneous` medium: extinction sigma_t(x) = scale * sigma_t volume and
// single-scattering albedo(x) from <volume>s (constvolume, gridvolume), present only inside the
// box of the sigma_t volume (Mitsuba's intersect_aabb), with a phase function.
//
// Free flights by delta tracking against the grey majorant  mu = scale * max sigma_t  (Mitsuba's
// default, no majorant supergrid), written in the null-collision path space so that it plugs into
// the integrator's hero-channel MIS (medium.h): every tentative collision is real with probability
// sigma_t,c / mu for the hero channel c; a null collision multiplies the weight and the pdf ratio
// by sigma_n / sigma_n,c (sigma_n = mu - sigma_t), a real one by sigma_s / sigma_t,c and
// sigma_t / sigma_t,c. Transmittance by ratio tracking: prod (1 - sigma_t / mu) over tentative
// collisions. Both are unbiased; Mitsuba's estimators differ in noise, not in expectation.
#pragma once

#include <memory>

#include "medium.h"
#include "volume.h"

namespace mf {

class HeterogeneousMedium final : public Medium {
public:
    /// `sigma_t` and `albedo`: 3-channel volumes; `box`: where the medium is (world space).
    HeterogeneousMedium(std::shared_ptr<const Volume> sigma_t, float scale, std::shared_ptr<const Volume> albedo, const Aabb& box,
                        std::shared_ptr<PhaseFunction> phase);
    bool sample_free_flight(const Ray& ray, float t_max, const MediumInteraction* from, int channel, Sampler& sampler,
                            MediumInteraction* mi, Rgb* weight, Rgb* pdf_ratio) const override;
    Rgb transmittance(const Ray& ray, float t_max, Sampler& sampler) const override;
    const PhaseFunction& phase() const override { return *phase_; }
    std::string name() const override { return "heterogeneous"; }
    float majorant() const { return majorant_; }

private:
    /// The part [*t0, *t1] of [0, t_max] inside the box; false if empty.
    bool clip(const Ray& ray, float t_max, float* t0, float* t1) const;
    Rgb sigma_t(const Vec3& p) const;

    std::shared_ptr<const Volume> sigma_t_, albedo_;
    float scale_, majorant_;
    Aabb box_;
    std::shared_ptr<PhaseFunction> phase_;
};

}  // namespace mf
