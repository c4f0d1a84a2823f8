// mfhost — Mitsuba 3 XML scene-description subset: parsing into a generic object tree.
//
// The parser resolves <default>/$name substitution, -D overrides, <include>, <path>, <alias>,
// <ref> (forward references included) and id bookkeeping, upgrades pre-2.0 scenes in memory as
// Mitsuba does, and turns property elements into typed Property values (transforms composed in
// Mitsuba's order, spectra converted to RGB as Mitsuba's RGB variants do). It does not know about
// plugins; scene_builder.cpp interprets the tree and reports every property or child that no
// plugin consumed as an "unknown parameter" error.
//
// Every problem is reported (up to ErrorSink::kMaxErrors), each with its file:line; an element
// with a problem is skipped and marked `broken` so that the builder does not report its
// consequences again. Resource limits (XmlLimits) keep hostile input bounded: nesting depth,
// file and total size, include depth, substituted value length; parse time is linear in the
// input size.
#pragma once

#include <map>
#include <memory>
#include <string>
#include <vector>

#include "error.h"
#include "math.h"

namespace mf {

/// Resource limits of the scene reader (stated in `mfrender --help`).
struct XmlLimits {
    static constexpr int kMaxNesting = 64;                      // elements and references, any path
    static constexpr int kMaxIncludeDepth = 15;                  // as Mitsuba's MI_XML_INCLUDE_MAX_RECURSION
    static constexpr size_t kMaxFileBytes = size_t(64) << 20;    // one XML file (regular files only)
    static constexpr size_t kMaxTotalBytes = size_t(256) << 20;  // all XML files of one scene
    static constexpr size_t kMaxValueBytes = size_t(1) << 20;    // an attribute after $substitution
};

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
    bool from_spectrum = false;  // an <rgb> obtained from a <spectrum>
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
    std::shared_ptr<const std::vector<std::string>> search_path;  // <path> folders + scene dir, in order
    SourceLoc loc;
    bool broken = false;  // a problem inside it was already reported: the builder skips it quietly
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
    /// The child with this tag and name (a nested element's or a <ref>'s "name"), marked used.
    const Child* child_named(const std::string& tag, const std::string& name) const;
    /// Throws mf::Error (an ErrorList if several) for every property or child not consumed.
    void check_all_used() const;
    /// Resolve a file name as Mitsuba's file resolver does: absolute, else the <path> folders
    /// (latest first), the main scene's folder, this element's file's folder, the working
    /// directory. Returns the first candidate that exists (else the name joined to `dir`).
    std::string resolve_path(const std::string& name) const;
};

struct ParsedScene {
    std::shared_ptr<SceneObject> root;  // tag "scene"; its children are the top-level objects
    std::string main_file;
    std::string version;
    bool upgraded = false;  // a pre-2.0.0 scene upgraded in memory (camelCase names etc.)
    uint64_t content_hash = 0;  // FNV-1a of every XML file read and the -D values (shard checks)
    /// What Mitsuba accepts with a warning (e.g. a spectrum clamped to [0, 1]), "file:line: ...".
    std::vector<std::string> warnings;
};

using Defines = std::vector<std::pair<std::string, std::string>>;

/// Parse a scene file. `cli_defines` are the -D name=value pairs (they override <default>).
/// Without `errors`, throws every problem found (mf::Error, or mf::ErrorList if several); with
/// it, adds them there and returns what could be read (broken elements marked).
ParsedScene parse_scene_file(const std::string& path, const Defines& cli_defines, ErrorSink* errors = nullptr);
/// Parse from memory (tests, fuzzing). `virtual_path` is used in messages and to resolve files.
ParsedScene parse_scene_string(const std::string& xml, const std::string& virtual_path, const Defines& cli_defines,
                               ErrorSink* errors = nullptr);

/// Line number (1-based) of a byte offset in a text buffer.
int line_of_offset(const std::string& text, size_t offset);

}  // namespace mf
