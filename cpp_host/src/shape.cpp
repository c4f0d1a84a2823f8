// mfhost — shapes (see shape.h).
#include "shape.h"

#include "embree_user_geometry.h"

namespace mf {

// ----------------------------------------------------------------------------------------------
// MeshShape

MeshShape::MeshShape(TriMesh mesh, std::string kind, bool winding_flipped)
    : mesh_(std::move(mesh)), kind_(std::move(kind)) {
    for (const Vec3& q : mesh_.p) bounds_.expand(q);
    cdf_.resize(mesh_.num_triangles());
    double acc = 0;
    for (size_t t = 0; t < mesh_.num_triangles(); ++t) {
        const Vec3& a = mesh_.p[mesh_.idx[3 * t]];
        const Vec3& b = mesh_.p[mesh_.idx[3 * t + 1]];
        const Vec3& c = mesh_.p[mesh_.idx[3 * t + 2]];
        acc += 0.5 * double(length(cross(b - a, c - a)));
        cdf_[t] = float(acc);
    }
    area_ = float(acc);

    // dp/du per triangle, Mitsuba 3's mesh rule (Mesh::compute_surface_interaction): from the
    // uv parameterization where it is non-degenerate, else the first axis of the coordinate
    // system of the face normal (taken before flip_normals).
    dpdu_.resize(mesh_.num_triangles());
    for (size_t t = 0; t < mesh_.num_triangles(); ++t) {
        uint32_t i0 = mesh_.idx[3 * t], i1 = mesh_.idx[3 * t + 1], i2 = mesh_.idx[3 * t + 2];
        Vec3 dp0 = mesh_.p[i1] - mesh_.p[i0], dp1 = mesh_.p[i2] - mesh_.p[i0];
        Vec3 ng = normalize(cross(dp0, dp1)) * (winding_flipped ? -1.0f : 1.0f);
        Vec3 d = Frame(ng).s;
        if (!mesh_.uv.empty()) {
            Vec2 duv0(mesh_.uv[i1].x - mesh_.uv[i0].x, mesh_.uv[i1].y - mesh_.uv[i0].y);
            Vec2 duv1(mesh_.uv[i2].x - mesh_.uv[i0].x, mesh_.uv[i2].y - mesh_.uv[i0].y);
            float det = duv0.x * duv1.y - duv0.y * duv1.x;
            if (det != 0) d = (dp0 * duv1.y - dp1 * duv0.y) / det;
        }
        dpdu_[t] = d;
    }
    uniform_dpdu_ = !dpdu_.empty();
    for (const Vec3& d : dpdu_)
        if (d.x != dpdu_[0].x || d.y != dpdu_[0].y || d.z != dpdu_[0].z) uniform_dpdu_ = false;
}

Vec3 MeshShape::dpdu(const Vec3& p, const Vec3& n, uint32_t prim) const {
    if (param_) {
        Vec2 uv;
        Vec3 d;
        param_(p, &uv, &d);
        return d;
    }
    if (prim < dpdu_.size()) return dpdu_[prim];
    if (uniform_dpdu_) return dpdu_[0];
    // Triangle unknown: Mitsuba's rule for meshes without uv, applied to the caller's normal.
    return Frame(n).s;
}

void MeshShape::sample_position(const Vec2& u, Vec3* p, Vec3* n) const {
    float target = u.x * area_;
    size_t t = size_t(std::upper_bound(cdf_.begin(), cdf_.end(), target) - cdf_.begin());
    if (t >= cdf_.size()) t = cdf_.size() - 1;
    float lo = t > 0 ? cdf_[t - 1] : 0.0f;
    float w = cdf_[t] - lo;
    float ux = w > 0 ? std::clamp((target - lo) / w, 0.0f, 1.0f) : 0.5f;
    float su = std::sqrt(ux);
    float b1 = 1.0f - su, b2 = u.y * su;
    const Vec3& a = mesh_.p[mesh_.idx[3 * t]];
    const Vec3& b = mesh_.p[mesh_.idx[3 * t + 1]];
    const Vec3& c = mesh_.p[mesh_.idx[3 * t + 2]];
    *p = a * (1.0f - b1 - b2) + b * b1 + c * b2;
    *n = normalize(cross(b - a, c - a));
}

unsigned MeshShape::attach(RTCDevice device, RTCScene scene) const {
    RTCGeometry g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
    float* vb = static_cast<float*>(
        rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), mesh_.p.size()));
    for (size_t i = 0; i < mesh_.p.size(); ++i) {
        vb[3 * i] = mesh_.p[i].x;
        vb[3 * i + 1] = mesh_.p[i].y;
        vb[3 * i + 2] = mesh_.p[i].z;
    }
    unsigned* ib = static_cast<unsigned*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                                                  3 * sizeof(unsigned), mesh_.num_triangles()));
    for (size_t i = 0; i < mesh_.idx.size(); ++i) ib[i] = mesh_.idx[i];
    rtcCommitGeometry(g);
    unsigned id = rtcAttachGeometry(scene, g);
    rtcReleaseGeometry(g);
    return id;
}

void MeshShape::fill_hit(const Ray& ray, float t, unsigned prim, float u, float v, SurfaceHit* hit) const {
    uint32_t i0 = mesh_.idx[3 * prim], i1 = mesh_.idx[3 * prim + 1], i2 = mesh_.idx[3 * prim + 2];
    const Vec3& a = mesh_.p[i0];
    const Vec3& b = mesh_.p[i1];
    const Vec3& c = mesh_.p[i2];
    hit->t = t;
    // Barycentric position is more accurate than o + t d for the spawn point.
    hit->p = a * (1.0f - u - v) + b * u + c * v;
    if (!all_finite(hit->p)) hit->p = ray.at(t);
    hit->ng = normalize(cross(b - a, c - a));
    if (!mesh_.n.empty()) {
        Vec3 ns = normalize(mesh_.n[i0] * (1.0f - u - v) + mesh_.n[i1] * u + mesh_.n[i2] * v);
        hit->ns = length_sq(ns) > 0 ? ns : hit->ng;
    } else {
        hit->ns = hit->ng;
    }
    if (param_) {
        param_(hit->p, &hit->uv, &hit->dpdu);
    } else {
        if (!mesh_.uv.empty()) {
            hit->uv = Vec2(mesh_.uv[i0].x * (1 - u - v) + mesh_.uv[i1].x * u + mesh_.uv[i2].x * v,
                           mesh_.uv[i0].y * (1 - u - v) + mesh_.uv[i1].y * u + mesh_.uv[i2].y * v);
        } else {
            hit->uv = Vec2(u, v);  // Mitsuba: the barycentrics
        }
        hit->dpdu = dpdu_[prim];
    }
    hit->shape = this;
    hit->prim = prim;
    hit->mesh = &mesh_;
    hit->bary = Vec2(u, v);
}

// ----------------------------------------------------------------------------------------------
// SphereShape (Embree user geometry)

Aabb SphereShape::bounds() const {
    Aabb b;
    b.expand(c_ - Vec3(r_));
    b.expand(c_ + Vec3(r_));
    return b;
}

void SphereShape::sample_position(const Vec2& u, Vec3* p, Vec3* n) const {
    float z = 1.0f - 2.0f * u.x;
    float r = safe_sqrt(1.0f - z * z), phi = 2.0f * kPi * u.y;
    Vec3 d(r * std::cos(phi), r * std::sin(phi), z);
    *p = c_ + d * r_;
    *n = flip_ ? -d : d;
}

bool SphereShape::chord(const Vec3& o, const Vec3& d, double radius, double* t0, double* t1) const {
    const auto [a, b, c, disc] = quadratic(o, d, c_, radius);
    if (!(disc >= 0)) return false;
    double sq = std::sqrt(disc);
    // numerically stable roots
    double q = b > 0 ? -(b + sq) : -(b - sq);
    *t0 = q / a;
    *t1 = q != 0 ? c / q : *t0;
    if (*t0 > *t1) std::swap(*t0, *t1);
    return true;
}

bool SphereShape::intersect(const Vec3& o, const Vec3& d, float tnear, float tfar, float* t) const {
    double t0, t1;
    if (!chord(o, d, r_, &t0, &t1)) return false;
    if (t0 > tnear && t0 < tfar) { *t = float(t0); return true; }
    if (t1 > tnear && t1 < tfar) { *t = float(t1); return true; }
    return false;
}

namespace {

bool sphere_hit(const SphereShape& s, const Vec3& o, const Vec3& d, float tnear, float tfar, UserGeometryHit* h) {
    if (!s.intersect(o, d, tnear, tfar, &h->t)) return false;
    h->ng = o + d * h->t - s.center();
    h->u = 0.0f;
    return true;
}

}  // namespace

unsigned SphereShape::attach(RTCDevice device, RTCScene scene) const {
    return UserGeometry<SphereShape, sphere_hit>::attach(device, scene, this);
}

Vec3 SphereShape::local_dir(const Vec3& p) const {
    Vec3 d = p - c_;
    // rot_ is orthonormal: its transpose maps world to object space
    Vec3 l(float(rot_.m[0][0] * d.x + rot_.m[1][0] * d.y + rot_.m[2][0] * d.z),
           float(rot_.m[0][1] * d.x + rot_.m[1][1] * d.y + rot_.m[2][1] * d.z),
           float(rot_.m[0][2] * d.x + rot_.m[1][2] * d.y + rot_.m[2][2] * d.z));
    return normalize(l);
}

Vec3 SphereShape::dpdu(const Vec3& p, const Vec3&, uint32_t) const {
    Vec3 l = local_dir(p);
    return rot_.vector(Vec3(-l.y, l.x, 0.0f)) * (2.0f * kPi * r_);
}

void SphereShape::fill_hit(const Ray& ray, float t, unsigned prim, float, float, SurfaceHit* hit) const {
    Vec3 p = ray.at(t);
    Vec3 n = normalize(p - c_);
    hit->t = t;
    hit->p = c_ + n * r_;  // re-project onto the surface
    hit->ng = flip_ ? -n : n;
    hit->ns = hit->ng;
    // Mitsuba's sphere: u = azimuth / 2 pi in [0, 1), v = polar angle / pi, in the object frame
    Vec3 l = local_dir(hit->p);
    float u = std::atan2(l.y, l.x) * (0.5f * kInvPi);
    if (u < 0) u += 1.0f;
    hit->uv = Vec2(u, std::acos(std::clamp(l.z, -1.0f, 1.0f)) * kInvPi);
    hit->dpdu = rot_.vector(Vec3(-l.y, l.x, 0.0f)) * (2.0f * kPi * r_);
    hit->shape = this;
    hit->prim = prim;
}

// ----------------------------------------------------------------------------------------------
// Canonical meshes

TriMesh make_cube_mesh() {
    TriMesh m;
    // Mitsuba 3's cube: per face, u = (a.p + 1) / 2 and v = (b.p + 1) / 2 (read off its uv and
    // dp/du; dp/du = 2a). a x b = -n, so the triangles run (0, 2, 1), (0, 3, 2) to face outwards.
    struct Face { Vec3 n, a, b; };
    const Face faces[6] = {{Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, -1)},  {Vec3(-1, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, 1)},
                           {Vec3(0, 1, 0), Vec3(-1, 0, 0), Vec3(0, 0, -1)}, {Vec3(0, -1, 0), Vec3(0, 0, 1), Vec3(1, 0, 0)},
                           {Vec3(0, 0, 1), Vec3(0, 1, 0), Vec3(1, 0, 0)},   {Vec3(0, 0, -1), Vec3(0, -1, 0), Vec3(1, 0, 0)}};
    for (const Face& f : faces) {
        uint32_t base = uint32_t(m.p.size());
        const float cu[4] = {-1, 1, 1, -1}, cv[4] = {-1, -1, 1, 1};
        for (int k = 0; k < 4; ++k) {
            m.p.push_back(f.n + f.a * cu[k] + f.b * cv[k]);
            m.n.push_back(f.n);
            m.uv.push_back(Vec2(0.5f * (cu[k] + 1), 0.5f * (cv[k] + 1)));
        }
        const uint32_t tri[6] = {0, 2, 1, 0, 3, 2};
        for (uint32_t k : tri) m.idx.push_back(base + k);
    }
    return m;
}

TriMesh make_rectangle_mesh() {
    TriMesh m;
    m.p = {Vec3(-1, -1, 0), Vec3(1, -1, 0), Vec3(1, 1, 0), Vec3(-1, 1, 0)};
    m.n = {Vec3(0, 0, 1), Vec3(0, 0, 1), Vec3(0, 0, 1), Vec3(0, 0, 1)};
    m.uv = {Vec2(0, 0), Vec2(1, 0), Vec2(1, 1), Vec2(0, 1)};
    m.idx = {0, 1, 2, 0, 2, 3};
    return m;
}

TriMesh make_disk_mesh(int segments) {
    TriMesh m;
    m.p.push_back(Vec3(0, 0, 0));
    m.n.push_back(Vec3(0, 0, 1));
    m.uv.push_back(Vec2(0.5f, 0.5f));
    for (int i = 0; i < segments; ++i) {
        double phi = 2.0 * 3.14159265358979323846 * i / segments;
        m.p.push_back(Vec3(float(std::cos(phi)), float(std::sin(phi)), 0));
        m.n.push_back(Vec3(0, 0, 1));
        m.uv.push_back(Vec2(float(0.5 + 0.5 * std::cos(phi)), float(0.5 + 0.5 * std::sin(phi))));
    }
    for (int i = 0; i < segments; ++i) {
        m.idx.push_back(0);
        m.idx.push_back(uint32_t(1 + i));
        m.idx.push_back(uint32_t(1 + (i + 1) % segments));
    }
    return m;
}

TriMesh make_cylinder_mesh(int segments) {
    TriMesh m;
    for (int i = 0; i < segments; ++i) {
        double phi = 2.0 * 3.14159265358979323846 * i / segments;
        float x = float(std::cos(phi)), y = float(std::sin(phi));
        for (float z : {0.0f, 1.0f}) {
            m.p.push_back(Vec3(x, y, z));
            m.n.push_back(Vec3(x, y, 0));  // the exact radial normal: shading is the true cylinder's
        }
    }
    for (int i = 0; i < segments; ++i) {
        uint32_t a = uint32_t(2 * i), b = uint32_t(2 * ((i + 1) % segments));
        // (x, y, 0) -> next phi -> top: counter-clockwise seen from outside, normal outwards
        m.idx.insert(m.idx.end(), {a, b, b + 1, a, b + 1, a + 1});
    }
    return m;
}

TriMesh make_sphere_mesh(int rings, int segments) {
    TriMesh m;
    m.p.push_back(Vec3(0, 0, 1));
    for (int r = 1; r < rings; ++r) {
        double th = 3.14159265358979323846 * r / rings;
        for (int s = 0; s < segments; ++s) {
            double ph = 2.0 * 3.14159265358979323846 * s / segments;
            m.p.push_back(Vec3(float(std::sin(th) * std::cos(ph)), float(std::sin(th) * std::sin(ph)), float(std::cos(th))));
        }
    }
    m.p.push_back(Vec3(0, 0, -1));
    uint32_t south = uint32_t(m.p.size() - 1);
    auto ring = [&](int r, int s) { return uint32_t(1 + (r - 1) * segments + ((s % segments + segments) % segments)); };
    for (int s = 0; s < segments; ++s) {
        m.idx.insert(m.idx.end(), {0u, ring(1, s), ring(1, s + 1)});
        m.idx.insert(m.idx.end(), {south, ring(rings - 1, s + 1), ring(rings - 1, s)});
    }
    for (int r = 1; r + 1 < rings; ++r)
        for (int s = 0; s < segments; ++s) {
            m.idx.insert(m.idx.end(), {ring(r, s), ring(r + 1, s), ring(r + 1, s + 1)});
            m.idx.insert(m.idx.end(), {ring(r, s), ring(r + 1, s + 1), ring(r, s + 1)});
        }
    return m;
}

}  // namespace mf
