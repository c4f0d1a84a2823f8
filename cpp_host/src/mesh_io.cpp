// mfhost — OBJ / PLY readers and mesh utilities.
#include "mesh_io.h"

#include <zlib.h>
#include <iterator>

#include <cstdlib>
#include <cstring>
#include <fstream>
#include <map>
#include <sstream>
#include <tuple>
#include <unordered_map>

#include "error.h"

namespace mf {

void TriMesh::transform(const Mat4& m) {
    if (m.is_identity()) return;
    for (Vec3& q : p) q = m.point(q);
    if (!n.empty()) {
        Mat4 inv = m.inverse();
        for (Vec3& q : n) {
            Vec3 r(float(inv.m[0][0] * q.x + inv.m[1][0] * q.y + inv.m[2][0] * q.z),
                   float(inv.m[0][1] * q.x + inv.m[1][1] * q.y + inv.m[2][1] * q.z),
                   float(inv.m[0][2] * q.x + inv.m[1][2] * q.y + inv.m[2][2] * q.z));
            q = normalize(r);
        }
    }
    // A mirroring transform would turn the winding inside out; Mitsuba keeps the geometric
    // normal consistent with the transformed shading normals, so reverse the winding.
    if (m.det3() < 0)
        for (size_t t = 0; t + 2 < idx.size(); t += 3) std::swap(idx[t + 1], idx[t + 2]);
}

void TriMesh::compute_vertex_normals() {
    n.assign(p.size(), Vec3(0.0f));
    for (size_t t = 0; t < num_triangles(); ++t) {
        uint32_t i[3] = {idx[3 * t], idx[3 * t + 1], idx[3 * t + 2]};
        Vec3 fn = cross(p[i[1]] - p[i[0]], p[i[2]] - p[i[0]]);
        float l = length(fn);
        if (!(l > 0)) continue;
        fn = fn / l;
        for (int k = 0; k < 3; ++k) {
            Vec3 a = normalize(p[i[(k + 1) % 3]] - p[i[k]]);
            Vec3 b = normalize(p[i[(k + 2) % 3]] - p[i[k]]);
            float angle = std::acos(std::clamp(dot(a, b), -1.0f, 1.0f));
            n[i[k]] += fn * angle;
        }
    }
    for (Vec3& q : n) {
        float l = length(q);
        q = l > 0 ? q / l : Vec3(0, 0, 1);
    }
}

void TriMesh::make_face_normals() {
    std::vector<Vec3> np;
    std::vector<Vec2> nuv;
    std::vector<uint32_t> nidx;
    np.reserve(idx.size());
    for (size_t k = 0; k < idx.size(); ++k) {
        np.push_back(p[idx[k]]);
        if (!uv.empty()) nuv.push_back(uv[idx[k]]);
        nidx.push_back(uint32_t(k));
    }
    for (Attribute& a : attributes) {  // vertex attributes follow their split vertices
        if (a.per_face) continue;
        std::vector<Rgb> nv;
        nv.reserve(idx.size());
        for (uint32_t i : idx) nv.push_back(a.values[i]);
        a.values.swap(nv);
    }
    p.swap(np);
    uv.swap(nuv);
    idx.swap(nidx);
    n.clear();
}

void TriMesh::flip_normals() {
    for (size_t t = 0; t + 2 < idx.size(); t += 3) std::swap(idx[t + 1], idx[t + 2]);
    for (Vec3& q : n) q = -q;
}

// ----------------------------------------------------------------------------------------------
// OBJ

namespace {

[[noreturn]] void file_error(const std::string& path, int line, const std::string& msg) {
    throw Error(SourceLoc{path, line}, msg);
}

bool parse_float_tok(const char*& s, float* out) {
    while (*s == ' ' || *s == '\t') ++s;
    char* end = nullptr;
    double v = std::strtod(s, &end);
    if (end == s) return false;
    s = end;
    *out = float(v);
    return std::isfinite(*out);
}

}  // namespace

TriMesh load_obj(const std::string& path) {
    std::ifstream in(path);
    if (!in) throw Error("cannot open OBJ file \"" + path + "\"");
    std::vector<Vec3> vp, vn;
    std::vector<Vec2> vt;
    struct Key {
        int v, t, n;
        bool operator==(const Key& o) const { return v == o.v && t == o.t && n == o.n; }
    };
    struct KeyHash {
        size_t operator()(const Key& k) const {
            return (size_t(k.v) * 73856093u) ^ (size_t(k.t + 1) * 19349663u) ^ (size_t(k.n + 1) * 83492791u);
        }
    };
    std::unordered_map<Key, uint32_t, KeyHash> vmap;
    std::vector<Key> verts;
    std::vector<uint32_t> idx;
    bool any_t = false, any_n = false, all_t = true, all_n = true;
    std::string line;
    int lineno = 0;
    while (std::getline(in, line)) {
        ++lineno;
        if (!line.empty() && line.back() == '\r') line.pop_back();
        const char* s = line.c_str();
        while (*s == ' ' || *s == '\t') ++s;
        if (*s == '#' || *s == 0) continue;
        if (s[0] == 'v' && (s[1] == ' ' || s[1] == '\t')) {
            s += 1;
            Vec3 q;
            if (!parse_float_tok(s, &q.x) || !parse_float_tok(s, &q.y) || !parse_float_tok(s, &q.z))
                file_error(path, lineno, "malformed vertex position");
            vp.push_back(q);
        } else if (s[0] == 'v' && s[1] == 'n' && (s[2] == ' ' || s[2] == '\t')) {
            s += 2;
            Vec3 q;
            if (!parse_float_tok(s, &q.x) || !parse_float_tok(s, &q.y) || !parse_float_tok(s, &q.z))
                file_error(path, lineno, "malformed vertex normal");
            vn.push_back(q);
        } else if (s[0] == 'v' && s[1] == 't' && (s[2] == ' ' || s[2] == '\t')) {
            s += 2;
            Vec2 q;
            if (!parse_float_tok(s, &q.x)) file_error(path, lineno, "malformed texture coordinate");
            if (!parse_float_tok(s, &q.y)) q.y = 0;
            vt.push_back(q);
        } else if (s[0] == 'f' && (s[1] == ' ' || s[1] == '\t')) {
            s += 1;
            std::vector<uint32_t> poly;
            std::istringstream ss(s);
            std::string tok;
            while (ss >> tok) {
                int ids[3] = {0, 0, 0};
                bool present[3] = {false, false, false};
                size_t start = 0;
                for (int c = 0; c < 3 && start <= tok.size(); ++c) {
                    size_t slash = tok.find('/', start);
                    std::string part = tok.substr(start, slash == std::string::npos ? std::string::npos : slash - start);
                    if (!part.empty()) {
                        char* end = nullptr;
                        long v = std::strtol(part.c_str(), &end, 10);
                        if (*end || v == 0) file_error(path, lineno, "malformed face index \"" + tok + "\"");
                        ids[c] = int(v);
                        present[c] = true;
                    }
                    if (slash == std::string::npos) break;
                    start = slash + 1;
                }
                if (!present[0]) file_error(path, lineno, "face vertex without position index \"" + tok + "\"");
                const size_t sizes[3] = {vp.size(), vt.size(), vn.size()};
                Key k{-1, -1, -1};
                int* dst[3] = {&k.v, &k.t, &k.n};
                for (int c = 0; c < 3; ++c) {
                    if (!present[c]) continue;
                    long r = ids[c] > 0 ? ids[c] - 1 : long(sizes[c]) + ids[c];
                    if (r < 0 || r >= long(sizes[c]))
                        file_error(path, lineno, "face index out of range in \"" + tok + "\"");
                    *dst[c] = int(r);
                }
                any_t |= k.t >= 0; all_t &= k.t >= 0;
                any_n |= k.n >= 0; all_n &= k.n >= 0;
                auto it = vmap.find(k);
                uint32_t vi;
                if (it == vmap.end()) {
                    vi = uint32_t(verts.size());
                    verts.push_back(k);
                    vmap.emplace(k, vi);
                } else {
                    vi = it->second;
                }
                poly.push_back(vi);
            }
            if (poly.size() < 3) file_error(path, lineno, "face with fewer than 3 vertices");
            for (size_t i = 1; i + 1 < poly.size(); ++i) {
                idx.push_back(poly[0]);
                idx.push_back(poly[i]);
                idx.push_back(poly[i + 1]);
            }
        }
        // everything else (o, g, s, usemtl, mtllib, l, p, vp, ...) is ignored
    }
    if (idx.empty()) throw Error(SourceLoc{path, 0}, "OBJ file contains no faces");
    TriMesh m;
    m.p.reserve(verts.size());
    for (const Key& k : verts) m.p.push_back(vp[size_t(k.v)]);
    if (any_t && all_t)
        for (const Key& k : verts) m.uv.push_back(vt[size_t(k.t)]);
    if (any_n && all_n)
        for (const Key& k : verts) m.n.push_back(normalize(vn[size_t(k.n)]));
    m.idx = std::move(idx);
    return m;
}

// ----------------------------------------------------------------------------------------------
// PLY

namespace {

enum class PlyType { I8, U8, I16, U16, I32, U32, F32, F64, Invalid };

PlyType ply_type(const std::string& s) {
    if (s == "char" || s == "int8") return PlyType::I8;
    if (s == "uchar" || s == "uint8") return PlyType::U8;
    if (s == "short" || s == "int16") return PlyType::I16;
    if (s == "ushort" || s == "uint16") return PlyType::U16;
    if (s == "int" || s == "int32") return PlyType::I32;
    if (s == "uint" || s == "uint32") return PlyType::U32;
    if (s == "float" || s == "float32") return PlyType::F32;
    if (s == "double" || s == "float64") return PlyType::F64;
    return PlyType::Invalid;
}

size_t ply_size(PlyType t) {
    switch (t) {
        case PlyType::I8: case PlyType::U8: return 1;
        case PlyType::I16: case PlyType::U16: return 2;
        case PlyType::I32: case PlyType::U32: case PlyType::F32: return 4;
        case PlyType::F64: return 8;
        default: return 0;
    }
}

struct PlyProp {
    std::string name;
    bool is_list = false;
    PlyType count_type = PlyType::Invalid, type = PlyType::Invalid;
};

struct PlyElement {
    std::string name;
    size_t count = 0;
    std::vector<PlyProp> props;
};

class PlyReader {
public:
    PlyReader(const std::string& path, std::istream& in, bool binary) : path_(path), in_(in), binary_(binary) {}
    double read(PlyType t) {
        if (binary_) {
            unsigned char buf[8];
            size_t n = ply_size(t);
            if (!in_.read(reinterpret_cast<char*>(buf), std::streamsize(n)))
                throw Error(SourceLoc{path_, 0}, "unexpected end of binary PLY data");
            switch (t) {
                case PlyType::I8: { int8_t v; std::memcpy(&v, buf, 1); return v; }
                case PlyType::U8: return buf[0];
                case PlyType::I16: { int16_t v; std::memcpy(&v, buf, 2); return v; }
                case PlyType::U16: { uint16_t v; std::memcpy(&v, buf, 2); return v; }
                case PlyType::I32: { int32_t v; std::memcpy(&v, buf, 4); return v; }
                case PlyType::U32: { uint32_t v; std::memcpy(&v, buf, 4); return v; }
                case PlyType::F32: { float v; std::memcpy(&v, buf, 4); return v; }
                case PlyType::F64: { double v; std::memcpy(&v, buf, 8); return v; }
                default: break;
            }
            return 0;
        }
        std::string tok;
        if (!(in_ >> tok)) throw Error(SourceLoc{path_, 0}, "unexpected end of ASCII PLY data");
        char* end = nullptr;
        double v = std::strtod(tok.c_str(), &end);
        if (*end) throw Error(SourceLoc{path_, 0}, "malformed number \"" + tok + "\" in ASCII PLY data");
        return v;
    }

private:
    std::string path_;
    std::istream& in_;
    bool binary_;
};

}  // namespace

/// Mitsuba's PLY reader groups the scalar properties r, g, b of an element into its "color"
/// attribute (values as stored: Mitsuba 3.9.1 does not rescale uchar colours).
static bool ply_color_props(const PlyElement& e, int color[3]) {
    color[0] = color[1] = color[2] = -1;
    for (size_t k = 0; k < e.props.size(); ++k) {
        if (e.props[k].is_list) continue;
        const std::string& n = e.props[k].name;
        if (n == "r") color[0] = int(k); else if (n == "g") color[1] = int(k); else if (n == "b") color[2] = int(k);
    }
    return color[0] >= 0 && color[1] >= 0 && color[2] >= 0;
}

static Rgb ply_color(const std::vector<double>& vals, const int color[3]) {
    return Rgb(float(vals[size_t(color[0])]), float(vals[size_t(color[1])]), float(vals[size_t(color[2])]));
}

TriMesh load_ply(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw Error("cannot open PLY file \"" + path + "\"");
    std::string line;
    int lineno = 0;
    auto getline = [&]() -> bool {
        if (!std::getline(in, line)) return false;
        ++lineno;
        if (!line.empty() && line.back() == '\r') line.pop_back();
        return true;
    };
    if (!getline() || line != "ply") file_error(path, 1, "not a PLY file (missing \"ply\" magic)");
    bool binary = false, have_format = false;
    std::vector<PlyElement> elems;
    while (true) {
        if (!getline()) file_error(path, lineno, "unexpected end of PLY header");
        std::istringstream ss(line);
        std::string kw;
        ss >> kw;
        if (kw == "end_header") break;
        if (kw == "comment" || kw == "obj_info" || kw.empty()) continue;
        if (kw == "format") {
            std::string fmt, ver;
            ss >> fmt >> ver;
            if (fmt == "ascii") binary = false;
            else if (fmt == "binary_little_endian") binary = true;
            else if (fmt == "binary_big_endian") file_error(path, lineno, "binary_big_endian PLY files are not supported");
            else file_error(path, lineno, "unknown PLY format \"" + fmt + "\"");
            have_format = true;
        } else if (kw == "element") {
            PlyElement e;
            long long c = -1;
            ss >> e.name >> c;
            if (e.name.empty() || c < 0) file_error(path, lineno, "malformed element declaration");
            e.count = size_t(c);
            elems.push_back(e);
        } else if (kw == "property") {
            if (elems.empty()) file_error(path, lineno, "property before any element");
            PlyProp p;
            std::string t;
            ss >> t;
            if (t == "list") {
                std::string ct, it;
                ss >> ct >> it >> p.name;
                p.is_list = true;
                p.count_type = ply_type(ct);
                p.type = ply_type(it);
                if (p.count_type == PlyType::Invalid || p.type == PlyType::Invalid || p.name.empty())
                    file_error(path, lineno, "malformed list property");
            } else {
                ss >> p.name;
                p.type = ply_type(t);
                if (p.type == PlyType::Invalid || p.name.empty())
                    file_error(path, lineno, "unknown property type \"" + t + "\"");
            }
            elems.back().props.push_back(p);
        } else {
            file_error(path, lineno, "unknown PLY header keyword \"" + kw + "\"");
        }
    }
    if (!have_format) file_error(path, lineno, "PLY header lacks a format line");
    PlyReader rd(path, in, binary);
    TriMesh m;
    bool have_vertices = false;
    for (const PlyElement& e : elems) {
        if (e.name == "vertex") {
            have_vertices = true;
            int ix = -1, iy = -1, iz = -1, inx = -1, iny = -1, inz = -1, iu = -1, iv = -1;
            for (size_t k = 0; k < e.props.size(); ++k) {
                const std::string& n = e.props[k].name;
                int kk = int(k);
                if (n == "x") ix = kk; else if (n == "y") iy = kk; else if (n == "z") iz = kk;
                else if (n == "nx") inx = kk; else if (n == "ny") iny = kk; else if (n == "nz") inz = kk;
                else if (n == "u" || n == "s" || n == "texture_u" || n == "texture_s") iu = kk;
                else if (n == "v" || n == "t" || n == "texture_v" || n == "texture_t") iv = kk;
            }
            if (ix < 0 || iy < 0 || iz < 0) file_error(path, 0, "vertex element lacks x/y/z properties");
            int color[3];
            bool colors = ply_color_props(e, color);
            TriMesh::Attribute vertex_color{"vertex_color", false, {}};
            bool normals = inx >= 0 && iny >= 0 && inz >= 0, uvs = iu >= 0 && iv >= 0;
            std::vector<double> vals(e.props.size());
            m.p.resize(e.count);
            if (normals) m.n.resize(e.count);
            if (uvs) m.uv.resize(e.count);
            for (size_t i = 0; i < e.count; ++i) {
                for (size_t k = 0; k < e.props.size(); ++k) {
                    const PlyProp& p = e.props[k];
                    if (p.is_list) {
                        size_t c = size_t(rd.read(p.count_type));
                        for (size_t j = 0; j < c; ++j) rd.read(p.type);
                        vals[k] = 0;
                    } else {
                        vals[k] = rd.read(p.type);
                    }
                }
                m.p[i] = Vec3(float(vals[size_t(ix)]), float(vals[size_t(iy)]), float(vals[size_t(iz)]));
                if (!all_finite(m.p[i])) file_error(path, 0, "non-finite vertex position");
                if (normals) m.n[i] = normalize(Vec3(float(vals[size_t(inx)]), float(vals[size_t(iny)]), float(vals[size_t(inz)])));
                if (uvs) m.uv[i] = Vec2(float(vals[size_t(iu)]), float(vals[size_t(iv)]));
                if (colors) vertex_color.values.push_back(ply_color(vals, color));
            }
            if (colors) m.attributes.push_back(std::move(vertex_color));
        } else if (e.name == "face") {
            int ii = -1;
            for (size_t k = 0; k < e.props.size(); ++k)
                if (e.props[k].is_list && (e.props[k].name == "vertex_indices" || e.props[k].name == "vertex_index"))
                    ii = int(k);
            if (ii < 0) file_error(path, 0, "face element lacks a vertex_indices list");
            int color[3];
            bool colors = ply_color_props(e, color);
            TriMesh::Attribute face_color{"face_color", true, {}};
            std::vector<double> vals(e.props.size());
            for (size_t i = 0; i < e.count; ++i) {
                std::vector<uint32_t> poly;
                for (size_t k = 0; k < e.props.size(); ++k) {
                    const PlyProp& p = e.props[k];
                    if (p.is_list) {
                        double cd = rd.read(p.count_type);
                        if (cd < 0 || cd > 1e6) file_error(path, 0, "invalid list length in face element");
                        size_t c = size_t(cd);
                        for (size_t j = 0; j < c; ++j) {
                            double v = rd.read(p.type);
                            if (int(k) == ii) {
                                if (v < 0 || v >= double(m.p.size()) || !have_vertices)
                                    file_error(path, 0, "face " + std::to_string(i) + " has a vertex index out of range");
                                poly.push_back(uint32_t(v));
                            }
                        }
                    } else {
                        vals[k] = rd.read(p.type);
                    }
                }
                if (poly.size() < 3) file_error(path, 0, "face " + std::to_string(i) + " has fewer than 3 vertices");
                for (size_t j = 1; j + 1 < poly.size(); ++j) {
                    m.idx.push_back(poly[0]);
                    m.idx.push_back(poly[j]);
                    m.idx.push_back(poly[j + 1]);
                    if (colors) face_color.values.push_back(ply_color(vals, color));
                }
            }
            if (colors) m.attributes.push_back(std::move(face_color));
        } else {
            for (size_t i = 0; i < e.count; ++i)
                for (const PlyProp& p : e.props) {
                    if (p.is_list) {
                        size_t c = size_t(rd.read(p.count_type));
                        for (size_t j = 0; j < c; ++j) rd.read(p.type);
                    } else {
                        rd.read(p.type);
                    }
                }
        }
    }
    if (m.idx.empty()) throw Error(SourceLoc{path, 0}, "PLY file contains no faces");
    return m;
}

// ----------------------------------------------------------------------------------------------
// Mitsuba's serialized format: per shape, uint16 0x041C, uint16 version (3 or 4), then a zlib
// stream: uint32 flags, [v4: NUL-terminated name], uint64 vertex and triangle counts, positions,
// [normals], [uv], [colours] (float32 or float64 by flag), indices (uint32, or uint64 above 2^32
// vertices). A file with several shapes ends with their offsets (uint64 in v4, uint32 in v3)
// and a uint32 count.

namespace {

constexpr uint32_t kSerHasNormals = 0x0001, kSerHasUv = 0x0002, kSerHasColors = 0x0008, kSerFaceNormals = 0x0010,
                   kSerSingle = 0x1000, kSerDouble = 0x2000;
constexpr uint64_t kSerMaxElements = uint64_t(1) << 31;  // vertices or triangles per shape

/// Inflates a zlib stream from `data` on demand and refuses reads past its end.
class Inflater {
public:
    Inflater(const std::string& path, const unsigned char* data, size_t size) : path_(path) {
        std::memset(&z_, 0, sizeof z_);
        if (inflateInit(&z_) != Z_OK) throw Error(path_ + ": zlib initialisation failed");
        z_.next_in = const_cast<unsigned char*>(data);
        z_.avail_in = uInt(std::min<size_t>(size, 0xFFFFFFFFu));
    }
    ~Inflater() { inflateEnd(&z_); }
    void read(void* out, size_t n) {
        z_.next_out = static_cast<unsigned char*>(out);
        while (n > 0) {
            uInt chunk = uInt(std::min<size_t>(n, 1u << 30));
            z_.avail_out = chunk;
            int r = inflate(&z_, Z_SYNC_FLUSH);
            size_t got = chunk - z_.avail_out;
            n -= got;
            if (n == 0) break;
            if (r == Z_STREAM_END || r != Z_OK || got == 0)
                throw Error(path_ + ": serialized shape data is truncated or corrupt (zlib)");
        }
    }
    template <class T> T get() {
        T v;
        read(&v, sizeof v);
        return v;
    }

private:
    std::string path_;
    z_stream z_;
};

}  // namespace

TriMesh load_serialized(const std::string& path, int shape_index, bool* face_normals) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw Error("cannot read serialized mesh \"" + path + "\"");
    std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    const unsigned char* b = reinterpret_cast<const unsigned char*>(bytes.data());
    const size_t n = bytes.size();
    auto bad = [&](const std::string& why) { return Error(path + ": not a Mitsuba serialized mesh: " + why); };
    if (n < 4) throw bad("file too short");
    auto u16 = [&](size_t at) { return uint16_t(b[at] | (b[at + 1] << 8)); };
    auto u32 = [&](size_t at) { uint32_t v; std::memcpy(&v, b + at, 4); return v; };
    auto u64 = [&](size_t at) { uint64_t v; std::memcpy(&v, b + at, 8); return v; };
    if (u16(0) != 0x041C) throw bad("missing the 0x041C header");
    uint16_t version = u16(2);
    if (version != 3 && version != 4) throw bad("unsupported version " + std::to_string(version));
    // shape offsets: the trailing dictionary when there is one, else the only shape at 0
    size_t offset = 0;
    uint32_t count = u32(n - 4);
    size_t entry = version == 4 ? 8 : 4;
    bool has_dict = count >= 1 && uint64_t(count) * entry + 4 <= n && n >= 8;
    if (has_dict) {
        size_t dict = n - 4 - size_t(count) * entry;
        uint64_t first = version == 4 ? u64(dict) : u32(dict);
        has_dict = first == 0;  // the first shape starts the file
        if (has_dict) {
            if (shape_index < 0 || uint32_t(shape_index) >= count)
                throw bad("shape_index " + std::to_string(shape_index) + " out of range (the file has " +
                          std::to_string(count) + " shapes)");
            uint64_t at = dict + size_t(shape_index) * entry;
            offset = size_t(version == 4 ? u64(at) : u32(at));
            if (offset + 4 > dict) throw bad("shape offset out of range");
        }
    }
    if (!has_dict && shape_index != 0) throw bad("the file has one shape, shape_index must be 0");
    if (u16(offset) != 0x041C || u16(offset + 2) != version) throw bad("shape " + std::to_string(shape_index) + " has no header");
    Inflater z(path, b + offset + 4, n - offset - 4);
    uint32_t flags = z.get<uint32_t>();
    if (version == 4) {
        for (int i = 0; i < 4096; ++i)
            if (z.get<char>() == '\0') break;  // the shape's name
    }
    uint64_t nv = z.get<uint64_t>(), nt = z.get<uint64_t>();
    if (nv == 0 || nt == 0 || nv > kSerMaxElements || nt > kSerMaxElements)
        throw bad("vertex/triangle counts " + std::to_string(nv) + "/" + std::to_string(nt) + " out of range");
    bool dbl = flags & kSerDouble;
    if (!(flags & (kSerSingle | kSerDouble))) throw bad("no precision flag");
    auto reals = [&](size_t k, std::vector<float>* out) {
        out->resize(k);
        if (!dbl) {
            z.read(out->data(), k * sizeof(float));
        } else {
            std::vector<double> d(k);
            z.read(d.data(), k * sizeof(double));
            for (size_t i = 0; i < k; ++i) (*out)[i] = float(d[i]);
        }
        for (float v : *out)
            if (!std::isfinite(v)) throw bad("non-finite vertex data");
    };
    TriMesh m;
    std::vector<float> tmp;
    reals(3 * nv, &tmp);
    m.p.resize(nv);
    for (size_t i = 0; i < nv; ++i) m.p[i] = Vec3(tmp[3 * i], tmp[3 * i + 1], tmp[3 * i + 2]);
    if (flags & kSerHasNormals) {
        reals(3 * nv, &tmp);
        m.n.resize(nv);
        for (size_t i = 0; i < nv; ++i) m.n[i] = normalize(Vec3(tmp[3 * i], tmp[3 * i + 1], tmp[3 * i + 2]));
    }
    if (flags & kSerHasUv) {
        reals(2 * nv, &tmp);
        m.uv.resize(nv);
        for (size_t i = 0; i < nv; ++i) m.uv[i] = Vec2(tmp[2 * i], tmp[2 * i + 1]);
    }
    if (flags & kSerHasColors) reals(3 * nv, &tmp);  // vertex colours: not used
    m.idx.resize(3 * nt);
    if (nv <= 0xFFFFFFFFull) {
        z.read(m.idx.data(), m.idx.size() * sizeof(uint32_t));
    } else {
        for (uint32_t& i : m.idx) i = uint32_t(z.get<uint64_t>());
    }
    for (uint32_t i : m.idx)
        if (i >= nv) throw bad("vertex index out of range");
    *face_normals = flags & kSerFaceNormals;
    if (*face_normals) m.n.clear();
    return m;
}

}  // namespace mf
