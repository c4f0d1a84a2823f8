// mfhost — the parameters of the library's media (see medium_params.h).
#include "medium_params.h"

#include <macrofacet.h>

#include "library_abi.h"

namespace mf {

namespace {

std::string describe(const MediumParamBag& bag) {
    return "<medium type=\"" + bag.type + "\"" + (bag.id.empty() ? std::string() : " id=\"" + bag.id + "\"") + ">";
}

/// The bag entry a library message refers to: the longest bag name quoted in the message; else
/// the string parameter whose value the message quotes (e.g. `distribution "ggx" has no ...`).
const std::pair<std::string, ParamValue>* param_named_in(const MediumParamBag& bag, const std::string& msg) {
    const std::pair<std::string, ParamValue>* best = nullptr;
    for (const auto& kv : bag.params) {
        if (msg.find("\"" + kv.first + "\"") == std::string::npos) continue;
        if (!best || kv.first.size() > best->first.size()) best = &kv;
    }
    if (best) return best;
    for (const auto& kv : bag.params)
        if (kv.second.kind == ParamValue::Kind::String && msg.find(kv.first) != std::string::npos &&
            msg.find("\"" + kv.second.s + "\"") != std::string::npos)
            return &kv;
    return nullptr;
}

}  // namespace

Error medium_param_error(const MediumParamBag& bag, const std::string& msg) {
    const auto* p = param_named_in(bag, msg);
    return Error(p ? p->second.loc : bag.loc, describe(bag) + ": " + msg);
}

std::string medium_label(const MediumParamBag& bag) {
    const std::string what = describe(bag);
    return bag.loc.str().empty() ? what : bag.loc.str() + ": " + what;
}

ParamsHandle bag_to_params(const MediumParamBag& bag) {
    const std::string what = describe(bag);
    mf_params* raw = nullptr;
    if (mf_params_new(&raw) != MF_OK) throw Error(bag.loc, what + ": " + mf_last_error());
    ParamsHandle params(raw, &mf_params_free);  // freed on every exit, the throws included
    for (const auto& kv : bag.params) {
        const std::string& name = kv.first;
        const ParamValue& v = kv.second;
        mf_status st = MF_OK;
        switch (v.kind) {
            case ParamValue::Kind::Float: st = mf_params_set_float(params.get(), name.c_str(), v.f); break;
            case ParamValue::Kind::Int: st = mf_params_set_float(params.get(), name.c_str(), double(v.i)); break;
            case ParamValue::Kind::Rgb: {
                double c[3] = {v.rgb.r, v.rgb.g, v.rgb.b};
                st = mf_params_set_rgb(params.get(), name.c_str(), c);
                break;
            }
            case ParamValue::Kind::String: st = mf_params_set_string(params.get(), name.c_str(), v.s.c_str()); break;
            case ParamValue::Kind::Bool:
                throw Error(v.loc, what + ": parameter \"" + name + "\" is a boolean; " + bag.type +
                                       " parameters are float, integer, rgb or string");
        }
        if (st != MF_OK) throw Error(v.loc, what + ": parameter \"" + name + "\": " + mf_last_error());
    }
    return params;
}

}  // namespace mf
