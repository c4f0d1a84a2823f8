// mfhost — library-owned microfacet distributions (see microfacet_library.h).
#include "microfacet_library.h"

#include <macrofacet.h>

#include <cmath>

#include "error.h"

namespace mf {

namespace {

// The shading frame is the local frame: normal +z, tangent (alpha_u, transform x axis) +x.
const mf_frame kLocalFrame = {{0.0, 0.0, 1.0}, {1.0, 0.0, 0.0}};

mf_vec3 vec(const Vec3& v) {
    // Directions arrive normalised in float; renormalise in double so that the library's
    // unit-length check (1e-6) never sees float round-off.
    double x = v.x, y = v.y, z = v.z;
    double len = std::sqrt(x * x + y * y + z * z);
    if (!(len > 0)) return mf_vec3{0.0, 0.0, 0.0};
    return mf_vec3{x / len, y / len, z / len};
}

std::string library_error() {
    char buf[512];
    size_t len = 0;
    if (mf_last_error_message(buf, sizeof buf, &len) != MF_OK) return "unknown error";
    return buf;
}

}  // namespace

LibraryMicrofacet::LibraryMicrofacet(mf_ndf* ndf, bool height_correlated) : ndf_(ndf), height_correlated_(height_correlated) {}

LibraryMicrofacet::~LibraryMicrofacet() { mf_ndf_free(ndf_); }

// A failing call (a degenerate direction) contributes nothing instead of stopping the render.
float LibraryMicrofacet::D(const Vec3& m) const {
    double d = 0;
    if (mf_ndf_eval(ndf_, &kLocalFrame, vec(m), &d) != MF_OK) return 0.0f;
    return float(d);
}

float LibraryMicrofacet::Lambda(const Vec3& w) const {
    double lambda = 0;
    if (mf_ndf_lambda(ndf_, &kLocalFrame, vec(w), &lambda) != MF_OK) return INFINITY;
    return float(lambda);
}

Vec3 LibraryMicrofacet::sample(const Vec3& wi, const Vec2& u, float u3, float* pdf) const {
    // Uniforms in [0, 1): a float can round up to 1.
    auto unit = [](float x) { return std::min(double(x), 1.0 - 1e-16); };
    double uu[MF_NDF_SAMPLE_DIMENSIONS] = {unit(u.x), unit(u.y), unit(u3)};
    mf_ndf_sample s;
    if (mf_ndf_sample_visible(ndf_, &kLocalFrame, vec(wi), uu, &s) != MF_OK || !s.valid) {
        *pdf = 0.0f;
        return Vec3(0.0f, 0.0f, 1.0f);
    }
    *pdf = float(s.pdf);
    return Vec3(float(s.m.x), float(s.m.y), float(s.m.z));
}

float LibraryMicrofacet::pdf(const Vec3& wi, const Vec3& m) const {
    double p = 0;
    if (mf_ndf_pdf_visible(ndf_, &kLocalFrame, vec(wi), vec(m), &p) != MF_OK) return 0.0f;
    return float(p);
}

std::shared_ptr<LibraryMicrofacet> make_library_microfacet(const mf_params* params, bool height_correlated,
                                                           const std::string& what) {
    mf_ndf* ndf = nullptr;
    if (mf_ndf_new(params, &ndf) != MF_OK) throw Error(what + ": " + library_error());
    return std::make_shared<LibraryMicrofacet>(ndf, height_correlated);
}

}  // namespace mf
