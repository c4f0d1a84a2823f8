// mfhost — participating media and phase functions.
//
// The integrator is medium-agnostic (as in pbrt-v4 and Mitsuba 3's volpath): it tracks which
// Medium the current ray segment is in (through the interior/exterior references of the shapes
// it crosses) and asks that Medium to sample a free flight or a transmittance along [0, t_max]
// of the segment, where t_max is the distance to the next surface, and its phase function to
// scatter. How the medium does it is its own business: the homogeneous medium samples
// exponentials; the macrofacet medium hands the segment to the library's tracker
// (medium_macrofacet.h), which returns the collision with its local frame (MediumInteraction's
// frame_n / frame_t) for the phase function; the gpis medium realizes a Gaussian-process surface
// along the segment (medium_gpis.h): its interaction is a crossing, its phase function a Dirac
// lobe (is_delta), and a flight that leaves one of its crossings continues that realization's
// memory (sample_free_flight's `from`).
#pragma once

#include <array>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "error.h"
#include "math.h"
#include "sampler.h"

namespace mf {

class Medium;
class Shape;
struct MediumFields;

struct MediumInteraction {
    Vec3 p;                  // scattering position
    float t = 0;             // distance along the ray
    Vec3 wo;                 // direction towards the previous vertex (= -ray.d)
    Vec3 frame_n{0, 0, 1};   // optional local frame normal for anisotropic phase functions
    Vec3 frame_t{1, 0, 0};   // optional local tangent (macrofacet media: direction of alpha_u)
    float sdf_f = 0;         // optional: signed distance at p (macrofacet media)
    const Medium* medium = nullptr;
    /// The medium's own record of the event, opaque to the integrator, which hands the event
    /// back to the medium as the `from` of the next free flight (and to its phase function):
    /// the gpis medium keeps the crossing's exact point, normal and sampled gradient here.
    std::array<double, 24> record{};
    /// A macrofacet medium's mf_collision::hint: where the library found the surface at p, for
    /// the event's escape flight and shadow rays (mf_track_query::hint; 0: none).
    uint64_t surface_hint = 0;
};

class PhaseFunction {
public:
    virtual ~PhaseFunction() = default;
    /// Phase function value p(wo, wi) (1/sr) times any single-scattering colour (RGB).
    /// wo points back along the incoming ray, wi is the new direction.
    virtual Rgb eval(const MediumInteraction& mi, const Vec3& wo, const Vec3& wi) const = 0;
    virtual float pdf(const MediumInteraction& mi, const Vec3& wo, const Vec3& wi) const = 0;
    /// eval() and pdf() together (what NEE with MIS needs); override when both share work.
    virtual Rgb eval_pdf(const MediumInteraction& mi, const Vec3& wo, const Vec3& wi, float* pdf_out) const {
        *pdf_out = pdf(mi, wo, wi);
        return eval(mi, wo, wi);
    }
    /// Sample wi; *weight = eval / pdf. Draws its uniforms from `sampler` (isotropic and HG take
    /// two, the macrofacet phase MF_PHASE_SAMPLE_DIMENSIONS).
    virtual bool sample(const MediumInteraction& mi, const Vec3& wo, Sampler& sampler, Vec3* wi, float* pdf,
                        Rgb* weight) const = 0;
    /// A Dirac lobe (eval and pdf are 0, sample gives the direction with *pdf = 0 and the weight):
    /// no next-event estimation at its events, and emitters reached from them count fully.
    virtual bool is_delta() const { return false; }
};

class IsotropicPhase final : public PhaseFunction {
public:
    Rgb eval(const MediumInteraction&, const Vec3&, const Vec3&) const override { return Rgb(kInv4Pi); }
    float pdf(const MediumInteraction&, const Vec3&, const Vec3&) const override { return kInv4Pi; }
    bool sample(const MediumInteraction&, const Vec3&, Sampler& sampler, Vec3* wi, float* pdf, Rgb* weight) const override;
};

/// Henyey–Greenstein; g > 0 is forward scattering (wi close to -wo).
class HenyeyGreenstein final : public PhaseFunction {
public:
    explicit HenyeyGreenstein(float g) : g_(g) {}
    float value(float cos_theta) const;  // cos_theta = dot(-wo, wi)
    Rgb eval(const MediumInteraction&, const Vec3& wo, const Vec3& wi) const override { return Rgb(value(dot(-wo, wi))); }
    float pdf(const MediumInteraction&, const Vec3& wo, const Vec3& wi) const override { return value(dot(-wo, wi)); }
    bool sample(const MediumInteraction&, const Vec3& wo, Sampler& sampler, Vec3* wi, float* pdf, Rgb* weight) const override;

private:
    float g_;
};

class Medium {
public:
    virtual ~Medium() = default;
    /// Free-flight sampling along ray (|d| = 1) over [0, t_max] (t_max may be +inf).
    /// Returns true and fills *mi on a real scattering event; false if the flight passed t_max.
    /// *mi is reused across bounces: the medium writes every field its phase function and its
    /// own `from` read (t, p, wo and medium always), whatever an earlier event left there.
    /// `from` is the event of this path the ray leaves (the previous vertex, when it was a
    /// scattering event in a medium: the ray starts at from->p), else null (the camera, a surface,
    /// a boundary crossing). Media without memory ignore it.
    ///
    /// Chromatic media use path-space "hero channel" MIS: the integrator picks `channel` once
    /// per path; distances are sampled with that channel's extinction. The medium returns
    ///   *weight    = f / p_channel  per RGB channel (f = sigma_s·T for a scattering event,
    ///                T for passing), and
    ///   *pdf_ratio = p_k / p_channel for k = R, G, B (the pdf of the same event had channel k
    ///                been the hero).
    /// The integrator multiplies both along the path and divides the throughput by the average
    /// of the pdf-ratio product (one-sample balance heuristic over the hero choice), which keeps
    /// weights bounded. Grey media (e.g. the macrofacet medium) return pdf_ratio = 1.
    virtual bool sample_free_flight(const Ray& ray, float t_max, const MediumInteraction* from, int channel,
                                    Sampler& sampler, MediumInteraction* mi, Rgb* weight, Rgb* pdf_ratio) const = 0;
    /// Transmittance (or an unbiased estimate of it) over [0, t_max].
    virtual Rgb transmittance(const Ray& ray, float t_max, Sampler& sampler) const = 0;
    /// transmittance() of a shadow ray the integrator kept with probability `survival` in
    /// (0, 1] in a Russian roulette (Scene::shadow_roulette): an estimate of T / survival. A
    /// medium whose estimator plays a roulette of its own counts the weight in it
    /// (MacrofacetMedium: mf_track_query::survival); by default the estimate is divided.
    virtual Rgb transmittance_kept(const Ray& ray, float t_max, Sampler& sampler, double survival) const {
        return transmittance(ray, t_max, sampler) * float(1.0 / survival);
    }
    virtual const PhaseFunction& phase() const = 0;
    virtual std::string name() const = 0;

    /// Whether the medium finds each ray's exit from its region itself (MacrofacetMedium::
    /// find_exits): the integrator then casts rays inside it against the shapes near the region
    /// only (Scene::intersect_near(near_scene())), without its boundary, and calls the *_to_exit
    /// forms below.
    bool finds_exits() const { return finds_exits_; }
    /// The medium beyond the region's exit (null: vacuum), when finds_exits().
    const Medium* exterior() const { return exterior_; }
    unsigned near_scene() const { return near_scene_; }
    /// sample_free_flight for a ray inside the region, up to t_max or the region's exit:
    /// *t_end is where a flight that passed ended (the ray continues from there, outside).
    /// `from` as sample_free_flight's.
    virtual bool sample_free_flight_to_exit(const Ray& ray, float t_max, const MediumInteraction* from, Sampler& sampler,
                                            MediumInteraction* mi, float* t_end) const;
    /// transmittance, up to t_max or the region's exit (*t_end); `from` is the event the shadow
    /// ray leaves, or null.
    virtual Rgb transmittance_to_exit(const Ray& ray, float t_max, const MediumInteraction* from, Sampler& sampler,
                                      float* t_end) const;

protected:
    bool finds_exits_ = false;
    const Medium* exterior_ = nullptr;
    unsigned near_scene_ = 0;
};

class HomogeneousMedium final : public Medium {
public:
    HomogeneousMedium(const Rgb& sigma_t, const Rgb& albedo, std::shared_ptr<PhaseFunction> phase)
        : sigma_t_(sigma_t), albedo_(albedo), phase_(std::move(phase)) {}
    /// Exponential free flights with the hero channel's sigma_t (see Medium); exact
    /// (weight = albedo) for grey media. For a homogeneous medium this is what delta tracking
    /// with majorant = sigma_t reduces to.
    bool sample_free_flight(const Ray& ray, float t_max, const MediumInteraction* from, int channel, Sampler& sampler,
                            MediumInteraction* mi, Rgb* weight, Rgb* pdf_ratio) const override;
    Rgb transmittance(const Ray& ray, float t_max, Sampler& sampler) const override;
    const PhaseFunction& phase() const override { return *phase_; }
    std::string name() const override { return "homogeneous"; }
    const Rgb& sigma_t() const { return sigma_t_; }
    const Rgb& albedo() const { return albedo_; }

private:
    Rgb sigma_t_, albedo_;
    std::shared_ptr<PhaseFunction> phase_;
};

/// A parameter of a plugin that mfrender does not interpret itself (macrofacet and gpis media):
/// kept verbatim so it can be handed to the library's mf_params_* C API.
struct ParamValue {
    enum class Kind { Float, Rgb, String, Int, Bool } kind = Kind::Float;
    double f = 0;
    Rgb rgb;
    std::string s;
    long long i = 0;
    bool b = false;
    SourceLoc loc;
};

struct MediumParamBag {
    std::string type;  // "macrofacet" or "gpis"
    std::string id;
    SourceLoc loc;     // of the <medium> element
    std::vector<std::pair<std::string, ParamValue>> params;  // in document order
    /// The parameters given as non-constant volumes or textures (field.h); null if none.
    std::shared_ptr<const MediumFields> fields;
    const ParamValue* get(const std::string& name) const {
        for (const auto& kv : params)
            if (kv.first == name) return &kv.second;
        return nullptr;
    }
};

}  // namespace mf
