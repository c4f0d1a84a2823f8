// mfhost — the gpis medium through the C ABI (see medium_gpis.h and README.md).
#include "medium_gpis.h"

#include <macrofacet.h>

#include <cmath>
#include <memory>
#include <limits>

#include "library_abi.h"
#include "mean_surface.h"
#include "medium_field.h"
#include "medium_params.h"

namespace mf {
namespace {

// Layout of MediumInteraction::record for a crossing (double precision: the next segment starts
// exactly there, and the reflection uses the library's normal unrounded), then the field's local
// parameters there (medium_field.h: store_local / load_local).
constexpr int kPoint = 0, kNormal = 3, kGradient = 6, kLocal = 9;

/// The user_data of one mf_gpis_trace, shared by the mean's and the field's callbacks.
struct TraceContext {
    const mf_surface* surface;
    const LibraryField* field;  // null without a field
};

mf_vec3 record_vec(const MediumInteraction& mi, int at) { return mf_vec3{mi.record[at], mi.record[at + 1], mi.record[at + 2]}; }

void set_record_vec(MediumInteraction* mi, int at, const mf_vec3& v) {
    mi->record[at] = v.x;
    mi->record[at + 1] = v.y;
    mi->record[at + 2] = v.z;
}

/// mf_sdf_fn over the library's mean surface: its signed distance and frame normal (world
/// space). A failure is reported as NaN, which makes the trace fail with a status.
extern "C" void mean_sdf_callback(void* user_data, mf_vec3 p, mf_sdf_sample* out) {
    const mf_surface* surface = static_cast<const TraceContext*>(user_data)->surface;
    mf_surface_point s;
    if (mf_surface_eval(surface, nullptr, p, &s) == MF_OK) {
        out->f = s.f;
        out->gradient = s.normal;
        out->u = s.u;
        out->v = s.v;
    } else {
        out->f = std::numeric_limits<double>::quiet_NaN();
        out->gradient = mf_vec3{0, 0, 0};
    }
}

/// The medium's mf_field: forwards to the host field with its own user_data.
extern "C" int32_t field_at_callback(void* user_data, mf_vec3 p, const mf_surface_point* point, mf_local_params* out) {
    const LibraryField* f = static_cast<const TraceContext*>(user_data)->field;
    return f->callbacks().at(f->user_data(), p, point, out);
}

extern "C" int32_t field_bounds_callback(void* user_data, mf_vec3 p, mf_vec3 d, double length, mf_param_bounds* out) {
    const LibraryField* f = static_cast<const TraceContext*>(user_data)->field;
    return f->callbacks().bounds(f->user_data(), p, d, length, out);
}

/// The first entering crossing of a realization along ray.o + t ray.d, 0 < t <= t_max: ON_SURFACE
/// at `from`'s crossing (its exact point and sampled gradient) when given, else FREE at ray.o.
bool trace(const mf_gpis* gpis, const MeanSurface& mean, const mf_field* field, const LibraryField* host_field,
           const std::string& label, const Ray& ray, float t_max, const MediumInteraction* from, uint64_t seed, mf_gpis_hit* hit) {
    if (!(t_max > 0)) return false;
    mf_gpis_start start;
    mf_vec3 origin;
    if (from) {
        start.kind = MF_GPIS_START_ON_SURFACE;
        start.gradient = record_vec(*from, kGradient);
        origin = record_vec(*from, kPoint);
    } else {
        start.kind = MF_GPIS_START_FREE;
        start.gradient = mf_vec3{0, 0, 0};
        origin = to_mf(ray.o);
    }
    const double tm = std::isfinite(t_max) ? double(t_max) : std::numeric_limits<double>::infinity();
    TraceContext context{mean.handle(), host_field};
    if (mf_gpis_trace(gpis, mean_sdf_callback, field, &context, origin, to_mf_unit(ray.d), tm, &start, seed, hit) != MF_OK)
        throw Error(label + ": mf_gpis_trace failed: " + mf_last_error());
    return hit->hit;
}

/// The crossing's specular reflection (mf_gpis_scatter about the recorded normal, Fresnel ×
/// specular_reflectance): a Dirac lobe, so eval and pdf are 0 and sample returns *pdf = 0.
class GpisReflection final : public PhaseFunction {
public:
    GpisReflection(const mf_gpis* gpis, std::string label) : gpis_(gpis), label_(std::move(label)) {}
    Rgb eval(const MediumInteraction&, const Vec3&, const Vec3&) const override { return Rgb(0.0f); }
    float pdf(const MediumInteraction&, const Vec3&, const Vec3&) const override { return 0.0f; }
    bool sample(const MediumInteraction& mi, const Vec3& wo, Sampler&, Vec3* wi, float* pdf, Rgb* weight) const override {
        mf_vec3 n = record_vec(mi, kNormal);
        double l = std::sqrt(n.x * n.x + n.y * n.y + n.z * n.z);
        if (!(l > 0)) return false;
        mf_phase_sample_result s;
        mf_local_params local;
        if (mf_gpis_scatter(gpis_, load_local(mi, kLocal, &local), to_mf_unit(wo), mf_vec3{n.x / l, n.y / l, n.z / l}, &s) != MF_OK)
            throw Error(label_ + ": mf_gpis_scatter failed: " + mf_last_error());
        if (!s.valid) return false;
        *wi = from_mf(s.wo);
        *pdf = 0.0f;
        *weight = Rgb(float(s.weight.r), float(s.weight.g), float(s.weight.b));
        return weight->finite();
    }
    bool is_delta() const override { return true; }

private:
    const mf_gpis* gpis_;
    std::string label_;
};

}  // namespace

GpisMedium::GpisMedium(mf_gpis* handle, std::shared_ptr<const MeanSurface> mean, std::string label,
                       std::shared_ptr<const LibraryField> field)
    : handle_(handle), mean_(std::move(mean)), host_field_(std::move(field)), label_(std::move(label)) {
    phase_ = std::make_shared<GpisReflection>(handle_, label_);
    std::string msg;
    if (host_field_) {
        const mf_field_callbacks forward{field_at_callback, field_bounds_callback, host_field_->callbacks().sigma_max};
        if (mf_field_new_callbacks(&forward, &field_) != MF_OK) msg = "mf_field_new_callbacks failed: " + mf_last_error();
    }
    if (msg.empty() && (mf_gpis_envelope(handle_, field_, &envelope_) != MF_OK || !(envelope_ > 0)))
        msg = "mf_gpis_envelope failed: " + mf_last_error();
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

bool GpisMedium::sample_free_flight(const Ray& ray, float t_max, const MediumInteraction* from, int, Sampler& sampler,
                                    MediumInteraction* mi, Rgb* weight, Rgb* pdf_ratio) const {
    *weight = Rgb(1.0f);  // the realization decides: a crossing or a pass, each with weight 1
    *pdf_ratio = Rgb(1.0f);
    const uint64_t seed = sampler.next_u64();
    mf_gpis_hit h;
    if (!trace(handle_, *mean_, field_, host_field_.get(), label_, ray, t_max, from && from->medium == this ? from : nullptr, seed, &h))
        return false;
    mi->t = float(h.t);
    mi->p = from_mf(h.point);
    mi->wo = -ray.d;
    mi->frame_n = from_mf(h.normal);
    mi->medium = this;
    set_record_vec(mi, kPoint, h.point);
    set_record_vec(mi, kNormal, h.normal);
    set_record_vec(mi, kGradient, h.gradient);
    store_local(h.local, mi, kLocal);
    return true;
}

Rgb GpisMedium::transmittance(const Ray& ray, float t_max, Sampler& sampler) const {
    const uint64_t seed = sampler.next_u64();
    mf_gpis_hit h;
    return trace(handle_, *mean_, field_, host_field_.get(), label_, ray, t_max, nullptr, seed, &h) ? Rgb(0.0f) : Rgb(1.0f);
}

std::shared_ptr<GpisMedium> create_gpis_medium(const MediumParamBag& bag, std::shared_ptr<const MeanSurface> mean) {
    if (bag.type != "gpis") throw Error(bag.loc, "not a gpis medium");
    const MediumParamBag base = base_bag(bag);
    ParamsHandle params = bag_to_params(base);
    mf_gpis* handle = nullptr;
    if (mf_gpis_new(params.get(), &handle) != MF_OK) throw medium_param_error(base, mf_last_error());
    std::unique_ptr<mf_gpis, void (*)(mf_gpis*)> owned(handle, mf_gpis_free);  // freed if the field throws
    std::shared_ptr<const LibraryField> field = library_field_of(bag);
    return std::make_shared<GpisMedium>(owned.release(), std::move(mean), medium_label(bag), std::move(field));
}

}  // namespace mf
