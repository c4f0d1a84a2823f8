// mfhost — partial renders and their merge (see shard.h).
#include "shard.h"

#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <map>
#include <sstream>

#include "error.h"

namespace mf {

namespace {
const char* kMagic = "mfrender-partial 1";
constexpr size_t kMaxHeaderBytes = 1 << 16;
}  // namespace

std::string ShardHeader::settings_key() const {
    std::ostringstream s;
    s << "content_hash=" << content_hash << " seed=" << seed << " spp=" << spp << " size=" << width << "x" << height
      << " max_depth=" << max_depth << " rr_depth=" << rr_depth << " integrator=" << integrator << " filter=" << filter
      << " shards=" << shard_count;
    return s.str();
}

ShardHeader shard_header(const Scene& scene, const std::string& scene_path, int index, int count) {
    ShardHeader h;
    h.scene = scene_path;
    h.content_hash = scene.content_hash;
    h.seed = scene.seed;
    h.spp = scene.spp;
    h.width = scene.camera.width;
    h.height = scene.camera.height;
    h.max_depth = scene.integrator.max_depth;
    h.rr_depth = scene.integrator.rr_depth;
    h.integrator = scene.integrator.volumetric ? "volpath" : "path";
    h.filter = scene.filter.describe();
    h.shard_index = index;
    h.shard_count = count;
    return h;
}

void write_shard(const std::string& path, const ShardHeader& h, const FilmSums& film) {
    std::ofstream out(path, std::ios::binary);
    if (!out) throw Error("cannot open " + quote(path, 200) + " for writing");
    std::string scene = h.scene;
    for (char& c : scene)
        if (c == '\n' || c == '\r') c = ' ';
    out << kMagic << "\n"
        << "scene " << scene << "\n"
        << "content_hash " << h.content_hash << "\n"
        << "seed " << h.seed << "\n"
        << "spp " << h.spp << "\n"
        << "width " << h.width << "\n"
        << "height " << h.height << "\n"
        << "max_depth " << h.max_depth << "\n"
        << "rr_depth " << h.rr_depth << "\n"
        << "integrator " << h.integrator << "\n"
        << "filter " << h.filter << "\n"
        << "shard " << h.shard_index << " " << h.shard_count << "\n"
        << "invalid_samples " << h.invalid_samples << "\n"
        << "data\n";
    static_assert(sizeof(double) == 8, "float64 film");
    out.write(reinterpret_cast<const char*>(film.data.data()), std::streamsize(film.data.size() * sizeof(double)));
    out.flush();
    if (!out) throw Error("cannot write " + quote(path, 200));
}

FilmSums read_shard(const std::string& path, ShardHeader* h) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw Error("cannot read partial render " + quote(path, 200));
    auto bad = [&](const std::string& why) { return Error(path + ": not a valid mfrender partial render: " + why); };
    std::string line;
    if (!std::getline(in, line) || line != kMagic) throw bad("missing the \"" + std::string(kMagic) + "\" line");
    size_t header_bytes = line.size();
    std::map<std::string, std::string> kv;
    while (true) {
        if (!std::getline(in, line)) throw bad("no \"data\" line");
        header_bytes += line.size() + 1;
        if (header_bytes > kMaxHeaderBytes) throw bad("header too long");
        if (line == "data") break;
        size_t sp = line.find(' ');
        if (sp == std::string::npos) throw bad("malformed header line " + quote(line));
        kv[line.substr(0, sp)] = line.substr(sp + 1);
    }
    auto need = [&](const char* k) -> const std::string& {
        auto it = kv.find(k);
        if (it == kv.end()) throw bad(std::string("no \"") + k + "\" entry");
        return it->second;
    };
    auto num = [&](const char* k, long long lo, long long hi) {
        const std::string& v = need(k);
        char* end = nullptr;
        long long x = std::strtoll(v.c_str(), &end, 10);
        if (v.empty() || *end || x < lo || x > hi) throw bad(std::string("bad \"") + k + "\" " + quote(v));
        return x;
    };
    h->scene = need("scene");
    {
        const std::string& v = need("content_hash");
        char* end = nullptr;
        h->content_hash = std::strtoull(v.c_str(), &end, 10);
        if (v.empty() || *end) throw bad("bad content_hash");
        const std::string& s = need("seed");
        h->seed = std::strtoull(s.c_str(), &end, 10);
        if (s.empty() || *end) throw bad("bad seed");
    }
    h->spp = int(num("spp", 1, 1 << 24));
    h->width = int(num("width", 1, 65536));
    h->height = int(num("height", 1, 65536));
    h->max_depth = int(num("max_depth", -1, 1 << 20));
    h->rr_depth = int(num("rr_depth", 0, 1 << 20));
    h->integrator = need("integrator");
    h->filter = need("filter");
    h->invalid_samples = uint64_t(num("invalid_samples", 0, (1LL << 62)));
    {
        std::istringstream s(need("shard"));
        if (!(s >> h->shard_index >> h->shard_count) || h->shard_count < 1 || h->shard_index < 0 ||
            h->shard_index >= h->shard_count)
            throw bad("bad \"shard\" entry");
    }
    FilmSums film;
    film.resize(h->width, h->height);
    in.read(reinterpret_cast<char*>(film.data.data()), std::streamsize(film.data.size() * sizeof(double)));
    if (size_t(in.gcount()) != film.data.size() * sizeof(double)) throw bad("data shorter than width x height x 4 doubles");
    if (in.peek() != std::char_traits<char>::eof()) throw bad("data longer than width x height x 4 doubles");
    for (size_t i = 0; i < film.data.size(); ++i)
        if (!std::isfinite(film.data[i]) || (i % 4 == 3 && film.data[i] < 0)) throw bad("non-finite or negative data");
    return film;
}

FilmSums merge_shards(const std::vector<std::string>& paths, ShardHeader* merged) {
    if (paths.empty()) throw Error("merge: no partial renders given");
    std::vector<ShardHeader> headers(paths.size());
    std::vector<FilmSums> films(paths.size());
    std::map<int, size_t> by_index;
    for (size_t i = 0; i < paths.size(); ++i) {
        films[i] = read_shard(paths[i], &headers[i]);
        if (i > 0 && headers[i].settings_key() != headers[0].settings_key())
            throw Error("merge: " + paths[i] + " does not belong with " + paths[0] + ": its settings differ (" +
                        headers[i].settings_key() + " vs " + headers[0].settings_key() + ")");
        auto ins = by_index.emplace(headers[i].shard_index, i);
        if (!ins.second)
            throw Error("merge: " + paths[i] + " and " + paths[ins.first->second] + " are both shard " +
                        std::to_string(headers[i].shard_index) + "/" + std::to_string(headers[i].shard_count));
    }
    int count = headers[0].shard_count;
    if (int(by_index.size()) != count) {
        std::string missing;
        for (int k = 0; k < count; ++k)
            if (!by_index.count(k)) missing += (missing.empty() ? "" : ", ") + std::to_string(k);
        throw Error("merge: shards " + missing + " of " + std::to_string(count) + " are missing");
    }
    FilmSums out;
    out.resize(headers[0].width, headers[0].height);
    *merged = headers[0];
    merged->shard_index = 0;
    merged->invalid_samples = 0;
    for (const auto& kv : by_index) {  // shard order: the result does not depend on the argument order
        const FilmSums& f = films[kv.second];
        for (size_t j = 0; j < out.data.size(); ++j) out.data[j] += f.data[j];
        merged->invalid_samples += headers[kv.second].invalid_samples;
    }
    return out;
}

}  // namespace mf
