// Mesh loader tests: OBJ (polygons, negative indices, v/vt/vn combinations), PLY ascii and
// binary little endian (extra properties / elements skipped), error reporting, canonical
// shapes. Positions are compared exactly or to 1e-6 (float parsing of short decimals).
#include <cstring>
#include <fstream>

#include "check.h"
#include "mesh_io.h"
#include "shape.h"

using namespace mf;

static std::string work(const std::string& name) { return std::string(MFHOST_TEST_WORK) + "/" + name; }

static void write_file(const std::string& path, const std::string& content) {
    std::ofstream f(path, std::ios::binary);
    f << content;
}

TEST_CASE(obj_polygons_and_negative_indices) {
    const std::string path = work("quad.obj");
    write_file(path, R"(# a quad and a triangle
o test
v 0 0 0
v 1 0 0
v 1 1 0
v 0 1 0
vt 0 0
vt 1 0
vt 1 1
vt 0 1
vn 0 0 1
s off
usemtl whatever
f 1/1/1 2/2/1 3/3/1 4/4/1
f -4/-4/-1 -2/-2/-1 -1/-1/-1
)");
    TriMesh m = load_obj(path);
    CHECK(m.num_triangles() == 3);       // quad -> 2, triangle -> 1
    CHECK(m.p.size() == 4);              // identical v/vt/vn triples are shared
    CHECK(m.n.size() == 4 && m.uv.size() == 4);
    CHECK_NEAR(m.p[m.idx[2]].x, 1, 0);  // fan: (1,2,3)
    CHECK_NEAR(m.p[m.idx[2]].y, 1, 0);
    CHECK(m.idx[6] == m.idx[0]);         // -4 is vertex 1
    CHECK_NEAR(m.n[0].z, 1, 0);
    // positions only, with '//' normals form
    const std::string p2 = work("tri.obj");
    write_file(p2, "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1//1 2//1 3//1\n");
    TriMesh m2 = load_obj(p2);
    CHECK(m2.num_triangles() == 1 && m2.uv.empty() && m2.n.size() == 3);
}

TEST_CASE(obj_errors) {
    const std::string path = work("bad.obj");
    write_file(path, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n");
    CHECK_THROWS_WITH(load_obj(path), "bad.obj:4: face index out of range");
    write_file(path, "v 0 0\n");
    CHECK_THROWS_WITH(load_obj(path), "bad.obj:1: malformed vertex position");
    write_file(path, "v 0 0 0\nv 1 0 0\nf 1 2\n");
    CHECK_THROWS_WITH(load_obj(path), "bad.obj:3: face with fewer than 3 vertices");
    CHECK_THROWS_WITH(load_obj(work("missing.obj")), "cannot open OBJ file");
}

template <typename T>
static void put(std::string& s, T v) {
    char b[sizeof(T)];
    std::memcpy(b, &v, sizeof(T));
    s.append(b, sizeof(T));
}

TEST_CASE(ply_ascii_and_binary_agree) {
    const float P[4][3] = {{0, 0, 0}, {2, 0, 0}, {2, 3, 0}, {0, 3, 1.5f}};
    std::string ascii =
        "ply\nformat ascii 1.0\ncomment test\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
        "property float nx\nproperty float ny\nproperty float nz\nproperty float u\nproperty float v\n"
        "element face 2\nproperty list uchar int vertex_indices\nend_header\n";
    for (int i = 0; i < 4; ++i)
        ascii += std::to_string(P[i][0]) + " " + std::to_string(P[i][1]) + " " + std::to_string(P[i][2]) + " 0 0 1 " +
                 std::to_string(i * 0.25) + " 0.5\n";
    ascii += "4 0 1 2 3\n3 0 2 3\n";
    write_file(work("a.ply"), ascii);

    std::string bin =
        "ply\nformat binary_little_endian 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
        "property uchar red\nproperty double nx\nproperty double ny\nproperty double nz\nproperty float s\nproperty float t\n"
        "element face 2\nproperty uchar flags\nproperty list uchar uint vertex_indices\n"
        "element material 1\nproperty list uchar float junk\nend_header\n";
    for (int i = 0; i < 4; ++i) {
        put<float>(bin, P[i][0]); put<float>(bin, P[i][1]); put<float>(bin, P[i][2]);
        put<uint8_t>(bin, 255);
        put<double>(bin, 0.0); put<double>(bin, 0.0); put<double>(bin, 1.0);
        put<float>(bin, float(i * 0.25)); put<float>(bin, 0.5f);
    }
    put<uint8_t>(bin, 7); put<uint8_t>(bin, 4);
    for (uint32_t k : {0u, 1u, 2u, 3u}) put<uint32_t>(bin, k);
    put<uint8_t>(bin, 7); put<uint8_t>(bin, 3);
    for (uint32_t k : {0u, 2u, 3u}) put<uint32_t>(bin, k);
    put<uint8_t>(bin, 2); put<float>(bin, 1.0f); put<float>(bin, 2.0f);
    write_file(work("b.ply"), bin);

    TriMesh a = load_ply(work("a.ply"));
    TriMesh b = load_ply(work("b.ply"));
    CHECK(a.num_triangles() == 3 && b.num_triangles() == 3);
    CHECK(a.idx == b.idx);
    CHECK(a.p.size() == 4 && b.p.size() == 4);
    for (size_t i = 0; i < 4 && i < a.p.size() && i < b.p.size(); ++i) {
        CHECK_NEAR(a.p[i].x, b.p[i].x, 1e-6);
        CHECK_NEAR(a.p[i].z, b.p[i].z, 1e-6);
        CHECK_NEAR(a.uv[i].x, b.uv[i].x, 1e-6);
        CHECK_NEAR(a.n[i].z, 1, 0);
    }
    CHECK_NEAR(b.p[3].z, 1.5, 0);

    write_file(work("c.ply"), "ply\nformat binary_big_endian 1.0\nelement vertex 0\nend_header\n");
    CHECK_THROWS_WITH(load_ply(work("c.ply")), "c.ply:2: binary_big_endian PLY files are not supported");
    write_file(work("d.ply"), "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                              "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 5\n");
    CHECK_THROWS_WITH(load_ply(work("d.ply")), "vertex index out of range");
    write_file(work("e.ply"), "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                              "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n");
    CHECK_THROWS_WITH(load_ply(work("e.ply")), "unexpected end of ASCII PLY data");
}

TEST_CASE(canonical_shapes_and_transforms) {
    TriMesh cube = make_cube_mesh();
    MeshShape cs(cube, "cube");
    CHECK_NEAR(cs.surface_area(), 24.0, 1e-4);
    // every face normal points away from the centre
    for (size_t t = 0; t < cube.num_triangles(); ++t) {
        Vec3 a = cube.p[cube.idx[3 * t]], b = cube.p[cube.idx[3 * t + 1]], c = cube.p[cube.idx[3 * t + 2]];
        CHECK(dot(cross(b - a, c - a), (a + b + c) / 3.0f) > 0);
    }
    MeshShape disk(make_disk_mesh(256), "disk");
    // polygon area = (n/2) sin(2π/n), within 1e-4 of π for n = 256
    CHECK_NEAR(disk.surface_area(), 3.14159265, 4e-4);
    // a mirroring transform keeps the winding consistent with the (transformed) normals
    TriMesh r = make_rectangle_mesh();
    r.transform(Mat4::scale(1, 1, -1));
    Vec3 n = cross(r.p[r.idx[1]] - r.p[r.idx[0]], r.p[r.idx[2]] - r.p[r.idx[0]]);
    CHECK(n.z < 0 && r.n[0].z < 0);
    r.flip_normals();
    n = cross(r.p[r.idx[1]] - r.p[r.idx[0]], r.p[r.idx[2]] - r.p[r.idx[0]]);
    CHECK(n.z > 0 && r.n[0].z > 0);
}

TEST_MAIN()
