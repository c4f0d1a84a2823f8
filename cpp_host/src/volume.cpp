// mfhost — constant and grid volumes (see volume.h).
#include "volume.h"

#include <algorithm>
#include <cmath>
#include <cstring>

namespace mf {

namespace {

class ConstantVolume final : public Volume {
public:
    ConstantVolume(const float* v, int channels, int stride) : channels_(channels), stride_(stride) {
        std::copy(v, v + stride, value_);
    }
    int channels() const override { return channels_; }
    void eval(const Vec3&, float* out) const override { std::copy(value_, value_ + channels_, out); }
    ValueRange range_box(const Aabb&) const override { return range(); }
    ValueRange range_segment(const Vec3&, const Vec3&, float) const override { return range(); }
    ValueRange range() const override { return ValueRange::of(value_, stride_); }
    const float* constant() const override { return value_; }
    bool covers(const Aabb&) const override { return true; }
    const char* kind() const override { return "constvolume"; }

private:
    int channels_, stride_;
    float value_[ValueRange::kMaxChannels] = {};
};

/// An affine map in single precision (world -> grid-local), for the per-query transforms.
struct Affine3f {
    float m[3][4];
    explicit Affine3f(const Mat4& a) {
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 4; ++j) m[i][j] = float(a.m[i][j]);
    }
    Vec3 point(const Vec3& p) const {
        return {m[0][0] * p.x + m[0][1] * p.y + m[0][2] * p.z + m[0][3], m[1][0] * p.x + m[1][1] * p.y + m[1][2] * p.z + m[1][3],
                m[2][0] * p.x + m[2][1] * p.y + m[2][2] * p.z + m[2][3]};
    }
    Vec3 vector(const Vec3& v) const {
        return {m[0][0] * v.x + m[0][1] * v.y + m[0][2] * v.z, m[1][0] * v.x + m[1][1] * v.y + m[1][2] * v.z,
                m[2][0] * v.x + m[2][1] * v.y + m[2][2] * v.z};
    }
    /// |linear part| * v: the half extent of the image of a box with half extent v.
    Vec3 abs_vector(const Vec3& v) const {
        return {std::fabs(m[0][0]) * v.x + std::fabs(m[0][1]) * v.y + std::fabs(m[0][2]) * v.z,
                std::fabs(m[1][0]) * v.x + std::fabs(m[1][1]) * v.y + std::fabs(m[1][2]) * v.z,
                std::fabs(m[2][0]) * v.x + std::fabs(m[2][1]) * v.y + std::fabs(m[2][2]) * v.z};
    }
};

/// floor() as an int, with the argument kept where the int conversion is defined (a point
/// millions of cells away reads the same samples as one a few cells away, for every wrap mode
/// up to rounding of a coordinate that float cannot resolve anyway).
inline long long floor_index(float x) {
    constexpr float kLimit = 1e9f;
    if (!(x > -kLimit)) return -(long long)kLimit;  // also NaN
    if (x > kLimit) return (long long)kLimit;
    return (long long)std::floor(x);
}

class GridVolume final : public Volume {
public:
    GridVolume(SampleGrid grid, int channels, const Mat4& to_world, VolumeFilter filter, WrapMode wrap)
        : grid_(std::move(grid)), channels_(channels), to_world_(to_world), to_local_d_(to_world.inverse()),
          to_local_(to_local_d_), filter_(filter), wrap_(wrap) {
        for (int a = 0; a < 3; ++a) res_[a] = float(grid_.size(a));
    }
    int channels() const override { return channels_; }
    const char* kind() const override { return "gridvolume"; }

    void eval(const Vec3& p, float* out) const override {
        Vec3 u = to_local_.point(p);
        if (filter_ == VolumeFilter::Nearest) {
            const float* s = grid_.at(wrap(floor_index(u.x * res_[0]), 0), wrap(floor_index(u.y * res_[1]), 1),
                                      wrap(floor_index(u.z * res_[2]), 2));
            std::copy(s, s + channels_, out);
            return;
        }
        // Trilinear between cell centres: x = u n - 1/2 (Dr.Jit's Texture3f, as Mitsuba's gridvolume).
        float x = u.x * res_[0] - 0.5f, y = u.y * res_[1] - 0.5f, z = u.z * res_[2] - 0.5f;
        long long x0 = floor_index(x), y0 = floor_index(y), z0 = floor_index(z);
        float tx = x - float(x0), ty = y - float(y0), tz = z - float(z0);
        if (!(tx >= 0 && tx <= 1)) tx = 0;  // far outside (floor_index clamped) or NaN
        if (!(ty >= 0 && ty <= 1)) ty = 0;
        if (!(tz >= 0 && tz <= 1)) tz = 0;
        int i[2] = {wrap(x0, 0), wrap(x0 + 1, 0)}, j[2] = {wrap(y0, 1), wrap(y0 + 1, 1)}, k[2] = {wrap(z0, 2), wrap(z0 + 1, 2)};
        float wx[2] = {1 - tx, tx}, wy[2] = {1 - ty, ty}, wz[2] = {1 - tz, tz};
        for (int c = 0; c < channels_; ++c) out[c] = 0;
        for (int dz = 0; dz < 2; ++dz)
            for (int dy = 0; dy < 2; ++dy)
                for (int dx = 0; dx < 2; ++dx) {
                    float w = wx[dx] * wy[dy] * wz[dz];
                    const float* s = grid_.at(i[dx], j[dy], k[dz]);
                    for (int c = 0; c < channels_; ++c) out[c] += w * s[c];
                }
    }

    ValueRange range_box(const Aabb& box) const override {
        if (!box.valid() || !all_finite(box.lo) || !all_finite(box.hi)) return range();
        Vec3 c = to_local_.point(box.center()), e = to_local_.abs_vector(box.extent() * 0.5f);
        ValueRange r = ValueRange::empty(grid_.stride());
        include_local_box(c - e, c + e, &r);
        return r;
    }

    ValueRange range_segment(const Vec3& o, const Vec3& d, float length) const override {
        if (!(length >= 0) || !std::isfinite(length) || !all_finite(o) || !all_finite(d)) return range();
        Vec3 ol = to_local_.point(o), dl = to_local_.vector(d) * length;
        // Pieces of at most kPieceCells cells along the longest axis (up to kMaxPieces): each piece's
        // box spans few nodes of a fine pyramid level, so a long diagonal segment is not bounded by
        // its whole bounding box.
        float cells = std::max(std::fabs(dl.x) * res_[0], std::max(std::fabs(dl.y) * res_[1], std::fabs(dl.z) * res_[2]));
        constexpr float kPieceCells = 4.0f;
        constexpr int kMaxPieces = 64;
        int pieces = cells <= kPieceCells ? 1 : int(std::min<float>(std::ceil(cells / kPieceCells), float(kMaxPieces)));
        ValueRange r = ValueRange::empty(grid_.stride());
        Vec3 a = ol;
        for (int n = 1; n <= pieces; ++n) {
            Vec3 b = n == pieces ? ol + dl : ol + dl * (float(n) / float(pieces));
            include_local_box(vmin(a, b), vmax(a, b), &r);
            a = b;
        }
        return r;
    }

    ValueRange range() const override { return grid_.global_range(); }

    bool covers(const Aabb& box) const override {
        if (wrap_ != WrapMode::Clamp) return true;
        constexpr double kTol = 1e-5;  // unit-cube coordinates: float rounding of the scene's numbers
        for (int corner = 0; corner < 8; ++corner) {
            Vec3 p((corner & 1) ? box.hi.x : box.lo.x, (corner & 2) ? box.hi.y : box.lo.y, (corner & 4) ? box.hi.z : box.lo.z);
            const auto& m = to_local_d_.m;
            for (int a = 0; a < 3; ++a) {
                double u = m[a][0] * p.x + m[a][1] * p.y + m[a][2] * p.z + m[a][3];
                if (!(u >= -kTol && u <= 1 + kTol)) return false;
            }
        }
        return true;
    }

    const SampleGrid& grid() const { return grid_; }

private:
    int wrap(long long i, int axis) const {
        // wrap_index takes an int: reduce first (clamp keeps its meaning; periods are exact).
        int n = grid_.size(axis);
        if (wrap_ == WrapMode::Clamp) return int(std::clamp<long long>(i, 0, n - 1));
        long long period = wrap_ == WrapMode::Repeat ? n : 2LL * n;
        long long r = i % period;
        return wrap_index(int(r < 0 ? r + period : r), n, wrap_);
    }

    /// Widens r by the samples the interpolant reads anywhere in the local (unit-cube) box [lo, hi].
    void include_local_box(const Vec3& lo, const Vec3& hi, ValueRange* r) const {
        // A margin of 1e-3 cells absorbs the float rounding between this box and a point's own
        // transform in eval(): the answer may include one more sample, never miss one.
        constexpr float kMargin = 1e-3f;
        const float shift = filter_ == VolumeFilter::Trilinear ? 0.5f : 0.0f;
        long long ilo[3], ihi[3];
        for (int a = 0; a < 3; ++a) {
            ilo[a] = floor_index(lo[a] * res_[a] - shift - kMargin);
            ihi[a] = floor_index(hi[a] * res_[a] - shift + kMargin) + (filter_ == VolumeFilter::Trilinear ? 1 : 0);
        }
        grid_.include_range_wrapped(ilo, ihi, wrap_, r);
    }

    SampleGrid grid_;
    int channels_;
    Mat4 to_world_, to_local_d_;
    Affine3f to_local_;
    VolumeFilter filter_;
    WrapMode wrap_;
    float res_[3];
};

}  // namespace

std::shared_ptr<Volume> make_constant_volume(const float* value, int channels, int stride) {
    return std::make_shared<ConstantVolume>(value, channels, stride);
}

std::shared_ptr<Volume> make_grid_volume(SampleGrid grid, int channels, const Mat4& to_world, VolumeFilter filter,
                                         WrapMode wrap) {
    return std::make_shared<GridVolume>(std::move(grid), channels, to_world, filter, wrap);
}

}  // namespace mf
