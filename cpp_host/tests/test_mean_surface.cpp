// The mean surfaces mfrender hands to the library (mean_surface.h), checked through the C ABI
// against geometry computed here. Tolerances:
//  * tessellated unit sphere vs the analytic sphere: the mesh is inscribed, so
//    |f_mesh − f_exact| <= 1 − cos(δ) (sagitta, δ = the largest angular edge length); the frame
//    normal (interpolated vertex normals) agrees with the radial direction within δ;
//  * the canonical cube placed by a similarity transform vs the exact box distance: both exact,
//    equal up to float rounding of the vertices (1e-5);
//  * zero-area triangles must not change the result (same tolerances);
//  * a sphere's tangent is Mitsuba's dp/du = pole × (p − c) (the seam-free azimuthal direction);
//  * an open mesh is refused with a message, and so is a shape that cannot be a mean surface.
#include <macrofacet.h>

#include <random>

#include "check.h"
#include "mean_surface.h"
#include "scene_builder.h"
#include "shape.h"

using namespace mf;

static Vec3 rand_point(std::mt19937& rng, float r) {
    std::uniform_real_distribution<float> U(-r, r);
    return Vec3(U(rng), U(rng), U(rng));
}

static void check_sphere(TriMesh m, double sagitta, double delta, const char* label) {
    MeshShape shape(std::move(m), "obj");
    auto s = MeanSurface::of(shape);
    std::mt19937 rng(7);
    int bad_f = 0, bad_sign = 0, bad_normal = 0, n = 4000;
    double worst = 0;
    for (int i = 0; i < n; ++i) {
        Vec3 p = rand_point(rng, 2.0f);
        Vec3 normal;
        double f = s->eval(p, &normal, nullptr), exact = length(p) - 1.0;
        double err = std::fabs(f - exact);
        worst = std::max(worst, err);
        if (err > sagitta + 1e-6) ++bad_f;
        if (std::fabs(exact) > sagitta + 1e-6 && (f > 0) != (exact > 0)) ++bad_sign;
        if (dot(normal, normalize(p)) < std::cos(delta) - 1e-6 || std::fabs(length(normal) - 1.0f) > 1e-5f) ++bad_normal;
    }
    CHECK_MSG(bad_f == 0, std::string(label) + ": distance outside the sagitta bound, worst " + std::to_string(worst));
    CHECK_MSG(bad_sign == 0, std::string(label) + ": wrong sign");
    CHECK_MSG(bad_normal == 0, std::string(label) + ": frame normal off");
    for (int i = 0; i < 500; ++i) {  // just off the surface: sign from pseudo-normals
        Vec3 d = normalize(rand_point(rng, 1.0f));
        double out = s->eval(d * float(1.0 + 2 * sagitta + 1e-4), nullptr, nullptr);
        double in = s->eval(d * float(1.0 - 2 * sagitta - 1e-4), nullptr, nullptr);
        if (!(out > 0) || !(in < 0)) ++bad_sign;
    }
    CHECK_MSG(bad_sign == 0, std::string(label) + ": near-surface sign");
}

TEST_CASE(mesh_matches_sphere_within_sagitta) {
    const int rings = 48, segs = 96;
    TriMesh m = make_sphere_mesh(rings, segs);
    m.compute_vertex_normals();
    double delta = std::max(M_PI / rings, 2 * M_PI / segs);
    check_sphere(m, 1.0 - std::cos(delta), delta, "sphere");
}

TEST_CASE(zero_area_triangles_change_nothing) {
    const int rings = 32, segs = 64;
    TriMesh m = make_sphere_mesh(rings, segs);
    m.compute_vertex_normals();
    std::vector<uint32_t> idx = m.idx;
    for (size_t t = 0; t < m.num_triangles(); t += 5) {
        uint32_t a = m.idx[3 * t], b = m.idx[3 * t + 1];
        idx.insert(idx.end(), {a, a, b, a, b, b});  // repeated vertices: zero area
    }
    m.idx = idx;
    double delta = std::max(M_PI / rings, 2 * M_PI / segs);
    check_sphere(m, 1.0 - std::cos(delta), delta, "sphere+degenerate");
}

/// The exact signed distance of the box [-h, h]^3.
static double box_sdf(const Vec3& p, double h) {
    double q[3] = {std::fabs(p.x) - h, std::fabs(p.y) - h, std::fabs(p.z) - h};
    double out = 0, in = std::max(q[0], std::max(q[1], q[2]));
    for (double c : q) out += std::max(c, 0.0) * std::max(c, 0.0);
    return in > 0 ? std::sqrt(out) : in;
}

TEST_CASE(transformed_cube_is_the_exact_box) {
    const char* xml = R"(<scene version="3.0.0">
      <sensor type="perspective"><float name="fov" value="30"/></sensor>
      <shape type="cube"><transform name="to_world"><scale value="1.7"/><rotate x="0.48" y="0.6" z="0.64" angle="33"/>
        <translate x="0.3" y="-1" z="2"/></transform></shape>
    </scene>)";
    auto scene = build_scene(parse_scene_string(xml, "t.xml", {}), BuildOptions(), nullptr);
    const Shape& cube = *scene->shapes().at(0);
    auto s = MeanSurface::of(cube);
    // Mitsuba's order: each operation left-multiplies.
    Mat4 to_world = Mat4::translate(0.3, -1, 2) * Mat4::rotate(0.48, 0.6, 0.64, 33) * Mat4::scale(1.7, 1.7, 1.7);
    Mat4 to_local = to_world.inverse();
    std::mt19937 rng(11);
    int bad = 0;
    double worst = 0;
    for (int i = 0; i < 4000; ++i) {
        Vec3 p = rand_point(rng, 4.0f) + Vec3(0.3f, -1, 2);
        double exact = 1.7 * box_sdf(to_local.point(p), 1.0), f = s->eval(p, nullptr, nullptr);
        worst = std::max(worst, std::fabs(f - exact));
        if (std::fabs(f - exact) > 1e-5) ++bad;
    }
    CHECK_MSG(bad == 0, "cube vs box distance: " + std::to_string(bad) + " mismatches, worst " + std::to_string(worst));
}

TEST_CASE(sphere_tangent_is_mitsubas_dpdu) {
    // A sphere rotated so that its object +z (the pole of Mitsuba's u) is `pole`.
    const Vec3 c(1, 0.5f, -2), pole = normalize(Vec3(0.3f, -0.2f, 1));
    const Vec3 axis = cross(Vec3(0, 0, 1), pole);
    const Mat4 rot = Mat4::rotate(axis.x, axis.y, axis.z, std::acos(double(pole.z)) * 180.0 / M_PI);
    SphereShape sphere(c, 2.0f, false, rot);
    CHECK_NEAR(dot(sphere.pole(), pole), 1, 1e-6);
    auto s = MeanSurface::of(sphere);
    std::mt19937 rng(5);
    for (int i = 0; i < 200; ++i) {
        Vec3 p = c + rand_point(rng, 3.0f), normal, tangent;
        double f = s->eval(p, &normal, &tangent);
        CHECK_NEAR(f, length(p - c) - 2.0, 1e-5);
        Vec3 dpdu = cross(pole, p - c);
        CHECK_NEAR(length(cross(normalize(tangent), normalize(dpdu))), 0, 1e-5);
        CHECK(dot(tangent, dpdu) > 0);
        CHECK_NEAR(dot(normal, normalize(p - c)), 1, 1e-6);
    }
    SphereShape flipped(c, 2.0f, true, rot);  // inward normals: the outside is the interior
    CHECK_NEAR(MeanSurface::of(flipped)->eval(c, nullptr, nullptr), 2.0, 1e-6);
}

TEST_CASE(sphere_may_enter_is_false_only_where_no_chord_lies_ahead) {
    // Li skips the media of a ray that may enter no superposed region: wherever chord() finds a
    // part of the half-line t > 0 inside, may_enter must be true. Origins inside, near and far
    // outside; half the rays aimed at the sphere.
    const Vec3 c(0.5f, -1, 2);
    SphereShape sphere(c, 1.5f, false, Mat4());
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> u(-1, 1);
    int ahead = 0, skipped = 0;
    for (int i = 0; i < 20000; ++i) {
        const Vec3 o = c + rand_point(rng, i % 3 == 0 ? 1.6f : 6.0f);
        const Vec3 d = i % 2 ? normalize(Vec3(u(rng), u(rng), u(rng))) : normalize(c + rand_point(rng, 1.4f) - o);
        const double radius = 1.5 * (1 + 1e-4);
        double t0, t1;
        const bool lies_ahead = sphere.chord(o, d, radius, &t0, &t1) && t1 > 0;
        const bool may = sphere.may_enter(o, d, radius);
        ahead += lies_ahead;
        skipped += !may;
        CHECK_MSG(may || !lies_ahead, "a chord ahead from " + std::to_string(o.x) + ", " + std::to_string(o.y) + ", " + std::to_string(o.z));
    }
    // Not vacuous: both kinds of ray are common.
    CHECK_MSG(ahead > 5000 && skipped > 5000, std::to_string(ahead) + " rays with a chord ahead, " + std::to_string(skipped) + " skipped");
}

TEST_CASE(open_meshes_are_refused) {
    MeshShape rect(make_rectangle_mesh(), "rectangle");
    bool threw = false;
    try {
        MeanSurface::of(rect);
    } catch (const Error& e) {
        threw = std::string(e.what()).find("not closed") != std::string::npos;
    }
    CHECK_MSG(threw, "an open rectangle must be refused as a mean surface");
}

TEST_MAIN()
