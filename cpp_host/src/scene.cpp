// mfhost — scene and Embree plumbing (see scene.h).
#include "scene.h"

#include <algorithm>
#include <cstdio>

#include "error.h"

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

Scene::Scene() {
    device_ = rtcNewDevice(nullptr);
    if (!device_) throw Error("could not create the Embree device");
    rtcSetDeviceErrorFunction(device_, embree_error, nullptr);
    scene_ = rtcNewScene(device_);
    rtcSetSceneBuildQuality(scene_, RTC_BUILD_QUALITY_HIGH);
    rtcSetSceneFlags(scene_, RTC_SCENE_FLAG_ROBUST);
}

Scene::~Scene() {
    if (scene_) rtcReleaseScene(scene_);
    if (device_) rtcReleaseDevice(device_);
}

void Scene::add_shape(std::shared_ptr<Shape> s) {
    unsigned id = s->attach(device_, scene_);
    if (by_geom_id_.size() <= id) by_geom_id_.resize(id + 1, nullptr);
    by_geom_id_[id] = s.get();
    bounds_.expand(s->bounds());
    shapes_.push_back(std::move(s));
}

bool SuperposedMedium::clip(const Ray& ray, float t_max, Ray* inside, float* t0, float* length) const {
    double lo, hi;
    if (!region_->chord(ray.o, ray.d, double(region_->radius()) * (1.0 + kRegionMargin), &lo, &hi)) return false;
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

void Scene::add_superposed_medium(SuperposedMedium m) {
    bounds_.expand(m.region().bounds());
    superposed_.push_back(std::move(m));
}

void Scene::add_emitter(std::shared_ptr<Emitter> e) {
    if (e->is_infinite()) infinite_.push_back(e.get());
    emitters_.push_back(std::move(e));
}

void Scene::commit() {
    rtcCommitScene(scene_);
    if (rtcGetDeviceError(device_) != RTC_ERROR_NONE) throw Error("Embree failed to build the scene BVH");
}

bool Scene::intersect(const Ray& ray, SurfaceHit* hit) const {
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
    rtcIntersect1(scene_, &ctx, &rh);
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return false;
    const Shape* s = by_geom_id_[rh.hit.geomID];
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
