// mfhost — the renderable scene: shapes in an Embree BVH, emitters, camera and settings.
#pragma once

#include <embree3/rtcore.h>

#include <memory>
#include <string>
#include <vector>

#include "emitter.h"
#include "film.h"
#include "medium.h"
#include "shape.h"

namespace mf {

/// Mitsuba `perspective` sensor: local frame looks down +z with +x to the left of the image
/// and +y up; fov measured along fov_axis (x, y, diagonal, smaller, larger). Mitsuba's
/// `orthographic` (orthographic = true): parallel rays along local +z from the near plane over
/// x in [-1, 1], y in [-1/aspect, 1/aspect] (to_world scales that window).
class MacrofacetMedium;

struct Camera {
    Mat4 to_world;
    bool orthographic = false;
    float tan_half_x = 0.5f, tan_half_y = 0.5f;
    float near_clip = 1e-2f, far_clip = 1e4f;
    int width = 768, height = 576;
    /// Primary ray through film position (fx, fy) in pixels (0..width, 0..height).
    Ray generate_ray(float fx, float fy) const;
};

/// How light from non-delta emitters is gathered at non-delta vertices: emitter sampling (NEE)
/// and BSDF / phase sampling combined by the power heuristic (the default, as Mitsuba's volpath),
/// or one of them alone (delta emitters are always sampled). Each is an unbiased estimator of the
/// same image, so the three agree in expectation (test_render/light_sampling_estimators_agree).
enum class LightSampling { Mis, BsdfOnly, EmitterOnly };

/// IntegratorSettings::shadow_roulette's default. On bench/anchor.xml's thin torus shell it took
/// 8.5 % off the rendering's instructions (64², 8 spp) for 0.23 % more pixel variance (128², 16 spp,
/// 24 seeds a side; 0.3: 10 % for 2.4 %), on the torus as roughconductor 3.4 % for 0.10 %.
constexpr float kShadowRoulette = 0.1f;

struct IntegratorSettings {
    std::string name = "path";  // the XML plugin: volpath, path or direct (path with max_depth 2)
    bool volumetric = true;  // volpath (media) or path and direct (media ignored)
    int max_depth = -1;      // -1 = unbounded
    int rr_depth = 5;
    bool hide_emitters = false;
    LightSampling light_sampling = LightSampling::Mis;  // not in the XML (Mitsuba 3.9.1 has no such parameter)
    /// Russian roulette on next-event rays by their unoccluded contribution, before their
    /// transmittance (Pharr et al., PBRT 3rd ed., §13.7): a ray whose weight
    /// g = max(f) w / p_light (its contribution over the path's throughput times the emitter's
    /// radiance) is below this is traced with probability g / shadow_roulette and weighted by
    /// its inverse, so a kept one adds at most shadow_roulette times throughput times radiance
    /// (no fireflies). Such rays are mostly MIS-weighted within a lobe or far outside it; the
    /// tracked ones of a macrofacet shell cost ~6 occlusion rays each. 0: every ray is traced
    /// (mfrender --no-shadow-roulette). Not in the XML (Mitsuba 3.9.1 has no such parameter).
    float shadow_roulette = kShadowRoulette;
};

/// A medium present wherever a ray goes, whose extinction vanishes outside the sphere `region`:
/// a macrofacet medium in vacuum (above its shell's top, sigma_t = 0), tracked over the chord of
/// its region along every ray instead of behind a boundary in the BVH, which costs a ray two
/// crossings, each an Embree traversal, per pass through a shell (issue 8). The chord is widened
/// by kRegionMargin of the radius for the boundary's float rounding.
class SuperposedMedium {
public:
    SuperposedMedium(const Medium* medium, std::shared_ptr<const SphereShape> region)
        : medium_(medium), region_(std::move(region)) {}
    const Medium* medium() const { return medium_; }
    const SphereShape& region() const { return *region_; }
    /// Medium::sample_free_flight over the part of [0, t_max] inside the region (*weight and
    /// *pdf_ratio are 1 when the ray misses it).
    bool sample_free_flight(const Ray& ray, float t_max, const MediumInteraction* from, int channel, Sampler& sampler,
                            MediumInteraction* mi, Rgb* weight, Rgb* pdf_ratio) const;
    /// False only where the ray's half-line has no part inside the region (clip finds nothing
    /// for any t_max): a cheaper test, for rays that meet no medium.
    bool may_enter(const Ray& ray) const { return region_->may_enter(ray.o, ray.d, radius()); }
    /// Medium::transmittance over the part of [0, t_max] inside the region.
    Rgb transmittance(const Ray& ray, float t_max, Sampler& sampler) const;
    /// Medium::transmittance_kept over that part: an estimate of T / survival.
    Rgb transmittance_kept(const Ray& ray, float t_max, Sampler& sampler, double survival) const;

private:
    static constexpr double kRegionMargin = 1e-4;
    /// The region's radius with the margin.
    double radius() const { return double(region_->radius()) * (1.0 + kRegionMargin); }
    /// The part [t0, t1] of [0, t_max] inside the region, as a ray starting at t0; false if empty.
    bool clip(const Ray& ray, float t_max, Ray* inside, float* t0, float* length) const;
    const Medium* medium_;
    std::shared_ptr<const SphereShape> region_;
};

struct SceneSummary {
    size_t shapes = 0, triangles = 0, emitters = 0, media = 0;
};

class Scene {
public:
    Scene();
    ~Scene();
    Scene(const Scene&) = delete;
    Scene& operator=(const Scene&) = delete;

    void add_shape(std::shared_ptr<Shape> s);
    void add_emitter(std::shared_ptr<Emitter> e);
    /// Build the BVH. Must be called once after all shapes are added.
    void commit();

    /// Closest hit with t in (ray.tmin, ray.tmax).
    bool intersect(const Ray& ray, SurfaceHit* hit) const;
    /// A scene of some of the shapes (already added): those in the box `region` that holds the
    /// region of a medium that finds its rays' exits itself (Medium::finds_exits), its boundary
    /// left out. Returns its index for intersect_near.
    unsigned add_near_scene(const std::vector<std::shared_ptr<Shape>>& shapes, const Aabb& region);
    /// intersect against near scene `index` only, and within its region's box (where the
    /// medium's flights end, at the latest).
    bool intersect_near(unsigned index, const Ray& ray, SurfaceHit* hit) const;

    const std::vector<std::shared_ptr<Shape>>& shapes() const { return shapes_; }
    const std::vector<std::shared_ptr<Emitter>>& emitters() const { return emitters_; }
    const std::vector<const Emitter*>& infinite_emitters() const { return infinite_; }
    void add_superposed_medium(SuperposedMedium m);
    const std::vector<SuperposedMedium>& superposed_media() const { return superposed_; }
    /// Whether the ray may enter a superposed medium's region (SuperposedMedium::may_enter).
    bool may_enter_superposed(const Ray& ray) const {
        for (const SuperposedMedium& m : superposed_)
            if (m.may_enter(ray)) return true;
        return false;
    }
    /// The opaque core of a macrofacet shell on the sphere of `center` and `radius`
    /// (MacrofacetMedium::opaque_core): rays from f >= start_level that reach f <= core_level
    /// have a transmittance that rounds to 0.
    /// `medium` plays the depth roulette of shadow rays that descend into its shell
    /// (shadow_roulette).
    void add_opaque_core(const Vec3& center, double radius, double start_level, double core_level,
                         const MacrofacetMedium* medium);
    /// True when the ray o + s d, s in [0, dist), meets an opaque core from an origin that may use
    /// it: a shadow ray that needs neither its phase or BSDF value nor tracking (its estimate
    /// would be 0). A few dozen instructions per core.
    bool blocked_by_opaque_core(const Vec3& o, const Vec3& d, float dist) const;
    bool has_opaque_cores() const { return !cores_.empty(); }
    /// The depth roulette of a shadow ray o + s d, s in [0, dist) (mf_track_depth_roulette): the
    /// ray descends into the first shell with a core from its height at o to its chord's deepest
    /// point, which bounds its transmittance there. `survival` is the probability with which it
    /// is kept (1: no roulette; 0: not kept, its estimate is 0 and nothing need be evaluated),
    /// and `medium` the shell's, whose transmittance estimate takes it (Medium::transmittance_kept).
    struct ShadowRoulette {
        double survival = 1.0;
        const Medium* medium = nullptr;
    };
    ShadowRoulette shadow_roulette(const Vec3& o, const Vec3& d, float dist, Sampler& sampler) const;
    /// What the opaque cores say of a next-event ray, before anything is evaluated for it:
    /// survival 0 where it meets a core (blocked_by_opaque_core), else shadow_roulette's.
    ShadowRoulette next_event_roulette(const Vec3& o, const Vec3& d, float dist, Sampler& sampler) const;
    const Aabb& bounds() const { return bounds_; }
    SceneSummary summary() const;

    Camera camera;
    std::shared_ptr<const Medium> camera_medium;
    IntegratorSettings integrator;
    int spp = 16;
    uint64_t seed = 0;
    ReconstructionFilter filter;  // Mitsuba's hdrfilm default: gaussian, stddev 0.5
    uint64_t content_hash = 0;    // of the scene's XML text and -D values (shard compatibility)
    std::vector<std::shared_ptr<const Medium>> media;  // keeps media alive

private:
    /// An Embree scene and its shapes by geometry id.
    struct Traced {
        RTCScene scene = nullptr;
        std::vector<const Shape*> by_geom_id;
        Aabb bounds;  // of the shapes, padded (Scene::commit, add_near_scene)
        Aabb region;  // add_near_scene
        void attach(RTCDevice device, const Shape& s);
        bool intersect(const Ray& ray, SurfaceHit* hit) const;
    };
    RTCDevice device_ = nullptr;
    Traced all_;
    std::vector<Traced> near_;  // add_near_scene (a null scene: no shape)
    std::vector<std::shared_ptr<Shape>> shapes_;
    std::vector<std::shared_ptr<Emitter>> emitters_;
    std::vector<const Emitter*> infinite_;
    std::vector<SuperposedMedium> superposed_;
    /// add_opaque_core: squared radii, each with a margin for the chord's rounding.
    struct OpaqueCore {
        Vec3 center;
        double start_radius2, core_radius2, radius, top;
        const MacrofacetMedium* medium;
    };
    std::vector<OpaqueCore> cores_;
    /// A ray o + s d seen from a core's centre c: |o − c|², (o − c)·d and d·d.
    struct CoreChord {
        double oo, b, dd;
    };
    static CoreChord chord_of(const OpaqueCore& c, const Vec3& o, const Vec3& d);
    /// blocked_by_opaque_core for one core.
    static bool blocks(const OpaqueCore& c, const CoreChord& ray, float dist);
    /// shadow_roulette's levels for one core: false when the ray does not descend into its shell.
    static bool descends(const OpaqueCore& c, const CoreChord& ray, float dist, double* f_from, double* f_to);
    static ShadowRoulette roulette(const OpaqueCore& c, double f_from, double f_to, Sampler& sampler);
    Aabb bounds_;
};

}  // namespace mf
