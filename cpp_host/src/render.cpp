// mfhost — tile renderer (see render.h).
#include "render.h"

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <exception>
#include <map>
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

FilmSums render_film(const Scene& scene, const RenderOptions& opts, RenderStats* stats) {
    const Camera& cam = scene.camera;
    const ReconstructionFilter& filter = scene.filter;
    FilmSums film;
    film.resize(cam.width, cam.height);
    const int tiles_x = (cam.width + kTile - 1) / kTile, tiles_y = (cam.height + kTile - 1) / kTile;
    const int n_tiles = tiles_x * tiles_y;
    int n_threads = opts.threads > 0 ? opts.threads : int(std::max(1u, std::thread::hardware_concurrency()));
    n_threads = std::max(1, std::min(n_threads, n_tiles));
    const int count = std::max(1, opts.shard_count), index = std::clamp(opts.shard_index, 0, count - 1);
    const uint64_t s_begin = uint64_t(scene.spp) * uint64_t(index) / uint64_t(count);
    const uint64_t s_end = uint64_t(scene.spp) * uint64_t(index + 1) / uint64_t(count);
    // a sample in pixel x lands within [x, x + 1): its filter reaches `margin` pixels beyond
    const bool box = filter.kind == ReconstructionFilter::Kind::Box;
    const int margin = box ? 0 : int(std::ceil(filter.radius));
    const int span = kTile + 2 * margin;

    std::atomic<int> next_tile{0};
    std::atomic<int> done_tiles{0};
    std::atomic<uint64_t> invalid{0};
    std::mutex err_mutex;
    std::exception_ptr error;
    std::mutex done_mutex;
    std::condition_variable done_cv;
    // Tiles overlap through the filter margin, so they are added to the film in tile order
    // (the floating-point sums then do not depend on scheduling): finished tiles wait here.
    std::mutex commit_mutex;
    std::map<int, std::vector<double>> finished;
    int next_commit = 0;
    auto commit = [&](int tile, std::vector<double>&& buf) {
        std::lock_guard<std::mutex> lock(commit_mutex);
        finished.emplace(tile, std::move(buf));
        for (auto it = finished.find(next_commit); it != finished.end(); it = finished.find(next_commit)) {
            int t = it->first, x0 = (t % tiles_x) * kTile - margin, y0 = (t / tiles_x) * kTile - margin;
            const std::vector<double>& b = it->second;
            for (int ly = 0; ly < span; ++ly) {
                int y = y0 + ly;
                if (y < 0 || y >= cam.height) continue;
                for (int lx = 0; lx < span; ++lx) {
                    int x = x0 + lx;
                    if (x < 0 || x >= cam.width) continue;
                    const double* src = &b[4 * (size_t(ly) * span + lx)];
                    double* dst = &film.data[4 * (size_t(y) * cam.width + x)];
                    for (int c = 0; c < 4; ++c) dst[c] += src[c];
                }
            }
            finished.erase(it);
            ++next_commit;
        }
    };

    PathIntegrator integrator(scene);
    const Medium* cam_medium = scene.camera_medium.get();

    auto worker = [&]() {
        try {
            std::vector<float> wx(size_t(2 * margin + 2)), wy(size_t(2 * margin + 2));
            while (true) {
                int tile = next_tile.fetch_add(1);
                if (tile >= n_tiles) break;
                int tx = tile % tiles_x, ty = tile / tiles_x;
                int x0 = tx * kTile - margin, y0 = ty * kTile - margin;
                std::vector<double> buf(size_t(span) * span * 4, 0.0);
                uint64_t local_invalid = 0;
                for (int y = ty * kTile; y < std::min((ty + 1) * kTile, cam.height); ++y)
                    for (int x = tx * kTile; x < std::min((tx + 1) * kTile, cam.width); ++x) {
                        uint64_t pixel = uint64_t(y) * uint64_t(cam.width) + uint64_t(x);
                        for (uint64_t s = s_begin; s < s_end; ++s) {
                            Sampler sampler(scene.seed, pixel, s);
                            Vec2 u = sampler.next_2d();
                            Ray ray = cam.generate_ray(float(x) + u.x, float(y) + u.y);
                            Rgb L = integrator.Li(ray, cam_medium, sampler);
                            if (!L.finite()) {
                                ++local_invalid;
                                L = Rgb(0.0f);
                            }
                            if (box) {
                                double* px = &buf[4 * (size_t(y - y0) * span + (x - x0))];
                                px[0] += L.r; px[1] += L.g; px[2] += L.b; px[3] += 1.0;
                                continue;
                            }
                            // pixels j with centre j + 0.5 within the radius of the sample
                            float sx = float(x) + u.x, sy = float(y) + u.y;
                            int jx0 = x - margin, jy0 = y - margin;
                            for (int k = 0; k < 2 * margin + 1; ++k) {
                                wx[size_t(k)] = filter.eval(float(jx0 + k) + 0.5f - sx);
                                wy[size_t(k)] = filter.eval(float(jy0 + k) + 0.5f - sy);
                            }
                            for (int ky = 0; ky < 2 * margin + 1; ++ky) {
                                if (wy[size_t(ky)] == 0) continue;
                                for (int kx = 0; kx < 2 * margin + 1; ++kx) {
                                    double w = double(wx[size_t(kx)]) * double(wy[size_t(ky)]);
                                    if (w == 0) continue;
                                    double* px = &buf[4 * (size_t(jy0 + ky - y0) * span + (jx0 + kx - x0))];
                                    px[0] += w * L.r; px[1] += w * L.g; px[2] += w * L.b; px[3] += w;
                                }
                            }
                        }
                    }
                invalid += local_invalid;
                commit(tile, std::move(buf));
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
        stats->samples = uint64_t(cam.width) * cam.height * (s_end - s_begin);
        stats->invalid_samples = invalid.load();
    }
    return film;
}

Image develop(const FilmSums& film) {
    Image img;
    img.width = film.width;
    img.height = film.height;
    img.rgb.assign(size_t(img.width) * img.height * 3, 0.0f);
    for (size_t i = 0; i < size_t(img.width) * img.height; ++i) {
        const double* p = &film.data[4 * i];
        if (p[3] > 0)
            for (int c = 0; c < 3; ++c) img.rgb[3 * i + size_t(c)] = float(p[c] / p[3]);
    }
    return img;
}

Image render(const Scene& scene, const RenderOptions& opts, RenderStats* stats) {
    return develop(render_film(scene, opts, stats));
}

}  // namespace mf
