// mfhost — emitters (see emitter.h).
#include "emitter.h"

namespace mf {

// ----------------------------------------------------------------------------------------------
// Distribution2D

Distribution2D::Distribution2D(const std::vector<float>& f, int nu, int nv) : nu_(nu), nv_(nv), f_(f) {
    cond_cdf_.assign(size_t(nv) * (nu + 1), 0.0f);
    row_int_.assign(size_t(nv), 0.0f);
    marg_cdf_.assign(size_t(nv) + 1, 0.0f);
    for (int v = 0; v < nv; ++v) {
        double acc = 0;
        float* cdf = &cond_cdf_[size_t(v) * (nu + 1)];
        cdf[0] = 0;
        for (int u = 0; u < nu; ++u) {
            acc += std::max(0.0f, f[size_t(v) * nu + u]) / double(nu);
            cdf[u + 1] = float(acc);
        }
        row_int_[size_t(v)] = float(acc);
        if (acc > 0)
            for (int u = 1; u <= nu; ++u) cdf[u] = float(cdf[u] / acc);
        else
            for (int u = 1; u <= nu; ++u) cdf[u] = float(u) / nu;
        cdf[nu] = 1.0f;
    }
    double acc = 0;
    for (int v = 0; v < nv; ++v) {
        acc += row_int_[size_t(v)] / double(nv);
        marg_cdf_[size_t(v) + 1] = float(acc);
    }
    total_ = float(acc);
    if (acc > 0)
        for (int v = 1; v <= nv; ++v) marg_cdf_[size_t(v)] = float(marg_cdf_[size_t(v)] / acc);
    else
        for (int v = 1; v <= nv; ++v) marg_cdf_[size_t(v)] = float(v) / nv;
    marg_cdf_[size_t(nv)] = 1.0f;
}

static int find_interval(const float* cdf, int n, float u) {
    // largest i in [0, n-1] with cdf[i] <= u
    int i = int(std::upper_bound(cdf, cdf + n + 1, u) - cdf) - 1;
    return std::clamp(i, 0, n - 1);
}

Vec2 Distribution2D::sample(const Vec2& u, float* pdf) const {
    int v = find_interval(marg_cdf_.data(), nv_, u.y);
    // skip zero-probability rows (can only be selected at exact cdf ties)
    float dv = marg_cdf_[size_t(v) + 1] - marg_cdf_[size_t(v)];
    float fv = dv > 0 ? (u.y - marg_cdf_[size_t(v)]) / dv : 0.5f;
    const float* cdf = &cond_cdf_[size_t(v) * (nu_ + 1)];
    int c = find_interval(cdf, nu_, u.x);
    float du = cdf[c + 1] - cdf[c];
    float fu = du > 0 ? (u.x - cdf[c]) / du : 0.5f;
    Vec2 uv((c + std::clamp(fu, 0.0f, 1.0f)) / nu_, (v + std::clamp(fv, 0.0f, 1.0f)) / nv_);
    *pdf = total_ > 0 ? std::max(0.0f, f_[size_t(v) * nu_ + c]) / total_ : 1.0f;
    return uv;
}

float Distribution2D::pdf(const Vec2& uv) const {
    int c = std::clamp(int(uv.x * nu_), 0, nu_ - 1);
    int v = std::clamp(int(uv.y * nv_), 0, nv_ - 1);
    return total_ > 0 ? std::max(0.0f, f_[size_t(v) * nu_ + c]) / total_ : 1.0f;
}

// ----------------------------------------------------------------------------------------------

bool AreaEmitter::sample_li(const Vec3& ref, const Vec2& u, EmitterSample* s) const {
    Vec3 p, n;
    shape_->sample_position(u, &p, &n);
    Vec3 d = p - ref;
    float dist2 = length_sq(d);
    if (!(dist2 > 0)) return false;
    float dist = std::sqrt(dist2);
    Vec3 wi = d / dist;
    float cos_l = -dot(n, wi);
    if (cos_l <= 0) return false;  // one-sided emission
    s->wi = wi;
    s->dist = dist;
    s->Li = L_;
    s->pdf = dist2 / (cos_l * shape_->surface_area());
    s->delta = false;
    return std::isfinite(s->pdf);
}

float AreaEmitter::pdf_surface(const Vec3& ref, const SurfaceHit& hit) const {
    Vec3 d = hit.p - ref;
    float dist2 = length_sq(d);
    float cos_l = std::fabs(dot(hit.ng, d)) / std::sqrt(dist2);
    if (!(cos_l > 0)) return 0.0f;
    return dist2 / (cos_l * shape_->surface_area());
}

namespace {
/// The direction and distance from `ref` to a point light at `p` (pdf 1, delta); Li is set to
/// the intensity `I` over the squared distance. False when ref coincides with p.
bool sample_point_light(const Vec3& p, const Rgb& I, const Vec3& ref, EmitterSample* s) {
    Vec3 d = p - ref;
    float dist2 = length_sq(d);
    if (!(dist2 > 0)) return false;
    s->dist = std::sqrt(dist2);
    s->wi = d / s->dist;
    s->Li = I / dist2;
    s->pdf = 1.0f;
    s->delta = true;
    return true;
}
}  // namespace

bool PointEmitter::sample_li(const Vec3& ref, const Vec2&, EmitterSample* s) const {
    return sample_point_light(p_, I_, ref, s);
}

SpotEmitter::SpotEmitter(const Mat4& to_world, const Rgb& intensity, float cutoff_angle, float beam_width,
                         std::shared_ptr<const Texture> texture)
    : to_world_(to_world), to_local_(to_world.inverse()), p_(to_world.point(Vec3(0.0f))), I_(intensity),
      cutoff_(cutoff_angle), cos_cutoff_(std::cos(cutoff_angle)), cos_beam_(std::cos(beam_width)),
      // beam_width == cutoff_angle: no ramp (the ramp branch is never reached, see falloff)
      inv_transition_(cutoff_angle > beam_width ? 1.0f / (cutoff_angle - beam_width) : 0.0f),
      uv_factor_(std::tan(cutoff_angle)), texture_(std::move(texture)) {}

float SpotEmitter::falloff(const Vec3& local_d) const {
    float cos_theta = normalize(local_d).z;
    if (!(cos_theta > cos_cutoff_)) return 0.0f;
    if (cos_theta >= cos_beam_) return 1.0f;
    return (cutoff_ - std::acos(std::min(cos_theta, 1.0f))) * inv_transition_;
}

bool SpotEmitter::sample_li(const Vec3& ref, const Vec2&, EmitterSample* s) const {
    if (!sample_point_light(p_, I_, ref, s)) return false;
    Vec3 local = to_local_.vector(-s->wi);
    float f = falloff(local);
    if (!(f > 0)) return false;
    if (texture_) {
        Vec3 l = normalize(local);
        s->Li = s->Li * texture_->eval(Vec2(0.5f + 0.5f * l.x / (l.z * uv_factor_), 0.5f + 0.5f * l.y / (l.z * uv_factor_)));
    }
    s->Li = s->Li * f;
    return true;
}

ProjectorEmitter::ProjectorEmitter(const Mat4& to_world, const Vec2& tan_half, std::shared_ptr<const Texture> irradiance, float scale)
    : to_world_(to_world), to_local_(to_world.inverse()), p_(to_world.point(Vec3(0.0f))), axis_(to_world.vector(Vec3(0, 0, 1))),
      tan_half_(tan_half), irradiance_(std::move(irradiance)), scale_(scale) {}

bool ProjectorEmitter::sample_li(const Vec3& ref, const Vec2&, EmitterSample* s) const {
    const Vec3 local = to_local_.point(ref);
    if (!(local.z > 0)) return false;
    const Vec2 uv(0.5f - 0.5f * local.x / (local.z * tan_half_.x), 0.5f - 0.5f * local.y / (local.z * tan_half_.y));
    if (!(uv.x >= 0 && uv.x <= 1 && uv.y >= 0 && uv.y <= 1)) return false;
    if (!sample_point_light(p_, Rgb(1.0f), ref, s)) return false;
    const float cos_theta = -dot(axis_, s->wi);
    if (!(cos_theta > 0)) return false;
    s->Li = irradiance_->eval(uv) * (kPi * scale_ / (local.z * local.z * cos_theta));
    return true;
}

bool DirectionalEmitter::sample_li(const Vec3&, const Vec2&, EmitterSample* s) const {
    s->wi = -d_;
    s->dist = kInf;
    s->Li = E_;
    s->pdf = 1.0f;
    s->delta = true;
    return true;
}

bool ConstantEmitter::sample_li(const Vec3&, const Vec2& u, EmitterSample* s) const {
    float z = 1.0f - 2.0f * u.x;
    float r = safe_sqrt(1.0f - z * z), phi = 2.0f * kPi * u.y;
    s->wi = Vec3(r * std::cos(phi), r * std::sin(phi), z);
    s->dist = kInf;
    s->Li = L_;
    s->pdf = kInv4Pi;
    s->delta = false;
    return true;
}

// ----------------------------------------------------------------------------------------------
// Envmap

EnvmapEmitter::EnvmapEmitter(std::vector<float> rgb, int width, int height, float scale, const Mat4& to_world)
    : rgb_(std::move(rgb)), w_(width), h_(height), scale_(scale), to_world_(to_world), to_local_(to_world.inverse()) {
    std::vector<float> lum(size_t(w_) * h_);
    for (int y = 0; y < h_; ++y) {
        float sin_t = std::sin(kPi * (y + 0.5f) / h_);
        for (int x = 0; x < w_; ++x) {
            size_t i = size_t(y) * w_ + x;
            Rgb c(rgb_[3 * i], rgb_[3 * i + 1], rgb_[3 * i + 2]);
            lum[i] = std::max(0.0f, c.luminance()) * sin_t;
        }
    }
    dist_ = Distribution2D(lum, w_, h_);
}

Vec2 EnvmapEmitter::dir_to_uv(const Vec3& world_d, float* sin_theta) const {
    Vec3 v = normalize(to_local_.vector(world_d));
    float rxz = std::sqrt(v.x * v.x + v.z * v.z);
    float u = std::atan2(v.x, -v.z) * (0.5f * kInvPi);
    // atan2 rather than acos(y): accurate near the poles, where the pdf ~ 1/sin(theta)
    float t = std::atan2(rxz, v.y) * kInvPi;
    u -= std::floor(u);
    if (sin_theta) *sin_theta = rxz;
    return Vec2(u, t);
}

Rgb EnvmapEmitter::texel(const Vec2& uv) const {
    int x = std::clamp(int(uv.x * w_), 0, w_ - 1);
    int y = std::clamp(int(uv.y * h_), 0, h_ - 1);
    size_t i = size_t(y) * w_ + x;
    return Rgb(rgb_[3 * i], rgb_[3 * i + 1], rgb_[3 * i + 2]) * scale_;
}

Rgb EnvmapEmitter::eval_direction(const Vec3& d) const { return texel(dir_to_uv(d, nullptr)); }

float EnvmapEmitter::pdf_direction(const Vec3& d) const {
    float st;
    Vec2 uv = dir_to_uv(d, &st);
    if (!(st > 0)) return 0.0f;
    return dist_.pdf(uv) / (2.0f * kPi * kPi * st);
}

bool EnvmapEmitter::sample_li(const Vec3&, const Vec2& u, EmitterSample* s) const {
    float pdf_uv;
    Vec2 uv = dist_.sample(u, &pdf_uv);
    if (!(pdf_uv > 0)) return false;
    float phi = uv.x * 2.0f * kPi, theta = uv.y * kPi;
    float st = std::sin(theta), ct = std::cos(theta);
    if (!(st > 0)) return false;
    Vec3 local(std::sin(phi) * st, ct, -std::cos(phi) * st);
    s->wi = normalize(to_world_.vector(local));
    s->dist = kInf;
    // Value and pdf of the returned (float) direction, so that NEE and BSDF-sampled hits of
    // the same direction agree exactly (matters at texel edges and the poles).
    s->Li = eval_direction(s->wi);
    s->pdf = pdf_direction(s->wi);
    if (!(s->pdf > 0)) return false;
    s->delta = false;
    return true;
}

}  // namespace mf
