// mfhost — signed distance queries.
//
// Convention (shared with the Rust core's macrofacet medium): f > 0 on the side the surface
// normal points to ("outside"), f < 0 inside, |grad| = 1 wherever f is differentiable.
#pragma once

#include <memory>
#include <vector>

#include "math.h"

namespace mf {

struct SdfSample {
    float f = kInf;  // signed distance
    Vec3 grad;       // unit gradient of f (outward normal of the closest surface feature at f = 0)
};

/// Exact SDFs of Mitsuba's canonical shapes in their local frames.
SdfSample sdf_sphere(const Vec3& p, const Vec3& center, float radius);
SdfSample sdf_cube_local(const Vec3& p);       // [-1,1]^3
SdfSample sdf_rectangle_local(const Vec3& p);  // [-1,1]^2 at z = 0, normal +z (sign: side of +z)
SdfSample sdf_disk_local(const Vec3& p);       // unit disk at z = 0, normal +z (sign: side of +z)

/// Signed distance to a triangle mesh: closest point over a BVH, sign from angle-weighted
/// pseudo-normals (Bærentzen & Aanæs 2005). Vertices are welded by exact position first so that
/// meshes split by normals/uvs still have correct vertex/edge pseudo-normals. Degenerate
/// triangles (zero area) contribute no face normal and are treated as their three edges.
/// For open meshes the sign is that of the side of the closest feature (like the rectangle).
class MeshSdf {
public:
    MeshSdf(const std::vector<Vec3>& positions, const std::vector<uint32_t>& indices);
    SdfSample eval(const Vec3& p) const;
    /// eval() plus a smooth normal: the angle-weighted vertex pseudo-normals interpolated
    /// barycentrically at the closest point (Phong-style; continuous across edges, unlike grad).
    SdfSample eval(const Vec3& p, Vec3* smooth_normal) const;
    /// Unsigned distance, closest point and the pseudo-normal of the closest feature; when
    /// `smooth_normal` is given, also the interpolated vertex normal at the closest point.
    float closest(const Vec3& p, Vec3* closest_point, Vec3* pseudo_normal, Vec3* smooth_normal = nullptr) const;
    size_t num_triangles() const { return tri_.size(); }

private:
    struct Tri {
        uint32_t v[3];
        Vec3 fn;      // unit face normal (zero if degenerate)
        Vec3 en[3];   // unit edge pseudo-normals for edges (v0v1, v1v2, v2v0)
        Vec3 bc;      // bounding sphere (centre, radius): a cheap lower bound of the distance
        float br;
        bool degenerate;
    };
    struct Node {
        Aabb box;
        uint32_t left_or_first;  // inner: index of left child (right = left + 1); leaf: first triangle
        uint32_t count;          // 0 for inner nodes
    };
    void build(uint32_t node, uint32_t first, uint32_t count, std::vector<Vec3>& centroids);
    float closest_in_tri(const Tri& t, const Vec3& p, Vec3* c, Vec3* pn) const;

    std::vector<Vec3> pos_;
    std::vector<Vec3> vn_;  // angle-weighted vertex pseudo-normals
    std::vector<Tri> tri_;
    std::vector<Node> nodes_;
    float scale_ = 1.0f;
};

}  // namespace mf
