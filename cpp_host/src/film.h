// mfhost — image reconstruction as Mitsuba 3's hdrfilm does it: every sample is splatted to the
// pixels within the filter's radius with weight f(dx) f(dy) (pixel centres at integer + 0.5),
// and a pixel's value is sum(w L) / sum(w). Filters: box (radius 0.5: the sample's own pixel),
// tent (1 - |x| / r), gaussian (Mitsuba's: exp(-x^2 / (2 sd^2)) - exp(-r^2 / (2 sd^2)) clamped at
// 0, r = 4 sd; the hdrfilm default with sd = 0.5).
#pragma once

#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

namespace mf {

struct ReconstructionFilter {
    enum class Kind { Box, Tent, Gaussian };
    Kind kind = Kind::Gaussian;
    float radius = 2.0f;
    float stddev = 0.5f;
    /// The gaussian's exponent factor -1 / (2 sd^2) and its value at the radius, exp(a r^2),
    /// computed once per filter rather than per weight (they were half the film's exps, and the
    /// film a fifth of a simple scene's render time).
    float gaussian_a = kind == Kind::Gaussian ? -1.0f / (2.0f * stddev * stddev) : 0.0f;
    float gaussian_bias = kind == Kind::Gaussian ? std::exp(gaussian_a * radius * radius) : 0.0f;

    static ReconstructionFilter box() { return {Kind::Box, 0.5f, 0.0f}; }
    static ReconstructionFilter tent(float r) { return {Kind::Tent, r, 0.0f}; }
    static ReconstructionFilter gaussian(float sd) { return {Kind::Gaussian, 4.0f * sd, sd}; }

    /// 1D weight at offset x (pixels) from the sample.
    float eval(float x) const {
        switch (kind) {
            case Kind::Box: return std::fabs(x) <= radius ? 1.0f : 0.0f;
            case Kind::Tent: return std::max(0.0f, 1.0f - std::fabs(x) / radius);
            case Kind::Gaussian: return std::max(0.0f, std::exp(gaussian_a * x * x) - gaussian_bias);
        }
        return 0.0f;
    }
    /// e.g. "gaussian(stddev=0.5)": part of a shard's settings.
    std::string describe() const {
        char buf[64];
        if (kind == Kind::Box) return "box";
        if (kind == Kind::Tent) std::snprintf(buf, sizeof buf, "tent(radius=%.9g)", double(radius));
        else std::snprintf(buf, sizeof buf, "gaussian(stddev=%.9g)", double(stddev));
        return buf;
    }
};

/// Unnormalised film: per pixel the filter-weighted radiance sums and the weight sum (double, so
/// that partial films of disjoint sample sets add up to the full film to rounding).
struct FilmSums {
    int width = 0, height = 0;
    std::vector<double> data;  // 4 per pixel: sum w R, sum w G, sum w B, sum w
    void resize(int w, int h) {
        width = w;
        height = h;
        data.assign(size_t(w) * size_t(h) * 4, 0.0);
    }
};

}  // namespace mf
