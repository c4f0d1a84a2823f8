// mfhost — the phase-2 hook for macrofacet / GP-implicit-surface media.
//
// Phase 2 replaces this function: convert `bag` into the Rust library's parameter set through
// its mf_params_* C API, build the medium, and return a Medium subclass whose free-flight and
// transmittance routines query `shape->sdf(p)` for the signed distance f and its gradient.
#include "medium.h"
#include "shape.h"

namespace mf {

std::shared_ptr<Medium> create_macrofacet_medium(const MediumParamBag& bag, const std::shared_ptr<const Shape>& shape) {
    (void)shape;
    throw Error(bag.loc, "<medium type=\"" + bag.type + "\"" + (bag.id.empty() ? std::string() : " id=\"" + bag.id + "\"") +
                             ">: macrofacet media need phase 2 (the Rust macrofacet library is not linked into this "
                             "mfrender build yet); the scene was parsed but cannot be rendered");
}

}  // namespace mf
