// mfhost — the macrofacet medium through the C ABI (see medium_macrofacet.h and README.md).
#include "medium_macrofacet.h"

#include <macrofacet.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <thread>
#include <vector>

#include "embree_user_geometry.h"

namespace mf {
namespace {

/// Tracking segments per free flight before giving up (the path is then terminated). Never
/// reached in practice: the density grows without bound inside the object.
constexpr int kMaxSegments = 1 << 16;
/// Ratio tracking: below this transmittance estimate, continue by Russian roulette.
constexpr double kRatioRoulette = 0.1;
constexpr double kPiD = 3.14159265358979323846;

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

/// World vector -> unit mf_vec3 (renormalised in double: the library checks |v| = 1 to 1e-6).
mf_vec3 unit(const Vec3& v) {
    double x = v.x, y = v.y, z = v.z, l = std::sqrt(x * x + y * y + z * z);
    if (!(l > 0)) return mf_vec3{0, 0, 1};
    return mf_vec3{x / l, y / l, z / l};
}

mf_vec3 vec(const Vec3& v) { return mf_vec3{v.x, v.y, v.z}; }

/// The tangent handed to the library: world +z (it projects it orthogonally to the normal and
/// picks any orthonormal vector where they are parallel). It only matters for anisotropic
/// roughness; for a sphere it is the meridian direction d/dtheta.
const Vec3 kTangentRef(0.0f, 0.0f, 1.0f);

mf_frame make_frame(const Vec3& n, const Vec3& t) { return mf_frame{vec(n), vec(t)}; }

/// The phase function of the library (Eq. 11 with the flakes' reflectance), in the local frame
/// carried by the MediumInteraction. Host convention: `wo` points back along the incoming ray,
/// `wi` is the new direction; the library's `wi` is our `wo` and its `wo` our `wi`.
class MacrofacetPhaseFn final : public PhaseFunction {
public:
    MacrofacetPhaseFn(const mf_medium* h, std::string label) : h_(h), label_(std::move(label)) {}

    Rgb eval(const MediumInteraction& mi, const Vec3& wo, const Vec3& wi) const override {
        mf_frame fr = make_frame(mi.frame_n, mi.frame_t);
        mf_rgb v;
        check(mf_phase_eval(h_, &fr, unit(wo), unit(wi), &v), "mf_phase_eval");
        return Rgb(float(v.r), float(v.g), float(v.b));
    }
    float pdf(const MediumInteraction& mi, const Vec3& wo, const Vec3& wi) const override {
        mf_frame fr = make_frame(mi.frame_n, mi.frame_t);
        double p = 0;
        check(mf_phase_pdf(h_, &fr, unit(wo), unit(wi), &p), "mf_phase_pdf");
        return float(p);
    }
    bool sample(const MediumInteraction& mi, const Vec3& wo, Sampler& sampler, Vec3* wi, float* pdf,
                Rgb* weight) const override {
        double u[MF_PHASE_SAMPLE_DIMENSIONS];
        for (double& x : u) x = double(sampler.next_1d());
        mf_frame fr = make_frame(mi.frame_n, mi.frame_t);
        mf_phase_sample_result s;
        check(mf_phase_sample(h_, &fr, unit(wo), u, &s), "mf_phase_sample");
        if (!s.valid || !(s.pdf > 0)) return false;
        *wi = Vec3(float(s.wo.x), float(s.wo.y), float(s.wo.z));
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

}  // namespace

// ----------------------------------------------------------------------------------------------
// SdfBoundGrid

SdfBoundGrid::SdfBoundGrid(const Shape& shape, const Aabb& box, int cells) {
    Vec3 ext = box.extent();
    h_ = std::max(1e-6f, max_comp(ext) / float(std::max(cells, 1)));
    origin_ = box.lo;
    for (int a = 0; a < 3; ++a) n_[a] = int(std::ceil(ext[a] / h_)) + 1;
    const size_t total = size_t(n_[0]) * n_[1] * n_[2];
    v_.assign(total, 0.0f);
    // slabs of constant z in parallel (each value is a pure function of its node: deterministic)
    unsigned nt = std::max(1u, std::min(8u, std::thread::hardware_concurrency()));
    std::vector<std::thread> pool;
    for (unsigned w = 0; w < nt; ++w)
        pool.emplace_back([&, w] {
            for (int z = int(w); z < n_[2]; z += int(nt))
                for (int y = 0; y < n_[1]; ++y)
                    for (int x = 0; x < n_[0]; ++x)
                        v_[(size_t(z) * n_[1] + y) * n_[0] + x] = shape.sdf(origin_ + Vec3(float(x), float(y), float(z)) * h_).f;
        });
    for (std::thread& t : pool) t.join();
}

void SdfBoundGrid::bounds(const Vec3& p, float* lo, float* hi) const {
    int idx[3];
    Vec3 q;
    for (int a = 0; a < 3; ++a) {
        idx[a] = std::clamp(int(std::lround((p[a] - origin_[a]) / h_)), 0, n_[a] - 1);
        q[a] = origin_[a] + float(idx[a]) * h_;
    }
    float v = v_[(size_t(idx[2]) * n_[1] + idx[1]) * n_[0] + idx[0]];
    // |p - q| plus a relative margin for the float rounding of node positions and values
    float d = length(p - q) * 1.001f + 1e-6f * (h_ + std::fabs(v));
    *lo = v - d;
    *hi = v + d;
}

// ----------------------------------------------------------------------------------------------
// MacrofacetMedium

MacrofacetMedium::MacrofacetMedium(mf_medium* handle, std::shared_ptr<const Shape> mean, double sigma, std::string label)
    : handle_(handle), mean_(std::move(mean)), sigma_(sigma), label_(std::move(label)) {
    phase_ = std::make_shared<MacrofacetPhaseFn>(handle_, label_);
    if (mf_medium_shell_top(handle_, &top_) != MF_OK) throw Error(label_ + ": " + last_error());
    grid_ = make_sdf_bound_grid(mean_, top_);
    // sigma_t(f, d) = rho(f) * S(d) with S(d) the flakes' projected area against d in the local
    // frame (Eq. 14). On a curved shell the frame turns along a segment, so the majorant uses
    // S_max = max over all directions (relative to the frame; sweeping d over the sphere with a
    // fixed frame covers every relative orientation, anisotropy included). S is smooth in d; the
    // 1-degree grid's maximum times 1.05 bounds it (a violation counter checks this at run time).
    mf_frame canon = make_frame(Vec3(0, 0, 1), Vec3(1, 0, 0));
    mf_vec3 down{0, 0, -1};
    double s_ref = 0;
    if (mf_medium_sigma_t(handle_, &canon, 0.0, down, &s_ref) != MF_OK) throw Error(label_ + ": " + last_error());
    double s_max = s_ref;
    for (int i = 0; i <= 180; ++i) {
        double th = kPiD * i / 180.0;
        for (int j = 0; j < 180; ++j) {
            double ph = 2.0 * kPiD * j / 180.0;
            mf_vec3 d{std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph), std::cos(th)};
            double s = 0;
            if (mf_medium_sigma_t(handle_, &canon, 0.0, d, &s) != MF_OK) throw Error(label_ + ": " + last_error());
            s_max = std::max(s_max, s);
        }
    }
    if (!(s_ref > 0)) throw Error(label_ + ": the medium has no extinction straight down (degenerate NDF)");
    smax_factor_ = 1.05 * s_max / s_ref;
}

MacrofacetMedium::~MacrofacetMedium() {
    uint64_t v = violations_.load();
    if (v > 0)
        std::fprintf(stderr, "mfrender: warning: %s: the majorant was exceeded at %llu tentative collisions\n",
                     label_.c_str(), (unsigned long long)v);
    mf_medium_free(handle_);
}

double MacrofacetMedium::majorant(double f_min) const {
    if (f_min > top_) return 0.0;
    static const mf_frame canon = make_frame(Vec3(0, 0, 1), Vec3(1, 0, 0));
    double m = 0;
    if (mf_medium_majorant(handle_, &canon, f_min, f_min, mf_vec3{0, 0, -1}, &m) != MF_OK)
        throw Error(label_ + ": mf_medium_majorant failed: " + last_error());
    return m * smax_factor_;
}

double MacrofacetMedium::segment_length(double f0) const { return std::max(sigma_, 0.5 * std::fabs(f0)); }

double MacrofacetMedium::sigma_t_at(const Vec3& p, const Vec3& d, Vec3* n, Vec3* tangent, float* f) const {
    SdfSample s = mean_->sdf_frame(p, n);
    *f = s.f;
    *tangent = kTangentRef;
    mf_frame fr = make_frame(*n, *tangent);
    double st = 0;
    if (mf_medium_sigma_t(handle_, &fr, double(s.f), unit(d), &st) != MF_OK)
        throw Error(label_ + ": mf_medium_sigma_t failed: " + last_error());
    return st;
}

// The segment march shared by delta and ratio tracking: segments [t, t + len] with the majorant
// of the lowest signed distance the segment can reach: f >= f(t) - len (the SDF is 1-Lipschitz).
// Space above the shell is skipped by the same bound. The exponential step is memoryless, so
// restarting it at each segment boundary with the next majorant is exact. At every tentative
// collision the real sigma_t is evaluated and `on_collision(t, p, st, mu, n, tangent, f)` decides
// whether the march continues (true) or stops (false).
template <class OnCollision>
MacrofacetMedium::MarchEnd MacrofacetMedium::march(const Ray& ray, float t_max, Sampler& sampler,
                                                   OnCollision&& on_collision) const {
    const double tm = t_max;
    double t = 0;
    for (int seg = 0; seg < kMaxSegments; ++seg) {
        if (!(t < tm)) return MarchEnd::Left;
        Vec3 p0 = ray.at(float(t));
        if (grid_) {  // cheap conservative skip far above the shell
            float lo, hi;
            grid_->bounds(p0, &lo, &hi);
            if (lo > top_ + sigma_) {
                if (!std::isfinite(tm)) return MarchEnd::Left;
                t += lo - top_;
                continue;
            }
        }
        double f0 = mean_->sdf(p0).f;
        if (f0 > top_ + sigma_) {
            // above the shell: no density until f comes back down to top (Lipschitz)
            if (!std::isfinite(tm)) return MarchEnd::Left;
            t += f0 - top_;
            continue;
        }
        double len = std::min(segment_length(f0), tm - t);
        double mu = majorant(f0 - len);
        double end = t + len;
        if (!(mu > 0)) {
            t = end;
            continue;
        }
        while (true) {
            t += -std::log1p(-double(sampler.next_1d())) / mu;
            if (!(t < end)) {
                t = end;
                break;
            }
            Vec3 p = ray.at(float(t)), n, tan;
            float f;
            double st = sigma_t_at(p, ray.d, &n, &tan, &f);
            if (st > mu * (1.0 + 1e-9)) violations_.fetch_add(1, std::memory_order_relaxed);
            if (!on_collision(t, p, st, mu, n, tan, f)) return MarchEnd::Stopped;
        }
    }
    return MarchEnd::OutOfSegments;
}

// Delta tracking (Woodcock): a tentative collision is real with probability sigma_t / mu.
bool MacrofacetMedium::sample_free_flight(const Ray& ray, float t_max, int, Sampler& sampler, MediumInteraction* mi,
                                          Rgb* weight, Rgb* pdf_ratio) const {
    *weight = Rgb(1.0f);
    *pdf_ratio = Rgb(1.0f);
    MarchEnd e = march(ray, t_max, sampler,
                       [&](double t, const Vec3& p, double st, double mu, const Vec3& n, const Vec3& tan, float f) {
                           if (!(double(sampler.next_1d()) * mu < st)) return true;
                           mi->t = float(t);
                           mi->p = p;
                           mi->wo = -ray.d;
                           mi->frame_n = n;
                           mi->frame_t = tan;
                           mi->sdf_f = f;
                           mi->medium = this;
                           return false;
                       });
    if (e == MarchEnd::Stopped) return true;
    if (e == MarchEnd::OutOfSegments) *weight = Rgb(0.0f);
    return false;
}

// Ratio tracking with the same segments and majorants; Russian roulette once the estimate drops
// below kRatioRoulette (unbiased; it stops walks deep into the opaque interior).
Rgb MacrofacetMedium::transmittance(const Ray& ray, float t_max, Sampler& sampler) const {
    double T = 1.0;
    MarchEnd e = march(ray, t_max, sampler,
                       [&](double, const Vec3&, double st, double mu, const Vec3&, const Vec3&, float) {
                           T *= std::max(0.0, 1.0 - st / mu);
                           if (T < kRatioRoulette) {
                               if (!(double(sampler.next_1d()) * kRatioRoulette < T)) return false;  // killed
                               T = kRatioRoulette;
                           }
                           return true;
                       });
    return e == MarchEnd::Left ? Rgb(float(T)) : Rgb(0.0f);
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

std::shared_ptr<Medium> create_macrofacet_medium(const MediumParamBag& bag, const std::shared_ptr<const Shape>& shape) {
    const std::string what = describe(bag);
    if (bag.type != "macrofacet") throw Error(bag.loc, what + ": not a macrofacet medium");
    double sigma = -1;
    ParamsGuard params;
    params.p = bag_to_params(bag, &sigma);
    mf_medium* handle = nullptr;
    if (mf_medium_new(params.p, &handle) != MF_OK) throw medium_param_error(bag, last_error());
    if (!(sigma > 0)) {  // cannot happen after a successful mf_medium_new; keep the handle safe
        mf_medium_free(handle);
        throw Error(bag.loc, what + ": sigma must be positive");
    }
    return std::make_shared<MacrofacetMedium>(handle, shape, sigma, medium_label(bag));
}

// ----------------------------------------------------------------------------------------------
// The region boundary f = top

std::shared_ptr<const SdfBoundGrid> make_sdf_bound_grid(const std::shared_ptr<const Shape>& mean, double top) {
    auto mesh = std::dynamic_pointer_cast<const MeshShape>(mean);
    if (!mesh || mesh->has_analytic_sdf()) return nullptr;
    Aabb b = mesh->bounds();
    float grow = float(top) + 0.05f * max_comp(b.extent());
    b.lo = b.lo - Vec3(grow);
    b.hi = b.hi + Vec3(grow);
    return std::make_shared<SdfBoundGrid>(*mesh, b, 64);
}

std::shared_ptr<Shape> make_region_boundary(const std::shared_ptr<const Shape>& mean, double top_d,
                                            const std::shared_ptr<const Medium>& medium,
                                            const std::shared_ptr<const SdfBoundGrid>& grid) {
    const float top = float(top_d);
    std::shared_ptr<Shape> b;
    if (auto sph = std::dynamic_pointer_cast<const SphereShape>(mean)) {
        // exact: the level set f = top of a sphere is the concentric sphere of radius r +- top
        float r = sph->flipped() ? sph->radius() - top : sph->radius() + top;
        if (!(r > 0))
            throw Error(mean->loc, "<shape type=\"sphere\">: the " + medium->name() + " shell (" + std::to_string(top) +
                                       ") is thicker than this flipped sphere's radius");
        b = std::make_shared<SphereShape>(sph->center(), r, sph->flipped());
    } else {
        b = std::make_shared<LevelSetShape>(mean, top, grid);
    }
    b->id = mean->id;
    b->loc = mean->loc;
    b->bsdf = make_null_bsdf();
    b->interior = medium;
    b->exterior = mean->exterior;
    return b;
}

// ----------------------------------------------------------------------------------------------
// LevelSetShape

LevelSetShape::LevelSetShape(std::shared_ptr<const Shape> base, float offset, std::shared_ptr<const SdfBoundGrid> grid)
    : base_(std::move(base)), offset_(offset), grid_(std::move(grid)) {
    Aabb b = base_->bounds();
    float ext = std::max(1e-6f, max_comp(b.extent()));
    // A level set f = offset > 0 lies within `offset` of the base shape's bounds.
    float grow = std::max(0.0f, offset_) + 1e-4f * ext;
    bounds_.lo = b.lo - Vec3(grow);
    bounds_.hi = b.hi + Vec3(grow);
    min_step_ = 1e-3f * ext;
    tol_ = 1e-6f * (ext + max_comp(vabs(b.center())));
}

SdfSample LevelSetShape::sdf(const Vec3& p) const {
    SdfSample s = base_->sdf(p);
    s.f -= offset_;
    return s;
}

void LevelSetShape::sample_position(const Vec2&, Vec3*, Vec3*) const {
    throw Error(loc, "a macrofacet shell boundary cannot be sampled (it cannot carry an emitter)");
}

// Sphere tracing of g(t) = sdf(o + t d) - offset: a step of |g| cannot cross the level set
// (1-Lipschitz); steps are at least min_step_ so that grazing rays progress. A sign change is
// then located by bisection down to tol_. The first crossing after tnear is reported.
bool LevelSetShape::intersect(const Vec3& o, const Vec3& d, float tnear, float tfar, float* t_hit, bool* exiting) const {
    // clip to the bounds (slab test)
    double t0 = tnear, t1 = tfar;
    for (int a = 0; a < 3; ++a) {
        double inv = 1.0 / double(d[a]);
        double ta = (double(bounds_.lo[a]) - o[a]) * inv, tb = (double(bounds_.hi[a]) - o[a]) * inv;
        if (std::isnan(ta) || std::isnan(tb)) {  // d[a] == 0 and o on a slab plane
            if (o[a] < bounds_.lo[a] || o[a] > bounds_.hi[a]) return false;
            continue;
        }
        if (ta > tb) std::swap(ta, tb);
        t0 = std::max(t0, ta);
        t1 = std::min(t1, tb);
    }
    if (!(t0 <= t1)) return false;
    auto g = [&](double t) { return double(base_->sdf(o + d * float(t)).f) - offset_; };
    // A value with the sign of g and at most its magnitude: from the bound grid when it proves
    // the sign (far from the level set), else exact.
    auto g_step = [&](double t) {
        if (grid_) {
            float lo, hi;
            grid_->bounds(o + d * float(t), &lo, &hi);
            if (lo - offset_ > 0) return double(lo - offset_);
            if (hi - offset_ < 0) return double(hi - offset_);
        }
        return g(t);
    };
    double t = t0, gt = g_step(t);
    const bool inside0 = gt < 0;
    for (int it = 0; it < 100000; ++it) {
        bool last = false;
        double tn = t + std::max(std::fabs(gt), double(min_step_));
        if (tn >= t1) {
            tn = t1;
            last = true;
        }
        double gn = g_step(tn);
        if ((gn < 0) != inside0) {
            // Bracketed root refinement: Illinois (modified regula falsi) on exact values,
            // falling back to bisection, down to tol_; [lo, hi] always brackets the crossing.
            double lo = t, hi = tn, glo = g(lo), ghi = g(hi);
            if ((glo < 0) != inside0) {  // bound-grid value was not exact: re-bracket
                hi = lo;
                ghi = glo;
                lo = t - std::max(std::fabs(gt), double(min_step_));
                glo = g(std::max(lo, double(t0)));
            }
            int side = 0;
            for (int k = 0; k < 60 && hi - lo > tol_; ++k) {
                double x = (glo != ghi) ? (lo * ghi - hi * glo) / (ghi - glo) : 0.5 * (lo + hi);
                if (!(x > lo && x < hi) || k % 4 == 3) x = 0.5 * (lo + hi);  // keep shrinking the bracket
                double gx = g(x);
                if (std::fabs(gx) <= 0.5 * tol_) {  // within tol_ of the level set (g is a distance)
                    lo = hi = x;
                    break;
                }
                if ((gx < 0) != inside0) {
                    hi = x;
                    ghi = gx;
                    if (side == -1) glo *= 0.5;
                    side = -1;
                } else {
                    lo = x;
                    glo = gx;
                    if (side == 1) ghi *= 0.5;
                    side = 1;
                }
            }
            if (!(hi > tnear)) return false;
            *t_hit = float(hi);
            *exiting = inside0;
            return true;
        }
        if (last) return false;
        t = tn;
        gt = gn;
    }
    return false;
}

namespace {

bool levelset_hit(const LevelSetShape& s, const Vec3& o, const Vec3& d, float tnear, float tfar, UserGeometryHit* h) {
    bool exiting;
    if (!s.intersect(o, d, tnear, tfar, &h->t, &exiting)) return false;
    h->ng = exiting ? d : -d;       // placeholder; fill_hit computes the real normal
    h->u = exiting ? 1.0f : 0.0f;  // crossing direction for fill_hit
    return true;
}

}  // namespace

unsigned LevelSetShape::attach(RTCDevice device, RTCScene scene) const {
    return UserGeometry<LevelSetShape, levelset_hit>::attach(device, scene, this);
}

void LevelSetShape::fill_hit(const Ray& ray, float t, unsigned prim, float u, float, SurfaceHit* hit) const {
    const bool exiting = u > 0.5f;
    Vec3 p = ray.at(t);
    Vec3 n = base_->sdf(p).grad;
    // The normal must agree with the crossing the tracer found (dot(d, n) > 0 when leaving the
    // medium): the integrator picks the next medium from its sign. Near-tangent crossings where
    // the SDF gradient disagrees fall back to the ray direction.
    float c = dot(ray.d, n);
    if (!(length_sq(n) > 0.5f) || (exiting ? c <= 1e-4f : c >= -1e-4f)) n = exiting ? ray.d : -ray.d;
    hit->t = t;
    hit->p = p;
    hit->ng = normalize(n);
    hit->ns = hit->ng;
    hit->uv = Vec2(0.0f, 0.0f);
    hit->shape = this;
    hit->prim = prim;
}

}  // namespace mf
