// mfhost — <medium type="gpis">: the realization-based ground truth (seeds/004) through the C
// ABI's mf_gpis_* functions, behind the same Medium interface as every other medium.
//
// A shape whose interior is a gpis medium is the *mean surface* of a Gaussian-process implicit
// surface; realizations live in the band |f| <= envelope (mf_gpis_envelope) around it. The
// region f < +envelope is registered exactly like a macrofacet region (make_region_boundary:
// the same null-BSDF boundary), with this medium as its interior. The mean is the library's
// signed distance of the shape (mean_surface.h), handed to mf_gpis_trace as its callback.
//
//  * Free flight: the segment [0, t_max] up to the next surface is realized by mf_gpis_trace;
//    its first entering crossing is the interaction (weight 1: the realization decides, nothing
//    is sampled against a density), a miss passes t_max. A flight that leaves a crossing of this
//    medium (`from`) starts ON_SURFACE there with that crossing's sampled gradient (Renewal+
//    memory; Renewal ignores the gradient); any other flight starts FREE.
//  * Phase function: the crossing reflects specularly (mf_gpis_scatter about its normal): a
//    Dirac lobe, so the integrator does no NEE there and emitters hit next count fully.
//  * Transmittance (shadow rays crossing the region): a fresh realization (START_FREE) over the
//    segment: a crossing occludes (0), a miss transmits (1), an unbiased estimate of the Renewal
//    transmittance (a shadow ray starts its own realization, as a ray entering the band does).
// Every call takes its seed from one dimension of the path's sampler, so renders stay
// bit-identical per --seed whatever the thread count.
//
// Spatially varying parameters (issue 12): with a field (medium_field.h, the same one the
// macrofacet medium reads) the kernel is the non-stationary one of seeds/004 Eqs. 25-26 with the
// field's local parameters, the band widens to shell_extent times the field's largest sigma, and
// each crossing carries the field's parameters to its reflection.
#pragma once

#include <memory>
#include <string>

#include "medium.h"

struct mf_gpis;
struct mf_field;

namespace mf {

class LibraryField;
class MeanSurface;

class GpisMedium final : public Medium {
public:
    /// Takes ownership of `handle` (freed with mf_gpis_free in the destructor). `field` (optional)
    /// makes the parameters vary in space; throws mf::Error if the library refuses it.
    GpisMedium(mf_gpis* handle, std::shared_ptr<const MeanSurface> mean, std::string label,
               std::shared_ptr<const LibraryField> field = nullptr);
    ~GpisMedium() override;
    GpisMedium(const GpisMedium&) = delete;
    GpisMedium& operator=(const GpisMedium&) = delete;

    /// The first crossing of a realization of [0, t_max] (see the file comment); *mi carries the
    /// crossing's normal as frame_n and, in `record`, its exact point, normal and gradient.
    bool sample_free_flight(const Ray& ray, float t_max, const MediumInteraction* from, int channel, Sampler& sampler,
                            MediumInteraction* mi, Rgb* weight, Rgb* pdf_ratio) const override;
    /// Binary estimate: a fresh realization (START_FREE, seed from `sampler`) crossing = 0, miss = 1.
    Rgb transmittance(const Ray& ray, float t_max, Sampler& sampler) const override;
    /// The specular reflection at a crossing (is_delta).
    const PhaseFunction& phase() const override { return *phase_; }
    std::string name() const override { return "gpis"; }

    /// Half-width of the band of realizations around the mean surface (scene units).
    double envelope() const { return envelope_; }

private:
    mf_gpis* handle_;
    std::shared_ptr<const MeanSurface> mean_;
    std::shared_ptr<const LibraryField> host_field_;
    /// The library's view of host_field_ for traces: forwards to it (a trace's user_data is the
    /// mean's and the field's, see medium_gpis.cpp).
    mf_field* field_ = nullptr;
    std::shared_ptr<PhaseFunction> phase_;
    double envelope_ = 0;
    std::string label_;
};

/// The gpis hook: parameter bag -> mf_params -> mf_gpis_new (the same bag conversion and error
/// locations as the macrofacet hook, medium_params.h), with the bag's fields as in
/// create_macrofacet_medium. Throws mf::Error at the offending parameter's line.
std::shared_ptr<GpisMedium> create_gpis_medium(const MediumParamBag& bag, std::shared_ptr<const MeanSurface> mean);

}  // namespace mf
