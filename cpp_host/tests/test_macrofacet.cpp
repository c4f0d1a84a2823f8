// Macrofacet medium tests: the library through the C ABI, the shell region, delta /
// ratio tracking on curved shells, the phase function with NEE + MIS, end to end.
//
//  * tracking_vs_analytic (planar): near the centre of a large cube's top face the SDF is exactly
//    linear, where the library's closed-form transmittance T(t) is the reference. Ratio-tracking
//    estimates of T and delta-tracking collision probabilities P(t_coll < t) = 1 − T(t) at three
//    lengths must agree within 4.5 standard errors (binomial / sample SE, N = 40000) + 1e-4.
//  * tracking_vs_quadrature (curved): on a sphere whose shell is thick compared with its radius
//    (sigma = 0.1 r) the optical depth along a chord through the shell is integrated by a fine
//    composite Simpson rule of the library's sigma_t with the exact normal at each point; ratio
//    tracking and delta tracking must match exp(−tau) within 4.5 SE + 2e-4 (quadrature error).
//  * white_furnace: mirror flakes (material none) in a closed object, constant environment 1:
//    every NDF (beckmann, ggx, gpss with alpha_z = 0 and alpha_z = alpha) at a small and a large
//    sigma, a cube (sphere-traced level set) and a mesh (mesh SDF, smooth frame normals). The
//    image mean must be within 4.5 SE of 1 (SE from the per-pixel spread) + 1e-3, and no pixel
//    further than 10 per-pixel standard deviations. The +1e-3 covers float accumulation and the
//    2e-5·scale ray-offset at each boundary crossing.
//  * thin_shell: sigma = 1e-3 r, max_depth 2 (single scattering) against roughconductor with the
//    same NDF, roughness and material under an area light and a constant environment. Pixels
//    within the silhouette margin (cos(view, normal) < 0.35) are excluded: there the separable
//    Smith G1·G1 of roughconductor and the height-correlated masking-shadowing that a thin
//    shell produces differ by O(Lambda_i·Lambda_o), and the kσ shell widens the silhouette.
//    Passes when the mean relative difference is < 1.5 % and below 4.5 SE of the pixel-wise
//    difference + 0.5 %, and < 0.5 % of pixel values have |z| > 4.5 (z from the two renders'
//    noise, modelled as var = k·(a + b) with k fitted over the mask).
//  * unbiased_convergence: the same macrofacet and homogeneous scenes at 32 spp / seed 1 and
//    128 spp / seed 2 agree (mean difference within 4.5 combined SE).
//  * media_find_their_exits: a mesh shell whose tracker finds the rays' exits renders as with a
//    ray cast for every exit (--cast-exits).
//  * boundary_form: the form Mitsuba with the plugin reads (nested mean surface, null-BSDF
//    boundary) renders as the mean-surface form, with a tight and a loose boundary.
//  * determinism: bit-identical EXR for the same seed (1 and 2 threads).
#include <macrofacet.h>

#include <limits>
#include <sstream>
#include <vector>

#include "check.h"
#include "integrator.h"
#include "mean_surface.h"
#include "render.h"
#include "medium_macrofacet.h"
#include "scene_builder.h"
#include "scene_util.h"

using namespace mf;

static std::string medium_xml(const std::string& id, const std::string& params) {
    return "<medium type=\"macrofacet\" id=\"" + id + "\">" + params + "</medium>";
}

static const MacrofacetMedium* first_macrofacet(const Scene& s) {
    for (const auto& m : s.media)
        if (auto* mm = dynamic_cast<const MacrofacetMedium*>(m.get())) return mm;
    return nullptr;
}

// ------------------------------------------------------------------------------------------
// Tracking against analytic (planar) and quadrature (curved) references

struct TrackStats {
    double T_ratio = 0, T_ratio_se = 0, P_coll = 0;
};

static TrackStats track(const MacrofacetMedium& m, const Ray& r, float t, int n, uint64_t seed) {
    double sum = 0, sum2 = 0;
    int coll = 0;
    for (int i = 0; i < n; ++i) {
        Sampler s(seed, uint64_t(i), 0);
        double T = m.transmittance(r, t, s).r;
        sum += T;
        sum2 += T * T;
        MediumInteraction mi;
        Rgb w, pr;
        Sampler s2(seed + 1, uint64_t(i), 0);
        if (m.sample_free_flight(r, t, nullptr, 0, s2, &mi, &w, &pr)) ++coll;
    }
    TrackStats st;
    st.T_ratio = sum / n;
    st.T_ratio_se = std::sqrt(std::max(0.0, sum2 / n - st.T_ratio * st.T_ratio) / n);
    st.P_coll = double(coll) / n;
    return st;
}

static void compare_tracking(const std::string& what, const MacrofacetMedium& m, const Ray& r, float t, double T_ref,
                             double extra_tol) {
    const int n = 40000;
    TrackStats st = track(m, r, t, n, 11);
    double tol_r = 4.5 * st.T_ratio_se + extra_tol + 1e-4;
    double se_p = std::sqrt(std::max(T_ref * (1 - T_ref), 1e-6) / n);
    double tol_p = 4.5 * se_p + extra_tol + 1e-4;
    CHECK_MSG(std::fabs(st.T_ratio - T_ref) < tol_r, what + ": ratio tracking T " + std::to_string(st.T_ratio) + " vs " +
                                                         std::to_string(T_ref) + " (tol " + std::to_string(tol_r) + ")");
    CHECK_MSG(std::fabs(st.P_coll - (1 - T_ref)) < tol_p, what + ": delta tracking P(coll) " + std::to_string(st.P_coll) +
                                                              " vs " + std::to_string(1 - T_ref));
    std::printf("  %s: T_ref %.5f  ratio %.5f (se %.5f)  delta 1-P %.5f (se %.5f)\n", what.c_str(), T_ref, st.T_ratio,
                st.T_ratio_se, 1 - st.P_coll, se_p);
}

TEST_CASE(tracking_vs_analytic_planar) {
    // cube of half-size 10: its top face z = 10 is the mean surface; near (0,0,10) f = z - 10.
    for (const char* params : {R"(<float name="sigma" value="0.05"/><string name="distribution" value="beckmann"/><float name="alpha" value="0.4"/>)",
                               R"(<float name="sigma" value="0.05"/><string name="distribution" value="gpss"/><float name="alpha" value="0.7"/>)",
                               R"(<float name="sigma" value="0.05"/><string name="distribution" value="ggx"/><float name="alpha_u" value="0.2"/><float name="alpha_v" value="0.6"/>)"}) {
        std::string xml = "<scene version=\"3.0.0\">" + camera(30, 30, 4, 4, 1) + medium_xml("m", params) +
                          R"(<shape type="cube"><transform name="to_world"><scale value="10"/></transform><ref name="interior" id="m"/></shape></scene>)";
        auto scene = build_scene(parse_scene_string(xml, "planar.xml", {}), BuildOptions(), nullptr);
        const MacrofacetMedium* m = first_macrofacet(*scene);
        CHECK(m != nullptr);
        if (!m) return;
        const double top = m->shell_top();
        CHECK_NEAR(top, 0.15, 1e-9);
        // a ray entering at the top face of the shell going down at 50° from the normal
        Vec3 d = normalize(Vec3(std::sin(0.87f), 0.3f * std::sin(0.87f), -std::cos(0.87f)));
        Ray r(Vec3(-0.2f, 0.1f, float(10 + top)), d);
        // The frame of the reference: the top face's normal and the tangent the medium uses there
        // (the cube's dp/du, Mitsuba's convention; it matters for the anisotropic GGX case).
        Vec3 tangent;
        m->surface().eval(r.o, nullptr, &tangent);
        mf_frame fr{{0, 0, 1}, {tangent.x, tangent.y, tangent.z}};
        mf_vec3 dd{d.x, d.y, d.z};
        for (float t : {0.1f, 0.2f, 0.35f}) {
            double T = 0;
            CHECK(mf_medium_transmittance(m->handle(), &fr, top, dd, t, &T) == MF_OK);
            compare_tracking(std::string("planar t=") + std::to_string(t), *m, r, t, T, 0.0);
        }
        // upwards from below the mean surface to beyond the shell (exits at f = top)
        Vec3 u = normalize(Vec3(0.4f, 0.0f, 1.0f));
        Ray r2(Vec3(0.0f, 0.0f, 10.0f - 0.03f), u);
        float tlen = float((top + 0.03) / u.z);
        double T = 0;
        CHECK(mf_medium_transmittance(m->handle(), &fr, -0.03, mf_vec3{u.x, u.y, u.z}, tlen, &T) == MF_OK);
        compare_tracking("planar upward", *m, r2, tlen, T, 0.0);
    }
}

TEST_CASE(tracking_vs_quadrature_curved) {
    // sphere r = 1, sigma = 0.1: a chord through the shell only (grazing the mean surface)
    std::string xml = "<scene version=\"3.0.0\">" + camera(30, 30, 4, 4, 1) +
                      medium_xml("m", R"(<float name="sigma" value="0.1"/><string name="distribution" value="gpss"/>
                                         <float name="alpha" value="0.5"/><float name="alpha_z" value="0.2"/>)") +
                      R"(<shape type="sphere"><ref name="interior" id="m"/></shape></scene>)";
    auto scene = build_scene(parse_scene_string(xml, "curved.xml", {}), BuildOptions(), nullptr);
    const MacrofacetMedium* m = first_macrofacet(*scene);
    CHECK(m != nullptr);
    if (!m) return;
    const double R = 1.0 + m->shell_top();
    for (double b : {1.02, 1.1, 0.9}) {  // impact parameter of the chord
        Vec3 d = normalize(Vec3(1.0f, 0.2f, 0.0f));
        Vec3 side = normalize(cross(d, Vec3(0, 0, 1)));
        double half = std::sqrt(R * R - b * b);
        Vec3 o = side * float(b) - d * float(half);
        // when the chord reaches the interior (b < 1) stop at the mean surface's first crossing
        double len = b < 1.0 ? half - std::sqrt(1.0 - b * b) + 0.05 : 2 * half;
        const int N = 20000;
        double h = len / N, tau = 0;
        for (int i = 0; i <= N; ++i) {
            Vec3 p = o + d * float(i * h);
            Vec3 n, tan;
            float f;
            double st = m->sigma_t_at(p, d, &n, &tan, &f);
            double w = (i == 0 || i == N) ? 1 : (i % 2 ? 4 : 2);
            tau += w * st;
        }
        tau *= h / 3;
        compare_tracking("sphere chord b=" + std::to_string(b), *m, Ray(o, d), float(len), std::exp(-tau), 2e-4);
    }
    CHECK(m->majorant_violations() == 0);
}

// ------------------------------------------------------------------------------------------
// White furnace

static void furnace(const std::string& name, const std::string& object, int spp) {
    Image img = render(name, furnace_scene(object, spp, 8, 30.0f));
    Stats s = check_furnace(name, img, 1.0, 1e-3);
    std::printf("  %-28s mean %.5f %.5f %.5f  se %.5f  (%.1f se)  max |dev| %.3f\n", name.c_str(), s.mean[0], s.mean[1],
                s.mean[2], s.se[0], std::fabs(s.mean[0] - 1) / std::max(s.se[0], 1e-12), s.maxdev);
}

static std::string sphere_with(const std::string& params, float radius = 0.7f) {
    return medium_xml("m", params) + "<shape type=\"sphere\"><float name=\"radius\" value=\"" + std::to_string(radius) +
           "\"/><ref name=\"interior\" id=\"m\"/></shape>";
}

TEST_CASE(white_furnace) {
    struct Ndf { const char* name; const char* params; };
    const Ndf ndfs[] = {
        {"beckmann", R"(<string name="distribution" value="beckmann"/><float name="alpha" value="0.5"/>)"},
        {"ggx", R"(<string name="distribution" value="ggx"/><float name="alpha" value="0.5"/>)"},
        {"gpss_az0", R"(<string name="distribution" value="gpss"/><float name="alpha_u" value="0.5"/><float name="alpha_v" value="0.3"/><float name="alpha_z" value="0"/>)"},
        {"gpss_iso", R"(<string name="distribution" value="gpss"/><float name="alpha" value="0.8"/>)"},
    };
    for (const Ndf& n : ndfs)
        for (const char* sigma : {"0.005", "0.1"})
            furnace(std::string("mf_furnace_") + n.name + "_s" + sigma,
                    sphere_with(std::string("<float name=\"sigma\" value=\"") + sigma + "\"/>" + n.params), 64);
    // the sphere-traced level set of a cube (analytic SDF with edges and corners)
    furnace("mf_furnace_cube", medium_xml("m", R"(<float name="sigma" value="0.03"/><string name="distribution" value="gpss"/><float name="alpha" value="0.6"/>)") +
                                   R"(<shape type="cube"><transform name="to_world"><scale value="0.45"/><rotate x="1" y="1" angle="35"/></transform><ref name="interior" id="m"/></shape>)",
            64);
    // a triangle mesh (mesh SDF + smooth frame normals): a 32x16 UV sphere as OBJ
    {
        std::ostringstream obj;
        const int R = 16, S = 32;
        obj << "v 0 0 0.7\n";
        for (int r = 1; r < R; ++r)
            for (int s = 0; s < S; ++s) {
                double th = 3.14159265358979 * r / R, ph = 2 * 3.14159265358979 * s / S;
                obj << "v " << 0.7 * std::sin(th) * std::cos(ph) << " " << 0.7 * std::sin(th) * std::sin(ph) << " "
                    << 0.7 * std::cos(th) << "\n";
            }
        obj << "v 0 0 -0.7\n";
        auto ring = [&](int r, int s) { return 2 + (r - 1) * S + (s % S); };
        for (int s = 0; s < S; ++s) obj << "f 1 " << ring(1, s) << " " << ring(1, s + 1) << "\n";
        for (int r = 1; r + 1 < R; ++r)
            for (int s = 0; s < S; ++s)
                obj << "f " << ring(r, s) << " " << ring(r + 1, s) << " " << ring(r + 1, s + 1) << " " << ring(r, s + 1) << "\n";
        int south = 2 + (R - 1) * S;
        for (int s = 0; s < S; ++s) obj << "f " << south << " " << ring(R - 1, s + 1) << " " << ring(R - 1, s) << "\n";
        write_file(work("mf_uvsphere.obj"), obj.str());
        furnace("mf_furnace_mesh", medium_xml("m", R"(<float name="sigma" value="0.02"/><string name="distribution" value="ggx"/><float name="alpha" value="0.4"/>)") +
                                       "<shape type=\"obj\"><string name=\"filename\" value=\"" + work("mf_uvsphere.obj") +
                                       "\"/><ref name=\"interior\" id=\"m\"/></shape>",
                64);
    }
}

// ------------------------------------------------------------------------------------------
// Thin-shell limit vs roughconductor (single scattering)

static std::string thin_scene(const std::string& object, int spp) {
    return "<scene version=\"3.0.0\"><integrator type=\"volpath\"><integer name=\"max_depth\" value=\"2\"/></integrator>" +
           camera(4.0f, 22.0f, 40, 40, spp) + object +
           R"(<shape type="rectangle"><transform name="to_world"><scale value="0.6"/><lookat origin="1.5, 1.8, 2.2" target="0, 0, 0" up="0, 0, 1"/></transform>
                <emitter type="area"><rgb name="radiance" value="6"/></emitter></shape>
              <emitter type="constant"><rgb name="radiance" value="0.4, 0.5, 0.6"/></emitter></scene>)";
}

// The camera rays of the thin-shell scene's pixel centres that hit the unit sphere with
// cos(view, n) >= 0.35 (the mask), as (pixel index, direction).
static std::vector<std::pair<size_t, Vec3>> thin_mask(int W, int H, float cos_min = 0.35f) {
    const float th = std::tan(0.5f * 22.0f * kPi / 180.0f);
    std::vector<std::pair<size_t, Vec3>> px;
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x) {
            // camera at +4z looking at the origin, up +y: image x -> world -x... the mask is symmetric
            double lx = (1 - 2 * (x + 0.5) / W) * th, ly = (1 - 2 * (y + 0.5) / H) * th;
            Vec3 d = normalize(Vec3(float(lx), float(ly), -1.0f));
            Vec3 o(0, 0, 4);
            float bq = dot(o, d), c = dot(o, o) - 1.0f, disc = bq * bq - c;
            if (disc <= 0) continue;
            float t = -bq - std::sqrt(disc);
            Vec3 n = normalize(o + d * t);
            if (dot(n, -d) < cos_min) continue;
            px.push_back({size_t(y) * W + x, d});
        }
    return px;
}

struct PairStats {
    double n = 0, rel = 0, md = 0, se = 0, mean_z = 0, sd_z = 0, max_z = 0;
    int over3 = 0, over45 = 0;
};

// a - b over the mask: the mean relative difference sum(a - b) / sum(b), the mean difference with
// its standard error (from the spread of the pixel-wise differences), and per-pixel z-scores
// with a brightness-dependent noise model var_i = k (a_i + b_i) (shot-noise like: the highlight
// is noisier than the dark limb), k fitted over the mask (so sd(z) = 1 by construction; the tail
// counts and the mean z are the information).
static PairStats compare_masked(const Image& a, const Image& b, const std::vector<std::pair<size_t, Vec3>>& mask) {
    std::vector<double> diff, vals;
    double sa = 0, sb = 0;
    for (const auto& m : mask)
        for (int ch = 0; ch < 3; ++ch) {
            size_t i = 3 * m.first + ch;
            diff.push_back(double(a.rgb[i]) - double(b.rgb[i]));
            vals.push_back(double(a.rgb[i]) + double(b.rgb[i]));
            sa += a.rgb[i];
            sb += b.rgb[i];
        }
    PairStats st;
    const double n = double(diff.size());
    st.n = n;
    double md = 0, v = 0;
    for (double d : diff) md += d / n;
    for (double d : diff) v += (d - md) * (d - md) / (n - 1);
    st.md = md;
    st.se = std::sqrt(v / n);
    st.rel = (sa - sb) / sb;
    double sum_d2 = 0, sum_ab = 0;
    for (size_t i = 0; i < diff.size(); ++i) {
        sum_d2 += diff[i] * diff[i];
        sum_ab += vals[i];
    }
    double k = sum_d2 / std::max(sum_ab, 1e-12), sz = 0, sz2 = 0;
    for (size_t i = 0; i < diff.size(); ++i) {
        double z = diff[i] / std::sqrt(k * std::max(vals[i], 1e-6));
        sz += z;
        sz2 += z * z;
        st.max_z = std::max(st.max_z, std::fabs(z));
        st.over3 += std::fabs(z) > 3;
        st.over45 += std::fabs(z) > 4.5;
    }
    st.mean_z = sz / n;
    st.sd_z = std::sqrt(std::max(0.0, sz2 / n - st.mean_z * st.mean_z));
    return st;
}

// Predicted ratio sum(separable) / sum(height-correlated) over the mask, by quadrature at the
// pixel centres: for each masked pixel, the single-scattering radiance = the mean over a 64x64
// stratified grid (plus a golden-ratio third coordinate) of BSDF (VNDF) samples of weight × (the area light's radiance where the sampled
// direction hits it, else the environment). The two modes share the sampling (the VNDF pdf has
// G1 only), so the grid is the same and only the weights differ.
static double predicted_ratio(const std::string& sep_xml, const std::string& hc_xml, float cos_min) {
    auto s_sep = build_scene(parse_scene_string(sep_xml, "sep.xml", {}), BuildOptions(), nullptr);
    auto s_hc = build_scene(parse_scene_string(hc_xml, "hc.xml", {}), BuildOptions(), nullptr);
    const Emitter* env = s_sep->infinite_emitters().empty() ? nullptr : s_sep->infinite_emitters()[0];
    const int G = 64;
    double sum[2] = {0, 0};
    for (const auto& m : thin_mask(40, 40, cos_min)) {
        for (int mode = 0; mode < 2; ++mode) {
            const Scene& sc = mode == 0 ? *s_sep : *s_hc;
            SurfaceHit h;
            if (!sc.intersect(Ray(Vec3(0, 0, 4), m.second), &h)) continue;
            // The integrator's frame: anisotropic roughness follows dp/du.
            Frame fr = Frame::shading(h.ns, h.dpdu);
            Vec3 wo_l = fr.to_local(-m.second);
            Rgb acc(0.0f);
            for (int i = 0; i < G; ++i)
                for (int j = 0; j < G; ++j) {
                    BsdfSample bs;
                    // The library's samplers (GTR) also read the lobe number: a third, well
                    // spread coordinate (golden-ratio sequence), unused by mfrender's own BSDFs.
                    float u3 = float(std::fmod(0.5 + 0.6180339887498949 * (i * G + j), 1.0));
                    if (!h.shape->bsdf->sample(wo_l, u3, Vec2((i + 0.5f) / G, (j + 0.5f) / G), &bs)) continue;
                    Vec3 wi = fr.to_world(bs.wi);
                    SurfaceHit lh;
                    Rgb Li(0.0f);
                    if (sc.intersect(Ray(h.p + h.ng * 1e-4f, wi), &lh)) {
                        if (lh.shape->emitter) Li = lh.shape->emitter->eval_surface(lh, -wi);
                    } else if (env) {
                        Li = env->eval_direction(wi);
                    }
                    acc += bs.weight * Li;
                }
            sum[mode] += (acc.r + acc.g + acc.b) / double(G * G);
        }
    }
    return sum[0] / sum[1];
}

// `extra`: further distribution parameters as XML (GTR's gamma, a microsurface transform).
static std::string rc_object(const std::string& dist, const std::string& alpha, const std::string& material,
                             const std::string& shadowing, const std::string& extra = "") {
    return "<shape type=\"sphere\"><bsdf type=\"roughconductor\"><string name=\"distribution\" value=\"" + dist +
           "\"/><float name=\"alpha\" value=\"" + alpha + "\"/><string name=\"material\" value=\"" + material +
           "\"/><string name=\"shadowing\" value=\"" + shadowing + "\"/>" + extra + "</bsdf></shape>";
}

// separable vs height_correlated roughconductor in the thin-shell scene, rendered with the same
// seed (identical sampled directions: only the G weights differ, so the ratio of image sums is
// nearly noise-free). Pixels whose centre sees the sphere at cos >= 0.3 (fully covered pixels,
// silhouette included). The ratio must be < 1 (G1 G1 <= G2) and match the quadrature prediction
// within 10 % of the deficit + 4.5 SE + 2e-5 (float accumulation).
static void separable_deficit(const std::string& name, const std::string& hc_exr, const std::string& dist,
                              const std::string& alpha, const std::string& material, int spp, bool render_hc,
                              const std::string& extra = "") {
    const std::string hc_xml = thin_scene(rc_object(dist, alpha, material, "height_correlated", extra), spp);
    const std::string sep_xml = thin_scene(rc_object(dist, alpha, material, "separable", extra), spp);
    if (render_hc) {
        write_file(work(name + "_hc.xml"), hc_xml);
        CHECK(run({work(name + "_hc.xml"), "-o", hc_exr, "--quiet", "--seed", "4"}) == 0);
    }
    write_file(work(name + "_sep.xml"), sep_xml);
    CHECK(run({work(name + "_sep.xml"), "-o", work(name + "_sep.exr"), "--quiet", "--seed", "4"}) == 0);
    Image hc = read_exr(hc_exr), sep = read_exr(work(name + "_sep.exr"));
    const auto mask = thin_mask(hc.width, hc.height, 0.3f);
    double ssep = 0, shc = 0;
    for (const auto& m : mask)
        for (int ch = 0; ch < 3; ++ch) {
            ssep += sep.rgb[3 * m.first + ch];
            shc += hc.rgb[3 * m.first + ch];
        }
    const double ratio = ssep / shc;
    double ve = 0;
    const double n = 3.0 * double(mask.size());
    for (const auto& m : mask)
        for (int ch = 0; ch < 3; ++ch) {
            double e = sep.rgb[3 * m.first + ch] - ratio * hc.rgb[3 * m.first + ch];
            ve += e * e / (n - 1);
        }
    const double ratio_se = std::sqrt(ve * n) / shc;  // delta method
    const double pred = predicted_ratio(thin_scene(rc_object(dist, alpha, material, "separable", extra), 1),
                                        thin_scene(rc_object(dist, alpha, material, "height_correlated", extra), 1), 0.3f);
    CHECK_MSG(ratio <= 1.0 + 2e-5, name + ": separable/height_correlated = " + std::to_string(ratio) + " > 1");
    CHECK_MSG(std::fabs(ratio - pred) < 0.1 * (1 - pred) + 4.5 * ratio_se + 2e-5,
              name + ": separable/height_correlated = " + std::to_string(ratio) + " vs predicted " + std::to_string(pred));
    std::printf("  %s: separable/height_correlated = %.6f (se %.6f), predicted %.6f (deficit %.4f %%)\n", name.c_str(), ratio,
                ratio_se, pred, 100 * (1 - pred));
}

static void thin_shell(const std::string& name, const std::string& dist, const std::string& alpha, const std::string& material,
                       const std::string& extra = "") {
    const int spp = 256;
    // sigma = 1e-4 r: the shell's finite-thickness bias (measured ~ +1.5 sigma/r, README) is then
    // ~20x below the Monte Carlo standard error, so no allowance is needed
    std::string mfobj = medium_xml("m", "<float name=\"sigma\" value=\"0.0001\"/><string name=\"distribution\" value=\"" + dist +
                                            "\"/><float name=\"alpha\" value=\"" + alpha + "\"/><string name=\"material\" value=\"" +
                                            material + "\"/>" + extra) +
                        R"(<shape type="sphere"><ref name="interior" id="m"/></shape>)";
    write_file(work(name + "_mf.xml"), thin_scene(mfobj, spp));
    write_file(work(name + "_hc.xml"), thin_scene(rc_object(dist, alpha, material, "height_correlated", extra), spp));
    CHECK(run({work(name + "_mf.xml"), "-o", work(name + "_mf.exr"), "--quiet", "--seed", "3"}) == 0);
    CHECK(run({work(name + "_hc.xml"), "-o", work(name + "_hc.exr"), "--quiet", "--seed", "4"}) == 0);
    Image a = read_exr(work(name + "_mf.exr")), hc = read_exr(work(name + "_hc.exr"));
    const auto mask = thin_mask(a.width, a.height);

    // thin shell vs height-correlated roughconductor: no allowance beyond Monte Carlo error
    PairStats st = compare_masked(a, hc, mask);
    CHECK_MSG(std::fabs(st.md) < 4.5 * st.se, name + ": macrofacet - height_correlated mean difference " +
                                                  std::to_string(st.md) + " = " + std::to_string(st.md / st.se) + " se");
    // |z| > 4.5 has probability 7e-6 for a normal z; the fitted shot-noise model is only
    // approximate in the highlight (heavier tails at 256 spp): allow 3 in 1000
    CHECK_MSG(st.over45 <= 0.003 * st.n, name + ": " + std::to_string(st.over45) + " of " + std::to_string(int(st.n)) +
                                            " pixel values with |z| > 4.5");
    std::printf("  %s: mf vs rc(height_correlated): %d masked values, mean rel diff %+.5f, mean diff %+.6f = %+.2f se;"
                " z: mean %+.4f sd %.3f max|z| %.2f, |z|>3: %d (%.2f%%, normal 0.27%%), |z|>4.5: %d\n",
                name.c_str(), int(st.n), st.rel, st.md, st.md / st.se, st.mean_z, st.sd_z, st.max_z, st.over3,
                100.0 * st.over3 / st.n, st.over45);
    separable_deficit(name, work(name + "_hc.exr"), dist, alpha, material, spp, false, extra);
}

TEST_CASE(thin_shell_vs_roughconductor) {
    thin_shell("thin_beckmann_Au", "beckmann", "0.3", "Au");
    thin_shell("thin_ggx_none", "ggx", "0.2", "none");
    // seeds/001: the heavy-tailed GTR, stretched (Eq. 31) along the spheres' dp/du, in the
    // medium and in roughconductor (both from the library)
    thin_shell("thin_gtr_stretched_Ag", "gtr", "0.25", "Ag", R"(<float name="gamma" value="1.5"/><float name="stretch" value="0.4"/>)");
    // a rough GGX (long tails, Lambda far from 0 at the limb): a clearly measurable deficit
    separable_deficit("shadowing_ggx_rough", work("shadowing_ggx_rough_hc.exr"), "ggx", "0.6", "none", 64, true);
}

// ------------------------------------------------------------------------------------------
// Unbiased convergence and determinism

static const char* kSmallScene = R"(
    <shape type="rectangle"><transform name="to_world"><scale value="3"/><translate z="-0.8"/></transform>
      <bsdf type="diffuse"><rgb name="reflectance" value="0.6, 0.5, 0.4"/></bsdf></shape>
    <medium type="macrofacet" id="mf"><float name="sigma" value="0.04"/><string name="distribution" value="gpss"/>
      <float name="alpha" value="0.5"/><float name="alpha_z" value="0.25"/><string name="material" value="Cu"/></medium>
    <shape type="sphere"><point name="center" x="-0.45" y="0" z="0"/><float name="radius" value="0.4"/><ref name="interior" id="mf"/></shape>
    <shape type="sphere"><point name="center" x="0.45" y="0" z="0"/><float name="radius" value="0.4"/><bsdf type="null"/>
      <medium type="homogeneous" name="interior"><rgb name="sigma_t" value="0.6, 0.8, 1"/><float name="scale" value="5"/><rgb name="albedo" value="0.9"/>
      <phase type="hg"><float name="g" value="0.4"/></phase></medium></shape>
    <shape type="rectangle"><transform name="to_world"><scale value="0.5"/><lookat origin="0, 1.5, 2" target="0, 0, 0" up="0, 0, 1"/></transform>
      <emitter type="area"><rgb name="radiance" value="5"/></emitter></shape>
    <emitter type="constant"><rgb name="radiance" value="0.3"/></emitter></scene>)";

static std::string small_scene(int spp) {
    return "<scene version=\"3.0.0\"><integrator type=\"volpath\"/>" + camera(3.5f, 40.0f, 32, 24, spp) + kSmallScene;
}

TEST_CASE(unbiased_convergence) {
    // Left half of the image: the macrofacet sphere; right half: the homogeneous one.
    write_file(work("conv_32.xml"), small_scene(32));
    write_file(work("conv_128.xml"), small_scene(128));
    CHECK(run({work("conv_32.xml"), "-o", work("conv_32.exr"), "--quiet", "--seed", "1"}) == 0);
    CHECK(run({work("conv_128.xml"), "-o", work("conv_128.exr"), "--quiet", "--seed", "2"}) == 0);
    Image a = read_exr(work("conv_32.exr")), b = read_exr(work("conv_128.exr"));
    for (int half = 0; half < 2; ++half) {
        // per-half image means and their SEs (pixel means with their own spread across seeds is
        // unknown; use the spread of pixel-wise differences, which is pure noise if unbiased)
        std::vector<double> d;
        double sa = 0;
        for (int y = 0; y < a.height; ++y)
            for (int x = half * a.width / 2; x < (half + 1) * a.width / 2; ++x)
                for (int c = 0; c < 3; ++c) {
                    size_t i = 3 * (size_t(y) * a.width + x) + c;
                    d.push_back(double(a.rgb[i]) - double(b.rgb[i]));
                    sa += b.rgb[i];
                }
        double n = double(d.size()), m = 0, v = 0;
        for (double x : d) m += x / n;
        for (double x : d) v += (x - m) * (x - m) / (n - 1);
        double se = std::sqrt(v / n);
        CHECK_MSG(std::fabs(m) < 4.5 * se + 1e-4, std::string(half ? "homogeneous" : "macrofacet") + " half: 32 vs 128 spp mean diff " +
                                                      std::to_string(m) + " se " + std::to_string(se));
        std::printf("  %s half: mean %.5f, 32 spp - 128 spp = %+.5f (%.2f se)\n", half ? "homogeneous" : "macrofacet", sa / n, m,
                    m / se);
    }
}

// The boundary form (mitsuba_plugin/; Mitsuba with the plugin reads it too): the medium nests
// its mean surface and a null-BSDF shape is the boundary rays enter through. With the tight
// boundary (radius r + k sigma) and a loose one (r + 3 k sigma) the image equals the
// mean-surface form's (mfrender's own boundary) within 4.5 SE of the pixel-wise differences.
// So does the mean-surface form with --media-boundaries: its boundary traced in the BVH, where
// by default the medium in vacuum is tracked along every ray over the boundary's chord
// (SuperposedMedium).
/// The mean of `ref` and the mean pixel difference b - ref with its standard error.
static void mean_difference(const Image& ref, const Image& b, double* mean, double* m, double* se) {
    const double n = double(ref.rgb.size());
    double v = 0;
    *m = *mean = 0;
    for (size_t i = 0; i < ref.rgb.size(); ++i) {
        *m += (double(b.rgb[i]) - ref.rgb[i]) / n;
        *mean += ref.rgb[i] / n;
    }
    for (size_t i = 0; i < ref.rgb.size(); ++i) {
        const double d = double(b.rgb[i]) - ref.rgb[i] - *m;
        v += d * d / (n - 1);
    }
    *se = std::sqrt(v / n);
}

/// `scene` rendered with `flag`, a mode that must change only the noise (seed 1), against the
/// default (seed 2): their means agree within 4.5 standard errors.
static void expect_same_image(const std::string& scene, const std::string& flag, const std::string& what) {
    const std::string flagged = work(what + "_flagged.exr"), plain = work(what + "_default.exr");
    CHECK(run({scene, "-o", flagged, "--quiet", "--seed", "1", flag}) == 0);
    CHECK(run({scene, "-o", plain, "--quiet", "--seed", "2"}) == 0);
    double mean, m, se;
    mean_difference(read_exr(flagged), read_exr(plain), &mean, &m, &se);
    CHECK_MSG(std::fabs(m) < 4.5 * se + 1e-4, what + ": default - " + flag + " = " + std::to_string(m) + " (se " + std::to_string(se) + ")");
    std::printf("  %s: mean %.5f, default - %s = %+.5f (%.2f se)\n", what.c_str(), mean, flag.c_str(), m, m / se);
}

TEST_CASE(boundary_form) {
    const std::string params = R"(<float name="sigma" value="0.04"/><string name="distribution" value="gpss"/>)"
                               R"(<float name="alpha" value="0.5"/><float name="alpha_z" value="0.25"/><string name="material" value="Cu"/>)";
    const std::string lights = R"(<shape type="rectangle"><transform name="to_world"><scale value="0.5"/><lookat origin="0, 1.5, 2" target="0, 0, 0" up="0, 0, 1"/></transform>
        <emitter type="area"><rgb name="radiance" value="5"/></emitter></shape><emitter type="constant"><rgb name="radiance" value="0.3"/></emitter>)";
    auto scene = [&](const std::string& sphere) {
        return "<scene version=\"3.0.0\"><integrator type=\"volpath\"/>" + camera(3.0f, 40.0f, 24, 24, 64) + sphere + lights + "</scene>";
    };
    write_file(work("form_mean.xml"), scene(medium_xml("mf", params) + R"(<shape type="sphere"><ref name="interior" id="mf"/></shape>)"));
    CHECK(run({work("form_mean.xml"), "-o", work("form_mean.exr"), "--quiet", "--seed", "1"}) == 0);
    const Image ref = read_exr(work("form_mean.exr"));
    for (const char* radius : {"1.12", "1.36", "traced"}) {
        const bool traced = std::string(radius) == "traced";
        const std::string name = std::string("form_boundary_") + radius;
        if (traced) {
            write_file(work(name + ".xml"), read_file(work("form_mean.xml")));
            CHECK(run({work(name + ".xml"), "-o", work(name + ".exr"), "--quiet", "--seed", "2", "--media-boundaries"}) == 0);
        } else {
            write_file(work(name + ".xml"), scene(medium_xml("mf", params + R"(<shape type="sphere" name="mean_surface"/>)") +
                                                  R"(<shape type="sphere"><float name="radius" value=")" + radius +
                                                  R"("/><bsdf type="null"/><ref name="interior" id="mf"/></shape>)"));
            CHECK(run({work(name + ".xml"), "-o", work(name + ".exr"), "--quiet", "--seed", "2"}) == 0);
        }
        double mean, m, se;
        mean_difference(ref, read_exr(work(name + ".exr")), &mean, &m, &se);
        CHECK_MSG(std::fabs(m) < 4.5 * se + 1e-4, name + ": boundary form - mean-surface form = " + std::to_string(m) + " (se " +
                                                      std::to_string(se) + ")");
        std::printf("  boundary %s: mean %.5f, boundary form - mean-surface form = %+.5f (%.2f se)\n", radius, mean, m, m / se);
    }
}

// A torus mesh shell cut by a floor (the shapes near its region): the tracker finds each ray's
// exit from the enclosure (SceneBuilder::let_media_find_exits) and renders what casting a ray for
// every exit renders (--cast-exits).
// A scene `name`.xml: a torus mesh shell (32 x 12 quads) cut by a diffuse floor, lit by an area
// light and a constant environment.
static std::string torus_shell_scene(const std::string& name) {
    std::ostringstream obj;
    const int U = 32, V = 12;
    for (int i = 0; i < U; ++i)
        for (int j = 0; j < V; ++j) {
            const double u = 2 * 3.14159265358979 * i / U, v = 2 * 3.14159265358979 * j / V, r = 0.6 + 0.25 * std::cos(v);
            obj << "v " << r * std::cos(u) << " " << r * std::sin(u) << " " << 0.25 * std::sin(v) << "\n";
        }
    auto at = [&](int i, int j) { return 1 + (i % U) * V + (j % V); };
    for (int i = 0; i < U; ++i)
        for (int j = 0; j < V; ++j) obj << "f " << at(i, j) << " " << at(i + 1, j) << " " << at(i + 1, j + 1) << " " << at(i, j + 1) << "\n";
    write_file(work(name + "_torus.obj"), obj.str());
    const std::string xml = "<scene version=\"3.0.0\"><integrator type=\"volpath\"/>" + camera(3.0f, 40.0f, 24, 24, 64) +
                            medium_xml("mf", R"(<float name="sigma" value="0.01"/><string name="distribution" value="ggx"/><float name="alpha" value="0.3"/><string name="material" value="Au"/>)") +
                            R"(<shape type="obj"><string name="filename" value=")" + work(name + "_torus.obj") + R"("/><ref name="interior" id="mf"/></shape>
        <shape type="rectangle"><transform name="to_world"><scale value="2"/><translate z="-0.15"/></transform>
          <bsdf type="diffuse"><rgb name="reflectance" value="0.5"/></bsdf></shape>
        <shape type="rectangle"><transform name="to_world"><scale value="0.5"/><lookat origin="0, 1.5, 2" target="0, 0, 0" up="0, 0, 1"/></transform>
          <emitter type="area"><rgb name="radiance" value="5"/></emitter></shape><emitter type="constant"><rgb name="radiance" value="0.3"/></emitter></scene>)";
    write_file(work(name + ".xml"), xml);
    return xml;
}

TEST_CASE(media_find_their_exits) {
    const std::string xml = torus_shell_scene("exits");
    for (bool finds : {true, false}) {
        BuildOptions o;
        o.media_find_exits = finds;
        auto scene = build_scene(parse_scene_string(xml, work("exits.xml"), {}), o, nullptr);
        const MacrofacetMedium* m = first_macrofacet(*scene);
        CHECK(m && m->finds_exits() == finds);
    }
    expect_same_image(work("exits.xml"), "--cast-exits", "exits");
}

// The next-event rays' contribution roulette (IntegratorSettings::shadow_roulette) on the torus
// shell and its floor: it draws (the same seed renders another image), and the image is the one
// that traces every next-event ray (--no-shadow-roulette), to noise.
TEST_CASE(shadow_roulette) {
    const std::string xml = torus_shell_scene("roulette");
    const auto threshold = [&](bool roulette) {
        BuildOptions o;
        o.shadow_roulette = roulette;
        return build_scene(parse_scene_string(xml, work("roulette.xml"), {}), o, nullptr)->integrator.shadow_roulette;
    };
    CHECK(threshold(true) == kShadowRoulette && threshold(false) == 0.0f);
    const std::string with = work("roulette_on.exr"), without = work("roulette_off.exr");
    CHECK(run({work("roulette.xml"), "-o", with, "--quiet", "--seed", "3", "--spp", "4"}) == 0);
    CHECK(run({work("roulette.xml"), "-o", without, "--quiet", "--seed", "3", "--spp", "4", "--no-shadow-roulette"}) == 0);
    CHECK_MSG(read_file(with) != read_file(without), "the roulette changed no path");
    expect_same_image(work("roulette.xml"), "--no-shadow-roulette", "shadow_roulette");
}

// A thin shell's opaque core (mf_track_opaque_core, Scene::add_opaque_core) ends the shadow rays
// that meet it from above its start level, and the depth roulette (mf_track_depth_roulette,
// Scene::shadow_roulette) keeps those that descend into the shell with a probability of their
// transmittance's bound over 0.5: the image is the one that tracks them all
// (--no-opaque-cores), to noise. The geometric test takes only such rays, and only where they
// reach the core before their end; the roulette, only rays that descend.
TEST_CASE(opaque_cores) {
    const std::string xml = "<scene version=\"3.0.0\"><integrator type=\"volpath\"/>" + camera(3.0f, 40.0f, 24, 24, 64) +
                            medium_xml("mf", R"(<float name="sigma" value="0.002"/><string name="distribution" value="beckmann"/><float name="alpha" value="0.3"/><string name="material" value="Au"/>)") +
                            R"(<shape type="sphere"><ref name="interior" id="mf"/></shape>
        <shape type="rectangle"><transform name="to_world"><scale value="3"/><translate z="-1.2"/></transform>
          <bsdf type="diffuse"><rgb name="reflectance" value="0.5"/></bsdf></shape>
        <emitter type="constant"><rgb name="radiance" value="1"/></emitter></scene>)";
    write_file(work("cores.xml"), xml);
    for (bool cores : {true, false}) {
        BuildOptions o;
        o.opaque_cores = cores;
        auto scene = build_scene(parse_scene_string(xml, work("cores.xml"), {}), o, nullptr);
        const MacrofacetMedium* m = first_macrofacet(*scene);
        double start = 0, core = 0;
        CHECK(m && m->opaque_core(&start, &core));
        CHECK_MSG(start == -8 * 0.002 && core < -30 * 0.002 && core > -50 * 0.002, "core " + std::to_string(core));
        const float above = 1.0f + float(start) + 1e-4f, inf = std::numeric_limits<float>::infinity();
        CHECK(scene->blocked_by_opaque_core(Vec3(0, 0, above), Vec3(0, 0, -1), inf) == cores);
        CHECK(scene->blocked_by_opaque_core(Vec3(0, 0, 2), Vec3(0, 0, -1), inf) == cores);        // from outside the shell
        CHECK(!scene->blocked_by_opaque_core(Vec3(0, 0, above), Vec3(0, 0, 1), inf));            // outward
        CHECK(!scene->blocked_by_opaque_core(Vec3(0, 0, above), Vec3(1, 0, 0), inf));            // above the core all along
        CHECK(!scene->blocked_by_opaque_core(Vec3(0, 0, above), Vec3(0, 0, -1), float(-0.5 * core)));  // ends before it
        CHECK(!scene->blocked_by_opaque_core(Vec3(0, 0, 1.0f + 1.5f * float(start)), Vec3(0, 0, -1), inf));  // below the start level
        CHECK(!scene->blocked_by_opaque_core(Vec3(0, 0, 0.5f), Vec3(0, 0, -1), inf));           // inside the core
        // From the mean surface: outward, grazing (1° under the tangent plane: 0.08σ deep, a bound
        // of 0.94) and 10° under it (7.6σ deep, a bound of about Φ(−7.6)/Φ(0) ≈ 3e-14).
        Sampler sampler(1, 2, 3);
        const auto below = [](double degrees) {
            const double a = degrees * 3.14159265358979 / 180;
            return Vec3(float(std::cos(a)), 0.0f, float(-std::sin(a)));
        };
        const Vec3 top(0, 0, 1);
        int kept = 0;
        for (int i = 0; i < 200; ++i) {
            const Scene::ShadowRoulette out = scene->shadow_roulette(top, Vec3(0.6f, 0.0f, 0.8f), inf, sampler);
            const Scene::ShadowRoulette graze = scene->shadow_roulette(top, below(1), inf, sampler);
            const Scene::ShadowRoulette steep = scene->shadow_roulette(top, below(10), inf, sampler);
            CHECK(out.survival == 1.0 && out.medium == nullptr);
            CHECK(graze.survival == 1.0);
            CHECK(steep.medium == (cores ? m : nullptr));
            CHECK(cores ? steep.survival == 0.0 || (steep.survival > 0 && steep.survival < 1e-3) : steep.survival == 1.0);
            kept += steep.survival > 0;
        }
        CHECK_MSG(cores ? kept <= 2 : kept == 200, "kept " + std::to_string(kept));
        // Both verdicts at once, for a next-event ray: a core in the way ends it.
        CHECK(scene->next_event_roulette(Vec3(0, 0, above), Vec3(0, 0, -1), inf, sampler).survival == (cores ? 0.0 : 1.0));
        CHECK(scene->next_event_roulette(top, Vec3(0.6f, 0.0f, 0.8f), inf, sampler).survival == 1.0);
    }
    expect_same_image(work("cores.xml"), "--no-opaque-cores", "opaque_cores");
}

TEST_CASE(determinism) {
    write_file(work("mf_det.xml"), small_scene(8));
    const std::string a = work("mf_det_a.exr"), b = work("mf_det_b.exr"), c = work("mf_det_c.exr");
    CHECK(run({work("mf_det.xml"), "-o", a, "--quiet", "--seed", "9", "--threads", "2"}) == 0);
    CHECK(run({work("mf_det.xml"), "-o", b, "--quiet", "--seed", "9", "--threads", "2"}) == 0);
    CHECK(run({work("mf_det.xml"), "-o", c, "--quiet", "--seed", "9", "--threads", "1"}) == 0);
    std::string fa = read_file(a);
    CHECK(!fa.empty());
    CHECK(fa == read_file(b));
    CHECK(fa == read_file(c));
}

// The tracking counts that mfrender prints are per-thread tallies summed: the same at 1 and 3
// threads (the render is deterministic), and every rendering thread gives its slot back.
TEST_CASE(tracking_counts_across_threads) {
    auto scene = build_scene(parse_scene_string(small_scene(4), work("mf_counts.xml"), {}), BuildOptions(), nullptr);
    const MacrofacetMedium* medium = nullptr;
    for (const auto& m : scene->media)
        if (auto* mm = dynamic_cast<const MacrofacetMedium*>(m.get())) medium = mm;
    CHECK(medium != nullptr);
    if (!medium) return;
    const unsigned held_before = tally_slots_held();
    TrackCounts counts[2];
    for (int i = 0; i < 2; ++i) {
        const TrackCounts before = medium->counts();
        RenderOptions o;
        o.threads = i == 0 ? 1 : 3;
        RenderStats st;
        render_film(*scene, o, &st);
        const TrackCounts after = medium->counts();
        counts[i] = {after.calls - before.calls, after.surface_queries - before.surface_queries, after.segments - before.segments,
                     after.tentative_collisions - before.tentative_collisions, after.majorant_violations - before.majorant_violations};
        CHECK(tally_slots_held() == held_before);
    }
    CHECK(counts[0].calls > 1000);
    CHECK(counts[0].calls == counts[1].calls);
    CHECK(counts[0].surface_queries == counts[1].surface_queries);
    CHECK(counts[0].segments == counts[1].segments);
    CHECK(counts[0].tentative_collisions == counts[1].tentative_collisions);
    CHECK(counts[0].majorant_violations == 0 && counts[1].majorant_violations == 0);
    std::printf("  tracking counts: %llu calls, %llu surface queries at 1 and 3 threads\n", (unsigned long long)counts[0].calls,
                (unsigned long long)counts[0].surface_queries);
}

TEST_MAIN()
