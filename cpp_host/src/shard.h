// mfhost — partial renders ("shards") and their merge.
//
// `mfrender scene.xml --shard I/N -o part.mfpart` renders sample indices
// [spp*I/N, spp*(I+1)/N) of every pixel and writes the unnormalised film sums (double) with the
// settings that decide the image; `mfrender merge -o out.exr parts...` checks that the parts come
// from the same scene text, -D values, seed, spp, resolution, filter and depth and together are
// shards 0..N-1 exactly once, adds them in shard order and develops the image: the single run
// with the same seed, to rounding (the sums only associate differently).
//
// File format (little-endian): the line "mfrender-partial 1", then "key value" lines, then the
// line "data", then width*height*4 float64 (R, G, B, weight sums per pixel, rows top first).
#pragma once

#include <string>
#include <vector>

#include "film.h"
#include "scene.h"

namespace mf {

struct ShardHeader {
    std::string scene;         // scene file as given (informational)
    uint64_t content_hash = 0; // Scene::content_hash
    uint64_t seed = 0;
    int spp = 0;
    int width = 0, height = 0;
    int max_depth = -1;
    int rr_depth = 0;
    std::string integrator;    // volpath | path
    std::string filter;        // ReconstructionFilter::describe()
    int shard_index = 0, shard_count = 1;
    uint64_t invalid_samples = 0;
    /// The settings that must agree for shards to merge (everything but the shard index, the
    /// scene path and the invalid-sample count).
    std::string settings_key() const;
};

ShardHeader shard_header(const Scene& scene, const std::string& scene_path, int index, int count);
void write_shard(const std::string& path, const ShardHeader& header, const FilmSums& film);
/// Reads and validates one part (format, sizes, finite data); throws mf::Error naming the file.
FilmSums read_shard(const std::string& path, ShardHeader* header);
/// Merge parts into the full film; throws mf::Error when they do not belong together.
FilmSums merge_shards(const std::vector<std::string>& paths, ShardHeader* merged);

}  // namespace mf
