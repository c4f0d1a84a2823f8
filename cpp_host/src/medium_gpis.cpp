// mfhost — the gpis medium through the C ABI (see medium_gpis.h and README.md).
#include "medium_gpis.h"

#include <cmath>
#include <exception>
#include <limits>

#include "mean_surface.h"
#include "medium_macrofacet.h"

namespace mf {
namespace {

/// The user_data of one mf_gpis_trace, shared by the mean's and the field's callbacks.
struct TraceContext {
    const mf_surface* surface;
    const GpisField* field;  // null without a field
};

/// mf_sdf_fn over the library's mean surface: its signed distance and frame normal (world
/// space). A failure is reported as NaN, which makes the trace fail with a status.
extern "C" void mean_sdf_callback(void* user_data, mf_vec3 p, mf_sdf_sample* out) {
    const mf_surface* surface = static_cast<const TraceContext*>(user_data)->surface;
    mf_surface_point s;
    if (mf_surface_eval(surface, nullptr, p, &s) == MF_OK) {
        out->f = s.f;
        out->gradient = s.normal;
    } else {
        out->f = std::numeric_limits<double>::quiet_NaN();
        out->gradient = mf_vec3{0, 0, 0};
    }
}

/// The medium's mf_field: forwards to the host field's callbacks with its own data.
extern "C" int32_t field_at_callback(void* user_data, mf_vec3 p, const mf_surface_point* point, mf_local_params* out) {
    const GpisField* f = static_cast<const TraceContext*>(user_data)->field;
    return f->callbacks.at(f->user_data, p, point, out);
}

extern "C" int32_t field_bounds_callback(void* user_data, mf_vec3 p, mf_vec3 d, double length, mf_param_bounds* out) {
    const GpisField* f = static_cast<const TraceContext*>(user_data)->field;
    return f->callbacks.bounds(f->user_data, p, d, length, out);
}

mf_vec3 unit_d(const Vec3& v) {
    double x = v.x, y = v.y, z = v.z, l = std::sqrt(x * x + y * y + z * z);
    if (!(l > 0)) return mf_vec3{0, 0, 1};
    return mf_vec3{x / l, y / l, z / l};
}

/// Never used by the integrator (gpis vertices are delta reflections it handles itself): a delta
/// lobe has no density, so eval/pdf are 0 and sample reflects with pdf 0.
class GpisPhase final : public PhaseFunction {
public:
    explicit GpisPhase(const GpisMedium* m) : m_(m) {}
    Rgb eval(const MediumInteraction&, const Vec3&, const Vec3&) const override { return Rgb(0.0f); }
    float pdf(const MediumInteraction&, const Vec3&, const Vec3&) const override { return 0.0f; }
    bool sample(const MediumInteraction& mi, const Vec3& wo, Sampler&, Vec3* wi, float* pdf, Rgb* weight) const override {
        GpisHit h;
        h.normal[0] = mi.frame_n.x;
        h.normal[1] = mi.frame_n.y;
        h.normal[2] = mi.frame_n.z;
        *pdf = 0.0f;
        return m_->scatter(wo, h, wi, weight);
    }

private:
    const GpisMedium* m_;
};

}  // namespace

GpisMedium::GpisMedium(mf_gpis* handle, std::shared_ptr<const MeanSurface> mean, std::string label,
                       const GpisField* field)
    : handle_(handle), mean_(std::move(mean)), label_(std::move(label)) {
    phase_ = std::make_shared<GpisPhase>(this);
    std::string msg;
    if (field) {
        host_field_ = *field;
        const mf_field_callbacks forward{field_at_callback, field_bounds_callback, field->callbacks.sigma_max};
        if (!field->callbacks.at || !field->callbacks.bounds)
            msg = "the field needs both callbacks (at, bounds)";
        else if (mf_field_new_callbacks(&forward, &field_) != MF_OK)
            msg = std::string("mf_field_new_callbacks failed: ") + mf_last_error();
    }
    if (msg.empty() && (mf_gpis_envelope(handle_, field_, &envelope_) != MF_OK || !(envelope_ > 0)))
        msg = std::string("mf_gpis_envelope failed: ") + mf_last_error();
    if (!msg.empty()) {
        mf_field_free(field_);
        mf_gpis_free(handle_);
        throw Error(label_ + ": " + msg);
    }
}

GpisMedium::~GpisMedium() {
    mf_field_free(field_);
    mf_gpis_free(handle_);
}

bool GpisMedium::trace(const Vec3& o, const Vec3& d, double t_max, const GpisStart& start, uint64_t seed,
                       GpisHit* hit) const {
    if (!(t_max > 0)) return false;
    mf_gpis_start st;
    mf_vec3 origin;
    if (start.on_surface) {
        st.kind = MF_GPIS_START_ON_SURFACE;
        st.gradient = mf_vec3{start.gradient[0], start.gradient[1], start.gradient[2]};
        origin = mf_vec3{start.p[0], start.p[1], start.p[2]};
    } else {
        st.kind = MF_GPIS_START_FREE;
        st.gradient = mf_vec3{0, 0, 0};
        origin = mf_vec3{o.x, o.y, o.z};
    }
    mf_gpis_hit h;
    const double tm = std::isfinite(t_max) ? t_max : std::numeric_limits<double>::infinity();
    TraceContext context{mean_->handle(), field_ ? &host_field_ : nullptr};
    if (mf_gpis_trace(handle_, mean_sdf_callback, field_, &context, origin, unit_d(d), tm, &st, seed, &h) != MF_OK)
        throw Error(label_ + ": mf_gpis_trace failed: " + mf_last_error());
    if (!h.hit) return false;
    hit->t = h.t;
    hit->p[0] = h.point.x, hit->p[1] = h.point.y, hit->p[2] = h.point.z;
    hit->normal[0] = h.normal.x, hit->normal[1] = h.normal.y, hit->normal[2] = h.normal.z;
    hit->gradient[0] = h.gradient.x, hit->gradient[1] = h.gradient.y, hit->gradient[2] = h.gradient.z;
    hit->local = h.local;
    return true;
}

bool GpisMedium::scatter(const Vec3& wo, const GpisHit& hit, Vec3* wi, Rgb* weight) const {
    double nx = hit.normal[0], ny = hit.normal[1], nz = hit.normal[2], l = std::sqrt(nx * nx + ny * ny + nz * nz);
    if (!(l > 0)) return false;
    mf_phase_sample_result s;
    if (mf_gpis_scatter(handle_, &hit.local, unit_d(wo), mf_vec3{nx / l, ny / l, nz / l}, &s) != MF_OK)
        throw Error(label_ + ": mf_gpis_scatter failed: " + mf_last_error());
    if (!s.valid) return false;
    *wi = Vec3(float(s.wo.x), float(s.wo.y), float(s.wo.z));
    *weight = Rgb(float(s.weight.r), float(s.weight.g), float(s.weight.b));
    return weight->finite();
}

bool GpisMedium::sample_free_flight(const Ray& ray, float t_max, int, Sampler& sampler, MediumInteraction* mi,
                                    Rgb* weight, Rgb* pdf_ratio) const {
    *weight = Rgb(1.0f);
    *pdf_ratio = Rgb(1.0f);
    GpisHit h;
    if (!trace(ray.o, ray.d, t_max, GpisStart(), sampler.next_u64(), &h)) return false;
    mi->t = float(h.t);
    mi->p = h.point();
    mi->wo = -ray.d;
    mi->frame_n = h.n();
    mi->medium = this;
    return true;
}

Rgb GpisMedium::transmittance(const Ray& ray, float t_max, Sampler& sampler) const {
    GpisHit h;
    return trace(ray.o, ray.d, t_max, GpisStart(), sampler.next_u64(), &h) ? Rgb(0.0f) : Rgb(1.0f);
}

std::shared_ptr<GpisMedium> create_gpis_medium(const MediumParamBag& bag, std::shared_ptr<const MeanSurface> mean,
                                               const GpisField* field) {
    if (bag.type != "gpis") throw Error(bag.loc, "not a gpis medium");
    mf_params* params = bag_to_params(bag, nullptr);
    mf_gpis* handle = nullptr;
    mf_status st = mf_gpis_new(params, &handle);
    std::string msg = st == MF_OK ? std::string() : mf_last_error();
    mf_params_free(params);
    if (st != MF_OK) throw medium_param_error(bag, msg);
    return std::make_shared<GpisMedium>(handle, std::move(mean), medium_label(bag), field);
}

}  // namespace mf
