// BSDF / microfacet tests.
//  * Fresnel: closed forms at normal incidence, TIR, "none" = 1 (tolerance 1e-6, float).
//  * For Beckmann and GGX, isotropic and anisotropic, visible and non-visible sampling:
//    (a) D is normalised: ∫ D(m) cos θm dm = 1; (b) the visible-normal density integrates to 1:
//    ∫ G1(wi,m) <wi,m>+ D(m) / cos θi dm = 1 (checks Λ against D); (c) the pdf reported by
//    sample() equals pdf() of the sampled direction; (d) the directional albedo estimated by
//    BSDF sampling (mean of weights) equals the one estimated by uniform hemisphere sampling of
//    eval(). (a,b,d) are Monte Carlo estimates: the tolerance is 5 standard errors (measured
//    from the samples) plus 2e-3 for the float arithmetic.
//  * The same for the library's distributions behind roughconductor (mf_ndf: GTR, transforms).
#include <macrofacet.h>

#include <complex>
#include <random>
#include <vector>

#include "bsdf.h"
#include "check.h"
#include "microfacet.h"
#include "sampler.h"

using namespace mf;

TEST_CASE(fresnel) {
    CHECK_NEAR(fresnel_dielectric(1.0f, 1.5f, nullptr), 0.04, 1e-6);
    CHECK_NEAR(fresnel_dielectric(-1.0f, 1.5f, nullptr), 0.04, 1e-6);
    CHECK_NEAR(fresnel_dielectric(-0.3f, 1.5f, nullptr), 1.0, 0);  // inside, beyond the critical angle
    float eta = 0.2f, k = 3.0f;
    double r0 = ((1 - eta) * (1 - eta) + k * k) / ((1 + eta) * (1 + eta) + k * k);
    CHECK_NEAR(fresnel_conductor(1.0f, eta, k), r0, 1e-6);
    CHECK_NEAR(fresnel_conductor(1e-4f, eta, k), 1.0, 1e-3);  // grazing
    // k = 0 reduces to the dielectric formula
    CHECK_NEAR(fresnel_conductor(0.6f, 1.5f, 0.0f), fresnel_dielectric(0.6f, 1.5f, nullptr), 1e-6);
    // The real-arithmetic form against the complex amplitudes r_s, r_p themselves, over angles
    // and IORs from the presets' range (and below 1, where a dielectric reflects totally).
    auto amplitudes = [](double c, double eta, double k) {
        using C = std::complex<double>;
        C n(eta, k), cos_t = std::sqrt(1.0 - (1.0 - c * c) / (n * n));
        C r_s = (c - n * cos_t) / (c + n * cos_t), r_p = (n * c - cos_t) / (n * c + cos_t);
        return 0.5 * (std::norm(r_s) + std::norm(r_p));
    };
    double worst = 0;  // NaN-propagating: a NaN anywhere fails the check
    for (float eta_i : {0.05f, 0.2f, 0.7f, 1.0f, 1.5f, 3.0f})
        for (float k_i : {0.0f, 0.5f, 3.0f, 8.0f})
            for (int j = 0; j <= 100; ++j) {
                float c = j / 100.0f;
                if (eta_i == 1.0f && k_i == 0.0f && j == 0) continue;  // 0/0 in both forms, below
                double diff = std::fabs(fresnel_conductor(c, eta_i, k_i) - amplitudes(c, eta_i, k_i));
                if (!(diff <= worst)) worst = diff;
            }
    CHECK_NEAR(worst, 0.0, 1e-6);
    // An index-matched interface at grazing incidence: 0, the limit along its other angles.
    CHECK_NEAR(fresnel_conductor(0.0f, 1.0f, 0.0f), 0.0, 0);
    ConductorIor ior;
    CHECK(conductor_preset("none", &ior) && ior.perfect);
    CHECK(conductor_preset("Au", &ior) && !ior.perfect);
    CHECK(!conductor_preset("Xx", &ior));
    float n;
    CHECK(dielectric_ior_by_name("bk7", &n) && std::fabs(n - 1.5046f) < 1e-6f);
}

static Vec3 uniform_hemisphere(const Vec2& u) {
    float z = u.x, r = safe_sqrt(1 - z * z), phi = 2 * kPi * u.y;
    return Vec3(r * std::cos(phi), r * std::sin(phi), z);
}

struct Est {
    double sum = 0, sum2 = 0;
    long n = 0;
    void add(double v) { sum += v; sum2 += v * v; ++n; }
    double mean() const { return sum / n; }
    double se() const { double m = mean(); return std::sqrt(std::max(0.0, sum2 / n - m * m) / n); }
};

/// Checks (a)-(d) for a distribution `mf` and its roughconductor `bsdf` at incidence `wi`.
template <class Distribution>
static void check_microfacet_consistency(const std::string& name, const Distribution& mf, const Bsdf& bsdf, const Vec3& wi, int N) {
    Est normD, normV, alb_s, alb_u;
    int pdf_mismatch = 0;
    Sampler s(1, 2, 3);
    for (int i = 0; i < N; ++i) {
        // (a), (b), (d-uniform): uniform hemisphere sampling, pdf 1/(2π)
        Vec3 m = uniform_hemisphere(s.next_2d());
        double D = mf.D(m);
        normD.add(D * m.z * 2 * M_PI);
        normV.add(mf.G1(wi, m) * std::max(0.0f, dot(wi, m)) * D / wi.z * 2 * M_PI);
        Vec3 wo = uniform_hemisphere(s.next_2d());
        alb_u.add(bsdf.eval(wi, wo).r * 2 * M_PI);
        // (c), (d-sampled)
        BsdfSample bs;
        if (bsdf.sample(wi, s.next_1d(), s.next_2d(), &bs)) {
            alb_s.add(bs.weight.r);
            float p = bsdf.pdf(wi, bs.wi);
            if (std::fabs(p - bs.pdf) > 1e-3f * std::max(1.0f, p)) ++pdf_mismatch;
        } else {
            alb_s.add(0.0);
        }
    }
    std::string tag = name + " wi.z=" + std::to_string(wi.z);
    CHECK_MSG(std::fabs(normD.mean() - 1) < 5 * normD.se() + 2e-3, tag + " ∫D cos = " + std::to_string(normD.mean()) + " ± " + std::to_string(normD.se()));
    CHECK_MSG(std::fabs(normV.mean() - 1) < 5 * normV.se() + 2e-3, tag + " ∫D_wi = " + std::to_string(normV.mean()) + " ± " + std::to_string(normV.se()));
    CHECK_MSG(pdf_mismatch == 0, tag + " pdf mismatches: " + std::to_string(pdf_mismatch));
    double diff = std::fabs(alb_s.mean() - alb_u.mean());
    double tol = 5 * std::sqrt(alb_s.se() * alb_s.se() + alb_u.se() * alb_u.se()) + 2e-3;
    CHECK_MSG(diff < tol, tag + " albedo sampled " + std::to_string(alb_s.mean()) + " vs integrated " +
                              std::to_string(alb_u.mean()) + " (tol " + std::to_string(tol) + ")");
    CHECK_MSG(alb_s.mean() <= 1.0 + 5 * alb_s.se(), tag + " albedo > 1");
}

TEST_CASE(microfacet_consistency) {
    struct Config { MicrofacetType t; float au, av; bool vis; const char* name; };
    const Config cfgs[] = {
        {MicrofacetType::Beckmann, 0.3f, 0.3f, true, "beckmann iso vndf"},
        {MicrofacetType::Beckmann, 0.1f, 0.5f, true, "beckmann aniso vndf"},
        {MicrofacetType::Beckmann, 0.3f, 0.3f, false, "beckmann iso D"},
        {MicrofacetType::GGX, 0.3f, 0.3f, true, "ggx iso vndf"},
        {MicrofacetType::GGX, 0.6f, 0.15f, true, "ggx aniso vndf"},
        {MicrofacetType::GGX, 0.3f, 0.3f, false, "ggx iso D"},
    };
    const Vec3 wis[] = {normalize(Vec3(0.1f, 0.0f, 1.0f)), normalize(Vec3(0.6f, 0.5f, 0.4f)), normalize(Vec3(-0.9f, 0.2f, 0.15f))};
    ConductorIor none;
    conductor_preset("none", &none);
    const int N = 200000;
    for (const Config& c : cfgs) {
        Microfacet mf(c.t, c.au, c.av, c.vis);
        auto bsdf = make_rough_conductor(none, make_constant_texture(Rgb(1.0f)), c.t, c.au, c.av, c.vis);
        for (const Vec3& wi : wis) check_microfacet_consistency(c.name, mf, *bsdf, wi, N);
    }
}

// The library's distributions behind roughconductor (GTR and microsurface transforms, seeds/001):
// D and the visible normals integrate to 1, sampling agrees with eval/pdf.
TEST_CASE(library_microfacet_consistency) {
    struct Config { const char* name; std::vector<std::pair<const char*, double>> floats; const char* dist; };
    const Config cfgs[] = {
        {"gtr 1.5", {{"alpha", 0.3}, {"gamma", 1.5}}, "gtr"},
        {"gtr 3 skew", {{"alpha", 0.25}, {"gamma", 3.0}, {"transform_xx", 1}, {"transform_xy", 2}, {"transform_yx", 0}, {"transform_yy", 1}}, "gtr"},
        {"ggx stretch", {{"alpha", 0.3}, {"stretch", -0.5}}, "ggx"},
    };
    const Vec3 wis[] = {normalize(Vec3(0.1f, 0.0f, 1.0f)), normalize(Vec3(0.6f, 0.5f, 0.4f)), normalize(Vec3(-0.9f, 0.2f, 0.15f))};
    ConductorIor none;
    conductor_preset("none", &none);
    const int N = 100000;
    for (const Config& c : cfgs) {
        mf_params* p = nullptr;
        CHECK(mf_params_new(&p) == MF_OK);
        CHECK(mf_params_set_string(p, "distribution", c.dist) == MF_OK);
        for (const auto& f : c.floats) CHECK(mf_params_set_float(p, f.first, f.second) == MF_OK);
        auto mf = make_library_microfacet(p, false, c.name);
        mf_params_free(p);
        auto bsdf = make_rough_conductor(none, make_constant_texture(Rgb(1.0f)), mf);
        for (const Vec3& wi : wis) check_microfacet_consistency(c.name, *mf, *bsdf, wi, N);
    }
}

TEST_CASE(diffuse_and_dielectric) {
    auto d = make_diffuse(Rgb(0.5f));
    BsdfSample bs;
    Sampler s(0, 0, 0);
    CHECK(d->sample(Vec3(0, 0, 1), s.next_1d(), s.next_2d(), &bs));
    CHECK_NEAR(bs.weight.g, 0.5, 1e-6);
    CHECK(!d->sample(Vec3(0, 0, -1), 0.5f, Vec2(0.5f, 0.5f), &bs));  // one-sided
    auto two = make_twosided(d, d);
    CHECK(two->sample(Vec3(0, 0, -1), 0.5f, Vec2(0.5f, 0.5f), &bs) && bs.wi.z < 0);
    auto g = make_dielectric(1.5f, 1.0f, Rgb(1.0f), Rgb(1.0f));
    Vec3 wo = normalize(Vec3(0.5f, 0.0f, 1.0f));
    // transmission (u_lobe above F): Snell's law and the 1/eta^2 radiance factor
    CHECK(g->sample(wo, 0.99f, Vec2(), &bs) && bs.transmission);
    float sin_i = wo.x, sin_t = std::sqrt(bs.wi.x * bs.wi.x + bs.wi.y * bs.wi.y);
    CHECK_NEAR(sin_t * 1.5f, sin_i, 1e-6);
    CHECK(bs.wi.z < 0);
    CHECK_NEAR(bs.weight.r, 1.0 / 2.25, 1e-6);
    CHECK(g->sample(wo, 0.0f, Vec2(), &bs) && !bs.transmission && bs.wi.z > 0);
}

// Rough dielectric (both sides, both distributions) and rough plastic: the pdf reported by
// sample() equals pdf(), and the directional albedo of sampling (mean weight) equals the
// integral of eval() over the sphere by uniform sampling (5 standard errors + 2e-3).
TEST_CASE(rough_dielectric_and_plastic_consistency) {
    struct Config { std::shared_ptr<Bsdf> bsdf; const char* name; };
    auto white = make_constant_texture(Rgb(1.0f));
    const Config cfgs[] = {
        {make_rough_dielectric(1.5f, 1.0f, nullptr, nullptr, MicrofacetType::Beckmann, 0.3f, 0.3f, true), "roughdielectric beckmann"},
        {make_rough_dielectric(1.33f, 1.0f, nullptr, nullptr, MicrofacetType::GGX, 0.5f, 0.2f, true), "roughdielectric ggx aniso"},
        {make_rough_dielectric(1.5f, 1.0f, nullptr, nullptr, MicrofacetType::GGX, 0.2f, 0.2f, false), "roughdielectric ggx D"},
        {make_rough_plastic(1.49f, 1.0f, make_constant_texture(Rgb(0.5f, 0.3f, 0.1f)), nullptr, false, MicrofacetType::Beckmann,
                            0.1f, true), "roughplastic beckmann"},
        {make_rough_plastic(1.9f, 1.0f, make_constant_texture(Rgb(0.8f)), white, true, MicrofacetType::GGX, 0.4f, true),
         "roughplastic ggx nonlinear"},
    };
    const Vec3 wos[] = {normalize(Vec3(0.1f, 0.0f, 1.0f)), normalize(Vec3(0.6f, 0.5f, 0.4f)), normalize(Vec3(-0.9f, 0.2f, 0.15f)),
                        normalize(Vec3(0.3f, -0.2f, -0.8f)), normalize(Vec3(0.7f, 0.1f, -0.3f))};
    const int N = 200000;
    for (const Config& c : cfgs) {
        for (const Vec3& wo : wos) {
            Est alb_s, alb_u;
            int pdf_mismatch = 0;
            Sampler s(4, 5, 6);
            for (int i = 0; i < N; ++i) {
                Vec2 u = s.next_2d();
                float z = 1 - 2 * u.x, r = safe_sqrt(1 - z * z), phi = 2 * kPi * u.y;
                Vec3 wi(r * std::cos(phi), r * std::sin(phi), z);
                alb_u.add(c.bsdf->eval(wo, wi).g * 4 * M_PI);
                BsdfSample bs;
                if (c.bsdf->sample(wo, s.next_1d(), s.next_2d(), &bs)) {
                    alb_s.add(bs.weight.g);
                    float p = c.bsdf->pdf(wo, bs.wi);
                    if (std::fabs(p - bs.pdf) > 1e-3f * std::max(1.0f, p)) ++pdf_mismatch;
                } else {
                    alb_s.add(0.0);
                }
            }
            std::string tag = std::string(c.name) + " wo.z=" + std::to_string(wo.z);
            CHECK_MSG(pdf_mismatch == 0, tag + " pdf mismatches: " + std::to_string(pdf_mismatch));
            double diff = std::fabs(alb_s.mean() - alb_u.mean());
            double tol = 5 * std::sqrt(alb_s.se() * alb_s.se() + alb_u.se() * alb_u.se()) + 2e-3;
            CHECK_MSG(diff < tol, tag + " albedo sampled " + std::to_string(alb_s.mean()) + " vs integrated " +
                                      std::to_string(alb_u.mean()) + " (tol " + std::to_string(tol) + ")");
        }
    }
}

TEST_CASE(normal_map_as_mitsuba) {
    // Reference values: Mitsuba 3.9.1 scalar_rgb through its Python API, normalmap with a
    // constant map value c = (0.6, 0.7, 0.85), shading frame = identity. Our wo is Mitsuba's
    // si.wi (camera side), our wi its wo. Tolerance 1e-4: float arithmetic only.
    auto normals = make_constant_texture(Rgb(0.6f, 0.7f, 0.85f));
    auto diffuse = make_diffuse(Rgb(1.0f));
    auto nm = make_normal_map(normals, diffuse, true), nm_plain = make_normal_map(normals, diffuse, false);
    const Vec3 cam = normalize(Vec3(0.3f, -0.2f, 0.8f)), grazing_cam = normalize(Vec3(-0.7f, -0.2f, 0.3f));
    const Vec3 l1 = normalize(Vec3(-0.4f, 0.1f, 0.7f)), l2 = normalize(Vec3(0.6f, 0.3f, 0.3f));
    CHECK_NEAR(nm->eval(cam, l1).r * kPi, 0.663906, 1e-4);        // cos to the tilted normal x shadowing
    CHECK_NEAR(nm->eval(cam, l2).r * kPi, 0.695378, 1e-4);
    CHECK_NEAR(nm_plain->eval(cam, l1).r * kPi, 0.666831, 1e-4);  // the cosine alone
    CHECK_NEAR(nm_plain->eval(cam, l2).r * kPi, 0.737210, 1e-4);
    CHECK_NEAR(nm->eval(cam, Vec3(0, 0, 1)).r * kPi, 0.842701, 1e-4);  // untilted light: no shadowing
    // camera above the surface but below the tilted normal: its tangential part is mirrored
    CHECK_NEAR(nm->eval(grazing_cam, l1).r * kPi, 0.781934, 1e-4);
    CHECK(nm->eval(grazing_cam, l2).r == 0.0f);
    CHECK(nm->eval(cam, normalize(Vec3(0.2f, 0.1f, -0.5f))).is_black());  // below the surface
    // seen from below (a rough dielectric, alpha 0.3 GGX, bk7/air, no shadowing): the normal is
    // mirrored only where the camera direction is on different sides of it and of the surface
    auto glass = make_normal_map(normals, make_rough_dielectric(1.5046f, 1.000277f, nullptr, nullptr, MicrofacetType::GGX, 0.3f, 0.3f, true), false);
    const Vec3 up = normalize(Vec3(-0.2f, 0.1f, 0.9f)), down = normalize(Vec3(0.1f, 0.3f, -0.7f));
    CHECK_NEAR(glass->eval(normalize(Vec3(0.3f, -0.2f, -0.8f)), up).r, 0.625751, 1e-3);   // not mirrored
    CHECK_NEAR(glass->eval(normalize(Vec3(0.9f, 0.6f, -0.1f)), down).r, 0.014938, 1e-4);  // mirrored
    CHECK(glass->eval(normalize(Vec3(0.9f, 0.6f, -0.1f)), up).is_black());
    // anisotropic GGX (alpha_u 0.05, alpha_v 0.4): the tilted frame's tangent follows the shading
    // frame's s; Mitsuba: eval 1.29100, pdf 1.302237 at this direction
    ConductorIor perfect;
    perfect.perfect = true;
    auto rough = make_normal_map(normals, make_rough_conductor(perfect, make_constant_texture(Rgb(1.0f)), MicrofacetType::GGX, 0.05f, 0.4f, true), true);
    const Vec3 wi(0.140165f, 0.604664f, 0.784051f);
    CHECK_NEAR(rough->eval(cam, wi).r, 0.99137056 * 1.3022367, 2e-4);
    CHECK_NEAR(rough->pdf(cam, wi), 1.302237, 2e-4);
    // sampling: weight = eval / pdf (shadowing in the weight, not in the pdf), pdf = pdf()
    Sampler rng(7, 0, 0);
    int checked = 0;
    for (int k = 0; k < 256; ++k) {
        BsdfSample s;
        if (!rough->sample(cam, rng.next_1d(), rng.next_2d(), &s)) continue;
        float pdf = rough->pdf(cam, s.wi);
        CHECK_NEAR(s.pdf, pdf, 1e-3 * pdf + 1e-5);
        CHECK_NEAR(s.weight.r, rough->eval(cam, s.wi).r / pdf, 1e-3 * s.weight.r + 1e-5);
        ++checked;
    }
    CHECK(checked > 128);
}

TEST_MAIN()
