/* A minimal consumer of the installed library: builds a medium, queries it, frees it. */
#include <macrofacet.h>

#include <math.h>
#include <stdio.h>
#include <string.h>

int main(void) {
  if (strcmp(mf_version(), MF_VERSION_STRING) != 0) {
    fprintf(stderr, "library %s, header %s\n", mf_version(), MF_VERSION_STRING);
    return 1;
  }
  mf_params *params = NULL;
  mf_medium *medium = NULL;
  if (mf_params_new(&params) != MF_OK || mf_params_set_float(params, "sigma", 0.1) != MF_OK ||
      mf_params_set_float(params, "alpha", 0.3) != MF_OK || mf_params_set_string(params, "material", "Au") != MF_OK ||
      mf_medium_new(params, &medium) != MF_OK) {
    char message[256];
    mf_last_error_message(message, sizeof message, NULL);
    fprintf(stderr, "building the medium failed: %s\n", message);
    mf_params_free(params);
    return 1;
  }
  mf_params_free(params);
  const mf_frame frame = {{0, 0, 1}, {1, 0, 0}};
  const mf_vec3 down = {0, 0, -1};
  double transmittance = -1;
  mf_status status = mf_medium_transmittance(medium, &frame, 0.3, down, INFINITY, &transmittance);
  mf_medium_free(medium);
  if (status != MF_OK || transmittance != 0.0) {
    fprintf(stderr, "transmittance into the interior: status %d, %g (expected 0)\n", (int)status, transmittance);
    return 1;
  }
  printf("consumer: macrofacet %s works\n", mf_version());
  return 0;
}
