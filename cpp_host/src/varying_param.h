// mfhost — the medium parameters that may vary in space (issue 12; seeds/004 §6.1) and their
// rules, shared by mfrender's scene reader (medium_fields.cpp) and the Mitsuba plugin
// (mitsuba_plugin/src/varying_params.h): names, channels, value constraints, the anisotropy's
// positive-definiteness and eigenvalue bounds, and the base medium's stand-in values. Depends on
// no scene or file format.
#pragma once

#include <string>

#include "medium.h"

namespace mf {

enum class Constraint { Positive, NonNegative, Unit, Matrix };

struct VaryingParam {
    const char* name;
    int channels;  // of the value the library takes (1, 3, or 3 per half of the 6-entry matrix)
    Constraint constraint;
    bool scalar_form;  // the library also takes it as a number (a constvolume folds into the bag)
};

/// The parameter `name`, or null if it cannot vary in space.
const VaryingParam* varying_param(const std::string& name);
/// "sigma, variance, alpha, ..." (for messages).
std::string varying_param_list();

/// The rule of a constraint, e.g. "must be finite and > 0" (for messages).
const char* constraint_text(Constraint c);
bool satisfies(Constraint c, float x);

/// Sylvester's criterion in double precision for s = (xx, yy, zz, xy, xz, yz): the leading
/// minors are positive.
bool positive_definite(const double s[6]);

/// The 8 range channels of one anisotropy sample: the 6 entries, then a lower bound of the
/// smallest and an upper bound of the largest eigenvalue (rounded outwards to float; Field::kEigenMin/Max).
void matrix_sample(const double s[6], float out[8]);

/// A copy of `bag` in which every varying parameter with a scalar form is replaced by its largest
/// value (so that the library validates the other parameters, and the largest values, as it
/// would for a render; medium_field.h's base_bag builds on it).
MediumParamBag stand_in_bag(const MediumParamBag& bag);

}  // namespace mf
