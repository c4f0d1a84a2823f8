// mfcompare — tiny EXR statistics for scripts (comparison renders, benchmarks).
//
//   mfcompare stats A.exr            -> {"mean": [r, g, b], "mean_all": m, "min": x, "max": y, "nonfinite": n}
//   mfcompare mse A.exr B.exr        -> the mean squared error over all pixels and RGB channels
//   mfcompare relmse A.exr B.exr     -> sum (a-b)^2 / sum b^2  (relative MSE)
//   mfcompare maxreldiff A.exr B.exr -> max |a-b| / max(|a|, |b|) over all values (0 where both are 0)
//   mfcompare average OUT.exr A.exr B.exr...
//       writes the value-wise mean of independent renders of one image at equal spp (with a box
//       filter: a render with all their samples), and its 8-bit sRGB PNG preview beside it
//       (OUT with .png for .exr), as mfrender does
//   mfcompare patches NX NY A.exr B.exr
//       per patch of an NX x NY partition of the image (patch (r, c): rows [r H/NY, (r+1) H/NY),
//       columns [c W/NX, (c+1) W/NX); lines in row-major order, top row first, after a header):
//       row col mse mean_a mean_b  (mse over the patch's pixels and RGB channels, means of all values)
//   mfcompare patches NX NY A1.exr A2.exr B1.exr B2.exr
//       A1, A2 are two independent halves of one estimate A = (A1 + A2) / 2 (same spp, other seed),
//       likewise B. Per patch also:
//         noise_a  the mean variance of A's values, E[(A1 - A2)^2] / 4 (its own noise: the MSE of A
//                  against its expectation), noise_b likewise;
//         bias2    mean over the patch of (A - B)^2 - (A1 - A2)^2/4 - (B1 - B2)^2/4, an unbiased
//                  estimate of the mean squared difference of the expectations (what mse would be
//                  without noise), and bias2_se its standard error over the patch's pixels;
//         rel_diff (mean_a - mean_b) / mean_b, and z that difference over its standard error (from
//                  the halves' differences of the pixels' RGB means).
// Images must have the same size. Exit 0 / 1 (I/O or size error) / 2 (usage).
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <string>
#include <vector>

#include "cli.h"
#include "image_io.h"

namespace {

bool same_size(const mf::Image& a, const mf::Image& b) {
    if (a.width == b.width && a.height == b.height) return true;
    std::fprintf(stderr, "mfcompare: size mismatch %dx%d vs %dx%d\n", a.width, a.height, b.width, b.height);
    return false;
}

/// Parses a patch count in [1, 1024]; false (with a message) otherwise.
bool parse_count(const char* s, int* out) {
    char* end = nullptr;
    long v = std::strtol(s, &end, 10);
    if (end == s || *end != '\0' || v < 1 || v > 1024) {
        std::fprintf(stderr, "mfcompare: patch count \"%s\" must be an integer in [1, 1024]\n", s);
        return false;
    }
    *out = int(v);
    return true;
}

/// The value-wise mean of two images of one size.
mf::Image mean_of(const mf::Image& a, const mf::Image& b) {
    mf::Image m = a;
    for (size_t i = 0; i < m.rgb.size(); ++i) m.rgb[i] = 0.5f * (a.rgb[i] + b.rgb[i]);
    return m;
}

/// `patches` for the images `a`, `b` and, when `halves` holds A1, A2, B1, B2, the noise and
/// bias columns. Returns the exit status.
int patches(int nx, int ny, const mf::Image& a, const mf::Image& b, const std::vector<mf::Image>& halves) {
    if (nx > a.width || ny > a.height) {
        std::fprintf(stderr, "mfcompare: %dx%d patches do not fit a %dx%d image\n", nx, ny, a.width, a.height);
        return 1;
    }
    const bool with_halves = halves.size() == 4;
    std::printf(with_halves ? "row\tcol\tmse\tmean_a\tmean_b\tnoise_a\tnoise_b\tbias2\tbias2_se\trel_diff\tz\n"
                            : "row\tcol\tmse\tmean_a\tmean_b\n");
    for (int r = 0; r < ny; ++r)
        for (int c = 0; c < nx; ++c) {
            const int y0 = r * a.height / ny, y1 = (r + 1) * a.height / ny;
            const int x0 = c * a.width / nx, x1 = (c + 1) * a.width / nx;
            double se = 0, sa = 0, sb = 0, na = 0, nb = 0;
            double su = 0, suu = 0;     // per-pixel bias2 terms (RGB mean) and their squares
            double sd = 0, svar = 0;    // per-pixel differences of RGB means and their variances
            for (int y = y0; y < y1; ++y)
                for (int x = x0; x < x1; ++x) {
                    double u = 0, d = 0, da = 0, db = 0;
                    for (int k = 0; k < 3; ++k) {
                        const size_t i = (size_t(y) * size_t(a.width) + size_t(x)) * 3 + size_t(k);
                        const double e = double(a.rgb[i]) - double(b.rgb[i]);
                        se += e * e;
                        sa += a.rgb[i];
                        sb += b.rgb[i];
                        d += e / 3;
                        if (with_halves) {
                            const double ea = double(halves[0].rgb[i]) - double(halves[1].rgb[i]);
                            const double eb = double(halves[2].rgb[i]) - double(halves[3].rgb[i]);
                            na += ea * ea / 4;
                            nb += eb * eb / 4;
                            u += (e * e - ea * ea / 4 - eb * eb / 4) / 3;
                            da += ea / 3;
                            db += eb / 3;
                        }
                    }
                    su += u;
                    suu += u * u;
                    sd += d;
                    svar += da * da / 4 + db * db / 4;
                }
            const double pixels = double(y1 - y0) * double(x1 - x0), values = 3 * pixels;
            std::printf("%d\t%d\t%.6g\t%.6g\t%.6g", r, c, se / values, sa / values, sb / values);
            if (with_halves) {
                const double bias2 = su / pixels;
                const double var_u = pixels > 1 ? std::fmax(suu / pixels - bias2 * bias2, 0.0) * pixels / (pixels - 1) : 0;
                const double rel = sb != 0 ? (sa - sb) / sb : 0;
                const double z = svar > 0 ? sd / std::sqrt(svar) : 0;
                std::printf("\t%.6g\t%.6g\t%.6g\t%.6g\t%.6g\t%.4g", na / values, nb / values, bias2, std::sqrt(var_u / pixels), rel, z);
            }
            std::printf("\n");
        }
    return 0;
}

}  // namespace

int main(int argc, char** argv) {
    if (argc < 3) {
        std::fprintf(stderr,
                     "usage: mfcompare stats A.exr | mse|relmse|maxreldiff A.exr B.exr | average OUT.exr A.exr B.exr...\n"
                     "       | patches NX NY A.exr B.exr | patches NX NY A1.exr A2.exr B1.exr B2.exr\n");
        return 2;
    }
    const std::string mode = argv[1];
    try {
        if (mode == "average") {
            if (argc < 5) {
                std::fprintf(stderr, "mfcompare: average needs OUT.exr and at least two inputs\n");
                return 2;
            }
            mf::Image sum = mf::read_exr(argv[3]);
            std::vector<double> acc(sum.rgb.begin(), sum.rgb.end());
            for (int k = 4; k < argc; ++k) {
                mf::Image next = mf::read_exr(argv[k]);
                if (!same_size(sum, next)) return 1;
                for (size_t i = 0; i < acc.size(); ++i) acc[i] += next.rgb[i];
            }
            for (size_t i = 0; i < acc.size(); ++i) sum.rgb[i] = float(acc[i] / double(argc - 3));
            mf::write_image_outputs(argv[2], sum);
            return 0;
        }
        if (mode == "patches") {
            int nx = 0, ny = 0;
            if (argc != 6 && argc != 8) {
                std::fprintf(stderr, "mfcompare: patches takes NX NY and two images (A B) or four halves (A1 A2 B1 B2)\n");
                return 2;
            }
            if (!parse_count(argv[2], &nx) || !parse_count(argv[3], &ny)) return 2;
            std::vector<mf::Image> in;
            for (int k = 4; k < argc; ++k) {
                in.push_back(mf::read_exr(argv[k]));
                if (!same_size(in.front(), in.back())) return 1;
            }
            if (in.size() == 2) return patches(nx, ny, in[0], in[1], {});
            return patches(nx, ny, mean_of(in[0], in[1]), mean_of(in[2], in[3]), in);
        }
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
            if (!same_size(a, b)) return 1;
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
