// mfhost — the mean surface of a shape as the library sees it (an mf_surface), and the region
// boundary that tells Embree where a medium living on it begins.
//
// A shape whose interior is a macrofacet or gpis medium is the *mean surface* of a Gaussian-
// process statistical surface. The library owns its signed distance: spheres are exact
// (mf_surface_new_sphere, tangent = Mitsuba's dp/du around the sphere's pole), every mesh shape
// (obj, ply, cube, ...) is an exact triangle-mesh SDF (mf_surface_new_mesh: vertex normals for the
// frame as Mitsuba shades; the canonical cube has none, so its frame is the distance gradient).
// Mean surfaces must be closed: the medium fills their interior.
//
// The medium occupies f < level (the shell's top, kσ, for a macrofacet medium; the realization
// band for gpis). Embree sees a null-BSDF boundary whose interior is the medium: the exact offset
// sphere for spheres, otherwise the library's conservative enclosure (mf_surface_enclosure: grid
// cells that may meet the region), so no ray marches the signed distance to find the shell.
// (In scenes whose macrofacet media sit in vacuum, a sphere's boundary is the chord each ray is
// tracked over instead of a surface in the BVH: SuperposedMedium in scene.h.)
#pragma once

#include <cmath>
#include <memory>
#include <optional>

#include "math.h"

struct mf_surface;

namespace mf {

class Shape;
class Medium;

/// An mf_surface handle, freed on destruction. Immutable; shared by all render threads.
class MeanSurface {
public:
    /// The mean surface of `shape` (a sphere or a closed mesh), a mesh's built on up to `threads`
    /// threads (mf_surface_new_mesh; its enclosures use as many) for media tracked up to `reach`
    /// from it (a macrofacet medium's shell top; INFINITY: any medium); throws mf::Error at the
    /// shape's location otherwise.
    static std::shared_ptr<const MeanSurface> of(const Shape& shape, size_t threads = 1, double reach = INFINITY);
    ~MeanSurface();
    MeanSurface(const MeanSurface&) = delete;
    MeanSurface& operator=(const MeanSurface&) = delete;

    const mf_surface* handle() const { return handle_; }
    /// Signed distance at p, with the frame normal and tangent (double precision).
    double eval(const Vec3& p, Vec3* normal, Vec3* tangent) const;

    /// A sphere's centre and radius, where f = |p - c| - r (not flipped).
    struct Sphere {
        Vec3 center;
        double radius;
    };
    /// The sphere this surface is, or null (a mesh, a grid, a flipped sphere).
    const Sphere* sphere() const { return sphere_ ? &*sphere_ : nullptr; }

private:
    explicit MeanSurface(mf_surface* handle) : handle_(handle) {}
    mf_surface* handle_;
    std::optional<Sphere> sphere_;
};

/// The boundary of the region f < level of `mean` as a null-BSDF shape whose interior is
/// `medium` and whose exterior is the mean shape's exterior (see the file comment).
std::shared_ptr<Shape> make_region_boundary(const std::shared_ptr<const Shape>& mean, const MeanSurface& surface,
                                            double level, const std::shared_ptr<const Medium>& medium);

}  // namespace mf
