// mfhost — spatially varying medium parameters (issue 12): a Field is one parameter of a
// macrofacet or gpis medium given as a <volume> over world space or a <texture> over the mean
// surface's uv instead of a number; MediumFields collects a medium's fields by parameter name.
//
// The library stays pure: the host evaluates fields and hands the local values to the library
// per query, together with conservative bounds for majorants. Hence every Field offers
//   eval(p, uv)            the value at world point p (volumes) or surface coordinates uv
//                          (textures: the uv of the mean surface's point closest to p);
//   range_segment(o,d,L)   bounds over the segment o + s d, s in [0, L] (volumes; a texture
//                          returns its bounds over all uv, as uv along a segment is unknown);
//   range_box(box)         bounds over a world box (volumes; textures as above);
//   range_uv(lo, hi)       bounds over a uv rectangle (textures; volumes: all of space);
//   range()                bounds over everything.
// Bounds are per channel and always contain the true values (they may be wider).
//
// Channels: 1 for scalars (sigma, variance, alpha*, lengthscale*), 3 for reflectances (rgb), 6
// for the anisotropy matrix Sigma of seeds/004 Eqs. 25-26, stored as Mitsuba 3's sggx phase
// function stores its matrix S: (xx, yy, zz, xy, xz, yz) in world coordinates. Entries are
// interpolated linearly (seeds/004 §6.1.1, after SGGX): positive-definite samples then give
// positive-definite values everywhere, since a convex combination of positive-definite matrices
// is positive definite. The ranges of an anisotropy field carry two more channels,
// kEigenMin / kEigenMax: lo[kEigenMin] bounds the smallest eigenvalue from below and
// hi[kEigenMax] the largest from above (the smallest eigenvalue is concave and the largest convex
// in the matrix, so the samples' extreme eigenvalues bound every interpolated matrix's).
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "error.h"
#include "math.h"
#include "sample_grid.h"
#include "texture.h"
#include "volume.h"

namespace mf {

class Field {
public:
    enum class Domain { Volume, Texture };
    static constexpr int kEigenMin = 6, kEigenMax = 7;  // derived range channels of a 6-channel field

    /// A field over world space. `element` describes the volume for messages.
    Field(std::string param, SourceLoc loc, std::string element, std::shared_ptr<const Volume> volume);
    /// A field over the mean surface's uv with `channels` 1 (the texture's luminance, as Mitsuba's
    /// eval_1 of an RGB bitmap) or 3.
    Field(std::string param, SourceLoc loc, std::string element, std::shared_ptr<const Texture> texture, int channels);

    const std::string& param() const { return param_; }
    const SourceLoc& loc() const { return loc_; }
    /// e.g. <volume type="gridvolume"> (for messages).
    const std::string& element() const { return element_; }
    Domain domain() const { return texture_ ? Domain::Texture : Domain::Volume; }
    int channels() const { return channels_; }

    /// The value: channels() floats into out. `uv` is read by textures only, `p` by volumes only.
    void eval(const Vec3& p, const Vec2& uv, float* out) const;
    ValueRange range_segment(const Vec3& o, const Vec3& d, float length) const;
    ValueRange range_box(const Aabb& world_box) const;
    ValueRange range_uv(const Vec2& uv_lo, const Vec2& uv_hi) const;
    ValueRange range() const;
    /// Non-null if the field is the same everywhere (a constvolume): its channels() values.
    const float* constant() const;

    const Volume* volume() const { return volume_.get(); }
    const Texture* texture() const { return texture_.get(); }

private:
    ValueRange texture_range(const ValueRange& rgb) const;  // 1 channel: luminance bounds
    std::string param_;
    SourceLoc loc_;
    std::string element_;
    std::shared_ptr<const Volume> volume_;
    std::shared_ptr<const Texture> texture_;
    int channels_ = 0;
    float constant_[ValueRange::kMaxChannels] = {};
    bool is_constant_ = false;
};

/// The spatially varying parameters of one macrofacet or gpis medium, by parameter name.
/// Parameters given as numbers stay in the medium's parameter bag (medium.h); a constvolume is
/// folded into the bag as its number (so that it renders exactly as the number does) and does not
/// appear here, except the anisotropy, which has no scalar form.
struct MediumFields {
    std::vector<std::shared_ptr<const Field>> fields;  // document order
    const Field* find(const std::string& param) const {
        for (const auto& f : fields)
            if (f->param() == param) return f.get();
        return nullptr;
    }
    bool empty() const { return fields.empty(); }
    /// Whether any field is a texture (the mean surface must then have uv).
    bool needs_uv() const {
        for (const auto& f : fields)
            if (f->domain() == Field::Domain::Texture) return true;
        return false;
    }
};

}  // namespace mf
