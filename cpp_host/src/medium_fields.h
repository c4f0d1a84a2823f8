// mfhost — the XML of spatially varying macrofacet/gpis parameters (issue 12): <volume> elements
// (constvolume, gridvolume from .vol or .vdb), textures as parameters of a medium, their
// validation, and the checks that tie them to the mean surface.
//
//   <medium type="macrofacet" id="m">
//       <float name="sigma" value="0.02"/>
//       <volume name="alpha" type="gridvolume">
//           <string name="filename" value="alpha.vol"/>      (or a .vdb, with <string name="grid">)
//           <transform name="to_world"> ... </transform>
//       </volume>
//       <texture name="specular_reflectance" type="bitmap"> ... </texture>
//   </medium>
//
// Parameters that may vary (kVaryingParams): sigma, variance, alpha, alpha_u, alpha_v, alpha_z,
// lengthscale, lengthscale_x/_y/_z (1 channel), specular_reflectance and reflectance (the flakes'
// reflectance scale; 1 or 3 channels), and the local anisotropy Sigma of seeds/004 Eqs. 25-26 as
// `anisotropy` (a 6-channel volume in the order of Mitsuba 3's sggx matrix S: xx, yy, zz, xy, xz,
// yz) or as its diagonal and off-diagonal halves `anisotropy_diagonal` (xx, yy, zz) and
// `anisotropy_offdiagonal` (xy, xz, yz), 3 channels each (e.g. two rgb constvolumes or two Vec3
// grids of one .vdb), which must then share one grid layout so that every voxel's matrix is known.
// Every sample is checked at load: finite; sigma, variance, alpha*, lengthscale* > 0 (alpha_z >= 0);
// reflectances in [0, 1]; every anisotropy matrix positive definite.
//
// A constvolume of a parameter that has a scalar form is folded into the parameter bag as that
// number (with the number's own precision), so it renders exactly as the scalar does.
#pragma once

#include <functional>
#include <map>
#include <memory>
#include <string>

#include "field.h"
#include "medium.h"
#include "texture.h"
#include "volume_io.h"
#include "xml_scene.h"

namespace mf {

class Shape;

/// Loads grid files once per <volume> element (a volume referenced by several parameters).
class VolumeFileCache {
public:
    /// The grid of `o` (a gridvolume): its file read (and made dense) once. Throws mf::Error.
    std::shared_ptr<const VolumeGridData> grid(const SceneObject& o, const std::string& path, const std::string& grid_name,
                                               GridCentering centering);

private:
    std::map<const SceneObject*, std::shared_ptr<const VolumeGridData>> grids_;
};

using TextureBuilder = std::function<std::shared_ptr<const Texture>(const SceneObject&)>;

/// Consumes the <volume>/<texture> children (nested or <ref>) of a macrofacet/gpis medium
/// element: constvolumes of scalar parameters are added to `bag`, everything else becomes a
/// Field. Throws mf::Error (an ErrorList if several) at the element's file:line for an unknown
/// parameter or volume type, a missing or corrupt file, an out-of-range sample, a channel count
/// that does not fit the parameter, or a parameter given twice. Returns null if nothing varies.
std::shared_ptr<const MediumFields> build_medium_fields(const SceneObject& medium, MediumParamBag* bag,
                                                        VolumeFileCache& files, const TextureBuilder& build_texture);

/// A <volume> (constvolume or gridvolume) as Mitsuba's media read sigma_t and albedo: 3 channels
/// (1-channel data as grey), every value finite and in [0, max_value]. *world_box receives the
/// box of the unit cube under its to_world (Mitsuba's Volume::bbox, a constvolume's too).
std::shared_ptr<const Volume> build_rgb_volume(const SceneObject& o, VolumeFileCache& files, float max_value, Aabb* world_box);

/// Builds a top-level <volume id="..."> element once to report its problems (its values are
/// checked for finiteness only; the parameter it is used for checks the rest).
void check_volume_element(const SceneObject& o, VolumeFileCache& files);

/// The checks that need the mean surface `shape` of the medium of `bag`: textures need uv on the
/// shape; every grid must cover the medium's region, the shape's bounding box grown by the
/// shell's top (shell_extent times the largest sigma, seeds/000 §4: the shell ends at +k sigma).
void check_fields_on_surface(const MediumParamBag& bag, const Shape& shape);

/// The shell's top k * sigma_max for the bag's parameters and fields (the largest sigma any
/// point can have); k = shell_extent or its default (3 for macrofacet, 6 for gpis).
double shell_top_bound(const MediumParamBag& bag);

/// Until the library takes local parameters per query: throws mf::Error naming the first
/// spatially varying parameter of `bag` (nothing if none varies).
void refuse_varying_fields(const MediumParamBag& bag);

}  // namespace mf
