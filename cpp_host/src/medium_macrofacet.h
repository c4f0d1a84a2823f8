// mfhost — the macrofacet medium, built and tracked through the library's C ABI only.
//
// A shape whose interior is a <medium type="macrofacet"> is the *mean surface* of a Gaussian-
// process statistical surface (see mean_surface.h for the region and its boundary). Inside, the
// library owns the volume event: mf_track_free_flight samples the next real collision with its
// local frame, mf_track_transmittance estimates shadow-ray transmittance, and the phase function
// is evaluated in that frame (mf_phase_eval_pdf, mf_phase_sample). mfrender keeps geometry only:
// the mean surface handle and the Embree boundary. Each call gets a 64-bit seed from the
// path's sampler, so renders stay deterministic per --seed whatever the thread count.
#pragma once

#include <array>
#include <atomic>
#include <cmath>
#include <memory>
#include <string>

#include "mean_surface.h"
#include "medium.h"

struct mf_medium;
struct mf_track_query;
struct mf_track_stats;

namespace mf {

class LibraryField;

/// Cumulative tracking counts of one medium (for benchmarks and tests).
struct TrackCounts {
    uint64_t calls = 0, surface_queries = 0, segments = 0, tentative_collisions = 0, majorant_violations = 0;
};

class MacrofacetMedium final : public Medium {
public:
    /// Takes ownership of `handle` (freed with mf_medium_free in the destructor).
    /// `field`: the spatially varying parameters (null for a stationary medium).
    MacrofacetMedium(mf_medium* handle, std::shared_ptr<const MeanSurface> surface, std::string label,
                     std::shared_ptr<const LibraryField> field = nullptr);
    ~MacrofacetMedium() override;
    MacrofacetMedium(const MacrofacetMedium&) = delete;
    MacrofacetMedium& operator=(const MacrofacetMedium&) = delete;

    bool sample_free_flight(const Ray& ray, float t_max, const MediumInteraction* from, int channel, Sampler& sampler,
                            MediumInteraction* mi, Rgb* weight, Rgb* pdf_ratio) const override;
    Rgb transmittance(const Ray& ray, float t_max, Sampler& sampler) const override;
    Rgb transmittance_kept(const Ray& ray, float t_max, Sampler& sampler, double survival) const override;
    bool sample_free_flight_to_exit(const Ray& ray, float t_max, const MediumInteraction* from, Sampler& sampler,
                                    MediumInteraction* mi, float* t_end) const override;
    Rgb transmittance_to_exit(const Ray& ray, float t_max, const MediumInteraction* from, Sampler& sampler,
                              float* t_end) const override;
    /// The hint of `from`, an event of this medium the ray leaves (0: none).
    uint64_t hint_of(const MediumInteraction* from) const { return from && from->medium == this ? from->surface_hint : 0; }
    /// Let the tracking calls find each ray's exit from the region (mf_track_query::exit_level):
    /// only where the region's boundary encloses points with f <= exit_level alone, and with
    /// `near_scene` the shapes within exit_level of the boundary's box, none of them a medium
    /// transition (SceneBuilder::let_media_find_exits). Beyond the exit lies `exterior`.
    void find_exits(double exit_level, const Medium* exterior, unsigned near_scene);
    const PhaseFunction& phase() const override { return *phase_; }
    std::string name() const override { return "macrofacet"; }

    const mf_medium* handle() const { return handle_; }
    const MeanSurface& surface() const { return *surface_; }
    /// The signed distance of the shell's top face, k·sigma (mf_medium_shell_top).
    double shell_top() const { return top_; }
    /// The opaque core (mf_track_opaque_core): a ray from f >= *start_level that reaches
    /// f <= *core_level has a transmittance that rounds to 0. False without one (a field, or no
    /// bound).
    bool opaque_core(double* start_level, double* core_level) const {
        *start_level = core_start_;
        *core_level = core_level_;
        return std::isfinite(core_level_);
    }
    /// The probability with which a shadow ray that descends from height f_from to f_to is kept
    /// for the uniform u (mf_track_depth_roulette; 0: not kept).
    double depth_roulette(double f_from, double f_to, double u) const;
    /// The sphere whose core mfrender tests shadow rays against (Scene::add_opaque_core), with
    /// the levels: when the mean surface is a sphere and the core lies inside it.
    const MeanSurface::Sphere* sphere_core(double* start_level, double* core_level) const {
        const MeanSurface::Sphere* s = surface_->sphere();
        return s && opaque_core(start_level, core_level) && s->radius + *core_level > 0 ? s : nullptr;
    }
    /// The real sigma_t at p for direction d, with the surface's frame and signed distance there.
    double sigma_t_at(const Vec3& p, const Vec3& d, Vec3* normal, Vec3* tangent, float* f) const;
    /// Tentative collisions whose real sigma_t exceeded the library's majorant (must stay 0).
    uint64_t majorant_violations() const { return violations_.load(std::memory_order_relaxed); }
    TrackCounts counts() const;
    const std::string& label() const { return label_; }

private:
    void count(const ::mf_track_stats& s) const;
    /// One free flight or transmittance call (*t_end: where it ended).
    bool flight(const ::mf_track_query& q, const Ray& ray, MediumInteraction* mi, float* t_end) const;
    Rgb transmittance_of(const ::mf_track_query& q, float* t_end) const;

    /// Tracking counts of the thread that holds this slot (tally_slot in the .cpp), on a cache
    /// line of their own: that thread adds with plain relaxed loads and stores, no locked
    /// instruction and no line shared between threads (four atomic additions per call took 2 %
    /// of the time of bench/gpis_compare.xml). The last slot is shared, with fetch_add.
    struct alignas(64) Tally {
        std::atomic<uint64_t> calls{0}, queries{0}, segments{0}, tentative{0};
    };
    static constexpr unsigned kTallySlots = 64;

    mf_medium* handle_;
    std::shared_ptr<const MeanSurface> surface_;
    std::shared_ptr<const LibraryField> field_;
    std::shared_ptr<PhaseFunction> phase_;
    double top_ = 0;
    double core_start_ = 0, core_level_ = -INFINITY;  // opaque_core
    double exit_level_ = 0;  // find_exits
    std::string label_;
    mutable std::array<Tally, kTallySlots + 1> tallies_;
    mutable std::atomic<uint64_t> violations_{0};  // exact and rare: always fetch_add
};

/// How many threads hold a tally slot of MacrofacetMedium's counts now (each gives its slot back
/// when it ends; for tests).
unsigned tally_slots_held();

/// Builds the macrofacet medium of the shape `mean` from its parameter bag (mf_params_* /
/// mf_medium_new), with its spatially varying parameters as a library field, and the mean surface
/// for it (on up to `threads` threads, for the medium's reach: MeanSurface::of); throws mf::Error
/// at the file:line of the offending parameter, or at the shape's.
std::shared_ptr<MacrofacetMedium> create_macrofacet_medium(const MediumParamBag& bag, const Shape& mean, size_t threads);

}  // namespace mf
