// mfhost — mfrender command line.
#include "cli.h"

#include <algorithm>

#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <functional>
#include <new>
#include <string>

#include "image_io.h"
#include "field.h"
#include "medium_macrofacet.h"
#include "render.h"
#include "scene_builder.h"
#include "sdf_grid.h"
#include "shard.h"
#include "xml_scene.h"

namespace mf {

namespace {

const char* kUsage =
    "usage: mfrender scene.xml [-o out.exr] [--spp N] [--seed S] [--threads N] [--max-depth N]\n"
    "                [-D name=value]... [--shard I/N] [--media-boundaries] [--cast-exits]\n"
    "                [--no-opaque-cores] [--no-shadow-roulette]\n"
    "                [--quiet] [--check]\n"
    "                [--help]\n"
    "       mfrender merge -o out.exr part.mfpart...\n"
    "\n"
    "Renders a Mitsuba 3 XML scene (subset below) with a volumetric path tracer and writes a\n"
    "float RGB OpenEXR image plus an 8-bit sRGB PNG preview beside it (out.png).\n"
    "\n"
    "  -o FILE        output OpenEXR (default: the scene's name with .exr, beside the scene)\n"
    "  --spp N        samples per pixel (overrides the sampler's sample_count)\n"
    "  --seed S       random seed (default: the sampler's seed, else 0); output is bit-identical\n"
    "                 for a given seed, whatever --threads is\n"
    "  --threads N    worker threads for rendering and for building the media's surfaces\n"
    "                 and boundaries, a single large mesh's on all of them (default: all cores)\n"
    "  --max-depth N  override the integrator's max_depth (-1 = unbounded)\n"
    "  -D name=value  define/override a <default> parameter used as $name in the scene\n"
    "  --media-boundaries  trace the boundaries of macrofacet media in vacuum as surfaces of the\n"
    "                 BVH, as in scenes with other media (default: such media are tracked along\n"
    "                 every ray without them; the image is the same, to noise, and faster)\n"
    "  --cast-exits   cast a ray for every exit from a macrofacet medium's region (default: a\n"
    "                 medium whose boundary the library built and near which nothing else lies\n"
    "                 finds the exit while it tracks; the image is the same, to noise)\n"
    "  --no-opaque-cores  trace every shadow ray into a sphere's shell (default: a ray from\n"
    "                 outside its core that meets it ends there: its transmittance, below\n"
    "                 e^-750, rounds to 0; mf_track_opaque_core; a shallower one is kept with\n"
    "                 the probability its depth allows: mf_track_depth_roulette); the same\n"
    "                 image, to noise\n"
    "  --no-shadow-roulette  trace every next-event ray (default: one whose contribution g =\n"
    "                 f w / p_light, relative to the path's throughput and the emitter's\n"
    "                 radiance, is below 0.1 is traced with probability g / 0.1 and weighted by\n"
    "                 its inverse, before any transmittance: a Russian roulette); the same\n"
    "                 image, to noise\n"
    "  --quiet        no progress bar and no summary line\n"
    "  --check        parse and build the scene, print a summary, do not render; every problem\n"
    "                 of the file is listed (rendering lists them too)\n"
    "  --shard I/N    render only shard I of N (0 <= I < N): sample indices [spp*I/N, spp*(I+1)/N)\n"
    "                 of every pixel; writes the unnormalised film (default -o: scene.part-I-of-N.mfpart)\n"
    "  merge          add the parts 0..N-1 of one render (same scene text, -D values, seed, spp,\n"
    "                 size, filter, depth; anything else is refused) into the image the single run\n"
    "                 makes (to rounding): mfrender merge -o out.exr parts... (also writes out.png)\n"
    "  --help         this text\n"
    "\n"
    "Exit status: 0 on success, 1 on a scene or rendering error (one message naming the file\n"
    "and line), 2 on a usage error. Outputs are written under temporary names and renamed only\n"
    "once everything succeeded.\n"
    "\n";

struct UsageError {
    std::string msg;
};

long long parse_int_arg(const std::string& flag, const char* v, long long lo, long long hi) {
    if (!v) throw UsageError{flag + " needs a value"};
    char* end = nullptr;
    errno = 0;
    long long x = std::strtoll(v, &end, 10);
    if (!*v || *end || errno || x < lo || x > hi)
        throw UsageError{flag + ": invalid value \"" + std::string(v) + "\" (expected an integer in [" + std::to_string(lo) +
                         ", " + std::to_string(hi) + "])"};
    return x;
}

std::string replace_ext(const std::string& path, const std::string& ext) {
    size_t slash = path.find_last_of('/');
    size_t dot = path.find_last_of('.');
    if (dot != std::string::npos && (slash == std::string::npos || dot > slash)) return path.substr(0, dot) + ext;
    return path + ext;
}

std::string dir_of(const std::string& path) {
    size_t p = path.find_last_of('/');
    if (p == std::string::npos) return ".";
    return p == 0 ? "/" : path.substr(0, p);
}

struct TempFiles {
    std::vector<std::string> paths;
    ~TempFiles() {
        for (const std::string& p : paths) std::remove(p.c_str());
    }
};

void check_output_dir(const std::string& out_path) {
    struct stat st;
    std::string d = dir_of(out_path);
    if (::stat(d.c_str(), &st) != 0 || !S_ISDIR(st.st_mode)) throw Error("output directory \"" + d + "\" does not exist");
}

void rename_or_throw(const std::string& from, const std::string& to) {
    if (std::rename(from.c_str(), to.c_str()) != 0)
        throw Error("cannot rename \"" + from + "\" to \"" + to + "\": " + std::strerror(errno));
}

}  // namespace

std::string write_image_outputs(const std::string& out_path, const Image& img) {
    std::string png_path = replace_ext(out_path, ".png");
    if (png_path == out_path) png_path = out_path + ".png";
    TempFiles tmp;
    std::string pid = std::to_string(::getpid());
    std::string exr_tmp = out_path + ".partial-" + pid, png_tmp = png_path + ".partial-" + pid;
    tmp.paths = {exr_tmp, png_tmp};
    write_exr(exr_tmp, img);
    write_png_srgb(png_tmp, img);
    rename_or_throw(exr_tmp, out_path);
    try {
        rename_or_throw(png_tmp, png_path);
    } catch (...) {
        std::remove(out_path.c_str());
        throw;
    }
    return png_path;
}

namespace {

int report_failure(const std::function<void()>& body) {
    try {
        body();
        return 0;
    } catch (const ErrorList& list) {
        for (const Error& e : list.errors()) std::fprintf(stderr, "mfrender: error: %s\n", e.what());
        std::fprintf(stderr, "mfrender: %zu problems\n", list.errors().size());
    } catch (const Error& e) {
        std::fprintf(stderr, "mfrender: error: %s\n", e.what());
    } catch (const std::bad_alloc&) {
        std::fprintf(stderr, "mfrender: error: out of memory\n");
    } catch (const std::exception& e) {
        std::fprintf(stderr, "mfrender: error: %s\n", e.what());
    } catch (...) {
        std::fprintf(stderr, "mfrender: error: unknown failure\n");
    }
    return 1;
}

int merge_main(int argc, char** argv) {
    std::string out_path;
    std::vector<std::string> parts;
    for (int i = 2; i < argc; ++i) {
        std::string a = argv[i];
        if (a == "-o" || a == "--output") {
            if (i + 1 >= argc || !*argv[i + 1]) {
                std::fprintf(stderr, "mfrender: error: -o needs a file name\nrun 'mfrender --help' for usage\n");
                return 2;
            }
            out_path = argv[++i];
        } else if (!a.empty() && a[0] == '-') {
            std::fprintf(stderr, "mfrender: error: merge: unknown option \"%s\"\nrun 'mfrender --help' for usage\n", a.c_str());
            return 2;
        } else {
            parts.push_back(a);
        }
    }
    if (out_path.empty() || parts.empty()) {
        std::fprintf(stderr, "mfrender: error: merge needs -o out.exr and at least one part\nrun 'mfrender --help' for usage\n");
        return 2;
    }
    return report_failure([&] {
        check_output_dir(out_path);
        ShardHeader h;
        FilmSums film = merge_shards(parts, &h);
        std::string png = write_image_outputs(out_path, develop(film));
        if (h.invalid_samples > 0)
            std::fprintf(stderr, "mfrender: warning: %llu samples had non-finite radiance and were counted as 0\n",
                         (unsigned long long)h.invalid_samples);
        std::fprintf(stderr, "mfrender: merged %d shards (%dx%d, %d spp) -> %s, %s\n", h.shard_count, h.width, h.height,
                     h.spp, out_path.c_str(), png.c_str());
    });
}

}  // namespace

int mfrender_main(int argc, char** argv) {
    if (argc >= 2 && std::string(argv[1]) == "merge") return merge_main(argc, argv);
    std::string scene_path, out_path;
    int shard_index = -1, shard_count = 0;
    Defines defines;
    BuildOptions bopts;
    RenderOptions ropts;
    bool quiet = false, check = false;
    try {
        for (int i = 1; i < argc; ++i) {
            std::string a = argv[i];
            auto next = [&]() -> const char* { return i + 1 < argc ? argv[++i] : nullptr; };
            if (a == "--help" || a == "-h") {
                std::fputs(kUsage, stdout);
                std::fputs(supported_subset_text(), stdout);
                return 0;
            } else if (a == "-o" || a == "--output") {
                const char* v = next();
                if (!v || !*v) throw UsageError{"-o needs a file name"};
                out_path = v;
            } else if (a == "--spp") {
                bopts.spp_override = int(parse_int_arg(a, next(), 1, 1 << 24));
            } else if (a == "--seed") {
                bopts.seed_override = parse_int_arg(a, next(), 0, (1LL << 62));
            } else if (a == "--threads") {
                ropts.threads = int(parse_int_arg(a, next(), 1, 4096));
            } else if (a == "--max-depth") {
                bopts.max_depth_override = int(parse_int_arg(a, next(), -1, 1 << 20));
            } else if (a == "--media-boundaries") {
                bopts.superpose_macrofacet = false;
            } else if (a == "--cast-exits") {
                bopts.media_find_exits = false;
            } else if (a == "--no-opaque-cores") {
                bopts.opaque_cores = false;
            } else if (a == "--no-shadow-roulette") {
                bopts.shadow_roulette = false;
            } else if (a == "--quiet" || a == "-q") {
                quiet = true;
            } else if (a == "--check") {
                check = true;
            } else if (a == "--shard") {
                const char* v = next();
                int consumed = 0;
                if (!v || std::sscanf(v, "%d/%d%n", &shard_index, &shard_count, &consumed) != 2 || v[consumed] ||
                    shard_count < 1 || shard_count > (1 << 24) || shard_index < 0 || shard_index >= shard_count)
                    throw UsageError{"--shard expects I/N with 0 <= I < N, got \"" + std::string(v ? v : "") + "\""};
            } else if (a.rfind("-D", 0) == 0) {
                std::string def = a.size() > 2 ? a.substr(2) : std::string(next() ? argv[i] : "");
                size_t eq = def.find('=');
                if (def.empty() || eq == std::string::npos || eq == 0)
                    throw UsageError{"-D expects name=value, got \"" + def + "\""};
                std::string name = def.substr(0, eq);
                bool replaced = false;
                for (auto& kv : defines)
                    if (kv.first == name) {
                        kv.second = def.substr(eq + 1);
                        replaced = true;
                    }
                if (!replaced) defines.emplace_back(name, def.substr(eq + 1));
            } else if (!a.empty() && a[0] == '-') {
                throw UsageError{"unknown option \"" + a + "\""};
            } else {
                if (!scene_path.empty()) throw UsageError{"more than one scene file given"};
                scene_path = a;
            }
        }
        if (scene_path.empty()) throw UsageError{"no scene file given"};
    } catch (const UsageError& e) {
        std::fprintf(stderr, "mfrender: error: %s\n%s", e.msg.c_str(), "run 'mfrender --help' for usage\n");
        return 2;
    }

    return report_failure([&] {
        const bool sharded = shard_count > 0;
        if (out_path.empty())
            out_path = sharded ? replace_ext(scene_path, ".part-" + std::to_string(shard_index) + "-of-" +
                                                             std::to_string(shard_count) + ".mfpart")
                               : replace_ext(scene_path, ".exr");
        check_output_dir(out_path);
        // Every problem of the file is reported in one run: the reader's and the builder's.
        ErrorSink problems;
        ParsedScene parsed = parse_scene_file(scene_path, defines, &problems);
        for (const std::string& w : parsed.warnings) std::fprintf(stderr, "mfrender: warning: %s\n", w.c_str());
        bopts.allow_macrofacet_placeholders = false;  // --check validates macrofacet parameters too
        bopts.validate_only = check;
        bopts.threads = ropts.threads;  // spatially varying parameters: validated, not rendered yet
        BuildReport report;
        std::unique_ptr<Scene> scene;
        if (parsed.root) scene = build_scene(parsed, bopts, &report, &problems);
        problems.raise();
        for (const std::string& w : report.warnings) std::fprintf(stderr, "mfrender: warning: %s\n", w.c_str());
        if (check) {
            SceneSummary s = scene->summary();
            std::printf("%s: OK: %zu shapes (%zu triangles), %zu emitters, %zu media, %dx%d, %d spp, %s\n",
                        scene_path.c_str(), s.shapes, s.triangles, s.emitters, s.media, scene->camera.width,
                        scene->camera.height, scene->spp, scene->integrator.name.c_str());
            for (const auto& u : report.macrofacet) {
                std::printf("  %s medium <%s%s> on shape %s (%s) with %zu parameters:", u.role.c_str(), u.bag->type.c_str(),
                            u.bag->id.empty() ? "" : (" id=" + u.bag->id).c_str(),
                            u.shape->id.empty() ? u.shape->kind().c_str() : u.shape->id.c_str(), u.shape->loc.str().c_str(),
                            u.bag->params.size());
                for (const auto& kv : u.bag->params) std::printf(" %s", kv.first.c_str());
                std::printf("\n");
                if (u.bag->fields)
                    for (const auto& f : u.bag->fields->fields) {
                        ValueRange r = f->range();
                        std::printf("    parameter %s varies: %s (%s), %d channel%s, values in [%g, %g]%s\n", f->param().c_str(),
                                    f->element().c_str(), f->loc().str().c_str(), f->channels(), f->channels() == 1 ? "" : "s",
                                    *std::min_element(r.lo, r.lo + f->channels()), *std::max_element(r.hi, r.hi + f->channels()),
                                    f->param() == "anisotropy" ? " (entries)" : "");
                    }
                if (auto* sdf = dynamic_cast<const SdfGridShape*>(u.shape.get()))
                    std::printf("    sdfgrid mean surface: %dx%dx%d samples, distances in [%g, %g], gradient bound %.4g\n",
                                sdf->grid().nx, sdf->grid().ny, sdf->grid().nz, sdf->grid().value_min, sdf->grid().value_max,
                                sdf->grid().lipschitz);
            }
            for (const auto& m : scene->media) {
                auto* mm = dynamic_cast<const MacrofacetMedium*>(m.get());
                if (!mm) continue;
                if (mm->finds_exits())
                    std::printf("  %s: finds its rays' exits from the region itself (--cast-exits: a ray cast each)\n",
                                mm->label().c_str());
                double start, core;
                if (bopts.opaque_cores && mm->sphere_core(&start, &core))
                    std::printf("  %s: shadow rays from f >= %g end at its opaque core, f <= %g (--no-opaque-cores: tracked)\n",
                                mm->label().c_str(), start, core);
            }
            return;
        }
        ropts.progress = !quiet && ::isatty(STDERR_FILENO);
        if (sharded) {
            ropts.shard_index = shard_index;
            ropts.shard_count = shard_count;
        }
        RenderStats stats;
        FilmSums film = render_film(*scene, ropts, &stats);
        std::string written;
        if (sharded) {
            ShardHeader h = shard_header(*scene, scene_path, shard_index, shard_count);
            h.invalid_samples = stats.invalid_samples;
            TempFiles tmp;
            std::string part_tmp = out_path + ".partial-" + std::to_string(::getpid());
            tmp.paths = {part_tmp};
            write_shard(part_tmp, h, film);
            rename_or_throw(part_tmp, out_path);
            written = out_path;
        } else {
            written = out_path + ", " + write_image_outputs(out_path, develop(film));
        }
        if (stats.invalid_samples > 0)
            std::fprintf(stderr, "mfrender: warning: %llu samples had non-finite radiance and were counted as 0\n",
                         (unsigned long long)stats.invalid_samples);
        if (!quiet)
            std::fprintf(stderr, "mfrender: %dx%d, %d spp%s in %.2f s (%.2f Msamples/s) -> %s\n", scene->camera.width,
                         scene->camera.height, scene->spp,
                         sharded ? (" (shard " + std::to_string(shard_index) + "/" + std::to_string(shard_count) + ")").c_str() : "",
                         stats.seconds, stats.seconds > 0 ? double(stats.samples) / stats.seconds * 1e-6 : 0.0, written.c_str());
        if (!quiet) {
            for (const auto& medium : scene->media) {
                const auto* m = dynamic_cast<const MacrofacetMedium*>(medium.get());
                if (!m) continue;
                TrackCounts c = m->counts();
                if (c.calls == 0) continue;
                double n = double(c.calls);
                std::fprintf(stderr, "mfrender: %s: %llu tracking calls; per call %.2f surface queries, %.2f segments, %.2f tentative collisions\n",
                             m->label().c_str(), (unsigned long long)c.calls, c.surface_queries / n, c.segments / n, c.tentative_collisions / n);
            }
        }
    });
}

}  // namespace mf
