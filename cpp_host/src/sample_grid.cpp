// mfhost — sample grids and their min/max pyramids (see sample_grid.h).
#include "sample_grid.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace mf {

int wrap_interval(long long lo, long long hi, int n, WrapMode mode, int out[2][2]) {
    const long long count = hi - lo + 1;
    auto mod = [](long long a, long long m) {
        long long r = a % m;
        return r < 0 ? r + m : r;
    };
    switch (mode) {
        case WrapMode::Clamp:
            out[0][0] = int(std::clamp<long long>(lo, 0, n - 1));
            out[0][1] = int(std::clamp<long long>(hi, 0, n - 1));
            return 1;
        case WrapMode::Repeat: {
            if (count >= n) {
                out[0][0] = 0;
                out[0][1] = n - 1;
                return 1;
            }
            long long a = mod(lo, n), b = a + count - 1;
            if (b < n) {
                out[0][0] = int(a);
                out[0][1] = int(b);
                return 1;
            }
            out[0][0] = int(a);
            out[0][1] = n - 1;
            out[1][0] = 0;
            out[1][1] = int(b - n);
            return 2;
        }
        case WrapMode::Mirror: {
            // The mirrored index runs monotonically between its turning points (0 at indices
            // = 0 or -1 mod 2n, n - 1 at indices = n - 1 or n mod 2n), so the image of an
            // interval is the interval between its end values, widened to a turning value the
            // interval contains.
            const long long period = 2LL * n;
            auto hits = [&](long long r) { return lo + mod(r - lo, period) <= hi; };
            int f = wrap_index(int(mod(lo, period)), n, mode), g = wrap_index(int(mod(hi, period)), n, mode);
            out[0][0] = (hits(0) || hits(period - 1)) ? 0 : std::min(f, g);
            out[0][1] = (hits(n - 1) || hits(n)) ? n - 1 : std::max(f, g);
            return 1;
        }
    }
    return 0;
}

ValueRange ValueRange::empty(int n) {
    ValueRange r;
    r.channels = n;
    for (int c = 0; c < kMaxChannels; ++c) {
        r.lo[c] = std::numeric_limits<float>::infinity();
        r.hi[c] = -std::numeric_limits<float>::infinity();
    }
    return r;
}

ValueRange ValueRange::of(const float* v, int n) {
    ValueRange r = empty(n);
    r.include(v);
    return r;
}

void ValueRange::include(const ValueRange& o) {
    for (int c = 0; c < channels; ++c) {
        lo[c] = std::min(lo[c], o.lo[c]);
        hi[c] = std::max(hi[c], o.hi[c]);
    }
}

void ValueRange::include(const float* v) {
    for (int c = 0; c < channels; ++c) {
        lo[c] = std::min(lo[c], v[c]);
        hi[c] = std::max(hi[c], v[c]);
    }
}

bool ValueRange::contains(const float* v, float tol) const {
    for (int c = 0; c < channels; ++c)
        if (!(v[c] >= lo[c] - tol && v[c] <= hi[c] + tol)) return false;
    return true;
}

SampleGrid::SampleGrid(std::vector<float> values, int nx, int ny, int nz, int stride)
    : values_(std::move(values)), n_{nx, ny, nz}, stride_(stride) {
    // Level 1 from the samples, each further level from the one below, up to a single node.
    const int s = stride_;
    int prev_n[3] = {nx, ny, nz};
    const float* prev_lo = values_.data();
    const float* prev_hi = values_.data();
    while (prev_n[0] > 1 || prev_n[1] > 1 || prev_n[2] > 1) {
        Level l;
        for (int a = 0; a < 3; ++a) l.n[a] = (prev_n[a] + 1) / 2;
        size_t nodes = size_t(l.n[0]) * size_t(l.n[1]) * size_t(l.n[2]);
        l.lo.assign(nodes * s, std::numeric_limits<float>::infinity());
        l.hi.assign(nodes * s, -std::numeric_limits<float>::infinity());
        for (int k = 0; k < prev_n[2]; ++k)
            for (int j = 0; j < prev_n[1]; ++j)
                for (int i = 0; i < prev_n[0]; ++i) {
                    size_t src = ((size_t(k) * prev_n[1] + j) * prev_n[0] + i) * s;
                    size_t dst = ((size_t(k / 2) * l.n[1] + j / 2) * l.n[0] + i / 2) * s;
                    for (int c = 0; c < s; ++c) {
                        l.lo[dst + c] = std::min(l.lo[dst + c], prev_lo[src + c]);
                        l.hi[dst + c] = std::max(l.hi[dst + c], prev_hi[src + c]);
                    }
                }
        levels_.push_back(std::move(l));
        const Level& top = levels_.back();
        for (int a = 0; a < 3; ++a) prev_n[a] = top.n[a];
        prev_lo = top.lo.data();
        prev_hi = top.hi.data();
    }
    global_ = ValueRange::empty(std::min(s, ValueRange::kMaxChannels));
    for (int c = 0; c < global_.channels; ++c) {
        global_.lo[c] = prev_lo[c];
        global_.hi[c] = prev_hi[c];
    }
}

void SampleGrid::include_range(const int lo[3], const int hi[3], ValueRange* r) const {
    // The finest level at which the box spans at most two nodes per axis.
    int level = 0;
    while ((hi[0] >> level) - (lo[0] >> level) > 1 || (hi[1] >> level) - (lo[1] >> level) > 1 ||
           (hi[2] >> level) - (lo[2] >> level) > 1)
        ++level;
    const int s = stride_, channels = r->channels;
    if (level == 0) {
        for (int k = lo[2]; k <= hi[2]; ++k)
            for (int j = lo[1]; j <= hi[1]; ++j)
                for (int i = lo[0]; i <= hi[0]; ++i) r->include(at(i, j, k));
        return;
    }
    const Level& l = levels_[size_t(level - 1)];
    for (int k = lo[2] >> level; k <= hi[2] >> level; ++k)
        for (int j = lo[1] >> level; j <= hi[1] >> level; ++j)
            for (int i = lo[0] >> level; i <= hi[0] >> level; ++i) {
                size_t node = ((size_t(k) * l.n[1] + j) * l.n[0] + i) * s;
                for (int c = 0; c < channels; ++c) {
                    r->lo[c] = std::min(r->lo[c], l.lo[node + c]);
                    r->hi[c] = std::max(r->hi[c], l.hi[node + c]);
                }
            }
}

void SampleGrid::include_range_wrapped(const long long lo[3], const long long hi[3], WrapMode mode, ValueRange* r) const {
    int iv[3][2][2], count[3];
    for (int a = 0; a < 3; ++a) count[a] = wrap_interval(lo[a], hi[a], n_[a], mode, iv[a]);
    for (int ck = 0; ck < count[2]; ++ck)
        for (int cj = 0; cj < count[1]; ++cj)
            for (int ci = 0; ci < count[0]; ++ci) {
                int box_lo[3] = {iv[0][ci][0], iv[1][cj][0], iv[2][ck][0]};
                int box_hi[3] = {iv[0][ci][1], iv[1][cj][1], iv[2][ck][1]};
                include_range(box_lo, box_hi, r);
            }
}

}  // namespace mf
