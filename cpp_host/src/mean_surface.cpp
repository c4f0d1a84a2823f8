// mfhost — mean surfaces and region boundaries (see mean_surface.h).
#include "mean_surface.h"

#include <macrofacet.h>

#include <cmath>
#include <string>
#include <vector>

#include "error.h"
#include "medium.h"
#include "sdf_grid.h"
#include "shape.h"

namespace mf {
namespace {

std::string library_error() {
    size_t len = 0;
    mf_last_error_message(nullptr, 0, &len);
    std::vector<char> buf(len + 1, '\0');
    mf_last_error_message(buf.data(), buf.size(), nullptr);
    return buf.data();
}

}  // namespace

std::shared_ptr<const MeanSurface> MeanSurface::of(const Shape& shape, size_t threads, double reach) {
    mf_surface* handle = nullptr;
    mf_status st = MF_OK;
    const auto* sphere = dynamic_cast<const SphereShape*>(&shape);
    if (sphere) {
        Vec3 c = sphere->center(), pole = sphere->pole();
        st = mf_surface_new_sphere(mf_vec3{c.x, c.y, c.z}, sphere->radius(), sphere->flipped(), mf_vec3{pole.x, pole.y, pole.z}, &handle);
    } else if (auto* mesh = dynamic_cast<const MeshShape*>(&shape)) {
        const TriMesh& m = mesh->mesh();
        std::vector<double> positions, normals, uvs;
        positions.reserve(3 * m.p.size());
        for (const Vec3& p : m.p) positions.insert(positions.end(), {p.x, p.y, p.z});
        // The canonical cube has per-face normals only: its frame is the distance gradient.
        if (!m.n.empty() && shape.kind() != "cube")
            for (const Vec3& n : m.n) normals.insert(normals.end(), {n.x, n.y, n.z});
        for (const Vec2& uv : m.uv) uvs.insert(uvs.end(), {uv.x, uv.y});
        mf_mesh desc{positions.data(), m.p.size(), m.idx.data(), m.num_triangles(), normals.empty() ? nullptr : normals.data(),
                     uvs.empty() ? nullptr : uvs.data()};
        st = mf_surface_new_mesh(&desc, threads, reach, &handle);
    } else if (auto* sdf = dynamic_cast<const SdfGridShape*>(&shape)) {
        // The library takes object-unit values over the unit cube and a similarity to_world:
        // divide the world distances by its scale.
        const SdfGrid& g = sdf->grid();
        const Mat4& w = g.to_world;
        double det = w.m[0][0] * (w.m[1][1] * w.m[2][2] - w.m[1][2] * w.m[2][1]) - w.m[0][1] * (w.m[1][0] * w.m[2][2] - w.m[1][2] * w.m[2][0]) +
                     w.m[0][2] * (w.m[1][0] * w.m[2][1] - w.m[1][1] * w.m[2][0]);
        const double scale = std::cbrt(det);
        std::vector<float> values(g.values.size());
        for (size_t i = 0; i < values.size(); ++i) values[i] = float(double(g.values[i]) / scale);
        mf_grid desc{values.data(), size_t(g.nx), size_t(g.ny), size_t(g.nz), {}};
        for (int r = 0; r < 3; ++r)
            for (int c = 0; c < 4; ++c) desc.to_world[4 * r + c] = w.m[r][c];
        st = mf_surface_new_grid(&desc, &handle);
    } else {
        throw Error(shape.loc, "<shape type=\"" + shape.kind() + "\">: cannot be the mean surface of a medium");
    }
    if (st != MF_OK)
        throw Error(shape.loc, "<shape type=\"" + shape.kind() + "\">: not a valid mean surface: " + library_error());
    auto surface = std::shared_ptr<MeanSurface>(new MeanSurface(handle));
    if (sphere && !sphere->flipped()) surface->sphere_ = Sphere{sphere->center(), sphere->radius()};
    return surface;
}

MeanSurface::~MeanSurface() { mf_surface_free(handle_); }

double MeanSurface::eval(const Vec3& p, Vec3* normal, Vec3* tangent) const {
    mf_surface_point s;
    if (mf_surface_eval(handle_, nullptr, mf_vec3{p.x, p.y, p.z}, &s) != MF_OK)
        throw Error("mf_surface_eval failed: " + library_error());
    if (normal) *normal = Vec3(float(s.normal.x), float(s.normal.y), float(s.normal.z));
    if (tangent) *tangent = Vec3(float(s.tangent.x), float(s.tangent.y), float(s.tangent.z));
    return s.f;
}

std::shared_ptr<Shape> make_region_boundary(const std::shared_ptr<const Shape>& mean, const MeanSurface& surface,
                                            double level, const std::shared_ptr<const Medium>& medium) {
    std::shared_ptr<Shape> b;
    if (auto sph = std::dynamic_pointer_cast<const SphereShape>(mean)) {
        // exact: the level set f = level of a sphere is the concentric sphere of radius r ± level
        float r = float(sph->flipped() ? sph->radius() - level : sph->radius() + level);
        if (!(r > 0))
            throw Error(mean->loc, "<shape type=\"sphere\">: the " + medium->name() + " shell (" + std::to_string(level) +
                                       ") is thicker than this flipped sphere's radius");
        b = std::make_shared<SphereShape>(sph->center(), r, sph->flipped());
    } else {
        mf_enclosure* enclosure = nullptr;
        if (mf_surface_enclosure(surface.handle(), nullptr, level, 0.0, &enclosure) != MF_OK)
            throw Error(mean->loc, "<shape type=\"" + mean->kind() + "\">: no region boundary: " + library_error());
        mf_mesh m;
        mf_enclosure_mesh(enclosure, &m);
        TriMesh tri;
        tri.p.reserve(m.vertex_count);
        for (size_t i = 0; i < m.vertex_count; ++i)
            tri.p.emplace_back(float(m.positions[3 * i]), float(m.positions[3 * i + 1]), float(m.positions[3 * i + 2]));
        tri.idx.assign(m.indices, m.indices + 3 * m.triangle_count);
        double exit_level = 0;
        mf_enclosure_exit_level(enclosure, &exit_level);
        mf_enclosure_free(enclosure);
        b = std::make_shared<MeshShape>(std::move(tri), "enclosure");
        b->region_boundary = true;
        b->exit_level = exit_level;
    }
    b->id = mean->id;
    b->loc = mean->loc;
    b->bsdf = make_null_bsdf();
    b->interior = medium;
    b->exterior = mean->exterior;
    return b;
}

}  // namespace mf
