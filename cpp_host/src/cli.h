// mfhost — the mfrender command line (kept in the library so tests can drive it in-process).
#pragma once

#include <string>

#include "image_io.h"

namespace mf {
/// Writes out.exr and its 8-bit sRGB PNG preview (out.png) under temporary names, renamed only
/// when both succeeded; returns the PNG's path. (mfrender's outputs; mfcompare average's too.)
std::string write_image_outputs(const std::string& out_path, const Image& img);

/// Returns the process exit code: 0 success, 1 scene/render error, 2 usage error.
int mfrender_main(int argc, char** argv);
}
