// mfhost — textures, as Mitsuba 3 takes them wherever a plugin parameter is a texture:
// a constant (<rgb>, <float>, <spectrum>), `checkerboard` (color0, color1, to_uv) and `bitmap`
// (filename: PNG, JPEG or OpenEXR; filter_type bilinear|nearest, wrap_mode repeat|mirror|clamp,
// raw, to_uv). Lookups use the surface's Mitsuba uv (SurfaceHit::uv). Range queries bound the
// values over all uv or a uv rectangle (conservatively: they contain every value, per channel),
// for majorants of spatially varying medium parameters (field.h).
#pragma once

#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "math.h"
#include "sample_grid.h"

namespace mf {

struct TriMesh;

/// Where a texture is looked up: Mitsuba's uv (SurfaceHit::uv) and, on a mesh, the hit triangle
/// and its barycentrics (for mesh_attribute textures). Implicit from a uv (tests, emitters).
struct TexturePoint {
    Vec2 uv;
    const TriMesh* mesh = nullptr;  // the hit mesh, or null (no mesh attributes)
    uint32_t prim = 0;              // its triangle
    Vec2 bary;                      // weights of the triangle's 2nd and 3rd vertex (Embree's u, v)
    TexturePoint(const Vec2& uv_) : uv(uv_) {}
};

class Texture {
public:
    virtual ~Texture() = default;
    virtual Rgb eval(const TexturePoint& uv) const = 0;
    /// Mitsuba's Texture::eval_1, the scalar that monochromatic users (mask opacity) read: the
    /// luminance of eval(), except where Mitsuba's own eval_1 differs (checkerboard).
    virtual float eval_1(const TexturePoint& uv) const { return eval(uv).luminance(); }
    /// Mitsuba's Texture::resolution: a bitmap's width and height, 1 x 1 otherwise (a projector
    /// takes its image's aspect from it).
    virtual std::pair<int, int> resolution() const { return {1, 1}; }
    /// Per-channel bounds (3 channels) over all uv.
    virtual ValueRange range() const = 0;
    /// Per-channel bounds over the uv rectangle [uv_lo, uv_hi] (before to_uv); by default range().
    virtual ValueRange range_uv(const Vec2& uv_lo, const Vec2& uv_hi) const {
        (void)uv_lo;
        (void)uv_hi;
        return range();
    }
    /// Largest value of any channel (bounds checks, e.g. reflectance <= 1).
    float max_value() const {
        ValueRange r = range();
        return std::max(r.hi[0], std::max(r.hi[1], r.hi[2]));
    }
    /// Non-null for a constant texture.
    virtual const Rgb* constant() const { return nullptr; }
    /// The mean value over uv and channels (Mitsuba's Texture::mean(): BSDFs weigh their lobes'
    /// sampling probabilities by it).
    virtual float mean() const = 0;
};

/// Mitsuba's to_uv: a 2D affine map given as a 4x4 <transform> (its x/y rows and columns).
struct UvTransform {
    float a = 1, b = 0, c = 0, d = 0, e = 1, f = 0;  // u' = a u + b v + c, v' = d u + e v + f
    static UvTransform from(const Mat4& m) {
        return {float(m.m[0][0]), float(m.m[0][1]), float(m.m[0][3]), float(m.m[1][0]), float(m.m[1][1]), float(m.m[1][3])};
    }
    Vec2 apply(const Vec2& uv) const { return Vec2(a * uv.x + b * uv.y + c, d * uv.x + e * uv.y + f); }
};

std::shared_ptr<Texture> make_constant_texture(const Rgb& value);
/// Mitsuba's mesh_attribute: the named attribute (TriMesh::attributes, e.g. "vertex_color",
/// interpolated with the barycentrics; "face_color", per triangle) of the mesh that is hit,
/// times `scale`. Zero where the point has no such attribute (the scene builder refuses
/// shapes without it).
std::shared_ptr<Texture> make_mesh_attribute_texture(std::string name, float scale);
/// Mitsuba's checkerboard: color0 where frac(u) and frac(v) are on the same side of 1/2.
std::shared_ptr<Texture> make_checkerboard_texture(std::shared_ptr<Texture> color0, std::shared_ptr<Texture> color1,
                                                   const UvTransform& to_uv);
enum class BitmapFilter { Bilinear, Nearest };
/// `rgb`: linear values, row 0 = v 0 (the image's top row, as Mitsuba stores it).
std::shared_ptr<Texture> make_bitmap_texture(std::vector<float> rgb, int width, int height, BitmapFilter filter,
                                             WrapMode wrap, const UvTransform& to_uv);

}  // namespace mf
