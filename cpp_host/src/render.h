// mfhost — multi-threaded tile renderer.
#pragma once

#include <cstdint>

#include "image_io.h"
#include "scene.h"

namespace mf {

struct RenderOptions {
    int threads = 0;        // 0 = hardware concurrency
    bool progress = false;  // draw a progress bar with ETA on stderr
};

struct RenderStats {
    double seconds = 0;
    uint64_t samples = 0;
    uint64_t invalid_samples = 0;  // NaN/inf radiance samples discarded (counted as 0)
};

/// Render the scene with a box pixel filter. Each pixel's samples are drawn from counter-based
/// samplers keyed by (scene.seed, pixel, sample) and summed in order, so the image is
/// bit-identical for a given seed whatever the number of threads.
Image render(const Scene& scene, const RenderOptions& opts, RenderStats* stats);

}  // namespace mf
