// mfhost — Mitsuba 3 XML subset parser (see xml_scene.h).
#include "xml_scene.h"

#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstdlib>
#include <fstream>
#include <set>
#include <sstream>
#include <unordered_map>
#include <unordered_set>

#include <pugixml.hpp>

#include "spectrum.h"

namespace mf {

const char* prop_type_name(PropType t) {
    switch (t) {
        case PropType::Integer: return "integer";
        case PropType::Float: return "float";
        case PropType::Boolean: return "boolean";
        case PropType::String: return "string";
        case PropType::Rgb: return "rgb";
        case PropType::Vector: return "vector";
        case PropType::Point: return "point";
        case PropType::Transform: return "transform";
    }
    return "?";
}

int line_of_offset(const std::string& text, size_t offset) {
    if (offset > text.size()) offset = text.size();
    return 1 + int(std::count(text.begin(), text.begin() + ptrdiff_t(offset), '\n'));
}

// ----------------------------------------------------------------------------------------------
// SceneObject accessors

std::string SceneObject::describe() const {
    std::string s = "<" + tag;
    if (!type.empty()) s += " type=" + quote(type);
    if (!id.empty()) s += " id=" + quote(id);
    return s + ">";
}

const Property* SceneObject::find(const std::string& name) const {
    for (const Property& p : props)
        if (p.name == name) {
            p.used = true;
            return &p;
        }
    return nullptr;
}

SourceLoc SceneObject::loc_of(const std::string& prop_name) const {
    for (const Property& p : props)
        if (p.name == prop_name) return p.loc;
    return loc;
}

static bool is_file(const std::string& p) {
    struct stat st;
    return ::stat(p.c_str(), &st) == 0 && S_ISREG(st.st_mode);
}

std::string SceneObject::resolve_path(const std::string& name) const {
    if (name.empty() || name[0] == '/') return name;
    auto join = [&](const std::string& d) { return (d.empty() || d == ".") ? name : d + "/" + name; };
    if (search_path)
        for (const std::string& d : *search_path)
            if (is_file(join(d))) return join(d);
    if (is_file(join(dir))) return join(dir);
    if (is_file(name)) return name;
    return join(dir);
}

static Error type_error(const SceneObject& o, const Property& p, const char* expected) {
    return Error(p.loc, o.describe() + ": parameter \"" + p.name + "\" has type " + prop_type_name(p.type) +
                            ", expected " + expected);
}

float SceneObject::get_float(const std::string& name, float def) const {
    const Property* p = find(name);
    if (!p) return def;
    double v;
    if (p->type == PropType::Float) v = p->f;
    else if (p->type == PropType::Integer) v = double(p->i);
    else throw type_error(*this, *p, "float");
    if (!std::isfinite(float(v)))
        throw Error(p->loc, describe() + ": parameter " + quote(name) + " is not a finite float");
    return float(v);
}

float SceneObject::get_float(const std::string& name) const {
    if (!find(name)) throw Error(loc, describe() + ": missing required parameter \"" + name + "\"");
    return get_float(name, 0.0f);
}

long long SceneObject::get_int(const std::string& name, long long def) const {
    const Property* p = find(name);
    if (!p) return def;
    if (p->type != PropType::Integer) throw type_error(*this, *p, "integer");
    return p->i;
}

bool SceneObject::get_bool(const std::string& name, bool def) const {
    const Property* p = find(name);
    if (!p) return def;
    if (p->type != PropType::Boolean) throw type_error(*this, *p, "boolean");
    return p->b;
}

std::string SceneObject::get_string(const std::string& name, const std::string& def) const {
    const Property* p = find(name);
    if (!p) return def;
    if (p->type != PropType::String) throw type_error(*this, *p, "string");
    return p->s;
}

std::string SceneObject::get_string(const std::string& name) const {
    if (!find(name)) throw Error(loc, describe() + ": missing required parameter \"" + name + "\"");
    return get_string(name, "");
}

Rgb SceneObject::get_rgb(const std::string& name, const Rgb& def) const {
    const Property* p = find(name);
    if (!p) return def;
    if (p->type == PropType::Rgb) return p->rgb;
    if (p->type == PropType::Float || p->type == PropType::Integer) return Rgb(get_float(name, 0.0f));
    throw type_error(*this, *p, "rgb, spectrum or float");
}

Vec3 SceneObject::get_vector(const std::string& name, const Vec3& def) const {
    const Property* p = find(name);
    if (!p) return def;
    if (p->type != PropType::Vector && p->type != PropType::Point) throw type_error(*this, *p, "vector");
    return p->v;
}

Vec3 SceneObject::get_point(const std::string& name, const Vec3& def) const {
    const Property* p = find(name);
    if (!p) return def;
    if (p->type != PropType::Point && p->type != PropType::Vector) throw type_error(*this, *p, "point");
    return p->v;
}

Mat4 SceneObject::get_transform(const std::string& name, const Mat4& def) const {
    const Property* p = find(name);
    if (!p) return def;
    if (p->type != PropType::Transform) throw type_error(*this, *p, "transform");
    return p->m;
}

std::vector<const Child*> SceneObject::children_with_tag(const std::string& t) const {
    std::vector<const Child*> out;
    for (const Child& c : children)
        if (c.obj->tag == t) {
            c.used = true;
            out.push_back(&c);
        }
    return out;
}

const Child* SceneObject::child_named(const std::string& t, const std::string& name) const {
    for (const Child& c : children)
        if (c.obj->tag == t && c.name == name) {
            c.used = true;
            return &c;
        }
    return nullptr;
}

void SceneObject::check_all_used() const {
    ErrorSink sink;
    for (const Property& p : props)
        if (!p.used)
            sink.add(Error(p.loc, describe() + ": unknown parameter " + quote(p.name) + " (" + prop_type_name(p.type) +
                                      ") for plugin " + quote(type)));
    for (const Child& c : children)
        if (!c.used)
            sink.add(Error(c.loc, describe() + ": unexpected nested " + c.obj->describe() +
                                      (c.name.empty() ? std::string() : " (name " + quote(c.name) + ")")));
    sink.raise();
}

// ----------------------------------------------------------------------------------------------
// Parser

namespace {

const std::set<std::string> kObjectTags = {"shape",   "bsdf",       "medium",  "emitter", "sensor", "film",
                                           "sampler", "integrator", "rfilter", "phase",   "texture", "volume"};
const std::set<std::string> kPropertyTags = {"integer", "float", "boolean", "string", "rgb",
                                             "vector",  "point", "transform", "spectrum"};

/// One XML file being read: its text and the byte offset of every line start, so that the line
/// of a node is a binary search (linear total parse time, whatever the number of elements).
struct FileCtx {
    std::string path;  // as shown in messages
    std::string dir;
    std::string text;
    std::vector<size_t> line_starts;
    int include_depth = 0;
    void index_lines() {
        line_starts.assign(1, 0);
        for (size_t i = 0; i < text.size(); ++i)
            if (text[i] == '\n') line_starts.push_back(i + 1);
    }
    int line(ptrdiff_t offset) const {
        if (offset < 0) return 0;
        return int(std::upper_bound(line_starts.begin(), line_starts.end(), size_t(offset)) - line_starts.begin());
    }
};

std::string dirname_of(const std::string& path) {
    size_t p = path.find_last_of('/');
    if (p == std::string::npos) return ".";
    if (p == 0) return "/";
    return path.substr(0, p);
}

/// Read a scene XML file: regular files only, at most `max_bytes` (a device such as /dev/zero
/// or an endless pipe is refused before anything is read).
std::string read_xml_file(const std::string& path, size_t max_bytes, const SourceLoc& where, const char* what) {
    struct stat st;
    if (::stat(path.c_str(), &st) != 0) throw Error(where, std::string(what) + ": no such file " + quote(path, 200));
    if (!S_ISREG(st.st_mode))
        throw Error(where, std::string(what) + ": " + quote(path, 200) + " is not a regular file");
    if (size_t(st.st_size) > max_bytes)
        throw Error(where, std::string(what) + ": " + quote(path, 200) + " is " + std::to_string(st.st_size) +
                               " bytes, more than the limit of " + std::to_string(max_bytes) + " for scene files");
    std::ifstream in(path, std::ios::binary);
    if (!in) throw Error(where, std::string(what) + ": cannot read file " + quote(path, 200));
    std::string text(size_t(st.st_size), '\0');
    in.read(&text[0], std::streamsize(text.size()));
    text.resize(size_t(in.gcount()));
    return text;
}

/// Mitsuba's <rotate>: Rodrigues' formula with the axis as given (Mitsuba does not normalise it,
/// so a non-unit axis also scales; scenes nearly always give unit axes).
Mat4 mitsuba_rotate(const Vec3& a, double angle_deg) {
    double t = angle_deg * 3.14159265358979323846 / 180.0;
    double c = std::cos(t), s = std::sin(t), k = 1.0 - c;
    double x = a.x, y = a.y, z = a.z;
    Mat4 r;
    r.m[0][0] = x * x * k + c;     r.m[0][1] = x * y * k - z * s; r.m[0][2] = x * z * k + y * s;
    r.m[1][0] = x * y * k + z * s; r.m[1][1] = y * y * k + c;     r.m[1][2] = y * z * k - x * s;
    r.m[2][0] = x * z * k - y * s; r.m[2][1] = y * z * k + x * s; r.m[2][2] = z * z * k + c;
    return r;
}

/// Mitsuba's in-memory upgrade of pre-2.0.0 scenes: camelCase parameter names become
/// snake_case (not <default> names).
std::string snake_case(const std::string& name) {
    std::string out;
    for (size_t i = 0; i < name.size(); ++i) {
        char c = name[i];
        if (i > 0 && std::isupper((unsigned char)c) && std::islower((unsigned char)name[i - 1])) {
            out += '_';
            while (i < name.size() && std::isupper((unsigned char)name[i])) out += char(std::tolower((unsigned char)name[i++]));
            --i;
            continue;
        }
        out += c;
    }
    return out;
}

/// Names whose <rgb>/<spectrum> Mitsuba's RGB variants keep unbounded outside emitters
/// (xml.cpp is_unbounded_spectrum); every other such value must lie in [0, 1] there.
bool is_unbounded_spectrum(const std::string& name) {
    return name == "eta" || name == "k" || name == "int_ior" || name == "ext_ior";
}

struct PendingRef {
    SceneObject* parent;
    size_t child;
    std::string id;
};

class Parser {
public:
    Parser(const Defines& cli, ErrorSink& errors) : errors_(errors) {
        for (const auto& kv : cli) params_[kv.first] = kv.second;
    }

    ParsedScene parse(const std::string& text, const std::string& path) {
        ParsedScene out;
        out.main_file = path;
        warnings_ = &out.warnings;
        out.root = std::make_shared<SceneObject>();
        out.root->tag = "scene";
        FileCtx ctx{path, dirname_of(path), text, {}, 0};
        ctx.index_lines();
        out.root->loc = SourceLoc{path, 1};
        out.root->dir = ctx.dir;
        search_path_ = std::make_shared<std::vector<std::string>>();
        search_path_->push_back(ctx.dir);
        out.root->search_path = search_path_;
        total_bytes_ = text.size();
        hash(text);
        for (const auto& kv : params_) hash(kv.first + "=" + kv.second + "\n");
        if (text.size() > XmlLimits::kMaxFileBytes) {
            errors_.add(Error(out.root->loc, "scene file is " + std::to_string(text.size()) + " bytes, more than the limit of " +
                                                 std::to_string(XmlLimits::kMaxFileBytes)));
            return out;
        }
        pugi::xml_document doc;
        out.root->broken = true;  // until the document is read: no consequential errors
        if (!load(ctx, doc)) return out;
        pugi::xml_node root = doc.document_element();
        if (std::string(root.name()) != "scene") {
            errors_.add(Error(loc(ctx, root), "root element must be <scene>, found <" + clip(root.name()) + ">"));
            return out;
        }
        out.root->loc = loc(ctx, root);
        try {
            check_attrs(ctx, root, {"version"});
            pugi::xml_attribute ver = root.attribute("version");
            if (!ver) throw Error(loc(ctx, root), "<scene> is missing the \"version\" attribute (expected 3.x.x)");
            out.version = ver.value();
            upgrade_ = check_version(ctx, root, out.version);
            out.upgraded = upgrade_;
        } catch (const Error& e) {
            errors_.add(e);
            return out;
        }
        out.root->broken = false;
        include_stack_.push_back(path);
        parse_children(ctx, root, *out.root, 1, true);
        resolve_refs();
        check_graph_depth(*out.root);
        out.content_hash = hash_;
        return out;
    }

private:
    ErrorSink& errors_;
    std::map<std::string, std::string> params_;
    std::unordered_map<std::string, std::shared_ptr<SceneObject>> ids_;
    std::unordered_map<std::string, SourceLoc> alias_locs_;
    std::vector<PendingRef> pending_;
    std::vector<std::string> include_stack_;
    std::shared_ptr<std::vector<std::string>> search_path_;
    std::vector<std::string>* warnings_ = nullptr;  // ParsedScene::warnings
    size_t total_bytes_ = 0;
    bool upgrade_ = false;  // current file is pre-2.0.0
    uint64_t hash_ = 0xcbf29ce484222325ull;
    void hash(const std::string& s) {  // FNV-1a 64
        for (unsigned char c : s) hash_ = (hash_ ^ c) * 0x100000001b3ull;
    }

    static std::string clip(const std::string& s) { return s.size() <= 64 ? s : s.substr(0, 64) + "..."; }

    static SourceLoc loc(const FileCtx& ctx, const pugi::xml_node& n) { return SourceLoc{ctx.path, ctx.line(n.offset_debug())}; }

    bool load(const FileCtx& ctx, pugi::xml_document& doc) {
        pugi::xml_parse_result res =
            doc.load_buffer(ctx.text.data(), ctx.text.size(), pugi::parse_default | pugi::parse_ws_pcdata_single);
        if (!res) {
            SourceLoc l{ctx.path, ctx.line(std::max<ptrdiff_t>(0, res.offset))};
            errors_.add(Error(l, std::string("malformed XML: ") + res.description()));
            return false;
        }
        return true;
    }

    /// Returns true for a pre-2.0.0 scene that needs Mitsuba's in-memory upgrade.
    bool check_version(const FileCtx& ctx, const pugi::xml_node& n, const std::string& v) {
        int major = 0, minor = 0, patch = 0;
        char tail = 0;
        if (std::sscanf(v.c_str(), "%d.%d.%d%c", &major, &minor, &patch, &tail) != 3 || major < 0 || minor < 0 || patch < 0)
            throw Error(loc(ctx, n), "invalid scene version " + quote(v) + " (expected major.minor.patch)");
        if (major > 3)
            throw Error(loc(ctx, n), "unsupported scene version " + quote(v) + ": Mitsuba 3 reads scenes up to 3.x.x");
        return major < 2;
    }

    void check_attrs(const FileCtx& ctx, const pugi::xml_node& n, std::initializer_list<const char*> allowed) {
        for (pugi::xml_attribute a : n.attributes()) {
            bool ok = false;
            for (const char* s : allowed)
                if (std::string(a.name()) == s) ok = true;
            if (!ok)
                throw Error(loc(ctx, n), "<" + clip(n.name()) + ">: unexpected attribute " + quote(a.name()));
        }
    }

    std::string substitute(const FileCtx& ctx, const pugi::xml_node& n, const std::string& in) {
        if (in.find('$') == std::string::npos) return in;
        std::string out;
        for (size_t i = 0; i < in.size();) {
            if (in[i] != '$') {
                out += in[i++];
                continue;
            }
            size_t j = i + 1;
            while (j < in.size() && (std::isalnum((unsigned char)in[j]) || in[j] == '_')) ++j;
            std::string key = in.substr(i + 1, j - i - 1);
            if (key.empty()) {
                out += in[i++];
                continue;
            }
            auto it = params_.find(key);
            if (it == params_.end())
                throw Error(loc(ctx, n), "<" + clip(n.name()) + ">: undefined parameter " + quote("$" + key) +
                                             " (declare it with <default name=" + quote(key) +
                                             " value=\"...\"/> or pass -D " + clip(key) + "=...)");
            out += it->second;
            if (out.size() > XmlLimits::kMaxValueBytes)
                throw Error(loc(ctx, n), "<" + clip(n.name()) + ">: value longer than " +
                                             std::to_string(XmlLimits::kMaxValueBytes) + " bytes after substituting $" + clip(key));
            i = j;
        }
        return out;
    }

    bool has_attr(const pugi::xml_node& n, const char* name) { return bool(n.attribute(name)); }

    std::string attr(const FileCtx& ctx, const pugi::xml_node& n, const char* name, bool required = true) {
        pugi::xml_attribute a = n.attribute(name);
        if (!a) {
            if (required) throw Error(loc(ctx, n), "<" + clip(n.name()) + ">: missing attribute \"" + name + "\"");
            return std::string();
        }
        return substitute(ctx, n, a.value());
    }

    /// A property or object "name": substituted, and snake_cased in a pre-2.0.0 scene.
    std::string name_attr(const FileCtx& ctx, const pugi::xml_node& n, bool required) {
        std::string s = attr(ctx, n, "name", required);
        return upgrade_ ? snake_case(s) : s;
    }

    std::vector<double> parse_numbers(const FileCtx& ctx, const pugi::xml_node& n, const std::string& s, const char* what) {
        std::vector<double> out;
        const char* p = s.c_str();
        while (*p) {
            while (*p && (std::isspace((unsigned char)*p) || *p == ',')) ++p;
            if (!*p) break;
            char* end = nullptr;
            errno = 0;
            double v = std::strtod(p, &end);
            if (end == p || (*end && !std::isspace((unsigned char)*end) && *end != ','))
                throw Error(loc(ctx, n), "<" + clip(n.name()) + ">: could not parse " + what + " " + quote(s));
            if (!std::isfinite(v)) throw Error(loc(ctx, n), "<" + clip(n.name()) + ">: " + what + " " + quote(s) + " is not finite");
            out.push_back(v);
            p = end;
        }
        return out;
    }

    double parse_number(const FileCtx& ctx, const pugi::xml_node& n, const std::string& s) {
        std::vector<double> v = parse_numbers(ctx, n, s, "number");
        if (v.size() != 1) throw Error(loc(ctx, n), "<" + clip(n.name()) + ">: expected a single number, got " + quote(s));
        return v[0];
    }

    /// x/y/z attributes, or value="v" (all three) / value="x y z" (Mitsuba's expand_value_to_xyz).
    Vec3 parse_xyz(const FileCtx& ctx, const pugi::xml_node& n, double def) {
        if (has_attr(n, "value")) {
            if (has_attr(n, "x") || has_attr(n, "y") || has_attr(n, "z"))
                throw Error(loc(ctx, n), "<" + clip(n.name()) + ">: give either value or x/y/z, not both");
            std::vector<double> v = parse_numbers(ctx, n, attr(ctx, n, "value"), "vector");
            if (v.size() == 1) return Vec3(float(v[0]));
            if (v.size() != 3) throw Error(loc(ctx, n), "<" + clip(n.name()) + ">: expected 1 or 3 components in value");
            return Vec3(float(v[0]), float(v[1]), float(v[2]));
        }
        Vec3 r{float(def), float(def), float(def)};
        if (has_attr(n, "x")) r.x = float(parse_number(ctx, n, attr(ctx, n, "x")));
        if (has_attr(n, "y")) r.y = float(parse_number(ctx, n, attr(ctx, n, "y")));
        if (has_attr(n, "z")) r.z = float(parse_number(ctx, n, attr(ctx, n, "z")));
        return r;
    }

    Mat4 parse_transform(const FileCtx& ctx, const pugi::xml_node& t) {
        Mat4 m;
        for (pugi::xml_node op : t.children()) {
            if (op.type() != pugi::node_element) continue;
            std::string k = op.name();
            if (upgrade_ && k == "lookAt") k = "lookat";
            Mat4 step;
            if (k == "translate") {
                check_attrs(ctx, op, {"x", "y", "z", "value"});
                Vec3 v = parse_xyz(ctx, op, 0.0);
                step = Mat4::translate(v.x, v.y, v.z);
            } else if (k == "scale") {
                check_attrs(ctx, op, {"x", "y", "z", "value"});
                Vec3 v = parse_xyz(ctx, op, 1.0);
                step = Mat4::scale(v.x, v.y, v.z);
            } else if (k == "rotate") {
                check_attrs(ctx, op, {"x", "y", "z", "value", "angle"});
                Vec3 axis = parse_xyz(ctx, op, 0.0);
                double angle = parse_number(ctx, op, attr(ctx, op, "angle"));
                if (length(axis) == 0) throw Error(loc(ctx, op), "<rotate>: rotation axis is zero");
                step = mitsuba_rotate(axis, angle);
            } else if (k == "matrix") {
                check_attrs(ctx, op, {"value"});
                std::vector<double> v = parse_numbers(ctx, op, attr(ctx, op, "value"), "matrix");
                if (v.size() == 16) {
                    for (int i = 0; i < 16; ++i) step.m[i / 4][i % 4] = v[size_t(i)];
                } else if (v.size() == 9) {
                    for (int i = 0; i < 9; ++i) step.m[i / 3][i % 3] = v[size_t(i)];
                } else {
                    throw Error(loc(ctx, op), "<matrix>: expected 16 (or 9) values, got " + std::to_string(v.size()));
                }
            } else if (k == "lookat") {
                check_attrs(ctx, op, {"origin", "target", "up"});
                auto vec = [&](const char* name) {
                    std::vector<double> v = parse_numbers(ctx, op, attr(ctx, op, name), name);
                    if (v.size() != 3) throw Error(loc(ctx, op), std::string("<lookat>: ") + name + " needs 3 components");
                    return Vec3(float(v[0]), float(v[1]), float(v[2]));
                };
                Vec3 o = vec("origin"), tg = vec("target");
                Vec3 d = tg - o;
                if (length(d) == 0) throw Error(loc(ctx, op), "<lookat>: origin and target coincide");
                // Mitsuba: without `up`, the first axis of coordinate_system(direction)
                Vec3 up = has_attr(op, "up") ? vec("up") : Frame(normalize(d)).s;
                if (length(cross(normalize(up), normalize(d))) < 1e-6f)
                    throw Error(loc(ctx, op), "<lookat>: up vector is parallel to the viewing direction");
                step = Mat4::look_at(o, tg, up);
            } else {
                throw Error(loc(ctx, op), "<transform>: unknown transform operation <" + clip(k) + ">");
            }
            m = step * m;  // Mitsuba: each operation is applied after the previous ones
        }
        if (!m.finite()) throw Error(loc(ctx, t), "<transform>: non-finite matrix");
        return m;
    }

    Property parse_property(const FileCtx& ctx, const pugi::xml_node& n, const std::string& parent_tag) {
        // Emitters' radiances and volumes' data (e.g. an anisotropy matrix's entries) are not
        // reflectances: their <rgb> may leave [0, 1].
        const bool unbounded_rgb = parent_tag == "emitter" || parent_tag == "volume";
        std::string k = n.name();
        Property p;
        p.loc = loc(ctx, n);
        if (k == "transform") {
            check_attrs(ctx, n, {"name"});
            p.name = name_attr(ctx, n, true);
            p.type = PropType::Transform;
            p.m = parse_transform(ctx, n);
            return p;
        }
        if (k == "vector" || k == "point") {
            check_attrs(ctx, n, {"name", "value", "x", "y", "z"});
            p.name = name_attr(ctx, n, true);
            p.type = k == "vector" ? PropType::Vector : PropType::Point;
            p.v = parse_xyz(ctx, n, 0.0);
            return p;
        }
        if (k == "spectrum" && has_attr(n, "type")) {
            check_attrs(ctx, n, {"name", "type"});
            p.name = name_attr(ctx, n, true);
            parse_srgb_spectrum(ctx, n, "<spectrum name=" + quote(p.name) + " type=" + quote(attr(ctx, n, "type")) + ">",
                                unbounded_rgb, &p);
            return p;
        }
        if (k == "spectrum") {
            check_attrs(ctx, n, {"name", "value", "filename"});
        } else {
            check_attrs(ctx, n, {"name", "value"});
        }
        p.name = name_attr(ctx, n, true);
        const std::string where = "<" + k + " name=" + quote(p.name) + ">";
        if (k == "spectrum") {
            parse_spectrum(ctx, n, parent_tag, where, &p);
            return p;
        }
        std::string v = attr(ctx, n, "value");
        if (k == "integer") {
            p.type = PropType::Integer;
            char* end = nullptr;
            errno = 0;
            p.i = std::strtoll(v.c_str(), &end, 10);
            while (end && *end && std::isspace((unsigned char)*end)) ++end;
            if (v.empty() || *end || errno) throw Error(p.loc, where + ": could not parse integer " + quote(v));
        } else if (k == "float") {
            p.type = PropType::Float;
            p.f = parse_number(ctx, n, v);
        } else if (k == "boolean") {
            p.type = PropType::Boolean;
            std::string l;
            for (char c : v) l += char(std::tolower((unsigned char)c));
            if (l == "true") p.b = true;
            else if (l == "false") p.b = false;
            else throw Error(p.loc, where + ": could not parse boolean " + quote(v) + " (expected true or false)");
        } else if (k == "string") {
            p.type = PropType::String;
            p.s = v;
        } else if (k == "rgb") {
            p.type = PropType::Rgb;
            std::vector<double> c = parse_numbers(ctx, n, v, "rgb value");
            if (c.size() == 1) p.rgb = Rgb(float(c[0]));
            else if (c.size() == 3) p.rgb = Rgb(float(c[0]), float(c[1]), float(c[2]));
            else throw Error(p.loc, where + ": expected 1 or 3 components, got " + quote(v));
            check_bounded(p, where, unbounded_rgb);
        }
        return p;
    }

    /// <spectrum type="srgb"><rgb name="color" value="..."/></spectrum>: Mitsuba's srgb spectrum
    /// plugin, which its RGB variants keep as the colour itself (bounded like an <rgb>).
    void parse_srgb_spectrum(const FileCtx& ctx, const pugi::xml_node& n, const std::string& where, bool unbounded_rgb,
                             Property* p) {
        if (attr(ctx, n, "type") != "srgb")
            throw Error(p->loc, where + ": unsupported spectrum plugin (supported: srgb; or a <spectrum value=...> "
                                        "constant, wavelength list or file)");
        p->type = PropType::Rgb;
        bool have_color = false;
        for (const pugi::xml_node& c : n.children()) {
            if (c.type() != pugi::node_element) continue;
            if (std::string(c.name()) != "rgb" || std::string(c.attribute("name").value()) != "color" || have_color)
                throw Error(loc(ctx, c), where + ": expects exactly one <rgb name=\"color\" value=...>");
            Property color = parse_property(ctx, c, "emitter");  // bounds are checked below, under the spectrum's name
            p->rgb = color.rgb;
            have_color = true;
        }
        if (!have_color) throw Error(p->loc, where + ": needs <rgb name=\"color\" value=...>");
        check_bounded(*p, where, unbounded_rgb);
    }

    /// <spectrum value="v"> (a constant), value="wl:v, wl:v, ..." or filename="x.spd", converted to
    /// RGB as Mitsuba 3's RGB variants do (spectrum.h): in an emitter as emission, else as a
    /// reflectance (clamped to [0, 1]) unless the name is an index of refraction.
    void parse_spectrum(const FileCtx& ctx, const pugi::xml_node& n, const std::string& parent_tag, const std::string& where,
                        Property* p) {
        p->type = PropType::Rgb;
        p->from_spectrum = true;
        const SpectrumUse use = parent_tag == "emitter" ? SpectrumUse::Emission
                                : is_unbounded_spectrum(p->name) ? SpectrumUse::Unbounded
                                                                 : SpectrumUse::Reflectance;
        if (has_attr(n, "value") == has_attr(n, "filename"))
            throw Error(p->loc, where + ": needs exactly one of \"value\" and \"filename\"");
        SampledSpectrum s;
        if (has_attr(n, "filename")) {
            std::string name = attr(ctx, n, "filename");
            SceneObject probe;
            probe.dir = ctx.dir;
            probe.search_path = search_path_;
            std::string path = probe.resolve_path(name);
            if (!is_file(path)) throw Error(p->loc, where + ": spectrum file " + quote(path, 200) + " not found");
            try {
                s = read_spectrum_file(path);
            } catch (const Error& e) {
                throw Error(p->loc, where + ": " + e.what());
            }
        } else {
            std::string v = attr(ctx, n, "value");
            if (v.find(':') == std::string::npos) {
                std::vector<double> c = parse_numbers(ctx, n, v, "spectrum value");
                if (c.size() != 1)
                    throw Error(p->loc, where + ": a constant spectrum has one value (wavelength:value pairs for a list, "
                                                "<rgb> for colours), got " + quote(v));
                p->rgb = constant_spectrum_to_rgb(c[0], use);
                return;
            }
            try {
                s = parse_spectrum_pairs(v);
            } catch (const Error& e) {
                throw Error(p->loc, where + ": " + e.what());
            }
        }
        bool clamped = false;
        p->rgb = sampled_spectrum_to_rgb(s, use, &clamped);
        if (clamped)
            warnings_->push_back(p->loc.str() + ": " + where + ": the spectrum's sRGB colour lies outside " +
                                 (use == SpectrumUse::Reflectance ? "[0, 1]" : "[0, inf)") + " and was clamped to (" +
                                 std::to_string(p->rgb.r) + ", " + std::to_string(p->rgb.g) + ", " + std::to_string(p->rgb.b) +
                                 ") as Mitsuba's RGB variants do");
    }

    /// Mitsuba's RGB variants turn an <rgb> outside an emitter into an sRGB reflectance
    /// texture, which refuses components outside [0, 1] unless the name is an IOR.
    static void check_bounded(const Property& p, const std::string& where, bool unbounded_rgb) {
        if (unbounded_rgb || is_unbounded_spectrum(p.name)) return;
        for (int c = 0; c < 3; ++c)
            if (p.rgb[c] < 0 || p.rgb[c] > 1)
                throw Error(p.loc, where + ": RGB value outside [0, 1] (Mitsuba's RGB variants refuse it outside "
                                           "emitters; use <float> with a scale, e.g. for sigma_t)");
    }

    std::shared_ptr<SceneObject> parse_object(const FileCtx& ctx, const pugi::xml_node& n, std::string* child_name, int depth) {
        check_attrs(ctx, n, {"type", "id", "name"});
        auto o = std::make_shared<SceneObject>();
        o->tag = n.name();
        o->loc = loc(ctx, n);
        o->dir = ctx.dir;
        o->search_path = search_path_;
        o->type = attr(ctx, n, "type");
        o->id = attr(ctx, n, "id", false);
        if (child_name) *child_name = name_attr(ctx, n, false);
        if (!o->id.empty()) register_id(o->loc, o->id, o);
        std::unordered_set<std::string> names;
        parse_children(ctx, n, *o, depth + 1, false, &names);
        return o;
    }

    void register_id(const SourceLoc& where, const std::string& id, const std::shared_ptr<SceneObject>& o) {
        auto it = ids_.find(id);
        if (it != ids_.end())
            throw Error(where, "duplicate id " + quote(id) + " (first defined at " + it->second->loc.str() + ")");
        ids_[id] = o;
    }

    /// Children of `parent` (the scene root or an object). Each child is parsed on its own: a
    /// problem is recorded, the child skipped and the parent marked broken.
    void parse_children(const FileCtx& ctx, const pugi::xml_node& node, SceneObject& parent, int depth, bool at_root,
                        std::unordered_set<std::string>* names = nullptr) {
        std::unordered_set<std::string> local_names;
        if (!names) names = &local_names;
        for (pugi::xml_node c : node.children()) {
            if (c.type() != pugi::node_element) continue;
            try {
                if (depth > XmlLimits::kMaxNesting)
                    throw Error(loc(ctx, c), "elements nested more than " + std::to_string(XmlLimits::kMaxNesting) +
                                                 " deep (the limit of the scene reader)");
                parse_member(ctx, c, parent, depth, at_root, *names);
            } catch (const Error& e) {
                errors_.add(e);
                parent.broken = true;
                if (depth > XmlLimits::kMaxNesting) return;  // one message per over-deep subtree
            }
        }
    }

    void parse_member(const FileCtx& ctx, const pugi::xml_node& c, SceneObject& parent, int depth, bool at_root,
                      std::unordered_set<std::string>& names) {
        std::string k = c.name();
        if (kPropertyTags.count(k)) {
            if (at_root) throw Error(loc(ctx, c), "property <" + k + "> is not allowed directly inside <scene>");
            Property p = parse_property(ctx, c, parent.tag);
            if (!names.insert(p.name).second) {
                SourceLoc first = parent.loc_of(p.name);
                throw Error(p.loc, parent.describe() + ": parameter " + quote(p.name) +
                                       " was specified more than once (first at line " + std::to_string(first.line) + ")");
            }
            parent.props.push_back(std::move(p));
        } else if (kObjectTags.count(k)) {
            Child ch;
            ch.loc = loc(ctx, c);
            try {
                ch.obj = parse_object(ctx, c, &ch.name, depth);
            } catch (const Error&) {
                parent.broken = true;
                throw;
            }
            parent.children.push_back(ch);
        } else if (k == "ref") {
            if (at_root) throw Error(loc(ctx, c), "<ref> is not allowed directly inside <scene>");
            check_attrs(ctx, c, {"id", "name"});
            Child ch;
            ch.loc = loc(ctx, c);
            ch.name = name_attr(ctx, c, false);
            std::string id = attr(ctx, c, "id");
            parent.children.push_back(ch);
            pending_.push_back({&parent, parent.children.size() - 1, id});  // forward references are fine
        } else if (k == "default") {
            check_attrs(ctx, c, {"name", "value"});
            std::string name = attr(ctx, c, "name");
            if (name.empty()) throw Error(loc(ctx, c), "<default>: empty name");
            std::string value = attr(ctx, c, "value");
            if (!params_.count(name)) params_[name] = value;
        } else if (k == "path") {
            if (!at_root) throw Error(loc(ctx, c), "<path> is only allowed directly inside <scene>");
            check_attrs(ctx, c, {"value"});
            std::string v = attr(ctx, c, "value");
            std::string d = (v.empty() || v[0] == '/') ? v : (ctx.dir == "." ? v : ctx.dir + "/" + v);
            struct stat st;
            if (::stat(d.c_str(), &st) != 0 || !S_ISDIR(st.st_mode))
                throw Error(loc(ctx, c), "<path>: folder " + quote(d, 200) + " not found");
            search_path_->insert(search_path_->begin(), d);  // Mitsuba prepends
        } else if (k == "alias") {
            check_attrs(ctx, c, {"id", "as"});
            std::string src = attr(ctx, c, "id"), dst = attr(ctx, c, "as");
            auto it = ids_.find(src);
            if (it == ids_.end())
                throw Error(loc(ctx, c), "<alias>: no object with id " + quote(src) + " was declared before this point");
            register_id(loc(ctx, c), dst, it->second);
        } else if (k == "include") {
            include(ctx, c, parent, depth, at_root, names);
        } else {
            throw Error(loc(ctx, c), "unknown element <" + clip(k) + "> inside " + parent.describe());
        }
    }

    void include(const FileCtx& ctx, const pugi::xml_node& c, SceneObject& parent, int depth, bool at_root,
                 std::unordered_set<std::string>& names) {
        check_attrs(ctx, c, {"filename"});
        SourceLoc where = loc(ctx, c);
        if (ctx.include_depth + 1 > XmlLimits::kMaxIncludeDepth)
            throw Error(where, "<include>: nested more than " + std::to_string(XmlLimits::kMaxIncludeDepth) + " deep");
        std::string name = attr(ctx, c, "filename");
        SceneObject probe;
        probe.dir = ctx.dir;
        probe.search_path = search_path_;
        std::string file = probe.resolve_path(name);
        for (const std::string& s : include_stack_)
            if (s == file) throw Error(where, "<include>: recursive inclusion of " + quote(file, 200));
        size_t budget = XmlLimits::kMaxTotalBytes - std::min(total_bytes_, XmlLimits::kMaxTotalBytes);
        FileCtx sub{file, dirname_of(file), read_xml_file(file, std::min(budget, XmlLimits::kMaxFileBytes), where, "<include>"),
                    {}, ctx.include_depth + 1};
        total_bytes_ += sub.text.size();
        hash(sub.text);
        sub.index_lines();
        pugi::xml_document doc;
        if (!load(sub, doc)) {
            parent.broken = true;
            return;
        }
        pugi::xml_node r = doc.document_element();
        bool saved_upgrade = upgrade_;
        include_stack_.push_back(file);
        try {
            if (std::string(r.name()) == "scene") {
                check_attrs(sub, r, {"version"});
                if (r.attribute("version")) upgrade_ = check_version(sub, r, r.attribute("version").value());
                parse_children(sub, r, parent, depth, at_root, &names);
            } else {
                // Mitsuba: a file whose root is an object stands for that one object
                parse_member(sub, r, parent, depth, at_root, names);
            }
        } catch (...) {
            include_stack_.pop_back();
            upgrade_ = saved_upgrade;
            throw;
        }
        include_stack_.pop_back();
        upgrade_ = saved_upgrade;
    }

    void resolve_refs() {
        for (const PendingRef& r : pending_) {
            Child& ch = r.parent->children[r.child];
            auto it = ids_.find(r.id);
            if (it == ids_.end()) {
                errors_.add(Error(ch.loc, "<ref id=" + quote(r.id) + ">: no object with this id is declared in the scene"));
                r.parent->broken = true;
                continue;
            }
            ch.obj = it->second;
        }
        // children whose reference failed are dropped (their parent is marked broken)
        std::unordered_set<SceneObject*> parents;
        for (const PendingRef& r : pending_) parents.insert(r.parent);
        for (SceneObject* p : parents)
            p->children.erase(std::remove_if(p->children.begin(), p->children.end(), [](const Child& c) { return !c.obj; }),
                              p->children.end());
    }

    /// References make the tree a graph: refuse cycles and chains deeper than kMaxNesting (the
    /// builder recurses along them), iteratively so that no input can exhaust the stack.
    void check_graph_depth(SceneObject& root) {
        std::unordered_map<const SceneObject*, int> depth_of;  // -1 = on the current path
        struct Frame { SceneObject* o; size_t next; };
        std::vector<Frame> stack;
        for (Child& top : root.children) {
            if (depth_of.count(top.obj.get())) continue;
            stack.push_back({top.obj.get(), 0});
            depth_of[top.obj.get()] = -1;
            while (!stack.empty()) {
                Frame& f = stack.back();
                if (f.next < f.o->children.size()) {
                    Child& c = f.o->children[f.next++];
                    auto it = depth_of.find(c.obj.get());
                    if (it == depth_of.end()) {
                        if (int(stack.size()) >= XmlLimits::kMaxNesting) {
                            errors_.add(Error(c.loc, "objects nested (through references) more than " +
                                                         std::to_string(XmlLimits::kMaxNesting) + " deep"));
                            f.o->broken = true;
                            c.obj = std::make_shared<SceneObject>(*c.obj);
                            c.obj->children.clear();
                            continue;
                        }
                        depth_of[c.obj.get()] = -1;
                        stack.push_back({c.obj.get(), 0});
                    } else if (it->second == -1) {
                        errors_.add(Error(c.loc, f.o->describe() + ": reference cycle through " + c.obj->describe()));
                        f.o->broken = true;
                        c.obj = std::make_shared<SceneObject>(*c.obj);
                        c.obj->children.clear();
                        c.obj->broken = true;
                    }
                } else {
                    int d = 0;
                    for (const Child& c : f.o->children) d = std::max(d, depth_of[c.obj.get()] + 1);
                    if (d >= XmlLimits::kMaxNesting) {
                        errors_.add(Error(f.o->loc, f.o->describe() + ": objects nested (through references) more than " +
                                                        std::to_string(XmlLimits::kMaxNesting) + " deep"));
                        f.o->broken = true;
                        f.o->children.clear();
                        d = 0;
                    }
                    depth_of[f.o] = d;
                    stack.pop_back();
                }
            }
        }
    }
};

}  // namespace

ParsedScene parse_scene_string(const std::string& xml, const std::string& virtual_path, const Defines& cli_defines,
                               ErrorSink* errors) {
    ErrorSink local;
    ErrorSink& sink = errors ? *errors : local;
    Parser p(cli_defines, sink);
    ParsedScene out = p.parse(xml, virtual_path);
    if (!errors) local.raise();
    return out;
}

ParsedScene parse_scene_file(const std::string& path, const Defines& cli_defines, ErrorSink* errors) {
    std::string text = read_xml_file(path, XmlLimits::kMaxFileBytes, SourceLoc{}, "cannot read scene file");
    return parse_scene_string(text, path, cli_defines, errors);
}

}  // namespace mf
