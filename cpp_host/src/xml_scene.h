// mfhost — Mitsuba 3 XML scene-description subset: parsing into a generic object tree.
//
// The parser resolves <default>/$name substitution, -D overrides, <include>, <ref> and id
// bookkeeping, and turns property elements into typed Property values (transforms composed in
// Mitsuba's order). It does not know about plugins; scene_builder.cpp interprets the tree and
// reports every property or child that no plugin consumed as an "unknown parameter" error.
#pragma once

#include <map>
#include <memory>
#include <string>
#include <vector>

#include "error.h"
#include "math.h"

namespace mf {

enum class PropType { Integer, Float, Boolean, String, Rgb, Vector, Point, Transform };
const char* prop_type_name(PropType t);

struct Property {
    PropType type = PropType::Float;
    std::string name;
    SourceLoc loc;
    long long i = 0;
    double f = 0;
    bool b = false;
    std::string s;
    Rgb rgb;
    Vec3 v;
    Mat4 m;
    bool from_spectrum = false;  // an <rgb> obtained from a single-valued <spectrum>
    mutable bool used = false;
};

struct SceneObject;

struct Child {
    std::string name;  // "name" attribute of the nested element or of the <ref>, may be empty
    std::shared_ptr<SceneObject> obj;
    SourceLoc loc;     // where the child (or the <ref>) appears
    mutable bool used = false;
};

/// One plugin instance: <shape type="obj" id="...">…</shape>.
struct SceneObject {
    std::string tag;   // "shape", "bsdf", "medium", "emitter", "sensor", "film", "sampler", "rfilter", "integrator", "phase", "scene"
    std::string type;  // plugin type attribute
    std::string id;
    std::string dir;   // directory of the file this element came from (for relative file names)
    SourceLoc loc;
    std::vector<Property> props;
    std::vector<Child> children;

    std::string describe() const;  // e.g. <bsdf type="diffuse" id="x">

    // Typed accessors. They mark the property as used and throw mf::Error (naming the property
    // and its line) on a type mismatch or a non-finite number.
    const Property* find(const std::string& name) const;
    bool has(const std::string& name) const { return find(name) != nullptr; }
    float get_float(const std::string& name, float def) const;
    float get_float(const std::string& name) const;  // required
    long long get_int(const std::string& name, long long def) const;
    bool get_bool(const std::string& name, bool def) const;
    std::string get_string(const std::string& name, const std::string& def) const;
    std::string get_string(const std::string& name) const;  // required
    Rgb get_rgb(const std::string& name, const Rgb& def) const;  // accepts rgb, spectrum or float
    Vec3 get_vector(const std::string& name, const Vec3& def) const;
    Vec3 get_point(const std::string& name, const Vec3& def) const;
    Mat4 get_transform(const std::string& name, const Mat4& def) const;
    SourceLoc loc_of(const std::string& prop_name) const;

    /// Children with the given tag (marks them used). `name_filter` empty = any name.
    std::vector<const Child*> children_with_tag(const std::string& tag) const;
    /// Throws mf::Error for the first property or child not consumed by the plugin.
    void check_all_used() const;
};

struct ParsedScene {
    std::shared_ptr<SceneObject> root;  // tag "scene"; its children are the top-level objects
    std::string main_file;
    std::string version;
};

using Defines = std::vector<std::pair<std::string, std::string>>;

/// Parse a scene file. `cli_defines` are the -D name=value pairs (they override <default>).
ParsedScene parse_scene_file(const std::string& path, const Defines& cli_defines);
/// Parse from memory (tests). `virtual_path` is used in messages and to resolve relative files.
ParsedScene parse_scene_string(const std::string& xml, const std::string& virtual_path, const Defines& cli_defines);

/// Line number (1-based) of a byte offset in a text buffer.
int line_of_offset(const std::string& text, size_t offset);

}  // namespace mf
