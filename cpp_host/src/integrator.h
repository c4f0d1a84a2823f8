// mfhost — unidirectional volumetric path tracer (Mitsuba's `volpath`; `path` ignores media).
//
// Next-event estimation to every emitter type, combined with BSDF / phase sampling by the
// power heuristic (or either alone: IntegratorSettings::light_sampling); free flights, shadow
// transmittance and scattering are delegated to the current Medium and its phase function, the
// same way for every medium (a Dirac phase lobe, e.g. a gpis crossing, gets no NEE); null-BSDF
// surfaces are crossed (changing the medium) by both path and shadow rays, any other surface
// (dielectrics included) blocks shadow rays; Russian roulette from rr_depth, and on next-event
// rays by their unoccluded contribution (IntegratorSettings::shadow_roulette).
#pragma once

#include "sampler.h"
#include "scene.h"

namespace mf {

class PathIntegrator {
public:
    explicit PathIntegrator(const Scene& scene) : scene_(scene) {}
    /// Radiance along a primary ray starting in `medium`.
    Rgb Li(Ray ray, const Medium* medium, Sampler& sampler) const;
    /// A next-event estimate's transmittance from `o` along unit `d` over `dist` (may be inf),
    /// crossing null surfaces; a shell's opaque core and depth roulette first
    /// (Scene::next_event_roulette).
    Rgb shadow_transmittance(Vec3 o, const Vec3& d, float dist, const Medium* medium, Sampler& sampler) const;

private:
    /// The same for a ray `kept` by the depth roulette (Scene::shadow_roulette): an estimate of
    /// T / kept.survival, whose weight the roulette's medium takes in its own estimate. And with
    /// `unblocked()` called once after the first ray cast unless that cast found an opaque
    /// surface: 0 without tracking any medium when it returns false (a next-event estimate whose
    /// phase value is 0, computed only for rays that are not blocked at once).
    /// `from`: the medium event the ray leaves (its first segment starts there), or null.
    template <class Unblocked>
    Rgb shadow_transmittance(Vec3 o, const Vec3& d, float dist, const Medium* medium, const MediumInteraction* from,
                             Sampler& sampler, const Scene::ShadowRoulette& kept, Unblocked&& unblocked) const;

    const Scene& scene_;
};

/// Origin for a ray leaving surface point p with geometric normal ng in direction d.
inline Vec3 offset_ray_origin(const Vec3& p, const Vec3& ng, const Vec3& d) {
    float scale = 1.0f + max_comp(vabs(p));
    float eps = 2e-5f * scale;
    return dot(d, ng) >= 0 ? p + ng * eps : p - ng * eps;
}

}  // namespace mf
