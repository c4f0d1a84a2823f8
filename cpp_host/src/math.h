// mfhost — small linear-algebra and colour types used throughout the host renderer.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

namespace mf {

constexpr float kPi = 3.14159265358979323846f;
constexpr float kInvPi = 0.31830988618379067154f;
constexpr float kInv4Pi = 0.07957747154594766788f;
constexpr float kInf = std::numeric_limits<float>::infinity();

struct Vec2 {
    float x = 0, y = 0;
    Vec2() = default;
    Vec2(float x_, float y_) : x(x_), y(y_) {}
};

struct Vec3 {
    float x = 0, y = 0, z = 0;
    Vec3() = default;
    constexpr Vec3(float x_, float y_, float z_) : x(x_), y(y_), z(z_) {}
    explicit constexpr Vec3(float v) : x(v), y(v), z(v) {}
    float operator[](int i) const { return i == 0 ? x : (i == 1 ? y : z); }
    float& operator[](int i) { return i == 0 ? x : (i == 1 ? y : z); }
    Vec3 operator+(const Vec3& o) const { return {x + o.x, y + o.y, z + o.z}; }
    Vec3 operator-(const Vec3& o) const { return {x - o.x, y - o.y, z - o.z}; }
    Vec3 operator*(float s) const { return {x * s, y * s, z * s}; }
    Vec3 operator/(float s) const { return {x / s, y / s, z / s}; }
    Vec3 operator-() const { return {-x, -y, -z}; }
    Vec3& operator+=(const Vec3& o) { x += o.x; y += o.y; z += o.z; return *this; }
    Vec3& operator-=(const Vec3& o) { x -= o.x; y -= o.y; z -= o.z; return *this; }
    Vec3& operator*=(float s) { x *= s; y *= s; z *= s; return *this; }
};
inline Vec3 operator*(float s, const Vec3& v) { return v * s; }
inline float dot(const Vec3& a, const Vec3& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline Vec3 cross(const Vec3& a, const Vec3& b) {
    return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
inline float length_sq(const Vec3& v) { return dot(v, v); }
inline float length(const Vec3& v) { return std::sqrt(dot(v, v)); }
inline Vec3 normalize(const Vec3& v) {
    float l = length(v);
    return l > 0 ? v / l : v;
}
inline Vec3 vmin(const Vec3& a, const Vec3& b) { return {std::min(a.x, b.x), std::min(a.y, b.y), std::min(a.z, b.z)}; }
inline Vec3 vmax(const Vec3& a, const Vec3& b) { return {std::max(a.x, b.x), std::max(a.y, b.y), std::max(a.z, b.z)}; }
inline Vec3 vabs(const Vec3& a) { return {std::fabs(a.x), std::fabs(a.y), std::fabs(a.z)}; }
inline float max_comp(const Vec3& a) { return std::max(a.x, std::max(a.y, a.z)); }
inline bool all_finite(const Vec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

/// Linear RGB radiometric quantity.
struct Rgb {
    float r = 0, g = 0, b = 0;
    Rgb() = default;
    constexpr Rgb(float r_, float g_, float b_) : r(r_), g(g_), b(b_) {}
    explicit constexpr Rgb(float v) : r(v), g(v), b(v) {}
    float operator[](int i) const { return i == 0 ? r : (i == 1 ? g : b); }
    float& operator[](int i) { return i == 0 ? r : (i == 1 ? g : b); }
    Rgb operator+(const Rgb& o) const { return {r + o.r, g + o.g, b + o.b}; }
    Rgb operator-(const Rgb& o) const { return {r - o.r, g - o.g, b - o.b}; }
    Rgb operator*(const Rgb& o) const { return {r * o.r, g * o.g, b * o.b}; }
    Rgb operator/(const Rgb& o) const { return {r / o.r, g / o.g, b / o.b}; }
    Rgb operator*(float s) const { return {r * s, g * s, b * s}; }
    Rgb operator/(float s) const { return {r / s, g / s, b / s}; }
    Rgb& operator+=(const Rgb& o) { r += o.r; g += o.g; b += o.b; return *this; }
    Rgb& operator*=(const Rgb& o) { r *= o.r; g *= o.g; b *= o.b; return *this; }
    Rgb& operator*=(float s) { r *= s; g *= s; b *= s; return *this; }
    bool is_black() const { return r == 0 && g == 0 && b == 0; }
    float max() const { return std::max(r, std::max(g, b)); }
    float average() const { return (r + g + b) / 3.0f; }
    float luminance() const { return 0.212671f * r + 0.715160f * g + 0.072169f * b; }
    bool finite() const { return std::isfinite(r) && std::isfinite(g) && std::isfinite(b); }
};
inline Rgb operator*(float s, const Rgb& c) { return c * s; }
inline Rgb exp(const Rgb& c) { return {std::exp(c.r), std::exp(c.g), std::exp(c.b)}; }

/// Orthonormal frame; `n` is the local +z axis.
struct Frame {
    Vec3 s, t, n;
    Frame() : s(1, 0, 0), t(0, 1, 0), n(0, 0, 1) {}
    explicit Frame(const Vec3& normal) : n(normal) {
        // Duff et al. 2017, "Building an orthonormal basis, revisited".
        float sign = std::copysign(1.0f, n.z);
        float a = -1.0f / (sign + n.z);
        float b = n.x * n.y * a;
        s = Vec3(1.0f + sign * n.x * n.x * a, sign * b, -sign * n.x);
        t = Vec3(b, sign + n.y * n.y * a, -n.y);
    }
    Frame(const Vec3& s_, const Vec3& t_, const Vec3& n_) : s(s_), t(t_), n(n_) {}
    /// Mitsuba 3's shading frame (SurfaceInteraction::initialize_sh_frame): s = dp/du made
    /// orthogonal to the unit normal n by Gram-Schmidt, t = n x s; where dp/du vanishes or is
    /// parallel to n, the basis of Frame(n). Anisotropic roughness alpha_u runs along s.
    static Frame shading(const Vec3& n, const Vec3& dpdu) {
        Vec3 s = dpdu - n * dot(n, dpdu);
        float l2 = length_sq(s);
        if (!(l2 > 1e-20f * length_sq(dpdu)) || !std::isfinite(l2)) return Frame(n);
        s = s / std::sqrt(l2);
        return Frame(s, cross(n, s), n);
    }
    Vec3 to_local(const Vec3& v) const { return {dot(v, s), dot(v, t), dot(v, n)}; }
    Vec3 to_world(const Vec3& v) const { return s * v.x + t * v.y + n * v.z; }
};

struct Ray {
    Vec3 o, d;
    float tmin = 0.0f;
    float tmax = kInf;
    Ray() = default;
    Ray(const Vec3& o_, const Vec3& d_, float tmin_ = 0.0f, float tmax_ = kInf) : o(o_), d(d_), tmin(tmin_), tmax(tmax_) {}
    Vec3 at(float t) const { return o + d * t; }
};

struct Aabb {
    Vec3 lo{kInf, kInf, kInf};
    Vec3 hi{-kInf, -kInf, -kInf};
    void expand(const Vec3& p) { lo = vmin(lo, p); hi = vmax(hi, p); }
    void expand(const Aabb& b) { lo = vmin(lo, b.lo); hi = vmax(hi, b.hi); }
    bool valid() const { return lo.x <= hi.x && lo.y <= hi.y && lo.z <= hi.z; }
    Vec3 center() const { return (lo + hi) * 0.5f; }
    Vec3 extent() const { return hi - lo; }
    bool contains(const Vec3& p) const {
        return p.x >= lo.x && p.x <= hi.x && p.y >= lo.y && p.y <= hi.y && p.z >= lo.z && p.z <= hi.z;
    }
    /// Narrows [*t0, *t1] to where o + t d lies in the box (slab test; a NaN from a zero
    /// component of d on a slab's plane leaves it); false if that is empty.
    bool clip(const Vec3& o, const Vec3& d, float* t0, float* t1) const {
        for (int a = 0; a < 3; ++a) {
            const float inv = 1.0f / d[a];
            float ta = (lo[a] - o[a]) * inv, tb = (hi[a] - o[a]) * inv;
            if (ta > tb) std::swap(ta, tb);
            if (ta > *t0) *t0 = ta;
            if (tb < *t1) *t1 = tb;
        }
        return !(*t0 > *t1);
    }
    /// Squared distance from p to the box (0 inside).
    float dist_sq(const Vec3& p) const {
        Vec3 d = vmax(vmax(lo - p, p - hi), Vec3(0.0f));
        return length_sq(d);
    }
};

/// Row-major 4x4 affine/projective matrix in double precision (scene-description transforms).
struct Mat4 {
    double m[4][4];
    Mat4() { set_identity(); }
    void set_identity() {
        for (int i = 0; i < 4; ++i)
            for (int j = 0; j < 4; ++j) m[i][j] = (i == j) ? 1.0 : 0.0;
    }
    static Mat4 identity() { return Mat4(); }
    static Mat4 translate(double x, double y, double z) {
        Mat4 r; r.m[0][3] = x; r.m[1][3] = y; r.m[2][3] = z; return r;
    }
    static Mat4 scale(double x, double y, double z) {
        Mat4 r; r.m[0][0] = x; r.m[1][1] = y; r.m[2][2] = z; return r;
    }
    /// Right-handed rotation by `angle_deg` degrees about `axis` (normalised internally).
    static Mat4 rotate(double ax, double ay, double az, double angle_deg) {
        double l = std::sqrt(ax * ax + ay * ay + az * az);
        ax /= l; ay /= l; az /= l;
        double a = angle_deg * 3.14159265358979323846 / 180.0;
        double c = std::cos(a), s = std::sin(a), t = 1.0 - c;
        Mat4 r;
        r.m[0][0] = t * ax * ax + c;      r.m[0][1] = t * ax * ay - s * az; r.m[0][2] = t * ax * az + s * ay;
        r.m[1][0] = t * ax * ay + s * az; r.m[1][1] = t * ay * ay + c;      r.m[1][2] = t * ay * az - s * ax;
        r.m[2][0] = t * ax * az - s * ay; r.m[2][1] = t * ay * az + s * ax; r.m[2][2] = t * az * az + c;
        return r;
    }
    Mat4 operator*(const Mat4& o) const {
        Mat4 r;
        for (int i = 0; i < 4; ++i)
            for (int j = 0; j < 4; ++j) {
                double s = 0;
                for (int k = 0; k < 4; ++k) s += m[i][k] * o.m[k][j];
                r.m[i][j] = s;
            }
        return r;
    }
    Vec3 point(const Vec3& p) const {
        double x = m[0][0] * p.x + m[0][1] * p.y + m[0][2] * p.z + m[0][3];
        double y = m[1][0] * p.x + m[1][1] * p.y + m[1][2] * p.z + m[1][3];
        double z = m[2][0] * p.x + m[2][1] * p.y + m[2][2] * p.z + m[2][3];
        double w = m[3][0] * p.x + m[3][1] * p.y + m[3][2] * p.z + m[3][3];
        if (w != 1.0 && w != 0.0) { x /= w; y /= w; z /= w; }
        return {float(x), float(y), float(z)};
    }
    Vec3 vector(const Vec3& v) const {
        return {float(m[0][0] * v.x + m[0][1] * v.y + m[0][2] * v.z),
                float(m[1][0] * v.x + m[1][1] * v.y + m[1][2] * v.z),
                float(m[2][0] * v.x + m[2][1] * v.y + m[2][2] * v.z)};
    }
    /// Transform a normal with the inverse transpose of this (affine) matrix; not normalised.
    Vec3 normal(const Vec3& n) const {
        Mat4 inv = inverse();
        return {float(inv.m[0][0] * n.x + inv.m[1][0] * n.y + inv.m[2][0] * n.z),
                float(inv.m[0][1] * n.x + inv.m[1][1] * n.y + inv.m[2][1] * n.z),
                float(inv.m[0][2] * n.x + inv.m[1][2] * n.y + inv.m[2][2] * n.z)};
    }
    double det3() const {
        return m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
               m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
    }
    /// General 4x4 inverse (Gauss-Jordan with partial pivoting). Returns identity-filled NaNs if singular.
    Mat4 inverse() const {
        double a[4][8];
        for (int i = 0; i < 4; ++i)
            for (int j = 0; j < 4; ++j) { a[i][j] = m[i][j]; a[i][j + 4] = (i == j) ? 1.0 : 0.0; }
        for (int c = 0; c < 4; ++c) {
            int piv = c;
            for (int r = c + 1; r < 4; ++r)
                if (std::fabs(a[r][c]) > std::fabs(a[piv][c])) piv = r;
            if (a[piv][c] == 0.0) {
                Mat4 bad;
                for (auto& row : bad.m)
                    for (double& v : row) v = std::numeric_limits<double>::quiet_NaN();
                return bad;
            }
            if (piv != c)
                for (int j = 0; j < 8; ++j) std::swap(a[c][j], a[piv][j]);
            double inv = 1.0 / a[c][c];
            for (int j = 0; j < 8; ++j) a[c][j] *= inv;
            for (int r = 0; r < 4; ++r) {
                if (r == c) continue;
                double f = a[r][c];
                if (f != 0.0)
                    for (int j = 0; j < 8; ++j) a[r][j] -= f * a[c][j];
            }
        }
        Mat4 r;
        for (int i = 0; i < 4; ++i)
            for (int j = 0; j < 4; ++j) r.m[i][j] = a[i][j + 4];
        return r;
    }
    bool is_identity() const {
        for (int i = 0; i < 4; ++i)
            for (int j = 0; j < 4; ++j)
                if (m[i][j] != ((i == j) ? 1.0 : 0.0)) return false;
        return true;
    }
    bool finite() const {
        for (auto& row : m)
            for (double v : row)
                if (!std::isfinite(v)) return false;
        return true;
    }
    /// If the linear part is a uniform scale times a rotation (a similarity), return the scale, else -1.
    double similarity_scale(double tol = 1e-5) const {
        if (m[3][0] != 0 || m[3][1] != 0 || m[3][2] != 0 || m[3][3] != 1) return -1;
        double c[3];
        for (int j = 0; j < 3; ++j) c[j] = std::sqrt(m[0][j] * m[0][j] + m[1][j] * m[1][j] + m[2][j] * m[2][j]);
        double s = c[0];
        if (!(s > 0)) return -1;
        for (int j = 1; j < 3; ++j)
            if (std::fabs(c[j] - s) > tol * s) return -1;
        for (int i = 0; i < 3; ++i)
            for (int j = i + 1; j < 3; ++j) {
                double d = m[0][i] * m[0][j] + m[1][i] * m[1][j] + m[2][i] * m[2][j];
                if (std::fabs(d) > tol * s * s) return -1;
            }
        return s;
    }
    /// Mitsuba's look_at: columns are (left, up', dir, origin); the local frame looks down +z.
    static Mat4 look_at(const Vec3& origin, const Vec3& target, const Vec3& up);
};

inline Mat4 Mat4::look_at(const Vec3& origin, const Vec3& target, const Vec3& up) {
    double dx = double(target.x) - origin.x, dy = double(target.y) - origin.y, dz = double(target.z) - origin.z;
    double dl = std::sqrt(dx * dx + dy * dy + dz * dz);
    dx /= dl; dy /= dl; dz /= dl;
    // left = normalize(cross(up, dir))
    double lx = double(up.y) * dz - double(up.z) * dy, ly = double(up.z) * dx - double(up.x) * dz,
           lz = double(up.x) * dy - double(up.y) * dx;
    double ll = std::sqrt(lx * lx + ly * ly + lz * lz);
    lx /= ll; ly /= ll; lz /= ll;
    // new_up = cross(dir, left)
    double ux = dy * lz - dz * ly, uy = dz * lx - dx * lz, uz = dx * ly - dy * lx;
    Mat4 r;
    r.m[0][0] = lx; r.m[1][0] = ly; r.m[2][0] = lz;
    r.m[0][1] = ux; r.m[1][1] = uy; r.m[2][1] = uz;
    r.m[0][2] = dx; r.m[1][2] = dy; r.m[2][2] = dz;
    r.m[0][3] = origin.x; r.m[1][3] = origin.y; r.m[2][3] = origin.z;
    return r;
}

inline float safe_sqrt(float x) { return std::sqrt(std::max(0.0f, x)); }
inline float sqr(float x) { return x * x; }
inline float power_heuristic(float a, float b) {
    float a2 = a * a, b2 = b * b;
    if (!(a2 + b2 > 0)) return 0.0f;
    if (std::isinf(a2)) return 1.0f;
    return a2 / (a2 + b2);
}

}  // namespace mf
