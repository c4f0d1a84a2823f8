// mfhost — Mitsuba 3 XML subset parser (see xml_scene.h).
#include "xml_scene.h"

#include <cctype>
#include <cerrno>
#include <cstdlib>
#include <fstream>
#include <set>
#include <sstream>

#include <pugixml.hpp>

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
    int line = 1;
    for (size_t i = 0; i < offset; ++i)
        if (text[i] == '\n') ++line;
    return line;
}

// ----------------------------------------------------------------------------------------------
// SceneObject accessors

std::string SceneObject::describe() const {
    std::string s = "<" + tag;
    if (!type.empty()) s += " type=\"" + type + "\"";
    if (!id.empty()) s += " id=\"" + id + "\"";
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
        throw Error(p->loc, describe() + ": parameter \"" + name + "\" is not a finite float");
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

void SceneObject::check_all_used() const {
    for (const Property& p : props)
        if (!p.used)
            throw Error(p.loc, describe() + ": unknown parameter \"" + p.name + "\" (" + prop_type_name(p.type) +
                                   ") for plugin \"" + type + "\"");
    for (const Child& c : children)
        if (!c.used)
            throw Error(c.loc, describe() + ": unexpected nested " + c.obj->describe() +
                                   (c.name.empty() ? std::string() : " (name \"" + c.name + "\")"));
}

// ----------------------------------------------------------------------------------------------
// Parser

namespace {

const std::set<std::string> kObjectTags = {"shape",   "bsdf",       "medium", "emitter", "sensor", "film",
                                           "sampler", "integrator", "rfilter", "phase"};
const std::set<std::string> kPropertyTags = {"integer", "float", "boolean", "string", "rgb",
                                             "vector",  "point", "transform", "spectrum"};

struct FileCtx {
    std::string path;  // as shown in messages
    std::string dir;
    std::string text;
};

std::string dirname_of(const std::string& path) {
    size_t p = path.find_last_of('/');
    if (p == std::string::npos) return ".";
    if (p == 0) return "/";
    return path.substr(0, p);
}

std::string join_path(const std::string& dir, const std::string& file) {
    if (file.empty() || file[0] == '/') return file;
    if (dir.empty() || dir == ".") return file;
    return dir + "/" + file;
}

bool read_text_file(const std::string& path, std::string* out) {
    std::ifstream in(path, std::ios::binary);
    if (!in) return false;
    std::ostringstream ss;
    ss << in.rdbuf();
    *out = ss.str();
    return true;
}

class Parser {
public:
    explicit Parser(const Defines& cli) {
        for (const auto& kv : cli) params_[kv.first] = kv.second;
    }

    ParsedScene parse(const std::string& text, const std::string& path) {
        FileCtx ctx{path, dirname_of(path), text};
        pugi::xml_document doc;
        load(ctx, doc);
        pugi::xml_node root = doc.document_element();
        if (std::string(root.name()) != "scene")
            throw Error(loc(ctx, root), "root element must be <scene>, found <" + std::string(root.name()) + ">");
        ParsedScene out;
        out.main_file = path;
        out.root = std::make_shared<SceneObject>();
        out.root->tag = "scene";
        out.root->loc = loc(ctx, root);
        out.root->dir = ctx.dir;
        check_attrs(ctx, root, {"version"});
        pugi::xml_attribute ver = root.attribute("version");
        if (!ver) throw Error(loc(ctx, root), "<scene> is missing the \"version\" attribute (expected 3.x.x)");
        out.version = ver.value();
        check_version(ctx, root, out.version);
        include_stack_.push_back(path);
        parse_scene_children(ctx, root, *out.root);
        return out;
    }

private:
    std::map<std::string, std::string> params_;
    std::map<std::string, std::shared_ptr<SceneObject>> ids_;
    std::vector<std::string> include_stack_;

    static SourceLoc loc(const FileCtx& ctx, const pugi::xml_node& n) {
        ptrdiff_t off = n.offset_debug();
        return SourceLoc{ctx.path, off >= 0 ? line_of_offset(ctx.text, size_t(off)) : 0};
    }

    void load(const FileCtx& ctx, pugi::xml_document& doc) {
        pugi::xml_parse_result res =
            doc.load_buffer(ctx.text.data(), ctx.text.size(), pugi::parse_default | pugi::parse_ws_pcdata_single);
        if (!res) {
            SourceLoc l{ctx.path, line_of_offset(ctx.text, size_t(std::max<ptrdiff_t>(0, res.offset)))};
            throw Error(l, std::string("malformed XML: ") + res.description());
        }
    }

    void check_version(const FileCtx& ctx, const pugi::xml_node& n, const std::string& v) {
        int major = 0, minor = 0, patch = 0;
        char tail = 0;
        if (std::sscanf(v.c_str(), "%d.%d.%d%c", &major, &minor, &patch, &tail) != 3)
            throw Error(loc(ctx, n), "invalid scene version \"" + v + "\" (expected major.minor.patch)");
        if (major != 3)
            throw Error(loc(ctx, n), "unsupported scene version \"" + v + "\": only Mitsuba 3 scenes (3.x.x) are supported");
    }

    void check_attrs(const FileCtx& ctx, const pugi::xml_node& n, std::initializer_list<const char*> allowed) {
        for (pugi::xml_attribute a : n.attributes()) {
            bool ok = false;
            for (const char* s : allowed)
                if (std::string(a.name()) == s) ok = true;
            if (!ok)
                throw Error(loc(ctx, n), "<" + std::string(n.name()) + ">: unexpected attribute \"" +
                                             std::string(a.name()) + "\"");
        }
    }

    std::string substitute(const FileCtx& ctx, const pugi::xml_node& n, const std::string& in) {
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
                throw Error(loc(ctx, n), "<" + std::string(n.name()) + ">: undefined parameter \"$" + key +
                                             "\" (declare it with <default name=\"" + key +
                                             "\" value=\"...\"/> or pass -D " + key + "=...)");
            out += it->second;
            i = j;
        }
        return out;
    }

    bool has_attr(const pugi::xml_node& n, const char* name) { return bool(n.attribute(name)); }

    std::string attr(const FileCtx& ctx, const pugi::xml_node& n, const char* name, bool required = true) {
        pugi::xml_attribute a = n.attribute(name);
        if (!a) {
            if (required)
                throw Error(loc(ctx, n), "<" + std::string(n.name()) + ">: missing attribute \"" + name + "\"");
            return std::string();
        }
        return substitute(ctx, n, a.value());
    }

    std::vector<double> parse_numbers(const FileCtx& ctx, const pugi::xml_node& n, const std::string& s,
                                      const char* what) {
        std::vector<double> out;
        const char* p = s.c_str();
        while (*p) {
            while (*p && (std::isspace((unsigned char)*p) || *p == ',')) ++p;
            if (!*p) break;
            char* end = nullptr;
            errno = 0;
            double v = std::strtod(p, &end);
            if (end == p || (*end && !std::isspace((unsigned char)*end) && *end != ','))
                throw Error(loc(ctx, n), "<" + std::string(n.name()) + ">: could not parse " + what + " \"" + s + "\"");
            if (!std::isfinite(v))
                throw Error(loc(ctx, n), "<" + std::string(n.name()) + ">: " + what + " \"" + s + "\" is not finite");
            out.push_back(v);
            p = end;
        }
        return out;
    }

    double parse_number(const FileCtx& ctx, const pugi::xml_node& n, const std::string& s) {
        std::vector<double> v = parse_numbers(ctx, n, s, "number");
        if (v.size() != 1)
            throw Error(loc(ctx, n), "<" + std::string(n.name()) + ">: expected a single number, got \"" + s + "\"");
        return v[0];
    }

    Vec3 parse_xyz(const FileCtx& ctx, const pugi::xml_node& n, double def) {
        if (has_attr(n, "value")) {
            if (has_attr(n, "x") || has_attr(n, "y") || has_attr(n, "z"))
                throw Error(loc(ctx, n), "<" + std::string(n.name()) + ">: give either value or x/y/z, not both");
            std::vector<double> v = parse_numbers(ctx, n, attr(ctx, n, "value"), "vector");
            if (v.size() == 1) return Vec3(float(v[0]));
            if (v.size() != 3)
                throw Error(loc(ctx, n), "<" + std::string(n.name()) + ">: expected 3 components in value");
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
            Mat4 step;
            if (k == "translate") {
                check_attrs(ctx, op, {"x", "y", "z", "value"});
                Vec3 v = parse_xyz(ctx, op, 0.0);
                if (has_attr(op, "value") && attr(ctx, op, "value").find_first_of(", \t") == std::string::npos)
                    throw Error(loc(ctx, op), "<translate>: value needs 3 components");
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
                step = Mat4::rotate(axis.x, axis.y, axis.z, angle);
            } else if (k == "matrix") {
                check_attrs(ctx, op, {"value"});
                std::vector<double> v = parse_numbers(ctx, op, attr(ctx, op, "value"), "matrix");
                if (v.size() == 16) {
                    for (int i = 0; i < 16; ++i) step.m[i / 4][i % 4] = v[i];
                } else if (v.size() == 9) {
                    for (int i = 0; i < 9; ++i) step.m[i / 3][i % 3] = v[i];
                } else {
                    throw Error(loc(ctx, op), "<matrix>: expected 16 (or 9) values, got " + std::to_string(v.size()));
                }
            } else if (k == "lookat") {
                check_attrs(ctx, op, {"origin", "target", "up"});
                auto vec = [&](const char* name, bool required, Vec3 def) {
                    if (!required && !has_attr(op, name)) return def;
                    std::vector<double> v = parse_numbers(ctx, op, attr(ctx, op, name), name);
                    if (v.size() != 3) throw Error(loc(ctx, op), std::string("<lookat>: ") + name + " needs 3 components");
                    return Vec3(float(v[0]), float(v[1]), float(v[2]));
                };
                Vec3 o = vec("origin", true, Vec3()), tg = vec("target", true, Vec3()), up = vec("up", false, Vec3(0, 1, 0));
                Vec3 d = tg - o;
                if (length(d) == 0) throw Error(loc(ctx, op), "<lookat>: origin and target coincide");
                if (length(cross(normalize(up), normalize(d))) < 1e-6f)
                    throw Error(loc(ctx, op), "<lookat>: up vector is parallel to the viewing direction");
                step = Mat4::look_at(o, tg, up);
            } else {
                throw Error(loc(ctx, op), "<transform>: unknown transform operation <" + k + ">");
            }
            m = step * m;  // Mitsuba: each operation is applied after the previous ones
        }
        if (!m.finite()) throw Error(loc(ctx, t), "<transform>: non-finite matrix");
        return m;
    }

    Property parse_property(const FileCtx& ctx, const pugi::xml_node& n) {
        std::string k = n.name();
        Property p;
        p.loc = loc(ctx, n);
        if (k == "transform") {
            check_attrs(ctx, n, {"name"});
            p.name = attr(ctx, n, "name");
            p.type = PropType::Transform;
            p.m = parse_transform(ctx, n);
            return p;
        }
        if (k == "vector" || k == "point") {
            check_attrs(ctx, n, {"name", "value", "x", "y", "z"});
            p.name = attr(ctx, n, "name");
            p.type = k == "vector" ? PropType::Vector : PropType::Point;
            p.v = parse_xyz(ctx, n, 0.0);
            return p;
        }
        check_attrs(ctx, n, {"name", "value"});
        p.name = attr(ctx, n, "name");
        std::string v = attr(ctx, n, "value");
        const std::string where = "<" + k + " name=\"" + p.name + "\">";
        if (k == "integer") {
            p.type = PropType::Integer;
            char* end = nullptr;
            errno = 0;
            p.i = std::strtoll(v.c_str(), &end, 10);
            if (v.empty() || *end || errno) throw Error(p.loc, where + ": could not parse integer \"" + v + "\"");
        } else if (k == "float") {
            p.type = PropType::Float;
            p.f = parse_number(ctx, n, v);
        } else if (k == "boolean") {
            p.type = PropType::Boolean;
            std::string l;
            for (char c : v) l += char(std::tolower((unsigned char)c));
            if (l == "true") p.b = true;
            else if (l == "false") p.b = false;
            else throw Error(p.loc, where + ": could not parse boolean \"" + v + "\" (expected true or false)");
        } else if (k == "string") {
            p.type = PropType::String;
            p.s = v;
        } else if (k == "rgb") {
            p.type = PropType::Rgb;
            std::vector<double> c = parse_numbers(ctx, n, v, "rgb value");
            if (c.size() == 1) p.rgb = Rgb(float(c[0]));
            else if (c.size() == 3) p.rgb = Rgb(float(c[0]), float(c[1]), float(c[2]));
            else throw Error(p.loc, where + ": expected 1 or 3 components, got \"" + v + "\"");
        } else if (k == "spectrum") {
            p.type = PropType::Rgb;
            p.from_spectrum = true;
            if (v.find(':') != std::string::npos)
                throw Error(p.loc, where + ": only a single-valued <spectrum> (a constant, e.g. value=\"0.5\") is "
                                           "supported; wavelength:value lists are not (use <rgb>)");
            std::vector<double> c = parse_numbers(ctx, n, v, "spectrum value");
            if (c.size() != 1)
                throw Error(p.loc, where + ": only a single-valued <spectrum> is supported (use <rgb> for colours)");
            p.rgb = Rgb(float(c[0]));
        }
        return p;
    }

    void add_property(SceneObject& o, Property p) {
        for (const Property& q : o.props)
            if (q.name == p.name)
                throw Error(p.loc, o.describe() + ": parameter \"" + p.name + "\" was specified more than once (first at line " +
                                       std::to_string(q.loc.line) + ")");
        o.props.push_back(std::move(p));
    }

    std::shared_ptr<SceneObject> parse_object(const FileCtx& ctx, const pugi::xml_node& n, std::string* child_name) {
        check_attrs(ctx, n, {"type", "id", "name"});
        auto o = std::make_shared<SceneObject>();
        o->tag = n.name();
        o->loc = loc(ctx, n);
        o->dir = ctx.dir;
        o->type = attr(ctx, n, "type");
        o->id = attr(ctx, n, "id", false);
        if (child_name) *child_name = attr(ctx, n, "name", false);
        for (pugi::xml_node c : n.children()) {
            if (c.type() != pugi::node_element) continue;
            parse_member(ctx, c, *o);
        }
        if (!o->id.empty()) register_id(ctx, n, o);
        return o;
    }

    void register_id(const FileCtx& ctx, const pugi::xml_node& n, const std::shared_ptr<SceneObject>& o) {
        auto it = ids_.find(o->id);
        if (it != ids_.end())
            throw Error(loc(ctx, n), "duplicate id \"" + o->id + "\" (first defined at " + it->second->loc.str() + ")");
        ids_[o->id] = o;
    }

    void parse_member(const FileCtx& ctx, const pugi::xml_node& c, SceneObject& parent) {
        std::string k = c.name();
        if (kPropertyTags.count(k)) {
            add_property(parent, parse_property(ctx, c));
        } else if (kObjectTags.count(k)) {
            Child ch;
            ch.loc = loc(ctx, c);
            ch.obj = parse_object(ctx, c, &ch.name);
            parent.children.push_back(ch);
        } else if (k == "ref") {
            check_attrs(ctx, c, {"id", "name"});
            std::string id = attr(ctx, c, "id");
            auto it = ids_.find(id);
            if (it == ids_.end())
                throw Error(loc(ctx, c), "<ref id=\"" + id + "\">: no object with this id was declared before this point");
            Child ch;
            ch.loc = loc(ctx, c);
            ch.name = attr(ctx, c, "name", false);
            ch.obj = it->second;
            parent.children.push_back(ch);
        } else if (k == "texture") {
            throw Error(loc(ctx, c), "<texture> is not supported by mfrender (use a constant <rgb> value)");
        } else if (k == "default" || k == "include") {
            throw Error(loc(ctx, c), "<" + k + "> is only allowed directly inside <scene>");
        } else {
            throw Error(loc(ctx, c), "unknown element <" + k + "> inside " + parent.describe());
        }
    }

    void parse_scene_children(const FileCtx& ctx, const pugi::xml_node& root, SceneObject& scene) {
        for (pugi::xml_node c : root.children()) {
            if (c.type() != pugi::node_element) continue;
            std::string k = c.name();
            if (k == "default") {
                check_attrs(ctx, c, {"name", "value"});
                std::string name = attr(ctx, c, "name");
                if (name.empty()) throw Error(loc(ctx, c), "<default>: empty name");
                std::string value = attr(ctx, c, "value");
                if (!params_.count(name)) params_[name] = value;
            } else if (k == "include") {
                check_attrs(ctx, c, {"filename"});
                std::string file = join_path(ctx.dir, attr(ctx, c, "filename"));
                for (const std::string& s : include_stack_)
                    if (s == file) throw Error(loc(ctx, c), "<include>: recursive inclusion of \"" + file + "\"");
                FileCtx sub{file, dirname_of(file), std::string()};
                if (!read_text_file(file, &sub.text))
                    throw Error(loc(ctx, c), "<include>: cannot read file \"" + file + "\"");
                pugi::xml_document doc;
                load(sub, doc);
                pugi::xml_node r = doc.document_element();
                if (std::string(r.name()) != "scene")
                    throw Error(loc(sub, r), "included file must have a <scene> root element");
                check_attrs(sub, r, {"version"});
                if (r.attribute("version")) check_version(sub, r, r.attribute("version").value());
                include_stack_.push_back(file);
                parse_scene_children(sub, r, scene);
                include_stack_.pop_back();
            } else if (k == "shape" || k == "bsdf" || k == "medium" || k == "emitter" || k == "sensor" ||
                       k == "integrator" || k == "ref" || k == "texture") {
                if (k == "ref") throw Error(loc(ctx, c), "<ref> is not allowed directly inside <scene>");
                parse_member(ctx, c, scene);
            } else if (kPropertyTags.count(k)) {
                throw Error(loc(ctx, c), "property <" + k + "> is not allowed directly inside <scene>");
            } else if (kObjectTags.count(k)) {
                throw Error(loc(ctx, c), "<" + k + "> must be nested inside another object (e.g. <sensor>)");
            } else {
                throw Error(loc(ctx, c), "unknown element <" + k + "> inside <scene>");
            }
        }
    }
};

}  // namespace

ParsedScene parse_scene_string(const std::string& xml, const std::string& virtual_path, const Defines& cli_defines) {
    Parser p(cli_defines);
    return p.parse(xml, virtual_path);
}

ParsedScene parse_scene_file(const std::string& path, const Defines& cli_defines) {
    std::string text;
    if (!read_text_file(path, &text)) throw Error("cannot read scene file \"" + path + "\"");
    return parse_scene_string(text, path, cli_defines);
}

}  // namespace mf
