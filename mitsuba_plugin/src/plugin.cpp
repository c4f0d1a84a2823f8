// macrofacet for Mitsuba 3 — the plugin's one translation unit: registers <medium
// type="macrofacet"> for scalar_rgb. The other variants are registered with a constructor that
// raises a clear error: the spectral ones because the library's conductor data and phase
// function are RGB (README "Use in Mitsuba 3"), the LLVM/CUDA ones because their kernels are
// traced symbolically and cannot call the library per query.
#include <mitsuba/core/plugin.h>

#include <stdexcept>
#include <string>
#include <utility>

#include "medium.h"

NAMESPACE_BEGIN(mitsuba)

namespace {

constexpr const char* kUnsupportedVariants[] = {
    "scalar_spectral", "scalar_spectral_polarized", "llvm_ad_rgb",      "llvm_ad_mono",
    "llvm_ad_mono_polarized", "llvm_ad_spectral", "llvm_ad_spectral_polarized", "cuda_ad_rgb",
    "cuda_ad_mono",    "cuda_ad_mono_polarized",    "cuda_ad_spectral", "cuda_ad_spectral_polarized"};

template <size_t I>
ref<Object> unsupported(void*, const Properties&) {
    const std::string v = kUnsupportedVariants[I];
    const bool spectral = v.find("spectral") != std::string::npos && v.rfind("scalar", 0) == 0;
    throw std::runtime_error("<medium type=\"macrofacet\">: the variant \"" + v + "\" is not supported (scalar_rgb only): " +
                             (spectral ? "the library's conductor data and phase function are RGB"
                                       : "this variant traces symbolic kernels, which cannot call the library per query"));
}

template <size_t... I>
void register_unsupported(std::string_view name, PluginRegisterFn fn, std::index_sequence<I...>) {
    (fn(name, kUnsupportedVariants[I], ObjectType::Medium, &unsupported<I>), ...);
}

}  // namespace

extern "C" MI_EXPORT void init_plugin(std::string_view name, PluginRegisterFn fn) {
    using ScalarRgbMedium = mfmi::MacrofacetMedium<float, Color<float, 3>>;
    fn(name, "scalar_rgb", ObjectType::Medium, [](void*, const Properties& props) -> ref<Object> { return new ScalarRgbMedium(props); });
    register_unsupported(name, fn, std::make_index_sequence<std::size(kUnsupportedVariants)>{});
}

NAMESPACE_END(mitsuba)
