// mfhost — the parameters of the media the library implements (<medium type="macrofacet"> and
// <medium type="gpis">): the scene's parameter bag (MediumParamBag, kept verbatim by the scene
// reader) as the library's mf_params, and the library's messages about it placed at the
// file:line of the parameter they name. Both media validate nothing themselves: the library does.
#pragma once

#include <memory>
#include <string>

#include "error.h"
#include "medium.h"

struct mf_params;

namespace mf {

/// An mf_params handle that frees itself (mf_params_free).
using ParamsHandle = std::unique_ptr<mf_params, void (*)(mf_params*)>;

/// The parameter bag as the library's parameters, set by name in document order (<float> and
/// <integer> with mf_params_set_float, <rgb> with mf_params_set_rgb, <string> with
/// mf_params_set_string; booleans are refused). Throws mf::Error at the offending parameter's
/// line when the library rejects a name or value.
ParamsHandle bag_to_params(const MediumParamBag& bag);
/// An error for a library message about `bag`, at the line of the parameter the message names
/// (the longest bag name quoted in it; else the string parameter whose value it quotes), else at
/// the <medium> element.
Error medium_param_error(const MediumParamBag& bag, const std::string& msg);
/// "file:line: <medium type=... id=...>" for messages at run time.
std::string medium_label(const MediumParamBag& bag);

}  // namespace mf
