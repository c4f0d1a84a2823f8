// macrofacet for Mitsuba 3 — the <volume> and <texture> objects nested in a medium as the sources
// of mfrender's fields (cpp_host/src/field.h, volume.h, texture.h), so that the parameter
// mapping of cpp_host/src/medium_field.h serves both renderers. Values come from Mitsuba's own
// Volume and Texture API (its filter, wrap mode, to_uv, colour handling); bounds, which the API
// does not give, come from the samples themselves:
//
//   gridvolume    Volume::max() and max_per_channel() bound from above over all of space only,
//                 and nothing bounds from below, while majorants need both per region (a
//                 varying sigma's density factor is (sigma_hi / sigma_lo)², seeds/000 Eq. 13 via
//                 src/field.rs; the kernel form's roughness is sqrt(2) sigma / l, largest at the
//                 smallest l). So the plugin reads the grid's samples (traverse "data", shape
//                 nz × ny × nx × channels) and its world → unit-cube map (Volume::m_to_local,
//                 including to_world and use_grid_bbox), and bounds segments with mfrender's
//                 min/max pyramid over them (sample_grid.h: at most 8 nodes per query). Samples
//                 sit at cell centres, ((i + ½) / nx, ...), as Mitsuba's Dr.Jit texture reads
//                 them. The pyramid is read as for trilinear lookups, which also bounds
//                 filter_type nearest (its sample is one of the trilinear pair).
//   wrap_mode     not reported by the API, but decided by the values Mitsuba returns beyond the
//                 unit cube (wrap_mode_of): clamp, repeat and mirror read different samples there.
//   constvolume   its value, read once (a float's `value` is a UniformSpectrum: 1 channel).
//   bitmap        its texels (traverse "data", float32 or float16): bilinear and nearest lookups
//                 are convex combinations of them; checkerboard: the union of its two textures;
//                 a texture that is not spatially varying: its value. Textures are bounded over
//                 all of uv (the uv along a segment is unknown), as mfrender's.
//
// Every source is read by Mitsuba in float; bounds carry the host pyramid's margins (volume.cpp).
#pragma once

#include <mitsuba/render/texture.h>
#include <mitsuba/render/volume.h>

#include <memory>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "cpp_host/src/texture.h"
#include "cpp_host/src/volume.h"
#include "traversal.h"

namespace mfmi {

/// A Mitsuba tensor's values as floats, with its shape.
struct TensorSamples {
    std::vector<float> values;
    std::vector<size_t> shape;
};

/// The float32 or float16 tensor `name` that `t` reports, or false.
template <typename Float>
bool tensor_samples(const Traversed& t, std::string_view name, TensorSamples* out) {
    auto read = [&](const auto* tensor) {
        if (!tensor) return false;
        out->shape.assign(tensor->shape().begin(), tensor->shape().end());
        const auto& a = tensor->array();
        out->values.resize(a.size());
        for (size_t i = 0; i < a.size(); ++i) out->values[i] = float(a.data()[i]);
        return true;
    };
    using Tensor32 = dr::Tensor<mitsuba::DynamicBuffer<Float>>;
    using Tensor16 = dr::Tensor<mitsuba::DynamicBuffer<dr::float16_array_t<Float>>>;
    return read(t.value<Tensor32>(name)) || read(t.value<Tensor16>(name));
}

/// The samples of a gridvolume as mfrender's grid volumes take them: x fastest, `channels` per
/// sample, the unit cube placed in the world by `to_world`.
struct GridSamples {
    std::vector<float> values;
    int n[3] = {0, 0, 0};
    int channels = 0;
    ::mf::Mat4 to_world;
    const float* at(size_t i, size_t j, size_t k) const {
        return values.data() + ((k * size_t(n[1]) + j) * size_t(n[0]) + i) * size_t(channels);
    }
};

/// Reads Volume::m_to_local, which the API does not expose (a protected member of the wheel's
/// volume.h; a member pointer named through a derived class may read it on any Volume).
template <typename Float, typename Spectrum>
struct VolumePlacement final : mitsuba::Volume<Float, Spectrum> {
    static ::mf::Mat4 to_world(const mitsuba::Volume<Float, Spectrum>& volume) {
        const auto& to_local = volume.*(&VolumePlacement::m_to_local);
        ::mf::Mat4 m;
        for (int r = 0; r < 4; ++r)
            for (int c = 0; c < 4; ++c) m.m[r][c] = double(to_local.matrix(r, c));
        return m.inverse();
    }
};

/// "gridvolume", "constvolume", "bitmap", "checkerboard", or Mitsuba's class name.
inline std::string plugin_name(const mitsuba::Object& o) {
    const std::string_view c = o.class_name();
    if (c == "GridVolume") return "gridvolume";
    if (c == "ConstVolume") return "constvolume";
    if (c.rfind("BitmapTexture", 0) == 0) return "bitmap";
    if (c == "Checkerboard") return "checkerboard";
    return std::string(c);
}

/// How many values a Mitsuba volume gives (a gridvolume: its channels; a constvolume: 1 for a
/// float value, 3 otherwise).
template <typename Float, typename Spectrum>
int volume_channels(const mitsuba::Volume<Float, Spectrum>& v) {
    if (plugin_name(v) != "constvolume") return int(v.channel_count());
    mitsuba::Object* value = Traversed(const_cast<mitsuba::Volume<Float, Spectrum>*>(&v)).object("value");
    return value && value->class_name() == std::string_view("UniformSpectrum") ? 1 : 3;
}

/// A gridvolume's `channels` values at world point p (Mitsuba's eval_1 / eval_3 / eval_6).
template <typename Float, typename Spectrum>
void eval_grid(const mitsuba::Volume<Float, Spectrum>& v, int channels, const ::mf::Vec3& p, float* out) {
    MI_IMPORT_TYPES()
    const Interaction3f it(0.f, 0.f, Wavelength(0.f), Point3f(p.x, p.y, p.z));
    if (channels == 1) {
        out[0] = v.eval_1(it);
    } else if (channels == 3) {
        const Vector3f c = v.eval_3(it);
        for (int i = 0; i < 3; ++i) out[i] = c[i];
    } else {
        const dr::Array<Float, 6> c = v.eval_6(it);
        for (int i = 0; i < 6; ++i) out[i] = c[i];
    }
}

/// A constvolume's value (`channels` = volume_channels()); throws if its value varies.
template <typename Float, typename Spectrum>
void constvolume_value(const mitsuba::Volume<Float, Spectrum>& v, int channels, float* out) {
    MI_IMPORT_TYPES()
    auto* value = dynamic_cast<mitsuba::Texture<Float, Spectrum>*>(
        Traversed(const_cast<mitsuba::Volume<Float, Spectrum>*>(&v)).object("value"));
    if (value && value->is_spatially_varying()) throw std::runtime_error("the constvolume's value varies (give a gridvolume)");
    const auto c = v.eval(Interaction3f(0.f, 0.f, Wavelength(0.f), Point3f(0.f)));
    for (int i = 0; i < channels; ++i) out[i] = c[i];
}

/// A gridvolume's samples and placement; throws if the volume does not report them.
template <typename Float, typename Spectrum>
GridSamples grid_samples(const mitsuba::Volume<Float, Spectrum>& v) {
    TensorSamples t;
    if (!tensor_samples<Float>(Traversed(const_cast<mitsuba::Volume<Float, Spectrum>*>(&v)), "data", &t) || t.shape.size() != 4)
        throw std::runtime_error("cannot read the grid's samples");
    GridSamples g;
    g.n[0] = int(t.shape[2]);
    g.n[1] = int(t.shape[1]);
    g.n[2] = int(t.shape[0]);
    g.channels = int(t.shape[3]);
    g.values = std::move(t.values);
    g.to_world = VolumePlacement<Float, Spectrum>::to_world(v);
    if (!g.to_world.finite()) throw std::runtime_error("the grid's placement (to_world) is singular");
    return g;
}

/// The wrap_mode of a gridvolume, from its values beyond the unit cube. At local coordinate
/// 1 + (m + ½) / n along an axis, with the other axes at cell centres, the lookup reads (for
/// either filter) the sample of index n + m, which is n − 1 under clamp, m under repeat and
/// n − 1 − m under mirror. The samples show where two candidates differ; one evaluation there
/// keeps the candidates that predict the value Mitsuba returns. Candidates that no sample tells
/// apart are the same function everywhere (e.g. clamp and repeat of a grid that is constant along
/// every axis); clamp is then reported, the strictest for the coverage check.
template <typename Float, typename Spectrum>
::mf::WrapMode wrap_mode_of(const mitsuba::Volume<Float, Spectrum>& v, const GridSamples& g) {
    using ::mf::WrapMode;
    std::vector<WrapMode> left = {WrapMode::Clamp, WrapMode::Repeat, WrapMode::Mirror};
    auto differ = [](float a, float b) { return std::fabs(a - b) > 1e-4f * (std::fabs(a) + std::fabs(b)); };
    std::vector<float> observed(size_t(g.channels));
    for (int a = 0; a < 3; ++a) {
        const int n = g.n[a];
        if (n < 2) continue;
        for (size_t k = 0; k < size_t(g.n[2]); ++k)
            for (size_t j = 0; j < size_t(g.n[1]); ++j)
                for (size_t i = 0; i < size_t(g.n[0]); ++i) {
                    size_t idx[3] = {i, j, k};
                    const int m = int(idx[a]);
                    auto read = [&](int along) {
                        size_t q[3] = {i, j, k};
                        q[a] = size_t(along);
                        return g.at(q[0], q[1], q[2]);
                    };
                    const float* predicted[3];
                    for (size_t c = 0; c < left.size(); ++c)
                        predicted[c] = read(left[c] == WrapMode::Clamp ? n - 1 : left[c] == WrapMode::Repeat ? m : n - 1 - m);
                    for (int ch = 0; ch < g.channels; ++ch) {
                        bool split = false;
                        for (size_t x = 0; x < left.size(); ++x)
                            for (size_t y = x + 1; y < left.size(); ++y) split |= differ(predicted[x][ch], predicted[y][ch]);
                        if (!split) continue;
                        ::mf::Vec3 u;
                        for (int b = 0; b < 3; ++b) u[b] = float((double(idx[b]) + 0.5) / double(g.n[b]));
                        u[a] = float(1.0 + (double(m) + 0.5) / double(n));
                        eval_grid(v, g.channels, g.to_world.point(u), observed.data());
                        size_t best = 0;
                        for (size_t c = 1; c < left.size(); ++c)
                            if (std::fabs(predicted[c][ch] - observed[size_t(ch)]) < std::fabs(predicted[best][ch] - observed[size_t(ch)])) best = c;
                        std::vector<WrapMode> kept;
                        const float* kept_predicted[3];
                        for (size_t c = 0; c < left.size(); ++c)
                            if (!differ(predicted[c][ch], predicted[best][ch])) {
                                kept_predicted[kept.size()] = predicted[c];
                                kept.push_back(left[c]);
                            }
                        left = kept;
                        if (left.size() == 1) return left[0];
                        for (size_t c = 0; c < left.size(); ++c) predicted[c] = kept_predicted[c];
                    }
                }
    }
    return left[0];
}

/// One parameter's value from Mitsuba volumes, as mfrender's Volume: parts side by side (a
/// matrix from its two halves), each read from a Mitsuba volume or a constant; a 1-channel part
/// of a 3-channel parameter is broadcast. Ranges, coverage and constancy are `bounds`'s: an
/// mfrender volume over the same samples (with derived range channels where the field adds them,
/// field.h).
template <typename Float, typename Spectrum>
class MitsubaVolume final : public ::mf::Volume {
public:
    using MiVolume = mitsuba::Volume<Float, Spectrum>;
    struct Part {
        mitsuba::ref<const MiVolume> volume;  // a gridvolume, or null: `constant`
        int channels = 1;                     // what the volume gives
        int width = 1;                        // what the parameter takes (channels, or 3 from 1)
        float constant[3] = {0, 0, 0};
    };

    MitsubaVolume(std::vector<Part> parts, std::shared_ptr<const ::mf::Volume> bounds)
        : parts_(std::move(parts)), bounds_(std::move(bounds)) {}

    int channels() const override { return bounds_->channels(); }
    void eval(const ::mf::Vec3& p, float* out) const override {
        for (const Part& part : parts_) {
            float v[6];
            if (part.volume) eval_grid(*part.volume, part.channels, p, v);
            else std::copy(part.constant, part.constant + part.channels, v);
            for (int c = 0; c < part.width; ++c) out[c] = v[part.channels == 1 ? 0 : c];
            out += part.width;
        }
    }
    ::mf::ValueRange range_box(const ::mf::Aabb& box) const override { return bounds_->range_box(box); }
    ::mf::ValueRange range_segment(const ::mf::Vec3& o, const ::mf::Vec3& d, float length) const override {
        return bounds_->range_segment(o, d, length);
    }
    ::mf::ValueRange range() const override { return bounds_->range(); }
    const float* constant() const override { return bounds_->constant(); }
    bool covers(const ::mf::Aabb& box) const override { return bounds_->covers(box); }
    const char* kind() const override { return bounds_->kind(); }

private:
    std::vector<Part> parts_;
    std::shared_ptr<const ::mf::Volume> bounds_;
};

/// Per-channel bounds (rgb) of every value a Mitsuba texture takes (file comment); throws for a
/// texture whose values the plugin cannot bound.
template <typename Float, typename Spectrum>
::mf::ValueRange texture_range(const mitsuba::Texture<Float, Spectrum>& t) {
    MI_IMPORT_TYPES()
    using MiTexture = mitsuba::Texture<Float, Spectrum>;
    auto* object = const_cast<MiTexture*>(&t);
    const std::string kind = plugin_name(t);
    if (!t.is_spatially_varying()) {
        const auto c = t.eval(dr::zeros<SurfaceInteraction3f>());
        const float v[3] = {c[0], c[1], c[2]};
        return ::mf::ValueRange::of(v, 3);
    }
    if (kind == "bitmap") {
        TensorSamples s;
        if (!tensor_samples<Float>(Traversed(object), "data", &s) || s.shape.size() != 3 || (s.shape[2] != 1 && s.shape[2] != 3))
            throw std::runtime_error("cannot read the bitmap's texels (1 or 3 channels)");
        const size_t channels = s.shape[2];
        ::mf::ValueRange r = ::mf::ValueRange::empty(3);
        for (size_t i = 0; i < s.values.size(); i += channels) {
            const float v[3] = {s.values[i], s.values[i + (channels == 3 ? 1 : 0)], s.values[i + (channels == 3 ? 2 : 0)]};
            r.include(v);
        }
        return r;
    }
    if (kind == "checkerboard") {
        const Traversed parts(object);
        auto* c0 = dynamic_cast<MiTexture*>(parts.object("color0"));
        auto* c1 = dynamic_cast<MiTexture*>(parts.object("color1"));
        if (!c0 || !c1) throw std::runtime_error("cannot read the checkerboard's color0 and color1");
        ::mf::ValueRange r = texture_range(*c0);
        r.include(texture_range(*c1));
        return r;
    }
    throw std::runtime_error("<texture> of class " + kind +
                             ": the plugin bounds the values of bitmap, checkerboard and constant textures only "
                             "(majorants need them)");
}

/// A Mitsuba texture as mfrender's Texture: eval at the mean surface's uv through Mitsuba's
/// Texture::eval, bounds from texture_range().
template <typename Float, typename Spectrum>
class MitsubaTexture final : public ::mf::Texture {
public:
    using MiTexture = mitsuba::Texture<Float, Spectrum>;
    explicit MitsubaTexture(mitsuba::ref<const MiTexture> texture)
        : texture_(std::move(texture)), range_(texture_range(*texture_)), constant_(!texture_->is_spatially_varying()) {
        value_ = ::mf::Rgb(range_.lo[0], range_.lo[1], range_.lo[2]);
    }
    ::mf::Rgb eval(const ::mf::TexturePoint& at) const override {
        MI_IMPORT_TYPES()
        SurfaceInteraction3f si = dr::zeros<SurfaceInteraction3f>();
        si.uv = Point2f(at.uv.x, at.uv.y);
        const auto c = texture_->eval(si);
        return ::mf::Rgb(c[0], c[1], c[2]);
    }
    ::mf::ValueRange range() const override { return range_; }
    const ::mf::Rgb* constant() const override { return constant_ ? &value_ : nullptr; }
    /// Mitsuba's own mean over the texture's domain.
    float mean() const override { return static_cast<float>(dr::slice(texture_->mean())); }

private:
    mitsuba::ref<const MiTexture> texture_;
    ::mf::ValueRange range_;
    bool constant_;
    ::mf::Rgb value_;
};

}  // namespace mfmi
