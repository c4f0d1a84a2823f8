// mfhost — tile renderer (see render.h).
#include "render.h"

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <exception>
#include <mutex>
#include <thread>

#include "integrator.h"

namespace mf {

namespace {

constexpr int kTile = 16;

void draw_progress(double frac, double elapsed, bool final) {
    const int width = 40;
    int filled = int(frac * width + 0.5);
    char bar[width + 1];
    for (int i = 0; i < width; ++i) bar[i] = i < filled ? '#' : '-';
    bar[width] = 0;
    double eta = frac > 0 ? elapsed * (1.0 - frac) / frac : 0.0;
    std::fprintf(stderr, "\rRendering [%s] %5.1f%%  elapsed %6.1fs  ETA %6.1fs%s", bar, frac * 100.0, elapsed,
                 final ? 0.0 : eta, final ? "\n" : "");
    std::fflush(stderr);
}

}  // namespace

Image render(const Scene& scene, const RenderOptions& opts, RenderStats* stats) {
    const Camera& cam = scene.camera;
    Image img;
    img.width = cam.width;
    img.height = cam.height;
    img.rgb.assign(size_t(img.width) * img.height * 3, 0.0f);
    const int tiles_x = (img.width + kTile - 1) / kTile, tiles_y = (img.height + kTile - 1) / kTile;
    const int n_tiles = tiles_x * tiles_y;
    int n_threads = opts.threads > 0 ? opts.threads : int(std::max(1u, std::thread::hardware_concurrency()));
    n_threads = std::max(1, std::min(n_threads, n_tiles));

    std::atomic<int> next_tile{0};
    std::atomic<int> done_tiles{0};
    std::atomic<uint64_t> invalid{0};
    std::mutex err_mutex;
    std::exception_ptr error;
    std::mutex done_mutex;
    std::condition_variable done_cv;
    PathIntegrator integrator(scene);
    const int spp = scene.spp;
    const Medium* cam_medium = scene.camera_medium.get();

    auto worker = [&]() {
        try {
            while (true) {
                int tile = next_tile.fetch_add(1);
                if (tile >= n_tiles) break;
                int tx = tile % tiles_x, ty = tile / tiles_x;
                uint64_t local_invalid = 0;
                for (int y = ty * kTile; y < std::min((ty + 1) * kTile, img.height); ++y)
                    for (int x = tx * kTile; x < std::min((tx + 1) * kTile, img.width); ++x) {
                        uint64_t pixel = uint64_t(y) * uint64_t(img.width) + uint64_t(x);
                        double acc[3] = {0, 0, 0};
                        for (int s = 0; s < spp; ++s) {
                            Sampler sampler(scene.seed, pixel, uint64_t(s));
                            Vec2 u = sampler.next_2d();
                            Ray ray = cam.generate_ray(float(x) + u.x, float(y) + u.y);
                            Rgb L = integrator.Li(ray, cam_medium, sampler);
                            if (!L.finite()) {
                                ++local_invalid;
                                continue;
                            }
                            acc[0] += L.r;
                            acc[1] += L.g;
                            acc[2] += L.b;
                        }
                        float* px = &img.rgb[3 * pixel];
                        for (int c = 0; c < 3; ++c) px[c] = float(acc[c] / double(spp));
                    }
                invalid += local_invalid;
                done_tiles.fetch_add(1);
                done_cv.notify_one();
            }
        } catch (...) {
            std::lock_guard<std::mutex> lock(err_mutex);
            if (!error) error = std::current_exception();
            next_tile.store(n_tiles);
            done_cv.notify_one();
        }
    };

    auto t0 = std::chrono::steady_clock::now();
    std::vector<std::thread> pool;
    for (int i = 0; i < n_threads; ++i) pool.emplace_back(worker);
    if (opts.progress) {
        std::unique_lock<std::mutex> lock(done_mutex);
        while (done_tiles.load() < n_tiles) {
            {
                std::lock_guard<std::mutex> el(err_mutex);
                if (error) break;
            }
            double el = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
            draw_progress(double(done_tiles.load()) / n_tiles, el, false);
            done_cv.wait_for(lock, std::chrono::milliseconds(250));
        }
    }
    for (std::thread& t : pool) t.join();
    double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (error) {
        if (opts.progress) std::fprintf(stderr, "\n");
        std::rethrow_exception(error);
    }
    if (opts.progress) draw_progress(1.0, secs, true);
    if (stats) {
        stats->seconds = secs;
        stats->samples = uint64_t(img.width) * img.height * uint64_t(spp);
        stats->invalid_samples = invalid.load();
    }
    return img;
}

}  // namespace mf
