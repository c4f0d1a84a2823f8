// mfhost — triangle meshes and the OBJ / PLY readers (self-written).
#pragma once

#include <string>
#include <vector>

#include "math.h"

namespace mf {

struct TriMesh {
    std::vector<Vec3> p;          // positions
    std::vector<Vec3> n;          // per-vertex normals (empty if none)
    std::vector<Vec2> uv;         // per-vertex texture coordinates (empty if none)
    std::vector<uint32_t> idx;    // 3 indices per triangle
    /// Mitsuba's mesh attributes read from PLY files: "vertex_color" (per vertex, from the r, g, b
    /// properties) and "face_color" (per face, after triangulation one value per triangle).
    struct Attribute {
        std::string name;
        bool per_face = false;
        std::vector<Rgb> values;
    };
    std::vector<Attribute> attributes;
    const Attribute* attribute(const std::string& name) const {
        for (const Attribute& a : attributes)
            if (a.name == name) return &a;
        return nullptr;
    }
    size_t num_triangles() const { return idx.size() / 3; }
    void transform(const Mat4& m);  // positions, normals (inverse transpose), flips winding if det < 0
    void compute_vertex_normals();  // angle-weighted smooth normals from the winding
    /// Split every triangle into its own vertices and drop normals (Mitsuba's face_normals).
    void make_face_normals();
    void flip_normals();            // reverse winding and negate normals
};

/// Read a Wavefront OBJ file: v / vt / vn / f (polygons fan-triangulated, negative indices).
/// Other statements (o, g, s, usemtl, mtllib, l, p, ...) are ignored. Throws mf::Error whose
/// message names the file and line on malformed content.
TriMesh load_obj(const std::string& path);
/// Read a PLY file (ascii or binary_little_endian 1.0): vertex x y z [nx ny nz] [u v | s t |
/// texture_u texture_v], face vertex_indices (or vertex_index) lists; polygons fan-triangulated.
TriMesh load_ply(const std::string& path);
/// Read shape `shape_index` of a Mitsuba serialized file (zlib-compressed, versions 3 and 4).
/// *face_normals is set when the file asks for flat faces (its normals are then dropped).
TriMesh load_serialized(const std::string& path, int shape_index, bool* face_normals);

}  // namespace mf
