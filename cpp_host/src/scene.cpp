// mfhost — scene and Embree plumbing (see scene.h).
#include "scene.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "error.h"
#include "medium_macrofacet.h"

namespace mf {

Ray Camera::generate_ray(float fx, float fy) const {
    float sx = fx / float(width), sy = fy / float(height);
    if (orthographic) {
        Vec3 o = to_world.point(Vec3(1.0f - 2.0f * sx, (1.0f - 2.0f * sy) * float(height) / float(width), near_clip));
        Vec3 z = to_world.vector(Vec3(0, 0, 1));
        return Ray(o, normalize(z), 0.0f, (far_clip - near_clip) * length(z));
    }
    // Mitsuba: image x grows to the right = local -x; image y grows downwards = local -y.
    Vec3 d_local((1.0f - 2.0f * sx) * tan_half_x, (1.0f - 2.0f * sy) * tan_half_y, 1.0f);
    float inv_z = 1.0f / length(d_local);
    Vec3 dl = d_local * inv_z;
    Vec3 o = to_world.point(Vec3(0, 0, 0));
    Vec3 d = normalize(to_world.vector(dl));
    // near/far clip planes are measured along the local z axis
    return Ray(o, d, near_clip / dl.z, far_clip / dl.z);
}

static void embree_error(void*, RTCError code, const char* str) {
    std::fprintf(stderr, "mfrender: embree error %d: %s\n", int(code), str ? str : "");
}

static RTCScene new_scene(RTCDevice device) {
    RTCScene scene = rtcNewScene(device);
    rtcSetSceneBuildQuality(scene, RTC_BUILD_QUALITY_HIGH);
    rtcSetSceneFlags(scene, RTC_SCENE_FLAG_ROBUST);
    return scene;
}

/// `b` grown by 1e-4 of its extent or coordinates, whichever is larger: a box test against it
/// does not drop a hit that the float slabs round off.
static Aabb padded(const Aabb& b) {
    if (!b.valid()) return b;  // no shape: no ray hits the empty box
    const Vec3 e = b.extent();
    const float largest = std::max({e.x, e.y, e.z, std::abs(b.lo.x), std::abs(b.lo.y), std::abs(b.lo.z),
                                    std::abs(b.hi.x), std::abs(b.hi.y), std::abs(b.hi.z)});
    const Vec3 pad(1e-4f * largest);
    Aabb grown = b;
    grown.lo = b.lo - pad;
    grown.hi = b.hi + pad;
    return grown;
}

Scene::Scene() {
    device_ = rtcNewDevice(nullptr);
    if (!device_) throw Error("could not create the Embree device");
    rtcSetDeviceErrorFunction(device_, embree_error, nullptr);
    all_.scene = new_scene(device_);
}

Scene::~Scene() {
    for (Traced& t : near_)
        if (t.scene) rtcReleaseScene(t.scene);
    if (all_.scene) rtcReleaseScene(all_.scene);
    if (device_) rtcReleaseDevice(device_);
}

void Scene::Traced::attach(RTCDevice device, const Shape& s) {
    unsigned id = s.attach(device, scene);
    if (by_geom_id.size() <= id) by_geom_id.resize(id + 1, nullptr);
    by_geom_id[id] = &s;
    bounds.expand(s.bounds());
}

void Scene::add_shape(std::shared_ptr<Shape> s) {
    all_.attach(device_, *s);
    bounds_.expand(s->bounds());
    shapes_.push_back(std::move(s));
}

unsigned Scene::add_near_scene(const std::vector<std::shared_ptr<Shape>>& shapes, const Aabb& region) {
    Traced t;
    t.region = region;
    if (!shapes.empty()) {
        t.scene = new_scene(device_);
        for (const auto& s : shapes) t.attach(device_, *s);
        t.bounds = padded(t.bounds);
    }
    near_.push_back(std::move(t));
    return unsigned(near_.size() - 1);
}

bool SuperposedMedium::clip(const Ray& ray, float t_max, Ray* inside, float* t0, float* length) const {
    double lo, hi;
    if (!region_->chord(ray.o, ray.d, radius(), &lo, &hi)) return false;
    lo = std::max(lo, 0.0);
    hi = std::min(hi, double(t_max));
    if (!(lo < hi)) return false;
    *t0 = float(lo);
    *length = float(hi - lo);
    *inside = Ray(ray.at(*t0), ray.d);
    return true;
}

bool SuperposedMedium::sample_free_flight(const Ray& ray, float t_max, const MediumInteraction* from, int channel, Sampler& sampler,
                                          MediumInteraction* mi, Rgb* weight, Rgb* pdf_ratio) const {
    Ray inside;
    float t0, length;
    if (!clip(ray, t_max, &inside, &t0, &length)) {
        *weight = *pdf_ratio = Rgb(1.0f);
        return false;
    }
    if (!medium_->sample_free_flight(inside, length, from, channel, sampler, mi, weight, pdf_ratio)) return false;
    mi->t += t0;
    return true;
}

Rgb SuperposedMedium::transmittance(const Ray& ray, float t_max, Sampler& sampler) const {
    Ray inside;
    float t0, length;
    if (!clip(ray, t_max, &inside, &t0, &length)) return Rgb(1.0f);
    return medium_->transmittance(inside, length, sampler);
}

Rgb SuperposedMedium::transmittance_kept(const Ray& ray, float t_max, Sampler& sampler, double survival) const {
    Ray inside;
    float t0, length;
    if (!clip(ray, t_max, &inside, &t0, &length)) return Rgb(float(1.0 / survival));
    return medium_->transmittance_kept(inside, length, sampler, survival);
}

void Scene::add_superposed_medium(SuperposedMedium m) {
    bounds_.expand(m.region().bounds());
    superposed_.push_back(std::move(m));
}

void Scene::add_opaque_core(const Vec3& center, double radius, double start_level, double core_level,
                            const MacrofacetMedium* medium) {
    // The test's sphere lies 1e-6 r inside the core and its origins 1e-6 r above the start level:
    // far beyond the rounding of a chord in double precision (~1e-15 r).
    const double margin = 1e-6 * radius, core = radius + core_level - margin, start = radius + start_level + margin;
    if (!(core > 0) || !(start > core)) return;  // (a core deeper than the centre: none)
    cores_.push_back(OpaqueCore{center, start * start, core * core, radius, medium->shell_top(), medium});
}

Scene::CoreChord Scene::chord_of(const OpaqueCore& c, const Vec3& o, const Vec3& d) {
    const SphereShape::Quadratic q = SphereShape::quadratic(o, d, c.center, 0.0);  // (q.c = |o − c|²)
    return CoreChord{q.c, q.b, q.a};
}

bool Scene::blocks(const OpaqueCore& c, const CoreChord& ray, float dist) {
    // From above the start level (so outside the core), heading towards the centre.
    if (!(ray.oo >= c.start_radius2) || !(ray.b < 0)) return false;
    const double disc = ray.b * ray.b - ray.dd * (ray.oo - c.core_radius2);
    if (!(disc > 0)) return false;
    return (-ray.b - std::sqrt(disc)) / ray.dd < double(dist);  // the entry (-b > 0: no cancellation)
}

bool Scene::descends(const OpaqueCore& c, const CoreChord& ray, float dist, double* f_from, double* f_to) {
    if (!(ray.b < 0)) return false;  // moving away from the centre: the height only grows
    // The chord's deepest point: its closest approach to the centre, or its end.
    const double s = std::min(-ray.b / ray.dd, double(dist));
    const double deepest2 = std::max(0.0, ray.oo + s * (2 * ray.b + s * ray.dd));
    // Heights rounded the bound's safe ways (the start down, the deepest point up) by the
    // opaque cores' margin, far beyond the rounding of doubles.
    const double margin = 1e-6 * c.radius;
    *f_from = std::sqrt(ray.oo) - c.radius - margin;
    *f_to = std::sqrt(deepest2) - c.radius + margin;
    // (Above the shell's top all along, or not descending: nothing to bound.)
    return *f_to < *f_from && *f_to < c.top;
}

Scene::ShadowRoulette Scene::roulette(const OpaqueCore& c, double f_from, double f_to, Sampler& sampler) {
    return ShadowRoulette{c.medium->depth_roulette(f_from, f_to, double(sampler.next_1d())), c.medium};
}

Scene::ShadowRoulette Scene::shadow_roulette(const Vec3& o, const Vec3& d, float dist, Sampler& sampler) const {
    double f_from, f_to;
    for (const OpaqueCore& c : cores_)
        if (descends(c, chord_of(c, o, d), dist, &f_from, &f_to)) return roulette(c, f_from, f_to, sampler);
    return ShadowRoulette{};
}

bool Scene::blocked_by_opaque_core(const Vec3& o, const Vec3& d, float dist) const {
    for (const OpaqueCore& c : cores_)
        if (blocks(c, chord_of(c, o, d), dist)) return true;
    return false;
}

Scene::ShadowRoulette Scene::next_event_roulette(const Vec3& o, const Vec3& d, float dist, Sampler& sampler) const {
    // One chord per core for both tests: any core in the way ends the ray; else the first shell
    // it descends into plays the roulette.
    const OpaqueCore* first = nullptr;
    double f_from = 0, f_to = 0;
    for (const OpaqueCore& c : cores_) {
        const CoreChord ray = chord_of(c, o, d);
        if (blocks(c, ray, dist)) return ShadowRoulette{0.0, nullptr};
        if (!first && descends(c, ray, dist, &f_from, &f_to)) first = &c;
    }
    return first ? roulette(*first, f_from, f_to, sampler) : ShadowRoulette{};
}

void Scene::add_emitter(std::shared_ptr<Emitter> e) {
    if (e->is_infinite()) infinite_.push_back(e.get());
    emitters_.push_back(std::move(e));
}

void Scene::commit() {
    all_.bounds = padded(all_.bounds);
    rtcCommitScene(all_.scene);
    for (Traced& t : near_)
        if (t.scene) rtcCommitScene(t.scene);
    if (rtcGetDeviceError(device_) != RTC_ERROR_NONE) throw Error("Embree failed to build the scene BVH");
}

bool Scene::intersect(const Ray& ray, SurfaceHit* hit) const {
    // A ray that misses the box of every traced shape needs no traversal: Embree's call costs
    // about 350 instructions before its first box test (superposed media and infinite emitters
    // are not in it; on bench/gpis_compare.xml most rays miss the only traced shape, the light).
    // (A ray from inside the box meets it: no test.)
    const Aabb& box = all_.bounds;
    if (!box.contains(ray.o)) {
        float t0 = ray.tmin, t1 = ray.tmax;
        if (!box.clip(ray.o, ray.d, &t0, &t1)) return false;
    }
    return all_.intersect(ray, hit);
}

bool Scene::intersect_near(unsigned index, const Ray& ray, SurfaceHit* hit) const {
    // (most rays in a shell miss the few shapes near it before they leave its box: box tests
    // instead of a traversal)
    const Traced& t = near_[index];
    if (!t.scene) return false;
    float t0 = ray.tmin, t1 = ray.tmax;
    if (!t.region.clip(ray.o, ray.d, &t0, &t1)) return false;
    float n0 = ray.tmin, n1 = t1;
    if (!t.bounds.clip(ray.o, ray.d, &n0, &n1)) return false;
    return t.intersect(Ray(ray.o, ray.d, ray.tmin, t1), hit);
}

bool Scene::Traced::intersect(const Ray& ray, SurfaceHit* hit) const {
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    RTCRayHit rh;
    rh.ray.org_x = ray.o.x; rh.ray.org_y = ray.o.y; rh.ray.org_z = ray.o.z;
    rh.ray.dir_x = ray.d.x; rh.ray.dir_y = ray.d.y; rh.ray.dir_z = ray.d.z;
    rh.ray.tnear = ray.tmin;
    rh.ray.tfar = ray.tmax;
    rh.ray.time = 0.0f;
    rh.ray.mask = 0xFFFFFFFFu;
    rh.ray.id = 0;
    rh.ray.flags = 0;
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.primID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(scene, &ctx, &rh);
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return false;
    const Shape* s = by_geom_id[rh.hit.geomID];
    if (s->region_boundary) {
        // A ray only passes through a region boundary (Shape::region_boundary): where, and on
        // which side (Embree's geometric normal, oriented as MeshShape::fill_hit's), without
        // reading the mesh's arrays.
        *hit = SurfaceHit();
        hit->t = rh.ray.tfar;
        hit->p = ray.at(rh.ray.tfar);
        hit->ng = hit->ns = normalize(Vec3(rh.hit.Ng_x, rh.hit.Ng_y, rh.hit.Ng_z));
        hit->shape = s;
        hit->prim = rh.hit.primID;
        return true;
    }
    s->fill_hit(ray, rh.ray.tfar, rh.hit.primID, rh.hit.u, rh.hit.v, hit);
    return true;
}

SceneSummary Scene::summary() const {
    SceneSummary s;
    s.shapes = shapes_.size();
    for (const auto& sh : shapes_)
        if (auto* m = dynamic_cast<const MeshShape*>(sh.get())) s.triangles += m->mesh().num_triangles();
    s.emitters = emitters_.size();
    s.media = media.size();
    return s;
}

}  // namespace mf
