// mfcompare — tiny EXR statistics for scripts (comparison renders, benchmarks).
//
//   mfcompare stats A.exr            -> {"mean": [r, g, b], "mean_all": m, "min": x, "max": y, "nonfinite": n}
//   mfcompare mse A.exr B.exr        -> the mean squared error over all pixels and RGB channels
//   mfcompare relmse A.exr B.exr     -> sum (a-b)^2 / sum b^2  (relative MSE)
//   mfcompare maxreldiff A.exr B.exr -> max |a-b| / max(|a|, |b|) over all values (0 where both are 0)
// Images must have the same size. Exit 0 / 1 (I/O or size error) / 2 (usage).
#include <cmath>
#include <cstdio>
#include <exception>
#include <string>

#include "image_io.h"

int main(int argc, char** argv) {
    if (argc < 3) {
        std::fprintf(stderr, "usage: mfcompare stats A.exr | mse|relmse|maxreldiff A.exr B.exr\n");
        return 2;
    }
    const std::string mode = argv[1];
    try {
        mf::Image a = mf::read_exr(argv[2]);
        const size_t n = a.rgb.size();
        if (mode == "stats") {
            double s[3] = {0, 0, 0}, lo = INFINITY, hi = -INFINITY;
            size_t bad = 0;
            for (size_t i = 0; i < n; ++i) {
                double v = a.rgb[i];
                if (!std::isfinite(v)) { ++bad; continue; }
                s[i % 3] += v;
                lo = std::fmin(lo, v);
                hi = std::fmax(hi, v);
            }
            double np = double(n / 3);
            std::printf("{\"mean\": [%.8g, %.8g, %.8g], \"mean_all\": %.8g, \"min\": %.8g, \"max\": %.8g, \"nonfinite\": %zu}\n",
                        s[0] / np, s[1] / np, s[2] / np, (s[0] + s[1] + s[2]) / (3 * np), lo, hi, bad);
            return 0;
        }
        if ((mode == "mse" || mode == "relmse" || mode == "maxreldiff") && argc == 4) {
            mf::Image b = mf::read_exr(argv[3]);
            if (a.width != b.width || a.height != b.height) {
                std::fprintf(stderr, "mfcompare: size mismatch %dx%d vs %dx%d\n", a.width, a.height, b.width, b.height);
                return 1;
            }
            double se = 0, sb = 0, maxrel = 0;
            for (size_t i = 0; i < n; ++i) {
                double m = std::fmax(std::fabs(double(a.rgb[i])), std::fabs(double(b.rgb[i])));
                if (m > 0) maxrel = std::fmax(maxrel, std::fabs(double(a.rgb[i]) - double(b.rgb[i])) / m);
                double d = double(a.rgb[i]) - double(b.rgb[i]);
                se += d * d;
                sb += double(b.rgb[i]) * double(b.rgb[i]);
            }
            if (mode == "maxreldiff") std::printf("%.10g\n", maxrel);
            else std::printf("%.10g\n", mode == "mse" ? se / double(n) : se / std::fmax(sb, 1e-300));
            return 0;
        }
        std::fprintf(stderr, "mfcompare: unknown mode or wrong arguments\n");
        return 2;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "mfcompare: %s\n", e.what());
        return 1;
    }
}
