// mfhost — the macrofacet medium (phase 2), built on the Rust library's C ABI only.
//
// A shape whose interior is a <medium type="macrofacet"> is the *mean surface* of a Gaussian-
// process statistical surface. The medium occupies every point whose signed distance to the
// mean surface is f < top = k·sigma (mf_medium_shell_top): the shell out to +k·sigma and the
// whole interior. mfrender does not put the mean surface into Embree; it registers the level
// set f = top instead (an exact offset sphere for spheres, a sphere-traced SDF level set for
// every other shape), as an index-matched (null) interface whose interior is the medium.
//
// Inside, free flights use delta tracking and shadow rays ratio tracking against a piecewise-
// constant majorant that is valid for curved shells (see MacrofacetMedium); real collisions
// scatter with the library's phase function (mf_phase_sample / eval / pdf) in the local frame
// (normal = the shape's frame normal at the collision, tangent = world +z projected).
// README.md ("Phase 2") documents the design, its approximations and their error.
#pragma once

#include <atomic>
#include <memory>
#include <string>
#include <vector>

#include "medium.h"
#include "shape.h"

struct mf_medium;
struct mf_params;

namespace mf {

/// Conservative bounds of an expensive SDF (the mesh SDF) from its values on a coarse grid:
/// by the 1-Lipschitz property, sdf(p) lies within |p - q| of sdf(q) at the nearest node q.
/// Used to skip space far from the shell (sphere tracing, tracking); never to decide anything
/// near it, so it changes the cost only, not the result.
class SdfBoundGrid {
public:
    SdfBoundGrid(const Shape& shape, const Aabb& box, int cells_longest_axis);
    /// [lo, hi] containing shape.sdf(p).f
    void bounds(const Vec3& p, float* lo, float* hi) const;

private:
    Vec3 origin_;
    float h_;
    int n_[3];
    std::vector<float> v_;
};

class MacrofacetMedium final : public Medium {
public:
    /// Takes ownership of `handle` (freed with mf_medium_free in the destructor).
    MacrofacetMedium(mf_medium* handle, std::shared_ptr<const Shape> mean, double sigma, std::string label);
    ~MacrofacetMedium() override;
    MacrofacetMedium(const MacrofacetMedium&) = delete;
    MacrofacetMedium& operator=(const MacrofacetMedium&) = delete;

    bool sample_free_flight(const Ray& ray, float t_max, int channel, Sampler& sampler, MediumInteraction* mi,
                            Rgb* weight, Rgb* pdf_ratio) const override;
    Rgb transmittance(const Ray& ray, float t_max, Sampler& sampler) const override;
    const PhaseFunction& phase() const override { return *phase_; }
    std::string name() const override { return "macrofacet"; }

    const mf_medium* handle() const { return handle_; }
    const Shape& mean_shape() const { return *mean_; }
    double shell_top() const { return top_; }
    double sigma() const { return sigma_; }
    /// The direction-independent majorant of sigma_t over a segment whose signed distance
    /// stays >= f_min (Lipschitz bound); 0 above the shell.
    double majorant(double f_min) const;
    /// Real sigma_t at a point, with its local frame (filled into *n, *tangent, *f).
    double sigma_t_at(const Vec3& p, const Vec3& d, Vec3* n, Vec3* tangent, float* f) const;
    /// Coarse SDF bounds for mesh shapes (null for analytic SDFs).
    const std::shared_ptr<const SdfBoundGrid>& grid() const { return grid_; }
    /// Tentative collisions whose real sigma_t exceeded the majorant (should stay 0).
    uint64_t majorant_violations() const { return violations_.load(std::memory_order_relaxed); }

private:
    /// Length of the next tracking segment starting at signed distance f0.
    double segment_length(double f0) const;
    /// How march() ended: the ray left [0, t_max] (or escaped above the shell towards infinity),
    /// the collision callback stopped it, or it ran out of segments.
    enum class MarchEnd { Left, Stopped, OutOfSegments };
    /// The segment march of both tracking estimators (defined in medium_macrofacet.cpp).
    template <class OnCollision>
    MarchEnd march(const Ray& ray, float t_max, Sampler& sampler, OnCollision&& on_collision) const;

    mf_medium* handle_;
    std::shared_ptr<const Shape> mean_;
    std::shared_ptr<PhaseFunction> phase_;
    std::shared_ptr<const SdfBoundGrid> grid_;
    double sigma_, top_;
    double smax_factor_ = 1;  // max over directions of sigma(d) / sigma(d_ref), times a margin
    std::string label_;
    mutable std::atomic<uint64_t> violations_{0};
};

/// Shared by the macrofacet and gpis hooks: the parameter bag as an mf_params handle (the caller
/// frees it with mf_params_free; *sigma = sigma or sqrt(variance) when given, else -1). Throws
/// mf::Error at the offending parameter's line when the library rejects a value.
struct mf_params* bag_to_params(const MediumParamBag& bag, double* sigma);
/// An error for a library message about `bag`, at the line of the parameter the message names
/// (the longest bag name quoted in it), else at the <medium> element.
Error medium_param_error(const MediumParamBag& bag, const std::string& msg);
/// "file:line: <medium type=... id=...>" for messages at run time.
std::string medium_label(const MediumParamBag& bag);
/// mf_last_error_message() of this thread as a string.
std::string mf_last_error();

/// Coarse SDF bounds of a mesh shape without an analytic SDF (null otherwise), covering the
/// shape's bounds grown by `top` (+5 % of its extent).
std::shared_ptr<const SdfBoundGrid> make_sdf_bound_grid(const std::shared_ptr<const Shape>& mean, double top);

/// THE region mechanism of the media that live on a mean surface (macrofacet and gpis): the level
/// set f = top of `mean` as a null-BSDF shape whose interior is `medium` and whose exterior is
/// the mean shape's exterior — an exact offset sphere for spheres, a sphere-traced
/// LevelSetShape (with `grid` bounds for mesh SDFs) otherwise. Throws mf::Error (at the mean
/// shape's location) when the offset is impossible (a flipped sphere thinner than the shell).
std::shared_ptr<Shape> make_region_boundary(const std::shared_ptr<const Shape>& mean, double top,
                                            const std::shared_ptr<const Medium>& medium,
                                            const std::shared_ptr<const SdfBoundGrid>& grid);

/// Embree user geometry for the level set {p : sdf(p) = offset} of a shape, found by sphere
/// tracing the 1-Lipschitz SDF with a final bisection (see README: tolerance).
class LevelSetShape final : public Shape {
public:
    LevelSetShape(std::shared_ptr<const Shape> base, float offset, std::shared_ptr<const SdfBoundGrid> grid = nullptr);
    SdfSample sdf(const Vec3& p) const override;
    Aabb bounds() const override { return bounds_; }
    float surface_area() const override { return base_->surface_area(); }
    void sample_position(const Vec2& u, Vec3* p, Vec3* n) const override;
    unsigned attach(RTCDevice device, RTCScene scene) const override;
    void fill_hit(const Ray& ray, float t, unsigned prim, float u, float v, SurfaceHit* hit) const override;
    std::string kind() const override { return base_->kind() + " (shell boundary)"; }
    /// First crossing of the level set with t in (tnear, tfar); *exiting = it goes from inside
    /// (sdf < offset) to outside.
    bool intersect(const Vec3& o, const Vec3& d, float tnear, float tfar, float* t, bool* exiting) const;
    /// Minimum sphere-tracing step (scene units): crossings shorter than this along a ray can be
    /// missed (grazing tangencies of the level set).
    float min_step() const { return min_step_; }

private:
    std::shared_ptr<const Shape> base_;
    float offset_;
    std::shared_ptr<const SdfBoundGrid> grid_;
    Aabb bounds_;
    float min_step_, tol_;
};

}  // namespace mf
