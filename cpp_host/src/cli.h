// mfhost — the mfrender command line (kept in the library so tests can drive it in-process).
#pragma once

namespace mf {
/// Returns the process exit code: 0 success, 1 scene/render error, 2 usage error.
int mfrender_main(int argc, char** argv);
}
