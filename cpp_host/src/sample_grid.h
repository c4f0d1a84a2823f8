// mfhost — regular grids of multi-channel samples (the storage of grid volumes and bitmap
// textures), their wrap modes, and conservative value ranges over index boxes.
//
// A SampleGrid holds nx x ny x nz samples of `stride` floats each (a 2D grid has nz = 1), sample
// (i, j, k) at ((k * ny + j) * nx + i) * stride, as Mitsuba's .vol files and bitmaps store them.
// Besides the samples it keeps a min/max pyramid: level l + 1 holds, per channel, the minimum and
// maximum over 2x2x2 nodes of level l (level 0 is the samples). A query over an index box reads
// the level at which the box spans at most two nodes per axis, i.e. at most 8 nodes, so its cost
// does not depend on the box's size; the answer contains the true range (it may be wider, never
// narrower). Trilinear and bilinear interpolants are convex combinations of their samples, so
// the range of the samples an interpolant reads bounds the interpolant itself.
#pragma once

#include <cstddef>
#include <vector>

namespace mf {

/// How sample indices outside [0, n) map into the grid (Mitsuba 3 / Dr.Jit conventions):
/// clamp to the edge, repeat periodically, or mirror at every edge (period 2n).
enum class WrapMode { Repeat, Mirror, Clamp };

/// The index in [0, n) that sample index i reads under `mode` (n > 0).
inline int wrap_index(int i, int n, WrapMode mode) {
    switch (mode) {
        case WrapMode::Repeat: i %= n; return i < 0 ? i + n : i;
        case WrapMode::Clamp: return i < 0 ? 0 : (i >= n ? n - 1 : i);
        case WrapMode::Mirror: {
            int p = i % (2 * n);
            if (p < 0) p += 2 * n;
            return p < n ? p : 2 * n - 1 - p;
        }
    }
    return 0;
}

/// The indices in [0, n) that the index interval [lo, hi] (lo <= hi) reads under `mode`, as at most
/// two inclusive intervals out[0..count) (repeat may split an interval at the edge; clamp and
/// mirror map an interval to one interval). Returns the count.
int wrap_interval(long long lo, long long hi, int n, WrapMode mode, int out[2][2]);

/// Per-channel value bounds. `channels` entries of lo/hi are meaningful.
struct ValueRange {
    static constexpr int kMaxChannels = 8;  // 6 matrix entries + 2 eigenvalue bounds (field.h)
    int channels = 0;
    float lo[kMaxChannels];
    float hi[kMaxChannels];
    /// An empty range (lo = +inf, hi = -inf) of `n` channels, to be widened with include().
    static ValueRange empty(int n);
    /// The range of exactly the values v[0..n).
    static ValueRange of(const float* v, int n);
    void include(const ValueRange& r);
    void include(const float* v);
    bool contains(const float* v, float tol = 0) const;
};

class SampleGrid {
public:
    SampleGrid() = default;
    /// `values` holds nx * ny * nz * stride floats; the pyramid is built over all `stride` channels.
    SampleGrid(std::vector<float> values, int nx, int ny, int nz, int stride);

    int nx() const { return n_[0]; }
    int ny() const { return n_[1]; }
    int nz() const { return n_[2]; }
    int size(int axis) const { return n_[axis]; }
    int stride() const { return stride_; }
    size_t count() const { return size_t(n_[0]) * size_t(n_[1]) * size_t(n_[2]); }
    const std::vector<float>& values() const { return values_; }
    /// The `stride` floats of sample (i, j, k), all in range.
    const float* at(int i, int j, int k) const {
        return values_.data() + ((size_t(k) * size_t(n_[1]) + size_t(j)) * size_t(n_[0]) + size_t(i)) * size_t(stride_);
    }

    /// Widens `r` (stride channels) to contain every sample in the inclusive index box
    /// [lo[a], hi[a]] on each axis a, which must lie inside the grid.
    void include_range(const int lo[3], const int hi[3], ValueRange* r) const;
    /// Widens `r` by the samples an interpolant reads over the (unwrapped) index box: each axis's
    /// interval goes through wrap_interval first.
    void include_range_wrapped(const long long lo[3], const long long hi[3], WrapMode mode, ValueRange* r) const;
    /// The range of all samples (the pyramid's top).
    const ValueRange& global_range() const { return global_; }

private:
    struct Level {
        int n[3] = {0, 0, 0};
        std::vector<float> lo, hi;  // node ((k * ny + j) * nx + i) * stride + c
    };
    std::vector<float> values_;
    int n_[3] = {0, 0, 0};
    int stride_ = 0;
    std::vector<Level> levels_;  // levels_[l - 1] is level l >= 1
    ValueRange global_;
};

}  // namespace mf
