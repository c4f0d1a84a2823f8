// The installed header in C++ (cpp_compat) with the static library.
#include <macrofacet.h>

#include <cstdio>
#include <memory>

int main() {
  mf_params *raw = nullptr;
  if (mf_params_new(&raw) != MF_OK) return 1;
  std::unique_ptr<mf_params, decltype(&mf_params_free)> params(raw, &mf_params_free);
  mf_medium *medium = nullptr;
  // No sigma: the build must fail with a named parameter.
  if (mf_medium_new(params.get(), &medium) != MF_ERROR_MISSING_PARAMETER || medium != nullptr) return 1;
  char message[256];
  mf_last_error_message(message, sizeof message, nullptr);
  std::printf("consumer (C++): expected error: %s\n", message);
  return 0;
}
