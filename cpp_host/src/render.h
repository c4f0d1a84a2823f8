// mfhost — multi-threaded tile renderer with Mitsuba's film reconstruction, and sample shards.
#pragma once

#include <cstdint>

#include "film.h"
#include "image_io.h"
#include "scene.h"

namespace mf {

struct RenderOptions {
    int threads = 0;        // 0 = hardware concurrency
    bool progress = false;  // draw a progress bar with ETA on stderr
    /// Render only this shard's share of every pixel's samples: sample indices
    /// [spp * index / count, spp * (index + 1) / count). Shards are disjoint and together make up
    /// exactly the samples of a single run, so their film sums add up to its film.
    int shard_index = 0, shard_count = 1;
};

struct RenderStats {
    double seconds = 0;
    uint64_t samples = 0;
    uint64_t invalid_samples = 0;  // NaN/inf radiance samples discarded (counted as 0)
};

/// Render this shard's samples into unnormalised film sums. Each sample is drawn from a
/// counter-based sampler keyed by (scene.seed, pixel, sample index) and splatted with the
/// scene's reconstruction filter; tiles are added to the film in a fixed order, so the result is
/// bit-identical for a given seed whatever the number of threads.
FilmSums render_film(const Scene& scene, const RenderOptions& opts, RenderStats* stats);
/// Normalise film sums into an image (sum w L / sum w; 0 where no sample landed).
Image develop(const FilmSums& film);
/// render_film + develop.
Image render(const Scene& scene, const RenderOptions& opts, RenderStats* stats);

}  // namespace mf
