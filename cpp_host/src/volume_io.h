// mfhost — reading volume grids: Mitsuba's binary .vol files and grids of OpenVDB .vdb files.
//
// Mitsuba .vol (VolumeGrid::read, little endian): "VOL", version byte 3, int32 encoding 1
// (float32), int32 nx, ny, nz, int32 channels, six float32 (xmin, ymin, zmin, xmax, ymax, zmax:
// the bounding box, which Mitsuba's gridvolume only uses with use_grid_bbox), then
// nx * ny * nz * channels float32 with x fastest, channels innermost. The file must hold exactly
// that many bytes.
//
// OpenVDB: a float, double, Vec3s or Vec3d grid picked by name, made dense over its active
// voxels' bounding box. VDB values sit at integer index coordinates and its transform maps
// index to world space (linear transforms only). `grid_to_world` maps the unit cube of the dense
// grid to VDB world space in the requested convention: cell-centred (gridvolume: sample i at
// (i + 0.5) / n, the box padded by one voxel of background so that interpolation falls off to the
// background as OpenVDB's own samplers do) or node-centred (sdfgrid: sample i at i / (n - 1)).
#pragma once

#include <string>
#include <vector>

#include "math.h"

namespace mf {

struct VolumeGridData {
    int nx = 0, ny = 0, nz = 0, channels = 0;
    std::vector<float> values;  // ((k * ny + j) * nx + i) * channels + c
    Aabb bbox;                  // .vol: the header's bounding box; .vdb: the unit cube's image in VDB world
    bool has_grid_to_world = false;  // .vdb: grid_to_world below is the grid's own placement
    Mat4 grid_to_world;
};

/// Whether `path` names an existing regular file.
bool is_regular_file(const std::string& path);
/// Whether `path` ends in ".vdb" (any case): an OpenVDB file; otherwise a Mitsuba .vol file.
bool is_vdb_path(const std::string& path);

/// Largest number of samples (times channels) mfrender loads from one grid.
constexpr size_t kMaxGridFloats = size_t(1) << 28;  // 1 GiB of float32

/// Reads a Mitsuba .vol file; throws mf::Error naming the file and the problem (missing or
/// unreadable file, wrong magic, version or encoding, non-positive sizes or channels, a length
/// that does not match the header).
VolumeGridData read_vol_file(const std::string& path);

enum class GridCentering { Cell, Node };
/// Reads grid `grid_name` of an OpenVDB file (empty name: the file's only grid); throws mf::Error
/// for a missing or unreadable file, a missing grid (listing the file's grids), an unsupported
/// value type or transform, or an empty grid. The reader is a module (libmfhost_vdb.so, beside
/// the binary) loaded on the first call, so that runs without .vdb files do not load OpenVDB;
/// a module that cannot be loaded is an mf::Error too.
VolumeGridData read_vdb_grid(const std::string& path, const std::string& grid_name, GridCentering centering);

/// Writes a Mitsuba .vol file (tests, tools). Throws mf::Error if it cannot.
void write_vol_file(const std::string& path, const VolumeGridData& grid);

}  // namespace mf
