// mfhost — Mitsuba 3's normalmap BSDF: a nested BSDF evaluated in a shading frame tilted by a
// normal-map texture, with Mitsuba 3.9.1's rules (measured through its Python API, see
// tests/test_bsdf.cpp normal_map_as_mitsuba):
//   * the map's value c gives the tilted normal n = normalize(2 c - 1) in the local shading
//     frame; its tangent is the shading frame's s made orthogonal to n (dp/du plays no further
//     part);
//   * where the camera-side direction lies on different sides of n and of the shading normal,
//     the tangential part of n is mirrored, n = (-n_x, -n_y, n_z) (seen from below the surface,
//     e.g. inside a dielectric, a direction below n is therefore kept);
//   * a direction must lie on the same side of both frames (else the BSDF is zero);
//   * use_shadowing_function (default true) multiplies eval and the sampling weight, not the
//     pdf, by the Smith-type shadowing of the light-side direction of Conty Estevez et al. 2019
//     ("A Microfacet-Based Shadowing Function to Solve the Bump Terminator Problem", Ray
//     Tracing Gems ch. 12): G = 2 / (1 + sqrt(1 + alpha^2 tan^2 theta)), with
//     alpha^2 = clamp(tan^2(angle between n and the shading normal) / 8, 0, 1).
#include <algorithm>
#include <cmath>

#include "bsdf.h"

namespace mf {
namespace {

class NormalMap final : public Bsdf {
public:
    NormalMap(std::shared_ptr<const Texture> normals, std::shared_ptr<Bsdf> nested, bool shadowing)
        : normals_(std::move(normals)), nested_(std::move(nested)), shadowing_(shadowing) {}

    Rgb eval(const TexturePoint& uv, const Vec3& wo, const Vec3& wi) const override {
        Frame f = frame(uv, wo);
        Vec3 wi_p = f.to_local(wi);
        if (!(wi.z * wi_p.z > 0)) return Rgb(0.0f);
        return nested_->eval(uv, f.to_local(wo), wi_p) * shadowing(f.n.z, wi.z);
    }
    float pdf(const TexturePoint& uv, const Vec3& wo, const Vec3& wi) const override {
        Frame f = frame(uv, wo);
        Vec3 wi_p = f.to_local(wi);
        if (!(wi.z * wi_p.z > 0)) return 0.0f;
        return nested_->pdf(uv, f.to_local(wo), wi_p);
    }
    bool sample(const TexturePoint& uv, const Vec3& wo, float u_lobe, const Vec2& u, BsdfSample* s) const override {
        Frame f = frame(uv, wo);
        if (!nested_->sample(uv, f.to_local(wo), u_lobe, u, s)) return false;
        Vec3 wi = f.to_world(s->wi);
        if (!(wi.z * s->wi.z > 0)) return false;
        s->wi = wi;
        s->weight = s->weight * shadowing(f.n.z, wi.z);
        return true;
    }
    bool is_delta() const override { return nested_->is_delta(); }
    std::string name() const override { return "normalmap"; }

private:
    /// The tilted frame at uv, in local shading coordinates, for the camera-side direction wo.
    Frame frame(const TexturePoint& uv, const Vec3& wo) const {
        Rgb c = normals_->eval(uv);
        Vec3 n(2.0f * c.r - 1.0f, 2.0f * c.g - 1.0f, 2.0f * c.b - 1.0f);
        float l2 = length_sq(n);
        // A map value of (0.5, 0.5, 0.5) has no direction (Mitsuba would produce NaN): keep the
        // untilted frame there.
        if (!(l2 > 1e-12f) || !std::isfinite(l2)) return Frame();
        n = n / std::sqrt(l2);
        if (dot(n, wo) * wo.z < 0) n = Vec3(-n.x, -n.y, n.z);
        return Frame::shading(n, Vec3(1, 0, 0));
    }
    /// Conty Estevez et al. 2019's shadowing of direction cosine cos_i for a normal tilted to
    /// cosine cos_d against the shading normal (see the file comment).
    float shadowing(float cos_d, float cos_i) const {
        if (!shadowing_) return 1.0f;
        float cd2 = cos_d * cos_d, ci2 = cos_i * cos_i;
        // tan^2 / 8 clamped to [0, 1] (Conty Estevez 2019): a normal at or below the horizon
        // (cos_d = 0) gets the largest roughness, 1
        float alpha2 = cd2 > 0 ? std::clamp(0.125f * (1.0f - cd2) / cd2, 0.0f, 1.0f) : 1.0f;
        if (alpha2 == 0.0f) return 1.0f;  // untilted: no shadowing (avoids 0 * inf at grazing)
        if (!(ci2 > 0)) return 0.0f;      // grazing light direction: fully shadowed
        float tan2_i = (1.0f - ci2) / ci2;
        return 2.0f / (1.0f + std::sqrt(1.0f + alpha2 * tan2_i));
    }

    std::shared_ptr<const Texture> normals_;
    std::shared_ptr<Bsdf> nested_;
    bool shadowing_;
};

}  // namespace

std::shared_ptr<Bsdf> make_normal_map(std::shared_ptr<const Texture> normals, std::shared_ptr<Bsdf> nested, bool shadowing) {
    return std::make_shared<NormalMap>(std::move(normals), std::move(nested), shadowing);
}

}  // namespace mf
