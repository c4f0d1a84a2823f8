// <medium type="gpis"> tests: the realization-based ground truth through the C ABI.
//
//  * white_furnace_gpis: mirror crossings (material none) on a closed object in a constant
//    environment 1, rr_depth 1 (so Russian roulette runs on every reflected path): a sphere with
//    Renewal+ and Renewal memory (isotropic gpss), a Beckmann height field, and a cube (its
//    boundary is the sphere-traced level set). Image mean within 4.5 SE + 1e-3 of 1, and no pixel
//    beyond 10 per-pixel standard deviations (+1e-3). The same scenes in gold must NOT be white
//    (the blue mean over the image < 0.9): the realizations are actually hit.
//  * gpis_vs_macrofacet_gold: a gold gpss sphere (sigma = 0.02 r/0.7, alpha = 0.5) in the
//    constant environment, gpis (Renewal+) vs macrofacet: the image means agree within 2 % per
//    channel. This is a sanity bound on the *model* difference (measured: ~0.2 %), not noise.
//  * shadow_rays: PathIntegrator::shadow_transmittance across a gpis sphere: a ray through the
//    centre is always blocked, a ray outside the band never, a ray through the band only
//    (grazing the mean surface) sometimes (0 < mean T < 1, N = 2000).
//  * determinism_gpis: a floor, an area light, a gold gpis sphere: bit-identical EXR for the same
//    seed with 1 and 2 threads; a different seed gives a different image.
//  * gpis_field_plumbing: a host field built here (GpisField) reaches the library: a field that
//    sets nothing gives bit-identical hits; a field whose sigma steps across x = 0 widens the band
//    to 6 sigma_max, reports its sigma at the hits, and halves the reflection where its
//    reflectance scale is one half; a failing field and a field without callbacks throw.
#include <cstring>
#include <vector>

#include "check.h"
#include "integrator.h"
#include "mean_surface.h"
#include "medium_gpis.h"
#include "scene_builder.h"
#include "scene_util.h"
#include "shape.h"

using namespace mf;

static std::string env_scene(const std::string& object, int spp, int w = 24) {
    return furnace_scene(object, spp, 1, 30.0f, w);
}

static std::string gpis_object(const std::string& type, const std::string& params, const std::string& material,
                               const std::string& shape = "<shape type=\"sphere\"><float name=\"radius\" value=\"0.7\"/>") {
    return "<medium type=\"" + type + "\" id=\"g\">" + params + "<string name=\"material\" value=\"" + material +
           "\"/></medium>" + shape + "<ref name=\"interior\" id=\"g\"/></shape>";
}

static void furnace(const std::string& name, const std::string& params, const std::string& shape) {
    Image img = render("gpis_furnace_" + name, env_scene(gpis_object("gpis", params, "none", shape), 16));
    Stats s = check_furnace(name, img, 1.0, 1e-3);
    Image au = render("gpis_furnace_au_" + name, env_scene(gpis_object("gpis", params, "Au", shape), 4));
    Stats sa = stats(au, 1.0);
    CHECK_MSG(sa.mean[2] < 0.9, name + ": a gold gpis is not visible (blue mean " + std::to_string(sa.mean[2]) + ")");
    std::printf("  %-22s mean %.5f %.5f %.5f  se %.5f  max |dev| %.4f   (gold: blue mean %.3f)\n", name.c_str(), s.mean[0],
                s.mean[1], s.mean[2], s.se[0], s.maxdev, sa.mean[2]);
}

static const char* kSphere = "<shape type=\"sphere\"><float name=\"radius\" value=\"0.7\"/>";

TEST_CASE(white_furnace_gpis) {
    furnace("renewal_plus", R"(<float name="sigma" value="0.02"/><string name="distribution" value="gpss"/><float name="alpha" value="0.5"/>)", kSphere);
    furnace("renewal", R"(<float name="sigma" value="0.02"/><string name="distribution" value="gpss"/><float name="alpha" value="0.5"/><string name="memory" value="renewal"/>)", kSphere);
    furnace("beckmann", R"(<float name="sigma" value="0.01"/><string name="distribution" value="beckmann"/><float name="alpha" value="0.3"/>)", kSphere);
    furnace("cube", R"(<float name="sigma" value="0.02"/><string name="distribution" value="gpss"/><float name="alpha" value="0.6"/>)",
            R"(<shape type="cube"><transform name="to_world"><scale value="0.45"/><rotate x="1" y="1" angle="35"/></transform>)");
}

TEST_CASE(gpis_vs_macrofacet_gold) {
    const char* params = R"(<float name="sigma" value="0.02"/><string name="distribution" value="gpss"/><float name="alpha" value="0.5"/>)";
    Image g = render("gpis_gold_g", env_scene(gpis_object("gpis", params, "Au"), 32, 32));
    Image m = render("gpis_gold_m", env_scene(gpis_object("macrofacet", params, "Au"), 32, 32));
    Stats sg = stats(g, 1.0), sm = stats(m, 1.0);
    for (int c = 0; c < 3; ++c) {
        double rel = sm.mean[c] / sg.mean[c] - 1;
        CHECK_MSG(std::fabs(rel) < 0.02, "channel " + std::to_string(c) + ": macrofacet/gpis - 1 = " + std::to_string(rel));
        std::printf("  channel %d: gpis %.5f (se %.5f)  macrofacet %.5f (se %.5f)  rel %+.4f\n", c, sg.mean[c], sg.se[c],
                    sm.mean[c], sm.se[c], rel);
    }
}

TEST_CASE(shadow_rays) {
    std::string xml = env_scene(gpis_object("gpis", R"(<float name="sigma" value="0.02"/><string name="distribution" value="gpss"/><float name="alpha" value="0.5"/>)", "none"), 1);
    auto scene = build_scene(parse_scene_string(xml, "shadow.xml", {}), BuildOptions(), nullptr);
    const GpisMedium* g = nullptr;
    for (const auto& m : scene->media)
        if (m->as_gpis()) g = m->as_gpis();
    CHECK(g != nullptr);
    if (!g) return;
    CHECK_NEAR(g->envelope(), 6 * 0.02, 1e-9);  // default shell_extent 6
    PathIntegrator integ(*scene);
    auto mean_T = [&](float b) {
        double sum = 0;
        const int N = 2000;
        for (int i = 0; i < N; ++i) {
            Sampler s(17, uint64_t(i), 0);
            sum += integ.shadow_transmittance(Vec3(b, 0.0f, 3.0f), Vec3(0, 0, -1), kInf, nullptr, s).r;
        }
        return sum / N;
    };
    double t_centre = mean_T(0.0f), t_out = mean_T(0.7f + 0.13f), t_graze = mean_T(0.7f + 0.01f);
    CHECK_MSG(t_centre == 0.0, "through the centre: mean T " + std::to_string(t_centre));
    CHECK_MSG(t_out == 1.0, "outside the band: mean T " + std::to_string(t_out));
    CHECK_MSG(t_graze > 0.0 && t_graze < 1.0, "grazing the band: mean T " + std::to_string(t_graze));
    std::printf("  shadow T: centre %.3f, grazing (b = r + sigma/2) %.3f, outside %.3f\n", t_centre, t_graze, t_out);
}

static const char* kDetScene = R"(
    <shape type="rectangle"><transform name="to_world"><scale value="3"/><translate z="-0.8"/></transform>
      <bsdf type="diffuse"><rgb name="reflectance" value="0.6, 0.5, 0.4"/></bsdf></shape>
    <medium type="gpis" id="g"><float name="sigma" value="0.03"/><string name="distribution" value="gpss"/>
      <float name="alpha" value="0.5"/><string name="material" value="Au"/></medium>
    <shape type="sphere"><float name="radius" value="0.5"/><ref name="interior" id="g"/></shape>
    <shape type="rectangle"><transform name="to_world"><scale value="0.5"/><lookat origin="0, 1.5, 2" target="0, 0, 0" up="0, 0, 1"/></transform>
      <emitter type="area"><rgb name="radiance" value="5"/></emitter></shape>
    <emitter type="constant"><rgb name="radiance" value="0.3"/></emitter></scene>)";

TEST_CASE(determinism_gpis) {
    write_file(work("gpis_det.xml"), "<scene version=\"3.0.0\"><integrator type=\"volpath\"/>" + camera(3.5f, 40.0f, 32, 24, 4) + kDetScene);
    const std::string a = work("gpis_det_a.exr"), b = work("gpis_det_b.exr"), c = work("gpis_det_c.exr"), d = work("gpis_det_d.exr");
    CHECK(run({work("gpis_det.xml"), "-o", a, "--quiet", "--seed", "9", "--threads", "2"}) == 0);
    CHECK(run({work("gpis_det.xml"), "-o", b, "--quiet", "--seed", "9", "--threads", "2"}) == 0);
    CHECK(run({work("gpis_det.xml"), "-o", c, "--quiet", "--seed", "9", "--threads", "1"}) == 0);
    CHECK(run({work("gpis_det.xml"), "-o", d, "--quiet", "--seed", "10", "--threads", "2"}) == 0);
    std::string fa = read_file(a);
    CHECK(!fa.empty());
    CHECK(fa == read_file(b));
    CHECK(fa == read_file(c));
    CHECK(fa != read_file(d));
}

namespace {

/// A host field: sigma 0.01 for x < 0 and 0.03 (with a reflectance scale of one half) for
/// x >= 0 (mode 0), nothing set (mode 1), a failure (mode 2). Counts its calls (the traces here
/// run on one thread).
struct StepField {
    int mode = 0;
    int calls = 0;
};

extern "C" int32_t step_field_at(void* user_data, mf_vec3 p, const mf_surface_point*, mf_local_params* out) {
    auto* field = static_cast<StepField*>(user_data);
    ++field->calls;
    std::memset(out, 0, sizeof *out);
    if (field->mode == 2) return 3;
    if (field->mode == 0) {
        out->set = MF_LOCAL_SIGMA;
        out->sigma = p.x < 0 ? 0.01 : 0.03;
        if (p.x >= 0) {
            out->set |= MF_LOCAL_REFLECTANCE_SCALE;
            out->reflectance_scale = mf_rgb{0.5, 0.5, 0.5};
        }
    }
    return 0;
}

extern "C" int32_t step_field_bounds(void*, mf_vec3, mf_vec3, double, mf_param_bounds* out) {
    out->set = MF_LOCAL_SIGMA;
    out->sigma_lo = 0.01, out->sigma_hi = 0.03, out->alpha_lo = out->alpha_hi = 0;
    return 0;
}

MediumParamBag gold_gpis_bag() {
    MediumParamBag bag;
    bag.type = "gpis";
    bag.id = "g";
    auto number = [](double x) {
        ParamValue v;
        v.kind = ParamValue::Kind::Float;
        v.f = x;
        return v;
    };
    ParamValue au;
    au.kind = ParamValue::Kind::String;
    au.s = "Au";
    bag.params = {{"sigma", number(0.02)}, {"alpha", number(0.5)}, {"material", au}};
    return bag;
}

}  // namespace

TEST_CASE(gpis_field_plumbing) {
    SphereShape sphere(Vec3(0, 0, 0), 0.5f, false);
    auto surface = MeanSurface::of(sphere);
    const MediumParamBag bag = gold_gpis_bag();
    StepField own_data{1, 0}, step_data{0, 0}, failing_data{2, 0};
    const GpisField own{{step_field_at, step_field_bounds, 0.0}, &own_data};
    const GpisField stepped{{step_field_at, step_field_bounds, 0.03}, &step_data};
    const GpisField failing{{step_field_at, step_field_bounds, 0.03}, &failing_data};
    auto plain = create_gpis_medium(bag, surface);
    auto through_own = create_gpis_medium(bag, surface, &own);
    auto varying = create_gpis_medium(bag, surface, &stepped);
    CHECK_NEAR(plain->envelope(), 6 * 0.02, 1e-12);
    CHECK_NEAR(through_own->envelope(), 6 * 0.02, 1e-12);
    CHECK_NEAR(varying->envelope(), 6 * 0.03, 1e-12);

    // Nothing set: the same realizations, bit for bit.
    const Vec3 down(0, 0, -1);
    int identical = 0;
    for (uint64_t seed = 0; seed < 50; ++seed) {
        const Vec3 o(0.1f, 0.05f, 1.0f);
        GpisHit a, b;
        const bool ha = plain->trace(o, down, kInf, GpisStart(), seed, &a), hb = through_own->trace(o, down, kInf, GpisStart(), seed, &b);
        identical += ha && hb && a.t == b.t && std::memcmp(a.gradient, b.gradient, sizeof a.gradient) == 0 && b.local.set == 0;
    }
    CHECK_MSG(identical == 50, "a field that sets nothing changed " + std::to_string(50 - identical) + " of 50 hits");
    CHECK(own_data.calls > 0);

    // The stepped field: its sigma at the hits on either side, and half the reflection where
    // its reflectance scale is one half (same direction).
    int left = 0, right = 0, halved = 0;
    for (uint64_t seed = 0; seed < 40; ++seed) {
        const float x = seed % 2 ? 0.2f : -0.2f;
        GpisHit h;
        if (!varying->trace(Vec3(x, 0, 1), down, kInf, GpisStart(), seed, &h)) continue;
        const bool on_right = h.p[0] >= 0;
        left += !on_right && h.local.sigma == 0.01;
        right += on_right && h.local.sigma == 0.03;
        GpisHit unscaled = h;
        unscaled.local = mf_local_params{};
        Vec3 wi_a, wi_b;
        Rgb wa, wb;
        const Vec3 wo = h.n();
        if (varying->scatter(wo, h, &wi_a, &wa) && varying->scatter(wo, unscaled, &wi_b, &wb))
            halved += on_right ? std::fabs(wa.r - 0.5f * wb.r) < 1e-6f : wa.r == wb.r;
    }
    CHECK_MSG(left == 20 && right == 20, "local sigma at the hits: " + std::to_string(left) + " left, " + std::to_string(right) + " right of 20");
    CHECK_MSG(halved == 40, "reflectance scale applied at " + std::to_string(halved) + " of 40 hits");

    // A failing field fails the trace with the library's message; a field without callbacks is
    // refused at construction.
    auto broken = create_gpis_medium(bag, surface, &failing);
    GpisHit h;
    CHECK_THROWS_WITH(broken->trace(Vec3(0, 0, 1), down, kInf, GpisStart(), 1, &h), "returned 3");
    const GpisField incomplete{{nullptr, step_field_bounds, 0.0}, &own_data};
    CHECK_THROWS_WITH(create_gpis_medium(bag, surface, &incomplete), "both callbacks");
}

TEST_MAIN()
