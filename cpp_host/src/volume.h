// mfhost — volumes, as Mitsuba 3's <volume> plugins: 3D data sources evaluated at world points.
//
//   constvolume  one value (float or rgb `value`) everywhere;
//   gridvolume   samples on a regular grid (a Mitsuba .vol file, or a grid of an OpenVDB .vdb
//                file: volume_io.h), with Mitsuba's conventions: the grid fills the unit cube
//                [0, 1]^3 of its local space, sample (i, j, k) at the cell centre
//                ((i + 0.5) / nx, (j + 0.5) / ny, (k + 0.5) / nz), `to_world` maps local to world;
//                filter_type trilinear (default; between cell centres) or nearest; wrap_mode clamp
//                (default), repeat or mirror outside [0, 1].
//
// Besides evaluation, every volume answers CONSERVATIVE range queries — per-channel bounds that
// contain every value the volume takes over a world box or along a segment — for majorants. They
// read the samples' min/max pyramid (sample_grid.h): a trilinear value is a convex combination of
// the 8 samples around it, so the samples an interpolant reads over a region bound it there.
#pragma once

#include <memory>
#include <string>

#include "math.h"
#include "sample_grid.h"

namespace mf {

enum class VolumeFilter { Trilinear, Nearest };

class Volume {
public:
    virtual ~Volume() = default;
    /// Channels per value: 1, 3 or 6 (Mitsuba's gridvolume), plus the derived channels of
    /// range() where a field adds them (field.h).
    virtual int channels() const = 0;
    /// The value at world point p: channels() floats into out.
    virtual void eval(const Vec3& p, float* out) const = 0;
    /// Bounds over every point of the world box (inclusive).
    virtual ValueRange range_box(const Aabb& world_box) const = 0;
    /// Bounds over the segment o + s d, s in [0, length] (d need not be unit; length finite).
    virtual ValueRange range_segment(const Vec3& o, const Vec3& d, float length) const = 0;
    /// Bounds over all of space.
    virtual ValueRange range() const = 0;
    /// Non-null for a constant volume: its channels() values.
    virtual const float* constant() const { return nullptr; }
    /// Whether every point of the world box lies where the samples define the volume: inside the
    /// grid's box (a constant, or a grid that repeats or mirrors, defines it everywhere).
    virtual bool covers(const Aabb& world_box) const = 0;
    /// "constvolume" or "gridvolume" (messages).
    virtual const char* kind() const = 0;
};

/// `value` has `stride` floats (channels <= stride <= ValueRange::kMaxChannels): the first
/// `channels` are the value, the rest take part in range queries only (derived bounds, field.h).
std::shared_ptr<Volume> make_constant_volume(const float* value, int channels, int stride);

/// A grid volume over `grid` whose first `channels` of each sample are the value; further
/// channels of the stride (if any) take part in range queries only (derived bounds, field.h).
/// `to_world` maps the unit cube to world space and must be invertible.
std::shared_ptr<Volume> make_grid_volume(SampleGrid grid, int channels, const Mat4& to_world, VolumeFilter filter,
                                         WrapMode wrap);

}  // namespace mf
