// mfhost — the medium parameters that may vary in space (see varying_param.h).
#include "varying_param.h"

#include <algorithm>
#include <cmath>

#include "field.h"

namespace mf {

namespace {

constexpr VaryingParam kVaryingParams[] = {
    {"sigma", 1, Constraint::Positive, true},
    {"variance", 1, Constraint::Positive, true},
    {"alpha", 1, Constraint::Positive, true},
    {"alpha_u", 1, Constraint::Positive, true},
    {"alpha_v", 1, Constraint::Positive, true},
    {"alpha_z", 1, Constraint::NonNegative, true},  // 0 = a height field (seeds/000 §5)
    {"lengthscale", 1, Constraint::Positive, true},
    {"lengthscale_x", 1, Constraint::Positive, true},
    {"lengthscale_y", 1, Constraint::Positive, true},
    {"lengthscale_z", 1, Constraint::Positive, true},
    {"specular_reflectance", 3, Constraint::Unit, true},
    {"reflectance", 3, Constraint::Unit, true},
    {"anisotropy", 6, Constraint::Matrix, false},
    {"anisotropy_diagonal", 3, Constraint::Matrix, false},
    {"anisotropy_offdiagonal", 3, Constraint::Matrix, false},
};

/// Smallest and largest eigenvalue of the symmetric matrix s = (xx, yy, zz, xy, xz, yz)
/// (trigonometric solution of the characteristic cubic, in double precision).
void eigen_range(const double s[6], double* lmin, double* lmax) {
    const double xx = s[0], yy = s[1], zz = s[2], xy = s[3], xz = s[4], yz = s[5];
    const double p1 = xy * xy + xz * xz + yz * yz;
    const double q = (xx + yy + zz) / 3;
    if (p1 == 0) {
        *lmin = std::min(xx, std::min(yy, zz));
        *lmax = std::max(xx, std::max(yy, zz));
        return;
    }
    const double p2 = (xx - q) * (xx - q) + (yy - q) * (yy - q) + (zz - q) * (zz - q) + 2 * p1;
    const double p = std::sqrt(p2 / 6);
    // B = (A - q I) / p; r = det(B) / 2, clamped to [-1, 1] against rounding
    const double b00 = (xx - q) / p, b11 = (yy - q) / p, b22 = (zz - q) / p, b01 = xy / p, b02 = xz / p, b12 = yz / p;
    double r = 0.5 * (b00 * (b11 * b22 - b12 * b12) - b01 * (b01 * b22 - b12 * b02) + b02 * (b01 * b12 - b11 * b02));
    r = std::clamp(r, -1.0, 1.0);
    const double phi = std::acos(r) / 3;
    const double e1 = q + 2 * p * std::cos(phi);
    const double e3 = q + 2 * p * std::cos(phi + 2.0943951023931954923);  // + 2 pi / 3
    *lmax = e1;
    *lmin = e3;
}

}  // namespace

const VaryingParam* varying_param(const std::string& name) {
    for (const VaryingParam& v : kVaryingParams)
        if (name == v.name) return &v;
    return nullptr;
}

std::string varying_param_list() {
    std::string s;
    for (const VaryingParam& v : kVaryingParams) s += (s.empty() ? "" : ", ") + std::string(v.name);
    return s;
}

const char* constraint_text(Constraint c) {
    switch (c) {
        case Constraint::Positive: return "must be finite and > 0";
        case Constraint::NonNegative: return "must be finite and >= 0";
        case Constraint::Unit: return "must lie in [0, 1]";
        case Constraint::Matrix: return "must be finite";
    }
    return "";
}

bool satisfies(Constraint c, float x) {
    switch (c) {
        case Constraint::Positive: return std::isfinite(x) && x > 0;
        case Constraint::NonNegative: return std::isfinite(x) && x >= 0;
        case Constraint::Unit: return x >= 0 && x <= 1;
        case Constraint::Matrix: return std::isfinite(x);
    }
    return false;
}

bool positive_definite(const double s[6]) {
    const double xx = s[0], yy = s[1], zz = s[2], xy = s[3], xz = s[4], yz = s[5];
    const double m2 = xx * yy - xy * xy;
    const double det = xx * (yy * zz - yz * yz) - xy * (xy * zz - yz * xz) + xz * (xy * yz - yy * xz);
    return xx > 0 && m2 > 0 && det > 0;
}

void matrix_sample(const double s[6], float out[8]) {
    for (int c = 0; c < 6; ++c) out[c] = float(s[c]);
    double lmin, lmax;
    eigen_range(s, &lmin, &lmax);
    // The closed form is accurate to a few ulps of the largest entry: widen by that much.
    double slack = 1e-12 * std::max({std::fabs(lmin), std::fabs(lmax), 1e-300});
    out[Field::kEigenMin] = std::nextafter(float(lmin - slack), -kInf);
    out[Field::kEigenMax] = std::nextafter(float(lmax + slack), kInf);
}

MediumParamBag stand_in_bag(const MediumParamBag& bag) {
    MediumParamBag out = bag;
    out.fields = nullptr;
    if (!bag.fields) return out;
    for (const auto& f : bag.fields->fields) {
        const VaryingParam* p = varying_param(f->param());
        if (!p || !p->scalar_form) continue;
        ParamValue v;
        v.loc = f->loc();
        ValueRange r = f->range();
        if (f->channels() == 1) {
            v.kind = ParamValue::Kind::Float;
            v.f = r.hi[0];
        } else {
            v.kind = ParamValue::Kind::Rgb;
            v.rgb = Rgb(r.hi[0], r.hi[1], r.hi[2]);
        }
        out.params.emplace_back(f->param(), v);
    }
    return out;
}

}  // namespace mf
