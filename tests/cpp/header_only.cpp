// Header-only compile test (C++17, -pedantic -Wall -Wextra -Werror): include/macrofacet.h must
// compile on its own in C++, twice (the include guard), with C linkage for the functions
// (cpp_compat); nothing is linked or called.
#include "macrofacet.h"
#include "macrofacet.h"

// The result type of mf_phase_sample().
typedef mf_phase_sample_result phase_sample_t;

#include <cstring>
#include <type_traits>

static_assert(MF_OK == 0, "MF_OK is zero");
static_assert(std::is_trivially_copyable_v<mf_flight_query> && std::is_standard_layout_v<mf_flight_query>,
              "query structs are plain C data");
static_assert(std::is_standard_layout_v<phase_sample_t>, "the phase sample is plain C data");
static_assert(std::is_same_v<decltype(&mf_phase_sample),
                             mf_status (*)(const mf_medium *, const mf_frame *, mf_vec3, const double *, phase_sample_t *)>,
              "mf_phase_sample signature");
static_assert(std::is_same_v<decltype(&mf_medium_sigma_t),
                             mf_status (*)(const mf_medium *, const mf_frame *, double, mf_vec3, double *)>,
              "mf_medium_sigma_t signature");
static_assert(std::is_same_v<decltype(&mf_phase_eval_batch),
                             mf_status (*)(const mf_medium *, const mf_phase_query *, size_t, mf_phase_value *)>,
              "mf_phase_eval_batch signature");
static_assert(std::is_same_v<decltype(&mf_status_str), const char *(*)(int32_t)>, "mf_status_str signature");

int main() {
  mf_frame frame{{0.0, 0.0, 1.0}, {1.0, 0.0, 0.0}};
  return std::strlen(MF_VERSION_STRING) > 0 && frame.normal.z == 1.0 ? 0 : 1;
}
