// macrofacet for Mitsuba 3 — the mean surface from the Mitsuba shape nested in the medium
// (<shape name="mean_surface">): Mitsuba loads it (any mesh plugin: obj, ply, serialized, ...;
// sphere; sdfgrid), and the library gets exactly what Mitsuba shades.
//
//   sphere   centre and radius from its bounding box (Mitsuba's sphere box is the exact ball),
//            flip from has_flipped_normals(), and the pole of its dp/du: Mitsuba's sphere has
//            dp/du ∝ pole × (p − c) everywhere, so two probe intersections give the pole as the
//            cross product of their dp/du (sign fixed by the first probe).
//   mesh     world-space vertices and triangles, Mitsuba's vertex normals (the frame normal is
//            their interpolation, as Mitsuba shades) and texture coordinates (the tangent is then
//            dp/du); face-normal meshes get the distance gradient. The mesh must be closed.
//   sdfgrid  Mitsuba's samples and to_world, unchanged, for mf_surface_new_grid. Conventions: an
//            sdfgrid's samples sit at the NODES of a grid over the unit cube, sample (i, j, k)
//            at (i / (nx − 1), j / (ny − 1), k / (nz − 1)) (a ray along the grid's middle row
//            meets Mitsuba's sdfgrid where the nodes' linear interpolant vanishes), x fastest —
//            the library's mf_grid exactly — whereas a gridvolume's samples sit at CELL CENTRES,
//            ((i + ½) / nx, ...) (field_sources.h). Values are in the unit cube's units; to_world
//            must be a similarity (rotation, uniform scale, translation), so that they scale to
//            world distances. Checked here, as mfrender checks its sdfgrid: the values change sign
//            (a surface) and are distances: adjacent samples differ by at most their spacing
//            (+1 %: numerically built SDFs overshoot slightly), which the library's SDF-grid
//            bounds rely on. The library then checks the rest (finite values, positive outer
//            faces, the similarity). No uv: textures cannot vary over an sdfgrid.
// Buffers and grids are read through the shape's traverse() (traversal.h).
#pragma once

#include <mitsuba/render/interaction.h>
#include <mitsuba/render/shape.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "mean_surface.h"
#include "traversal.h"

namespace mfmi {

using namespace mitsuba;  // Mitsuba's MI_IMPORT_* macros name its types unqualified

inline constexpr const char* kSupportedShapes =
    "must be a sphere, a closed triangle mesh (obj, ply, serialized, cube, ...) or an sdfgrid";

/// Samples of a distance function differ by at most their distance; numerically built SDFs (fast
/// marching, VDB level sets) overshoot slightly: 1 % is accepted (as mfrender's sdf_grid.cpp).
inline constexpr double kSdfLipschitzTolerance = 1.01;

/// An sdfgrid's samples (x fastest, unit-cube units) as the library's grid surface, after the
/// checks of the file comment. `scale` is to_world's (world units per unit-cube unit).
inline std::shared_ptr<const MeanSurface> grid_surface(const float* values, const size_t n[3], const double to_world[12], double scale) {
    auto at = [&](size_t i, size_t j, size_t k) { return double(values[(k * n[1] + j) * n[0] + i]); };
    auto node = [](size_t i, size_t j, size_t k) {
        return "node (" + std::to_string(i) + ", " + std::to_string(j) + ", " + std::to_string(k) + ")";
    };
    double lo = INFINITY, hi = -INFINITY;
    GridFaceMinimum faces;
    for (size_t k = 0; k < n[2]; ++k)
        for (size_t j = 0; j < n[1]; ++j)
            for (size_t i = 0; i < n[0]; ++i) {
                const double v = at(i, j, k);
                if (!std::isfinite(v)) throw std::runtime_error("the sdfgrid's " + node(i, j, k) + " is " + std::to_string(v) + ", not a distance");
                lo = std::min(lo, v);
                hi = std::max(hi, v);
                const size_t idx[3] = {i, j, k};
                for (int a = 0; a < 3; ++a) {
                    if (n[a] < 2 || idx[a] + 1 >= n[a]) continue;
                    const double step = std::fabs(at(i + (a == 0), j + (a == 1), k + (a == 2)) - v), spacing = 1.0 / double(n[a] - 1);
                    if (step > kSdfLipschitzTolerance * spacing)
                        throw std::runtime_error("the sdfgrid's values are not distances: next to " + node(i, j, k) + " along axis " +
                                                 std::to_string(a) + " they change by " + std::to_string(step) + " over a spacing of " +
                                                 std::to_string(spacing) + " (the unit cube's units); a distance changes by at most the spacing");
                }
                const bool on_face = i == 0 || j == 0 || k == 0 || i + 1 == n[0] || j + 1 == n[1] || k + 1 == n[2];
                if (on_face && v * scale < faces.value) faces = GridFaceMinimum{v * scale, {i, j, k}};
            }
    if (!(lo < 0) || !(hi > 0))
        throw std::runtime_error("the sdfgrid's values lie in [" + std::to_string(lo) + ", " + std::to_string(hi) +
                                 "]: a surface needs negative values (inside) and positive values (outside)");
    mf_grid desc{values, n[0], n[1], n[2], {}};
    std::copy(to_world, to_world + 12, desc.to_world);
    return MeanSurface::grid(desc, faces);
}

/// The mean surface of a Mitsuba shape, for media tracked up to `reach` from it (a macrofacet
/// medium's shell top; mf_surface_new_mesh).
template <typename Float, typename Spectrum>
std::shared_ptr<const MeanSurface> mean_surface_of(mitsuba::Shape<Float, Spectrum>* shape, double reach) {
    using namespace mitsuba;
    MI_IMPORT_TYPES()
    static_assert(!dr::is_jit_v<Float>, "scalar variants only");

    if (shape->shape_type() == +ShapeType::Sphere) {
        ScalarBoundingBox3f box = shape->bbox();
        ScalarPoint3f c = box.center();
        double radius = 0.5 * double(box.max.x() - box.min.x());
        // two probes from different sides; dp/du is orthogonal to the pole at both
        ScalarVector3f e1 = dr::normalize(ScalarVector3f(0.8f, 0.5f, 0.3f)),
                       e2 = dr::normalize(ScalarVector3f(-0.3f, 0.7f, -0.6f));
        auto dpdu = [&](const ScalarVector3f& e) {
            Ray3f ray(c + e * Float(3 * radius), -e);
            SurfaceInteraction3f si = shape->ray_intersect(ray, +RayFlags::All);
            if (!si.is_valid()) throw std::runtime_error("cannot probe the sphere's parameterization");
            return std::make_pair(Vector3f(si.p - c), si.dp_du);
        };
        const auto [p1, d1] = dpdu(e1);
        const Vector3f d2 = dpdu(e2).second;
        Vector3f pole = dr::normalize(dr::cross(d1, d2));
        if (dr::dot(dr::cross(pole, p1), d1) < 0) pole = -pole;
        return MeanSurface::sphere(mf_vec3{c.x(), c.y(), c.z()}, radius, shape->has_flipped_normals(),
                                   mf_vec3{pole.x(), pole.y(), pole.z()});
    }

    if (shape->is_mesh()) {
        if (shape->has_flipped_normals())
            throw std::runtime_error("a mesh mean surface cannot have flip_normals (its triangles' winding defines the "
                                     "interior)");
        using FloatBuffer = DynamicBuffer<Float>;
        using IndexBuffer = DynamicBuffer<dr::uint32_array_t<Float>>;
        const Traversed t(shape);
        const FloatBuffer *positions = t.value<FloatBuffer>("vertex_positions"), *normals_in = t.value<FloatBuffer>("vertex_normals"),
                          *texcoords = t.value<FloatBuffer>("vertex_texcoords");
        const IndexBuffer* faces = t.value<IndexBuffer>("faces");
        if (!positions || !faces || positions->size() == 0) throw std::runtime_error(kSupportedShapes);
        const size_t nv = positions->size() / 3, nf = faces->size() / 3;
        std::vector<double> vertices(positions->data(), positions->data() + 3 * nv), normals, uvs;
        // Mitsuba's cube has per-face normals only (split vertices): its frame is the distance
        // gradient, as in mfrender
        const bool face_normals = shape->class_name() == std::string_view("Cube");
        if (!face_normals && normals_in && normals_in->size() == 3 * nv) normals.assign(normals_in->data(), normals_in->data() + 3 * nv);
        if (texcoords && texcoords->size() == 2 * nv) uvs.assign(texcoords->data(), texcoords->data() + 2 * nv);
        mf_mesh desc{vertices.data(), nv, faces->data(), nf, normals.empty() ? nullptr : normals.data(), uvs.empty() ? nullptr : uvs.data()};
        return MeanSurface::mesh(desc, "mesh", reach);
    }

    if (shape->shape_type() == +ShapeType::SDFGrid) {
        const Traversed t(shape);
        const TensorXf* grid = t.value<TensorXf>("grid");
        const ScalarAffineTransform4f* to_world = t.value<ScalarAffineTransform4f>("to_world");
        if (!grid || !to_world || grid->ndim() != 4) throw std::runtime_error("cannot read the sdfgrid's samples and to_world");
        if (grid->shape(3) != 1)
            throw std::runtime_error("the sdfgrid has " + std::to_string(grid->shape(3)) + " channels; a signed distance has 1");
        const size_t n[3] = {grid->shape(2), grid->shape(1), grid->shape(0)};
        double rows[12];
        for (int r = 0; r < 3; ++r)
            for (int c = 0; c < 4; ++c) rows[4 * r + c] = double(to_world->matrix(r, c));
        const double det = rows[0] * (rows[5] * rows[10] - rows[6] * rows[9]) - rows[1] * (rows[4] * rows[10] - rows[6] * rows[8]) +
                           rows[2] * (rows[4] * rows[9] - rows[5] * rows[8]);
        return grid_surface(grid->array().data(), n, rows, std::cbrt(det));
    }
    throw std::runtime_error(kSupportedShapes);
}

}  // namespace mfmi
