// macrofacet for Mitsuba 3 — the mean surface from the Mitsuba shape nested in the medium
// (<shape name="mean_surface">): Mitsuba loads it (any mesh plugin: obj, ply, serialized, ...;
// or sphere), and the library gets exactly what Mitsuba shades.
//
//   sphere  centre and radius from its bounding box (Mitsuba's sphere box is the exact ball),
//           flip from has_flipped_normals(), and the pole of its dp/du: Mitsuba's sphere has
//           dp/du ∝ pole × (p − c) everywhere, so two probe intersections give the pole as the
//           cross product of their dp/du (sign fixed by the first probe).
//   mesh    world-space vertices and triangles, Mitsuba's vertex normals (the frame normal is
//           their interpolation, as Mitsuba shades) and texture coordinates (the tangent is then
//           dp/du); face-normal meshes get the distance gradient. The mesh must be closed. The
//           buffers are read through the shape's traverse() (the parameters mi.traverse shows):
//           mesh.h cannot be included, it needs struct-jit headers that the wheel lacks.
#pragma once

#include <mitsuba/render/interaction.h>
#include <mitsuba/render/shape.h>

#include <string>
#include <typeinfo>
#include <vector>

#include "mean_surface.h"

namespace mfmi {

using namespace mitsuba;  // Mitsuba's MI_IMPORT_* macros name its types unqualified

inline constexpr const char* kSupportedShapes = "must be a sphere or a closed triangle mesh (obj, ply, serialized, cube, ...)";

/// Collects a mesh's buffers from its traverse() (names as mi.traverse shows them).
template <typename Float>
struct MeshBuffers final : mitsuba::TraversalCallback {
    using FloatBuffer = mitsuba::DynamicBuffer<Float>;
    using IndexBuffer = mitsuba::DynamicBuffer<dr::uint32_array_t<Float>>;
    const FloatBuffer *positions = nullptr, *normals = nullptr, *texcoords = nullptr;
    const IndexBuffer* faces = nullptr;

protected:
    void put_value(std::string_view name, void* value, uint32_t, const std::type_info& type) override {
        if (type == typeid(FloatBuffer)) {
            const auto* buffer = static_cast<const FloatBuffer*>(value);
            if (name == "vertex_positions") positions = buffer;
            else if (name == "vertex_normals") normals = buffer;
            else if (name == "vertex_texcoords") texcoords = buffer;
        } else if (type == typeid(IndexBuffer) && name == "faces") {
            faces = static_cast<const IndexBuffer*>(value);
        }
    }
    void put_object(std::string_view, mitsuba::Object*, uint32_t) override {}
};

template <typename Float, typename Spectrum>
std::shared_ptr<const MeanSurface> mean_surface_of(mitsuba::Shape<Float, Spectrum>* shape) {
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
        MeshBuffers<Float> b;
        shape->traverse(&b);  // reports the buffers, changes nothing
        if (!b.positions || !b.faces || b.positions->size() == 0)
            throw std::runtime_error(kSupportedShapes);
        const size_t nv = b.positions->size() / 3, nf = b.faces->size() / 3;
        std::vector<double> positions(b.positions->data(), b.positions->data() + 3 * nv), normals, uvs;
        // Mitsuba's cube has per-face normals only (split vertices): its frame is the distance
        // gradient, as in mfrender
        const bool face_normals = shape->class_name() == std::string_view("Cube");
        if (!face_normals && b.normals && b.normals->size() == 3 * nv) normals.assign(b.normals->data(), b.normals->data() + 3 * nv);
        if (b.texcoords && b.texcoords->size() == 2 * nv) uvs.assign(b.texcoords->data(), b.texcoords->data() + 2 * nv);
        mf_mesh desc{positions.data(), nv, b.faces->data(), nf, normals.empty() ? nullptr : normals.data(),
                     uvs.empty() ? nullptr : uvs.data()};
        return MeanSurface::mesh(desc);
    }
    throw std::runtime_error(kSupportedShapes);
}

}  // namespace mfmi
