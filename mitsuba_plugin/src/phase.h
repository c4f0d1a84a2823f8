// macrofacet for Mitsuba 3 — the flakes' phase function (seeds/000 Eq. 11–12, the flakes'
// reflectance included) in the local frame of the mean surface at the event, with the medium's
// local parameters there when they vary in space (medium_state.h; mf_phase_*_local).
//
// It belongs to its medium: the medium creates it (a macrofacet medium takes no nested <phase>,
// its flake parameters define the phase function). Mitsuba's plugin registry keys plugins by
// (name, variant), so "macrofacet" names the medium; this class is not registered separately.
//
// Values: eval_pdf returns p(wi, wo) with the flakes' albedo in it and the density of sample();
// sample returns wo with weight p / pdf. The medium reports sigma_s = sigma_t (the albedo lives
// here, as in mfrender). Random numbers: Mitsuba passes sample1 and sample2 (three numbers),
// which conductor flakes use for the visible normal; diffuse flakes need two more, drawn from
// the context's sampler (or, when a caller passes none, hashed from the three).
#pragma once

#include <mitsuba/render/phase.h>

#include <memory>

#include "library.h"
#include "medium_state.h"

namespace mfmi {

using namespace mitsuba;  // Mitsuba's MI_IMPORT_* macros name its types unqualified

template <typename Float, typename Spectrum>
class MacrofacetPhase final : public mitsuba::PhaseFunction<Float, Spectrum> {
public:
    MI_IMPORT_BASE(PhaseFunction, m_flags, m_components)
    MI_IMPORT_TYPES(PhaseFunctionContext)

    MacrofacetPhase(std::shared_ptr<const MediumState> state)
        : Base(mitsuba::Properties("macrofacet_phase")), state_(std::move(state)) {
        m_flags = +mitsuba::PhaseFunctionFlags::Anisotropic;
        m_components.push_back(m_flags);
    }

    std::tuple<Vector3f, Spectrum, Float> sample(const PhaseFunctionContext& ctx, const MediumInteraction3f& mi,
                                                 Float sample1, const Point2f& sample2, Mask active) const override {
        if (!active) return {Vector3f(0.f), Spectrum(0.f), 0.f};
        double u[MF_PHASE_SAMPLE_DIMENSIONS] = {sample1, sample2.x(), sample2.y(), 0.5, 0.5};
        if (state_->diffuse_flakes) {
            if (ctx.sampler) {
                Point2f extra = ctx.sampler->next_2d(active);
                u[3] = extra.x();
                u[4] = extra.y();
            } else {
                const float three[3] = {sample1, sample2.x(), sample2.y()};
                const uint64_t key = hash_floats(three, 3, 0);
                u[3] = uniform_from_bits(key);
                u[4] = uniform_from_bits(~key);
            }
        }
        mf_phase_sample_result s;
        mf_frame frame;
        mf_local_params local;
        if (!event_at(mi, &frame, &local) || !call(mf_phase_sample_local(state_->medium, &local, &frame, wi(mi), u, &s)) || !s.valid ||
            !(s.pdf > 0))
            return {Vector3f(0.f), Spectrum(0.f), 0.f};
        return {Vector3f(float(s.wo.x), float(s.wo.y), float(s.wo.z)),
                Spectrum(float(s.weight.r), float(s.weight.g), float(s.weight.b)), Float(s.pdf)};
    }

    std::pair<Spectrum, Float> eval_pdf(const PhaseFunctionContext&, const MediumInteraction3f& mi, const Vector3f& wo,
                                        Mask active) const override {
        if (!active) return {Spectrum(0.f), 0.f};
        mf_phase_value v;
        mf_frame frame;
        mf_local_params local;
        if (!event_at(mi, &frame, &local) ||
            !call(mf_phase_eval_pdf_local(state_->medium, &local, &frame, wi(mi), unit(wo.x(), wo.y(), wo.z()), &v)))
            return {Spectrum(0.f), 0.f};
        return {Spectrum(float(v.value.r), float(v.value.g), float(v.value.b)), Float(v.pdf)};
    }

    std::string to_string() const override { return "MacrofacetPhase[" + state_->label + "]"; }

    MI_DECLARE_CLASS(MacrofacetPhase)

private:
    static mf_vec3 wi(const MediumInteraction3f& mi) { return unit(mi.wi.x(), mi.wi.y(), mi.wi.z()); }

    /// The event's frame and local parameters (medium_state.h); false when they are unknown.
    bool event_at(const MediumInteraction3f& mi, mf_frame* frame, mf_local_params* local) const {
        const float p[3] = {mi.p.x(), mi.p.y(), mi.p.z()};
        try {
            return state_->event_at(p, frame, local);
        } catch (const std::exception&) {
            return call(MF_ERROR_INVALID_ARGUMENT);
        }
    }

    /// False (and counted) when the library refuses a query; rendering goes on with a zero
    /// contribution rather than throwing inside Mitsuba's render loop.
    bool call(mf_status st) const {
        if (st == MF_OK) return true;
        state_->errors.fetch_add(1, std::memory_order_relaxed);
        return false;
    }

    std::shared_ptr<const MediumState> state_;
};

}  // namespace mfmi
