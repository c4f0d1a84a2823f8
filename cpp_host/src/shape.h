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
    Vec2 uv;   // Mitsuba 3's texture coordinates of the shape
    Vec3 dpdu; // Mitsuba 3's dp/du (world space, not normalised; zero = none): the shading frame's
               // tangent s, along which alpha_u runs, is this made orthogonal to ns (Frame::shading)
    const Shape* shape = nullptr;
    uint32_t prim = 0;
    const TriMesh* mesh = nullptr;  // the hit mesh (MeshShape), for mesh_attribute textures
    Vec2 bary;                      // Embree's barycentrics (u, v) on a mesh triangle
    /// Where the BSDF's textures are looked up.
    TexturePoint texture_point() const {
        TexturePoint t(uv);
        t.mesh = mesh;
        t.prim = prim;
        t.bary = bary;
        return t;
    }
};

class Shape {
public:
    virtual ~Shape() = default;
    /// Mitsuba 3's dp/du (world space, not normalised) at a point p on or near the surface, for
    /// the anisotropic tangent of a local frame with unit normal n: Frame::shading(n, dpdu(...)).
    /// `prim` is the triangle when known (SurfaceHit::prim), else kNoPrim. Cheap (no search):
    ///   sphere     to_world * (-y, x, 0) * 2 pi of the local point (x, y, z) (Mitsuba's sphere);
    ///   rectangle  to_world * (2, 0, 0);  disk  to_world * (cos phi, sin phi, 0) (radial);
    ///   cube / meshes with uv  from the triangle's uv (Mitsuba's mesh rule);
    ///   meshes without uv, or a mesh point with prim = kNoPrim whose triangles differ: the
    ///   first axis of Frame(face normal) resp. Frame(n) (Mitsuba: coordinate_system(n)).
    /// The default is that last rule for any shape.
    virtual Vec3 dpdu(const Vec3& p, const Vec3& n, uint32_t prim) const {
        (void)p;
        (void)prim;
        return Frame(n).s;
    }
    static constexpr uint32_t kNoPrim = ~0u;
    /// Whether the shape has Mitsuba uv (texture coordinates) at its points.
    virtual bool has_uv() const { return false; }
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
    /// Parameter bags of the macrofacet/gpis media referenced by this shape, which the scene builder
    /// hands to the library (mf_params) when it builds the medium on this mean surface.
    std::shared_ptr<const MediumParamBag> interior_bag, exterior_bag;
    const Emitter* emitter = nullptr;  // area emitter attached to this shape (owned by the scene)
    /// A medium's region boundary built by the renderer (make_region_boundary): null BSDF, no
    /// emitter, nothing textured. A ray only passes through it, so its hits carry t, p and ng
    /// alone (Scene::intersect).
    bool region_boundary = false;
    /// Of a region boundary: a level of the mean surface's f that no point it encloses exceeds,
    /// nor any within float rounding of it (mf_enclosure_exit_level; 0: unknown).
    double exit_level = 0;
};

class MeshShape final : public Shape {
public:
    /// `mesh` must already be in world space with its final orientation. `winding_flipped`: the
    /// winding was reversed (flip_normals) after Mitsuba would have taken its face normals for
    /// dp/du (meshes without uv).
    MeshShape(TriMesh mesh, std::string kind, bool winding_flipped = false);
    Aabb bounds() const override { return bounds_; }
    float surface_area() const override { return area_; }
    void sample_position(const Vec2& u, Vec3* p, Vec3* n) const override;
    unsigned attach(RTCDevice device, RTCScene scene) const override;
    void fill_hit(const Ray& ray, float t, unsigned prim, float u, float v, SurfaceHit* hit) const override;
    std::string kind() const override { return kind_; }
    const TriMesh& mesh() const { return mesh_; }
    /// Analytic texture coordinates and dp/du of a world point (disk: Mitsuba's (r, phi / 2 pi),
    /// which no per-vertex interpolation can represent); overrides the mesh's uv and dp/du.
    using Parameterization = std::function<void(const Vec3& p, Vec2* uv, Vec3* dpdu)>;
    void set_parameterization(Parameterization f) { param_ = std::move(f); }
    Vec3 dpdu(const Vec3& p, const Vec3& n, uint32_t prim) const override;
    bool has_uv() const override { return !mesh_.uv.empty() || bool(param_); }

private:
    TriMesh mesh_;
    std::string kind_;
    Aabb bounds_;
    float area_ = 0;
    std::vector<float> cdf_;  // cumulative triangle areas
    Parameterization param_;
    std::vector<Vec3> dpdu_;  // per triangle (Mitsuba's mesh rule)
    bool uniform_dpdu_ = false;  // all triangles share dpdu_[0] (rectangle, planar uv)
};

class SphereShape final : public Shape {
public:
    /// `rotation`: the rotation part of Mitsuba's to_world (object frame for uv and dp/du).
    SphereShape(const Vec3& center, float radius, bool flip, const Mat4& rotation = Mat4())
        : c_(center), r_(radius), flip_(flip), rot_(rotation) {}
    Vec3 dpdu(const Vec3& p, const Vec3& n, uint32_t prim) const override;
    bool has_uv() const override { return true; }
    Aabb bounds() const override;
    float surface_area() const override { return 4.0f * kPi * r_ * r_; }
    void sample_position(const Vec2& u, Vec3* p, Vec3* n) const override;
    unsigned attach(RTCDevice device, RTCScene scene) const override;
    void fill_hit(const Ray& ray, float t, unsigned prim, float u, float v, SurfaceHit* hit) const override;
    std::string kind() const override { return "sphere"; }
    const Vec3& center() const { return c_; }
    float radius() const { return r_; }
    bool flipped() const { return flip_; }
    /// The object's +z axis in world space: Mitsuba's u runs around it.
    Vec3 pole() const { return normalize(rot_.vector(Vec3(0, 0, 1))); }
    /// Exact ray–sphere intersection in double precision; smallest root in (tnear, tfar).
    bool intersect(const Vec3& o, const Vec3& d, float tnear, float tfar, float* t) const;
    /// Both roots t0 <= t1 of the line o + t d on the sphere of radius `radius` around the centre
    /// (double precision, numerically stable); false when the line misses it.
    bool chord(const Vec3& o, const Vec3& d, double radius, double* t0, double* t1) const;
    /// False only where `chord` finds nothing of the half-line t >= 0 inside that sphere: the
    /// line misses it, or starts outside and heads away. From chord's own coefficients, without
    /// its square root.
    bool may_enter(const Vec3& o, const Vec3& d, double radius) const {
        // From outside (c > 0) heading away (b >= 0) both roots are <= 0: chord's t1 = c / q < 0.
        const Quadratic q = quadratic(o, d, c_, radius);
        return q.disc >= 0 && (q.c <= 0 || q.b < 0);
    }
    /// The line's quadratic |o + t d - centre|^2 = radius^2 as a t^2 + 2 b t + c = 0, and
    /// b^2 - a c, in double precision (with radius 0, c is |o - centre|^2).
    struct Quadratic {
        double a, b, c, disc;
    };
    static Quadratic quadratic(const Vec3& o, const Vec3& d, const Vec3& centre, double radius) {
        double ox = double(o.x) - centre.x, oy = double(o.y) - centre.y, oz = double(o.z) - centre.z;
        double a = double(d.x) * d.x + double(d.y) * d.y + double(d.z) * d.z;
        double b = ox * d.x + oy * d.y + oz * d.z;
        double c = ox * ox + oy * oy + oz * oz - radius * radius;
        return Quadratic{a, b, c, b * b - a * c};
    }

private:
    /// Local unit direction of world point p (Mitsuba's to_object(p), normalised).
    Vec3 local_dir(const Vec3& p) const;
    Vec3 c_;
    float r_;
    bool flip_;
    Mat4 rot_;
};

/// Mitsuba's canonical meshes (local space).
TriMesh make_cube_mesh();       // [-1,1]^3, outward normals, per-face vertices, Mitsuba's uv
TriMesh make_rectangle_mesh();  // [-1,1]^2 at z = 0, normal +z
TriMesh make_disk_mesh(int segments = 256);  // unit disk at z = 0, normal +z
/// Mitsuba's cylinder: radius 1 around z, z in [0, 1], open ends, normals outwards; `segments`
/// facets (1024: the surface is within 5e-6 radii of the true cylinder, normals are exact).
TriMesh make_cylinder_mesh(int segments = 1024);
TriMesh make_sphere_mesh(int rings, int segments);  // unit sphere tessellation (tests)

}  // namespace mf
