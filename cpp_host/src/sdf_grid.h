// mfhost — <shape type="sdfgrid">, as Mitsuba 3 defines it: a signed distance function sampled on
// a grid (filename: a 1-channel Mitsuba .vol file, or a float grid of an OpenVDB .vdb file with
// <string name="grid">), whose samples are the NODES of a grid over the unit cube: sample
// (i, j, k) at (i / (nx - 1), j / (ny - 1), k / (nz - 1)), mapped to world space by `to_world`
// (the .vol header's bounding box is not used, as in Mitsuba); `normals` analytic|smooth is
// accepted. For a .vdb file the unit cube is the active voxels' bounding box in the grid's own
// index space, placed by the grid's transform, then by to_world.
//
// mfrender takes an sdfgrid only as the mean surface of a macrofacet or gpis medium: its values
// must then be signed distances (> 0 outside), in the units of the unit cube for a .vol file, of
// the VDB world for a .vdb file, and to_world must be a similarity so that they stay distances in
// world space. At load the grid is checked: finite values, a sign change (a surface), and
// 1-Lipschitz samples (adjacent samples differ by at most their distance, up to 1 %, as samples of
// a distance function do; the library's bounds rely on it). The SdfGrid holds the samples in WORLD
// units and the Lipschitz bound of its trilinear interpolant, for the library's SDF-grid surface.
// Ray intersection is the medium's business: the shape itself is never traced.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "math.h"
#include "shape.h"
#include "volume_io.h"
#include "xml_scene.h"

namespace mf {

struct SdfGrid {
    int nx = 0, ny = 0, nz = 0;  // >= 2 each
    /// Signed distances in world units (> 0 outside): node (i, j, k) at ((k * ny + j) * nx + i).
    std::vector<float> values;
    /// Unit cube -> world (a similarity composed with the grid's placement): node (i, j, k) at
    /// to_world.point((i / (nx - 1), j / (ny - 1), k / (nz - 1))).
    Mat4 to_world;
    /// World length of one node spacing along x, y, z (the grid's axes are orthogonal in world).
    double spacing[3] = {0, 0, 0};
    /// Upper bound of |grad f| of the trilinear interpolant, in world units: per cell, the root
    /// of the sum over axes of the squared largest slope along that axis's four edges (each
    /// partial derivative of a trilinear function is a bilinear blend of its edge slopes).
    double lipschitz = 0;
    bool smooth_normals = true;  // Mitsuba's normals="smooth" (default) or "analytic"
    float value_min = 0, value_max = 0;

    float at(int i, int j, int k) const { return values[(size_t(k) * ny + j) * nx + i]; }
    /// The world box of the whole grid.
    Aabb grid_bounds() const;
    /// A world box containing every point of the grid where the interpolant is < level: the cells
    /// with a corner value < level (a trilinear value lies between its corners' values). Empty
    /// (invalid) if there is none.
    Aabb region_bounds(double level) const;
    /// The first node on the grid's boundary whose value is < level, if any (-1 otherwise): the
    /// region f < level then reaches past the grid, where no distance is known.
    long long boundary_node_below(double level) const;
};

/// Reads and checks an sdfgrid shape's grid (`o` is the <shape type="sdfgrid"> element, after
/// its to_world was read). Throws mf::Error at the element's (or parameter's) file:line.
SdfGrid load_sdf_grid(const SceneObject& o, const Mat4& to_world);

/// The shape of an sdfgrid: the mean surface of a medium, never traced itself (the scene builder
/// refuses any other use). Its bounds are those of the solid, f <= 0.
class SdfGridShape final : public Shape {
public:
    explicit SdfGridShape(SdfGrid grid);
    const SdfGrid& grid() const { return grid_; }
    Aabb bounds() const override { return solid_bounds_; }
    float surface_area() const override { return 0.0f; }  // as Mitsuba's sdfgrid: no area sampling
    void sample_position(const Vec2& u, Vec3* p, Vec3* n) const override;
    unsigned attach(RTCDevice device, RTCScene scene) const override;
    void fill_hit(const Ray& ray, float t, unsigned prim, float u, float v, SurfaceHit* hit) const override;
    std::string kind() const override { return "sdfgrid"; }

private:
    SdfGrid grid_;
    Aabb solid_bounds_;
};

}  // namespace mf
