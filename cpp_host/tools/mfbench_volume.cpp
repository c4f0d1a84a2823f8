// mfbench_volume — the cost of grid-volume queries on the tracking path (issue 12): evaluation at
// a point, and the conservative range over a short segment (one tracked step), a long segment and
// a box, for 1- and 6-channel grids. Prints nanoseconds per call (single thread, seeded inputs).
//
//   mfbench_volume [resolution=128] [calls=2000000]
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <vector>

#include "volume.h"

using namespace mf;

namespace {

double now() { return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count(); }

template <typename F>
double ns_per_call(int calls, F&& f) {
    double t0 = now();
    for (int i = 0; i < calls; ++i) f(i);
    return (now() - t0) * 1e9 / calls;
}

void bench(int res, int channels, int calls) {
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> u01(0.0f, 1.0f);
    std::vector<float> values(size_t(res) * res * res * channels);
    for (float& v : values) v = u01(rng);
    // a grid over [-1, 1]^3
    Mat4 to_world = Mat4::translate(-1, -1, -1) * Mat4::scale(2, 2, 2);
    auto vol = make_grid_volume(SampleGrid(std::move(values), res, res, res, channels), channels, to_world,
                                VolumeFilter::Trilinear, WrapMode::Clamp);
    const int n = 4096;  // inputs cycled through (kept in cache: the queries, not the RNG, are timed)
    std::vector<Vec3> p(n), d(n);
    for (int i = 0; i < n; ++i) {
        p[i] = Vec3(2 * u01(rng) - 1, 2 * u01(rng) - 1, 2 * u01(rng) - 1);
        d[i] = normalize(Vec3(u01(rng) - 0.5f, u01(rng) - 0.5f, u01(rng) - 0.5f));
    }
    const float cell = 2.0f / float(res);
    volatile float sink = 0;
    float out[8];
    double eval = ns_per_call(calls, [&](int i) {
        vol->eval(p[i & (n - 1)], out);
        sink = sink + out[0];
    });
    double seg_short = ns_per_call(calls, [&](int i) {
        ValueRange r = vol->range_segment(p[i & (n - 1)], d[i & (n - 1)], 2 * cell);
        sink = sink + r.hi[0];
    });
    double seg_mid = ns_per_call(calls / 4, [&](int i) {
        ValueRange r = vol->range_segment(p[i & (n - 1)], d[i & (n - 1)], 16 * cell);
        sink = sink + r.hi[0];
    });
    double seg_long = ns_per_call(calls / 16, [&](int i) {
        ValueRange r = vol->range_segment(p[i & (n - 1)], d[i & (n - 1)], 1.0f);
        sink = sink + r.hi[0];
    });
    double box = ns_per_call(calls / 4, [&](int i) {
        Vec3 c = p[i & (n - 1)];
        Aabb b;
        b.expand(c - Vec3(4 * cell));
        b.expand(c + Vec3(4 * cell));
        ValueRange r = vol->range_box(b);
        sink = sink + r.hi[0];
    });
    std::printf("grid %d^3 x %d channel%s: eval %.1f ns | range: segment of 2 cells %.1f ns, 16 cells %.1f ns, "
                "%d cells %.1f ns; box of 8 cells %.1f ns\n",
                res, channels, channels == 1 ? " " : "s", eval, seg_short, seg_mid, res / 2, seg_long, box);
}

}  // namespace

int main(int argc, char** argv) {
    int res = argc > 1 ? std::atoi(argv[1]) : 128;
    int calls = argc > 2 ? std::atoi(argv[2]) : 2000000;
    if (res < 2 || res > 512 || calls < 16) {
        std::fprintf(stderr, "usage: mfbench_volume [resolution 2..512] [calls >= 16]\n");
        return 2;
    }
    bench(res, 1, calls);
    bench(res, 6, calls);
    return 0;
}
