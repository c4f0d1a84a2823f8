// libFuzzer target for mfrender's scene reader: parse any byte string as a scene file and build
// it (macrofacet media as placeholders, nothing rendered). The property: every input ends in a
// scene or in mf::Error(s) — no crash, no sanitizer report, no other exception, bounded time and
// memory (the reader's XmlLimits). Relative file names resolve in an empty temporary folder.
// Run by scripts/fuzz_scene.sh.
#include <unistd.h>

#include <cstdint>
#include <cstdlib>
#include <string>

#include "error.h"
#include "scene_builder.h"
#include "xml_scene.h"

namespace {

const std::string& scene_dir() {
    static const std::string dir = [] {
        char tmpl[] = "/tmp/mffuzz.XXXXXX";
        const char* d = ::mkdtemp(tmpl);
        return std::string(d ? d : "/tmp");
    }();
    return dir;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    const std::string xml(reinterpret_cast<const char*>(data), size);
    mf::ErrorSink problems;
    try {
        mf::ParsedScene parsed = mf::parse_scene_string(xml, scene_dir() + "/fuzz.xml", {{"fuzz", "0.5"}}, &problems);
        if (parsed.root) {
            mf::BuildOptions opts;
            opts.allow_macrofacet_placeholders = true;
            mf::build_scene(parsed, opts, nullptr, &problems);
        }
    } catch (const mf::Error&) {
        // a refusal: fine
    }
    return 0;
}
