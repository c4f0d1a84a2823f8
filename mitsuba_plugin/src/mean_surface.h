// macrofacet for Mitsuba 3 — the mean surface as the library sees it: an mf_surface (exact
// sphere or triangle-mesh signed distance with Mitsuba's shading frame), shared by the medium's
// tracking and its phase function. Independent of Mitsuba (shape_geometry.h builds it from a
// Mitsuba shape).
#pragma once

#include <macrofacet.h>

#include <memory>

#include "library.h"

namespace mfmi {

class MeanSurface {
public:
    /// Mitsuba's sphere (tangent = dp/du around `pole`, see mf_surface_new_sphere).
    static std::shared_ptr<const MeanSurface> sphere(const mf_vec3& center, double radius, bool flipped, const mf_vec3& pole) {
        mf_surface* h = nullptr;
        check(mf_surface_new_sphere(center, radius, flipped, pole, &h), "not a valid mean surface");
        return std::shared_ptr<const MeanSurface>(new MeanSurface(h));
    }

    /// A closed triangle mesh in world space (see mf_mesh; the arrays are copied).
    static std::shared_ptr<const MeanSurface> mesh(const mf_mesh& mesh) {
        mf_surface* h = nullptr;
        check(mf_surface_new_mesh(&mesh, &h), "not a valid mean surface");
        return std::shared_ptr<const MeanSurface>(new MeanSurface(h));
    }

    ~MeanSurface() { mf_surface_free(handle_); }
    MeanSurface(const MeanSurface&) = delete;
    MeanSurface& operator=(const MeanSurface&) = delete;

    const mf_surface* handle() const { return handle_; }

    /// f, frame normal and tangent at p.
    mf_surface_point point(const mf_vec3& p) const {
        mf_surface_point s;
        check(mf_surface_eval(handle_, nullptr, p, &s), "mf_surface_eval");
        return s;
    }

private:
    explicit MeanSurface(mf_surface* h) : handle_(h) {}
    mf_surface* handle_;
};

}  // namespace mfmi
