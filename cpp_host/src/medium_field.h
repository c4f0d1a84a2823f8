// mfhost — a medium's spatially varying parameters (field.h) as the library's mf_field: the
// callbacks the library calls at tentative collisions (the local parameters) and along tracked
// segments (their bounds), so that the library stays pure and the host keeps its grids and
// textures (issue 12; seeds/004 §6.1).
//
// The parameter names follow the library's table (src/params.rs): sigma | variance; the roughness
// as alpha | alpha_u, alpha_v[, alpha_z] or in kernel form lengthscale | lengthscale_x, _y[, _z]
// with alpha_i = sqrt(2) sigma / l_i (seeds/000 Eq. 4), so in kernel form the roughness follows
// a varying sigma; the anisotropy Sigma (6 entries, world space); specular_reflectance or
// reflectance as a scale of the base medium's value. The base medium is built from the bag with
// every varying parameter at its largest value (stand_in_bag), so its sigma is the field's
// largest (the region's top face) and every reflectance scale lies in [0, 1].
#pragma once

#include <array>
#include <memory>

#include "field.h"
#include "medium.h"

struct mf_field;
struct mf_field_callbacks;
struct mf_local_params;

namespace mf {

class LibraryField {
public:
    /// `bag`: the medium's parameters and fields; `gpss`: the distribution reads alpha_z.
    LibraryField(const MediumParamBag& bag, bool gpss);
    ~LibraryField();
    LibraryField(const LibraryField&) = delete;
    LibraryField& operator=(const LibraryField&) = delete;

    const ::mf_field* handle() const { return handle_; }
    /// The callbacks' user_data.
    void* user_data() const { return const_cast<LibraryField*>(this); }
    /// The callbacks themselves (for a medium that must forward them with its own user_data).
    const ::mf_field_callbacks& callbacks() const;

    /// One source of a scalar: a field or the bag's constant.
    struct Scalar {
        const Field* field = nullptr;
        double value = 0;
        bool present = false;
    };

private:
    friend struct LibraryFieldCallbacks;
    std::shared_ptr<::mf_field_callbacks> callbacks_;
    ::mf_field* handle_ = nullptr;
    Scalar sigma_;
    bool variance_ = false;  // sigma_ holds the variance
    bool kernel_form_ = false;
    bool gpss_ = false;
    std::array<Scalar, 4> roughness_;  // iso, u (x), v (y), z: alpha* or lengthscale*
    const Field* anisotropy_ = nullptr;
    const Field* reflectance_ = nullptr;
    std::array<double, 3> reflectance_base_{};
    bool roughness_varies_ = false;
};

/// The bag of the base medium (the library's constants): every varying parameter at its largest
/// value (stand_in_bag), and for an anisotropy alone the largest roughness it reaches,
/// sqrt(2) sigma_max / sqrt(lambda_min(Sigma)) (seeds/004 Eq. 25 with seeds/000 Eq. 4), as
/// `alpha`. The bag itself when nothing varies.
MediumParamBag base_bag(const MediumParamBag& bag);

/// The library field of a medium whose parameters vary (gpss unless `distribution` names a
/// height field); null when none varies.
std::shared_ptr<const LibraryField> library_field_of(const MediumParamBag& bag);

/// A collision's local parameters in an event record (MediumInteraction::record, 14 doubles from
/// `at`), and back: null when the medium's own parameters hold there.
void store_local(const ::mf_local_params& local, MediumInteraction* mi, int at);
const ::mf_local_params* load_local(const MediumInteraction& mi, int at, ::mf_local_params* out);

}  // namespace mf
