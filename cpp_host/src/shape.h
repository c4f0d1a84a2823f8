// mfhost — shapes: Embree geometry, surface sampling and signed distance queries.
//
// Every shape is one Embree geometry (triangle meshes; spheres are exact user geometries). The
// signed distance of a shape that is the mean surface of a medium belongs to the library
// (mean_surface.h).
#pragma once

#include <embree3/rtcore.h>

#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "bsdf.h"
#include "error.h"
#include "math.h"
#include "medium.h"
#include "mesh_io.h"

namespace mf {

class Shape;
class Emitter;

struct SurfaceHit {
    float t = kInf;
    Vec3 p;
    Vec3 ng;  // unit geometric normal (after flip_normals; the "outside" side)
    Vec3 ns;  // unit shading normal
    Vec2 uv;
    const Shape* shape = nullptr;
    uint32_t prim = 0;
};

class Shape {
public:
    virtual ~Shape() = default;
    virtual Aabb bounds() const = 0;
    virtual float surface_area() const = 0;
    /// Uniform sampling by area: position and unit normal (pdf = 1 / surface_area()).
    virtual void sample_position(const Vec2& u, Vec3* p, Vec3* n) const = 0;
    /// Create the Embree geometry, attach it to `scene`, return its geometry id.
    virtual unsigned attach(RTCDevice device, RTCScene scene) const = 0;
    /// Complete a hit record from Embree's (t, primID, u, v).
    virtual void fill_hit(const Ray& ray, float t, unsigned prim, float u, float v, SurfaceHit* hit) const = 0;
    virtual std::string kind() const = 0;

    /// A shape whose interior or exterior medium is set changes the current medium when a ray
    /// crosses it (Mitsuba's is_medium_transition); otherwise the medium is unchanged.
    bool is_medium_transition() const { return interior || exterior || interior_bag || exterior_bag; }
    const Medium* target_medium(const Vec3& ng, const Vec3& d) const {
        return dot(d, ng) < 0 ? interior.get() : exterior.get();
    }

    std::string id;
    SourceLoc loc;
    std::shared_ptr<const Bsdf> bsdf;
    std::shared_ptr<const Medium> interior, exterior;
    /// Parameter bags of macrofacet/gpis media referenced by this shape (phase 2 input).
    std::shared_ptr<const MediumParamBag> interior_bag, exterior_bag;
    const Emitter* emitter = nullptr;  // area emitter attached to this shape (owned by the scene)
};

class MeshShape final : public Shape {
public:
    /// `mesh` must already be in world space with its final orientation.
    MeshShape(TriMesh mesh, std::string kind);
    Aabb bounds() const override { return bounds_; }
    float surface_area() const override { return area_; }
    void sample_position(const Vec2& u, Vec3* p, Vec3* n) const override;
    unsigned attach(RTCDevice device, RTCScene scene) const override;
    void fill_hit(const Ray& ray, float t, unsigned prim, float u, float v, SurfaceHit* hit) const override;
    std::string kind() const override { return kind_; }
    const TriMesh& mesh() const { return mesh_; }

private:
    TriMesh mesh_;
    std::string kind_;
    Aabb bounds_;
    float area_ = 0;
    std::vector<float> cdf_;  // cumulative triangle areas
};

class SphereShape final : public Shape {
public:
    /// `pole`: the object's +z axis in world space (Mitsuba's u runs around it).
    SphereShape(const Vec3& center, float radius, bool flip, const Vec3& pole = Vec3(0, 0, 1))
        : c_(center), r_(radius), flip_(flip), pole_(normalize(pole)) {}
    Aabb bounds() const override;
    float surface_area() const override { return 4.0f * kPi * r_ * r_; }
    void sample_position(const Vec2& u, Vec3* p, Vec3* n) const override;
    unsigned attach(RTCDevice device, RTCScene scene) const override;
    void fill_hit(const Ray& ray, float t, unsigned prim, float u, float v, SurfaceHit* hit) const override;
    std::string kind() const override { return "sphere"; }
    const Vec3& center() const { return c_; }
    float radius() const { return r_; }
    bool flipped() const { return flip_; }
    const Vec3& pole() const { return pole_; }
    /// Exact ray–sphere intersection in double precision; smallest root in (tnear, tfar).
    bool intersect(const Vec3& o, const Vec3& d, float tnear, float tfar, float* t) const;

private:
    Vec3 c_;
    float r_;
    bool flip_;
    Vec3 pole_;
};

/// Mitsuba's canonical meshes (local space).
TriMesh make_cube_mesh();       // [-1,1]^3, outward normals, per-face vertices
TriMesh make_rectangle_mesh();  // [-1,1]^2 at z = 0, normal +z
TriMesh make_disk_mesh(int segments = 256);  // unit disk at z = 0, normal +z
TriMesh make_sphere_mesh(int rings, int segments);  // unit sphere tessellation (tests)

}  // namespace mf
