// mfhost — mfrender command line.
#include "cli.h"

#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <new>
#include <string>

#include "image_io.h"
#include "render.h"
#include "scene_builder.h"
#include "xml_scene.h"

namespace mf {

namespace {

const char* kUsage =
    "usage: mfrender scene.xml [-o out.exr] [--spp N] [--seed S] [--threads N] [--max-depth N]\n"
    "                [-D name=value]... [--quiet] [--check] [--help]\n"
    "\n"
    "Renders a Mitsuba 3 XML scene (subset below) with a volumetric path tracer and writes a\n"
    "float RGB OpenEXR image plus an 8-bit sRGB PNG preview beside it (out.png).\n"
    "\n"
    "  -o FILE        output OpenEXR (default: the scene's name with .exr, beside the scene)\n"
    "  --spp N        samples per pixel (overrides the sampler's sample_count)\n"
    "  --seed S       random seed (default: the sampler's seed, else 0); output is bit-identical\n"
    "                 for a given seed, whatever --threads is\n"
    "  --threads N    worker threads (default: all cores)\n"
    "  --max-depth N  override the integrator's max_depth (-1 = unbounded)\n"
    "  -D name=value  define/override a <default> parameter used as $name in the scene\n"
    "  --quiet        no progress bar and no summary line\n"
    "  --check        parse and build the scene, print a summary, do not render\n"
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

}  // namespace

int mfrender_main(int argc, char** argv) {
    std::string scene_path, out_path;
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
            } else if (a == "--quiet" || a == "-q") {
                quiet = true;
            } else if (a == "--check") {
                check = true;
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

    try {
        if (out_path.empty()) out_path = replace_ext(scene_path, ".exr");
        std::string png_path = replace_ext(out_path, ".png");
        if (png_path == out_path) png_path = out_path + ".png";
        {
            struct stat st;
            std::string d = dir_of(out_path);
            if (::stat(d.c_str(), &st) != 0 || !S_ISDIR(st.st_mode))
                throw Error("output directory \"" + d + "\" does not exist");
        }
        // Every problem of the file is reported in one run: the reader's and the builder's.
        ErrorSink problems;
        ParsedScene parsed = parse_scene_file(scene_path, defines, &problems);
        bopts.allow_macrofacet_placeholders = false;  // --check validates macrofacet parameters too
        BuildReport report;
        std::unique_ptr<Scene> scene;
        if (parsed.root) scene = build_scene(parsed, bopts, &report, &problems);
        problems.raise();
        if (check) {
            SceneSummary s = scene->summary();
            std::printf("%s: OK: %zu shapes (%zu triangles), %zu emitters, %zu media, %dx%d, %d spp, %s\n",
                        scene_path.c_str(), s.shapes, s.triangles, s.emitters, s.media, scene->camera.width,
                        scene->camera.height, scene->spp, scene->integrator.volumetric ? "volpath" : "path");
            for (const auto& u : report.macrofacet) {
                std::printf("  %s medium <%s%s> on shape %s (%s) with %zu parameters:", u.role.c_str(), u.bag->type.c_str(),
                            u.bag->id.empty() ? "" : (" id=" + u.bag->id).c_str(),
                            u.shape->id.empty() ? u.shape->kind().c_str() : u.shape->id.c_str(), u.shape->loc.str().c_str(),
                            u.bag->params.size());
                for (const auto& kv : u.bag->params) std::printf(" %s", kv.first.c_str());
                std::printf("\n");
            }
            return 0;
        }
        ropts.progress = !quiet && ::isatty(STDERR_FILENO);
        RenderStats stats;
        Image img = render(*scene, ropts, &stats);

        TempFiles tmp;
        std::string pid = std::to_string(::getpid());
        std::string exr_tmp = out_path + ".partial-" + pid, png_tmp = png_path + ".partial-" + pid;
        tmp.paths = {exr_tmp, png_tmp};
        write_exr(exr_tmp, img);
        write_png_srgb(png_tmp, img);
        if (std::rename(exr_tmp.c_str(), out_path.c_str()) != 0)
            throw Error("cannot rename \"" + exr_tmp + "\" to \"" + out_path + "\": " + std::strerror(errno));
        if (std::rename(png_tmp.c_str(), png_path.c_str()) != 0) {
            std::string why = std::strerror(errno);
            std::remove(out_path.c_str());
            throw Error("cannot rename \"" + png_tmp + "\" to \"" + png_path + "\": " + why);
        }
        if (stats.invalid_samples > 0)
            std::fprintf(stderr, "mfrender: warning: %llu samples had non-finite radiance and were counted as 0\n",
                         (unsigned long long)stats.invalid_samples);
        if (!quiet)
            std::fprintf(stderr, "mfrender: %dx%d, %d spp in %.2f s (%.2f Msamples/s) -> %s, %s\n", img.width, img.height,
                         scene->spp, stats.seconds, stats.seconds > 0 ? double(stats.samples) / stats.seconds * 1e-6 : 0.0,
                         out_path.c_str(), png_path.c_str());
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

}  // namespace mf
