// mfhost — the macrofacet medium through the library's tracking API (see medium_macrofacet.h).
#include "medium_macrofacet.h"

#include <macrofacet.h>

#include <cmath>
#include <cstdio>
#include <vector>

#include "mean_surface.h"

namespace mf {
namespace {

std::string last_error() {
    size_t len = 0;
    mf_last_error_message(nullptr, 0, &len);
    std::vector<char> buf(len + 1, '\0');
    mf_last_error_message(buf.data(), buf.size(), nullptr);
    std::string s(buf.data());
    return s.empty() ? std::string("unknown error") : s;
}

std::string describe(const MediumParamBag& bag) {
    return "<medium type=\"" + bag.type + "\"" + (bag.id.empty() ? std::string() : " id=\"" + bag.id + "\"") + ">";
}

mf_vec3 vec(const Vec3& v) { return mf_vec3{v.x, v.y, v.z}; }
Vec3 vec(const mf_vec3& v) { return Vec3(float(v.x), float(v.y), float(v.z)); }

/// A unit direction in double precision (the library checks |v| = 1 to 1e-6; hosts' floats are
/// renormalised here rather than rejected).
mf_vec3 unit(const Vec3& v) {
    double x = v.x, y = v.y, z = v.z, l = std::sqrt(x * x + y * y + z * z);
    if (!(l > 0)) return mf_vec3{0, 0, 1};
    return mf_vec3{x / l, y / l, z / l};
}

mf_frame frame_of(const MediumInteraction& mi) { return mf_frame{vec(mi.frame_n), vec(mi.frame_t)}; }

/// The library's phase function (seeds/000 Eq. 11 with the flakes' reflectance) in the frame the
/// tracker returned with the collision. Host convention: `wo` points back along the incoming ray,
/// `wi` is the new direction; the library's `wi` is our `wo` and its `wo` our `wi`.
class MacrofacetPhaseFn final : public PhaseFunction {
public:
    MacrofacetPhaseFn(const mf_medium* h, std::string label) : h_(h), label_(std::move(label)) {}

    Rgb eval(const MediumInteraction& mi, const Vec3& wo, const Vec3& wi) const override {
        float pdf;
        return eval_pdf(mi, wo, wi, &pdf);
    }
    float pdf(const MediumInteraction& mi, const Vec3& wo, const Vec3& wi) const override {
        float pdf;
        eval_pdf(mi, wo, wi, &pdf);
        return pdf;
    }
    Rgb eval_pdf(const MediumInteraction& mi, const Vec3& wo, const Vec3& wi, float* pdf) const override {
        mf_frame fr = frame_of(mi);
        mf_phase_value v;
        check(mf_phase_eval_pdf(h_, &fr, unit(wo), unit(wi), &v), "mf_phase_eval_pdf");
        *pdf = float(v.pdf);
        return Rgb(float(v.value.r), float(v.value.g), float(v.value.b));
    }
    bool sample(const MediumInteraction& mi, const Vec3& wo, Sampler& sampler, Vec3* wi, float* pdf,
                Rgb* weight) const override {
        double u[MF_PHASE_SAMPLE_DIMENSIONS];
        for (double& x : u) x = double(sampler.next_1d());
        mf_frame fr = frame_of(mi);
        mf_phase_sample_result s;
        check(mf_phase_sample(h_, &fr, unit(wo), u, &s), "mf_phase_sample");
        if (!s.valid || !(s.pdf > 0)) return false;
        *wi = vec(s.wo);
        *pdf = float(s.pdf);
        *weight = Rgb(float(s.weight.r), float(s.weight.g), float(s.weight.b));
        return weight->finite() && std::isfinite(*pdf);
    }

private:
    void check(mf_status st, const char* what) const {
        if (st != MF_OK) throw Error(label_ + ": " + what + " failed: " + last_error());
    }
    const mf_medium* h_;
    std::string label_;
};

mf_track_query query(const Ray& ray, float t_max, Sampler& sampler) {
    return mf_track_query{vec(ray.o), unit(ray.d), std::isfinite(t_max) ? double(t_max) : INFINITY, sampler.next_u64()};
}

}  // namespace

// ----------------------------------------------------------------------------------------------
// MacrofacetMedium

MacrofacetMedium::MacrofacetMedium(mf_medium* handle, std::shared_ptr<const MeanSurface> surface, std::string label)
    : handle_(handle), surface_(std::move(surface)), label_(std::move(label)) {
    phase_ = std::make_shared<MacrofacetPhaseFn>(handle_, label_);
    if (mf_medium_shell_top(handle_, &top_) != MF_OK) {
        std::string msg = last_error();
        mf_medium_free(handle_);
        throw Error(label_ + ": " + msg);
    }
}

MacrofacetMedium::~MacrofacetMedium() {
    uint64_t v = violations_.load();
    if (v > 0)
        std::fprintf(stderr, "mfrender: warning: %s: the majorant was exceeded at %llu tentative collisions\n",
                     label_.c_str(), (unsigned long long)v);
    mf_medium_free(handle_);
}

void MacrofacetMedium::count(const mf_track_stats& s) const {
    calls_.fetch_add(1, std::memory_order_relaxed);
    queries_.fetch_add(s.surface_queries, std::memory_order_relaxed);
    segments_.fetch_add(s.segments, std::memory_order_relaxed);
    tentative_.fetch_add(s.tentative_collisions, std::memory_order_relaxed);
    if (s.majorant_violations) violations_.fetch_add(s.majorant_violations, std::memory_order_relaxed);
}

TrackCounts MacrofacetMedium::counts() const {
    TrackCounts c;
    c.calls = calls_.load();
    c.surface_queries = queries_.load();
    c.segments = segments_.load();
    c.tentative_collisions = tentative_.load();
    c.majorant_violations = violations_.load();
    return c;
}

bool MacrofacetMedium::sample_free_flight(const Ray& ray, float t_max, int, Sampler& sampler, MediumInteraction* mi,
                                          Rgb* weight, Rgb* pdf_ratio) const {
    *weight = Rgb(1.0f);  // grey medium: the albedo lives in the phase function
    *pdf_ratio = Rgb(1.0f);
    mf_track_query q = query(ray, t_max, sampler);
    mf_collision c;
    if (mf_track_free_flight(handle_, surface_->handle(), nullptr, nullptr, &q, &c) != MF_OK)
        throw Error(label_ + ": mf_track_free_flight failed: " + last_error());
    count(c.stats);
    if (!c.scattered) return false;
    mi->t = float(c.t);
    mi->p = vec(c.p);
    mi->wo = -ray.d;
    mi->frame_n = vec(c.frame.normal);
    mi->frame_t = vec(c.frame.tangent);
    mi->sdf_f = float(c.f);
    mi->medium = this;
    return true;
}

Rgb MacrofacetMedium::transmittance(const Ray& ray, float t_max, Sampler& sampler) const {
    mf_track_query q = query(ray, t_max, sampler);
    mf_transmittance t;
    if (mf_track_transmittance(handle_, surface_->handle(), nullptr, nullptr, &q, &t) != MF_OK)
        throw Error(label_ + ": mf_track_transmittance failed: " + last_error());
    count(t.stats);
    return Rgb(float(t.transmittance));
}

double MacrofacetMedium::sigma_t_at(const Vec3& p, const Vec3& d, Vec3* normal, Vec3* tangent, float* f) const {
    double fd = surface_->eval(p, normal, tangent);
    *f = float(fd);
    mf_frame fr{vec(*normal), vec(*tangent)};
    double st = 0;
    if (mf_medium_sigma_t(handle_, &fr, fd, unit(d), &st) != MF_OK)
        throw Error(label_ + ": mf_medium_sigma_t failed: " + last_error());
    return st;
}

// ----------------------------------------------------------------------------------------------
// The hook: XML parameter bag -> mf_params -> mf_medium

namespace {

/// The bag entry a library message refers to: the longest bag name quoted in the message; else
/// the string parameter whose value the message quotes (e.g. `distribution "ggx" has no ...`).
const std::pair<std::string, ParamValue>* param_named_in(const MediumParamBag& bag, const std::string& msg) {
    const std::pair<std::string, ParamValue>* best = nullptr;
    for (const auto& kv : bag.params) {
        if (msg.find("\"" + kv.first + "\"") == std::string::npos) continue;
        if (!best || kv.first.size() > best->first.size()) best = &kv;
    }
    if (best) return best;
    for (const auto& kv : bag.params)
        if (kv.second.kind == ParamValue::Kind::String && msg.find(kv.first) != std::string::npos &&
            msg.find("\"" + kv.second.s + "\"") != std::string::npos)
            return &kv;
    return nullptr;
}

}  // namespace

std::string mf_last_error() { return last_error(); }

Error medium_param_error(const MediumParamBag& bag, const std::string& msg) {
    const auto* p = param_named_in(bag, msg);
    return Error(p ? p->second.loc : bag.loc, describe(bag) + ": " + msg);
}

std::string medium_label(const MediumParamBag& bag) {
    const std::string what = describe(bag);
    return bag.loc.str().empty() ? what : bag.loc.str() + ": " + what;
}

mf_params* bag_to_params(const MediumParamBag& bag, double* sigma_out) {
    const std::string what = describe(bag);
    mf_params* params = nullptr;
    if (mf_params_new(&params) != MF_OK) throw Error(bag.loc, what + ": " + last_error());
    double sigma = -1;
    try {
        for (const auto& kv : bag.params) {
            const std::string& name = kv.first;
            const ParamValue& v = kv.second;
            mf_status st = MF_OK;
            switch (v.kind) {
                case ParamValue::Kind::Float: st = mf_params_set_float(params, name.c_str(), v.f); break;
                case ParamValue::Kind::Int: st = mf_params_set_float(params, name.c_str(), double(v.i)); break;
                case ParamValue::Kind::Rgb: {
                    double c[3] = {v.rgb.r, v.rgb.g, v.rgb.b};
                    st = mf_params_set_rgb(params, name.c_str(), c);
                    break;
                }
                case ParamValue::Kind::String: st = mf_params_set_string(params, name.c_str(), v.s.c_str()); break;
                case ParamValue::Kind::Bool:
                    throw Error(v.loc, what + ": parameter \"" + name + "\" is a boolean; " + bag.type +
                                           " parameters are float, integer, rgb or string");
            }
            if (st != MF_OK) throw Error(v.loc, what + ": parameter \"" + name + "\": " + last_error());
            if (name == "sigma" && (v.kind == ParamValue::Kind::Float || v.kind == ParamValue::Kind::Int))
                sigma = v.kind == ParamValue::Kind::Float ? v.f : double(v.i);
            if (name == "variance" && (v.kind == ParamValue::Kind::Float || v.kind == ParamValue::Kind::Int))
                sigma = std::sqrt(v.kind == ParamValue::Kind::Float ? v.f : double(v.i));
        }
    } catch (...) {
        mf_params_free(params);
        throw;
    }
    if (sigma_out) *sigma_out = sigma;
    return params;
}

namespace {
struct ParamsGuard {
    mf_params* p = nullptr;
    ~ParamsGuard() { mf_params_free(p); }
};
}  // namespace

std::shared_ptr<MacrofacetMedium> create_macrofacet_medium(const MediumParamBag& bag, std::shared_ptr<const MeanSurface> surface) {
    if (bag.type != "macrofacet") throw Error(bag.loc, describe(bag) + ": not a macrofacet medium");
    ParamsGuard params;
    params.p = bag_to_params(bag, nullptr);
    mf_medium* handle = nullptr;
    if (mf_medium_new(params.p, &handle) != MF_OK) throw medium_param_error(bag, last_error());
    return std::make_shared<MacrofacetMedium>(handle, std::move(surface), medium_label(bag));
}

}  // namespace mf
