// mfhost — <medium type="gpis">: the realization-based ground truth (seeds/004) through the C
// ABI's mf_gpis_* functions.
//
// A shape whose interior is a gpis medium is the *mean surface* of a Gaussian-process implicit
// surface; realizations live in the band |f| <= envelope (mf_gpis_envelope) around it. The
// region f < +envelope is registered exactly like a macrofacet region (make_region_boundary:
// the same null-BSDF boundary), with this medium as its interior. The mean is the library's
// signed distance of the shape (mean_surface.h), handed to mf_gpis_trace as its callback. The integrator
// special-cases it (Medium::as_gpis): inside the region a path segment is realized by
// mf_gpis_trace up to the next surface (the band's exit); a hit is a delta reflection
// (mf_gpis_scatter), after which the next segment starts ON_SURFACE with the hit's sampled
// gradient (Renewal+ memory; Renewal ignores it). Shadow rays crossing the region trace a fresh
// realization (START_FREE): a hit occludes (transmittance 0), a miss transmits (1).
//
// Spatially varying parameters (issue 12): an optional GpisField (the host's field callbacks and
// their data) makes the kernel the non-stationary one of seeds/004 Eqs. 25-26 with the field's
// local parameters, as the macrofacet medium reads them; the band widens to shell_extent times
// the field's sigma_max, and each hit carries the field's parameters to its reflection.
#pragma once

#include <macrofacet.h>

#include <memory>
#include <string>

#include "medium.h"
#include "shape.h"

namespace mf {

class MeanSurface;

/// One crossing of a realization (double precision: the next segment starts exactly there).
struct GpisHit {
    double t = 0;
    double p[3] = {0, 0, 0};
    double normal[3] = {0, 0, 1};
    double gradient[3] = {0, 0, 1};
    mf_local_params local{};  // the field's parameters at the crossing (set = 0: the medium's own)
    Vec3 point() const { return Vec3(float(p[0]), float(p[1]), float(p[2])); }
    Vec3 n() const { return Vec3(float(normal[0]), float(normal[1]), float(normal[2])); }
};

/// The start of a traced segment: free (camera/light ray entering the band, or after any other
/// event) or on the previous crossing with its sampled gradient.
struct GpisStart {
    bool on_surface = false;
    double p[3] = {0, 0, 0};
    double gradient[3] = {0, 0, 1};
};

/// A field of local parameters for a gpis medium: the host's callbacks (as for
/// mf_field_new_callbacks; both required) and the data they are called with. The library calls
/// the mean's and the field's callbacks of a trace with one user_data, so the medium wraps these
/// in its own mf_field; `user_data` must outlive the medium and the callbacks be thread-safe.
struct GpisField {
    mf_field_callbacks callbacks{};
    void* user_data = nullptr;
};

class GpisMedium final : public Medium {
public:
    /// Takes ownership of `handle` (freed with mf_gpis_free in the destructor). `field` (optional,
    /// copied) makes the parameters vary in space; throws mf::Error if the library refuses it.
    GpisMedium(mf_gpis* handle, std::shared_ptr<const MeanSurface> mean, std::string label,
               const GpisField* field = nullptr);
    ~GpisMedium() override;
    GpisMedium(const GpisMedium&) = delete;
    GpisMedium& operator=(const GpisMedium&) = delete;

    /// Realizes the process along o + t d, 0 < t <= t_max (o = start.p when start.on_surface);
    /// true and *hit on the first entering crossing.
    bool trace(const Vec3& o, const Vec3& d, double t_max, const GpisStart& start, uint64_t seed, GpisHit* hit) const;
    /// Delta reflection of wo (pointing away from the hit, = -ray.d) about the hit normal:
    /// *wi and the RGB weight (Fresnel × specular_reflectance × the hit's reflectance_scale).
    /// False if invalid.
    bool scatter(const Vec3& wo, const GpisHit& hit, Vec3* wi, Rgb* weight) const;

    /// Generic-interface fallbacks (the integrator uses trace/scatter directly): a free flight is
    /// a START_FREE trace whose hit is reported as the interaction (frame_n = sampled normal).
    bool sample_free_flight(const Ray& ray, float t_max, int channel, Sampler& sampler, MediumInteraction* mi,
                            Rgb* weight, Rgb* pdf_ratio) const override;
    /// Binary estimate: a fresh realization (START_FREE, seed from `sampler`) hit = 0, miss = 1.
    Rgb transmittance(const Ray& ray, float t_max, Sampler& sampler) const override;
    const PhaseFunction& phase() const override { return *phase_; }
    std::string name() const override { return "gpis"; }
    const GpisMedium* as_gpis() const override { return this; }

    double envelope() const { return envelope_; }
    const MeanSurface& mean_surface() const { return *mean_; }
    const mf_gpis* handle() const { return handle_; }

private:
    mf_gpis* handle_;
    mf_field* field_ = nullptr;  // wraps host_field_ (null: stationary)
    GpisField host_field_;
    std::shared_ptr<const MeanSurface> mean_;
    std::shared_ptr<PhaseFunction> phase_;
    double envelope_ = 0;
    std::string label_;
};

/// The gpis hook: parameter bag -> mf_params -> mf_gpis_new (same bag conversion and error
/// locations as the macrofacet hook), with an optional field. Throws mf::Error at the offending
/// parameter's line.
std::shared_ptr<GpisMedium> create_gpis_medium(const MediumParamBag& bag, std::shared_ptr<const MeanSurface> mean,
                                               const GpisField* field = nullptr);

}  // namespace mf
