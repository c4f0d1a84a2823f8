// Spatially varying medium parameters in scenes (issue 12): <volume>/<texture> parameters of
// macrofacet media, constvolume folding (bit-identical renders to the scalar form), the
// anisotropy matrix, <shape type="sdfgrid"> mean surfaces, mfrender --check on such scenes, and
// every refusal with its file:line. Grid files are written by the tests into MFHOST_TEST_WORK.
#include <cmath>
#include <fstream>
#include <cstdio>
#include <random>
#include <tuple>

#include "check.h"
#include "field.h"
#include "medium_fields.h"
#include "scene_builder.h"
#include "scene_util.h"
#include "sdf_grid.h"
#include "volume_io.h"
#include "xml_scene.h"

using namespace mf;

/// volpath (the path integrator ignores media, as Mitsuba's) and a 16x16, 4 spp camera.
static const char* kSensor =
    R"(<integrator type="volpath"/><sensor type="perspective"><float name="fov" value="40"/><transform name="to_world"><lookat origin="0, 0, 4" target="0, 0, 0" up="0, 1, 0"/></transform><film type="hdrfilm"><integer name="width" value="16"/><integer name="height" value="16"/><rfilter type="box"/></film><sampler type="independent"><integer name="sample_count" value="4"/></sampler></sensor><emitter type="constant"><rgb name="radiance" value="1"/></emitter>)";

/// A scene whose macrofacet medium's parameters start on line 5 (lines of `params` follow).
static std::string sphere_scene(const std::string& params, const std::string& medium = "macrofacet") {
    return "<scene version=\"3.0.0\">\n" + std::string(kSensor) + "\n<shape type=\"sphere\">\n<medium type=\"" + medium +
           "\" name=\"interior\">\n" + params + "\n</medium></shape></scene>\n";
}

struct Built {
    std::unique_ptr<Scene> scene;
    BuildReport report;
};

static Built build(const std::string& xml, bool validate_only) {
    Built b;
    ParsedScene parsed = parse_scene_string(xml, work("fields.xml"), {});
    BuildOptions o;
    o.validate_only = validate_only;
    b.scene = build_scene(parsed, o, &b.report);
    return b;
}

static void write_grid(const std::string& name, int nx, int ny, int nz, int channels, const std::vector<float>& values) {
    VolumeGridData g;
    g.nx = nx, g.ny = ny, g.nz = nz, g.channels = channels;
    g.values = values;
    g.bbox.hi = Vec3(1.0f);
    write_vol_file(work(name), g);
}

/// A 4^3 roughness grid over [-2, 2]^3 (covers a unit sphere's shell) with values in [0.2, 0.4].
static const char* kAlphaGridToWorld =
    R"(<transform name="to_world"><scale value="4"/><translate x="-2" y="-2" z="-2"/></transform>)";

static void write_alpha_grid(const std::string& name, float lo = 0.2f, float hi = 0.4f) {
    std::vector<float> v(64);
    for (int i = 0; i < 64; ++i) v[size_t(i)] = lo + (hi - lo) * float(i) / 63.0f;
    write_grid(name, 4, 4, 4, 1, v);
}

static std::string grid_volume(const std::string& param, const std::string& file, const std::string& extra = kAlphaGridToWorld) {
    return "<volume name=\"" + param + "\" type=\"gridvolume\"><string name=\"filename\" value=\"" + file + "\"/>" + extra + "</volume>";
}

// ------------------------------------------------------------------------------- constvolume
TEST_CASE(constvolume_folds_into_the_bag) {
    Built b = build(sphere_scene("<float name=\"sigma\" value=\"0.01\"/>\n"
                                 "<volume name=\"alpha\" type=\"constvolume\"><float name=\"value\" value=\"0.3\"/></volume>\n"
                                 "<volume name=\"specular_reflectance\" type=\"constvolume\"><rgb name=\"value\" value=\"0.9, 0.8, 0.7\"/></volume>"),
                    false);
    CHECK(b.scene != nullptr);
    CHECK(b.report.macrofacet.size() == 1);
    const MediumParamBag& bag = *b.report.macrofacet[0].bag;
    CHECK(!bag.fields);
    const ParamValue* a = bag.get("alpha");
    CHECK(a && a->kind == ParamValue::Kind::Float && a->f == 0.3);  // the double as written
    CHECK(a && a->loc.line == 6);
    const ParamValue* r = bag.get("specular_reflectance");
    CHECK(r && r->kind == ParamValue::Kind::Rgb && r->rgb.r == 0.9f && r->rgb.b == 0.7f);
}

TEST_CASE(constvolume_renders_identically_to_the_scalar) {
    const std::string scalar = sphere_scene("<float name=\"sigma\" value=\"0.02\"/><float name=\"alpha\" value=\"0.3\"/>"
                                            "<string name=\"material\" value=\"Au\"/>");
    const std::string volume = sphere_scene(
        "<float name=\"sigma\" value=\"0.02\"/><volume name=\"alpha\" type=\"constvolume\"><float name=\"value\" value=\"0.3\"/>"
        "</volume><string name=\"material\" value=\"Au\"/>");
    Image a = render("fields_scalar", scalar, "3"), b = render("fields_constvolume", volume, "3");
    CHECK(a.width == 16 && a.rgb.size() == b.rgb.size());
    CHECK(a.rgb == b.rgb);  // bit for bit
    double mean = 0;
    for (float v : a.rgb) mean += v;
    // the sphere is there: neither black nor the white environment alone
    CHECK(mean / double(a.rgb.size()) > 0.05 && mean / double(a.rgb.size()) < 0.97);
}

// ------------------------------------------------------------------------------- grid fields
TEST_CASE(grid_field_is_validated_checked_and_rendered) {
    write_alpha_grid("alpha.vol");
    const std::string xml = sphere_scene("<float name=\"sigma\" value=\"0.01\"/>\n" + grid_volume("alpha", "alpha.vol"));
    Built b = build(xml, true);
    CHECK(b.scene != nullptr);
    const MediumParamBag& bag = *b.report.macrofacet[0].bag;
    CHECK(bag.fields && bag.fields->fields.size() == 1);
    const Field* f = bag.fields ? bag.fields->find("alpha") : nullptr;
    CHECK(f && f->domain() == Field::Domain::Volume && f->channels() == 1 && !f->constant());
    if (f) {
        float v;
        f->eval(Vec3(-2 + 0.5f, -2 + 0.5f, -2 + 0.5f), Vec2(), &v);  // the centre of voxel (0, 0, 0)
        CHECK_NEAR(v, 0.2, 1e-6);
        ValueRange r = f->range();
        CHECK_NEAR(r.lo[0], 0.2, 1e-6);
        CHECK_NEAR(r.hi[0], 0.4, 1e-6);
        ValueRange s = f->range_segment(Vec3(-1.9f, -1.9f, -1.9f), Vec3(1, 0, 0), 0.1f);
        CHECK(s.hi[0] < 0.3f);  // local, not global
    }
    CHECK(build(xml, false).scene != nullptr);
    // the command line: --check accepts it, a render writes the image
    write_file(work("fields_grid.xml"), xml);
    CHECK(run({work("fields_grid.xml"), "--check"}) == 0);
    std::remove(work("fields_grid.exr").c_str());
    CHECK(run({work("fields_grid.xml"), "-o", work("fields_grid.exr"), "--quiet"}) == 0);
    CHECK(exists(work("fields_grid.exr")));
}

/// Mean and standard error over seeds of the mean of columns [c0, c1) of 32x32 renders.
static void column_stats(const std::string& name, const std::string& xml, int c0, int c1, double* mean, double* se) {
    const int seeds = 6;
    double sum = 0, sum2 = 0;
    for (int s = 0; s < seeds; ++s) {
        Image img = render(name, xml, std::to_string(11 + s));
        double m = 0;
        int n = 0;
        for (int y = 0; y < img.height; ++y)
            for (int x = c0; x < c1; ++x, ++n)
                for (int c = 0; c < 3; ++c) m += img.rgb[3 * (size_t(y) * img.width + x) + c] / 3.0;
        m /= n;
        sum += m, sum2 += m * m;
    }
    *mean = sum / seeds;
    *se = std::sqrt(std::max(0.0, sum2 / seeds - *mean * *mean) / (seeds - 1));
}

TEST_CASE(piecewise_constant_field_matches_the_stationary_renders_region_by_region) {
    // Issue 12: roughness 0.15 for x < 0 and 0.6 for x > 0 (a 2-voxel grid, nearest lookup) on a
    // thin gold shell: away from the step each half renders as the stationary medium of its value
    // (means over 6 seeds within 4.5 combined standard errors).
    write_grid("alpha_step.vol", 2, 1, 1, 1, {0.15f, 0.6f});
    auto scene = [](const std::string& alpha) {
        const std::string sensor =
            R"(<integrator type="volpath"/><sensor type="perspective"><float name="fov" value="40"/><transform name="to_world"><lookat origin="0, 0, 4" target="0, 0, 0" up="0, 1, 0"/></transform><film type="hdrfilm"><integer name="width" value="32"/><integer name="height" value="32"/><rfilter type="box"/></film><sampler type="independent"><integer name="sample_count" value="16"/></sampler></sensor><emitter type="constant"><rgb name="radiance" value="1"/></emitter>)";
        return "<scene version=\"3.0.0\">\n" + sensor + "\n<shape type=\"sphere\">\n<medium type=\"macrofacet\" name=\"interior\">\n"
               "<float name=\"sigma\" value=\"0.005\"/><string name=\"material\" value=\"Au\"/>" + alpha + "</medium></shape></scene>\n";
    };
    const std::string stepped = scene(grid_volume("alpha", "alpha_step.vol",
                                                  R"(<string name="filter_type" value="nearest"/><transform name="to_world"><scale value="4"/><translate x="-2" y="-2" z="-2"/></transform>)"));
    for (auto [c0, c1, alpha] : {std::tuple{2, 12, "0.15"}, std::tuple{20, 30, "0.6"}}) {
        double m_field, se_field, m_flat, se_flat;
        column_stats("fields_step", stepped, c0, c1, &m_field, &se_field);
        column_stats("fields_flat", scene(std::string("<float name=\"alpha\" value=\"") + alpha + "\"/>"), c0, c1, &m_flat, &se_flat);
        const double z = (m_field - m_flat) / std::sqrt(se_field * se_field + se_flat * se_flat + 1e-12);
        std::printf("  columns [%d, %d): field %.5f +- %.5f, stationary alpha %s %.5f +- %.5f, z %+.2f\n", c0, c1, m_field, se_field,
                    alpha, m_flat, se_flat, z);
        CHECK(std::fabs(z) < 4.5);
    }
    // and the two halves differ (the field is applied)
    double left, se_l, right, se_r;
    column_stats("fields_flat_rough", scene("<float name=\"alpha\" value=\"0.6\"/>"), 2, 12, &left, &se_l);
    column_stats("fields_step", stepped, 2, 12, &right, &se_r);
    CHECK(std::fabs(left - right) > 6 * std::sqrt(se_l * se_l + se_r * se_r));
}

TEST_CASE(texture_field_on_a_sphere) {
    const std::string xml = sphere_scene(
        "<float name=\"sigma\" value=\"0.01\"/><float name=\"alpha\" value=\"0.2\"/>\n"
        "<texture name=\"specular_reflectance\" type=\"checkerboard\"><rgb name=\"color0\" value=\"0.9\"/>"
        "<rgb name=\"color1\" value=\"0.5, 0.6, 0.7\"/></texture>");
    Built b = build(xml, true);
    const Field* f = b.report.macrofacet[0].bag->fields->find("specular_reflectance");
    CHECK(f && f->domain() == Field::Domain::Texture && f->channels() == 3);
    if (f) {
        float v[3];
        f->eval(Vec3(), Vec2(0.25f, 0.25f), v);
        CHECK(v[0] == 0.9f);
        f->eval(Vec3(), Vec2(0.75f, 0.25f), v);
        CHECK(v[0] == 0.5f && v[2] == 0.7f);
        ValueRange r = f->range_segment(Vec3(), Vec3(1, 0, 0), 1);
        CHECK(r.lo[0] == 0.5f && r.hi[0] == 0.9f);
    }
}

TEST_CASE(alpha_z_may_be_zero_and_sigma_may_vary) {
    std::vector<float> zeros(8, 0.0f), sig(8, 0.02f);
    sig[7] = 0.05f;
    write_grid("alpha_z0.vol", 2, 2, 2, 1, zeros);
    write_grid("sigma.vol", 2, 2, 2, 1, sig);
    Built b = build(sphere_scene(grid_volume("sigma", "sigma.vol") + "\n<float name=\"alpha\" value=\"0.3\"/>\n" +
                                 grid_volume("alpha_z", "alpha_z0.vol")),
                    true);
    const MediumParamBag& bag = *b.report.macrofacet[0].bag;
    CHECK(bag.fields && bag.fields->find("alpha_z") && bag.fields->find("sigma"));
    CHECK_NEAR(shell_top_bound(bag), 3 * 0.05, 1e-7);  // k sigma_max with the default k = 3
}

TEST_CASE(anisotropy_matrix) {
    // constant halves: [[2, .5, 0], [.5, 3, 0], [0, 0, 4]]: eigenvalues 2.5 -+ sqrt(0.5) and 4
    Built b = build(sphere_scene("<float name=\"sigma\" value=\"0.01\"/><float name=\"alpha\" value=\"0.3\"/>\n"
                                 "<volume name=\"anisotropy_diagonal\" type=\"constvolume\"><rgb name=\"value\" value=\"2, 3, 4\"/></volume>\n"
                                 "<volume name=\"anisotropy_offdiagonal\" type=\"constvolume\"><rgb name=\"value\" value=\"0.5, 0, 0\"/></volume>"),
                    true);
    const Field* f = b.report.macrofacet[0].bag->fields->find("anisotropy");
    CHECK(f && f->channels() == 6 && f->constant());
    if (f) {
        float s[6];
        f->eval(Vec3(), Vec2(), s);
        CHECK(s[0] == 2 && s[1] == 3 && s[2] == 4 && s[3] == 0.5f && s[4] == 0 && s[5] == 0);
        ValueRange r = f->range();
        CHECK(r.channels == 8);
        CHECK(r.lo[Field::kEigenMin] <= 2.5 - std::sqrt(0.5) && r.lo[Field::kEigenMin] > 2.5 - std::sqrt(0.5) - 1e-5);
        CHECK(r.hi[Field::kEigenMax] >= 4 && r.hi[Field::kEigenMax] < 4 + 1e-5);
    }
    // a 6-channel grid (Mitsuba's sggx layout): random SPD samples A A^T + 0.1 I; the eigenvalue
    // bounds contain the eigenvalues of interpolated matrices (checked through Gershgorin-free
    // means: x^T S x / x^T x for random x lies in [lambda_min, lambda_max])
    std::mt19937 rng(3);
    std::normal_distribution<float> n01;
    std::vector<float> v(27 * 6);
    for (int i = 0; i < 27; ++i) {
        float a[9];
        for (float& x : a) x = n01(rng);
        float* s = &v[size_t(i) * 6];
        auto dot = [&](int r, int c) { return a[3 * r] * a[3 * c] + a[3 * r + 1] * a[3 * c + 1] + a[3 * r + 2] * a[3 * c + 2]; };
        s[0] = dot(0, 0) + 0.1f, s[1] = dot(1, 1) + 0.1f, s[2] = dot(2, 2) + 0.1f, s[3] = dot(0, 1), s[4] = dot(0, 2), s[5] = dot(1, 2);
    }
    write_grid("aniso6.vol", 3, 3, 3, 6, v);
    Built g = build(sphere_scene("<float name=\"sigma\" value=\"0.01\"/><float name=\"alpha\" value=\"0.3\"/>\n" +
                                 grid_volume("anisotropy", "aniso6.vol")),
                    true);
    const Field* a6 = g.report.macrofacet[0].bag->fields->find("anisotropy");
    CHECK(a6 && !a6->constant());
    int outside = 0;
    if (a6) {
        std::uniform_real_distribution<float> u(-1.5f, 1.5f);
        for (int t = 0; t < 500; ++t) {
            Vec3 o(u(rng), u(rng), u(rng)), d = normalize(Vec3(u(rng), u(rng), u(rng)));
            ValueRange r = a6->range_segment(o, d, 0.5f);
            for (int k = 0; k < 16; ++k) {
                float s[6];
                a6->eval(o + d * (0.5f * k / 15.0f), Vec2(), s);
                float x[3] = {n01(rng), n01(rng), n01(rng)};
                double num = s[0] * x[0] * x[0] + s[1] * x[1] * x[1] + s[2] * x[2] * x[2] +
                             2 * (s[3] * x[0] * x[1] + s[4] * x[0] * x[2] + s[5] * x[1] * x[2]);
                double rayleigh = num / (x[0] * x[0] + x[1] * x[1] + x[2] * x[2]);
                if (rayleigh < r.lo[Field::kEigenMin] - 1e-4 || rayleigh > r.hi[Field::kEigenMax] + 1e-4) ++outside;
                for (int c = 0; c < 6; ++c)
                    if (s[c] < r.lo[c] - 1e-5f || s[c] > r.hi[c] + 1e-5f) ++outside;
            }
        }
    }
    CHECK(outside == 0);
}

// ------------------------------------------------------------------------------- sdfgrid
/// A sphere of radius 0.3 about the unit cube's centre, as signed distances in unit-cube units,
/// on n^3 nodes (times `scale`: a non-distance when != 1).
static void write_sphere_sdf(const std::string& name, int n, float scale = 1.0f, int channels = 1) {
    std::vector<float> v;
    for (int k = 0; k < n; ++k)
        for (int j = 0; j < n; ++j)
            for (int i = 0; i < n; ++i) {
                float x = float(i) / float(n - 1) - 0.5f, y = float(j) / float(n - 1) - 0.5f, z = float(k) / float(n - 1) - 0.5f;
                for (int c = 0; c < channels; ++c) v.push_back(scale * (std::sqrt(x * x + y * y + z * z) - 0.3f));
            }
    write_grid(name, n, n, n, channels, v);
}

static std::string sdf_scene(const std::string& file, const std::string& params, const std::string& to_world,
                             const std::string& interior = "<medium type=\"macrofacet\" name=\"interior\">") {
    return "<scene version=\"3.0.0\">\n" + std::string(kSensor) + "\n<shape type=\"sdfgrid\">\n<string name=\"filename\" value=\"" +
           file + "\"/>" + to_world + "\n" + interior + params + "</medium></shape></scene>\n";
}

static const char* kSdfToWorld = R"(<transform name="to_world"><translate x="-0.5" y="-0.5" z="-0.5"/><scale value="2"/></transform>)";

TEST_CASE(sdfgrid_mean_surface) {
    write_sphere_sdf("sphere_sdf.vol", 17);
    const std::string xml = sdf_scene("sphere_sdf.vol", "<float name=\"sigma\" value=\"0.01\"/><float name=\"alpha\" value=\"0.3\"/>",
                                      kSdfToWorld);
    Built b = build(xml, true);
    CHECK(b.scene != nullptr && b.report.macrofacet.size() == 1);
    const auto* shape = dynamic_cast<const SdfGridShape*>(b.report.macrofacet[0].shape.get());
    CHECK(shape != nullptr);
    if (shape) {
        const SdfGrid& g = shape->grid();
        CHECK(g.nx == 17 && g.ny == 17 && g.nz == 17);
        CHECK_NEAR(g.at(8, 8, 8), -0.6, 1e-6);  // world units: 2 x (-0.3)
        CHECK_NEAR(g.spacing[0], 2.0 / 16, 1e-9);
        CHECK(g.lipschitz >= 1.0 && g.lipschitz <= 1.01 * std::sqrt(3.0));
        Aabb s = shape->bounds();  // the solid's cells: the radius-0.6 ball to within a cell
        CHECK(s.lo.x <= -0.6f && s.lo.x >= -0.6f - 0.13f && s.hi.z >= 0.6f && s.hi.z <= 0.6f + 0.13f);
        Vec3 p = g.to_world.point(Vec3(0.5f, 0.5f, 0.5f));
        CHECK_NEAR(p.x, 0.0, 1e-6);
    }
    CHECK(build(xml, false).scene != nullptr);
    write_file(work("fields_sdf.xml"), xml);
    CHECK(run({work("fields_sdf.xml"), "--check"}) == 0);
}

TEST_CASE(sdfgrid_sphere_renders_as_the_analytic_sphere) {
    // Issue 12: a sphere's distance sampled on 33^3 nodes (trilinear error below 2e-3 at the
    // surface) renders within 2 % + 4.5 SE of the analytic sphere of the same thin shell.
    write_sphere_sdf("sphere_sdf33.vol", 33);
    const std::string params = "<float name=\"sigma\" value=\"0.01\"/><float name=\"alpha\" value=\"0.3\"/><string name=\"material\" value=\"Au\"/>";
    const std::string grid = sdf_scene("sphere_sdf33.vol", params, kSdfToWorld);
    const std::string analytic = "<scene version=\"3.0.0\">\n" + std::string(kSensor) +
                                 "\n<shape type=\"sphere\"><float name=\"radius\" value=\"0.6\"/>\n<medium type=\"macrofacet\" name=\"interior\">" + params +
                                 "</medium></shape></scene>\n";
    double m_grid, se_grid, m_sphere, se_sphere;
    column_stats("fields_sdf_render", grid, 0, 16, &m_grid, &se_grid);
    column_stats("fields_sphere_render", analytic, 0, 16, &m_sphere, &se_sphere);
    std::printf("  sdfgrid %.5f +- %.5f, analytic sphere %.5f +- %.5f\n", m_grid, se_grid, m_sphere, se_sphere);
    CHECK(m_sphere > 0.05 && m_sphere < 0.97);
    CHECK(std::fabs(m_grid - m_sphere) < 0.02 * m_sphere + 4.5 * std::sqrt(se_grid * se_grid + se_sphere * se_sphere));
}

TEST_CASE(sdfgrid_refusals) {
    write_sphere_sdf("sphere_sdf.vol", 17);
    const std::string params = "<float name=\"sigma\" value=\"0.01\"/><float name=\"alpha\" value=\"0.3\"/>";
    CHECK_THROWS_WITH(build(sdf_scene("sphere_sdf.vol", "", kSdfToWorld, "<medium type=\"homogeneous\" name=\"interior\">"), true),
                      "fields.xml:3: <shape type=\"sdfgrid\">: sdfgrid is supported as the mean surface of a macrofacet medium");
    write_sphere_sdf("steep_sdf.vol", 17, 3.0f);
    CHECK_THROWS_WITH(build(sdf_scene("steep_sdf.vol", params, kSdfToWorld), true), "are not distances: between node");
    write_sphere_sdf("rgb_sdf.vol", 5, 1.0f, 3);
    CHECK_THROWS_WITH(build(sdf_scene("rgb_sdf.vol", params, kSdfToWorld), true), "has 3 channels; an SDF grid has 1");
    CHECK_THROWS_WITH(build(sdf_scene("sphere_sdf.vol", params, R"(<transform name="to_world"><scale x="2" y="1" z="1"/></transform>)"), true),
                      "to_world must be a similarity");
    // sigma 0.15: the shell's top 0.45 (world) lies beyond the faces' centres, 0.4 from the sphere
    CHECK_THROWS_WITH(build(sdf_scene("sphere_sdf.vol", "<float name=\"sigma\" value=\"0.15\"/><float name=\"alpha\" value=\"0.3\"/>",
                                      kSdfToWorld),
                            true),
                      "reaches the grid's boundary at node");
    CHECK_THROWS_WITH(build(sdf_scene("nothere_sdf.vol", params, kSdfToWorld), true),
                      "fields.xml:4: <shape type=\"sdfgrid\">: parameter \"filename\" refers to a missing file");
}

// ------------------------------------------------------------------------------- refusals
TEST_CASE(field_refusals_name_file_and_line) {
    const std::string s = "<float name=\"sigma\" value=\"0.01\"/>\n";
    auto fails = [&](const std::string& params) { return build(sphere_scene(params), true); };
    write_alpha_grid("alpha.vol");
    CHECK_THROWS_WITH(fails(s + grid_volume("alpha", "nothere.vol")),
                      "fields.xml:6: <volume type=\"gridvolume\">: parameter \"filename\" refers to a missing file");
    {
        std::string bytes = read_file(work("alpha.vol"));
        write_file(work("fields_truncated.vol"), bytes.substr(0, bytes.size() - 8));
    }
    CHECK_THROWS_WITH(fails(s + grid_volume("alpha", "fields_truncated.vol")), "fields.xml:6: <volume type=\"gridvolume\">: volume file");
    CHECK_THROWS_WITH(fails(s + grid_volume("alpha", "fields_truncated.vol")), "the file is truncated");
    write_file(work("corrupt.vol"), "VOX" + read_file(work("alpha.vol")).substr(3));
    CHECK_THROWS_WITH(fails(s + grid_volume("alpha", "corrupt.vol")), "is not a Mitsuba volume");
    write_file(work("notvdb.vdb"), "garbage");
    CHECK_THROWS_WITH(fails(s + grid_volume("alpha", "notvdb.vdb", "<string name=\"grid\" value=\"alpha\"/>")),
                      "fields.xml:6: <volume type=\"gridvolume\">: cannot read OpenVDB file");
    // negative, NaN and out-of-range voxels
    std::vector<float> v(8, 0.02f);
    v[1] = -0.5f;
    write_grid("neg_sigma.vol", 2, 2, 2, 1, v);
    CHECK_THROWS_WITH(fails(grid_volume("sigma", "neg_sigma.vol") + "<float name=\"alpha\" value=\"0.3\"/>"),
                      "fields.xml:5: <volume type=\"gridvolume\"> of parameter \"sigma\": voxel (1, 0, 0) is -0.5, but sigma must be "
                      "finite and > 0");
    v[1] = std::nanf("");
    write_grid("nan_alpha.vol", 2, 2, 2, 1, v);
    CHECK_THROWS_WITH(fails(s + grid_volume("alpha", "nan_alpha.vol")), "voxel (1, 0, 0) is nan, but alpha must be finite and > 0");
    v[1] = std::numeric_limits<float>::infinity();
    write_grid("inf_len.vol", 2, 2, 2, 1, v);
    CHECK_THROWS_WITH(fails(s + grid_volume("lengthscale", "inf_len.vol")), "is inf, but lengthscale must be finite and > 0");
    v[1] = 0.0f;
    write_grid("zero_alpha.vol", 2, 2, 2, 1, v);
    CHECK_THROWS_WITH(fails(s + grid_volume("alpha", "zero_alpha.vol")), "is 0, but alpha must be finite and > 0");
    v[1] = 1.5f;
    write_grid("bright.vol", 2, 2, 2, 1, v);
    CHECK_THROWS_WITH(fails(s + "<float name=\"alpha\" value=\"0.3\"/>" + grid_volume("specular_reflectance", "bright.vol")),
                      "is 1.5, but specular_reflectance must lie in [0, 1]");
    // coverage: a grid over [0, 1]^3 does not cover a unit sphere's shell
    CHECK_THROWS_WITH(fails(s + grid_volume("alpha", "alpha.vol", "")),
                      "fields.xml:6: <medium type=\"macrofacet\">: the grid of parameter \"alpha\" does not cover the medium's region");
    // wrap_mode repeat defines every point
    Built ok = build(sphere_scene(s + grid_volume("alpha", "alpha.vol", "<string name=\"wrap_mode\" value=\"repeat\"/>")), true);
    CHECK(ok.scene != nullptr);
    // types, names, channels, duplicates
    CHECK_THROWS_WITH(fails(s + "<volume name=\"alpha\" type=\"perlin\"/>"),
                      "fields.xml:6: <volume type=\"perlin\">: unsupported volume plugin \"perlin\" (supported: constvolume, gridvolume)");
    CHECK_THROWS_WITH(fails(s + "<float name=\"alpha\" value=\"0.3\"/><volume name=\"shell_extent\" type=\"constvolume\"/>"),
                      "names parameter \"shell_extent\", which cannot vary in space");
    CHECK_THROWS_WITH(fails(s + "<volume name=\"alpha\" type=\"constvolume\"><rgb name=\"value\" value=\"0.1, 0.2, 0.3\"/></volume>"),
                      "has 3 channels, but alpha takes 1 channel (a float)");
    CHECK_THROWS_WITH(fails(s + "<float name=\"alpha\" value=\"0.3\"/>\n" + grid_volume("alpha", "alpha.vol")),
                      "parameter \"alpha\" is given twice");
    CHECK_THROWS_WITH(fails(s + grid_volume("alpha", "alpha.vol", "<string name=\"grid\" value=\"a\"/>")),
                      "parameter \"grid\" names a grid of an OpenVDB (.vdb) file");
    CHECK_THROWS_WITH(fails(s + grid_volume("alpha", "alpha.vol", "<string name=\"filter_type\" value=\"cubic\"/>")),
                      "parameter \"filter_type\" must be trilinear or nearest");
    // the anisotropy: not positive definite; halves of different layouts; texture
    CHECK_THROWS_WITH(fails(s + "<float name=\"alpha\" value=\"0.3\"/>\n"
                                "<volume name=\"anisotropy_diagonal\" type=\"constvolume\"><rgb name=\"value\" value=\"1, 1, 1\"/></volume>"
                                "<volume name=\"anisotropy_offdiagonal\" type=\"constvolume\"><rgb name=\"value\" value=\"2, 0, 0\"/></volume>"),
                      "the matrix is not positive definite: (xx, yy, zz, xy, xz, yz) = (1, 1, 1, 2, 0, 0)");
    std::vector<float> diag3(8 * 3, 1.0f), off3(27 * 3, 0.0f);
    write_grid("diag2.vol", 2, 2, 2, 3, diag3);
    write_grid("off3.vol", 3, 3, 3, 3, off3);
    CHECK_THROWS_WITH(fails(s + "<float name=\"alpha\" value=\"0.3\"/>\n" + grid_volume("anisotropy_diagonal", "diag2.vol") +
                            grid_volume("anisotropy_offdiagonal", "off3.vol")),
                      "its grid must have the layout of anisotropy_diagonal's");
    diag3[5] = -1.0f;  // voxel (1, 0, 0) zz
    write_grid("diag_bad.vol", 2, 2, 2, 3, diag3);
    CHECK_THROWS_WITH(fails(s + "<float name=\"alpha\" value=\"0.3\"/>\n" + grid_volume("anisotropy_diagonal", "diag_bad.vol")),
                      "voxel (1, 0, 0) is not positive definite");
    CHECK_THROWS_WITH(fails(s + "<float name=\"alpha\" value=\"0.3\"/>\n<texture name=\"anisotropy_diagonal\" type=\"checkerboard\"/>"),
                      "is a matrix in world space: give it as a <volume>, not a texture");
}

TEST_CASE(texture_needs_uv_on_the_mean_surface) {
    // a closed tetrahedron without texture coordinates
    write_file(work("tetra_nouv.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n");
    const std::string xml = "<scene version=\"3.0.0\">\n" + std::string(kSensor) +
                            "\n<shape type=\"obj\"><string name=\"filename\" value=\"tetra_nouv.obj\"/>\n"
                            "<medium type=\"macrofacet\" name=\"interior\"><float name=\"sigma\" value=\"0.01\"/>\n"
                            "<texture name=\"alpha\" type=\"checkerboard\"><rgb name=\"color0\" value=\"0.2\"/>"
                            "<rgb name=\"color1\" value=\"0.4\"/></texture>\n</medium></shape></scene>\n";
    CHECK_THROWS_WITH(build(xml, true), "fields.xml:5: <medium type=\"macrofacet\">: parameter \"alpha\" is a texture over the mean "
                                        "surface's uv, but <shape type=\"obj\">");
    CHECK_THROWS_WITH(build(xml, true), "has no texture coordinates");
    // a texture whose values reach 0 cannot be a roughness
    CHECK_THROWS_WITH(build(sphere_scene("<float name=\"sigma\" value=\"0.01\"/>\n<texture name=\"alpha\" type=\"checkerboard\">"
                                         "<rgb name=\"color0\" value=\"0\"/><rgb name=\"color1\" value=\"0.4\"/></texture>"),
                            true),
                      "its values reach 0, but alpha must be finite and > 0 (a scalar is the texture's luminance)");
}

TEST_MAIN()
