// mfhost — textures (see texture.h).
#include "texture.h"

#include "mesh_io.h"

#include <algorithm>
#include <cmath>

namespace mf {

namespace {

class ConstantTexture final : public Texture {
public:
    explicit ConstantTexture(const Rgb& v) : v_(v) {}
    Rgb eval(const TexturePoint&) const override { return v_; }
    ValueRange range() const override {
        float v[3] = {v_.r, v_.g, v_.b};
        return ValueRange::of(v, 3);
    }
    const Rgb* constant() const override { return &v_; }
    float mean() const override { return v_.average(); }

private:
    Rgb v_;
};

class CheckerboardTexture final : public Texture {
public:
    CheckerboardTexture(std::shared_ptr<Texture> c0, std::shared_ptr<Texture> c1, const UvTransform& t)
        : c0_(std::move(c0)), c1_(std::move(c1)), t_(t) {}
    Rgb eval(const TexturePoint& uv_in) const override {
        Vec2 uv = t_.apply(uv_in.uv);
        float u = uv.x - std::floor(uv.x), v = uv.y - std::floor(uv.y);
        return ((u > 0.5f) == (v > 0.5f)) ? c0_->eval(uv_in) : c1_->eval(uv_in);
    }
    // Mitsuba 3.9.1's checkerboard eval_1 picks the colours the other way round from its eval
    // (measured with its mask plugin): reproduced, so that a mask's holes fall where Mitsuba's do
    float eval_1(const TexturePoint& uv_in) const override {
        Vec2 uv = t_.apply(uv_in.uv);
        float u = uv.x - std::floor(uv.x), v = uv.y - std::floor(uv.y);
        return ((u > 0.5f) != (v > 0.5f)) ? c0_->eval_1(uv_in) : c1_->eval_1(uv_in);
    }
    // Both colours may occur in any uv rectangle that is not inside one square: their union.
    ValueRange range() const override {
        ValueRange r = c0_->range();
        r.include(c1_->range());
        return r;
    }
    ValueRange range_uv(const Vec2& lo, const Vec2& hi) const override {
        ValueRange r = c0_->range_uv(lo, hi);
        r.include(c1_->range_uv(lo, hi));
        return r;
    }
    float mean() const override { return 0.5f * (c0_->mean() + c1_->mean()); }  // half the squares each

private:
    std::shared_ptr<Texture> c0_, c1_;
    UvTransform t_;
};

class BitmapTexture final : public Texture {
public:
    BitmapTexture(std::vector<float> rgb, int w, int h, BitmapFilter f, WrapMode m, const UvTransform& t)
        : texels_(std::move(rgb), w, h, 1, 3), w_(w), h_(h), filter_(f), wrap_(m), t_(t) {
        double sum = 0;
        for (float v : texels_.values()) sum += v;
        mean_ = texels_.values().empty() ? 0.0f : float(sum / double(texels_.values().size()));
    }
    float mean() const override { return mean_; }
    std::pair<int, int> resolution() const override { return {w_, h_}; }
    Rgb eval(const TexturePoint& uv_in) const override {
        Vec2 uv = t_.apply(uv_in.uv);
        float x = uv.x * float(w_), y = uv.y * float(h_);
        if (filter_ == BitmapFilter::Nearest) return texel(int(std::floor(x)), int(std::floor(y)));
        // bilinear between texel centres (integer + 0.5)
        x -= 0.5f;
        y -= 0.5f;
        float fx = std::floor(x), fy = std::floor(y);
        int x0 = int(fx), y0 = int(fy);
        float tx = x - fx, ty = y - fy;
        return texel(x0, y0) * ((1 - tx) * (1 - ty)) + texel(x0 + 1, y0) * (tx * (1 - ty)) +
               texel(x0, y0 + 1) * ((1 - tx) * ty) + texel(x0 + 1, y0 + 1) * (tx * ty);
    }
    ValueRange range() const override { return texels_.global_range(); }
    ValueRange range_uv(const Vec2& lo, const Vec2& hi) const override {
        // The rectangle's image under to_uv (an affine map: its corners' bounding box), then the
        // texels the filter reads there (bilinear: the two around x - 1/2 per axis).
        float u0 = kInf, u1 = -kInf, v0 = kInf, v1 = -kInf;
        for (int corner = 0; corner < 4; ++corner) {
            Vec2 q = t_.apply(Vec2((corner & 1) ? hi.x : lo.x, (corner & 2) ? hi.y : lo.y));
            u0 = std::min(u0, q.x), u1 = std::max(u1, q.x), v0 = std::min(v0, q.y), v1 = std::max(v1, q.y);
        }
        if (!(std::isfinite(u0) && std::isfinite(u1) && std::isfinite(v0) && std::isfinite(v1))) return range();
        constexpr float kMargin = 1e-3f;  // texels: float rounding between this box and eval()
        const float shift = filter_ == BitmapFilter::Bilinear ? 0.5f : 0.0f;
        const int extra = filter_ == BitmapFilter::Bilinear ? 1 : 0;
        constexpr float kLimit = 1e9f;  // far outside: wrap_interval covers the whole axis anyway
        auto index = [&](float x) { return (long long)std::floor(std::clamp(x, -kLimit, kLimit)); };
        long long ilo[3] = {index(u0 * w_ - shift - kMargin), index(v0 * h_ - shift - kMargin), 0};
        long long ihi[3] = {index(u1 * w_ - shift + kMargin) + extra, index(v1 * h_ - shift + kMargin) + extra, 0};
        ValueRange r = ValueRange::empty(3);
        texels_.include_range_wrapped(ilo, ihi, wrap_, &r);
        return r;
    }

private:
    Rgb texel(int x, int y) const {
        const float* t = texels_.at(wrap_index(x, w_, wrap_), wrap_index(y, h_, wrap_), 0);
        return Rgb(t[0], t[1], t[2]);
    }
    SampleGrid texels_;  // row 0 = v 0
    float mean_ = 0;
    int w_, h_;
    BitmapFilter filter_;
    WrapMode wrap_;
    UvTransform t_;
};

}  // namespace

namespace {

class MeshAttributeTexture final : public Texture {
public:
    MeshAttributeTexture(std::string name, float scale) : name_(std::move(name)), scale_(scale) {}
    Rgb eval(const TexturePoint& at) const override {
        const TriMesh::Attribute* a = at.mesh ? at.mesh->attribute(name_) : nullptr;
        if (!a) return Rgb(0.0f);
        if (a->per_face) return a->values[at.prim] * scale_;
        const uint32_t* tri = &at.mesh->idx[3 * size_t(at.prim)];
        return (a->values[tri[0]] * (1.0f - at.bary.x - at.bary.y) + a->values[tri[1]] * at.bary.x +
                a->values[tri[2]] * at.bary.y) * scale_;
    }
    // The values depend on the meshes the texture is used on: unbounded for range queries.
    ValueRange range() const override {
        ValueRange r;
        r.channels = 3;
        for (int c = 0; c < 3; ++c) {
            r.lo[c] = -kInf;
            r.hi[c] = kInf;
        }
        return r;
    }
    float mean() const override { return 0.5f; }

private:
    std::string name_;
    float scale_;
};

}  // namespace

std::shared_ptr<Texture> make_mesh_attribute_texture(std::string name, float scale) {
    return std::make_shared<MeshAttributeTexture>(std::move(name), scale);
}

std::shared_ptr<Texture> make_constant_texture(const Rgb& v) { return std::make_shared<ConstantTexture>(v); }
std::shared_ptr<Texture> make_checkerboard_texture(std::shared_ptr<Texture> c0, std::shared_ptr<Texture> c1,
                                                   const UvTransform& t) {
    return std::make_shared<CheckerboardTexture>(std::move(c0), std::move(c1), t);
}
std::shared_ptr<Texture> make_bitmap_texture(std::vector<float> rgb, int w, int h, BitmapFilter f, WrapMode m,
                                             const UvTransform& t) {
    return std::make_shared<BitmapTexture>(std::move(rgb), w, h, f, m, t);
}

}  // namespace mf
