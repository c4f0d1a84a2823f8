// mfhost — the Embree user-geometry boilerplate shared by the analytic shapes (SphereShape,
// LevelSetShape): one primitive whose bounds come from the shape's bounds() and whose hits come
// from a per-shape intersection routine; RTCRayN unpacking and RTCHitN filling live here only.
#pragma once

#include <embree3/rtcore.h>

#include "math.h"

namespace mf {

/// One hit of a user-geometry shape: ray parameter, the geometric normal handed to Embree and
/// the u coordinate (v = 0) that Embree passes back to Shape::fill_hit.
struct UserGeometryHit {
    float t;
    Vec3 ng;
    float u;
};

/// `Hit(shape, o, d, tnear, tfar, &hit)` reports the first hit with t in (tnear, tfar). The
/// occlusion query uses the same routine and ignores everything but whether it hit.
template <class S, bool (*Hit)(const S&, const Vec3&, const Vec3&, float, float, UserGeometryHit*)>
struct UserGeometry {
    static void bounds(const RTCBoundsFunctionArguments* args) {
        const S* s = static_cast<const S*>(args->geometryUserPtr);
        Aabb b = s->bounds();
        args->bounds_o->lower_x = b.lo.x; args->bounds_o->lower_y = b.lo.y; args->bounds_o->lower_z = b.lo.z;
        args->bounds_o->upper_x = b.hi.x; args->bounds_o->upper_y = b.hi.y; args->bounds_o->upper_z = b.hi.z;
    }

    static void intersect(const RTCIntersectFunctionNArguments* args) {
        const S* s = static_cast<const S*>(args->geometryUserPtr);
        for (unsigned i = 0; i < args->N; ++i) {
            if (!args->valid[i]) continue;
            RTCRayN* ray = RTCRayHitN_RayN(args->rayhit, args->N);
            RTCHitN* hit = RTCRayHitN_HitN(args->rayhit, args->N);
            UserGeometryHit h;
            if (!Hit(*s, origin(ray, args->N, i), direction(ray, args->N, i), RTCRayN_tnear(ray, args->N, i),
                     RTCRayN_tfar(ray, args->N, i), &h))
                continue;
            RTCRayN_tfar(ray, args->N, i) = h.t;
            RTCHitN_Ng_x(hit, args->N, i) = h.ng.x;
            RTCHitN_Ng_y(hit, args->N, i) = h.ng.y;
            RTCHitN_Ng_z(hit, args->N, i) = h.ng.z;
            RTCHitN_u(hit, args->N, i) = h.u;
            RTCHitN_v(hit, args->N, i) = 0.0f;
            RTCHitN_primID(hit, args->N, i) = args->primID;
            RTCHitN_geomID(hit, args->N, i) = args->geomID;
            RTCHitN_instID(hit, args->N, i, 0) = args->context->instID[0];
        }
    }

    static void occluded(const RTCOccludedFunctionNArguments* args) {
        const S* s = static_cast<const S*>(args->geometryUserPtr);
        for (unsigned i = 0; i < args->N; ++i) {
            if (!args->valid[i]) continue;
            RTCRayN* ray = args->ray;
            UserGeometryHit h;
            if (Hit(*s, origin(ray, args->N, i), direction(ray, args->N, i), RTCRayN_tnear(ray, args->N, i),
                    RTCRayN_tfar(ray, args->N, i), &h))
                RTCRayN_tfar(ray, args->N, i) = -kInf;
        }
    }

    /// Creates the geometry (user data = `shape`), attaches it to `scene` and returns its id.
    static unsigned attach(RTCDevice device, RTCScene scene, const S* shape) {
        RTCGeometry g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_USER);
        rtcSetGeometryUserPrimitiveCount(g, 1);
        rtcSetGeometryUserData(g, const_cast<S*>(shape));
        rtcSetGeometryBoundsFunction(g, bounds, nullptr);
        rtcSetGeometryIntersectFunction(g, intersect);
        rtcSetGeometryOccludedFunction(g, occluded);
        rtcCommitGeometry(g);
        unsigned id = rtcAttachGeometry(scene, g);
        rtcReleaseGeometry(g);
        return id;
    }

private:
    static Vec3 origin(RTCRayN* ray, unsigned N, unsigned i) {
        return Vec3(RTCRayN_org_x(ray, N, i), RTCRayN_org_y(ray, N, i), RTCRayN_org_z(ray, N, i));
    }
    static Vec3 direction(RTCRayN* ray, unsigned N, unsigned i) {
        return Vec3(RTCRayN_dir_x(ray, N, i), RTCRayN_dir_y(ray, N, i), RTCRayN_dir_z(ray, N, i));
    }
};

}  // namespace mf
