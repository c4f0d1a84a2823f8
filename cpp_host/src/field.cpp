// mfhost — spatially varying medium parameters (see field.h).
#include "field.h"

#include <algorithm>

namespace mf {

namespace {
// Mitsuba's luminance weights (Rgb::luminance): a scalar parameter read from an RGB texture.
constexpr float kLuminance[3] = {0.212671f, 0.715160f, 0.072169f};
}  // namespace

Field::Field(std::string param, SourceLoc loc, std::string element, std::shared_ptr<const Volume> volume)
    : param_(std::move(param)), loc_(std::move(loc)), element_(std::move(element)), volume_(std::move(volume)) {
    channels_ = volume_->channels();
    if (const float* c = volume_->constant()) {
        std::copy(c, c + channels_, constant_);
        is_constant_ = true;
    }
}

Field::Field(std::string param, SourceLoc loc, std::string element, std::shared_ptr<const Texture> texture, int channels)
    : param_(std::move(param)), loc_(std::move(loc)), element_(std::move(element)), texture_(std::move(texture)),
      channels_(channels) {
    if (const Rgb* c = texture_->constant()) {
        float v[3] = {c->r, c->g, c->b};
        if (channels_ == 1) constant_[0] = c->luminance();
        else std::copy(v, v + 3, constant_);
        is_constant_ = true;
    }
}

void Field::eval(const Vec3& p, const Vec2& uv, float* out) const {
    if (volume_) {
        volume_->eval(p, out);
        return;
    }
    Rgb v = texture_->eval(uv);
    if (channels_ == 1) {
        out[0] = v.luminance();
    } else {
        out[0] = v.r;
        out[1] = v.g;
        out[2] = v.b;
    }
}

ValueRange Field::texture_range(const ValueRange& rgb) const {
    if (channels_ == 3) return rgb;
    // The luminance is a combination of the channels with non-negative weights: the same
    // combination of the channels' bounds bounds it.
    ValueRange r = ValueRange::empty(1);
    r.lo[0] = r.hi[0] = 0;
    for (int c = 0; c < 3; ++c) {
        r.lo[0] += kLuminance[c] * rgb.lo[c];
        r.hi[0] += kLuminance[c] * rgb.hi[c];
    }
    return r;
}

ValueRange Field::range_segment(const Vec3& o, const Vec3& d, float length) const {
    return volume_ ? volume_->range_segment(o, d, length) : texture_range(texture_->range());
}

ValueRange Field::range_box(const Aabb& world_box) const {
    return volume_ ? volume_->range_box(world_box) : texture_range(texture_->range());
}

ValueRange Field::range_uv(const Vec2& uv_lo, const Vec2& uv_hi) const {
    return volume_ ? volume_->range() : texture_range(texture_->range_uv(uv_lo, uv_hi));
}

ValueRange Field::range() const { return volume_ ? volume_->range() : texture_range(texture_->range()); }

const float* Field::constant() const { return is_constant_ ? constant_ : nullptr; }

}  // namespace mf
