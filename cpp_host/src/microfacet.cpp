// mfhost — microfacet distributions (see microfacet.h).
#include "microfacet.h"

#include <vector>

#include "bsdf.h"  // fresnel_dielectric

namespace mf {

float Microfacet::D(const Vec3& m) const {
    if (m.z <= 0) return 0.0f;
    float cos2 = m.z * m.z;
    // slope-space: x = -m.x/m.z, y = -m.y/m.z
    float e = (m.x * m.x / (au_ * au_) + m.y * m.y / (av_ * av_)) / cos2;  // tan^2 with anisotropy
    float r;
    if (type_ == MicrofacetType::Beckmann) {
        r = std::exp(-e) / (kPi * au_ * av_ * cos2 * cos2);
    } else {
        float t = 1.0f + e;
        r = 1.0f / (kPi * au_ * av_ * cos2 * cos2 * t * t);
    }
    return (r * m.z > 1e-20f) ? r : 0.0f;
}

float Microfacet::Lambda(const Vec3& w) const {
    float xy2 = au_ * au_ * w.x * w.x + av_ * av_ * w.y * w.y;  // alpha^2 tan^2 * cos^2
    if (xy2 <= 0) return 0.0f;
    float z2 = w.z * w.z;
    if (type_ == MicrofacetType::GGX) {
        return 0.5f * (-1.0f + std::sqrt(1.0f + xy2 / z2));
    }
    // Beckmann: a = 1 / (alpha tan theta)
    float a = std::fabs(w.z) / std::sqrt(xy2);
    if (a > 8.0f) return 0.0f;
    return 0.5f * (std::erf(a) - 1.0f) + std::exp(-a * a) / (2.0f * a * std::sqrt(kPi));
}

float Microfacet::G1(const Vec3& w, const Vec3& m) const {
    if (dot(w, m) * w.z <= 0) return 0.0f;
    return 1.0f / (1.0f + Lambda(w));
}

float Microfacet::pdf(const Vec3& wi, const Vec3& m) const {
    if (visible_) {
        if (wi.z <= 0) return 0.0f;
        return G1(wi, m) * std::max(0.0f, dot(wi, m)) * D(m) / wi.z;
    }
    return D(m) * m.z;
}

Vec3 Microfacet::sample(const Vec3& wi, const Vec2& u, float* pdf_out) const {
    Vec3 m;
    if (visible_) {
        m = type_ == MicrofacetType::GGX ? sample_visible_ggx(wi, u) : sample_visible_beckmann(wi, u);
    } else {
        // Sample slopes from P22 directly: the induced normal density is D(m) cos(theta_m).
        float phi = 2.0f * kPi * u.y;
        float r;
        if (type_ == MicrofacetType::Beckmann) r = std::sqrt(-std::log(std::max(1.0f - u.x, 1e-30f)));
        else r = std::sqrt(u.x / std::max(1.0f - u.x, 1e-30f));
        float sx = au_ * r * std::cos(phi), sy = av_ * r * std::sin(phi);
        m = normalize(Vec3(-sx, -sy, 1.0f));
    }
    *pdf_out = pdf(wi, m);
    return m;
}

Vec3 Microfacet::sample_visible_ggx(const Vec3& wi, const Vec2& u) const {
    // Stretch to the hemisphere configuration, sample the projected disk, unstretch.
    Vec3 vh = normalize(Vec3(au_ * wi.x, av_ * wi.y, wi.z));
    float lensq = vh.x * vh.x + vh.y * vh.y;
    Vec3 t1 = lensq > 0 ? Vec3(-vh.y, vh.x, 0.0f) / std::sqrt(lensq) : Vec3(1, 0, 0);
    Vec3 t2 = cross(vh, t1);
    float r = std::sqrt(u.x), phi = 2.0f * kPi * u.y;
    float p1 = r * std::cos(phi), p2 = r * std::sin(phi);
    float s = 0.5f * (1.0f + vh.z);
    p2 = (1.0f - s) * std::sqrt(std::max(0.0f, 1.0f - p1 * p1)) + s * p2;
    Vec3 nh = t1 * p1 + t2 * p2 + vh * std::sqrt(std::max(0.0f, 1.0f - p1 * p1 - p2 * p2));
    return normalize(Vec3(au_ * nh.x, av_ * nh.y, std::max(1e-6f, nh.z)));
}

namespace {

/// Gauss-Legendre nodes and weights of order n on [-1, 1] (Newton on the Legendre recurrence;
/// nodes accurate to 1e-15).
void gauss_legendre(int n, std::vector<double>* nodes, std::vector<double>* weights) {
    nodes->assign(size_t(n), 0.0);
    weights->assign(size_t(n), 0.0);
    for (int i = 0; i < (n + 1) / 2; ++i) {
        double x = std::cos(3.14159265358979323846 * (i + 0.75) / (n + 0.5)), dp = 1;
        for (int it = 0; it < 100; ++it) {
            double p0 = 1, p1 = x;  // P_0, P_1
            for (int k = 2; k <= n; ++k) {
                double pk = ((2 * k - 1) * x * p1 - (k - 1) * p0) / k;
                p0 = p1;
                p1 = pk;
            }
            dp = n * (x * p1 - p0) / (x * x - 1);  // P_n'
            double dx = p1 / dp;
            x -= dx;
            if (std::fabs(dx) < 1e-15) break;
        }
        double w = 2 / ((1 - x * x) * dp * dp);
        (*nodes)[size_t(i)] = -x;
        (*nodes)[size_t(n - 1 - i)] = x;
        (*weights)[size_t(i)] = (*weights)[size_t(n - 1 - i)] = w;
    }
}

}  // namespace

/// The n x n Gauss-Legendre quadrature of g(m) over the visible normals m of wi (uniform on the
/// unit square of visible-normal samples), n = 32 for eta > 1 and 128 otherwise.
template <typename G>
static double integrate_visible_normals(const Microfacet& visible, const Vec3& wi, float eta, G&& g) {
    const int n = eta > 1 ? 32 : 128;
    std::vector<double> x, w;
    gauss_legendre(n, &x, &w);
    double sum = 0;
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) {
            Vec2 u(float(0.5 * x[size_t(i)] + 0.5), float(0.5 * x[size_t(j)] + 0.5));
            float pdf;
            Vec3 m = visible.sample(wi, u, &pdf);
            sum += double(g(m)) * w[size_t(i)] * w[size_t(j)] * 0.25;
        }
    return sum;
}

float Microfacet::eval_reflectance(const Vec3& wi, float eta) const {
    if (!(wi.z > 0)) return 0.0f;
    Microfacet visible(type_, au_, av_, true, height_correlated_);
    return float(integrate_visible_normals(visible, wi, eta, [&](const Vec3& m) {
        float c = dot(wi, m);
        Vec3 wo = m * (2.0f * c) - wi;
        return wo.z > 0 ? fresnel_dielectric(c, eta, nullptr) * G1(wo, m) : 0.0f;
    }));
}

float Microfacet::eval_transmittance(const Vec3& wi, float eta) const {
    if (!(wi.z > 0)) return 0.0f;
    Microfacet visible(type_, au_, av_, true, height_correlated_);
    return float(integrate_visible_normals(visible, wi, eta, [&](const Vec3& m) {
        float c = dot(wi, m), cos_t;
        float F = fresnel_dielectric(c, eta, &cos_t);
        float eta_ti = c > 0 ? 1.0f / eta : eta;  // index ratio (wi side / far side)
        Vec3 wt = m * (c * eta_ti - (c > 0 ? cos_t : -cos_t)) - wi * eta_ti;
        return wt.z * wi.z < 0 ? (1.0f - F) * G1(wt, m) : 0.0f;
    }));
}

namespace {

/// Sample x from the density p(x) ∝ (c − x) exp(−x²) on (−∞, c): the visible-slope marginal
/// of the unit-roughness Beckmann distribution for an incidence with cot(theta) = c.
/// CDF(x) = c √π/2 (1 + erf x) + exp(−x²)/2 (unnormalised); solved by safeguarded Newton.
double sample_beckmann_marginal(double c, double u) {
    const double sqrt_pi = 1.7724538509055160273;
    auto cdf = [&](double x) { return c * 0.5 * sqrt_pi * (1.0 + std::erf(x)) + 0.5 * std::exp(-x * x); };
    double total = cdf(c);
    double target = u * total;
    double lo = -6.0, hi = c;  // below -6 the mass is < 1e-16 of total for any c >= -something
    if (c < -5.5) lo = c - 6.0;
    double x = std::min(hi, std::max(lo, 0.0));
    for (int it = 0; it < 60; ++it) {
        double f = cdf(x) - target;
        if (std::fabs(f) <= 1e-12 * total) break;
        if (f > 0) hi = x; else lo = x;
        double dens = (c - x) * std::exp(-x * x);
        double xn = dens > 0 ? x - f / dens : 0.5 * (lo + hi);
        if (!(xn > lo && xn < hi)) xn = 0.5 * (lo + hi);
        if (hi - lo < 1e-12) break;
        x = xn;
    }
    return x;
}

/// Inverse of erf for the conditional Gaussian (y slope) via Newton on erf.
double erfinv(double y) {
    y = std::max(-1.0 + 1e-15, std::min(1.0 - 1e-15, y));
    // initial guess (Giles 2010 single-precision approximation form, refined by Newton)
    double w = -std::log((1.0 - y) * (1.0 + y)), x;
    if (w < 5.0) {
        w -= 2.5;
        x = 2.81022636e-08;
        x = 3.43273939e-07 + x * w; x = -3.5233877e-06 + x * w; x = -4.39150654e-06 + x * w;
        x = 0.00021858087 + x * w; x = -0.00125372503 + x * w; x = -0.00417768164 + x * w;
        x = 0.246640727 + x * w; x = 1.50140941 + x * w;
    } else {
        w = std::sqrt(w) - 3.0;
        x = -0.000200214257;
        x = 0.000100950558 + x * w; x = 0.00134934322 + x * w; x = -0.00367342844 + x * w;
        x = 0.00573950773 + x * w; x = -0.0076224613 + x * w; x = 0.00943887047 + x * w;
        x = 1.00167406 + x * w; x = 2.83297682 + x * w;
    }
    x *= y;
    for (int i = 0; i < 3; ++i) {
        double err = std::erf(x) - y;
        x -= err / (1.1283791670955126 * std::exp(-x * x));
    }
    return x;
}

}  // namespace

Vec3 Microfacet::sample_visible_beckmann(const Vec3& wi, const Vec2& u) const {
    // 1. stretch wi to the unit-roughness configuration
    Vec3 w = normalize(Vec3(au_ * wi.x, av_ * wi.y, wi.z));
    float sin_t = std::sqrt(std::max(0.0f, 1.0f - w.z * w.z));
    float cos_phi = 1.0f, sin_phi = 0.0f;
    if (sin_t > 1e-7f) {
        cos_phi = w.x / sin_t;
        sin_phi = w.y / sin_t;
    }
    // 2. visible slopes for the configuration phi = 0 (slopes x̃ = −m.x/m.z)
    double sx, sy;
    if (sin_t < 1e-5f) {
        // normal incidence: visible slopes are Gaussian with variance 1/2
        double r = std::sqrt(-std::log(std::max(1e-300, 1.0 - double(u.x))));
        double phi = 2.0 * 3.14159265358979323846 * u.y;
        sx = r * std::cos(phi);
        sy = r * std::sin(phi);
    } else {
        double c = double(w.z) / double(sin_t);  // cot(theta)
        // With m ∝ (−x̃, −ỹ, 1) and wi = (sin θ, 0, cos θ), <wi, m> ∝ cot θ − x̃, so the
        // visible x-slope has density ∝ (cot θ − x̃) exp(−x̃²) on x̃ < cot θ.
        sx = sample_beckmann_marginal(c, double(u.x));
        sy = erfinv(2.0 * double(u.y) - 1.0);
    }
    // 3. rotate and unstretch
    double tx = cos_phi * sx - sin_phi * sy;
    double ty = sin_phi * sx + cos_phi * sy;
    tx *= au_;
    ty *= av_;
    return normalize(Vec3(float(-tx), float(-ty), 1.0f));
}

}  // namespace mf
