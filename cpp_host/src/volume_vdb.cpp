// mfhost — grids of OpenVDB files (Debian's libopenvdb-dev), made dense (see volume_io.h). The
// OpenVDB headers are confined to this file, which is built as its own module (libmfhost_vdb.so)
// that read_vdb_grid (volume_io.cpp) loads on first use: libopenvdb and its dependencies carry
// ~70,000 symbol relocations, which cost every run of mfrender ~50 ms at start-up when linked.
#include <openvdb/io/File.h>
#include <openvdb/openvdb.h>

#include <mutex>

#include "error.h"
#include "volume_io.h"

namespace mf {

namespace {

template <typename GridT, int C>
void densify(const GridT& grid, const openvdb::CoordBBox& box, VolumeGridData* out) {
    auto acc = grid.getConstAccessor();
    out->values.resize(size_t(out->nx) * out->ny * out->nz * C);
    size_t n = 0;
    for (int k = box.min().z(); k <= box.max().z(); ++k)
        for (int j = box.min().y(); j <= box.max().y(); ++j)
            for (int i = box.min().x(); i <= box.max().x(); ++i) {
                const auto v = acc.getValue(openvdb::Coord(i, j, k));
                if constexpr (C == 1) {
                    out->values[n++] = float(v);
                } else {
                    for (int c = 0; c < C; ++c) out->values[n++] = float(v[c]);
                }
            }
}

VolumeGridData read_grid(const std::string& path, const std::string& grid_name, GridCentering centering) {
    const std::string what = "OpenVDB file " + quote(path, 200);
    static std::once_flag init;
    std::call_once(init, [] { openvdb::initialize(); });
    try {
        openvdb::io::File file(path);
        file.open(/*delayLoad=*/false);
        std::vector<std::string> names;
        for (auto it = file.beginName(); it != file.endName(); ++it) names.push_back(it.gridName());
        std::string list;
        for (const std::string& n : names) list += (list.empty() ? "" : ", ") + quote(n);
        std::string name = grid_name;
        if (name.empty()) {
            if (names.size() != 1)
                throw Error(what + " has " + std::to_string(names.size()) + " grids (" + (list.empty() ? "none" : list) +
                            "): choose one with the string parameter \"grid\"");
            name = names[0];
        } else if (!file.hasGrid(name)) {
            throw Error(what + " has no grid named " + quote(name) + " (its grids: " + (list.empty() ? "none" : list) + ")");
        }
        openvdb::GridBase::Ptr base = file.readGrid(name);
        file.close();

        const openvdb::math::Transform& xf = base->transform();
        if (!xf.isLinear())
            throw Error(what + ": grid " + quote(name) + " has a non-linear (frustum) transform, which mfrender does not support");
        openvdb::CoordBBox box = base->evalActiveVoxelBoundingBox();
        if (box.empty()) throw Error(what + ": grid " + quote(name) + " has no active voxels");
        // Cell-centred volumes get one voxel of background around the active box, so that the
        // interpolant falls off to the background as OpenVDB's own samplers do.
        if (centering == GridCentering::Cell) box.expand(1);
        VolumeGridData g;
        const openvdb::Coord dim = box.dim();
        g.nx = dim.x();
        g.ny = dim.y();
        g.nz = dim.z();
        if (centering == GridCentering::Node && (g.nx < 2 || g.ny < 2 || g.nz < 2))
            throw Error(what + ": grid " + quote(name) + " spans " + std::to_string(g.nx) + "x" + std::to_string(g.ny) + "x" +
                        std::to_string(g.nz) + " voxels; an SDF grid needs at least 2 along each axis");
        if (base->isType<openvdb::FloatGrid>() || base->isType<openvdb::DoubleGrid>()) g.channels = 1;
        else if (base->isType<openvdb::Vec3SGrid>() || base->isType<openvdb::Vec3DGrid>()) g.channels = 3;
        else
            throw Error(what + ": grid " + quote(name) + " has value type " + quote(base->valueType()) +
                        " (supported: float, double, vec3s, vec3d)");
        const double floats = double(g.nx) * double(g.ny) * double(g.nz) * double(g.channels);
        if (floats > double(kMaxGridFloats))
            throw Error(what + ": grid " + quote(name) + " spans " + std::to_string(g.nx) + "x" + std::to_string(g.ny) + "x" +
                        std::to_string(g.nz) + " voxels, more than mfrender makes dense (" + std::to_string(kMaxGridFloats) +
                        " values)");
        if (auto fg = openvdb::gridConstPtrCast<openvdb::FloatGrid>(base)) densify<openvdb::FloatGrid, 1>(*fg, box, &g);
        else if (auto dg = openvdb::gridConstPtrCast<openvdb::DoubleGrid>(base)) densify<openvdb::DoubleGrid, 1>(*dg, box, &g);
        else if (auto vs = openvdb::gridConstPtrCast<openvdb::Vec3SGrid>(base)) densify<openvdb::Vec3SGrid, 3>(*vs, box, &g);
        else densify<openvdb::Vec3DGrid, 3>(*openvdb::gridConstPtrCast<openvdb::Vec3DGrid>(base), box, &g);

        // unit cube -> index space: cell centres at (i + 0.5) / n, or nodes at i / (n - 1)
        Mat4 unit_to_index;
        const int n[3] = {g.nx, g.ny, g.nz};
        const openvdb::Coord lo = box.min();
        for (int a = 0; a < 3; ++a) {
            if (centering == GridCentering::Cell) {
                unit_to_index.m[a][a] = n[a];
                unit_to_index.m[a][3] = lo[a] - 0.5;
            } else {
                unit_to_index.m[a][a] = n[a] - 1;
                unit_to_index.m[a][3] = lo[a];
            }
        }
        // index -> VDB world: the images of the origin and the three unit vectors (linear map)
        Mat4 index_to_world;
        const openvdb::Vec3d o = xf.indexToWorld(openvdb::Vec3d(0, 0, 0));
        for (int a = 0; a < 3; ++a) {
            openvdb::Vec3d e(0, 0, 0);
            e[a] = 1;
            const openvdb::Vec3d col = xf.indexToWorld(e) - o;
            for (int r = 0; r < 3; ++r) index_to_world.m[r][a] = col[r];
        }
        for (int r = 0; r < 3; ++r) index_to_world.m[r][3] = o[r];
        g.has_grid_to_world = true;
        g.grid_to_world = index_to_world * unit_to_index;
        for (int corner = 0; corner < 8; ++corner)
            g.bbox.expand(g.grid_to_world.point(Vec3(float(corner & 1), float((corner >> 1) & 1), float((corner >> 2) & 1))));
        return g;
    } catch (const Error&) {
        throw;
    } catch (const std::exception& e) {
        throw Error("cannot read " + what + ": " + e.what());
    }
}

}  // namespace

}  // namespace mf

// The module's one entry point (volume_io.cpp calls it as ReadVdbGrid): reads the grid into *out, or
// returns 0 with the message in *error. Nothing is thrown across the module boundary.
extern "C" __attribute__((visibility("default"))) int mfhost_vdb_read_grid(const char* path, const char* grid_name,
                                                                           int centering, mf::VolumeGridData* out,
                                                                           std::string* error) noexcept {
    try {
        *out = mf::read_grid(path, grid_name, centering == 1 ? mf::GridCentering::Node : mf::GridCentering::Cell);
        return 1;
    } catch (const std::exception& e) {
        *error = e.what();
    } catch (...) {
        *error = std::string("cannot read OpenVDB file ") + mf::quote(path, 200) + ": unknown error";
    }
    return 0;
}
