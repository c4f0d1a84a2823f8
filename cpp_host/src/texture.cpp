// mfhost — textures (see texture.h).
#include "texture.h"

namespace mf {

namespace {

class ConstantTexture final : public Texture {
public:
    explicit ConstantTexture(const Rgb& v) : v_(v) {}
    Rgb eval(const Vec2&) const override { return v_; }
    float max_value() const override { return v_.max(); }
    const Rgb* constant() const override { return &v_; }

private:
    Rgb v_;
};

class CheckerboardTexture final : public Texture {
public:
    CheckerboardTexture(std::shared_ptr<Texture> c0, std::shared_ptr<Texture> c1, const UvTransform& t)
        : c0_(std::move(c0)), c1_(std::move(c1)), t_(t) {}
    Rgb eval(const Vec2& uv_in) const override {
        Vec2 uv = t_.apply(uv_in);
        float u = uv.x - std::floor(uv.x), v = uv.y - std::floor(uv.y);
        return ((u > 0.5f) == (v > 0.5f)) ? c0_->eval(uv_in) : c1_->eval(uv_in);
    }
    float max_value() const override { return std::max(c0_->max_value(), c1_->max_value()); }

private:
    std::shared_ptr<Texture> c0_, c1_;
    UvTransform t_;
};

class BitmapTexture final : public Texture {
public:
    BitmapTexture(std::vector<float> rgb, int w, int h, BitmapFilter f, WrapMode m, const UvTransform& t)
        : rgb_(std::move(rgb)), w_(w), h_(h), filter_(f), wrap_(m), t_(t) {
        for (float x : rgb_) max_ = std::max(max_, x);
    }
    Rgb eval(const Vec2& uv_in) const override {
        Vec2 uv = t_.apply(uv_in);
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
    float max_value() const override { return max_; }

private:
    int wrap(int i, int n) const {
        switch (wrap_) {
            case WrapMode::Repeat: i %= n; return i < 0 ? i + n : i;
            case WrapMode::Clamp: return std::clamp(i, 0, n - 1);
            case WrapMode::Mirror: {
                int p = i % (2 * n);
                if (p < 0) p += 2 * n;
                return p < n ? p : 2 * n - 1 - p;
            }
        }
        return 0;
    }
    Rgb texel(int x, int y) const {
        size_t i = 3 * (size_t(wrap(y, h_)) * size_t(w_) + size_t(wrap(x, w_)));
        return Rgb(rgb_[i], rgb_[i + 1], rgb_[i + 2]);
    }
    std::vector<float> rgb_;
    int w_, h_;
    BitmapFilter filter_;
    WrapMode wrap_;
    UvTransform t_;
    float max_ = 0;
};

}  // namespace

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
