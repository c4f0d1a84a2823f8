// mfhost — Mitsuba .vol files (see volume_io.h), and the loading of the OpenVDB reader module
// (volume_vdb.cpp).
#include "volume_io.h"

#include <dlfcn.h>
#include <sys/stat.h>

#include <cctype>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <mutex>

#include "error.h"

namespace mf {

namespace {

constexpr size_t kVolHeaderBytes = 48;

uint32_t le_u32(const unsigned char* b) { return uint32_t(b[0]) | uint32_t(b[1]) << 8 | uint32_t(b[2]) << 16 | uint32_t(b[3]) << 24; }
int32_t le_i32(const unsigned char* b) {
    uint32_t u = le_u32(b);
    int32_t i;
    std::memcpy(&i, &u, 4);
    return i;
}
float le_f32(const unsigned char* b) {
    uint32_t u = le_u32(b);
    float f;
    std::memcpy(&f, &u, 4);
    return f;
}
void put_u32(std::string& s, uint32_t u) {
    for (int k = 0; k < 4; ++k) s.push_back(char((u >> (8 * k)) & 0xff));
}
void put_f32(std::string& s, float f) {
    uint32_t u;
    std::memcpy(&u, &f, 4);
    put_u32(s, u);
}

}  // namespace

bool is_regular_file(const std::string& path) {
    struct stat st;
    return ::stat(path.c_str(), &st) == 0 && S_ISREG(st.st_mode);
}

namespace {

// volume_vdb.cpp's entry point (its signature there).
using ReadVdbGrid = int (*)(const char* path, const char* grid_name, int centering, VolumeGridData* out,
                            std::string* error);

// The directory of the binary this code is linked into (mfrender, a test), with its slash.
std::string own_directory() {
    Dl_info info;
    if (dladdr(reinterpret_cast<void*>(&own_directory), &info) == 0 || info.dli_fname == nullptr) return std::string();
    const std::string path = info.dli_fname;
    const size_t slash = path.rfind('/');
    return slash == std::string::npos ? std::string() : path.substr(0, slash + 1);
}

// Loads the OpenVDB module once: next to the binary first (a copied or installed build), then
// where the build put it. Throws mf::Error with what dlopen said for each place tried.
ReadVdbGrid vdb_reader() {
    static ReadVdbGrid reader = nullptr;
    static std::string failure;
    static std::once_flag once;
    std::call_once(once, [] {
        std::string tried;
        for (const std::string& path : {own_directory() + MFHOST_VDB_MODULE_NAME, std::string(MFHOST_VDB_MODULE_PATH)}) {
            void* module = dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL);
            if (module == nullptr) {
                const char* why = dlerror();
                tried += (tried.empty() ? "" : "; ") + std::string(why ? why : path + ": not loadable");
                continue;
            }
            reader = reinterpret_cast<ReadVdbGrid>(dlsym(module, "mfhost_vdb_read_grid"));
            if (reader != nullptr) return;
            tried += (tried.empty() ? "" : "; ") + path + ": no entry point mfhost_vdb_read_grid";
        }
        failure = "mfrender's OpenVDB reader module " + std::string(MFHOST_VDB_MODULE_NAME) +
                  " could not be loaded (" + tried + "); rebuild mfrender (it builds the module beside itself)";
    });
    if (reader == nullptr) throw Error(failure);
    return reader;
}

}  // namespace

VolumeGridData read_vdb_grid(const std::string& path, const std::string& grid_name, GridCentering centering) {
    if (!is_regular_file(path)) throw Error("cannot read OpenVDB file " + quote(path, 200) + ": no such file");
    VolumeGridData grid;
    std::string error;
    if (!vdb_reader()(path.c_str(), grid_name.c_str(), centering == GridCentering::Node ? 1 : 0, &grid, &error)) throw Error(error);
    return grid;
}

bool is_vdb_path(const std::string& path) {
    if (path.size() < 4) return false;
    std::string ext = path.substr(path.size() - 4);
    for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
    return ext == ".vdb";
}

VolumeGridData read_vol_file(const std::string& path) {
    const std::string what = "volume file " + quote(path, 200);
    struct stat st;
    if (::stat(path.c_str(), &st) != 0 || !S_ISREG(st.st_mode)) throw Error("cannot read " + what + ": no such file");
    std::ifstream f(path, std::ios::binary);
    if (!f) throw Error("cannot open " + what);
    const size_t file_bytes = size_t(st.st_size);
    unsigned char h[kVolHeaderBytes];
    if (file_bytes < kVolHeaderBytes || !f.read(reinterpret_cast<char*>(h), kVolHeaderBytes))
        throw Error(what + " is truncated: " + std::to_string(file_bytes) + " bytes, shorter than the 48-byte header");
    if (h[0] != 'V' || h[1] != 'O' || h[2] != 'L') throw Error(what + " is not a Mitsuba volume (the file does not start with \"VOL\")");
    if (h[3] != 3) throw Error(what + " has version " + std::to_string(int(h[3])) + ": only version 3 is supported");
    int32_t encoding = le_i32(h + 4);
    if (encoding != 1)
        throw Error(what + " has encoding " + std::to_string(encoding) + ": only 1 (float32) is supported");
    VolumeGridData g;
    int32_t n[4] = {le_i32(h + 8), le_i32(h + 12), le_i32(h + 16), le_i32(h + 20)};
    if (n[0] <= 0 || n[1] <= 0 || n[2] <= 0)
        throw Error(what + " has a non-positive size " + std::to_string(n[0]) + "x" + std::to_string(n[1]) + "x" + std::to_string(n[2]));
    if (n[3] != 1 && n[3] != 3 && n[3] != 6)
        throw Error(what + " has " + std::to_string(n[3]) + " channels: supported are 1, 3 and 6 (as Mitsuba's gridvolume)");
    g.nx = n[0];
    g.ny = n[1];
    g.nz = n[2];
    g.channels = n[3];
    const double floats = double(g.nx) * double(g.ny) * double(g.nz) * double(g.channels);
    if (floats > double(kMaxGridFloats))
        throw Error(what + " has " + std::to_string(g.nx) + "x" + std::to_string(g.ny) + "x" + std::to_string(g.nz) + "x" +
                    std::to_string(g.channels) + " values, more than mfrender loads (" + std::to_string(kMaxGridFloats) + ")");
    const size_t count = size_t(floats);
    const size_t expected = kVolHeaderBytes + 4 * count;
    if (file_bytes != expected)
        throw Error(what + " has " + std::to_string(file_bytes) + " bytes, but its header (" + std::to_string(g.nx) + "x" +
                    std::to_string(g.ny) + "x" + std::to_string(g.nz) + " cells, " + std::to_string(g.channels) +
                    " channels) needs " + std::to_string(expected) + (file_bytes < expected ? ": the file is truncated" : ""));
    g.bbox.lo = Vec3(le_f32(h + 24), le_f32(h + 28), le_f32(h + 32));
    g.bbox.hi = Vec3(le_f32(h + 36), le_f32(h + 40), le_f32(h + 44));
    std::vector<unsigned char> raw(4 * count);
    if (!f.read(reinterpret_cast<char*>(raw.data()), std::streamsize(raw.size())))
        throw Error("cannot read the data of " + what);
    g.values.resize(count);
    for (size_t i = 0; i < count; ++i) g.values[i] = le_f32(raw.data() + 4 * i);
    return g;
}

void write_vol_file(const std::string& path, const VolumeGridData& g) {
    std::string s = "VOL";
    s.push_back(char(3));
    put_u32(s, 1);
    for (int v : {g.nx, g.ny, g.nz, g.channels}) put_u32(s, uint32_t(v));
    for (float v : {g.bbox.lo.x, g.bbox.lo.y, g.bbox.lo.z, g.bbox.hi.x, g.bbox.hi.y, g.bbox.hi.z}) put_f32(s, v);
    for (float v : g.values) put_f32(s, v);
    std::ofstream f(path, std::ios::binary);
    if (!f || !f.write(s.data(), std::streamsize(s.size()))) throw Error("cannot write volume file " + quote(path, 200));
}

}  // namespace mf
