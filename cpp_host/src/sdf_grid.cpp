// mfhost — sdfgrid shapes (see sdf_grid.h).
#include "sdf_grid.h"

#include <algorithm>
#include <cmath>

#include "error.h"

namespace mf {

namespace {

std::string node_str(long long i, long long j, long long k) {
    return "node (" + std::to_string(i) + ", " + std::to_string(j) + ", " + std::to_string(k) + ")";
}

// Samples of a distance function differ by at most their distance; numerically built SDFs
// (fast marching, VDB level sets) overshoot slightly: 1 % is accepted.
constexpr double kLipschitzTolerance = 1.01;

}  // namespace

Aabb SdfGrid::grid_bounds() const {
    Aabb b;
    for (int corner = 0; corner < 8; ++corner)
        b.expand(to_world.point(Vec3(float(corner & 1), float((corner >> 1) & 1), float((corner >> 2) & 1))));
    return b;
}

Aabb SdfGrid::region_bounds(double level) const {
    int lo[3] = {nx, ny, nz}, hi[3] = {-1, -1, -1};
    for (int k = 0; k + 1 < nz; ++k)
        for (int j = 0; j + 1 < ny; ++j)
            for (int i = 0; i + 1 < nx; ++i) {
                float m = at(i, j, k);
                for (int c = 1; c < 8; ++c) m = std::min(m, at(i + (c & 1), j + ((c >> 1) & 1), k + ((c >> 2) & 1)));
                if (!(m < level)) continue;
                const int cell[3] = {i, j, k};
                for (int a = 0; a < 3; ++a) {
                    lo[a] = std::min(lo[a], cell[a]);
                    hi[a] = std::max(hi[a], cell[a] + 1);
                }
            }
    Aabb b;
    if (hi[0] < 0) return b;
    const int n[3] = {nx, ny, nz};
    for (int corner = 0; corner < 8; ++corner) {
        Vec3 u;
        for (int a = 0; a < 3; ++a) u[a] = float(((corner >> a) & 1) ? hi[a] : lo[a]) / float(n[a] - 1);
        b.expand(to_world.point(u));
    }
    return b;
}

long long SdfGrid::boundary_node_below(double level) const {
    for (int k = 0; k < nz; ++k)
        for (int j = 0; j < ny; ++j)
            for (int i = 0; i < nx; ++i) {
                bool boundary = i == 0 || j == 0 || k == 0 || i == nx - 1 || j == ny - 1 || k == nz - 1;
                if (!boundary) {
                    i = nx - 2;  // skip the interior of this row
                    continue;
                }
                if (at(i, j, k) < level) return (long long)((size_t(k) * ny + j) * nx + i);
            }
    return -1;
}

SdfGrid load_sdf_grid(const SceneObject& o, const Mat4& to_world) {
    SdfGrid g;
    const std::string what = o.describe();
    const std::string name = o.get_string("filename");
    const std::string path = o.resolve_path(name);
    if (!is_regular_file(path))
        throw Error(o.loc_of("filename"), what + ": parameter \"filename\" refers to a missing file " + quote(path, 200));
    const bool vdb = is_vdb_path(path);
    if (o.has("grid") && !vdb)
        throw Error(o.loc_of("grid"), what + ": parameter \"grid\" names a grid of an OpenVDB (.vdb) file; " + quote(name, 200) +
                                          " is a Mitsuba .vol file");
    const std::string normals = o.get_string("normals", "smooth");
    if (normals != "smooth" && normals != "analytic")
        throw Error(o.loc_of("normals"), what + ": parameter \"normals\" must be smooth or analytic, got " + quote(normals));
    g.smooth_normals = normals == "smooth";
    const double scale = to_world.similarity_scale(1e-4);
    if (scale < 0)
        throw Error(o.loc_of("to_world"), what + ": to_world must be a similarity (rotation, uniform scale, translation) so that "
                                                 "the grid's values stay distances in world space");
    VolumeGridData data;
    try {
        data = vdb ? read_vdb_grid(path, o.get_string("grid", ""), GridCentering::Node) : read_vol_file(path);
    } catch (const Error& e) {
        throw Error(o.loc, what + ": " + e.what());
    }
    if (data.channels != 1)
        throw Error(o.loc, what + ": " + quote(path, 200) + " has " + std::to_string(data.channels) +
                               " channels; an SDF grid has 1 (signed distances)");
    if (data.nx < 2 || data.ny < 2 || data.nz < 2)
        throw Error(o.loc, what + ": " + quote(path, 200) + " has " + std::to_string(data.nx) + "x" + std::to_string(data.ny) + "x" +
                               std::to_string(data.nz) + " samples; an SDF grid needs at least 2 along each axis");
    g.nx = data.nx;
    g.ny = data.ny;
    g.nz = data.nz;
    g.to_world = data.has_grid_to_world ? to_world * data.grid_to_world : to_world;
    const int n[3] = {g.nx, g.ny, g.nz};
    double col[3][3];
    for (int a = 0; a < 3; ++a) {
        for (int r = 0; r < 3; ++r) col[a][r] = g.to_world.m[r][a];
        g.spacing[a] = std::sqrt(col[a][0] * col[a][0] + col[a][1] * col[a][1] + col[a][2] * col[a][2]) / double(n[a] - 1);
    }
    for (int a = 0; a < 3; ++a)
        for (int b = a + 1; b < 3; ++b) {
            double d = col[a][0] * col[b][0] + col[a][1] * col[b][1] + col[a][2] * col[b][2];
            double la = g.spacing[a] * (n[a] - 1), lb = g.spacing[b] * (n[b] - 1);
            if (std::fabs(d) > 1e-4 * la * lb)
                throw Error(o.loc, what + ": the grid's axes are not orthogonal in world space (a sheared " +
                                       std::string(vdb ? "OpenVDB transform" : "placement") + "): its cells must be boxes");
        }
    // Values in world units: the unit cube's units (.vol) or the VDB world's, times to_world's scale.
    g.values = std::move(data.values);
    g.value_min = kInf;
    g.value_max = -kInf;
    for (size_t idx = 0; idx < g.values.size(); ++idx) {
        float& v = g.values[idx];
        if (!std::isfinite(v)) {
            size_t i = idx % size_t(g.nx), j = (idx / size_t(g.nx)) % size_t(g.ny), k = idx / (size_t(g.nx) * size_t(g.ny));
            throw Error(o.loc, what + ": " + node_str(i, j, k) + " of " + quote(path, 200) + " is " + number_str(v) + ", not a distance");
        }
        v = float(double(v) * scale);
        g.value_min = std::min(g.value_min, v);
        g.value_max = std::max(g.value_max, v);
    }
    if (!(g.value_min < 0) || !(g.value_max > 0))
        throw Error(o.loc, what + ": the values of " + quote(path, 200) + " lie in [" + number_str(g.value_min) + ", " + number_str(g.value_max) +
                               "]: a surface needs negative values (inside) and positive values (outside)");
    // 1-Lipschitz along every edge, and the per-cell bound of the interpolant's gradient.
    double lipschitz = 0;
    for (int k = 0; k < g.nz; ++k)
        for (int j = 0; j < g.ny; ++j)
            for (int i = 0; i < g.nx; ++i) {
                const int idx[3] = {i, j, k};
                for (int a = 0; a < 3; ++a) {
                    if (idx[a] + 1 >= n[a]) continue;
                    int nb[3] = {i, j, k};
                    ++nb[a];
                    double slope = std::fabs(double(g.at(nb[0], nb[1], nb[2])) - double(g.at(i, j, k))) / g.spacing[a];
                    if (slope > kLipschitzTolerance)
                        throw Error(o.loc, what + ": the values of " + quote(path, 200) + " are not distances: between " +
                                               node_str(i, j, k) + " and " + node_str(nb[0], nb[1], nb[2]) + " they change by " +
                                               number_str(slope * g.spacing[a]) + " over a spacing of " + number_str(g.spacing[a]) +
                                               " (world units); a distance changes by at most the spacing");
                }
                if (i + 1 < g.nx && j + 1 < g.ny && k + 1 < g.nz) {
                    double sum = 0;
                    for (int a = 0; a < 3; ++a) {
                        double m = 0;
                        for (int e = 0; e < 4; ++e) {
                            int p0[3] = {i, j, k};
                            p0[(a + 1) % 3] += e & 1;
                            p0[(a + 2) % 3] += (e >> 1) & 1;
                            int p1[3] = {p0[0], p0[1], p0[2]};
                            ++p1[a];
                            m = std::max(m, std::fabs(double(g.at(p1[0], p1[1], p1[2])) - double(g.at(p0[0], p0[1], p0[2]))));
                        }
                        m /= g.spacing[a];
                        sum += m * m;
                    }
                    lipschitz = std::max(lipschitz, std::sqrt(sum));
                }
            }
    g.lipschitz = lipschitz;
    return g;
}

SdfGridShape::SdfGridShape(SdfGrid grid) : grid_(std::move(grid)) { solid_bounds_ = grid_.region_bounds(0.0); }

// The scene builder admits an sdfgrid only as a mean surface, which the region boundary replaces
// (mean_surface.h): these are never reached from a built scene.
void SdfGridShape::sample_position(const Vec2&, Vec3*, Vec3*) const {
    throw Error(loc, "<shape type=\"sdfgrid\">: has no area to sample (it is the mean surface of a medium)");
}
unsigned SdfGridShape::attach(RTCDevice, RTCScene) const {
    throw Error(loc, "<shape type=\"sdfgrid\">: is not traced itself (it is the mean surface of a medium)");
}
void SdfGridShape::fill_hit(const Ray&, float, unsigned, float, float, SurfaceHit*) const {
    throw Error(loc, "<shape type=\"sdfgrid\">: is not traced itself (it is the mean surface of a medium)");
}

}  // namespace mf
