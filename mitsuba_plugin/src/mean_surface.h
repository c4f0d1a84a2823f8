// macrofacet for Mitsuba 3 — the mean surface as the library sees it: an mf_surface (exact
// sphere, triangle-mesh signed distance with Mitsuba's shading frame, or a signed-distance grid),
// shared by the medium's tracking and its phase function, with what the medium's checks need:
// whether the surface has texture coordinates (textures are evaluated at its uv) and, for a grid,
// its smallest value on the grid's outer faces (the medium's region must stay inside the grid).
// Independent of Mitsuba (shape_geometry.h builds it from a Mitsuba shape).
#pragma once

#include <macrofacet.h>

#include <algorithm>
#include <array>
#include <cstddef>
#include <limits>
#include <memory>
#include <string>
#include <thread>
#include <utility>

#include "library.h"

namespace mfmi {

/// The lowest sample on a grid surface's outer faces: its value in world units and its node.
struct GridFaceMinimum {
    double value = std::numeric_limits<double>::infinity();
    std::array<size_t, 3> node{};
};

class MeanSurface {
public:
    /// Mitsuba's sphere (tangent = dp/du around `pole`, see mf_surface_new_sphere; Mitsuba's uv).
    static std::shared_ptr<const MeanSurface> sphere(const mf_vec3& center, double radius, bool flipped, const mf_vec3& pole) {
        mf_surface* h = nullptr;
        check(mf_surface_new_sphere(center, radius, flipped, pole, &h), "not a valid mean surface");
        return std::shared_ptr<const MeanSurface>(new MeanSurface(h, "sphere", true, {}));
    }

    /// A closed triangle mesh in world space (see mf_mesh; the arrays are copied), built on one
    /// thread per core, at most the library's MF_MAX_BUILD_THREADS (mf_surface_new_mesh refuses
    /// more; the same surface whatever the count), for media tracked up to `reach` from it, as
    /// mfrender's scene builder does.
    static std::shared_ptr<const MeanSurface> mesh(const mf_mesh& mesh, const std::string& kind, double reach) {
        mf_surface* h = nullptr;
        const size_t threads = std::min<size_t>(std::max(1u, std::thread::hardware_concurrency()), MF_MAX_BUILD_THREADS);
        check(mf_surface_new_mesh(&mesh, threads, reach, &h), "not a valid mean surface");
        return std::shared_ptr<const MeanSurface>(new MeanSurface(h, kind, mesh.uvs != nullptr, {}));
    }

    /// A signed-distance grid (see mf_grid; the values are copied); no uv.
    static std::shared_ptr<const MeanSurface> grid(const mf_grid& grid, const GridFaceMinimum& faces) {
        mf_surface* h = nullptr;
        check(mf_surface_new_grid(&grid, &h), "not a valid mean surface");
        return std::shared_ptr<const MeanSurface>(new MeanSurface(h, "sdfgrid", false, faces));
    }

    ~MeanSurface() { mf_surface_free(handle_); }
    MeanSurface(const MeanSurface&) = delete;
    MeanSurface& operator=(const MeanSurface&) = delete;

    const mf_surface* handle() const { return handle_; }
    /// Mitsuba's plugin name, e.g. "sphere", "obj", "sdfgrid" (for messages).
    const std::string& kind() const { return kind_; }
    /// Whether the library reports Mitsuba's uv at the surface's points.
    bool has_uv() const { return has_uv_; }
    /// A grid's lowest outer-face sample (+inf for other surfaces).
    const GridFaceMinimum& grid_faces() const { return grid_faces_; }

    /// The box of the mean surface and its interior (mf_surface_bounding_box).
    std::array<mf_vec3, 2> bounding_box() const {
        std::array<mf_vec3, 2> box{};
        check(mf_surface_bounding_box(handle_, &box[0], &box[1]), "mf_surface_bounding_box");
        return box;
    }

    /// f, frame normal and tangent at p.
    mf_surface_point point(const mf_vec3& p) const {
        mf_surface_point s;
        check(mf_surface_eval(handle_, nullptr, p, &s), "mf_surface_eval");
        return s;
    }

private:
    MeanSurface(mf_surface* h, std::string kind, bool has_uv, const GridFaceMinimum& faces)
        : handle_(h), kind_(std::move(kind)), has_uv_(has_uv), grid_faces_(faces) {}
    mf_surface* handle_;
    std::string kind_;
    bool has_uv_;
    GridFaceMinimum grid_faces_;
};

}  // namespace mfmi
