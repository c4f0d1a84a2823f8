// End-to-end rendering tests (mfrender's CLI run in-process, EXR read back).
//  * White furnace: closed objects inside a constant environment of radiance 1 that neither
//    absorb nor emit render to exactly 1 in expectation. Tolerance: the image mean must be
//    within 4.5 standard errors of 1, the standard error measured from the per-pixel spread
//    (pixels are independent estimates of the same value), plus 1e-4 for float accumulation.
//  * Homogeneous slab: an absorbing slab (albedo 0) of thickness d seen along its normal has
//    transmittance exp(−σ_t d / cos θ). Tolerance: 4.5 standard errors of the image mean (for a
//    grey medium each sample is a Bernoulli(T) outcome, SE = sqrt(T(1−T)/(spp·pixels))).
//    The shadow-ray transmittance through the same slab is analytic: checked to 1e-5 relative.
//  * Determinism: same seed → bit-identical EXR files, with 1 and 2 threads alike.
//  * Light sampling: MIS, BSDF sampling alone and NEE alone render the same image (4.5 SE of the
//    pixel-wise difference), in media and on surfaces, for area, point and environment lights.
//  * Spot light: a diffuse plane lit and seen from the spot's position has the analytic radiance
//    ρ I f(θ) cos³θ / (π z²) (Mitsuba's linear falloff f); exactly 0 beyond the cutoff.
//  * Heterogeneous medium: through a grid varying along the view axis (and a chromatic constant
//    volume) the transmittance is exp(-scale ∫ sigma_t) over the volume's box only (Mitsuba's
//    extent), for camera paths (delta tracking) and shadow rays (ratio tracking): 4.5 SE.
//  * Mask: seen against an environment of 1 a black masked sheet shows 1 - opacity; a diffuse
//    plane under a directional light behind a mask gets rho E (1 - opacity) / pi in volpath
//    (shadow rays pass with the transparency) and 0 in path (visibility blocked), exactly.
//  * Projector: a diffuse plane at depth 1 facing it has radiance rho E inside the projected
//    frame (Mitsuba's inverse-importance scaling), 0 outside; the frame's aspect is the
//    bitmap's (4:2 here).
//  * Orthographic sensor: an emitting 0.6 x 0.4 rectangle fills exactly the pixels of its
//    footprint in the window x in [-1, 1], y in [-1/aspect, 1/aspect] (32x16: aspect 2).
//  * direct = path with max_depth 2 (bit-identical), moment(X) = X (bit-identical); refusals.
//  * Default BSDF: an area light without <bsdf> reflects nothing (Mitsuba: black diffuse): exactly
//    its radiance under an environment; a plain shape without one is diffuse 0.5.
#include <unistd.h>

#include <cstdint>
#include <vector>

#include "check.h"
#include "bsdf.h"
#include "integrator.h"
#include "render.h"
#include "scene_builder.h"
#include "scene_util.h"
#include "texture.h"

using namespace mf;

static void furnace(const std::string& name, const std::string& object, int spp, double expected = 1.0) {
    Image img = render(name, furnace_scene(object, spp, 3, 36.0f));
    Stats s = check_furnace(name, img, expected, 1e-4);
    std::printf("  %s: mean %.5f %.5f %.5f, se %.5f, max |dev| %.3f\n", name.c_str(), s.mean[0], s.mean[1], s.mean[2],
                s.se[0], s.maxdev);
}

TEST_CASE(white_furnace) {
    furnace("furnace_iso", R"(<shape type="sphere"><bsdf type="null"/>
        <medium type="homogeneous" name="interior"><float name="sigma_t" value="2"/><rgb name="albedo" value="1"/></medium></shape>)", 64);
    furnace("furnace_chroma_hg", R"(<shape type="sphere"><bsdf type="null"/>
        <medium type="homogeneous" name="interior"><rgb name="sigma_t" value="0.1, 0.4, 1"/><float name="scale" value="5"/><rgb name="albedo" value="1"/>
        <phase type="hg"><float name="g" value="0.6"/></phase></medium></shape>)", 64);
    furnace("furnace_mesh_cube_medium", R"(<shape type="cube"><transform name="to_world"><rotate x="1" y="1" angle="40"/><scale value="0.7"/></transform>
        <bsdf type="null"/><medium type="homogeneous" name="interior"><float name="sigma_t" value="3"/><float name="albedo" value="1"/>
        <phase type="hg"><float name="g" value="-0.4"/></phase></medium></shape>)", 64);
    furnace("furnace_diffuse", R"(<shape type="sphere"><bsdf type="diffuse"><rgb name="reflectance" value="1"/></bsdf></shape>)", 64);
    furnace("furnace_glass", R"(<shape type="sphere"><bsdf type="dielectric"><float name="int_ior" value="1.5"/></bsdf></shape>)", 64);
    furnace("furnace_glass_with_medium", R"(<shape type="sphere"><bsdf type="dielectric"/>
        <medium type="homogeneous" name="interior"><float name="sigma_t" value="1.5"/><rgb name="albedo" value="1"/></medium></shape>)", 64);
}

/// sigma_t = rgb * scale (Mitsuba's RGB variants keep an <rgb> outside emitters within [0, 1]).
static const char* slab_object(const char* rgb, const char* scale) {
    static std::string s;
    s = std::string(R"(<shape type="cube"><transform name="to_world"><scale x="20" y="20" z="0.25"/></transform><bsdf type="null"/>
        <medium type="homogeneous" name="interior"><rgb name="sigma_t" value=")") + rgb + R"("/><float name="scale" value=")" +
        scale + R"("/><rgb name="albedo" value="0"/></medium></shape>)";
    return s.c_str();
}

TEST_CASE(homogeneous_slab) {
    const double d = 0.5;
    struct Case { const char* sigma; const char* scale; double s[3]; };
    const Case cases[] = {{"1", "2", {2, 2, 2}}, {"0.125, 0.375, 1", "4", {0.5, 1.5, 4}}};
    int k = 0;
    for (const Case& c : cases) {
        const std::string scene = work("slab" + std::to_string(k) + ".xml"), out = work("slab" + std::to_string(k) + ".exr");
        ++k;
        // camera at z = 5 looking down -z through the slab (|z| <= 0.25), 2° field of view
        write_file(scene, "<scene version=\"3.0.0\"><integrator type=\"volpath\"/>" + camera(5.0f, 2.0f, 16, 16, 256) +
                              slab_object(c.sigma, c.scale) + "<emitter type=\"constant\"/></scene>");
        CHECK(run({scene, "-o", out, "--quiet"}) == 0);
        Image img = read_exr(out);
        Stats st = stats(img, 0.0);
        for (int ch = 0; ch < 3; ++ch) {
            // expected mean over pixel centres of exp(-σ d / cos θ) (cos θ >= 0.9998 here)
            double expect = 0;
            float th = std::tan(1.0f * kPi / 180.0f);
            for (int y = 0; y < 16; ++y)
                for (int x = 0; x < 16; ++x) {
                    double lx = (1 - 2 * (x + 0.5) / 16) * th, ly = (1 - 2 * (y + 0.5) / 16) * th;
                    double cos_t = 1 / std::sqrt(1 + lx * lx + ly * ly);
                    expect += std::exp(-c.s[ch] * d / cos_t) / 256.0;
                }
            double tol = 4.5 * st.se[ch] + 1e-4;
            CHECK_MSG(std::fabs(st.mean[ch] - expect) < tol, std::string("slab sigma=") + c.sigma + " ch " + std::to_string(ch) +
                                                             ": " + std::to_string(st.mean[ch]) + " vs " + std::to_string(expect) +
                                                             " (tol " + std::to_string(tol) + ")");
            std::printf("  slab sigma_t=%s ch%d: %.5f expected %.5f (se %.5f)\n", c.sigma, ch, st.mean[ch], expect, st.se[ch]);
        }
    }
}

TEST_CASE(shadow_ray_transmittance) {
    // Analytic transmittance through null boundaries, nested media, and a blocking dielectric.
    std::string xml = std::string("<scene version=\"3.0.0\"><integrator type=\"volpath\"/>") + camera(5, 30, 8, 8, 1) +
                      slab_object("0.25, 0.5, 0.75", "4") +
                      R"(<shape type="sphere"><point name="center" x="0" y="0" z="-3"/><float name="radius" value="0.5"/>
                           <bsdf type="null"/><medium type="homogeneous" name="interior"><rgb name="sigma_t" value="0.4"/></medium>
                           <medium type="homogeneous" name="exterior"><rgb name="sigma_t" value="0"/></medium></shape>
                         <shape type="sphere"><point name="center" x="5" y="0" z="0"/><float name="radius" value="0.5"/>
                           <bsdf type="dielectric"/></shape></scene>)";
    auto scene = build_scene(parse_scene_string(xml, "t.xml", {}), BuildOptions(), nullptr);
    PathIntegrator integ(*scene);
    Sampler s(0, 0, 0);
    Rgb T = integ.shadow_transmittance(Vec3(0, 0, 2), Vec3(0, 0, -1), kInf, nullptr, s);
    // slab thickness 0.5 with σ = (1,2,3), then the sphere: chord 1.0 with σ = 0.4
    const double e[3] = {std::exp(-0.5 * 1 - 0.4), std::exp(-0.5 * 2 - 0.4), std::exp(-0.5 * 3 - 0.4)};
    // Tolerance 2e-4 relative: each boundary crossing restarts the shadow ray 2e-5·(1+|p|)
    // past the surface (self-intersection offset), which that segment's medium does not see.
    for (int c = 0; c < 3; ++c) CHECK_NEAR(T[c], e[c], 2e-4 * e[c]);
    // stopping halfway through the slab (distance 2 reaches z = 0)
    Rgb T2 = integ.shadow_transmittance(Vec3(0, 0, 2), Vec3(0, 0, -1), 2.0f, nullptr, s);
    CHECK_NEAR(T2.r, std::exp(-0.25), 2e-4);
    // dielectrics are opaque to shadow rays
    Rgb T3 = integ.shadow_transmittance(Vec3(2, 0, 0.5f), normalize(Vec3(1, 0, -0.1667f)), kInf, nullptr, s);
    CHECK(T3.is_black());
}

TEST_CASE(determinism_and_outputs) {
    const std::string scene = work("det.xml");
    write_file(scene, std::string("<scene version=\"3.0.0\"><default name=\"g\" value=\"0.3\"/>") +
                          "<integrator type=\"volpath\"><integer name=\"max_depth\" value=\"12\"/></integrator>" +
                          camera(4, 40, 40, 30, 8) + R"(
        <shape type="rectangle"><transform name="to_world"><scale value="4"/><rotate x="1" angle="-90"/><translate y="-1"/></transform>
          <bsdf type="diffuse"><rgb name="reflectance" value="0.6, 0.5, 0.4"/></bsdf></shape>
        <shape type="sphere"><point name="center" x="-0.8" y="0" z="0"/><float name="radius" value="0.6"/>
          <bsdf type="roughconductor"><string name="material" value="Cu"/><float name="alpha" value="0.2"/></bsdf></shape>
        <shape type="sphere"><point name="center" x="0.8" y="0" z="0"/><float name="radius" value="0.6"/>
          <bsdf type="dielectric"/><medium type="homogeneous" name="interior"><rgb name="sigma_t" value="0.25, 0.5, 0.75"/><float name="scale" value="4"/>
          <phase type="hg"><float name="g" value="$g"/></phase></medium></shape>
        <shape type="disk"><transform name="to_world"><rotate x="1" angle="90"/><translate y="2"/></transform>
          <emitter type="area"><rgb name="radiance" value="4"/></emitter></shape>
        <emitter type="directional"><vector name="direction" x="1" y="-1" z="-1"/><rgb name="irradiance" value="0.5"/></emitter>
        <emitter type="point"><point name="position" x="0" y="1" z="2"/><rgb name="intensity" value="1"/></emitter>
        <emitter type="constant"><rgb name="radiance" value="0.1"/></emitter></scene>)");
    const std::string a = work("det_a.exr"), b = work("det_b.exr"), c = work("det_c.exr"), d = work("det_d.exr");
    for (const std::string& f : {a, b, c, d}) std::remove(f.c_str());
    CHECK(run({scene, "-o", a, "--quiet", "--threads", "2", "--seed", "42"}) == 0);
    CHECK(run({scene, "-o", b, "--quiet", "--threads", "2", "--seed", "42"}) == 0);
    CHECK(run({scene, "-o", c, "--quiet", "--threads", "1", "--seed", "42"}) == 0);
    CHECK(run({scene, "-o", d, "--quiet", "--threads", "2", "--seed", "43", "-D", "g=0.3"}) == 0);
    std::string fa = read_file(a);
    CHECK(!fa.empty());
    CHECK(fa == read_file(b));  // same seed, same threads: identical bytes
    CHECK(fa == read_file(c));  // different thread count: identical too
    CHECK(fa != read_file(d));  // another seed: different noise
    Image ia = read_exr(a), ic = read_exr(c);
    CHECK(ia.rgb == ic.rgb);
    bool finite = true;
    double sum = 0;
    for (float v : ia.rgb) {
        finite &= std::isfinite(v) && v >= 0;
        sum += v;
    }
    CHECK(finite && sum > 0);
    // the PNG preview sits beside the EXR; no temporaries remain
    CHECK(exists(work("det_a.png")));
    CHECK(!exists(a + ".partial-" + std::to_string(::getpid())));
    // --check on the same scene succeeds without rendering; a usage error returns 2
    CHECK(run({scene, "--check"}) == 0);
    CHECK(run({scene, "--spp", "zero"}) == 2);
    CHECK(run({}) == 2);
}

TEST_CASE(envmap_sampling) {
    // Importance sampling of a non-uniform lat-long map. Checks (tolerance 5 SE + 1e-3):
    // sampled pdf = pdf_direction(wi) and Li = eval_direction(wi) (up to float, 1e-3 rel);
    // ∫ pdf dω = 1 (uniform-sphere MC); E[Li/pdf] = ∫ L dω, the latter computed exactly as the
    // sum over texels of L·ΔΩ with ΔΩ = (2π/W)(cos θ0 − cos θ1).
    const int W = 32, H = 16;
    std::vector<float> rgb(size_t(W) * H * 3);
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x) {
            float v = 0.1f + (x == 5 && y == 4 ? 50.0f : 0.0f) + 0.5f * float(y) / H;
            size_t i = size_t(y) * W + x;
            rgb[3 * i] = v; rgb[3 * i + 1] = 0.5f * v; rgb[3 * i + 2] = 0.25f;
        }
    Mat4 rot = Mat4::rotate(1, 0.3, 0, 37);
    EnvmapEmitter env(rgb, W, H, 2.0f, rot);
    double exact = 0;
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x) {
            double dom = (2 * M_PI / W) * (std::cos(M_PI * y / H) - std::cos(M_PI * (y + 1) / H));
            exact += 2.0 * rgb[3 * (size_t(y) * W + x)] * dom;
        }
    Sampler s(4, 5, 6);
    double sum = 0, sum2 = 0, psum = 0, psum2 = 0;
    int bad = 0;
    const int N = 200000;
    for (int i = 0; i < N; ++i) {
        EmitterSample es;
        if (env.sample_li(Vec3(0.0f), s.next_2d(), &es)) {
            float p = env.pdf_direction(es.wi);
            Rgb L = env.eval_direction(es.wi);
            if (std::fabs(p - es.pdf) > 1e-3f * es.pdf || std::fabs(L.r - es.Li.r) > 1e-3f * L.r) ++bad;
            double v = es.Li.r / es.pdf;
            sum += v; sum2 += v * v;
        }
        Vec2 u = s.next_2d();
        float z = 1 - 2 * u.x, r = safe_sqrt(1 - z * z), phi = 2 * kPi * u.y;
        double q = env.pdf_direction(Vec3(r * std::cos(phi), r * std::sin(phi), z)) * 4 * M_PI;
        psum += q; psum2 += q * q;
    }
    CHECK_MSG(bad < N / 10000, "envmap pdf/eval mismatches: " + std::to_string(bad));
    double m = sum / N, se = std::sqrt(std::max(0.0, sum2 / N - m * m) / N);
    CHECK_MSG(std::fabs(m - exact) < 5 * se + 1e-3 * exact, "E[L/pdf] = " + std::to_string(m) + " vs " + std::to_string(exact));
    double pm = psum / N, pse = std::sqrt(std::max(0.0, psum2 / N - pm * pm) / N);
    CHECK_MSG(std::fabs(pm - 1) < 5 * pse + 1e-3, "∫pdf = " + std::to_string(pm));

    // Render: a constant-valued EXR envmap (rotated, scale 0.5) around a diffuse albedo-1 sphere;
    // furnace() adds its constant emitter of radiance 1, so the expectation is 1.5 (this also
    // exercises the uniform choice between two emitters in NEE and the MIS weights).
    Image img;
    img.width = 16;
    img.height = 8;
    img.rgb.assign(16 * 8 * 3, 1.0f);
    write_exr(work("white_env.exr"), img);
    furnace("furnace_envmap", R"(<shape type="sphere"><bsdf type="diffuse"><rgb name="reflectance" value="1"/></bsdf></shape>
        <emitter type="envmap"><string name="filename" value="white_env.exr"/><float name="scale" value="0.5"/>
          <transform name="to_world"><rotate x="1" angle="30"/></transform></emitter>)", 64, 1.5);
}

TEST_CASE(analytic_direct_lighting) {
    // A diffuse plane (albedo 0.5) seen from above with max_depth 2 (direct lighting only):
    //  * directional light along -z, irradiance E: radiance ρE/π exactly (no noise: delta light);
    //  * point light of intensity I at height h over the pixel seen at the image centre:
    //    ρI/(πh²) at that point (checked at the centre pixel, fov 0.5°: 1e-3 relative);
    //  * a huge emitting rectangle (half-size 1000 at height 1, radiance L) facing down:
    //    radiance ρL (missing solid angle ~1e-6), exercising area-light sampling + MIS with the
    //    BSDF; tolerance 4.5 SE.
    auto scene_with = [&](const std::string& name, const std::string& light, float fov, int spp) {
        const std::string path = work(name + ".xml"), out = work(name + ".exr");
        write_file(path, "<scene version=\"3.0.0\"><integrator type=\"path\"><integer name=\"max_depth\" value=\"2\"/></integrator>" +
                             camera(3.0f, fov, 8, 8, spp) +
                             R"(<shape type="rectangle"><transform name="to_world"><scale value="100"/></transform>
                                <bsdf type="diffuse"><rgb name="reflectance" value="0.5"/></bsdf></shape>)" + light + "</scene>");
        CHECK(run({path, "-o", out, "--quiet"}) == 0);
        return read_exr(out);
    };
    Image a = scene_with("direct_dir", R"(<emitter type="directional"><vector name="direction" x="0" y="0" z="-1"/>
        <rgb name="irradiance" value="2"/></emitter>)", 20, 4);
    for (float v : a.rgb) CHECK_NEAR(v, 0.5 * 2 / M_PI, 1e-5);
    Image b = scene_with("direct_point", R"(<emitter type="point"><point name="position" x="0" y="0" z="1.5"/>
        <rgb name="intensity" value="3"/></emitter>)", 0.5f, 4);
    double centre = (b.rgb[3 * (3 * 8 + 3)] + b.rgb[3 * (3 * 8 + 4)] + b.rgb[3 * (4 * 8 + 3)] + b.rgb[3 * (4 * 8 + 4)]) / 4;
    CHECK_NEAR(centre, 0.5 * 3 / (M_PI * 1.5 * 1.5), 1e-3 * 0.5 * 3 / (M_PI * 1.5 * 1.5));
    Image c = scene_with("direct_area", R"(<shape type="rectangle"><transform name="to_world"><scale value="1000"/>
        <rotate x="1" angle="180"/><translate z="1"/></transform><bsdf type="null"/>
        <emitter type="area"><rgb name="radiance" value="0.8"/></emitter></shape>)", 20, 256);
    Stats st = stats(c, 0.4);
    CHECK_MSG(std::fabs(st.mean[0] - 0.4) < 4.5 * st.se[0] + 1e-4,
              "area light: " + std::to_string(st.mean[0]) + " vs 0.4 (se " + std::to_string(st.se[0]) + ")");
    std::printf("  area light: %.5f (expected 0.4, se %.5f)\n", st.mean[0], st.se[0]);
}

TEST_CASE(emitter_default_bsdf) {
    // Mitsuba 3 gives a shape without a <bsdf> a diffuse BSDF of reflectance 0.5, but a black one
    // when the shape is an area emitter (Shape's constructor). A rectangle facing the camera under
    // a constant environment of radiance E (volpath, unoccluded hemisphere) therefore renders as
    //  * an area light of radiance L: exactly L in every pixel (nothing reflected, no noise);
    //    mfrender used to give it the 0.5 diffuse, i.e. L + 0.5 E, which made every path that
    //    reaches the light's front after a bounce brighter than Mitsuba (+0.15 % on a scattering
    //    sphere beside the light, 20 SE);
    //  * a plain rectangle: 0.5 E (diffuse 0.5 under radiance E); tolerance 4.5 SE.
    auto rectangle = [&](const std::string& name, const std::string& emitter) {
        return render(name, "<scene version=\"3.0.0\"><integrator type=\"volpath\"/>" + camera(3.0f, 20.0f, 8, 8, 64) +
                                R"(<shape type="rectangle"><transform name="to_world"><scale value="2"/></transform>)" +
                                emitter + R"(</shape><emitter type="constant"><rgb name="radiance" value="1"/></emitter></scene>)");
    };
    Image light = rectangle("default_bsdf_light", R"(<emitter type="area"><rgb name="radiance" value="2"/></emitter>)");
    Stats sl = stats(light, 2.0);
    CHECK_MSG(sl.maxdev < 1e-6, "area light without a BSDF: max |pixel - 2| = " + std::to_string(sl.maxdev) +
                                    " (mean " + std::to_string(sl.mean[0]) + ")");
    Image plain = rectangle("default_bsdf_plain", "");
    Stats sp = stats(plain, 0.5);
    for (int c = 0; c < 3; ++c)
        CHECK_MSG(std::fabs(sp.mean[c] - 0.5) < 4.5 * sp.se[c] + 1e-4,
                  "rectangle without a BSDF: channel " + std::to_string(c) + " mean " + std::to_string(sp.mean[c]) + " vs 0.5");
    std::printf("  area light: max |dev| %.2e; plain rectangle: %.5f (expected 0.5, se %.5f)\n", sl.maxdev, sp.mean[0], sp.se[0]);
}

TEST_CASE(light_sampling_estimators_agree) {
    // MIS (power heuristic), BSDF / phase sampling alone and emitter sampling (NEE) alone are
    // three unbiased estimators of one image: any error in an emitter pdf (area measure, solid
    // angle, emitter choice), a MIS weight, a phase or BSDF pdf, or the shadow-ray transmittance
    // makes them disagree. Scene: a homogeneous chromatic HG sphere (null boundary: NEE from medium
    // events through it), a Beckmann copper sphere, a diffuse floor, a rectangle light, a point
    // light (delta: NEE in all three) and a constant environment; max_depth 8.
    // Pixels of the difference of two independent renders are independent with mean 0 when the
    // estimators agree: the image mean of the difference must be within 4.5 SE (from its per-pixel
    // spread) of 0, per channel. At 512 spp the SE is ~0.3-0.7 % of the image mean: a rectangle
    // light whose NEE pdf is 10 % off fails (z = 6.5); MIS weights that do not sum to 1 are a
    // subtler bias (an emitter-hit pdf 1.5x off gives z = 2.6, which passes).
    const std::string xml = "<scene version=\"3.0.0\"><integrator type=\"volpath\"><integer name=\"max_depth\" value=\"8\"/>"
                            "</integrator>" + camera(4.0f, 40.0f, 32, 32, 512) + R"(
        <shape type="rectangle"><transform name="to_world"><scale value="4"/><rotate x="1" angle="-90"/><translate y="-0.6"/></transform>
          <bsdf type="diffuse"><rgb name="reflectance" value="0.5"/></bsdf></shape>
        <shape type="sphere"><point name="center" x="-0.6" y="0" z="0"/><float name="radius" value="0.55"/><bsdf type="null"/>
          <medium type="homogeneous" name="interior"><float name="sigma_t" value="4"/><rgb name="albedo" value="0.9, 0.8, 0.6"/>
          <phase type="hg"><float name="g" value="0.3"/></phase></medium></shape>
        <shape type="sphere"><point name="center" x="0.6" y="0" z="0"/><float name="radius" value="0.55"/>
          <bsdf type="roughconductor"><string name="material" value="Cu"/><float name="alpha" value="0.3"/></bsdf></shape>
        <shape type="rectangle"><transform name="to_world"><scale value="0.6"/><lookat origin="1.5, 1.8, 2.2" target="0, 0, 0" up="0, 0, 1"/></transform>
          <emitter type="area"><rgb name="radiance" value="6"/></emitter></shape>
        <emitter type="point"><point name="position" x="0" y="2" z="1"/><rgb name="intensity" value="1"/></emitter>
        <emitter type="constant"><rgb name="radiance" value="0.05"/></emitter></scene>)";
    auto render_with = [&](LightSampling ls, uint64_t seed) {
        auto scene = build_scene(parse_scene_string(xml, work("estimators.xml"), {}), BuildOptions(), nullptr);
        scene->integrator.light_sampling = ls;
        scene->seed = seed;
        RenderStats rs;
        return mf::render(*scene, RenderOptions(), &rs);
    };
    const Image mis = render_with(LightSampling::Mis, 1), bsdf = render_with(LightSampling::BsdfOnly, 2),
                nee = render_with(LightSampling::EmitterOnly, 3);
    auto agree = [&](const char* what, const Image& a, const Image& b) {
        const size_t n = size_t(a.width) * a.height;
        for (int c = 0; c < 3; ++c) {
            double sum = 0, sum2 = 0, mean_b = 0;
            for (size_t i = 0; i < n; ++i) {
                double d = double(a.rgb[3 * i + c]) - b.rgb[3 * i + c];
                sum += d;
                sum2 += d * d;
                mean_b += b.rgb[3 * i + c] / double(n);
            }
            double m = sum / n, se = std::sqrt(std::max(0.0, (sum2 - sum * sum / n) / (n - 1)) / n);
            CHECK_MSG(std::fabs(m) < 4.5 * se && mean_b > 0.02,
                      std::string(what) + " channel " + std::to_string(c) + ": mean difference " + std::to_string(m) +
                          " (se " + std::to_string(se) + ", image mean " + std::to_string(mean_b) + ")");
            std::printf("  %-16s channel %d: image mean %.5f, difference %+.5f (se %.5f, z %+.2f)\n", what, c, mean_b, m, se,
                        se > 0 ? m / se : 0.0);
        }
    };
    agree("bsdf-only - mis", bsdf, mis);
    agree("nee-only - mis", nee, mis);
}

TEST_CASE(spot_light_analytic) {
    // Spot at height z = 2 over a diffuse plane (ρ = 0.5), pointing straight down, seen by a
    // 64x64 camera at the same point (fov 90°: θ up to 54.7° at the corners). A delta light seen
    // with a box filter: each pixel averages ρ I f(θ) cos³θ / (π z²) over its footprint (256
    // uniform positions). Pixels whose four corners lie inside beam_width (20°): within 0.2 % of
    // the value at the centre (measured worst 0.13 %: the positions' noise); inside the linear
    // ramp (20°-30°, where f drops by ~0.17 across a pixel): 2 % of the beam-edge value (measured
    // worst ~1 %; a ramp linear in cos θ instead of θ is off by up to 4 %); beyond
    // cutoff_angle (30°): exactly 0.
    const float z = 2, rho = 0.5f, I = 4;
    const std::string path = work("spot_analytic.xml"), out = work("spot_analytic.exr");
    write_file(path, "<scene version=\"3.0.0\"><integrator type=\"path\"><integer name=\"max_depth\" value=\"2\"/></integrator>" +
                         camera(z, 90.0f, 64, 64, 256) +
                         R"(<shape type="rectangle"><transform name="to_world"><scale value="100"/></transform>
                            <bsdf type="diffuse"><rgb name="reflectance" value="0.5"/></bsdf></shape>
                            <emitter type="spot"><rgb name="intensity" value="4"/><float name="cutoff_angle" value="30"/>
                            <float name="beam_width" value="20"/><transform name="to_world">
                            <lookat origin="0, 0, 2" target="0, 0, 0" up="0, 1, 0"/></transform></emitter></scene>)");
    CHECK(run({path, "-o", out, "--quiet"}) == 0);
    Image img = read_exr(out);
    const double deg = M_PI / 180, cutoff = 30 * deg, beam = 20 * deg;
    auto theta = [](double a, double b) { return std::atan(std::sqrt(a * a + b * b)); };  // tan_half = 1
    auto radiance = [&](double th) {
        double f = th <= beam ? 1.0 : th < cutoff ? (cutoff - th) / (cutoff - beam) : 0.0;
        double c = std::cos(th);
        return rho * I * f * c * c * c / (M_PI * z * z);
    };
    int n_beam = 0, n_ramp = 0, n_dark = 0;
    double worst_beam = 0, worst_ramp = 0;
    for (int j = 0; j < 64; ++j)
        for (int i = 0; i < 64; ++i) {
            double lo_a = 2.0 * i / 64 - 1, hi_a = 2.0 * (i + 1) / 64 - 1, lo_b = 2.0 * j / 64 - 1, hi_b = 2.0 * (j + 1) / 64 - 1;
            double t_min = theta(std::min(std::fabs(lo_a), std::fabs(hi_a)) * (lo_a * hi_a > 0),
                                 std::min(std::fabs(lo_b), std::fabs(hi_b)) * (lo_b * hi_b > 0));
            double t_max = theta(std::max(std::fabs(lo_a), std::fabs(hi_a)), std::max(std::fabs(lo_b), std::fabs(hi_b)));
            double expect = radiance(theta((lo_a + hi_a) / 2, (lo_b + hi_b) / 2));
            float v = img.rgb[3 * (size_t(j) * 64 + i)];
            if (t_min > cutoff) {
                CHECK(v == 0.0f);
                ++n_dark;
            } else if (t_max < beam) {
                worst_beam = std::max(worst_beam, std::fabs(v / expect - 1));
                ++n_beam;
            } else if (t_min > beam && t_max < cutoff) {
                worst_ramp = std::max(worst_ramp, std::fabs(v - expect) / radiance(beam));
                ++n_ramp;
            }
        }
    std::printf("  spot: %d beam pixels (worst rel. error %.2e), %d ramp pixels (worst %.2e of the beam edge), %d dark\n",
                n_beam, worst_beam, n_ramp, worst_ramp, n_dark);
    CHECK(n_beam > 100 && n_ramp > 100 && n_dark > 1000);
    CHECK_MSG(worst_beam < 2e-3, "beam: " + std::to_string(worst_beam));
    CHECK_MSG(worst_ramp < 2e-2, "ramp: " + std::to_string(worst_ramp));
    // Mitsuba's refusals: a varying intensity, a constant projected texture; and angles
    auto spot = [&](const std::string& inner) {
        build_scene(parse_scene_string("<scene version=\"3.0.0\">" + camera(z, 90.0f, 8, 8, 1) + "<emitter type=\"spot\">" + inner +
                                           "</emitter></scene>", work("spot_bad.xml"), {}),
                    BuildOptions(), nullptr);
    };
    CHECK_THROWS_WITH(spot(R"(<texture name="intensity" type="checkerboard"/>)"), "cannot be spatially varying");
    CHECK_THROWS_WITH(spot(R"(<rgb name="texture" value="0.5"/>)"), "must be a spatially varying texture");
    CHECK_THROWS_WITH(spot(R"(<float name="cutoff_angle" value="10"/><float name="beam_width" value="12"/>)"),
                      "\"beam_width\" must lie in [0, cutoff_angle]");
    CHECK_THROWS_WITH(spot(R"(<float name="cutoff_angle" value="95"/><texture name="texture" type="checkerboard"/>)"),
                      "(0, 90) degrees with a texture");
}

TEST_CASE(direct_and_moment_integrators) {
    // Mitsuba's direct is the path estimator stopped after one bounce: same seed, same image as
    // path with max_depth 2, bit for bit; moment renders its nested integrator's image.
    const std::string body = camera(4.0f, 40.0f, 24, 24, 8) + R"(
        <shape type="sphere"><float name="radius" value="0.7"/><bsdf type="roughplastic"><float name="alpha" value="0.2"/></bsdf></shape>
        <shape type="rectangle"><transform name="to_world"><scale value="0.5"/><lookat origin="1, 2, 2" target="0, 0, 0" up="0, 1, 0"/></transform>
          <emitter type="area"><rgb name="radiance" value="5"/></emitter></shape>
        <emitter type="spot"><rgb name="intensity" value="3"/><transform name="to_world"><lookat origin="0, 0, 3" target="0, 0, 0"/></transform></emitter>
        <emitter type="constant"><rgb name="radiance" value="0.1"/></emitter></scene>)";
    auto render_xml = [&](const std::string& name, const std::string& integrator) {
        const std::string path = work(name + ".xml"), out = work(name + ".exr");
        write_file(path, "<scene version=\"3.0.0\">" + integrator + body);
        CHECK(run({path, "-o", out, "--quiet", "--seed", "7"}) == 0);
        return read_file(out);
    };
    const std::string path2 = render_xml("int_path2", R"(<integrator type="path"><integer name="max_depth" value="2"/></integrator>)");
    CHECK(render_xml("int_direct", R"(<integrator type="direct"/>)") == path2);
    CHECK(render_xml("int_moment", R"(<integrator type="moment"><integrator type="direct"/></integrator>)") == path2);
    auto built = [&](const std::string& integrator) {
        return build_scene(parse_scene_string("<scene version=\"3.0.0\">" + integrator + body, work("int.xml"), {}), BuildOptions(),
                           nullptr)->integrator;
    };
    IntegratorSettings s = built(R"(<integrator type="direct"><integer name="emitter_samples" value="0"/></integrator>)");
    CHECK(s.light_sampling == LightSampling::BsdfOnly && s.max_depth == 2 && !s.volumetric);
    s = built(R"(<integrator type="direct"><integer name="bsdf_samples" value="0"/></integrator>)");
    CHECK(s.light_sampling == LightSampling::EmitterOnly);
    CHECK_THROWS_WITH(built(R"(<integrator type="direct"><integer name="bsdf_samples" value="4"/></integrator>)"),
                      "\"bsdf_samples\" must be 0 or 1");
    CHECK_THROWS_WITH(built(R"(<integrator type="direct"><integer name="shading_samples" value="0"/></integrator>)"),
                      "both 0");
    CHECK_THROWS_WITH(built(R"(<integrator type="moment"/>)"), "exactly one nested <integrator>");
    CHECK_THROWS_WITH(built(R"(<integrator type="moment"><integrator type="ptracer"/></integrator>)"),
                      "unsupported integrator plugin \"ptracer\"");
}

TEST_CASE(heterogeneous_transmittance) {
    // A 1x1x4 grid (cell centres at z = 1/8, 3/8, 5/8, 7/8 of its box: 0.2, 1.0, 0.4, 0.8; clamped
    // beyond the end centres) placed on [-0.5, 0.5]^3 inside a null cube [-1, 1]^3: along z the
    // trilinear density integrates to 0.6, so with scale 2 the optical depth is 1.2 / cos θ --
    // beyond the box there is no medium (Mitsuba's intersect_aabb; a clamped grid evaluated there
    // would add 1.0). Albedo 0, constant environment 1: each pixel is the transmittance.
    const std::string vol = work("hetero_ramp.vol");
    {
        std::string b = "VOL";
        b.push_back(char(3));
        auto put_i = [&](int32_t v) { b.append(reinterpret_cast<const char*>(&v), 4); };
        auto put_f = [&](float v) { b.append(reinterpret_cast<const char*>(&v), 4); };
        for (int32_t v : {1, 1, 1, 4, 1}) put_i(v);  // float32, 1x1x4, 1 channel
        for (float v : {0.f, 0.f, 0.f, 1.f, 1.f, 1.f}) put_f(v);
        for (float v : {0.2f, 1.0f, 0.4f, 0.8f}) put_f(v);
        write_file(vol, b);
    }
    struct Case { std::string sigma_t; double tau[3]; };
    const std::string box = R"(<transform name="to_world"><translate value="-0.5, -0.5, -0.5"/></transform>)";
    const Case cases[] = {
        {R"(<volume name="sigma_t" type="gridvolume"><string name="filename" value="hetero_ramp.vol"/>)" + box + "</volume>", {1.2, 1.2, 1.2}},
        {R"(<volume name="sigma_t" type="constvolume"><rgb name="value" value="0.5, 0.25, 1"/>)" + box + "</volume>", {1.0, 0.5, 2.0}}};
    int k = 0;
    for (const Case& c : cases) {
        const std::string medium = R"(<shape type="cube"><bsdf type="null"/><medium type="heterogeneous" name="interior">)" + c.sigma_t +
                                   R"(<float name="scale" value="2"/><rgb name="albedo" value="0"/></medium></shape>)";
        const std::string scene = work("hetero" + std::to_string(k) + ".xml"), out = work("hetero" + std::to_string(k) + ".exr");
        ++k;
        write_file(scene, "<scene version=\"3.0.0\"><integrator type=\"volpath\"/>" + camera(5.0f, 2.0f, 16, 16, 256) + medium +
                              "<emitter type=\"constant\"/></scene>");
        CHECK(run({scene, "-o", out, "--quiet"}) == 0);
        Stats st = stats(read_exr(out), 0.0);
        for (int ch = 0; ch < 3; ++ch) {
            double expect = 0;  // mean over pixel centres of exp(-tau / cos θ), cos θ >= 0.9998
            float th = std::tan(1.0f * kPi / 180.0f);
            for (int y = 0; y < 16; ++y)
                for (int x = 0; x < 16; ++x) {
                    double lx = (1 - 2 * (x + 0.5) / 16) * th, ly = (1 - 2 * (y + 0.5) / 16) * th;
                    expect += std::exp(-c.tau[ch] * std::sqrt(1 + lx * lx + ly * ly)) / 256.0;
                }
            double tol = 4.5 * st.se[ch] + 1e-4;
            CHECK_MSG(std::fabs(st.mean[ch] - expect) < tol, "camera paths, case " + std::to_string(k) + " ch " + std::to_string(ch) +
                                                                 ": " + std::to_string(st.mean[ch]) + " vs " + std::to_string(expect));
            std::printf("  heterogeneous case %d ch%d (camera paths): %.5f expected %.5f (se %.5f)\n", k, ch, st.mean[ch], expect,
                        st.se[ch]);
        }
        // shadow rays straight down the axis: ratio tracking, averaged over 20000 estimates
        auto sc = build_scene(parse_scene_string("<scene version=\"3.0.0\"><integrator type=\"volpath\"/>" + camera(5.0f, 2.0f, 4, 4, 1) +
                                                     medium + "</scene>", scene, {}),
                              BuildOptions(), nullptr);
        PathIntegrator integ(*sc);
        double sum[3] = {0, 0, 0}, sum2[3] = {0, 0, 0};
        const int n = 20000;
        for (int i = 0; i < n; ++i) {
            Sampler smp(7, uint32_t(i), 0);
            Rgb T = integ.shadow_transmittance(Vec3(0, 0, 2), Vec3(0, 0, -1), kInf, nullptr, smp);
            for (int ch = 0; ch < 3; ++ch) sum[ch] += T[ch], sum2[ch] += double(T[ch]) * T[ch];
        }
        for (int ch = 0; ch < 3; ++ch) {
            double m = sum[ch] / n, se = std::sqrt(std::max(0.0, sum2[ch] / n - m * m) / n), expect = std::exp(-c.tau[ch]);
            CHECK_MSG(std::fabs(m - expect) < 4.5 * se + 2e-4 * expect,
                      "shadow rays, case " + std::to_string(k) + " ch " + std::to_string(ch) + ": " + std::to_string(m) + " vs " +
                          std::to_string(expect) + " (se " + std::to_string(se) + ")");
            std::printf("  heterogeneous case %d ch%d (shadow rays): %.5f expected %.5f (se %.5f)\n", k, ch, m, expect, se);
        }
    }
    // refusals: albedo above 1 in a grid, has_spectral_extinction false, a 6-channel volume
    auto build = [&](const std::string& inner) {
        build_scene(parse_scene_string("<scene version=\"3.0.0\">" + camera(5.0f, 2.0f, 4, 4, 1) +
                                           R"(<shape type="cube"><bsdf type="null"/><medium type="heterogeneous" name="interior">)" + inner +
                                           "</medium></shape></scene>", work("hetero_bad.xml"), {}),
                    BuildOptions(), nullptr);
    };
    CHECK_THROWS_WITH(build(R"(<boolean name="has_spectral_extinction" value="false"/>)"), "has_spectral_extinction");
    CHECK_THROWS_WITH(build(R"(<volume name="albedo" type="constvolume"><float name="value" value="1.5"/></volume>)"), "outside [0, 1]");
    CHECK_THROWS_WITH(build(R"(<float name="albedo" value="2"/>)"), "must lie in [0, 1]");
}

TEST_CASE(mask_bsdf) {
    const std::string sheet = R"(<shape type="rectangle"><transform name="to_world"><translate z="1"/></transform>
        <bsdf type="mask"><float name="opacity" value="0.3"/><bsdf type="diffuse"><rgb name="reflectance" value="0"/></bsdf></bsdf></shape>)";
    for (const char* integrator : {"path", "volpath"}) {
        const std::string name = std::string("mask_env_") + integrator;
        write_file(work(name + ".xml"), std::string("<scene version=\"3.0.0\"><integrator type=\"") + integrator + "\"/>" +
                                            camera(3.0f, 10.0f, 16, 16, 256) + sheet + "<emitter type=\"constant\"/></scene>");
        CHECK(run({work(name + ".xml"), "-o", work(name + ".exr"), "--quiet"}) == 0);
        Stats st = stats(read_exr(work(name + ".exr")), 0.7);
        CHECK_MSG(std::fabs(st.mean[0] - 0.7) < 4.5 * st.se[0], std::string(integrator) + ": " + std::to_string(st.mean[0]) + " vs 0.7");
        std::printf("  mask (%s) against the environment: %.5f (expected 0.7, se %.5f)\n", integrator, st.mean[0], st.se[0]);
        // a lit plane behind the sheet (seen from below through nothing): direct light through the mask
        const std::string lit = work(name + "_lit.xml");
        write_file(lit, std::string("<scene version=\"3.0.0\"><integrator type=\"") + integrator +
                            "\"><integer name=\"max_depth\" value=\"2\"/></integrator>" + camera(0.5f, 10.0f, 8, 8, 4) + sheet +
                            R"(<shape type="rectangle"><transform name="to_world"><scale value="100"/></transform>
                               <bsdf type="diffuse"><rgb name="reflectance" value="0.5"/></bsdf></shape>
                               <emitter type="directional"><vector name="direction" x="0" y="0" z="-1"/><rgb name="irradiance" value="2"/></emitter></scene>)");
        CHECK(run({lit, "-o", work(name + "_lit.exr"), "--quiet"}) == 0);
        const double expect = std::string(integrator) == "volpath" ? 0.5 * 2 * 0.7 / M_PI : 0.0;
        for (float v : read_exr(work(name + "_lit.exr")).rgb) CHECK_NEAR(v, expect, 1e-5);
    }
    // Mitsuba's checkerboard eval_1 (the mask's opacity) swaps the colours of its eval
    auto checker = make_checkerboard_texture(make_constant_texture(Rgb(1.0f)), make_constant_texture(Rgb(0.0f)), UvTransform());
    CHECK(checker->eval(Vec2(0.25f, 0.25f)).r == 1.0f && checker->eval_1(Vec2(0.25f, 0.25f)) == 0.0f);
    CHECK(make_mask(checker, make_diffuse(Rgb(0.5f)))->transparency(Vec2(0.25f, 0.25f)) == 1.0f);
    CHECK(make_mask(checker, make_diffuse(Rgb(0.5f)))->transparency(Vec2(0.75f, 0.25f)) == 0.0f);
}

TEST_CASE(projector_analytic) {
    // Projector at the camera position (0, 0, 2) looking down at a diffuse plane (rho = 0.5) at
    // depth 2, fov 40° along x, a 4x2 constant EXR of irradiance 0.3 (aspect 2: the frame's half
    // extent at depth 2 is 2 tan 20° = 0.728 in x, 0.364 in y) and scale 2: radiance
    // rho E scale / z² = 0.5 * 0.3 * 2 / 4 inside, 0 outside. Camera fov 60°, 32x32, box filter.
    Image tex;
    tex.width = 4;
    tex.height = 2;
    tex.rgb.assign(4 * 2 * 3, 0.3f);
    write_exr(work("projector_tex.exr"), tex);
    const std::string path = work("projector.xml"), out = work("projector_out.exr");
    write_file(path, "<scene version=\"3.0.0\"><integrator type=\"direct\"/>" + camera(2.0f, 60.0f, 32, 32, 4) +
                         R"(<shape type="rectangle"><transform name="to_world"><scale value="100"/></transform>
                            <bsdf type="diffuse"><rgb name="reflectance" value="0.5"/></bsdf></shape>
                            <emitter type="projector"><float name="fov" value="40"/><float name="scale" value="2"/>
                            <texture name="irradiance" type="bitmap"><string name="filename" value="projector_tex.exr"/></texture>
                            <transform name="to_world"><lookat origin="0, 0, 2" target="0, 0, 0" up="0, 1, 0"/></transform></emitter></scene>)");
    CHECK(run({path, "-o", out, "--quiet"}) == 0);
    Image img = read_exr(out);
    const double inside = 0.5 * 0.3 * 2 / 4, tx = std::tan(30 * M_PI / 180) * 2, hx = 2 * std::tan(20 * M_PI / 180), hy = hx / 2;
    int n_in = 0, n_out = 0;
    for (int j = 0; j < 32; ++j)
        for (int i = 0; i < 32; ++i) {
            // the pixel's footprint on the plane (|x| and |y| ranges; the image is symmetric)
            double x0 = std::fabs(tx * (2.0 * i / 32 - 1)), x1 = std::fabs(tx * (2.0 * (i + 1) / 32 - 1));
            double y0 = std::fabs(tx * (2.0 * j / 32 - 1)), y1 = std::fabs(tx * (2.0 * (j + 1) / 32 - 1));
            float v = img.rgb[3 * (size_t(j) * 32 + i)];
            if (std::max(x0, x1) < hx && std::max(y0, y1) < hy) {
                CHECK_NEAR(v, inside, 1e-5);
                ++n_in;
            } else if (std::min(x0, x1) > hx || std::min(y0, y1) > hy) {
                CHECK(v == 0.0f);
                ++n_out;
            }
        }
    std::printf("  projector: %d pixels inside the frame (%.5f each), %d outside (0)\n", n_in, inside, n_out);
    CHECK(n_in > 50 && n_out > 300);
}

TEST_CASE(orthographic_sensor) {
    const std::string path = work("ortho.xml"), out = work("ortho.exr");
    write_file(path, R"(<scene version="3.0.0"><integrator type="path"/>
        <sensor type="orthographic"><transform name="to_world"><lookat origin="0, 0, 3" target="0, 0, 0" up="0, 1, 0"/></transform>
          <film type="hdrfilm"><integer name="width" value="32"/><integer name="height" value="16"/><rfilter type="box"/></film>
          <sampler type="independent"><integer name="sample_count" value="4"/></sampler></sensor>
        <shape type="rectangle"><transform name="to_world"><scale x="0.3" y="0.2"/></transform>
          <emitter type="area"><rgb name="radiance" value="2"/></emitter></shape></scene>)");
    CHECK(run({path, "-o", out, "--quiet"}) == 0);
    Image img = read_exr(out);
    int lit = 0, dark = 0;
    for (int j = 0; j < 16; ++j)
        for (int i = 0; i < 32; ++i) {
            // the pixel's window: x in [-1, 1] over 32 columns, y in [-0.5, 0.5] over 16 rows
            double x0 = std::fabs(-1 + 2.0 * i / 32), x1 = std::fabs(-1 + 2.0 * (i + 1) / 32);
            double y0 = std::fabs(-0.5 + 1.0 * j / 16), y1 = std::fabs(-0.5 + 1.0 * (j + 1) / 16);
            float v = img.rgb[3 * (size_t(j) * 32 + i)];
            if (std::max(x0, x1) < 0.3 && std::max(y0, y1) < 0.2) {
                CHECK(v == 2.0f);
                ++lit;
            } else if (std::min(x0, x1) > 0.3 || std::min(y0, y1) > 0.2) {
                CHECK(v == 0.0f);
                ++dark;
            }
        }
    std::printf("  orthographic: %d pixels inside the rectangle, %d outside\n", lit, dark);
    CHECK(lit == 8 * 6 && dark > 400);  // 8 columns of 1/16 within |x| < 0.3, 6 rows of 1/16 within |y| < 0.2
}

TEST_MAIN()
