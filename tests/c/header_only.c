/* Header-only compile test (C11, -pedantic -Wall -Wextra -Werror): include/macrofacet.h must
 * compile on its own, twice (the include guard), and declare what the ABI promises. Nothing is
 * linked: no function is called, only types, macros and declarations are used. */
#include "macrofacet.h"
#include "macrofacet.h"

/* The result type of mf_phase_sample(); this alias is the one line to adjust if it is renamed. */
typedef mf_phase_sample_result phase_sample_t;

#include <string.h>

_Static_assert(MF_OK == 0, "MF_OK is zero");
_Static_assert(MF_ERROR_NULL_POINTER == 7101 && MF_ERROR_INTERNAL == 7199, "error range 7100-7199");
_Static_assert(sizeof(mf_vec3) == 3 * sizeof(double), "mf_vec3 is three packed doubles");
_Static_assert(MF_PHASE_SAMPLE_DIMENSIONS >= 1, "phase sample dimensions");

/* The declarations have the documented types (a mismatch is a compile error). */
static const char *(*const version_fn)(void) = mf_version;
static mf_status (*const medium_new_fn)(const mf_params *, mf_medium **) = mf_medium_new;
static void (*const medium_free_fn)(mf_medium *) = mf_medium_free;
static mf_status (*const sample_fn)(const mf_medium *, const mf_frame *, mf_vec3, const double *,
                                    phase_sample_t *) = mf_phase_sample;

int main(void) {
  mf_phase_sample_query q;
  memset(&q, 0, sizeof q);
  char version[] = MF_VERSION_STRING;
  int ok = sizeof q.u / sizeof q.u[0] == MF_PHASE_SAMPLE_DIMENSIONS && version[0] != 0 && version_fn != 0 &&
           medium_new_fn != 0 && medium_free_fn != 0 && sample_fn != 0;
  return ok ? 0 : 1;
}
