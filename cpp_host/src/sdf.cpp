// mfhost — signed distance functions (see sdf.h).
#include "sdf.h"

#include <array>
#include <cstring>
#include <unordered_map>

namespace mf {

SdfSample sdf_sphere(const Vec3& p, const Vec3& center, float radius) {
    Vec3 d = p - center;
    float l = length(d);
    SdfSample s;
    s.f = l - radius;
    s.grad = l > 0 ? d / l : Vec3(0, 0, 1);
    return s;
}

SdfSample sdf_cube_local(const Vec3& p) {
    Vec3 q = vabs(p) - Vec3(1.0f);
    Vec3 sgn(std::copysign(1.0f, p.x), std::copysign(1.0f, p.y), std::copysign(1.0f, p.z));
    SdfSample s;
    Vec3 qo = vmax(q, Vec3(0.0f));
    float outside = length(qo);
    if (outside > 0) {
        s.f = outside;
        s.grad = Vec3(qo.x * sgn.x, qo.y * sgn.y, qo.z * sgn.z) / outside;
    } else {
        int axis = (q.x >= q.y && q.x >= q.z) ? 0 : (q.y >= q.z ? 1 : 2);
        s.f = q[axis];
        s.grad = Vec3(0.0f);
        s.grad[axis] = sgn[axis];
    }
    return s;
}

static SdfSample planar_from_closest(const Vec3& p, const Vec3& c) {
    Vec3 d = p - c;
    float l = length(d);
    SdfSample s;
    float sign = p.z >= 0 ? 1.0f : -1.0f;
    s.f = sign * l;
    s.grad = l > 0 ? d * (sign / l) : Vec3(0, 0, 1);
    return s;
}

SdfSample sdf_rectangle_local(const Vec3& p) {
    Vec3 c(std::clamp(p.x, -1.0f, 1.0f), std::clamp(p.y, -1.0f, 1.0f), 0.0f);
    return planar_from_closest(p, c);
}

SdfSample sdf_disk_local(const Vec3& p) {
    float r = std::sqrt(p.x * p.x + p.y * p.y);
    Vec3 c = r > 1.0f ? Vec3(p.x / r, p.y / r, 0.0f) : Vec3(p.x, p.y, 0.0f);
    return planar_from_closest(p, c);
}

// ----------------------------------------------------------------------------------------------
// MeshSdf

namespace {

struct PosHash {
    size_t operator()(const Vec3& v) const {
        uint32_t a, b, c;
        std::memcpy(&a, &v.x, 4);
        std::memcpy(&b, &v.y, 4);
        std::memcpy(&c, &v.z, 4);
        return size_t(a) * 73856093u ^ size_t(b) * 19349663u ^ size_t(c) * 83492791u;
    }
};
struct PosEq {
    bool operator()(const Vec3& a, const Vec3& b) const { return a.x == b.x && a.y == b.y && a.z == b.z; }
};

/// Closest point on segment [a,b]; *where = 0 (at a), 1 (at b) or 2 (interior).
Vec3 closest_on_segment(const Vec3& p, const Vec3& a, const Vec3& b, int* where) {
    Vec3 ab = b - a;
    float l2 = length_sq(ab);
    float t = l2 > 0 ? dot(p - a, ab) / l2 : 0.0f;
    if (t <= 0) { *where = 0; return a; }
    if (t >= 1) { *where = 1; return b; }
    *where = 2;
    return a + ab * t;
}

}  // namespace

MeshSdf::MeshSdf(const std::vector<Vec3>& positions, const std::vector<uint32_t>& indices) {
    // Weld vertices by exact position.
    std::unordered_map<Vec3, uint32_t, PosHash, PosEq> weld;
    std::vector<uint32_t> remap(positions.size());
    for (size_t i = 0; i < positions.size(); ++i) {
        auto it = weld.find(positions[i]);
        if (it == weld.end()) {
            uint32_t id = uint32_t(pos_.size());
            weld.emplace(positions[i], id);
            pos_.push_back(positions[i]);
            remap[i] = id;
        } else {
            remap[i] = it->second;
        }
    }
    Aabb all;
    for (const Vec3& q : pos_) all.expand(q);
    scale_ = all.valid() ? std::max(1e-12f, max_comp(all.extent())) : 1.0f;

    // Face normals in double precision; degenerate if the area is negligible against the edges.
    size_t nt = indices.size() / 3;
    tri_.resize(nt);
    vn_.assign(pos_.size(), Vec3(0.0f));
    std::vector<double> vacc(pos_.size() * 3, 0.0);
    std::unordered_map<uint64_t, std::array<double, 3>> edge_acc;
    auto edge_key = [](uint32_t a, uint32_t b) {
        if (a > b) std::swap(a, b);
        return (uint64_t(a) << 32) | b;
    };
    for (size_t t = 0; t < nt; ++t) {
        Tri& tr = tri_[t];
        for (int k = 0; k < 3; ++k) tr.v[k] = remap[indices[3 * t + k]];
        double P[3][3];
        for (int k = 0; k < 3; ++k) {
            const Vec3& q = pos_[tr.v[k]];
            P[k][0] = q.x; P[k][1] = q.y; P[k][2] = q.z;
        }
        double e1[3], e2[3], c[3];
        for (int j = 0; j < 3; ++j) { e1[j] = P[1][j] - P[0][j]; e2[j] = P[2][j] - P[0][j]; }
        c[0] = e1[1] * e2[2] - e1[2] * e2[1];
        c[1] = e1[2] * e2[0] - e1[0] * e2[2];
        c[2] = e1[0] * e2[1] - e1[1] * e2[0];
        double cl = std::sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
        double maxe2 = 0;
        for (int k = 0; k < 3; ++k) {
            double s = 0;
            for (int j = 0; j < 3; ++j) { double d = P[(k + 1) % 3][j] - P[k][j]; s += d * d; }
            maxe2 = std::max(maxe2, s);
        }
        tr.degenerate = !(cl > 1e-10 * maxe2) || tr.v[0] == tr.v[1] || tr.v[1] == tr.v[2] || tr.v[0] == tr.v[2];
        double n[3] = {0, 0, 0};
        if (!tr.degenerate)
            for (int j = 0; j < 3; ++j) n[j] = c[j] / cl;
        tr.fn = Vec3(float(n[0]), float(n[1]), float(n[2]));
        if (tr.degenerate) continue;
        for (int k = 0; k < 3; ++k) {
            double a[3], b[3], la = 0, lb = 0, d = 0;
            for (int j = 0; j < 3; ++j) {
                a[j] = P[(k + 1) % 3][j] - P[k][j];
                b[j] = P[(k + 2) % 3][j] - P[k][j];
                la += a[j] * a[j];
                lb += b[j] * b[j];
                d += a[j] * b[j];
            }
            double cosang = d / std::sqrt(la * lb);
            double ang = std::acos(std::max(-1.0, std::min(1.0, cosang)));
            for (int j = 0; j < 3; ++j) vacc[3 * tr.v[k] + j] += ang * n[j];
            auto& e = edge_acc[edge_key(tr.v[k], tr.v[(k + 1) % 3])];
            for (int j = 0; j < 3; ++j) e[j] += n[j];
        }
    }
    for (size_t i = 0; i < pos_.size(); ++i) {
        double l = std::sqrt(vacc[3 * i] * vacc[3 * i] + vacc[3 * i + 1] * vacc[3 * i + 1] + vacc[3 * i + 2] * vacc[3 * i + 2]);
        vn_[i] = l > 0 ? Vec3(float(vacc[3 * i] / l), float(vacc[3 * i + 1] / l), float(vacc[3 * i + 2] / l)) : Vec3(0.0f);
    }
    for (Tri& tr : tri_) {
        for (int k = 0; k < 3; ++k) {
            auto it = edge_acc.find(edge_key(tr.v[k], tr.v[(k + 1) % 3]));
            Vec3 e(0.0f);
            if (it != edge_acc.end()) {
                const auto& a = it->second;
                double l = std::sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
                if (l > 0) e = Vec3(float(a[0] / l), float(a[1] / l), float(a[2] / l));
            }
            tr.en[k] = e;
        }
    }
    for (Tri& tr : tri_) {
        Vec3 c = (pos_[tr.v[0]] + pos_[tr.v[1]] + pos_[tr.v[2]]) / 3.0f;
        float r = 0;
        for (int k = 0; k < 3; ++k) r = std::max(r, length(pos_[tr.v[k]] - c));
        tr.bc = c;
        tr.br = r * 1.0001f + 1e-7f * scale_;
    }
    // BVH over triangles.
    std::vector<Vec3> centroids(nt);
    for (size_t t = 0; t < nt; ++t)
        centroids[t] = (pos_[tri_[t].v[0]] + pos_[tri_[t].v[1]] + pos_[tri_[t].v[2]]) / 3.0f;
    nodes_.reserve(nt > 0 ? 2 * nt : 1);
    if (nt > 0) {
        nodes_.push_back(Node());
        build(0, 0, uint32_t(nt), centroids);
    }
}

void MeshSdf::build(uint32_t node, uint32_t first, uint32_t count, std::vector<Vec3>& centroids) {
    Aabb box, cbox;
    for (uint32_t i = first; i < first + count; ++i) {
        for (int k = 0; k < 3; ++k) box.expand(pos_[tri_[i].v[k]]);
        cbox.expand(centroids[i]);
    }
    nodes_[node].box = box;
    if (count <= 4) {
        nodes_[node].left_or_first = first;
        nodes_[node].count = count;
        return;
    }
    Vec3 ext = cbox.extent();
    int axis = (ext.x >= ext.y && ext.x >= ext.z) ? 0 : (ext.y >= ext.z ? 1 : 2);
    uint32_t half = count / 2;
    // Median split: reorder triangles and centroids of this range together.
    std::vector<uint32_t> order(count);
    for (uint32_t i = 0; i < count; ++i) order[i] = first + i;
    std::nth_element(order.begin(), order.begin() + half, order.end(),
                     [&](uint32_t a, uint32_t b) { return centroids[a][axis] < centroids[b][axis]; });
    std::vector<Tri> tris(count);
    std::vector<Vec3> cents(count);
    for (uint32_t i = 0; i < count; ++i) {
        tris[i] = tri_[order[i]];
        cents[i] = centroids[order[i]];
    }
    std::copy(tris.begin(), tris.end(), tri_.begin() + first);
    std::copy(cents.begin(), cents.end(), centroids.begin() + first);
    uint32_t left = uint32_t(nodes_.size());
    nodes_.push_back(Node());
    nodes_.push_back(Node());
    nodes_[node].left_or_first = left;
    nodes_[node].count = 0;
    build(left, first, half, centroids);
    build(left + 1, first + half, count - half, centroids);
}

float MeshSdf::closest_in_tri(const Tri& t, const Vec3& p, Vec3* c, Vec3* pn) const {
    const Vec3& a = pos_[t.v[0]];
    const Vec3& b = pos_[t.v[1]];
    const Vec3& cc = pos_[t.v[2]];
    auto vertex = [&](int k) {
        *c = pos_[t.v[k]];
        *pn = vn_[t.v[k]];
    };
    auto edge = [&](int k, float s) {  // edge k from v[k] to v[k+1], parameter s
        *c = pos_[t.v[k]] + (pos_[t.v[(k + 1) % 3]] - pos_[t.v[k]]) * s;
        *pn = t.en[k];
    };
    if (t.degenerate) {
        // Closest over the three edges (a degenerate triangle is a segment or a point).
        float best = kInf;
        Vec3 bc, bn;
        for (int k = 0; k < 3; ++k) {
            int where;
            Vec3 q = closest_on_segment(p, pos_[t.v[k]], pos_[t.v[(k + 1) % 3]], &where);
            float d = length_sq(p - q);
            if (d < best) {
                best = d;
                bc = q;
                bn = where == 0 ? vn_[t.v[k]] : (where == 1 ? vn_[t.v[(k + 1) % 3]] : t.en[k]);
            }
        }
        *c = bc;
        *pn = bn;
        return best;
    }
    // Ericson, Real-Time Collision Detection, 5.1.5 — with the Voronoi region recorded.
    Vec3 ab = b - a, ac = cc - a, ap = p - a;
    float d1 = dot(ab, ap), d2 = dot(ac, ap);
    if (d1 <= 0 && d2 <= 0) { vertex(0); return length_sq(p - *c); }
    Vec3 bp = p - b;
    float d3 = dot(ab, bp), d4 = dot(ac, bp);
    if (d3 >= 0 && d4 <= d3) { vertex(1); return length_sq(p - *c); }
    float vc = d1 * d4 - d3 * d2;
    if (vc <= 0 && d1 >= 0 && d3 <= 0) { edge(0, d1 / (d1 - d3)); return length_sq(p - *c); }
    Vec3 cp = p - cc;
    float d5 = dot(ab, cp), d6 = dot(ac, cp);
    if (d6 >= 0 && d5 <= d6) { vertex(2); return length_sq(p - *c); }
    float vb = d5 * d2 - d1 * d6;
    if (vb <= 0 && d2 >= 0 && d6 <= 0) {
        // edge a–c is edge 2 (v2 -> v0): parameter from v2
        float w = d2 / (d2 - d6);  // from a towards c
        edge(2, 1.0f - w);
        return length_sq(p - *c);
    }
    float va = d3 * d6 - d5 * d4;
    if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
        edge(1, (d4 - d3) / ((d4 - d3) + (d5 - d6)));
        return length_sq(p - *c);
    }
    float denom = 1.0f / (va + vb + vc);
    float v = vb * denom, w = vc * denom;
    *c = a + ab * v + ac * w;
    *pn = t.fn;
    return length_sq(p - *c);
}

float MeshSdf::closest(const Vec3& p, Vec3* closest_point, Vec3* pseudo_normal, Vec3* smooth_normal) const {
    float best = kInf;
    Vec3 bc, bn(0, 0, 1);
    uint32_t best_tri = 0;
    if (nodes_.empty()) {
        *closest_point = p;
        *pseudo_normal = bn;
        if (smooth_normal) *smooth_normal = bn;
        return kInf;
    }
    // Coherence hint: consecutive queries of a thread (sphere tracing, tracking along a ray)
    // usually have the same or a nearby closest triangle; its distance is an upper bound that
    // prunes most of the traversal. Purely an accelerator: the result is the same.
    struct Hint {
        const MeshSdf* owner = nullptr;
        uint32_t tri = 0;
    };
    thread_local Hint hint;
    if (hint.owner == this && hint.tri < tri_.size()) {
        Vec3 c, pn;
        best = closest_in_tri(tri_[hint.tri], p, &c, &pn);
        bc = c;
        bn = pn;
        best_tri = hint.tri;
    }
    uint32_t stack[128];
    int sp = 0;
    stack[sp++] = 0;
    while (sp > 0) {
        const Node& n = nodes_[stack[--sp]];
        // Prune with a relative margin so that the result is the global argmin of (distance,
        // triangle index) whatever the starting bound: the answer must not depend on the hint
        // (bit-identical images whatever the thread count), even at rounding-level ties.
        const float prune = best * 1.0001f;
        if (n.box.dist_sq(p) > prune) continue;
        if (n.count > 0) {
            for (uint32_t i = n.left_or_first; i < n.left_or_first + n.count; ++i) {
                // bounding-sphere rejection (distance to the sphere is a lower bound)
                float ds = length(p - tri_[i].bc) - tri_[i].br;
                if (ds > 0 && ds * ds > prune) continue;
                Vec3 c, pn;
                float d = closest_in_tri(tri_[i], p, &c, &pn);
                if (d < best || (d == best && i < best_tri)) {
                    best = d;
                    bc = c;
                    bn = pn;
                    best_tri = i;
                }
            }
        } else {
            uint32_t l = n.left_or_first, r = l + 1;
            float dl = nodes_[l].box.dist_sq(p), dr = nodes_[r].box.dist_sq(p);
            // push the farther child first so the nearer one is visited first
            if (dl < dr) std::swap(l, r), std::swap(dl, dr);
            if (dl <= prune && sp < 127) stack[sp++] = l;
            if (dr <= prune && sp < 127) stack[sp++] = r;
        }
    }
    hint.owner = this;
    hint.tri = best_tri;
    *closest_point = bc;
    *pseudo_normal = bn;
    if (smooth_normal) {
        const Tri& t = tri_[best_tri];
        Vec3 sn = bn;
        if (!t.degenerate) {
            // barycentrics of the closest point (it lies on the triangle), clamped for rounding
            const Vec3& a = pos_[t.v[0]];
            Vec3 e1 = pos_[t.v[1]] - a, e2 = pos_[t.v[2]] - a, q = bc - a;
            float d11 = dot(e1, e1), d12 = dot(e1, e2), d22 = dot(e2, e2), q1 = dot(q, e1), q2 = dot(q, e2);
            float den = d11 * d22 - d12 * d12;
            if (den > 0) {
                float v = std::clamp((d22 * q1 - d12 * q2) / den, 0.0f, 1.0f);
                float w = std::clamp((d11 * q2 - d12 * q1) / den, 0.0f, 1.0f);
                float u = std::max(0.0f, 1.0f - v - w);
                Vec3 m = vn_[t.v[0]] * u + vn_[t.v[1]] * v + vn_[t.v[2]] * w;
                if (length_sq(m) > 1e-12f) sn = normalize(m);
            }
        }
        *smooth_normal = sn;
    }
    return std::sqrt(best);
}

SdfSample MeshSdf::eval(const Vec3& p) const { return eval(p, nullptr); }

SdfSample MeshSdf::eval(const Vec3& p, Vec3* smooth_normal) const {
    Vec3 c, pn;
    float d = closest(p, &c, &pn, smooth_normal);
    SdfSample s;
    if (!std::isfinite(d)) return s;
    Vec3 diff = p - c;
    float sign = dot(diff, pn) >= 0 ? 1.0f : -1.0f;
    s.f = sign * d;
    if (d > 1e-7f * scale_) s.grad = diff * (sign / d);
    else s.grad = length_sq(pn) > 0 ? normalize(pn) : Vec3(0, 0, 1);
    return s;
}

}  // namespace mf
