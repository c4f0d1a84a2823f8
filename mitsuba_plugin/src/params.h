// macrofacet for Mitsuba 3 — the medium's XML parameters as an mf_params set, by the names of
// the README's table (the library checks names, types and values, and its messages name the
// parameter). Conversions follow mfrender's: <float>/<integer> are floats, <rgb> and a constant
// <spectrum> (grey) are RGB, <string> strings; anything else is refused here, naming the
// parameter. The nested mean surface and the parameters Mitsuba's Medium base class reads
// itself (sample_emitters) are not part of the set. The same values go to mfrender's parameter
// bag, which the field mapping of spatially varying media reads (varying_params.h).
#pragma once

#include <mitsuba/core/properties.h>

#include <memory>
#include <string>

#include "cpp_host/src/medium.h"
#include "library.h"

namespace mfmi {

struct ParamsDeleter {
    void operator()(mf_params* p) const { mf_params_free(p); }
};
using ParamsPtr = std::unique_ptr<mf_params, ParamsDeleter>;

/// The mean surface's property name.
inline constexpr const char* kMeanSurface = "mean_surface";

/// The medium parameters of `props` (every non-object property not read by Mitsuba already), also
/// added to `bag`. Throws std::runtime_error naming the parameter at fault.
inline ParamsPtr params_of(const mitsuba::Properties& props, ::mf::MediumParamBag* bag) {
    using mitsuba::Properties;
    mf_params* raw = nullptr;
    check(mf_params_new(&raw), "mf_params_new");
    ParamsPtr params(raw);
    for (const auto& prop : props) {
        if (prop.queried() || prop.type() == Properties::Type::Object) continue;
        const std::string name(prop.name());
        const std::string what = "parameter \"" + name + "\"";
        mf_status st = MF_OK;
        ::mf::ParamValue value;
        switch (prop.type()) {
            case Properties::Type::Float:
                value.f = prop.get<double>();
                st = mf_params_set_float(raw, name.c_str(), value.f);
                break;
            case Properties::Type::Integer:
                value.f = double(prop.get<int64_t>());
                st = mf_params_set_float(raw, name.c_str(), value.f);
                break;
            case Properties::Type::String:
                value.kind = ::mf::ParamValue::Kind::String;
                value.s = prop.get<std::string>();
                st = mf_params_set_string(raw, name.c_str(), value.s.c_str());
                break;
            case Properties::Type::Color: {
                auto c = prop.get<mitsuba::Color<double, 3>>();
                const double rgb[3] = {c[0], c[1], c[2]};
                value.kind = ::mf::ParamValue::Kind::Rgb;
                value.rgb = ::mf::Rgb(float(c[0]), float(c[1]), float(c[2]));
                st = mf_params_set_rgb(raw, name.c_str(), rgb);
                break;
            }
            case Properties::Type::Spectrum: {
                auto s = prop.get<Properties::Spectrum>();
                if (!s.is_uniform() || s.values.size() != 1)
                    throw std::runtime_error(what + ": spectra given as wavelength lists are not supported (use rgb)");
                const double rgb[3] = {s.values[0], s.values[0], s.values[0]};
                value.kind = ::mf::ParamValue::Kind::Rgb;
                value.rgb = ::mf::Rgb(float(s.values[0]));
                st = mf_params_set_rgb(raw, name.c_str(), rgb);
                break;
            }
            case Properties::Type::Bool:
                throw std::runtime_error(what + " is a boolean; macrofacet parameters are float, integer, rgb or string");
            default:
                throw std::runtime_error(what + " has type " + std::string(mitsuba::property_type_name(prop.type())) +
                                         "; macrofacet parameters are float, integer, rgb or string");
        }
        if (st != MF_OK) throw std::runtime_error(what + ": " + library_error());
        props.mark_queried(name);
        bag->params.emplace_back(name, value);
    }
    return params;
}

}  // namespace mfmi
