// mfhost — emitters: area, point, spot, projector, directional, constant, envmap.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "math.h"
#include "shape.h"
#include "texture.h"

namespace mf {

struct EmitterSample {
    Vec3 wi;           // unit direction from the reference point towards the emitter
    float dist = kInf; // distance to the sampled point (inf for infinite/directional emitters)
    Rgb Li;            // incident radiance (or intensity/d^2, irradiance for delta emitters)
    float pdf = 0;     // solid-angle pdf (1 for delta emitters)
    bool delta = false;
};

/// 2D piecewise-constant distribution on [0,1]^2 (rows = v, columns = u).
class Distribution2D {
public:
    Distribution2D() = default;
    Distribution2D(const std::vector<float>& f, int nu, int nv);
    /// Returns (u, v) and the density with respect to the unit square.
    Vec2 sample(const Vec2& u, float* pdf) const;
    float pdf(const Vec2& uv) const;

private:
    int nu_ = 0, nv_ = 0;
    std::vector<float> cond_cdf_;   // nv rows of nu+1
    std::vector<float> row_int_;    // integral of each row
    std::vector<float> marg_cdf_;   // nv+1
    std::vector<float> f_;
    float total_ = 0;
};

class Emitter {
public:
    virtual ~Emitter() = default;
    /// Sample a direction towards the emitter from `ref`. Returns false if nothing to sample.
    virtual bool sample_li(const Vec3& ref, const Vec2& u, EmitterSample* s) const = 0;
    virtual bool is_delta() const { return false; }
    virtual bool is_infinite() const { return false; }
    /// Infinite emitters: radiance arriving from direction -d (i.e. seen looking along d).
    virtual Rgb eval_direction(const Vec3& d) const { (void)d; return Rgb(0.0f); }
    virtual float pdf_direction(const Vec3& d) const { (void)d; return 0.0f; }
    /// Area emitters: radiance leaving `hit` towards `wo`, and the pdf of sampling that point from ref.
    virtual Rgb eval_surface(const SurfaceHit& hit, const Vec3& wo) const { (void)hit; (void)wo; return Rgb(0.0f); }
    virtual float pdf_surface(const Vec3& ref, const SurfaceHit& hit) const { (void)ref; (void)hit; return 0.0f; }
    virtual std::string name() const = 0;
};

class AreaEmitter final : public Emitter {
public:
    AreaEmitter(const Shape* shape, const Rgb& radiance) : shape_(shape), L_(radiance) {}
    bool sample_li(const Vec3& ref, const Vec2& u, EmitterSample* s) const override;
    Rgb eval_surface(const SurfaceHit& hit, const Vec3& wo) const override {
        return dot(hit.ng, wo) > 0 ? L_ : Rgb(0.0f);
    }
    float pdf_surface(const Vec3& ref, const SurfaceHit& hit) const override;
    std::string name() const override { return "area"; }

private:
    const Shape* shape_;
    Rgb L_;
};

class PointEmitter final : public Emitter {
public:
    PointEmitter(const Vec3& p, const Rgb& intensity) : p_(p), I_(intensity) {}
    bool sample_li(const Vec3& ref, const Vec2& u, EmitterSample* s) const override;
    bool is_delta() const override { return true; }
    std::string name() const override { return "point"; }

private:
    Vec3 p_;
    Rgb I_;
};

/// Mitsuba 3's `spot`: a point light at to_world's origin shining along its local +z, with
/// intensity I (W/sr) inside beam_width, ramping linearly in angle to 0 at cutoff_angle, and an
/// optional texture projected over the cone (uv = 1/2 + (x, y) / (2 z tan(cutoff_angle))).
class SpotEmitter final : public Emitter {
public:
    /// Angles in radians; `texture` may be null (no projected texture).
    SpotEmitter(const Mat4& to_world, const Rgb& intensity, float cutoff_angle, float beam_width,
                std::shared_ptr<const Texture> texture);
    bool sample_li(const Vec3& ref, const Vec2& u, EmitterSample* s) const override;
    bool is_delta() const override { return true; }
    std::string name() const override { return "spot"; }
    /// The falloff factor in [0, 1] for a local direction (not necessarily unit).
    float falloff(const Vec3& local_d) const;

private:
    Mat4 to_world_, to_local_;
    Vec3 p_;
    Rgb I_;
    float cutoff_, cos_cutoff_, cos_beam_, inv_transition_, uv_factor_;
    std::shared_ptr<const Texture> texture_;
};

/// Mitsuba 3's `projector`: the reciprocal of a perspective sensor at to_world's origin looking
/// along local +z; `irradiance` is the irradiance on its image plane at z = 1 (uv as Mitsuba's
/// camera: u = 1/2 - x / (2 z tan_x), v = 1/2 - y / (2 z tan_y)), times `scale`. A point at local
/// depth z in direction cos θ from the axis receives pi E(uv) scale / (z² cos θ) -- Mitsuba's
/// inverse-importance factor, so that a plane facing the projector at z = 1 gets E.
class ProjectorEmitter final : public Emitter {
public:
    ProjectorEmitter(const Mat4& to_world, const Vec2& tan_half, std::shared_ptr<const Texture> irradiance, float scale);
    bool sample_li(const Vec3& ref, const Vec2& u, EmitterSample* s) const override;
    bool is_delta() const override { return true; }
    std::string name() const override { return "projector"; }

private:
    Mat4 to_world_, to_local_;
    Vec3 p_, axis_;  // axis_: to_world applied to local +z (not normalised, as Mitsuba's ds.n)
    Vec2 tan_half_;
    std::shared_ptr<const Texture> irradiance_;
    float scale_;
};

class DirectionalEmitter final : public Emitter {
public:
    DirectionalEmitter(const Vec3& direction, const Rgb& irradiance) : d_(normalize(direction)), E_(irradiance) {}
    bool sample_li(const Vec3& ref, const Vec2& u, EmitterSample* s) const override;
    bool is_delta() const override { return true; }
    bool is_infinite() const override { return false; }
    std::string name() const override { return "directional"; }

private:
    Vec3 d_;
    Rgb E_;
};

class ConstantEmitter final : public Emitter {
public:
    explicit ConstantEmitter(const Rgb& radiance) : L_(radiance) {}
    bool sample_li(const Vec3& ref, const Vec2& u, EmitterSample* s) const override;
    bool is_infinite() const override { return true; }
    Rgb eval_direction(const Vec3&) const override { return L_; }
    float pdf_direction(const Vec3&) const override { return kInv4Pi; }
    std::string name() const override { return "constant"; }

private:
    Rgb L_;
};

/// Lat-long environment map with Mitsuba 3's parameterisation (local +y up; u = atan2(x, -z)/2π,
/// v = acos(y)/π), importance-sampled by luminance × sin(theta) with a 2D piecewise-constant
/// distribution. Lookups are nearest-texel (piecewise constant), matching the sampling density
/// exactly (Mitsuba interpolates bilinearly).
class EnvmapEmitter final : public Emitter {
public:
    EnvmapEmitter(std::vector<float> rgb, int width, int height, float scale, const Mat4& to_world);
    bool sample_li(const Vec3& ref, const Vec2& u, EmitterSample* s) const override;
    bool is_infinite() const override { return true; }
    Rgb eval_direction(const Vec3& d) const override;
    float pdf_direction(const Vec3& d) const override;
    std::string name() const override { return "envmap"; }

private:
    Vec2 dir_to_uv(const Vec3& world_d, float* sin_theta) const;
    Rgb texel(const Vec2& uv) const;
    std::vector<float> rgb_;
    int w_, h_;
    float scale_;
    Mat4 to_world_, to_local_;
    Distribution2D dist_;
};

}  // namespace mf
