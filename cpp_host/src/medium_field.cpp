// mfhost — a medium's fields as the library's mf_field (see medium_field.h).
#include "medium_field.h"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "library_abi.h"
#include "varying_param.h"
#include "macrofacet.h"

namespace mf {

namespace {

constexpr double kSqrt2 = 1.4142135623730951;

/// The bag's constant, or the field of that name.
LibraryField::Scalar scalar(const MediumParamBag& bag, const char* name) {
    LibraryField::Scalar s;
    if (const Field* f = bag.fields ? bag.fields->find(name) : nullptr) {
        s.field = f;
        s.present = true;
    } else if (const ParamValue* v = bag.get(name)) {
        s.value = v->kind == ParamValue::Kind::Int ? double(v->i) : v->f;
        s.present = true;
    }
    return s;
}

double value_at(const LibraryField::Scalar& s, const Vec3& p, const Vec2& uv) {
    if (!s.field) return s.value;
    float v;
    s.field->eval(p, uv, &v);
    return double(v);
}

/// [lo, hi] of a scalar along a segment (a texture: over all of its uv).
std::array<double, 2> range_along(const LibraryField::Scalar& s, const Vec3& o, const Vec3& d, float length) {
    if (!s.field) return {s.value, s.value};
    ValueRange r = s.field->range_segment(o, d, length);
    return {double(r.lo[0]), double(r.hi[0])};
}

}  // namespace

struct LibraryFieldCallbacks {
    /// The roughness triple (alpha_u, alpha_v, alpha_z) at a point, for local sigma `sigma`.
    static std::array<double, 3> roughness(const LibraryField& lf, double sigma, const Vec3& p, const Vec2& uv) {
        auto alpha = [&](const LibraryField::Scalar& s) {
            double v = value_at(s, p, uv);
            return lf.kernel_form_ ? kSqrt2 * sigma / v : v;
        };
        const auto& [iso, u, v, z] = lf.roughness_;
        std::array<double, 3> a{};
        if (iso.present) a = {alpha(iso), alpha(iso), alpha(iso)};
        if (u.present) a[0] = alpha(u);
        if (v.present) a[1] = alpha(v);
        // Without an alpha_z (lengthscale_z) a gpss medium is isotropic (src/params.rs); beckmann
        // and ggx do not read it.
        a[2] = !lf.gpss_ ? 0.0 : z.present ? alpha(z) : a[2];
        return a;
    }

    static int32_t at(void* user_data, mf_vec3 pm, const mf_surface_point* point, mf_local_params* out) {
        const auto& lf = *static_cast<const LibraryField*>(user_data);
        const Vec3 p(float(pm.x), float(pm.y), float(pm.z));
        const Vec2 uv(float(point->u), float(point->v));
        std::memset(out, 0, sizeof *out);
        double sigma = value_at(lf.sigma_, p, uv);
        if (lf.variance_) sigma = std::sqrt(sigma);
        if (lf.sigma_.field) {
            out->set |= MF_LOCAL_SIGMA;
            out->sigma = sigma;
        }
        if (lf.anisotropy_) {
            float s[6];
            lf.anisotropy_->eval(p, uv, s);
            out->set |= MF_LOCAL_ANISOTROPY | MF_LOCAL_SIGMA;
            out->sigma = sigma;
            for (int i = 0; i < 6; ++i) out->anisotropy[i] = double(s[i]);
        } else if (lf.roughness_varies_) {
            auto a = roughness(lf, sigma, p, uv);
            out->set |= MF_LOCAL_ALPHA;
            out->alpha = mf_vec3{a[0], a[1], a[2]};
        }
        if (lf.reflectance_) {
            float r[3];
            lf.reflectance_->eval(p, uv, r);
            const int n = lf.reflectance_->channels();
            out->set |= MF_LOCAL_REFLECTANCE_SCALE;
            double scale[3];
            for (int c = 0; c < 3; ++c) {
                const double base = lf.reflectance_base_[c];
                scale[c] = base > 0 ? double(r[n == 3 ? c : 0]) / base : 0.0;
            }
            out->reflectance_scale = mf_rgb{scale[0], scale[1], scale[2]};
        }
        return 0;
    }

    static int32_t bounds(void* user_data, mf_vec3 pm, mf_vec3 dm, double length, mf_param_bounds* out) {
        const auto& lf = *static_cast<const LibraryField*>(user_data);
        const Vec3 o(float(pm.x), float(pm.y), float(pm.z)), d(float(dm.x), float(dm.y), float(dm.z));
        // The float segment may stop a rounding short of the double one: reach a little farther.
        const float len = float(length) * (1 + 1e-5f) + 1e-6f;
        std::memset(out, 0, sizeof *out);
        auto sigma = range_along(lf.sigma_, o, d, len);
        if (lf.variance_) sigma = {std::sqrt(sigma[0]), std::sqrt(sigma[1])};
        if (lf.sigma_.field) {
            out->set |= MF_LOCAL_SIGMA;
            out->sigma_lo = sigma[0];
            out->sigma_hi = sigma[1];
        }
        if (lf.anisotropy_) {
            // Every roughness sqrt(λ(2σ²Σ⁻¹)) lies in [√2σ_lo/√λmax(Σ), √2σ_hi/√λmin(Σ)].
            ValueRange r = lf.anisotropy_->range_segment(o, d, len);
            const double lmin = double(r.lo[Field::kEigenMin]), lmax = double(r.hi[Field::kEigenMax]);
            if (!(lmin > 0)) return 2;
            out->set |= MF_LOCAL_ALPHA | MF_LOCAL_SIGMA;
            out->sigma_lo = sigma[0];
            out->sigma_hi = sigma[1];
            out->alpha_lo = kSqrt2 * sigma[0] / std::sqrt(lmax);
            out->alpha_hi = kSqrt2 * sigma[1] / std::sqrt(lmin);
        } else if (lf.roughness_varies_) {
            double lo = INFINITY, hi = 0;
            const auto& [iso, u, v, z] = lf.roughness_;
            for (const auto* s : {&iso, &u, &v, &z}) {
                if (!s->present || (s == &z && !lf.gpss_)) continue;
                auto r = range_along(*s, o, d, len);
                // Roughness form: as given; kernel form: √2σ/l, smallest at σ_lo and l_hi.
                const double a_lo = lf.kernel_form_ ? kSqrt2 * sigma[0] / r[1] : r[0];
                const double a_hi = lf.kernel_form_ ? kSqrt2 * sigma[1] / r[0] : r[1];
                lo = std::min(lo, a_lo);
                hi = std::max(hi, a_hi);
            }
            out->set |= MF_LOCAL_ALPHA;
            out->alpha_lo = lo;
            out->alpha_hi = hi;
        }
        return 0;
    }
};

LibraryField::LibraryField(const MediumParamBag& bag, bool gpss) : gpss_(gpss) {
    sigma_ = scalar(bag, "sigma");
    if (!sigma_.present) {
        sigma_ = scalar(bag, "variance");
        variance_ = true;
    }
    kernel_form_ = scalar(bag, "lengthscale").present || scalar(bag, "lengthscale_x").present;
    const char* names[2][4] = {{"alpha", "alpha_u", "alpha_v", "alpha_z"}, {"lengthscale", "lengthscale_x", "lengthscale_y", "lengthscale_z"}};
    for (int i = 0; i < 4; ++i) roughness_[i] = scalar(bag, names[kernel_form_ ? 1 : 0][i]);
    roughness_varies_ = std::any_of(roughness_.begin(), roughness_.end(), [](const Scalar& s) { return s.field != nullptr; }) ||
                        (kernel_form_ && sigma_.field);
    if (bag.fields) {
        anisotropy_ = bag.fields->find("anisotropy");
        reflectance_ = bag.fields->find("specular_reflectance");
        if (!reflectance_) reflectance_ = bag.fields->find("reflectance");
    }
    if (anisotropy_ && !gpss)
        throw Error(anisotropy_->loc(), "the anisotropy applies to distribution \"gpss\" (the generalized macrofacet), not to height-field distributions");
    if (reflectance_) {
        // The base medium holds the largest value of each channel (stand_in_bag).
        ValueRange r = reflectance_->range();
        for (int c = 0; c < 3; ++c) reflectance_base_[c] = double(r.hi[reflectance_->channels() == 3 ? c : 0]);
    }
    double sigma_max = 0;
    if (sigma_.field) {
        sigma_max = double(sigma_.field->range().hi[0]);
        if (variance_) sigma_max = std::sqrt(sigma_max);
    }
    callbacks_ = std::make_shared<mf_field_callbacks>(mf_field_callbacks{LibraryFieldCallbacks::at, LibraryFieldCallbacks::bounds, sigma_max});
    if (mf_field_new_callbacks(callbacks_.get(), &handle_) != MF_OK) throw Error(bag.loc, "mf_field_new_callbacks failed: " + mf_last_error());
}

const mf_field_callbacks& LibraryField::callbacks() const { return *callbacks_; }

std::shared_ptr<const LibraryField> library_field_of(const MediumParamBag& bag) {
    if (!bag.fields) return nullptr;
    const ParamValue* distribution = bag.get("distribution");
    return std::make_shared<LibraryField>(bag, !distribution || distribution->s == "gpss");
}

MediumParamBag base_bag(const MediumParamBag& bag) {
    if (!bag.fields) return bag;
    MediumParamBag base = stand_in_bag(bag);
    const Field* anisotropy = bag.fields->find("anisotropy");
    const bool has_roughness = base.get("alpha") || base.get("alpha_u") || base.get("lengthscale") || base.get("lengthscale_x");
    if (anisotropy && !has_roughness) {
        const ParamValue* s = base.get("sigma");
        const double sigma = s ? s->f : std::sqrt(base.get("variance") ? base.get("variance")->f : 0.0);
        const double lambda_min = double(anisotropy->range().lo[Field::kEigenMin]);
        ParamValue alpha;
        alpha.kind = ParamValue::Kind::Float;
        alpha.f = lambda_min > 0 ? kSqrt2 * sigma / std::sqrt(lambda_min) : 1.0;
        alpha.loc = anisotropy->loc();
        base.params.emplace_back("alpha", alpha);
    }
    return base;
}

void store_local(const mf_local_params& l, MediumInteraction* mi, int at) {
    const double v[14] = {double(l.set), l.sigma, l.alpha.x, l.alpha.y, l.alpha.z, l.anisotropy[0], l.anisotropy[1],
                          l.anisotropy[2], l.anisotropy[3], l.anisotropy[4], l.anisotropy[5], l.reflectance_scale.r,
                          l.reflectance_scale.g, l.reflectance_scale.b};
    std::copy(v, v + 14, mi->record.begin() + at);
}

const mf_local_params* load_local(const MediumInteraction& mi, int at, mf_local_params* out) {
    const double* r = mi.record.data() + at;
    if (r[0] == 0) return nullptr;
    *out = mf_local_params{uint32_t(r[0]), r[1], mf_vec3{r[2], r[3], r[4]}, {r[5], r[6], r[7], r[8], r[9], r[10]}, mf_rgb{r[11], r[12], r[13]}};
    return out;
}

LibraryField::~LibraryField() { mf_field_free(handle_); }

}  // namespace mf
