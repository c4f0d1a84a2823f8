// Shared helpers of the end-to-end tests (test_render, test_macrofacet, test_gpis): files under
// MFHOST_TEST_WORK, mfrender run in-process, scene-string builders, image statistics and the
// white-furnace checks.
#pragma once

#include <sys/stat.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "check.h"
#include "cli.h"
#include "image_io.h"

inline std::string work(const std::string& name) { return std::string(MFHOST_TEST_WORK) + "/" + name; }

inline void write_file(const std::string& path, const std::string& content) {
    std::ofstream f(path, std::ios::binary);
    f << content;
}

inline std::string read_file(const std::string& path) {
    std::ifstream f(path, std::ios::binary);
    std::stringstream ss;
    ss << f.rdbuf();
    return ss.str();
}

inline bool exists(const std::string& p) {
    struct stat st;
    return ::stat(p.c_str(), &st) == 0;
}

/// mfrender_main with argv[0] = "mfrender".
inline int run(std::vector<std::string> args) {
    args.insert(args.begin(), "mfrender");
    std::vector<char*> argv;
    for (std::string& a : args) argv.push_back(a.data());
    return mf::mfrender_main(int(argv.size()), argv.data());
}

/// A perspective sensor at (0, 0, z) looking at the origin, box filter, independent sampler.
inline std::string camera(float z, float fov, int w, int h, int spp) {
    std::ostringstream s;
    s << "<sensor type=\"perspective\"><float name=\"fov\" value=\"" << fov << "\"/>"
      << "<transform name=\"to_world\"><lookat origin=\"0, 0, " << z << "\" target=\"0, 0, 0\" up=\"0, 1, 0\"/></transform>"
      << "<film type=\"hdrfilm\"><integer name=\"width\" value=\"" << w << "\"/><integer name=\"height\" value=\"" << h
      << "\"/><rfilter type=\"box\"/></film>"
      << "<sampler type=\"independent\"><integer name=\"sample_count\" value=\"" << spp << "\"/></sampler></sensor>";
    return s.str();
}

/// White-furnace scene: volpath with the given rr_depth, a w x w camera at z = 3, `object`, and a
/// constant environment of radiance 1.
inline std::string furnace_scene(const std::string& object, int spp, int rr_depth, float fov, int w = 24) {
    return "<scene version=\"3.0.0\"><integrator type=\"volpath\"><integer name=\"rr_depth\" value=\"" +
           std::to_string(rr_depth) + "\"/></integrator>" + camera(3.0f, fov, w, w, spp) + object +
           "<emitter type=\"constant\"><rgb name=\"radiance\" value=\"1\"/></emitter></scene>";
}

/// Writes work(name.xml), renders it to work(name.exr) (CHECKed exit status 0) and reads it back.
inline mf::Image render(const std::string& name, const std::string& xml, const std::string& seed = "5") {
    write_file(work(name + ".xml"), xml);
    CHECK(run({work(name + ".xml"), "-o", work(name + ".exr"), "--quiet", "--seed", seed}) == 0);
    return mf::read_exr(work(name + ".exr"));
}

/// Per-channel image mean and its standard error (from the per-pixel spread), and the largest
/// |pixel - expected| over all channels.
struct Stats {
    double mean[3] = {0, 0, 0}, se[3] = {0, 0, 0}, maxdev = 0;
};

inline Stats stats(const mf::Image& img, double expected) {
    Stats s;
    size_t n = size_t(img.width) * img.height;
    for (int c = 0; c < 3; ++c) {
        double sum = 0, sum2 = 0;
        for (size_t i = 0; i < n; ++i) {
            double v = img.rgb[3 * i + c];
            sum += v;
            sum2 += v * v;
            s.maxdev = std::max(s.maxdev, std::fabs(v - expected));
        }
        s.mean[c] = sum / n;
        double var = std::max(0.0, (sum2 - sum * sum / n) / (n - 1));
        s.se[c] = std::sqrt(var / n);
    }
    return s;
}

/// The white-furnace checks: each channel mean within 4.5 SE + mean_tol of `expected`, and no
/// pixel further than 10 per-pixel standard deviations (sd = se·sqrt(pixels)) + 1e-3 from it —
/// which catches unbounded weights (fireflies) that leave the mean test weak.
inline Stats check_furnace(const std::string& name, const mf::Image& img, double expected, double mean_tol) {
    Stats s = stats(img, expected);
    for (int c = 0; c < 3; ++c) {
        double tol = 4.5 * s.se[c] + mean_tol;
        CHECK_MSG(std::fabs(s.mean[c] - expected) < tol, name + ": channel " + std::to_string(c) + " mean " +
                                                      std::to_string(s.mean[c]) + " (tol " + std::to_string(tol) + ")");
    }
    double sd = 0;
    for (int c = 0; c < 3; ++c) sd = std::max(sd, s.se[c] * std::sqrt(double(img.width) * img.height));
    CHECK_MSG(s.maxdev < 10 * sd + 1e-3, name + ": max pixel deviation " + std::to_string(s.maxdev) + " vs sd " + std::to_string(sd));
    return s;
}
