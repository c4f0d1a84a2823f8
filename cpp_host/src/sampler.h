// mfhost — counter-based random numbers.
//
// A Sampler is a pure function of (seed, pixel index, sample index, dimension counter): the
// stream is SplitMix64 (Steele et al. 2014) keyed by a hash of the first three. Rendering a
// pixel therefore produces the same numbers whatever thread renders it, which makes output
// bit-identical for a given --seed regardless of thread count or scheduling.
#pragma once

#include <cstdint>

#include "math.h"

namespace mf {

inline uint64_t splitmix64(uint64_t x) {
    x += 0x9E3779B97F4A7C15ull;
    x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
    x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
    return x ^ (x >> 31);
}

class Sampler {
public:
    Sampler(uint64_t seed, uint64_t pixel, uint64_t sample_index)
        : key_(splitmix64(splitmix64(splitmix64(seed) ^ pixel) ^ (sample_index * 0xD1B54A32D192ED03ull))) {}
    /// Uniform in [0, 1).
    float next_1d() {
        uint64_t h = splitmix64(key_ + counter_++ * 0x9E3779B97F4A7C15ull);
        return float(h >> 40) * 0x1p-24f;
    }
    Vec2 next_2d() {
        float a = next_1d();
        float b = next_1d();
        return {a, b};
    }
    /// 64 random bits (one dimension): e.g. the seed of a library call that owns its generator
    /// (mf_gpis_trace), so it is a pure function of (seed, pixel, sample index, dimension).
    uint64_t next_u64() { return splitmix64(key_ + counter_++ * 0x9E3779B97F4A7C15ull); }
    uint64_t dimension() const { return counter_; }

private:
    uint64_t key_;
    uint64_t counter_ = 0;
};

}  // namespace mf
