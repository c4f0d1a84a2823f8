// macrofacet for Mitsuba 3 — medium parameters that vary in space (issue 12; seeds/004 §6.1), in
// the XML that mfrender reads (cpp_host/src/medium_fields.h, README "Use in Mitsuba 3"):
//
//   <medium type="macrofacet" id="m">
//       <float name="sigma" value="0.02"/>
//       <volume name="alpha" type="gridvolume">
//           <string name="filename" value="alpha.vol"/>
//           <transform name="to_world"> ... </transform>
//       </volume>
//       <texture name="specular_reflectance" type="bitmap"> ... </texture>
//       <shape type="sphere" name="mean_surface"/>
//   </medium>
//
// Mitsuba loads the nested objects; this file checks them against the parameter they give and
// turns them into mfrender's MediumFields (over field_sources.h's adapters), so that
// cpp_host/src/medium_field.h maps them to the library's local parameters and segment bounds for
// both renderers. The parameters, their channels and their checks are mfrender's: sigma, variance,
// alpha, alpha_u, alpha_v, lengthscale* (1 channel, > 0), alpha_z (>= 0), specular_reflectance
// and reflectance (1 or 3 channels, in [0, 1]), and the local anisotropy Sigma of
// seeds/004 Eqs. 25-26 as `anisotropy` (a 6-channel gridvolume, Mitsuba's sggx order xx, yy, zz, xy, xz, yz,
// world space) or as its halves `anisotropy_diagonal` and `anisotropy_offdiagonal` (3 channels
// each: gridvolumes of one layout, or rgb constvolumes), every matrix positive definite. Every
// voxel is checked, a texture by its bounds; a texture cannot give the anisotropy (a matrix in
// world space). A constvolume of a parameter with a scalar form becomes that number.
//
// The base medium (mf_medium_new) takes every varying parameter at its largest value, as
// mfrender's: its sigma is then the region's, sigma_max, and every reflectance scale lies in
// [0, 1]; an anisotropy without a roughness gives the largest roughness it reaches,
// sqrt(2) sigma_max / sqrt(lambda_min(Sigma)) (seeds/004 Eq. 25 with seeds/000 Eq. 4).
#pragma once

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "cpp_host/src/field.h"
#include "cpp_host/src/medium.h"
#include "cpp_host/src/varying_param.h"
#include "field_sources.h"
#include "mean_surface.h"

namespace mfmi {

/// A <volume> or <texture> nested in the medium under the name of the parameter it gives.
struct NestedParam {
    std::string name;
    mitsuba::ref<mitsuba::Object> object;
};

/// The double that a float of the scene file was written as: Mitsuba keeps a constvolume's value
/// in float, the medium's own numbers in double; the shortest decimal that rounds to the float
/// (std::to_chars), read back in double, is the number as written whenever it has at most 6
/// significant digits, so that a constvolume renders exactly as the number does.
inline double as_written(float x) {
    char buf[32];
    const auto end = std::to_chars(buf, buf + sizeof(buf), x).ptr;
    double d = double(x);
    std::from_chars(buf, end, d);
    return d;
}

/// Reads, checks and assembles the varying parameters (file comment). `bag` holds the medium's
/// numbers (params_of): a constvolume is added to it as its number, and bag->fields is set when
/// something varies (the base medium's numbers are then ::mf::base_bag(*bag), as mfrender's).
/// Throws std::runtime_error naming the parameter at fault.
template <typename Float, typename Spectrum>
void read_varying_params(const std::vector<NestedParam>& nested, ::mf::MediumParamBag* bag) {
    using MiVolume = mitsuba::Volume<Float, Spectrum>;
    using MiTexture = mitsuba::Texture<Float, Spectrum>;
    using Part = typename MitsubaVolume<Float, Spectrum>::Part;

    // A volume read for a parameter: its part of the value, and its samples if it is a grid.
    struct Source {
        std::string element;  // <volume type="gridvolume">
        std::string what;     // parameter "alpha": <volume type="gridvolume"> (messages)
        Part part;
        GridSamples grid;
        ::mf::WrapMode wrap = ::mf::WrapMode::Clamp;
        bool is_grid() const { return part.volume.get() != nullptr; }
        /// The element with the grid's size and wrap mode, e.g. <volume type="gridvolume"> (4 x 4 x 4, wrap_mode repeat).
        std::string grid_element() const {
            static const char* wraps[] = {"repeat", "mirror", "clamp"};  // ::mf::WrapMode's order
            return element + " (" + std::to_string(grid.n[0]) + " x " + std::to_string(grid.n[1]) + " x " + std::to_string(grid.n[2]) +
                   ", wrap_mode " + wraps[int(wrap)] + ")";
        }
        /// Channel c of sample i (a constant: its value).
        float sample(size_t i, int c) const {
            const int k = part.channels == 1 ? 0 : c;
            return is_grid() ? grid.values[i * size_t(part.channels) + size_t(k)] : part.constant[k];
        }
    };

    auto fields = std::make_shared<::mf::MediumFields>();
    std::optional<Source> matrix[3];  // anisotropy, anisotropy_diagonal, anisotropy_offdiagonal

    for (const NestedParam& n : nested) {
        const ::mf::VaryingParam* p = ::mf::varying_param(n.name);
        const std::string quoted = "\"" + n.name + "\"";
        auto* volume = dynamic_cast<const MiVolume*>(n.object.get());
        auto* texture = dynamic_cast<const MiTexture*>(n.object.get());
        const std::string element =
            std::string(volume ? "<volume" : "<texture") + " type=\"" + plugin_name(*n.object) + "\">";
        if (!p)
            throw std::runtime_error(element + " names parameter " + quoted +
                                     ", which cannot vary in space (parameters that can: " + ::mf::varying_param_list() + ")");
        const std::string what = "parameter " + quoted + ": " + element;
        auto bad_value = [&](const std::string& where, double x) {
            return std::runtime_error(what + ": " + where + " is " + ::mf::number_str(x) + ", but " + n.name + " " +
                                      ::mf::constraint_text(p->constraint));
        };
        auto satisfies = [&](float x) { return ::mf::satisfies(p->constraint, x); };

        if (texture) {
            if (p->constraint == ::mf::Constraint::Matrix)
                throw std::runtime_error("parameter " + quoted + " is a matrix in world space: give it as a <volume>, not a texture");
            std::shared_ptr<const ::mf::Texture> source;
            try {
                source = std::make_shared<MitsubaTexture<Float, Spectrum>>(mitsuba::ref<const MiTexture>(texture));
            } catch (const std::exception& e) {
                throw std::runtime_error(what + ": " + e.what());
            }
            auto field = std::make_shared<::mf::Field>(n.name, ::mf::SourceLoc{}, element, source, p->channels);
            const ::mf::ValueRange r = field->range();
            for (int c = 0; c < r.channels; ++c)
                for (float x : {r.lo[c], r.hi[c]})
                    if (!satisfies(x))
                        throw std::runtime_error(what + ": its values reach " + ::mf::number_str(x) + ", but " + n.name + " " +
                                                 ::mf::constraint_text(p->constraint) + (p->channels == 1 ? " (a scalar reads the texture's luminance)" : ""));
            fields->fields.push_back(field);
            continue;
        }
        if (!volume) throw std::runtime_error(what + " is neither a <volume> nor a <texture>");

        Source s;
        s.element = element;
        s.what = what;
        s.part.channels = volume_channels(*volume);
        s.part.width = p->channels;
        const int c = s.part.channels;
        if (!(c == p->channels || (p->channels == 3 && c == 1)))
            throw std::runtime_error(what + " has " + std::to_string(c) + " channel" + (c == 1 ? "" : "s") + ", but " + n.name + " takes " +
                                     (p->channels == 1 ? "1 channel (a float)" : p->channels == 3 ? "1 or 3 channels (float or rgb)" : "6 channels"));
        try {
            if (plugin_name(*volume) == "constvolume") {
                constvolume_value(*volume, c, s.part.constant);
            } else if (plugin_name(*volume) == "gridvolume") {
                s.part.volume = mitsuba::ref<const MiVolume>(volume);
                s.grid = grid_samples(*volume);
                s.wrap = wrap_mode_of(*volume, s.grid);
            } else {
                throw std::runtime_error("unsupported volume (constvolume or gridvolume)");
            }
        } catch (const std::exception& e) {
            throw std::runtime_error(what + ": " + e.what());
        }
        // every sample (the anisotropy's entries: finite; its matrices are checked below)
        const size_t count = s.is_grid() ? s.grid.values.size() / size_t(c) : 1;
        for (size_t i = 0; i < count; ++i)
            for (int k = 0; k < c; ++k)
                if (!satisfies(s.sample(i, k))) {
                    std::string where = c > 1 ? "channel " + std::to_string(k) + " of " : "";
                    if (s.is_grid()) {
                        const size_t nx = size_t(s.grid.n[0]), ny = size_t(s.grid.n[1]);
                        where += "voxel (" + std::to_string(i % nx) + ", " + std::to_string(i / nx % ny) + ", " + std::to_string(i / (nx * ny)) + ")";
                    } else {
                        where += "the value";
                    }
                    throw bad_value(where, s.sample(i, k));
                }

        if (p->constraint == ::mf::Constraint::Matrix) {
            matrix[n.name == "anisotropy" ? 0 : n.name == "anisotropy_diagonal" ? 1 : 2] = std::move(s);
            continue;
        }
        if (!s.is_grid()) {
            // a constant of a parameter with a scalar form: that number, as written
            ::mf::ParamValue pv;
            pv.kind = c == 1 ? ::mf::ParamValue::Kind::Float : ::mf::ParamValue::Kind::Rgb;
            pv.f = as_written(s.part.constant[0]);
            if (c == 3) pv.rgb = ::mf::Rgb(s.part.constant[0], s.part.constant[1], s.part.constant[2]);  // as_written when set
            bag->params.emplace_back(n.name, pv);
            continue;
        }
        // a grid: mfrender's volume over its samples (broadcast to the parameter's channels) bounds it
        std::vector<float> samples(count * size_t(p->channels));
        for (size_t i = 0; i < count; ++i)
            for (int k = 0; k < p->channels; ++k) samples[i * size_t(p->channels) + size_t(k)] = s.sample(i, k);
        auto bounds = ::mf::make_grid_volume(::mf::SampleGrid(std::move(samples), s.grid.n[0], s.grid.n[1], s.grid.n[2], p->channels),
                                             p->channels, s.grid.to_world, ::mf::VolumeFilter::Trilinear, s.wrap);
        auto source = std::make_shared<MitsubaVolume<Float, Spectrum>>(std::vector<Part>{s.part}, bounds);
        fields->fields.push_back(std::make_shared<::mf::Field>(n.name, ::mf::SourceLoc{}, s.grid_element(), source));
    }

    // The anisotropy: one 6-channel grid, or its halves (a missing off-diagonal is zero).
    const Source *full = matrix[0] ? &*matrix[0] : nullptr, *diag = matrix[1] ? &*matrix[1] : nullptr,
                 *off = matrix[2] ? &*matrix[2] : nullptr;
    if (full && (diag || off))
        throw std::runtime_error("give the anisotropy either as \"anisotropy\" (6 channels) or as its halves \"anisotropy_diagonal\" and "
                                 "\"anisotropy_offdiagonal\", not both");
    if (off && !diag) throw std::runtime_error("\"anisotropy_offdiagonal\" needs \"anisotropy_diagonal\" too");
    if (full || diag) {
        std::vector<const Source*> parts = full ? std::vector<const Source*>{full} : std::vector<const Source*>{diag, off};
        const Source* layout = nullptr;
        for (const Source* s : parts) {
            if (!s || !s->is_grid()) continue;
            if (!layout) {
                layout = s;
                continue;
            }
            bool same = s->wrap == layout->wrap;
            for (int a = 0; a < 3; ++a) same &= s->grid.n[a] == layout->grid.n[a];
            for (int r = 0; r < 4; ++r)
                for (int c = 0; c < 4; ++c) same &= s->grid.to_world.m[r][c] == layout->grid.to_world.m[r][c];
            if (!same)
                throw std::runtime_error(s->what + ": its grid must have the layout of anisotropy_diagonal's (the same size, to_world and "
                                                   "wrap_mode), so that every voxel's matrix is known");
        }
        const size_t count = layout ? layout->grid.values.size() / size_t(layout->part.channels) : 1;
        std::vector<float> samples(count * 8);
        for (size_t i = 0; i < count; ++i) {
            double m[6];
            for (int c = 0; c < 6; ++c) {
                const Source* s = full ? full : (c < 3 ? diag : off);
                m[c] = s ? double(full ? s->sample(i, c) : s->sample(i, c % 3)) : 0.0;
            }
            if (!::mf::positive_definite(m)) {
                const Source* at = layout ? layout : diag;
                const size_t nx = layout ? size_t(layout->grid.n[0]) : 1, ny = layout ? size_t(layout->grid.n[1]) : 1;
                throw std::runtime_error(at->what + ": " +
                                         (layout ? "the matrix of voxel (" + std::to_string(i % nx) + ", " + std::to_string(i / nx % ny) + ", " +
                                                       std::to_string(i / (nx * ny)) + ")"
                                                 : std::string("the matrix")) +
                                         ", (xx, yy, zz, xy, xz, yz) = (" + ::mf::number_str(m[0]) + ", " + ::mf::number_str(m[1]) + ", " +
                                         ::mf::number_str(m[2]) + ", " + ::mf::number_str(m[3]) + ", " + ::mf::number_str(m[4]) + ", " +
                                         ::mf::number_str(m[5]) + "), is not positive definite (the local anisotropy of seeds/004 Eq. 25)");
            }
            ::mf::matrix_sample(m, &samples[i * 8]);
        }
        std::shared_ptr<const ::mf::Volume> volume;
        if (!layout) {
            volume = ::mf::make_constant_volume(samples.data(), 6, 8);
        } else {
            auto bounds = ::mf::make_grid_volume(::mf::SampleGrid(std::move(samples), layout->grid.n[0], layout->grid.n[1], layout->grid.n[2], 8),
                                                 6, layout->grid.to_world, ::mf::VolumeFilter::Trilinear, layout->wrap);
            std::vector<Part> value_parts;
            for (const Source* s : parts) {
                Part zero;
                zero.width = 3;
                value_parts.push_back(s ? s->part : zero);
            }
            volume = std::make_shared<MitsubaVolume<Float, Spectrum>>(value_parts, bounds);
        }
        const Source& origin = full ? *full : *diag;
        fields->fields.push_back(std::make_shared<::mf::Field>("anisotropy", ::mf::SourceLoc{}, layout ? layout->grid_element() : origin.element, volume));
    }

    if (!fields->empty()) bag->fields = fields;
}

/// The checks that need the mean surface and the region's top k sigma_max: textures need the
/// surface's uv; every grid (wrap_mode clamp) must cover the region, the surface's box grown by
/// `top`; an sdfgrid must contain the region (its outer faces at f >= top).
inline void check_fields_on_surface(const ::mf::MediumFields* fields, const MeanSurface& surface, double top) {
    const std::string shape = "<shape type=\"" + surface.kind() + "\" name=\"mean_surface\">";
    const GridFaceMinimum& faces = surface.grid_faces();
    if (faces.value < top)
        throw std::runtime_error(shape + ": the medium's region f < " + ::mf::number_str(top) +
                                 " (the shell's top, shell_extent x the largest sigma) reaches the grid's boundary at node (" +
                                 std::to_string(faces.node[0]) + ", " + std::to_string(faces.node[1]) + ", " + std::to_string(faces.node[2]) +
                                 ") (f = " + ::mf::number_str(faces.value) + "): the SDF grid must contain the whole medium; enlarge it");
    if (!fields) return;
    const auto box = surface.bounding_box();
    ::mf::Aabb region;
    region.lo = ::mf::Vec3(float(box[0].x - top), float(box[0].y - top), float(box[0].z - top));
    region.hi = ::mf::Vec3(float(box[1].x + top), float(box[1].y + top), float(box[1].z + top));
    for (const auto& f : fields->fields) {
        const std::string what = "parameter \"" + f->param() + "\": " + f->element();
        if (f->domain() == ::mf::Field::Domain::Texture && !surface.has_uv())
            throw std::runtime_error(what + " is a texture over the mean surface's uv, but " + shape + " has no texture coordinates");
        if (f->domain() == ::mf::Field::Domain::Volume && !f->volume()->covers(region))
            throw std::runtime_error(what + ": the grid does not cover the medium's region [" + ::mf::number_str(region.lo.x) + ", " +
                                     ::mf::number_str(region.hi.x) + "] x [" + ::mf::number_str(region.lo.y) + ", " + ::mf::number_str(region.hi.y) +
                                     "] x [" + ::mf::number_str(region.lo.z) + ", " + ::mf::number_str(region.hi.z) + "] (the box of " + shape +
                                     " grown by the shell's top " + ::mf::number_str(top) +
                                     " = shell_extent x the largest sigma): enlarge the grid or its to_world, or use wrap_mode repeat or mirror");
    }
}

}  // namespace mfmi
