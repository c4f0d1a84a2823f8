/* C ABI test of libmacrofacet: calls every function declared in include/macrofacet.h (the test
 * `abi_test_covers_header` fails when a declared function is not called here), each at least once
 * with valid and with invalid arguments. It tests the ABI, not the physics: the physics is checked
 * by the Rust tests (the .rs files in tests/), and tests/ffi_abi.rs checks that every FFI result equals the
 * core's bit for bit.
 *
 * What it checks:
 *  - Struct layout: sizes and offsets equal the numbers tests/ffi_abi.rs checks on the Rust side
 *    (exact: a layout mismatch is an ABI break).
 *  - Conventions: mf_version() == MF_VERSION_STRING == MAJOR.MINOR.PATCH; every status has its own
 *    description and unknown codes give "unknown status"; mf_last_error_message with any buffer
 *    (length query, truncation, size 1, NULL); for every entry point and every kind of bad argument
 *    (NULL handle / out-pointer / frame / u, NaN and non-unit directions, NaN or infinite f,
 *    negative t, u outside [0,1)) the exact status, a message naming the problem and the
 *    out-parameter untouched (pre-filled sentinel bytes); *_free(NULL) is a no-op and every handle
 *    created is freed (the ASan build checks for leaks).
 *  - Parameters by name: every construction route of the parameter table builds, the kernel form
 *    equals the roughness form bit for bit, every way construction fails (unknown name, wrong
 *    type, missing, conflicting, out of range) gives its status and names the parameter.
 *  - Outputs within their documented ranges; phase samples consistent across entry points
 *    (pdf == mf_phase_pdf, weight == eval / pdf, 1e-9: wo is re-reflected and the half vector
 *    recomputed); conductor weights equal a complex-arithmetic Fresnel written here (1e-10: it
 *    also checks that eta/k set by name reach each channel).
 *  - A few values against numbers printed once from the Rust core (1e-12 relative: the same code
 *    runs, but another libm may round exp/log differently in the last place): catches ABI-level
 *    breakage (argument order, struct layout) that a self-consistent test would miss.
 *  - Batches equal single calls bit for bit and are validated before anything is written.
 *  - Callbacks (host surfaces and segment bounds, fields, the gpis signed distance), including
 *    callbacks that fail or answer NaN: reported at their first bad answer with a status.
 */
#include "macrofacet.h"

/* The result type of mf_phase_sample(); this alias is the one line to adjust if it is renamed. */
typedef mf_phase_sample_result phase_sample_t;

#include <complex.h>
#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Strict C11 has no PI; SQRT2 is the double nearest sqrt(2), as Rust's SQRT_2. */
#define PI 3.14159265358979323846
#define SQRT2 1.41421356237309504880

/* ------------------------------------------------------------------------------ harness */

static int g_failures = 0;
static int g_checks = 0;

#define CHECK(cond, ...)                                                                    \
  do {                                                                                      \
    ++g_checks;                                                                             \
    if (!(cond)) {                                                                          \
      ++g_failures;                                                                         \
      fprintf(stderr, "%s:%d: CHECK(%s) failed: ", __FILE__, __LINE__, #cond);              \
      fprintf(stderr, __VA_ARGS__);                                                         \
      fputc('\n', stderr);                                                                  \
    }                                                                                       \
  } while (0)

static const char *last_error(void) {
  static char buf[1024];
  size_t len = 0;
  buf[0] = 'X';
  buf[1] = 0;
  mf_status s = mf_last_error_message(buf, sizeof buf, &len);
  if (s != MF_OK) {
    return "<mf_last_error_message failed>";
  }
  return buf;
}

/* Checks status and, for an error, that the thread's last message contains `needle`. */
static void expect_status_at(const char *file, int line, const char *what, mf_status got, mf_status want,
                             const char *needle) {
  ++g_checks;
  if (got != want) {
    ++g_failures;
    fprintf(stderr, "%s:%d: %s: status %d (%s), expected %d (%s); last error: \"%s\"\n", file, line, what,
            (int)got, mf_status_str(got), (int)want, mf_status_str(want), last_error());
    return;
  }
  if (want != MF_OK && needle != NULL) {
    const char *msg = last_error();
    ++g_checks;
    if (strstr(msg, needle) == NULL) {
      ++g_failures;
      fprintf(stderr, "%s:%d: %s: message \"%s\" does not mention \"%s\"\n", file, line, what, msg, needle);
    }
  }
}
#define EXPECT_STATUS(call, want, needle) expect_status_at(__FILE__, __LINE__, #call, (call), (want), (needle))
#define EXPECT_OK(call) expect_status_at(__FILE__, __LINE__, #call, (call), MF_OK, NULL)

static int close_rel(double a, double b, double rel) {
  if (a == b) return 1;
  double scale = fabs(b) > 1e-300 ? fabs(b) : 1e-300;
  return fabs(a - b) <= rel * scale;
}
#define CHECK_REL(a, b, rel)                                                                           \
  CHECK(close_rel((a), (b), (rel)), "%s = %.17g, %s = %.17g, relative difference %.3g > %.1g", #a, (double)(a), \
        #b, (double)(b), fabs((double)(a) - (double)(b)) / fabs((double)(b)), (double)(rel))
#define CHECK_ABS(a, b, tol)                                                                                  \
  CHECK(fabs((a) - (b)) <= (tol), "%s = %.17g, %s = %.17g, difference %.3g > %.1g", #a, (double)(a), #b, \
        (double)(b), fabs((double)(a) - (double)(b)), (double)(tol))

static int same_bits(const void *a, const void *b, size_t n) { return memcmp(a, b, n) == 0; }

/* A deterministic generator (splitmix64): uniforms in [0, 1) with 53 bits. */
static uint64_t g_rng = 0x9E3779B97F4A7C15ull;
static double uniform01(void) {
  uint64_t z = (g_rng += 0x9E3779B97F4A7C15ull);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  z ^= z >> 31;
  return (double)(z >> 11) * 0x1.0p-53;
}

/* ------------------------------------------------------------------------------ vectors */

static mf_vec3 v3(double x, double y, double z) {
  mf_vec3 v = {x, y, z};
  return v;
}
static double dot(mf_vec3 a, mf_vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
static mf_vec3 scale(mf_vec3 a, double s) { return v3(a.x * s, a.y * s, a.z * s); }
static mf_vec3 add(mf_vec3 a, mf_vec3 b) { return v3(a.x + b.x, a.y + b.y, a.z + b.z); }
static mf_vec3 normalize(mf_vec3 a) { return scale(a, 1.0 / sqrt(dot(a, a))); }
static mf_vec3 cross(mf_vec3 a, mf_vec3 b) {
  return v3(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);
}

/* The orthonormal frame the library builds from an mf_frame (normal normalised, tangent made
 * orthogonal), reproduced here for the analytic checks. */
typedef struct basis {
  mf_vec3 s, t, n;
} basis;
static basis basis_of(mf_frame f) {
  basis b;
  b.n = normalize(f.normal);
  b.s = normalize(add(f.tangent, scale(b.n, -dot(b.n, f.tangent))));
  b.t = cross(b.n, b.s);
  return b;
}
static mf_vec3 to_world(basis b, mf_vec3 l) { return add(add(scale(b.s, l.x), scale(b.t, l.y)), scale(b.n, l.z)); }
static mf_vec3 to_local(basis b, mf_vec3 w) { return v3(dot(w, b.s), dot(w, b.t), dot(w, b.n)); }
static mf_vec3 spherical(double theta, double phi) {
  return v3(sin(theta) * cos(phi), sin(theta) * sin(phi), cos(theta));
}

static const mf_frame FRAME_Z = {{0.0, 0.0, 1.0}, {1.0, 0.0, 0.0}};
/* A tilted frame given unnormalised: n = (1,2,2)/3, tangent (2,1,-2)/3 (orthogonal). */
static const mf_frame FRAME_TILTED = {{1.0, 2.0, 2.0}, {2.0, 1.0, -2.0}};

/* ------------------------------------------------------------------------------ Fresnel */

/* Unpolarised Fresnel reflectance of a conductor, from complex amplitudes (n = eta + i k). It stays
 * here because it checks that eta and k set by name reach each colour channel of the flakes, and
 * because no Rust test compares src/fresnel.rs with an independent formula exactly (the Heitz walk
 * of tests/heitz_random_walk.rs does so only statistically, through gold's per-channel albedo). */
static double fresnel_conductor(double cos_i, double eta, double k) {
  double complex n = eta + k * I;
  double complex n2 = n * n;
  double sin2 = 1.0 - cos_i * cos_i;
  double complex root = csqrt(n2 - sin2);
  double complex rs = (cos_i - root) / (cos_i + root);
  double complex rp = (n2 * cos_i - root) / (n2 * cos_i + root);
  double as = cabs(rs), ap = cabs(rp);
  return 0.5 * (as * as + ap * ap);
}

/* ------------------------------------------------------------------------------ media */

typedef struct named_float {
  const char *name;
  double value;
} named_float;

/* Builds a medium from float, rgb and string parameters; NULL-terminated lists. */
static mf_medium *build(const named_float *floats, const char *const *strings, const char *rgb_name,
                        const double *rgb, const char *rgb_name2, const double *rgb2) {
  mf_params *p = NULL;
  mf_medium *m = NULL;
  EXPECT_OK(mf_params_new(&p));
  for (; floats && floats->name; ++floats) EXPECT_OK(mf_params_set_float(p, floats->name, floats->value));
  for (; strings && strings[0]; strings += 2) EXPECT_OK(mf_params_set_string(p, strings[0], strings[1]));
  if (rgb_name) EXPECT_OK(mf_params_set_rgb(p, rgb_name, rgb));
  if (rgb_name2) EXPECT_OK(mf_params_set_rgb(p, rgb_name2, rgb2));
  EXPECT_OK(mf_medium_new(p, &m));
  mf_params_free(p);
  CHECK(m != NULL, "medium not built: %s", last_error());
  return m;
}

static const double GPSS_ALPHA[3] = {0.3, 0.6, 0.4};
static const double GPSS_SIGMA = 0.5;
static const double COND_ETA[3] = {0.2, 0.9, 1.1};
static const double COND_K[3] = {3.9, 2.4, 2.1};

/* The main test medium: generalized macrofacet, conductor flakes, shell extent 8. */
static mf_medium *gpss_conductor(void) {
  const named_float f[] = {{"sigma", GPSS_SIGMA}, {"shell_extent", 8.0},      {"alpha_u", GPSS_ALPHA[0]},
                           {"alpha_v", GPSS_ALPHA[1]}, {"alpha_z", GPSS_ALPHA[2]}, {NULL, 0}};
  return build(f, NULL, "eta", COND_ETA, "k", COND_K);
}

/* ------------------------------------------------------------------------------ tests */

/* Layout shared with Rust (tests/ffi_abi.rs asserts the same numbers with offset_of!). */
_Static_assert(sizeof(mf_vec3) == 24 && offsetof(mf_vec3, y) == 8 && offsetof(mf_vec3, z) == 16, "mf_vec3");
_Static_assert(sizeof(mf_rgb) == 24 && offsetof(mf_rgb, g) == 8 && offsetof(mf_rgb, b) == 16, "mf_rgb");
_Static_assert(sizeof(mf_frame) == 48 && offsetof(mf_frame, tangent) == 24, "mf_frame");
_Static_assert(sizeof(mf_free_flight) == 16 && offsetof(mf_free_flight, t) == 8, "mf_free_flight");
_Static_assert(sizeof(phase_sample_t) == 64 && offsetof(phase_sample_t, weight) == 24 &&
                   offsetof(phase_sample_t, pdf) == 48 && offsetof(phase_sample_t, valid) == 56,
               "phase_sample_t");
_Static_assert(sizeof(mf_flight_query) == 96 && offsetof(mf_flight_query, f) == 48 &&
                   offsetof(mf_flight_query, d) == 56 && offsetof(mf_flight_query, t_max) == 80 &&
                   offsetof(mf_flight_query, u) == 88,
               "mf_flight_query");
_Static_assert(sizeof(mf_phase_query) == 96 && offsetof(mf_phase_query, wi) == 48 && offsetof(mf_phase_query, wo) == 72,
               "mf_phase_query");
_Static_assert(sizeof(mf_phase_value) == 32 && offsetof(mf_phase_value, pdf) == 24, "mf_phase_value");
_Static_assert(sizeof(mf_phase_sample_query) == 112 && offsetof(mf_phase_sample_query, wi) == 48 &&
                   offsetof(mf_phase_sample_query, u) == 72,
               "mf_phase_sample_query");
_Static_assert(sizeof(mf_status) == 4, "mf_status is a C int-sized enum");
_Static_assert(MF_PHASE_SAMPLE_DIMENSIONS == 5, "phase sample dimensions");
_Static_assert(sizeof(mf_ndf_sample) == 40 && offsetof(mf_ndf_sample, pdf) == 24 && offsetof(mf_ndf_sample, valid) == 32,
               "mf_ndf_sample");
_Static_assert(MF_NDF_SAMPLE_DIMENSIONS == 3, "ndf sample dimensions");

static void test_version_and_status(void) {
  const char *v = mf_version();
  CHECK(v != NULL && strcmp(v, MF_VERSION_STRING) == 0, "mf_version() = %s, header %s", v ? v : "(null)",
        MF_VERSION_STRING);
  char expected[64];
  snprintf(expected, sizeof expected, "%d.%d.%d", MF_VERSION_MAJOR, MF_VERSION_MINOR, MF_VERSION_PATCH);
  CHECK(strcmp(MF_VERSION_STRING, expected) == 0, "MF_VERSION_STRING %s vs macros %s", MF_VERSION_STRING, expected);

  const mf_status all[] = {MF_OK,
                           MF_ERROR_NULL_POINTER,
                           MF_ERROR_INVALID_ARGUMENT,
                           MF_ERROR_UNKNOWN_PARAMETER,
                           MF_ERROR_WRONG_TYPE,
                           MF_ERROR_MISSING_PARAMETER,
                           MF_ERROR_INVALID_VALUE,
                           MF_ERROR_INVALID_UTF8,
                           MF_ERROR_CALLBACK,
                           MF_ERROR_INTERNAL};
  const size_t n = sizeof all / sizeof all[0];
  CHECK(MF_OK == 0, "MF_OK must be 0");
  for (size_t i = 0; i < n; ++i) {
    const char *s = mf_status_str(all[i]);
    CHECK(s != NULL && s[0] != 0, "status %d has no description", (int)all[i]);
    CHECK(s != NULL && strcmp(s, "unknown status") != 0, "status %d described as unknown", (int)all[i]);
    if (i > 0) CHECK((int)all[i] >= 7100 && (int)all[i] <= 7199, "error %d outside 7100-7199", (int)all[i]);
    for (size_t j = 0; j < i; ++j) {
      CHECK(strcmp(s, mf_status_str(all[j])) != 0, "statuses %d and %d share a description", (int)all[i],
            (int)all[j]);
    }
  }
  CHECK(strcmp(mf_status_str(MF_OK), "success") == 0, "MF_OK: %s", mf_status_str(MF_OK));
  /* Values that are not enumerators (valid in C: the enum is an integer type). */
  const int unknown[] = {1, 7100, 7109, 7150, 7198, 7200, 4242};
  for (size_t i = 0; i < sizeof unknown / sizeof unknown[0]; ++i) {
    const char *s = mf_status_str((mf_status)unknown[i]);
    CHECK(s != NULL && strcmp(s, "unknown status") == 0, "mf_status_str(%d) = \"%s\"", unknown[i], s ? s : "(null)");
  }
}

static void test_last_error_message(void) {
  /* Nothing has failed on this thread yet: empty message, length 0. */
  char buf[64];
  size_t len = 99;
  memset(buf, 'X', sizeof buf);
  EXPECT_OK(mf_last_error_message(buf, sizeof buf, &len));
  CHECK(buf[0] == 0 && len == 0, "fresh thread: \"%s\" (len %zu)", buf, len);

  /* Produce an error and read it back in every way. */
  EXPECT_STATUS(mf_params_new(NULL), MF_ERROR_NULL_POINTER, "out_params");
  const char *full = "out_params must not be NULL";
  size_t full_len = strlen(full);
  len = 0;
  EXPECT_OK(mf_last_error_message(NULL, 0, &len)); /* length query */
  CHECK(len == full_len, "length query gave %zu, expected %zu", len, full_len);
  memset(buf, 'X', sizeof buf);
  EXPECT_OK(mf_last_error_message(buf, sizeof buf, &len));
  CHECK(strcmp(buf, full) == 0 && len == full_len, "message \"%s\" (len %zu)", buf, len);
  memset(buf, 'X', sizeof buf);
  EXPECT_OK(mf_last_error_message(buf, 5, &len)); /* truncated to 4 bytes + NUL */
  CHECK(memcmp(buf, "out_", 4) == 0 && buf[4] == 0 && buf[5] == 'X' && len == full_len,
        "truncated message \"%s\" (len %zu)", buf, len);
  memset(buf, 'X', sizeof buf);
  EXPECT_OK(mf_last_error_message(buf, 1, NULL)); /* only the NUL fits; out_len may be NULL */
  CHECK(buf[0] == 0 && buf[1] == 'X', "len 1 must write only the NUL");
  len = 12345;
  EXPECT_STATUS(mf_last_error_message(NULL, 8, &len), MF_ERROR_NULL_POINTER, NULL);
  CHECK(len == 12345, "out_len written on failure: %zu", len);
  /* A successful call does not clear the message (it is the last *failing* call's). */
  mf_params *p = NULL;
  EXPECT_OK(mf_params_new(&p));
  CHECK(strcmp(last_error(), full) == 0, "message after a successful call: \"%s\"", last_error());
  mf_params_free(p);
}

static void test_params_errors(void) {
  mf_params *p = NULL;
  EXPECT_OK(mf_params_new(&p));
  const double rgb[3] = {0.5, 0.5, 0.5};
  const double rgb_nan[3] = {0.5, NAN, 0.5};

  EXPECT_STATUS(mf_params_set_float(NULL, "sigma", 1.0), MF_ERROR_NULL_POINTER, "params");
  EXPECT_STATUS(mf_params_set_float(p, NULL, 1.0), MF_ERROR_NULL_POINTER, "name");
  EXPECT_STATUS(mf_params_set_float(p, "sigma", NAN), MF_ERROR_INVALID_VALUE, "finite");
  EXPECT_STATUS(mf_params_set_float(p, "sigma", INFINITY), MF_ERROR_INVALID_VALUE, "finite");
  EXPECT_STATUS(mf_params_set_float(p, "\xff\xfe", 1.0), MF_ERROR_INVALID_UTF8, "name");

  EXPECT_STATUS(mf_params_set_rgb(NULL, "eta", rgb), MF_ERROR_NULL_POINTER, "params");
  EXPECT_STATUS(mf_params_set_rgb(p, NULL, rgb), MF_ERROR_NULL_POINTER, "name");
  EXPECT_STATUS(mf_params_set_rgb(p, "eta", NULL), MF_ERROR_NULL_POINTER, "rgb");
  EXPECT_STATUS(mf_params_set_rgb(p, "eta", rgb_nan), MF_ERROR_INVALID_VALUE, "finite");

  EXPECT_STATUS(mf_params_set_string(NULL, "distribution", "ggx"), MF_ERROR_NULL_POINTER, "params");
  EXPECT_STATUS(mf_params_set_string(p, NULL, "ggx"), MF_ERROR_NULL_POINTER, "name");
  EXPECT_STATUS(mf_params_set_string(p, "distribution", NULL), MF_ERROR_NULL_POINTER, "value");
  EXPECT_STATUS(mf_params_set_string(p, "distribution", "gg\xc3"), MF_ERROR_INVALID_UTF8, "value");

  /* None of the failed calls stored anything: the set is still empty, so building a medium
   * reports the missing sigma (and not, e.g., a wrong "distribution"). */
  mf_medium *sentinel = (mf_medium *)(uintptr_t)0x5EAF00D;
  mf_medium *m = sentinel;
  EXPECT_STATUS(mf_medium_new(p, &m), MF_ERROR_MISSING_PARAMETER, "sigma");
  CHECK(m == sentinel, "out_medium written on failure");
  mf_params_free(p);

  mf_params_free(NULL); /* no-op */
  mf_medium_free(NULL); /* no-op */
}

/* One failing construction: the status, the message and an untouched out-parameter. */
typedef struct bad_build {
  const char *what;
  named_float floats[6];
  const char *strings[8];
  const char *rgb_name;
  double rgb[3];
  mf_status status;
  const char *needle;
} bad_build;

static void test_medium_new_errors(void) {
  const bad_build cases[] = {
      {"no sigma", {{"alpha", 0.3}}, {NULL}, NULL, {0}, MF_ERROR_MISSING_PARAMETER, "sigma"},
      {"negative sigma", {{"sigma", -1.0}, {"alpha", 0.3}}, {NULL}, NULL, {0}, MF_ERROR_INVALID_VALUE, "sigma"},
      {"zero variance", {{"variance", 0.0}, {"alpha", 0.3}}, {NULL}, NULL, {0}, MF_ERROR_INVALID_VALUE, "variance"},
      {"sigma and variance", {{"sigma", 1.0}, {"variance", 1.0}, {"alpha", 0.3}}, {NULL}, NULL, {0},
       MF_ERROR_MISSING_PARAMETER, "variance"},
      {"unknown name", {{"sigma", 1.0}, {"alpha", 0.3}, {"sigmaa", 1.0}}, {NULL}, NULL, {0},
       MF_ERROR_UNKNOWN_PARAMETER, "sigmaa"},
      {"wrong type (string for float)", {{"alpha", 0.3}}, {"sigma", "1.0", NULL}, NULL, {0}, MF_ERROR_WRONG_TYPE,
       "sigma"},
      {"wrong type (float for string)", {{"sigma", 1.0}, {"alpha", 0.3}, {"distribution", 1.0}}, {NULL}, NULL, {0},
       MF_ERROR_WRONG_TYPE, "distribution"},
      {"wrong type (rgb for float)", {{"sigma", 1.0}}, {NULL}, "alpha", {0.1, 0.2, 0.3}, MF_ERROR_WRONG_TYPE, "alpha"},
      {"unknown distribution", {{"sigma", 1.0}, {"alpha", 0.3}}, {"distribution", "phong", NULL}, NULL, {0},
       MF_ERROR_INVALID_VALUE, "distribution"},
      {"no roughness", {{"sigma", 1.0}}, {NULL}, NULL, {0}, MF_ERROR_MISSING_PARAMETER, "alpha"},
      {"negative alpha", {{"sigma", 1.0}, {"alpha", -0.3}}, {"distribution", "ggx", NULL}, NULL, {0},
       MF_ERROR_INVALID_VALUE, "alpha"},
      {"alpha_z on beckmann", {{"sigma", 1.0}, {"alpha", 0.3}, {"alpha_z", 0.3}}, {"distribution", "beckmann", NULL},
       NULL, {0}, MF_ERROR_UNKNOWN_PARAMETER, "alpha_z"},
      {"gpss anisotropic without alpha_z", {{"sigma", 1.0}, {"alpha_u", 0.3}, {"alpha_v", 0.2}}, {NULL}, NULL, {0},
       MF_ERROR_MISSING_PARAMETER, "alpha_z"},
      {"alpha and lengthscale", {{"sigma", 1.0}, {"alpha", 0.3}, {"lengthscale", 2.0}}, {NULL}, NULL, {0},
       MF_ERROR_MISSING_PARAMETER, "lengthscale"},
      {"negative lengthscale", {{"sigma", 1.0}, {"lengthscale", -2.0}}, {NULL}, NULL, {0}, MF_ERROR_INVALID_VALUE,
       "lengthscale"},
      {"negative shell_extent", {{"sigma", 1.0}, {"alpha", 0.3}, {"shell_extent", -1.0}}, {NULL}, NULL, {0},
       MF_ERROR_INVALID_VALUE, "shell_extent"},
      {"unknown micro_bsdf", {{"sigma", 1.0}, {"alpha", 0.3}}, {"micro_bsdf", "glass", NULL}, NULL, {0},
       MF_ERROR_INVALID_VALUE, "micro_bsdf"},
      {"unknown material", {{"sigma", 1.0}, {"alpha", 0.3}}, {"material", "Unobtainium", NULL}, NULL, {0},
       MF_ERROR_INVALID_VALUE, "material"},
      {"eta without k", {{"sigma", 1.0}, {"alpha", 0.3}}, {NULL}, "eta", {0.2, 0.9, 1.1}, MF_ERROR_MISSING_PARAMETER,
       "\"k\""},
      {"material and eta", {{"sigma", 1.0}, {"alpha", 0.3}}, {"material", "Au", NULL}, "eta", {0.2, 0.9, 1.1},
       MF_ERROR_MISSING_PARAMETER, "material"},
      {"reflectance > 1", {{"sigma", 1.0}, {"alpha", 0.3}}, {"micro_bsdf", "diffuse", NULL}, "reflectance",
       {0.5, 1.5, 0.5}, MF_ERROR_INVALID_VALUE, "reflectance"},
      {"negative specular_reflectance", {{"sigma", 1.0}, {"alpha", 0.3}}, {NULL}, "specular_reflectance",
       {0.5, -0.5, 0.5}, MF_ERROR_INVALID_VALUE, "specular_reflectance"},
      {"reflectance on a conductor", {{"sigma", 1.0}, {"alpha", 0.3}}, {NULL}, "reflectance", {0.5, 0.5, 0.5},
       MF_ERROR_UNKNOWN_PARAMETER, "reflectance"},
      {"mixture_ratio 1 on ggx (Appendix B)", {{"sigma", 1.0}, {"alpha", 0.3}, {"mixture_ratio", 1.0}},
       {"distribution", "ggx", "vndf_sampling", "mixture", NULL}, NULL, {0}, MF_ERROR_INVALID_VALUE, "mixture_ratio"},
      {"mixture with diffuse flakes", {{"sigma", 1.0}, {"alpha", 0.3}},
       {"micro_bsdf", "diffuse", "vndf_sampling", "mixture", NULL}, NULL, {0}, MF_ERROR_INVALID_VALUE, "mixture"},
      {"mixture_ratio out of (0,1)", {{"sigma", 1.0}, {"alpha", 0.3}, {"mixture_ratio", 1.5}},
       {"vndf_sampling", "mixture", NULL}, NULL, {0}, MF_ERROR_INVALID_VALUE, "mixture_ratio"},
      {"mixture_ratio without mixture", {{"sigma", 1.0}, {"alpha", 0.3}, {"mixture_ratio", 0.5}}, {NULL}, NULL, {0},
       MF_ERROR_UNKNOWN_PARAMETER, "mixture_ratio"},
      {"unknown vndf_sampling", {{"sigma", 1.0}, {"alpha", 0.3}}, {"vndf_sampling", "magic", NULL}, NULL, {0},
       MF_ERROR_INVALID_VALUE, "vndf_sampling"},
  };
  for (size_t i = 0; i < sizeof cases / sizeof cases[0]; ++i) {
    const bad_build *c = &cases[i];
    mf_params *p = NULL;
    EXPECT_OK(mf_params_new(&p));
    for (const named_float *f = c->floats; f->name; ++f) EXPECT_OK(mf_params_set_float(p, f->name, f->value));
    for (const char *const *s = c->strings; s[0]; s += 2) EXPECT_OK(mf_params_set_string(p, s[0], s[1]));
    if (c->rgb_name) EXPECT_OK(mf_params_set_rgb(p, c->rgb_name, c->rgb));
    mf_medium *sentinel = (mf_medium *)(uintptr_t)0xBADC0DE;
    mf_medium *m = sentinel;
    mf_status s = mf_medium_new(p, &m);
    ++g_checks;
    if (s != c->status || strstr(last_error(), c->needle) == NULL) {
      ++g_failures;
      fprintf(stderr, "mf_medium_new (%s): status %d, expected %d; message \"%s\" should mention %s\n", c->what,
              (int)s, (int)c->status, last_error(), c->needle);
    }
    CHECK(m == sentinel, "%s: out_medium written on failure", c->what);
    if (m != sentinel) mf_medium_free(m);
    mf_params_free(p);
  }

  /* NULL handle and NULL out-pointer. */
  mf_params *p = NULL;
  EXPECT_OK(mf_params_new(&p));
  EXPECT_OK(mf_params_set_float(p, "sigma", 1.0));
  EXPECT_OK(mf_params_set_float(p, "alpha", 0.3));
  mf_medium *sentinel = (mf_medium *)(uintptr_t)0xBADC0DE;
  mf_medium *m = sentinel;
  EXPECT_STATUS(mf_medium_new(NULL, &m), MF_ERROR_NULL_POINTER, "params");
  CHECK(m == sentinel, "out_medium written on failure");
  EXPECT_STATUS(mf_medium_new(p, NULL), MF_ERROR_NULL_POINTER, "out_medium");
  /* The set survives failed builds and can still build a medium; setting a name again replaces
   * its value (sigma 1 -> 0.5; default shell extent 3 gives top = 1.5). */
  EXPECT_OK(mf_params_set_float(p, "sigma", 0.5));
  EXPECT_OK(mf_medium_new(p, &m));
  mf_params_free(p); /* the medium does not depend on the parameter set */
  double top = -1.0;
  EXPECT_OK(mf_medium_shell_top(m, &top));
  CHECK(top == 1.5, "top = %.17g, expected 3 * 0.5", top);
  mf_medium_free(m);
}

/* Every construction route of the parameter table builds. */
static void test_medium_variants(void) {
  const char *presets[] = {"none", "Ag", "Al", "Au", "Cr", "Cu"};
  for (size_t i = 0; i < sizeof presets / sizeof presets[0]; ++i) {
    const named_float f[] = {{"sigma", 0.1}, {"alpha", 0.2}, {NULL, 0}};
    const char *s[] = {"material", presets[i], NULL};
    mf_medium *m = build(f, s, NULL, NULL, NULL, NULL);
    mf_rgb v = {-1, -1, -1};
    EXPECT_OK(mf_phase_eval(m, &FRAME_Z, v3(0, 0, 1), v3(0, 0.6, 0.8), &v));
    CHECK(v.r > 0 && v.g > 0 && v.b > 0, "%s: phase value %g %g %g", presets[i], v.r, v.g, v.b);
    mf_medium_free(m);
  }
  const char *dists[] = {"beckmann", "ggx", "gpss"};
  for (size_t i = 0; i < 3; ++i) {
    const named_float f[] = {{"variance", 0.01}, {"alpha_u", 0.2}, {"alpha_v", 0.4}, {NULL, 0}};
    const named_float fz[] = {{"variance", 0.01}, {"alpha_u", 0.2}, {"alpha_v", 0.4}, {"alpha_z", 0.0}, {NULL, 0}};
    const char *s[] = {"distribution", dists[i], "vndf_sampling", "exact", NULL};
    mf_medium *m = build(i == 2 ? fz : f, s, "specular_reflectance", (const double[3]){0.9, 0.8, 0.7}, NULL, NULL);
    mf_medium_free(m);
  }

  /* Kernel form: alpha_i = sqrt(2) sigma / l_i (seeds/000 Eq. 4). The same medium given by alphas computed
   * here with the same IEEE operations answers bit for bit the same. */
  const double var = 0.04, lx = 0.5, ly = 0.7, lz = 1.3;
  const double sigma = sqrt(var);
  const named_float fk[] = {{"variance", var}, {"lengthscale_x", lx}, {"lengthscale_y", ly}, {"lengthscale_z", lz},
                            {NULL, 0}};
  const named_float fa[] = {{"sigma", sigma},
                            {"alpha_u", SQRT2 * sigma / lx},
                            {"alpha_v", SQRT2 * sigma / ly},
                            {"alpha_z", SQRT2 * sigma / lz},
                            {NULL, 0}};
  mf_medium *mk = build(fk, (const char *[]){"material", "Cu", NULL}, NULL, NULL, NULL, NULL);
  mf_medium *ma = build(fa, (const char *[]){"material", "Cu", NULL}, NULL, NULL, NULL, NULL);
  mf_vec3 d = normalize(v3(0.3, -0.2, -0.9));
  mf_vec3 wi = normalize(v3(0.1, 0.5, 0.8)), wo = normalize(v3(-0.4, 0.1, 0.6));
  double sk = -1, sa = -2;
  EXPECT_OK(mf_medium_sigma_t(mk, &FRAME_TILTED, 0.05, d, &sk));
  EXPECT_OK(mf_medium_sigma_t(ma, &FRAME_TILTED, 0.05, d, &sa));
  CHECK(sk == sa && sk > 0, "kernel form sigma_t %.17g vs alpha form %.17g", sk, sa);
  mf_rgb pk, pa;
  EXPECT_OK(mf_phase_eval(mk, &FRAME_TILTED, wi, wo, &pk));
  EXPECT_OK(mf_phase_eval(ma, &FRAME_TILTED, wi, wo, &pa));
  CHECK(same_bits(&pk, &pa, sizeof pk), "kernel form phase %.17g vs %.17g", pk.r, pa.r);
  mf_medium_free(mk);
  mf_medium_free(ma);
  /* An isotropic kernel: lengthscale sets alpha_u = alpha_v = alpha_z. */
  const named_float fi[] = {{"sigma", 0.2}, {"lengthscale", 0.5}, {NULL, 0}};
  const named_float fi2[] = {{"sigma", 0.2}, {"alpha", SQRT2 * 0.2 / 0.5}, {NULL, 0}};
  mf_medium *mi = build(fi, NULL, NULL, NULL, NULL, NULL);
  mf_medium *mi2 = build(fi2, NULL, NULL, NULL, NULL, NULL);
  EXPECT_OK(mf_medium_sigma_t(mi, &FRAME_Z, 0.0, d, &sk));
  EXPECT_OK(mf_medium_sigma_t(mi2, &FRAME_Z, 0.0, d, &sa));
  CHECK(sk == sa, "isotropic kernel %.17g vs alpha %.17g", sk, sa);
  mf_medium_free(mi);
  mf_medium_free(mi2);
}

/* The ranges every medium query promises after MF_OK (README "Fuzzing"): sigma_t, the majorant
 * and the optical depth are finite and >= 0, the majorant bounds sigma_t at both ends, the
 * transmittance lies in [0, 1], a free flight stops in [0, t_max]. The values themselves are the
 * core's (tests/ffi_abi.rs compares them bit for bit; tests/free_flight.rs checks the physics). */
static void test_query_ranges(void) {
  mf_medium *m = gpss_conductor();
  double top = 0;
  EXPECT_OK(mf_medium_shell_top(m, &top));
  CHECK(top == 8.0 * GPSS_SIGMA, "top %.17g, expected shell_extent * sigma", top);
  const mf_frame *frames[2] = {&FRAME_Z, &FRAME_TILTED};
  const double fs[] = {-1.3, 0.0, 1.2, top + 0.1};
  for (int fi = 0; fi < 2; ++fi) {
    basis b = basis_of(*frames[fi]);
    for (int i = 0; i < 12; ++i) {
      const mf_vec3 d = to_world(b, spherical(acos(1.0 - 2.0 * uniform01()), 2.0 * PI * uniform01()));
      for (size_t k = 0; k < sizeof fs / sizeof fs[0]; ++k) {
        const double f = fs[k], t_max = (i % 3 == 0) ? INFINITY : 2.0 * uniform01();
        double st = -1, st_hi = -1, maj = -1, tau = -1, tr = -1;
        EXPECT_OK(mf_medium_sigma_t(m, frames[fi], f, d, &st));
        EXPECT_OK(mf_medium_sigma_t(m, frames[fi], f + 0.5, d, &st_hi));
        EXPECT_OK(mf_medium_majorant(m, frames[fi], f + 0.5, f, d, &maj));
        EXPECT_OK(mf_medium_optical_depth(m, frames[fi], f, d, t_max, &tau));
        EXPECT_OK(mf_medium_transmittance(m, frames[fi], f, d, t_max, &tr));
        CHECK(isfinite(st) && st >= 0 && isfinite(maj) && maj >= st && maj >= st_hi, "sigma_t %g, majorant %g", st,
              maj);
        CHECK(tau >= 0 && !isnan(tau) && tr >= 0 && tr <= 1, "optical depth %g, transmittance %g", tau, tr);
        mf_free_flight fl = {false, -1};
        EXPECT_OK(mf_medium_sample_free_flight(m, frames[fi], f, d, t_max, uniform01(), &fl));
        CHECK(fl.t >= 0 && (fl.scattered ? fl.t <= t_max : fl.t == t_max), "free flight t %g (t_max %g)", fl.t, t_max);
      }
    }
  }
  mf_medium_free(m);
}

/* Checks sampled directions against eval/pdf for one medium. With `spec` non-NULL the weight must
 * also equal the flake reflectance: Fresnel(eta, k) (or 1 when eta is NULL) times spec; that holds
 * for exact vNDF sampling only (the seeds/000 Eq. 40 mixture weights by D_wi / pdf as well). */
static void check_phase_sampling(const char *name, mf_medium *m, const mf_frame *frame, const double *eta,
                                 const double *k, const double *spec, int diffuse_albedo, const double *albedo) {
  basis b = basis_of(*frame);
  int valid = 0;
  for (int i = 0; i < 200; ++i) {
    mf_vec3 wi = to_world(b, spherical(acos(1.0 - 1.9 * uniform01()), 2.0 * PI * uniform01()));
    double u[MF_PHASE_SAMPLE_DIMENSIONS];
    for (int j = 0; j < MF_PHASE_SAMPLE_DIMENSIONS; ++j) u[j] = uniform01();
    phase_sample_t s;
    memset(&s, 0xA5, sizeof s);
    EXPECT_OK(mf_phase_sample(m, frame, wi, u, &s));
    if (!s.valid) {
      CHECK(s.pdf == 0 && s.weight.r == 0 && s.wo.x == 0 && s.wo.y == 0 && s.wo.z == 0,
            "%s: invalid sample with non-zero fields", name);
      continue;
    }
    ++valid;
    CHECK(fabs(dot(s.wo, s.wo) - 1.0) < 1e-12, "%s: |wo| = %.17g", name, sqrt(dot(s.wo, s.wo)));
    CHECK(s.pdf > 0 && isfinite(s.pdf), "%s: pdf %g", name, s.pdf);
    double pdf = -1;
    mf_rgb v = {-1, -1, -1};
    EXPECT_OK(mf_phase_pdf(m, frame, wi, s.wo, &pdf));
    EXPECT_OK(mf_phase_eval(m, frame, wi, s.wo, &v));
    CHECK(pdf > 0, "%s: pdf(wi, sampled wo) = %g", name, pdf);
    CHECK_REL(pdf, s.pdf, 1e-9);
    if (diffuse_albedo) {
      /* Exact: vNDF normal + cosine lobe reproduce p / albedo, so the weight is the albedo;
       * eval = albedo * pdf with the same quadrature. */
      CHECK(s.weight.r == albedo[0] && s.weight.g == albedo[1] && s.weight.b == albedo[2], "%s: weight %g %g %g",
            name, s.weight.r, s.weight.g, s.weight.b);
      CHECK(v.r == albedo[0] * pdf && v.g == albedo[1] * pdf && v.b == albedo[2] * pdf, "%s: eval != albedo * pdf",
            name);
      continue;
    }
    CHECK_REL(s.weight.r, v.r / pdf, 1e-9);
    CHECK_REL(s.weight.g, v.g / pdf, 1e-9);
    CHECK_REL(s.weight.b, v.b / pdf, 1e-9);
    if (spec == NULL) continue;
    mf_vec3 h = normalize(add(wi, s.wo));
    double c = dot(wi, h);
    const double *ch[3] = {&s.weight.r, &s.weight.g, &s.weight.b};
    for (int cc = 0; cc < 3; ++cc) {
      double fr = eta ? fresnel_conductor(c, eta[cc], k[cc]) : 1.0;
      CHECK_REL(*ch[cc], fr * spec[cc], 1e-10);
    }
  }
  CHECK(valid > 150, "%s: only %d of 200 samples valid", name, valid);
}

static void test_phase(void) {
  mf_medium *m = gpss_conductor();
  const double one[3] = {1, 1, 1};
  /* Back-to-back directions: no half vector, zero value and density. */
  mf_rgb zero = {-1, -1, -1};
  double zpdf = -1;
  EXPECT_OK(mf_phase_eval(m, &FRAME_Z, v3(0, 0.6, 0.8), v3(0, -0.6, -0.8), &zero));
  EXPECT_OK(mf_phase_pdf(m, &FRAME_Z, v3(0, 0.6, 0.8), v3(0, -0.6, -0.8), &zpdf));
  CHECK(zero.r == 0 && zero.g == 0 && zero.b == 0 && zpdf == 0, "back-to-back: %g %g", zero.r, zpdf);

  check_phase_sampling("gpss conductor", m, &FRAME_TILTED, COND_ETA, COND_K, one, 0, NULL);
  check_phase_sampling("gpss conductor (z frame)", m, &FRAME_Z, COND_ETA, COND_K, one, 0, NULL);
  mf_medium_free(m);

  const double spec[3] = {0.9, 0.7, 0.5};
  {
    const named_float f[] = {{"sigma", 0.2}, {"alpha_u", 0.4}, {"alpha_v", 0.3}, {NULL, 0}};
    mf_medium *mm = build(f, (const char *[]){"distribution", "ggx", "material", "none", NULL}, "specular_reflectance",
                          spec, NULL, NULL);
    check_phase_sampling("ggx mirror", mm, &FRAME_TILTED, NULL, NULL, spec, 0, NULL);
    mf_medium_free(mm);
  }
  {
    const named_float f[] = {{"sigma", 0.2}, {"alpha", 0.5}, {NULL, 0}};
    mf_medium *mm = build(f, (const char *[]){"distribution", "beckmann", "material", "none", NULL}, NULL, NULL, NULL,
                          NULL);
    check_phase_sampling("beckmann mirror", mm, &FRAME_Z, NULL, NULL, one, 0, NULL);
    /* Mirror flakes of reflectance 1: every sample has weight exactly 1. */
    double u[5] = {0.1, 0.2, 0.3, 0.4, 0.5};
    phase_sample_t s;
    EXPECT_OK(mf_phase_sample(mm, &FRAME_Z, v3(0.6, 0, 0.8), u, &s));
    CHECK(s.valid && s.weight.r == 1.0 && s.weight.g == 1.0 && s.weight.b == 1.0, "mirror weight %.17g", s.weight.r);
    /* A height field seen from straight below shows no flake: a valid call, no sample. */
    memset(&s, 0xA5, sizeof s);
    EXPECT_OK(mf_phase_sample(mm, &FRAME_Z, v3(0, 0, -1), u, &s));
    CHECK(!s.valid && s.pdf == 0 && s.wo.x == 0 && s.wo.y == 0 && s.wo.z == 0 && s.weight.r == 0 &&
              s.weight.g == 0 && s.weight.b == 0,
          "sample from below a height field: valid %d pdf %g", (int)s.valid, s.pdf);
    mf_medium_free(mm);
  }
  {
    const named_float f[] = {{"sigma", 0.2}, {"alpha_u", 0.3}, {"alpha_v", 0.5}, {"alpha_z", 0.6},
                             {"mixture_ratio", 0.3}, {NULL, 0}};
    mf_medium *mm = build(f, (const char *[]){"vndf_sampling", "mixture", "material", "Ag", NULL}, NULL, NULL, NULL,
                          NULL);
    check_phase_sampling("gpss mixture (Ag)", mm, &FRAME_TILTED, NULL, NULL, NULL, 0, NULL);
    mf_medium_free(mm);
  }
  {
    /* The "Au" preset reaches the flakes: its (eta, k) (src/fresnel.rs) give the weights. */
    const named_float f[] = {{"sigma", 0.2}, {"alpha", 0.3}, {NULL, 0}};
    mf_medium *mm = build(f, (const char *[]){"distribution", "beckmann", "material", "Au", NULL}, NULL, NULL, NULL,
                          NULL);
    const double au_eta[3] = {0.1431189557, 0.3749570432, 1.4424785571},
                 au_k[3] = {3.9831604247, 2.3857207478, 1.6032152899};
    check_phase_sampling("beckmann Au", mm, &FRAME_TILTED, au_eta, au_k, one, 0, NULL);
    mf_medium_free(mm);
  }
  {
    const double albedo[3] = {0.2, 0.5, 0.8};
    const named_float f[] = {{"sigma", 0.2}, {"alpha", 0.5}, {NULL, 0}};
    mf_medium *mm = build(f, (const char *[]){"micro_bsdf", "diffuse", NULL}, "reflectance", albedo, NULL, NULL);
    check_phase_sampling("gpss diffuse", mm, &FRAME_TILTED, NULL, NULL, NULL, 1, albedo);
    mf_medium_free(mm);
  }
}

/* Values printed once from the Rust core (medium_from_params + core methods) for the same
 * inputs; tolerance 1e-12 relative (see the top comment). */
static void test_reference_values(void) {
  mf_medium *m = gpss_conductor();
  const double s = 1.0 / sqrt(3.0);
  const mf_vec3 d = v3(s, -s, s), dn = v3(s, -s, -s), wi = v3(0, 0.6, 0.8), wo = v3(-0.6, 0, 0.8);
  double x = -1;
  EXPECT_OK(mf_medium_sigma_t(m, &FRAME_Z, 0.1, d, &x));
  CHECK_REL(x, 5.981797510962255e-3, 1e-12);
  EXPECT_OK(mf_medium_majorant(m, &FRAME_Z, 0.3, -0.4, d, &x));
  CHECK_REL(x, 1.2116498973963784e-2 * (1.0 + 1e-12), 1e-12); /* sigma_t at the lower end, MAJORANT_ROUNDING */
  EXPECT_OK(mf_medium_optical_depth(m, &FRAME_Z, -0.2, d, 1.5, &x));
  CHECK_REL(x, 7.440225196802669e-3, 1e-12);
  EXPECT_OK(mf_medium_transmittance(m, &FRAME_Z, -0.2, d, 1.5, &x));
  CHECK_REL(x, 9.925873847614832e-1, 1e-12);
  EXPECT_OK(mf_medium_optical_depth(m, &FRAME_Z, 0.7, v3(0.6, 0.0, -0.8), 2.0, &x));
  CHECK_REL(x, 3.242270009714714e0, 1e-12);
  mf_free_flight fl = {false, -1};
  EXPECT_OK(mf_medium_sample_free_flight(m, &FRAME_Z, 0.2, dn, INFINITY, 0.3, &fl));
  CHECK(fl.scattered, "reference free flight passed");
  CHECK_REL(fl.t, 4.332942818040923e-1, 1e-12);
  mf_rgb v;
  double pdf = -1;
  EXPECT_OK(mf_phase_eval(m, &FRAME_Z, wi, wo, &v));
  EXPECT_OK(mf_phase_pdf(m, &FRAME_Z, wi, wo, &pdf));
  CHECK_REL(v.r, 9.884436111959852e-2, 1e-12);
  CHECK_REL(v.g, 6.394362550981128e-2, 1e-12);
  CHECK_REL(v.b, 5.2078595740960874e-2, 1e-12);
  CHECK_REL(pdf, 1.0385263524433613e-1, 1e-12);
  const double u[5] = {0.25, 0.5, 0.75, 0.1, 0.9};
  phase_sample_t ps;
  EXPECT_OK(mf_phase_sample(m, &FRAME_Z, wi, u, &ps));
  CHECK(ps.valid, "reference sample invalid");
  CHECK_ABS(ps.wo.x, -4.115664662817114e-17, 1e-13);
  CHECK_ABS(ps.wo.y, -9.587983171762288e-1, 1e-13);
  CHECK_ABS(ps.wo.z, 2.840876396114976e-1, 1e-13);
  CHECK_REL(ps.weight.r, 9.475709523203734e-1, 1e-12);
  CHECK_REL(ps.weight.g, 6.193517134068397e-1, 1e-12);
  CHECK_REL(ps.weight.b, 5.154128633478088e-1, 1e-12);
  CHECK_REL(ps.pdf, 5.387096537488444e-1, 1e-12);
  mf_medium_free(m);

  const named_float fg[] = {{"sigma", 0.25}, {"alpha", 0.35}, {NULL, 0}};
  mf_medium *g = build(fg, (const char *[]){"distribution", "ggx", "material", "Au", NULL}, NULL, NULL, NULL, NULL);
  EXPECT_OK(mf_medium_sigma_t(g, &FRAME_Z, -0.1, d, &x));
  CHECK_REL(x, 1.4290267624592112e-1, 1e-12);
  EXPECT_OK(mf_phase_eval(g, &FRAME_Z, wi, wo, &v));
  EXPECT_OK(mf_phase_pdf(g, &FRAME_Z, wi, wo, &pdf));
  CHECK_REL(v.r, 1.1662763872175709e-1, 1e-12);
  CHECK_REL(v.g, 9.6772458963753735e-2, 1e-12);
  CHECK_REL(v.b, 3.9220090833175701e-2, 1e-12);
  CHECK_REL(pdf, 1.2066567854219414e-1, 1e-12);
  mf_medium_free(g);

  const named_float fd[] = {{"variance", 0.04}, {"lengthscale", 0.5}, {NULL, 0}};
  mf_medium *df = build(fd, (const char *[]){"micro_bsdf", "diffuse", NULL}, "reflectance",
                        (const double[3]){0.2, 0.5, 0.8}, NULL, NULL);
  EXPECT_OK(mf_phase_eval(df, &FRAME_Z, wi, wo, &v));
  EXPECT_OK(mf_phase_pdf(df, &FRAME_Z, wi, wo, &pdf));
  CHECK_REL(v.r, 4.501685894894002e-2, 1e-12);
  CHECK_REL(v.g, 1.1254214737235003e-1, 1e-12);
  CHECK_REL(v.b, 1.8006743579576007e-1, 1e-12);
  CHECK_REL(pdf, 2.2508429474470007e-1, 1e-12);
  mf_medium_free(df);
}

/* Batch calls equal single calls bit for bit; batch errors name the index and write nothing. */
#define NB 64
static void test_batches(void) {
  mf_medium *m = gpss_conductor();
  mf_flight_query fq[NB];
  mf_phase_query pq[NB];
  mf_phase_sample_query sq[NB];
  for (int i = 0; i < NB; ++i) {
    const mf_frame *frame = (i % 3) ? &FRAME_TILTED : &FRAME_Z;
    basis b = basis_of(*frame);
    fq[i].frame = *frame;
    fq[i].f = -1.5 + 3.5 * uniform01();
    fq[i].d = to_world(b, spherical(acos(1.0 - 2.0 * uniform01()), 2.0 * PI * uniform01()));
    fq[i].t_max = (i % 5 == 0) ? INFINITY : 3.0 * uniform01();
    fq[i].u = uniform01();
    pq[i].frame = *frame;
    pq[i].wi = to_world(b, spherical(acos(1.0 - 2.0 * uniform01()), 2.0 * PI * uniform01()));
    pq[i].wo = to_world(b, spherical(acos(1.0 - 2.0 * uniform01()), 2.0 * PI * uniform01()));
    sq[i].frame = *frame;
    sq[i].wi = pq[i].wi;
    for (int j = 0; j < MF_PHASE_SAMPLE_DIMENSIONS; ++j) sq[i].u[j] = uniform01();
  }
  double tr[NB];
  mf_free_flight ff[NB];
  mf_phase_value pv[NB];
  phase_sample_t ps[NB];
  EXPECT_OK(mf_medium_transmittance_batch(m, fq, NB, tr));
  EXPECT_OK(mf_medium_sample_free_flight_batch(m, fq, NB, ff));
  EXPECT_OK(mf_phase_eval_batch(m, pq, NB, pv));
  EXPECT_OK(mf_phase_sample_batch(m, sq, NB, ps));
  int scattered = 0;
  for (int i = 0; i < NB; ++i) {
    double t1 = -1;
    EXPECT_OK(mf_medium_transmittance(m, &fq[i].frame, fq[i].f, fq[i].d, fq[i].t_max, &t1));
    CHECK(same_bits(&t1, &tr[i], sizeof t1), "transmittance batch[%d] %.17g vs %.17g", i, tr[i], t1);
    mf_free_flight f1;
    EXPECT_OK(mf_medium_sample_free_flight(m, &fq[i].frame, fq[i].f, fq[i].d, fq[i].t_max, fq[i].u, &f1));
    CHECK(f1.scattered == ff[i].scattered && same_bits(&f1.t, &ff[i].t, sizeof f1.t), "free flight batch[%d]", i);
    scattered += f1.scattered;
    mf_rgb v1;
    double p1;
    EXPECT_OK(mf_phase_eval(m, &pq[i].frame, pq[i].wi, pq[i].wo, &v1));
    EXPECT_OK(mf_phase_pdf(m, &pq[i].frame, pq[i].wi, pq[i].wo, &p1));
    CHECK(same_bits(&v1, &pv[i].value, sizeof v1) && same_bits(&p1, &pv[i].pdf, sizeof p1), "phase eval batch[%d]", i);
    phase_sample_t s1;
    EXPECT_OK(mf_phase_sample(m, &sq[i].frame, sq[i].wi, sq[i].u, &s1));
    CHECK(s1.valid == ps[i].valid && same_bits(&s1.wo, &ps[i].wo, sizeof s1.wo) &&
              same_bits(&s1.weight, &ps[i].weight, sizeof s1.weight) && same_bits(&s1.pdf, &ps[i].pdf, sizeof s1.pdf),
          "phase sample batch[%d]", i);
  }
  CHECK(scattered > 5 && scattered < NB, "free flights: %d of %d scattered (both outcomes expected)", scattered, NB);

  /* count 0: NULL arrays are fine; the medium is still required. */
  EXPECT_OK(mf_medium_transmittance_batch(m, NULL, 0, NULL));
  EXPECT_OK(mf_medium_sample_free_flight_batch(m, NULL, 0, NULL));
  EXPECT_OK(mf_phase_eval_batch(m, NULL, 0, NULL));
  EXPECT_OK(mf_phase_sample_batch(m, NULL, 0, NULL));
  EXPECT_STATUS(mf_medium_transmittance_batch(NULL, NULL, 0, NULL), MF_ERROR_NULL_POINTER, "medium");
  EXPECT_STATUS(mf_medium_sample_free_flight_batch(NULL, NULL, 0, NULL), MF_ERROR_NULL_POINTER, "medium");
  EXPECT_STATUS(mf_phase_eval_batch(NULL, NULL, 0, NULL), MF_ERROR_NULL_POINTER, "medium");
  EXPECT_STATUS(mf_phase_sample_batch(NULL, NULL, 0, NULL), MF_ERROR_NULL_POINTER, "medium");

  /* NULL arrays with count > 0. */
  EXPECT_STATUS(mf_medium_transmittance_batch(m, NULL, NB, tr), MF_ERROR_NULL_POINTER, "queries");
  EXPECT_STATUS(mf_medium_transmittance_batch(m, fq, NB, NULL), MF_ERROR_NULL_POINTER, "out");
  EXPECT_STATUS(mf_medium_sample_free_flight_batch(m, NULL, NB, ff), MF_ERROR_NULL_POINTER, "queries");
  EXPECT_STATUS(mf_medium_sample_free_flight_batch(m, fq, NB, NULL), MF_ERROR_NULL_POINTER, "out");
  EXPECT_STATUS(mf_phase_eval_batch(m, NULL, NB, pv), MF_ERROR_NULL_POINTER, "queries");
  EXPECT_STATUS(mf_phase_eval_batch(m, pq, NB, NULL), MF_ERROR_NULL_POINTER, "out");
  EXPECT_STATUS(mf_phase_sample_batch(m, NULL, NB, ps), MF_ERROR_NULL_POINTER, "queries");
  EXPECT_STATUS(mf_phase_sample_batch(m, sq, NB, NULL), MF_ERROR_NULL_POINTER, "out");

  /* One bad query in the middle: status, its index in the message, nothing written. */
  unsigned char fill[sizeof ps];
  memset(fill, 0xA5, sizeof fill);
  mf_flight_query fq_bad[NB];
  memcpy(fq_bad, fq, sizeof fq);
  fq_bad[37].d = v3(NAN, 0, 1);
  memset(tr, 0xA5, sizeof tr);
  EXPECT_STATUS(mf_medium_transmittance_batch(m, fq_bad, NB, tr), MF_ERROR_INVALID_ARGUMENT, "query 37: d");
  CHECK(same_bits(tr, fill, sizeof tr), "transmittance batch wrote output on failure");
  memcpy(fq_bad, fq, sizeof fq);
  fq_bad[12].u = 1.0;
  memset(ff, 0xA5, sizeof ff);
  EXPECT_STATUS(mf_medium_sample_free_flight_batch(m, fq_bad, NB, ff), MF_ERROR_INVALID_ARGUMENT, "query 12: u");
  CHECK(same_bits(ff, fill, sizeof ff), "free-flight batch wrote output on failure");
  memcpy(fq_bad, fq, sizeof fq);
  fq_bad[NB - 1].t_max = -1.0;
  memset(ff, 0xA5, sizeof ff);
  EXPECT_STATUS(mf_medium_sample_free_flight_batch(m, fq_bad, NB, ff), MF_ERROR_INVALID_ARGUMENT, "query 63");
  CHECK(same_bits(ff, fill, sizeof ff), "free-flight batch wrote output on failure");
  mf_phase_query pq_bad[NB];
  memcpy(pq_bad, pq, sizeof pq);
  pq_bad[0].wo = v3(1, 1, 0);
  memset(pv, 0xA5, sizeof pv);
  EXPECT_STATUS(mf_phase_eval_batch(m, pq_bad, NB, pv), MF_ERROR_INVALID_ARGUMENT, "query 0: wo must be a unit");
  CHECK(same_bits(pv, fill, sizeof pv), "phase eval batch wrote output on failure");
  mf_phase_sample_query sq_bad[NB];
  memcpy(sq_bad, sq, sizeof sq);
  sq_bad[5].u[4] = -0.25;
  memset(ps, 0xA5, sizeof ps);
  EXPECT_STATUS(mf_phase_sample_batch(m, sq_bad, NB, ps), MF_ERROR_INVALID_ARGUMENT, "query 5: u[4]");
  CHECK(same_bits(ps, fill, sizeof ps), "phase sample batch wrote output on failure");
  memcpy(sq_bad, sq, sizeof sq);
  sq_bad[9].frame.normal = v3(0, 0, 0);
  memset(ps, 0xA5, sizeof ps);
  EXPECT_STATUS(mf_phase_sample_batch(m, sq_bad, NB, ps), MF_ERROR_INVALID_ARGUMENT, "query 9: the normal");
  CHECK(same_bits(ps, fill, sizeof ps), "phase sample batch wrote output on failure");
  mf_medium_free(m);
}

/* Every query entry point with every kind of bad argument: exact status, a message naming the
 * problem, out-parameter untouched. */
static void test_bad_query_arguments(void) {
  mf_medium *m = gpss_conductor();
  const mf_frame *fr = &FRAME_TILTED;
  const mf_vec3 good = normalize(v3(0.2, -0.3, 0.9));
  const mf_vec3 nan_dir = v3(NAN, 0.0, 1.0), inf_dir = v3(0.0, INFINITY, 0.0), long_dir = v3(1.0, 1.0, 0.0),
                zero_dir = v3(0, 0, 0);
  const mf_frame zero_normal = {{0, 0, 0}, {1, 0, 0}}, nan_normal = {{0, NAN, 1}, {1, 0, 0}},
                 inf_tangent = {{0, 0, 1}, {INFINITY, 0, 0}};
  const double sentinel = -12345.678;
  double x;
  mf_rgb rgb;
  mf_free_flight fl;
  phase_sample_t ps;
  const mf_rgb rgb_sentinel = {sentinel, sentinel, sentinel};
  const double u5[5] = {0.1, 0.2, 0.3, 0.4, 0.5};

#define DOUBLE_CASE(call, status, needle)                                  \
  do {                                                                     \
    x = sentinel;                                                          \
    EXPECT_STATUS(call, status, needle);                                   \
    CHECK(x == sentinel, "%s wrote its out-parameter on failure", #call); \
  } while (0)

  /* mf_medium_shell_top */
  DOUBLE_CASE(mf_medium_shell_top(NULL, &x), MF_ERROR_NULL_POINTER, "medium");
  EXPECT_STATUS(mf_medium_shell_top(m, NULL), MF_ERROR_NULL_POINTER, "out_top");

  /* mf_medium_sigma_t */
  DOUBLE_CASE(mf_medium_sigma_t(NULL, fr, 0.0, good, &x), MF_ERROR_NULL_POINTER, "medium");
  DOUBLE_CASE(mf_medium_sigma_t(m, NULL, 0.0, good, &x), MF_ERROR_NULL_POINTER, "frame");
  EXPECT_STATUS(mf_medium_sigma_t(m, fr, 0.0, good, NULL), MF_ERROR_NULL_POINTER, "out_sigma_t");
  DOUBLE_CASE(mf_medium_sigma_t(m, fr, 0.0, nan_dir, &x), MF_ERROR_INVALID_ARGUMENT, "d must be finite");
  DOUBLE_CASE(mf_medium_sigma_t(m, fr, 0.0, inf_dir, &x), MF_ERROR_INVALID_ARGUMENT, "d must be finite");
  DOUBLE_CASE(mf_medium_sigma_t(m, fr, 0.0, long_dir, &x), MF_ERROR_INVALID_ARGUMENT, "d must be a unit vector");
  DOUBLE_CASE(mf_medium_sigma_t(m, fr, 0.0, zero_dir, &x), MF_ERROR_INVALID_ARGUMENT, "d must be a unit vector");
  DOUBLE_CASE(mf_medium_sigma_t(m, fr, NAN, good, &x), MF_ERROR_INVALID_ARGUMENT, "f must be finite");
  DOUBLE_CASE(mf_medium_sigma_t(m, fr, -INFINITY, good, &x), MF_ERROR_INVALID_ARGUMENT, "f must be finite");
  DOUBLE_CASE(mf_medium_sigma_t(m, &zero_normal, 0.0, good, &x), MF_ERROR_INVALID_ARGUMENT, "normal");
  DOUBLE_CASE(mf_medium_sigma_t(m, &nan_normal, 0.0, good, &x), MF_ERROR_INVALID_ARGUMENT, "normal must be finite");
  DOUBLE_CASE(mf_medium_sigma_t(m, &inf_tangent, 0.0, good, &x), MF_ERROR_INVALID_ARGUMENT, "tangent must be finite");
  /* A direction within the documented 1e-6 of unit length is accepted. */
  x = sentinel;
  EXPECT_OK(mf_medium_sigma_t(m, fr, 0.0, scale(good, 1.0 + 5e-7), &x));
  CHECK(x != sentinel && x > 0, "sigma_t of a nearly unit direction %g", x);

  /* mf_medium_majorant */
  DOUBLE_CASE(mf_medium_majorant(NULL, fr, 0.0, 1.0, good, &x), MF_ERROR_NULL_POINTER, "medium");
  DOUBLE_CASE(mf_medium_majorant(m, NULL, 0.0, 1.0, good, &x), MF_ERROR_NULL_POINTER, "frame");
  EXPECT_STATUS(mf_medium_majorant(m, fr, 0.0, 1.0, good, NULL), MF_ERROR_NULL_POINTER, "out_majorant");
  DOUBLE_CASE(mf_medium_majorant(m, fr, NAN, 1.0, good, &x), MF_ERROR_INVALID_ARGUMENT, "f_a must be finite");
  DOUBLE_CASE(mf_medium_majorant(m, fr, 0.0, INFINITY, good, &x), MF_ERROR_INVALID_ARGUMENT, "f_b must be finite");
  DOUBLE_CASE(mf_medium_majorant(m, fr, 0.0, 1.0, nan_dir, &x), MF_ERROR_INVALID_ARGUMENT, "d must be finite");
  DOUBLE_CASE(mf_medium_majorant(m, fr, 0.0, 1.0, long_dir, &x), MF_ERROR_INVALID_ARGUMENT, "unit vector");
  DOUBLE_CASE(mf_medium_majorant(m, &zero_normal, 0.0, 1.0, good, &x), MF_ERROR_INVALID_ARGUMENT, "normal");

  /* mf_medium_optical_depth and mf_medium_transmittance (same arguments). The length check
   * names the argument "t_max" in both (see the report: these functions call it `t`). */
  for (int which = 0; which < 2; ++which) {
    typedef mf_status (*depth_fn)(const mf_medium *, const mf_frame *, double, mf_vec3, double, double *);
    depth_fn fn = which ? mf_medium_transmittance : mf_medium_optical_depth;
    const char *out_name = which ? "out_transmittance" : "out_tau";
    DOUBLE_CASE(fn(NULL, fr, 0.0, good, 1.0, &x), MF_ERROR_NULL_POINTER, "medium");
    DOUBLE_CASE(fn(m, NULL, 0.0, good, 1.0, &x), MF_ERROR_NULL_POINTER, "frame");
    EXPECT_STATUS(fn(m, fr, 0.0, good, 1.0, NULL), MF_ERROR_NULL_POINTER, out_name);
    DOUBLE_CASE(fn(m, fr, 0.0, nan_dir, 1.0, &x), MF_ERROR_INVALID_ARGUMENT, "d must be finite");
    DOUBLE_CASE(fn(m, fr, 0.0, long_dir, 1.0, &x), MF_ERROR_INVALID_ARGUMENT, "d must be a unit vector");
    DOUBLE_CASE(fn(m, fr, NAN, good, 1.0, &x), MF_ERROR_INVALID_ARGUMENT, "f must be finite");
    DOUBLE_CASE(fn(m, fr, 0.0, good, -1.0, &x), MF_ERROR_INVALID_ARGUMENT, "must be >= 0");
    DOUBLE_CASE(fn(m, fr, 0.0, good, -INFINITY, &x), MF_ERROR_INVALID_ARGUMENT, "must be >= 0");
    DOUBLE_CASE(fn(m, fr, 0.0, good, NAN, &x), MF_ERROR_INVALID_ARGUMENT, "must be >= 0");
    DOUBLE_CASE(fn(m, &nan_normal, 0.0, good, 1.0, &x), MF_ERROR_INVALID_ARGUMENT, "normal");
    /* Boundary values that are valid: t = 0 and t = +inf. */
    x = sentinel;
    EXPECT_OK(fn(m, fr, 0.0, good, 0.0, &x));
    CHECK(x == (which ? 1.0 : 0.0), "zero-length segment: %g", x);
  }

  /* mf_medium_sample_free_flight */
#define FLIGHT_CASE(call, status, needle)                                                  \
  do {                                                                                     \
    memset(&fl, 0xA5, sizeof fl);                                                          \
    unsigned char before[sizeof fl];                                                       \
    memcpy(before, &fl, sizeof fl);                                                        \
    EXPECT_STATUS(call, status, needle);                                                   \
    CHECK(same_bits(before, &fl, sizeof fl), "%s wrote its out-parameter on failure", #call); \
  } while (0)
  FLIGHT_CASE(mf_medium_sample_free_flight(NULL, fr, 0.0, good, 1.0, 0.5, &fl), MF_ERROR_NULL_POINTER, "medium");
  FLIGHT_CASE(mf_medium_sample_free_flight(m, NULL, 0.0, good, 1.0, 0.5, &fl), MF_ERROR_NULL_POINTER, "frame");
  EXPECT_STATUS(mf_medium_sample_free_flight(m, fr, 0.0, good, 1.0, 0.5, NULL), MF_ERROR_NULL_POINTER, "out_flight");
  FLIGHT_CASE(mf_medium_sample_free_flight(m, fr, 0.0, nan_dir, 1.0, 0.5, &fl), MF_ERROR_INVALID_ARGUMENT,
              "d must be finite");
  FLIGHT_CASE(mf_medium_sample_free_flight(m, fr, 0.0, long_dir, 1.0, 0.5, &fl), MF_ERROR_INVALID_ARGUMENT,
              "d must be a unit vector");
  FLIGHT_CASE(mf_medium_sample_free_flight(m, fr, NAN, good, 1.0, 0.5, &fl), MF_ERROR_INVALID_ARGUMENT,
              "f must be finite");
  FLIGHT_CASE(mf_medium_sample_free_flight(m, fr, 0.0, good, -1.0, 0.5, &fl), MF_ERROR_INVALID_ARGUMENT,
              "t_max must be >= 0");
  FLIGHT_CASE(mf_medium_sample_free_flight(m, fr, 0.0, good, 1.0, 1.0, &fl), MF_ERROR_INVALID_ARGUMENT,
              "u must lie in [0, 1)");
  FLIGHT_CASE(mf_medium_sample_free_flight(m, fr, 0.0, good, 1.0, -0.1, &fl), MF_ERROR_INVALID_ARGUMENT,
              "u must lie in [0, 1)");
  FLIGHT_CASE(mf_medium_sample_free_flight(m, fr, 0.0, good, 1.0, NAN, &fl), MF_ERROR_INVALID_ARGUMENT,
              "u must lie in [0, 1)");
  FLIGHT_CASE(mf_medium_sample_free_flight(m, &zero_normal, 0.0, good, 1.0, 0.5, &fl), MF_ERROR_INVALID_ARGUMENT,
              "normal");

  /* mf_phase_eval and mf_phase_pdf */
#define RGB_CASE(call, status, needle)                                                  \
  do {                                                                                  \
    rgb = rgb_sentinel;                                                                 \
    EXPECT_STATUS(call, status, needle);                                                \
    CHECK(same_bits(&rgb, &rgb_sentinel, sizeof rgb), "%s wrote its out-parameter", #call); \
  } while (0)
  RGB_CASE(mf_phase_eval(NULL, fr, good, good, &rgb), MF_ERROR_NULL_POINTER, "medium");
  RGB_CASE(mf_phase_eval(m, NULL, good, good, &rgb), MF_ERROR_NULL_POINTER, "frame");
  EXPECT_STATUS(mf_phase_eval(m, fr, good, good, NULL), MF_ERROR_NULL_POINTER, "out_value");
  RGB_CASE(mf_phase_eval(m, fr, nan_dir, good, &rgb), MF_ERROR_INVALID_ARGUMENT, "wi must be finite");
  RGB_CASE(mf_phase_eval(m, fr, good, nan_dir, &rgb), MF_ERROR_INVALID_ARGUMENT, "wo must be finite");
  RGB_CASE(mf_phase_eval(m, fr, long_dir, good, &rgb), MF_ERROR_INVALID_ARGUMENT, "wi must be a unit vector");
  RGB_CASE(mf_phase_eval(m, fr, good, long_dir, &rgb), MF_ERROR_INVALID_ARGUMENT, "wo must be a unit vector");
  RGB_CASE(mf_phase_eval(m, &nan_normal, good, good, &rgb), MF_ERROR_INVALID_ARGUMENT, "normal");
  DOUBLE_CASE(mf_phase_pdf(NULL, fr, good, good, &x), MF_ERROR_NULL_POINTER, "medium");
  DOUBLE_CASE(mf_phase_pdf(m, NULL, good, good, &x), MF_ERROR_NULL_POINTER, "frame");
  EXPECT_STATUS(mf_phase_pdf(m, fr, good, good, NULL), MF_ERROR_NULL_POINTER, "out_pdf");
  DOUBLE_CASE(mf_phase_pdf(m, fr, nan_dir, good, &x), MF_ERROR_INVALID_ARGUMENT, "wi must be finite");
  DOUBLE_CASE(mf_phase_pdf(m, fr, good, inf_dir, &x), MF_ERROR_INVALID_ARGUMENT, "wo must be finite");
  DOUBLE_CASE(mf_phase_pdf(m, fr, zero_dir, good, &x), MF_ERROR_INVALID_ARGUMENT, "wi must be a unit vector");
  DOUBLE_CASE(mf_phase_pdf(m, fr, good, long_dir, &x), MF_ERROR_INVALID_ARGUMENT, "wo must be a unit vector");
  DOUBLE_CASE(mf_phase_pdf(m, &zero_normal, good, good, &x), MF_ERROR_INVALID_ARGUMENT, "normal");

  /* mf_phase_sample */
#define SAMPLE_CASE(call, status, needle)                                                  \
  do {                                                                                     \
    memset(&ps, 0xA5, sizeof ps);                                                          \
    unsigned char before[sizeof ps];                                                       \
    memcpy(before, &ps, sizeof ps);                                                        \
    EXPECT_STATUS(call, status, needle);                                                   \
    CHECK(same_bits(before, &ps, sizeof ps), "%s wrote its out-parameter on failure", #call); \
  } while (0)
  SAMPLE_CASE(mf_phase_sample(NULL, fr, good, u5, &ps), MF_ERROR_NULL_POINTER, "medium");
  SAMPLE_CASE(mf_phase_sample(m, NULL, good, u5, &ps), MF_ERROR_NULL_POINTER, "frame");
  SAMPLE_CASE(mf_phase_sample(m, fr, good, NULL, &ps), MF_ERROR_NULL_POINTER, "u must not be NULL");
  EXPECT_STATUS(mf_phase_sample(m, fr, good, u5, NULL), MF_ERROR_NULL_POINTER, "out_sample");
  SAMPLE_CASE(mf_phase_sample(m, fr, nan_dir, u5, &ps), MF_ERROR_INVALID_ARGUMENT, "wi must be finite");
  SAMPLE_CASE(mf_phase_sample(m, fr, long_dir, u5, &ps), MF_ERROR_INVALID_ARGUMENT, "wi must be a unit vector");
  SAMPLE_CASE(mf_phase_sample(m, &zero_normal, good, u5, &ps), MF_ERROR_INVALID_ARGUMENT, "normal");
  for (int i = 0; i < MF_PHASE_SAMPLE_DIMENSIONS; ++i) {
    const double bad[] = {1.0, -1e-300, NAN, INFINITY};
    for (int j = 0; j < 4; ++j) {
      double u[5];
      memcpy(u, u5, sizeof u);
      u[i] = bad[j];
      char needle[32];
      snprintf(needle, sizeof needle, "u[%d] must lie in [0, 1)", i);
      SAMPLE_CASE(mf_phase_sample(m, fr, good, u, &ps), MF_ERROR_INVALID_ARGUMENT, needle);
    }
  }
  /* The largest double below 1 is a valid uniform. */
  const double u_edge[5] = {nextafter(1.0, 0.0), 0.0, nextafter(1.0, 0.0), 0.0, 0.5};
  EXPECT_OK(mf_phase_sample(m, fr, good, u_edge, &ps));
  mf_medium_free(m);
#undef DOUBLE_CASE
#undef FLIGHT_CASE
#undef RGB_CASE
#undef SAMPLE_CASE
}

/* ------------------------------------------------------------------------------ gpis */

/* The mean SDF of the plane z = 0 (f = z), with a call counter in user_data. */
static void plane_sdf(void *user_data, mf_vec3 p, mf_sdf_sample *out) {
  ++*(int *)user_data;
  out->f = p.z;
  out->gradient = v3(0, 0, 1);
}

static void nan_sdf(void *user_data, mf_vec3 p, mf_sdf_sample *out) {
  (void)user_data;
  (void)p;
  out->f = NAN;
  out->gradient = v3(0, 0, 1);
}

static mf_gpis *build_gpis(const char *memory) {
  mf_params *p = NULL;
  mf_gpis *g = NULL;
  EXPECT_OK(mf_params_new(&p));
  EXPECT_OK(mf_params_set_float(p, "sigma", 1.0));
  EXPECT_OK(mf_params_set_float(p, "alpha", 1.0));
  EXPECT_OK(mf_params_set_string(p, "material", "Au"));
  EXPECT_OK(mf_params_set_string(p, "memory", memory));
  EXPECT_OK(mf_gpis_new(p, &g));
  mf_params_free(p);
  CHECK(g != NULL, "gpis not built: %s", last_error());
  return g;
}

/* The realization-based GPIS: construction errors, determinism per seed, crossing geometry, the
 * first-crossing height statistics of a plane, specular scattering, and bad calls. */
static void test_gpis(void) {
  /* Construction: the macrofacet names plus memory; statistical-medium-only names are errors. */
  {
    mf_params *p = NULL;
    mf_gpis *g = (mf_gpis *)0x1;
    EXPECT_OK(mf_params_new(&p));
    EXPECT_OK(mf_params_set_float(p, "sigma", 1.0));
    EXPECT_OK(mf_params_set_float(p, "alpha", 0.5));
    EXPECT_OK(mf_params_set_string(p, "distribution", "ggx"));
    EXPECT_STATUS(mf_gpis_new(p, &g), MF_ERROR_INVALID_VALUE, "ggx");
    EXPECT_OK(mf_params_set_string(p, "distribution", "gpss"));
    EXPECT_OK(mf_params_set_string(p, "memory", "global"));
    EXPECT_STATUS(mf_gpis_new(p, &g), MF_ERROR_INVALID_VALUE, "memory");
    EXPECT_OK(mf_params_set_string(p, "memory", "renewal"));
    EXPECT_OK(mf_params_set_string(p, "vndf_sampling", "exact"));
    EXPECT_STATUS(mf_gpis_new(p, &g), MF_ERROR_UNKNOWN_PARAMETER, "vndf_sampling");
    CHECK(g == (mf_gpis *)0x1, "mf_gpis_new wrote its out-parameter on failure");
    EXPECT_STATUS(mf_gpis_new(NULL, &g), MF_ERROR_NULL_POINTER, "params");
    EXPECT_STATUS(mf_gpis_new(p, NULL), MF_ERROR_NULL_POINTER, "out_gpis");
    mf_params_free(p);
    mf_gpis_free(NULL);
  }

  mf_gpis *g = build_gpis("renewal_plus");
  double envelope = 0;
  EXPECT_OK(mf_gpis_envelope(g, NULL, &envelope));
  CHECK_REL(envelope, 6.0, 1e-15); /* default band: 6 sigma */

  const mf_vec3 down = v3(0, 0, -1);
  const mf_gpis_start free_start = {MF_GPIS_START_FREE, {0, 0, 0}};
  int calls = 0;
  mf_gpis_hit a, b;
  EXPECT_OK(mf_gpis_trace(g, plane_sdf, NULL, &calls, v3(0, 0, envelope), down, INFINITY, &free_start, 42, &a));
  EXPECT_OK(mf_gpis_trace(g, plane_sdf, NULL, &calls, v3(0, 0, envelope), down, INFINITY, &free_start, 42, &b));
  CHECK(calls > 0, "the sdf callback was never called");
  CHECK(a.hit && b.hit && a.t == b.t && same_bits(&a.normal, &b.normal, sizeof a.normal) &&
            same_bits(&a.gradient, &b.gradient, sizeof a.gradient),
        "same seed must give the same realization");
  CHECK_ABS(a.point.z, envelope - a.t, 1e-12);
  CHECK(a.normal.z > 0.0 && fabs(a.normal.x * a.normal.x + a.normal.y * a.normal.y + a.normal.z * a.normal.z - 1) < 1e-12,
        "normal (%g %g %g) must be unit and face the ray", a.normal.x, a.normal.y, a.normal.z);

  /* The seed is the whole random state of a trace (no generator lives in the handle): other seeds
   * give other realizations, every downward ray meets the plane's realization somewhere, and a
   * seed repeated after others gives its first answer again. Their statistics against Smith's
   * model: tests/gpis.rs (smith_masking_upward, transmittance_matches_macrofacet_...). */
  {
    const mf_vec3 d = v3(sin(1.2), 0, -cos(1.2));
    const mf_vec3 origin = v3(-envelope * d.x / d.z, 0, envelope);
    int hits = 0, distinct = 0;
    for (uint64_t seed = 0; seed < 50; ++seed) {
      mf_gpis_hit h;
      EXPECT_OK(mf_gpis_trace(g, plane_sdf, NULL, &calls, origin, d, INFINITY, &free_start, seed, &h));
      hits += h.hit;
      distinct += h.hit && h.t != a.t;
      CHECK(!h.hit || (h.t > 0 && isfinite(h.point.z)), "seed %u: crossing at t = %g", (unsigned)seed, h.t);
    }
    CHECK(hits == 50, "a downward ray must always meet the plane's realization (%d of 50)", hits);
    CHECK(distinct >= hits - 2, "seeds must change the realization (%d distinct)", distinct);
    mf_gpis_hit again;
    EXPECT_OK(mf_gpis_trace(g, plane_sdf, NULL, &calls, v3(0, 0, envelope), down, INFINITY, &free_start, 42, &again));
    CHECK(again.t == a.t, "seed 42 after other seeds: t %.17g vs %.17g", again.t, a.t);
  }

  /* Scattering: gold Fresnel at the reflection angle, mirror direction; behind the normal: invalid. */
  phase_sample_t s;
  const mf_vec3 wi = v3(0.6, 0, 0.8);
  EXPECT_OK(mf_gpis_scatter(g, NULL, wi, v3(0, 0, 1), &s));
  CHECK(s.valid && fabs(s.wo.x + 0.6) < 1e-15 && fabs(s.wo.z - 0.8) < 1e-15 && s.pdf == 0.0,
        "reflection of (0.6, 0, 0.8): (%g %g %g)", s.wo.x, s.wo.y, s.wo.z);
  CHECK(s.weight.r > s.weight.g && s.weight.g > s.weight.b && s.weight.r < 1.0, "gold weight %g %g %g", s.weight.r,
        s.weight.g, s.weight.b);
  EXPECT_OK(mf_gpis_scatter(g, NULL, wi, v3(0, 0, -1), &s));
  CHECK(!s.valid, "a direction behind the normal cannot reflect");

  /* Renewal+ continues from the crossing with its gradient; the next segment leaves upward. */
  EXPECT_OK(mf_gpis_scatter(g, NULL, v3(0, 0, 1), a.normal, &s));
  const mf_gpis_start on = {MF_GPIS_START_ON_SURFACE, a.gradient};
  mf_gpis_hit next;
  EXPECT_OK(mf_gpis_trace(g, plane_sdf, NULL, &calls, a.point, s.wo, INFINITY, &on, 7, &next));
  CHECK(!next.hit || next.t > 0.0, "a continuation crossing lies ahead");

  /* Bad calls leave the output untouched. */
  mf_gpis_hit h;
#define HIT_CASE(call, status, needle)                                                      \
  do {                                                                                      \
    memset(&h, 0xA5, sizeof h);                                                             \
    unsigned char before[sizeof h];                                                         \
    memcpy(before, &h, sizeof h);                                                           \
    EXPECT_STATUS(call, status, needle);                                                    \
    CHECK(same_bits(before, &h, sizeof h), "%s wrote its out-parameter on failure", #call); \
  } while (0)
  const mf_vec3 o = v3(0, 0, 1);
  HIT_CASE(mf_gpis_trace(NULL, plane_sdf, NULL, &calls, o, down, 1, &free_start, 1, &h), MF_ERROR_NULL_POINTER, "gpis");
  HIT_CASE(mf_gpis_trace(g, NULL, NULL, &calls, o, down, 1, &free_start, 1, &h), MF_ERROR_NULL_POINTER, "sdf");
  HIT_CASE(mf_gpis_trace(g, plane_sdf, NULL, &calls, o, down, 1, NULL, 1, &h), MF_ERROR_NULL_POINTER, "start");
  EXPECT_STATUS(mf_gpis_trace(g, plane_sdf, NULL, &calls, o, down, 1, &free_start, 1, NULL), MF_ERROR_NULL_POINTER, "out_hit");
  HIT_CASE(mf_gpis_trace(g, plane_sdf, NULL, &calls, v3(NAN, 0, 0), down, 1, &free_start, 1, &h), MF_ERROR_INVALID_ARGUMENT, "origin");
  HIT_CASE(mf_gpis_trace(g, plane_sdf, NULL, &calls, o, v3(0, 0, -2), 1, &free_start, 1, &h), MF_ERROR_INVALID_ARGUMENT, "d must be a unit vector");
  HIT_CASE(mf_gpis_trace(g, plane_sdf, NULL, &calls, o, down, 0.0, &free_start, 1, &h), MF_ERROR_INVALID_ARGUMENT, "t_max");
  HIT_CASE(mf_gpis_trace(g, plane_sdf, NULL, &calls, o, down, NAN, &free_start, 1, &h), MF_ERROR_INVALID_ARGUMENT, "t_max");
  const mf_gpis_start bad_kind = {7, {0, 0, 1}};
  HIT_CASE(mf_gpis_trace(g, plane_sdf, NULL, &calls, o, down, 1, &bad_kind, 1, &h), MF_ERROR_INVALID_ARGUMENT, "start.kind");
  const mf_gpis_start bad_gradient = {MF_GPIS_START_ON_SURFACE, {NAN, 0, 1}};
  HIT_CASE(mf_gpis_trace(g, plane_sdf, NULL, &calls, o, down, 1, &bad_gradient, 1, &h), MF_ERROR_INVALID_ARGUMENT, "gradient");
  HIT_CASE(mf_gpis_trace(g, nan_sdf, NULL, NULL, o, down, 1, &free_start, 1, &h), MF_ERROR_INVALID_ARGUMENT, "sdf callback");
  double x = 123.0;
  EXPECT_STATUS(mf_gpis_envelope(NULL, NULL, &x), MF_ERROR_NULL_POINTER, "gpis");
  EXPECT_STATUS(mf_gpis_envelope(g, NULL, NULL), MF_ERROR_NULL_POINTER, "out_envelope");
  CHECK(x == 123.0, "mf_gpis_envelope wrote its out-parameter on failure");
  memset(&s, 0xA5, sizeof s);
  phase_sample_t before = s;
  EXPECT_STATUS(mf_gpis_scatter(NULL, NULL, wi, o, &s), MF_ERROR_NULL_POINTER, "gpis");
  EXPECT_STATUS(mf_gpis_scatter(g, NULL, v3(NAN, 0, 1), o, &s), MF_ERROR_INVALID_ARGUMENT, "wi");
  EXPECT_STATUS(mf_gpis_scatter(g, NULL, wi, v3(0, 0, 3), &s), MF_ERROR_INVALID_ARGUMENT, "normal");
  EXPECT_STATUS(mf_gpis_scatter(g, NULL, wi, o, NULL), MF_ERROR_NULL_POINTER, "out_sample");
  CHECK(same_bits(&before, &s, sizeof s), "mf_gpis_scatter wrote its out-parameter on failure");
#undef HIT_CASE
  mf_gpis_free(g);

  mf_gpis *renewal = build_gpis("renewal");
  mf_gpis_hit r;
  EXPECT_OK(mf_gpis_trace(renewal, plane_sdf, NULL, &calls, v3(0, 0, 6), down, INFINITY, &free_start, 3, &r));
  CHECK(r.hit, "renewal trace must hit the plane");
  mf_gpis_free(renewal);
}

/* ------------------------------------------------------------------------------ surfaces and tracking */

/* A host surface: the sphere of radius 1 at the origin (convex), with a call counter and a mode
 * that makes it misbehave. */
typedef struct {
  int calls;
  int mode; /* 0 fine, 1 NaN f, 2 non-unit normal, 3 error code */
} host_sphere;

static int32_t host_sphere_point(void *user_data, mf_vec3 p, mf_surface_point *out) {
  host_sphere *h = (host_sphere *)user_data;
  ++h->calls;
  if (h->mode == 3) return 42;
  double r = sqrt(dot(p, p));
  out->f = h->mode == 1 ? NAN : r - 1.0;
  out->normal = h->mode == 2 ? v3(0, 0, 3) : (r > 0 ? scale(p, 1.0 / r) : v3(0, 0, 1));
  out->tangent = cross(v3(0, 0, 1), p); /* Mitsuba's dp/du around the z axis */
  return 0;
}

/* A host bound that lies (claims f never drops below f(p)): the tracker must still stay within
 * [0, t_max] and report what it saw as majorant violations. */
static int32_t lying_bound(void *user_data, const mf_surface_point *start, mf_vec3 p, mf_vec3 d, double length,
                           double tolerance, mf_segment_bound *out) {
  (void)user_data, (void)p, (void)d, (void)tolerance;
  out->length = length;
  out->f_lo[0] = out->f_lo[1] = start->f;
  out->f_hi[0] = out->f_hi[1] = INFINITY;
  out->cos_lo = -1;
  out->cos_hi = 1;
  return 0;
}

static int32_t nan_bound(void *user_data, const mf_surface_point *start, mf_vec3 p, mf_vec3 d, double length,
                         double tolerance, mf_segment_bound *out) {
  (void)user_data, (void)start, (void)p, (void)d, (void)tolerance;
  out->length = length;
  out->f_lo[0] = out->f_lo[1] = NAN;
  out->f_hi[0] = out->f_hi[1] = INFINITY;
  out->cos_lo = -1;
  out->cos_hi = 1;
  return 0;
}

/* Surfaces (built in and host callbacks) and the tracking calls: equal answers for equal inputs
 * and seeds, outputs within their ranges, the combined phase call, batches, and bad input —
 * including a misbehaving host surface, reported at its first bad answer. */
/* mf_track_opaque_core: a shadow ray from the shell into a sphere's core has a transmittance that
   rounds to 0; a mesh's core is never shallower; NULLs change nothing. */
static void test_opaque_core(void) {
  const named_float f[] = {{"sigma", 1e-3}, {"alpha", 0.3}, {NULL, 0}};
  mf_medium *m = build(f, (const char *[]){"distribution", "beckmann", "material", "Au", NULL}, NULL, NULL, NULL, NULL);
  mf_surface *sphere = NULL, *mesh = NULL;
  EXPECT_OK(mf_surface_new_sphere(v3(0, 0, 0), 1.0, false, v3(0, 0, 1), &sphere));
  const double octa_p[18] = {1, 0, 0, -1, 0, 0, 0, 1, 0, 0, -1, 0, 0, 0, 1, 0, 0, -1};
  const uint32_t octa_i[24] = {0, 2, 4, 2, 1, 4, 1, 3, 4, 3, 0, 4, 2, 0, 5, 1, 2, 5, 3, 1, 5, 0, 3, 5};
  mf_mesh octa = {octa_p, 6, octa_i, 8, NULL, NULL};
  EXPECT_OK(mf_surface_new_mesh(&octa, 1, INFINITY, &mesh));
  double start = 1, core = 1;
  EXPECT_OK(mf_track_opaque_core(m, sphere, &start, &core));
  /* start at -8 sigma; the core about 40 sigma deep (kappa ~ 1 for a sphere's gradient frame) */
  CHECK(start == -8e-3 && core < -0.035 && core > -0.045, "sphere core: start %g, core %g", start, core);
  for (uint64_t seed = 0; seed < 32; ++seed) {
    /* from the start level, 30 degrees below the tangent plane: the ray reaches f = -0.134 */
    const double r = 1 + start;
    mf_track_query in = {v3(0, 0, r), normalize(v3(sqrt(3.0), 0, -1)), INFINITY, seed, 0, 0, 0};
    mf_transmittance t;
    EXPECT_OK(mf_track_transmittance(m, sphere, NULL, NULL, &in, &t));
    CHECK(t.transmittance == 0, "a ray into the core must be opaque (seed %llu: %g)", (unsigned long long)seed, t.transmittance);
  }
  /* The depth roulette: a ray from the mean surface 10 degrees below its tangent plane reaches
     15 sigma deep (bound ~ e^-120): never kept for u >= 1e-30; a grazing one (0.5 degree, 0.04
     sigma deep) always; a kept ray's estimate is of T / survival. */
  double survival = -1;
  EXPECT_OK(mf_track_depth_roulette(m, sphere, 0.0, -15e-3, 1e-30, &survival));
  CHECK(survival == 0, "a deep ray kept with %g", survival);
  EXPECT_OK(mf_track_depth_roulette(m, sphere, 0.0, -4e-5, 0.999, &survival));
  CHECK(survival == 1, "a grazing ray kept with %g", survival);
  EXPECT_OK(mf_track_depth_roulette(m, sphere, 0.0, 1e-3, 0.5, &survival));
  CHECK(survival == 1, "a ray that does not descend kept with %g", survival);
  EXPECT_OK(mf_track_depth_roulette(m, sphere, 0.0, -2e-3, 0.0, &survival)); /* ~2 sigma: kept at u = 0 */
  CHECK(survival > 0 && survival < 1, "2 sigma deep: survival %g", survival);
  {
    /* 5.7 degrees below the tangent plane from f = 0: the chord reaches 2.5 sigma deep */
    mf_track_query kept = {v3(0, 0, 1), normalize(v3(10, 0, -1)), INFINITY, 3, 0, survival, 0};
    mf_transmittance t;
    mf_collision c;
    EXPECT_OK(mf_track_transmittance(m, sphere, NULL, NULL, &kept, &t));
    CHECK(t.transmittance >= 0 && t.transmittance <= 1 / survival, "kept estimate %g (survival %g)", t.transmittance, survival);
    EXPECT_STATUS(mf_track_free_flight(m, sphere, NULL, NULL, &kept, &c), MF_ERROR_INVALID_ARGUMENT, "transmittances only");
    kept.survival = 1.5;
    EXPECT_STATUS(mf_track_transmittance(m, sphere, NULL, NULL, &kept, &t), MF_ERROR_INVALID_ARGUMENT, "survival");
    kept.survival = NAN;
    EXPECT_STATUS(mf_track_transmittance(m, sphere, NULL, NULL, &kept, &t), MF_ERROR_INVALID_ARGUMENT, "survival");
  }
  double keep = 7;
  EXPECT_STATUS(mf_track_depth_roulette(m, sphere, NAN, -1e-3, 0.5, &keep), MF_ERROR_INVALID_ARGUMENT, "NaN");
  EXPECT_STATUS(mf_track_depth_roulette(m, sphere, 0.0, NAN, 0.5, &keep), MF_ERROR_INVALID_ARGUMENT, "NaN");
  EXPECT_STATUS(mf_track_depth_roulette(m, sphere, 0.0, -1e-3, 1.0, &keep), MF_ERROR_INVALID_ARGUMENT, "u must be");
  EXPECT_STATUS(mf_track_depth_roulette(m, sphere, 0.0, -1e-3, -0.1, &keep), MF_ERROR_INVALID_ARGUMENT, "u must be");
  EXPECT_STATUS(mf_track_depth_roulette(NULL, sphere, 0.0, -1e-3, 0.5, &keep), MF_ERROR_NULL_POINTER, "medium");
  EXPECT_STATUS(mf_track_depth_roulette(m, NULL, 0.0, -1e-3, 0.5, &keep), MF_ERROR_NULL_POINTER, "surface");
  EXPECT_STATUS(mf_track_depth_roulette(m, sphere, 0.0, -1e-3, 0.5, NULL), MF_ERROR_NULL_POINTER, "out_survival");
  CHECK(keep == 7, "mf_track_depth_roulette wrote its out-parameter on failure");
  double mesh_start = 1, mesh_core = 1;
  EXPECT_OK(mf_track_opaque_core(m, mesh, &mesh_start, &mesh_core));
  CHECK(mesh_start == start && mesh_core <= core, "mesh core %g above the sphere's %g", mesh_core, core);
  double keep_start = 7, keep_core = 7;
  EXPECT_STATUS(mf_track_opaque_core(NULL, sphere, &keep_start, &keep_core), MF_ERROR_NULL_POINTER, "medium");
  EXPECT_STATUS(mf_track_opaque_core(m, NULL, &keep_start, &keep_core), MF_ERROR_NULL_POINTER, "surface");
  EXPECT_STATUS(mf_track_opaque_core(m, sphere, NULL, &keep_core), MF_ERROR_NULL_POINTER, "out_start_level");
  EXPECT_STATUS(mf_track_opaque_core(m, sphere, &keep_start, NULL), MF_ERROR_NULL_POINTER, "out_core_level");
  CHECK(keep_start == 7 && keep_core == 7, "mf_track_opaque_core wrote an out-parameter on failure");
  mf_surface_free(mesh);
  mf_surface_free(sphere);
  mf_medium_free(m);
}

static void test_surfaces_and_tracking(void) {
  mf_medium *m = gpss_conductor();
  mf_surface *sphere = NULL, *callbacks = NULL, *mesh = NULL;
  EXPECT_OK(mf_surface_new_sphere(v3(0, 0, 0), 1.0, false, v3(0, 0, 1), &sphere));
  mf_surface_callbacks cb = {host_sphere_point, NULL, MF_SURFACE_CONVEX, {-1, -1, -1}, {1, 1, 1}};
  EXPECT_OK(mf_surface_new_callbacks(&cb, &callbacks));
  /* An octahedron of radius 2 (closed). */
  const double octa_p[18] = {2, 0, 0, -2, 0, 0, 0, 2, 0, 0, -2, 0, 0, 0, 2, 0, 0, -2};
  const uint32_t octa_i[24] = {0, 2, 4, 2, 1, 4, 1, 3, 4, 3, 0, 4, 2, 0, 5, 1, 2, 5, 3, 1, 5, 0, 3, 5};
  mf_mesh octa = {octa_p, 6, octa_i, 8, NULL, NULL};
  EXPECT_OK(mf_surface_new_mesh(&octa, 1, INFINITY, &mesh));

  /* Point queries: the built-in and the host sphere agree; the octahedron's face distance. */
  host_sphere hs = {0, 0};
  mf_surface_point a, b;
  EXPECT_OK(mf_surface_eval(sphere, NULL, v3(0.3, 1.2, -0.4), &a));
  EXPECT_OK(mf_surface_eval(callbacks, &hs, v3(0.3, 1.2, -0.4), &b));
  CHECK(hs.calls == 1 && fabs(a.f - b.f) < 1e-15 && fabs(dot(a.normal, b.normal) - 1) < 1e-15, "sphere queries differ");
  EXPECT_OK(mf_surface_eval(mesh, NULL, v3(1, 1, 1), &a));
  CHECK_ABS(a.f, (3.0 - 2.0) / sqrt(3.0), 1e-12); /* plane x + y + z = 2 */
  mf_vec3 lo, hi;
  EXPECT_OK(mf_surface_bounding_box(mesh, &lo, &hi));
  CHECK(lo.x == -2 && hi.z == 2, "octahedron bounds (%g, %g)", lo.x, hi.z);

  /* Free flights and transmittance: same seed, same answer (built-in vs host sphere too). */
  double top = 0;
  EXPECT_OK(mf_medium_shell_top(m, &top));
  const mf_track_query q = {v3(0, 0, 1 + top), v3(0, 0, -1), INFINITY, 99, 0, 0, 0};
  mf_collision c1, c2;
  EXPECT_OK(mf_track_free_flight(m, sphere, NULL, NULL, &q, &c1));
  hs.calls = 0;
  EXPECT_OK(mf_track_free_flight(m, callbacks, NULL, &hs, &q, &c2));
  CHECK(c1.scattered && c2.scattered && fabs(c1.t - c2.t) < 1e-12 && fabs(dot(c1.frame.normal, c2.frame.normal) - 1) < 1e-12,
        "the host and the built-in sphere must track alike (t %.17g vs %.17g)", c1.t, c2.t);
  CHECK(hs.calls >= (int)c2.stats.surface_queries && c2.stats.segments > 0, "callback calls %d vs queries %u",
        hs.calls, c2.stats.surface_queries);
  CHECK(c1.t > 0 && c1.t < 1 + top && fabs(c1.p.z - (1 + top - c1.t)) < 1e-12 && c1.stats.majorant_violations == 0,
        "collision at t = %g, p.z = %g", c1.t, c1.p.z);
  CHECK(fabs(dot(c1.frame.normal, c1.frame.normal) - 1) < 1e-12, "collision frame normal must be unit");
  /* The collision's frame feeds the phase function; eval_pdf equals eval and pdf. */
  mf_phase_value vp;
  mf_rgb value;
  double pdf;
  const mf_vec3 wi = v3(0, 0, 1), wo = normalize(v3(0.3, 0.1, 0.9));
  EXPECT_OK(mf_phase_eval_pdf(m, &c1.frame, wi, wo, &vp));
  EXPECT_OK(mf_phase_eval(m, &c1.frame, wi, wo, &value));
  EXPECT_OK(mf_phase_pdf(m, &c1.frame, wi, wo, &pdf));
  CHECK(vp.pdf == pdf && same_bits(&vp.value, &value, sizeof value), "mf_phase_eval_pdf must equal eval and pdf");

  mf_transmittance t1, t2;
  const mf_track_query up = {v3(0, 0, 1), normalize(v3(0.2, 0, 1)), INFINITY, 5, 0, 0, 0};
  EXPECT_OK(mf_track_transmittance(m, sphere, NULL, NULL, &up, &t1));
  EXPECT_OK(mf_track_transmittance(m, sphere, NULL, NULL, &up, &t2));
  CHECK(t1.transmittance == t2.transmittance && t1.transmittance >= 0 && t1.transmittance <= 1,
        "transmittance %g / %g", t1.transmittance, t2.transmittance);
  /* Passing: t_max short of the shell. */
  const mf_track_query shortq = {v3(0, 0, 3), v3(0, 0, -1), 0.5, 5, 0, 0, 0};
  EXPECT_OK(mf_track_free_flight(m, mesh, NULL, NULL, &shortq, &c1));
  CHECK(!c1.scattered && c1.t == 0.5, "a ray that ends above the shell passes (t = %g)", c1.t);
  /* A mesh collision's hint: the calls that start there take it (mf_track_query::hint), and any
     value is safe (a foreign triangle's, none past the last): the same flight and transmittance. */
  const mf_track_query onto = {v3(0.6, 0.7, 3), v3(0, 0, -1), INFINITY, 7, 0, 0, 0};
  EXPECT_OK(mf_track_free_flight(m, mesh, NULL, NULL, &onto, &c1));
  CHECK(c1.scattered && c1.hint != 0, "a collision in an octahedron's face hands on a hint (%llu)", (unsigned long long)c1.hint);
  const uint64_t hints[4] = {c1.hint, c1.hint % 8 + 1, 9, UINT64_MAX};
  const mf_vec3 escape = normalize(v3(0.2, -0.1, 1));
  for (int h = 0; h < 4; ++h) {
    const mf_track_query plain = {c1.p, escape, INFINITY, 11, 0, 0, 0}, hinted = {c1.p, escape, INFINITY, 11, 0, 0, hints[h]};
    mf_collision e1, e2;
    EXPECT_OK(mf_track_free_flight(m, mesh, NULL, NULL, &plain, &e1));
    EXPECT_OK(mf_track_free_flight(m, mesh, NULL, NULL, &hinted, &e2));
    CHECK(e1.scattered == e2.scattered && (e1.t == e2.t || fabs(e1.t - e2.t) <= 1e-12 * (1 + e1.t)), "hint %llu: flight t %.17g vs %.17g",
          (unsigned long long)hints[h], e1.t, e2.t);
    EXPECT_OK(mf_track_transmittance(m, mesh, NULL, NULL, &plain, &t1));
    EXPECT_OK(mf_track_transmittance(m, mesh, NULL, NULL, &hinted, &t2));
    CHECK(fabs(t1.transmittance - t2.transmittance) <= 1e-12, "hint %llu: transmittance %.17g vs %.17g",
          (unsigned long long)hints[h], t1.transmittance, t2.transmittance);
  }

  /* Batches equal single calls. */
  mf_track_query qs[3] = {q, up, shortq};
  mf_collision cs[3];
  mf_transmittance ts[3];
  EXPECT_OK(mf_track_free_flight_batch(m, sphere, NULL, NULL, qs, 3, cs));
  EXPECT_OK(mf_track_transmittance_batch(m, sphere, NULL, NULL, qs, 3, ts));
  for (int i = 0; i < 3; ++i) {
    mf_collision c;
    mf_transmittance t;
    EXPECT_OK(mf_track_free_flight(m, sphere, NULL, NULL, &qs[i], &c));
    EXPECT_OK(mf_track_transmittance(m, sphere, NULL, NULL, &qs[i], &t));
    CHECK(c.scattered == cs[i].scattered && c.t == cs[i].t && same_bits(&c.p, &cs[i].p, sizeof c.p) &&
              same_bits(&c.frame, &cs[i].frame, sizeof c.frame) && t.transmittance == ts[i].transmittance,
          "batch entry %d differs", i);
  }
  EXPECT_OK(mf_track_free_flight_batch(m, sphere, NULL, NULL, NULL, 0, NULL));

  /* A bound that lies is caught by the violation count, and the call stays in range. */
  mf_surface *liar = NULL;
  mf_surface_callbacks lcb = {host_sphere_point, lying_bound, MF_SURFACE_GENERAL, {-1, -1, -1}, {1, 1, 1}};
  EXPECT_OK(mf_surface_new_callbacks(&lcb, &liar));
  hs.mode = 0;
  unsigned violations = 0;
  for (uint64_t seed = 0; seed < 50; ++seed) {
    mf_track_query lq = q;
    lq.seed = seed;
    EXPECT_OK(mf_track_free_flight(m, liar, NULL, &hs, &lq, &c1));
    /* (the ray's chord through the region f < top, whose majorant the lie understates) */
    CHECK(!c1.scattered || (c1.t >= 0 && c1.t <= 2 * (1 + top)), "t = %g outside the region", c1.t);
    violations += c1.stats.majorant_violations;
  }
  CHECK(violations > 0, "a lying bound must show as majorant violations");

  /* Bad input: statuses, untouched outputs, and a misbehaving host reported at once. */
  mf_collision before;
  memset(&c1, 0xA5, sizeof c1);
  before = c1;
#define TRACK_CASE(call, status, needle)                                                        \
  do {                                                                                          \
    EXPECT_STATUS(call, status, needle);                                                        \
    CHECK(same_bits(&before, &c1, sizeof c1), "%s wrote its out-parameter on failure", #call); \
  } while (0)
  mf_track_query bad = q;
  bad.d = v3(0, 0, -2);
  TRACK_CASE(mf_track_free_flight(m, sphere, NULL, NULL, &bad, &c1), MF_ERROR_INVALID_ARGUMENT, "d must be a unit vector");
  bad = q;
  bad.origin.x = NAN;
  TRACK_CASE(mf_track_free_flight(m, sphere, NULL, NULL, &bad, &c1), MF_ERROR_INVALID_ARGUMENT, "origin");
  bad = q;
  bad.t_max = -1;
  TRACK_CASE(mf_track_free_flight(m, sphere, NULL, NULL, &bad, &c1), MF_ERROR_INVALID_ARGUMENT, "t_max");
  /* An exit level must be 0 (none) or finite and at least the shell's top. */
  const double bad_levels[] = {NAN, -1, INFINITY, 0.5 * top};
  for (int i = 0; i < 4; ++i) {
    bad = q;
    bad.exit_level = bad_levels[i];
    TRACK_CASE(mf_track_free_flight(m, sphere, NULL, NULL, &bad, &c1), MF_ERROR_INVALID_ARGUMENT, "exit_level");
  }
  TRACK_CASE(mf_track_free_flight(NULL, sphere, NULL, NULL, &q, &c1), MF_ERROR_NULL_POINTER, "medium");
  TRACK_CASE(mf_track_free_flight(m, NULL, NULL, NULL, &q, &c1), MF_ERROR_NULL_POINTER, "surface");
  TRACK_CASE(mf_track_free_flight(m, sphere, NULL, NULL, NULL, &c1), MF_ERROR_NULL_POINTER, "query");
  EXPECT_STATUS(mf_track_free_flight(m, sphere, NULL, NULL, &q, NULL), MF_ERROR_NULL_POINTER, "out_collision");
  for (int mode = 1; mode <= 3; ++mode) {
    hs.mode = mode;
    hs.calls = 0;
    TRACK_CASE(mf_track_free_flight(m, callbacks, NULL, &hs, &q, &c1), mode == 3 ? MF_ERROR_CALLBACK : MF_ERROR_INVALID_ARGUMENT,
               mode == 3 ? "returned 42" : (mode == 1 ? "f must not be NaN" : "normal must be unit"));
    CHECK(hs.calls == 1, "a bad host answer must be reported at once (%d calls)", hs.calls);
  }
  hs.mode = 0;
  mf_surface *nan_bounds = NULL;
  mf_surface_callbacks ncb = {host_sphere_point, nan_bound, MF_SURFACE_GENERAL, {-1, -1, -1}, {1, 1, 1}};
  EXPECT_OK(mf_surface_new_callbacks(&ncb, &nan_bounds));
  TRACK_CASE(mf_track_free_flight(m, nan_bounds, NULL, &hs, &q, &c1), MF_ERROR_INVALID_ARGUMENT, "segment bound");
  /* A batch with one bad query writes nothing and names it. */
  qs[1].d = v3(1, 1, 1);
  memset(cs, 0xA5, sizeof cs);
  mf_collision cs_before[3];
  memcpy(cs_before, cs, sizeof cs);
  EXPECT_STATUS(mf_track_free_flight_batch(m, sphere, NULL, NULL, qs, 3, cs), MF_ERROR_INVALID_ARGUMENT, "query 1");
  CHECK(same_bits(cs_before, cs, sizeof cs), "a failed batch must write nothing");
  /* mf_track_transmittance and its batch: the same conventions, a failing host surface too. */
  mf_transmittance tr_out, tr_before;
  memset(&tr_out, 0xA5, sizeof tr_out);
  tr_before = tr_out;
  bad = q;
  bad.d = v3(0, 0, -2);
  EXPECT_STATUS(mf_track_transmittance(m, sphere, NULL, NULL, &bad, &tr_out), MF_ERROR_INVALID_ARGUMENT, "d must be a unit vector");
  EXPECT_STATUS(mf_track_transmittance(NULL, sphere, NULL, NULL, &q, &tr_out), MF_ERROR_NULL_POINTER, "medium");
  EXPECT_STATUS(mf_track_transmittance(m, NULL, NULL, NULL, &q, &tr_out), MF_ERROR_NULL_POINTER, "surface");
  EXPECT_STATUS(mf_track_transmittance(m, sphere, NULL, NULL, NULL, &tr_out), MF_ERROR_NULL_POINTER, "query");
  EXPECT_STATUS(mf_track_transmittance(m, sphere, NULL, NULL, &q, NULL), MF_ERROR_NULL_POINTER, "out_transmittance");
  hs.mode = 3;
  hs.calls = 0;
  EXPECT_STATUS(mf_track_transmittance(m, callbacks, NULL, &hs, &q, &tr_out), MF_ERROR_CALLBACK, "returned 42");
  CHECK(hs.calls == 1, "a failing host surface must end the call at once (%d calls)", hs.calls);
  hs.mode = 0;
  CHECK(same_bits(&tr_before, &tr_out, sizeof tr_out), "mf_track_transmittance wrote its out-parameter on failure");
  mf_transmittance ts_bad[3], ts_before[3];
  memset(ts_bad, 0xA5, sizeof ts_bad);
  memcpy(ts_before, ts_bad, sizeof ts_bad);
  EXPECT_STATUS(mf_track_transmittance_batch(m, sphere, NULL, NULL, qs, 3, ts_bad), MF_ERROR_INVALID_ARGUMENT, "query 1");
  EXPECT_STATUS(mf_track_transmittance_batch(m, sphere, NULL, NULL, NULL, 3, ts_bad), MF_ERROR_NULL_POINTER, "queries");
  EXPECT_STATUS(mf_track_transmittance_batch(NULL, sphere, NULL, NULL, qs, 3, ts_bad), MF_ERROR_NULL_POINTER, "medium");
  CHECK(same_bits(ts_before, ts_bad, sizeof ts_bad), "a failed transmittance batch must write nothing");
  EXPECT_OK(mf_track_transmittance_batch(m, sphere, NULL, NULL, NULL, 0, NULL));

  /* mf_phase_eval_pdf: bad directions, frame and pointers. */
  mf_phase_value pv_out, pv_before;
  memset(&pv_out, 0xA5, sizeof pv_out);
  pv_before = pv_out;
  EXPECT_STATUS(mf_phase_eval_pdf(NULL, &FRAME_Z, wi, wo, &pv_out), MF_ERROR_NULL_POINTER, "medium");
  EXPECT_STATUS(mf_phase_eval_pdf(m, NULL, wi, wo, &pv_out), MF_ERROR_NULL_POINTER, "frame");
  EXPECT_STATUS(mf_phase_eval_pdf(m, &FRAME_Z, v3(NAN, 0, 1), wo, &pv_out), MF_ERROR_INVALID_ARGUMENT, "wi must be finite");
  EXPECT_STATUS(mf_phase_eval_pdf(m, &FRAME_Z, wi, v3(1, 1, 0), &pv_out), MF_ERROR_INVALID_ARGUMENT, "wo must be a unit vector");
  EXPECT_STATUS(mf_phase_eval_pdf(m, &FRAME_Z, wi, wo, NULL), MF_ERROR_NULL_POINTER, "out_value");
  CHECK(same_bits(&pv_before, &pv_out, sizeof pv_out), "mf_phase_eval_pdf wrote its out-parameter on failure");

  /* mf_surface_bounding_box: both out-pointers are checked before either is written. */
  mf_vec3 lo_keep = {7, 7, 7}, hi_keep = {8, 8, 8};
  EXPECT_STATUS(mf_surface_bounding_box(NULL, &lo_keep, &hi_keep), MF_ERROR_NULL_POINTER, "surface");
  EXPECT_STATUS(mf_surface_bounding_box(mesh, &lo_keep, NULL), MF_ERROR_NULL_POINTER, "out_max");
  EXPECT_STATUS(mf_surface_bounding_box(mesh, NULL, &hi_keep), MF_ERROR_NULL_POINTER, "out_min");
  CHECK(lo_keep.x == 7 && hi_keep.x == 8, "mf_surface_bounding_box wrote an out-parameter on failure");
#undef TRACK_CASE

  /* Surface construction errors. */
  mf_surface *s = (mf_surface *)0x1;
  EXPECT_STATUS(mf_surface_new_sphere(v3(0, 0, 0), -1.0, false, v3(0, 0, 1), &s), MF_ERROR_INVALID_VALUE, "radius");
  EXPECT_STATUS(mf_surface_new_sphere(v3(0, 0, 0), 1.0, false, v3(0, 0, 0), &s), MF_ERROR_INVALID_ARGUMENT, "pole");
  mf_surface_callbacks no_point = {NULL, NULL, MF_SURFACE_CONVEX, {-1, -1, -1}, {1, 1, 1}};
  EXPECT_STATUS(mf_surface_new_callbacks(&no_point, &s), MF_ERROR_NULL_POINTER, "callbacks->point");
  mf_surface_callbacks bad_shape = {host_sphere_point, NULL, 9, {-1, -1, -1}, {1, 1, 1}};
  EXPECT_STATUS(mf_surface_new_callbacks(&bad_shape, &s), MF_ERROR_INVALID_ARGUMENT, "shape");
  mf_surface_callbacks bad_box = {host_sphere_point, NULL, MF_SURFACE_CONVEX, {1, -1, -1}, {-1, 1, 1}};
  EXPECT_STATUS(mf_surface_new_callbacks(&bad_box, &s), MF_ERROR_INVALID_ARGUMENT, "bounds_min");
  const uint32_t open_i[3] = {0, 2, 4};
  mf_mesh open = {octa_p, 6, open_i, 1, NULL, NULL};
  EXPECT_STATUS(mf_surface_new_mesh(&open, 1, INFINITY, &s), MF_ERROR_INVALID_ARGUMENT, "not closed");
  const uint32_t bad_i[3] = {0, 2, 40};
  mf_mesh out_of_range = {octa_p, 6, bad_i, 1, NULL, NULL};
  EXPECT_STATUS(mf_surface_new_mesh(&out_of_range, 1, INFINITY, &s), MF_ERROR_INVALID_ARGUMENT, "refers to vertex");
  mf_mesh no_positions = {NULL, 6, octa_i, 8, NULL, NULL};
  EXPECT_STATUS(mf_surface_new_mesh(&no_positions, 1, INFINITY, &s), MF_ERROR_NULL_POINTER, "mesh->positions");
  EXPECT_STATUS(mf_surface_new_mesh(&octa, MF_MAX_BUILD_THREADS + 1, INFINITY, &s), MF_ERROR_INVALID_ARGUMENT, "threads must be at most");
  EXPECT_STATUS(mf_surface_new_mesh(&octa, 1, NAN, &s), MF_ERROR_INVALID_ARGUMENT, "reach must be positive");
  EXPECT_STATUS(mf_surface_new_mesh(&octa, 1, 0.0, &s), MF_ERROR_INVALID_ARGUMENT, "reach must be positive");
  EXPECT_STATUS(mf_surface_new_mesh(&octa, 1, -1.0, &s), MF_ERROR_INVALID_ARGUMENT, "reach must be positive");
  CHECK(s == (mf_surface *)0x1, "a failed mf_surface_new_* wrote its out-parameter");
  EXPECT_STATUS(mf_surface_eval(sphere, NULL, v3(INFINITY, 0, 0), &a), MF_ERROR_INVALID_ARGUMENT, "p must be finite");

  /* A signed-distance grid (Mitsuba's sdfgrid layout): a sphere of radius 0.3 in the unit cube,
   * scaled by 2 and moved; queries near its surface follow the sphere, a ray through it
   * collides, and grids that are not distances are refused. */
  {
    enum { N = 16 };
    static float values[N * N * N];
    for (int z = 0; z < N; ++z)
      for (int y = 0; y < N; ++y)
        for (int x = 0; x < N; ++x) {
          const double px = x / (N - 1.0) - 0.5, py = y / (N - 1.0) - 0.5, pz = z / (N - 1.0) - 0.5;
          values[(z * N + y) * N + x] = (float)(sqrt(px * px + py * py + pz * pz) - 0.3);
        }
    mf_grid g = {values, N, N, N, {2, 0, 0, -1, 0, 2, 0, -1, 0, 0, 2, -1}};
    mf_surface *grid = NULL;
    EXPECT_OK(mf_surface_new_grid(&g, &grid));
    mf_surface_point gp;
    EXPECT_OK(mf_surface_eval(grid, NULL, v3(0.65, 0, 0), &gp));
    CHECK_ABS(gp.f, 0.05, 8e-3); /* trilinear error h²/8 × 2/|x| with h = 2/15 */
    CHECK(gp.normal.x > 0.99, "grid normal (%g, %g, %g)", gp.normal.x, gp.normal.y, gp.normal.z);
    const mf_track_query gq = {v3(-3, 0.01, 0.02), v3(1, 0, 0), INFINITY, 3, 0, 0, 0};
    EXPECT_OK(mf_track_free_flight(m, grid, NULL, NULL, &gq, &c1));
    CHECK(c1.scattered && c1.stats.majorant_violations == 0, "a ray into the grid sphere scatters");
    mf_surface *g2 = (mf_surface *)0x1;
    mf_grid skew = g;
    skew.to_world[0] = 3;
    EXPECT_STATUS(mf_surface_new_grid(&skew, &g2), MF_ERROR_INVALID_ARGUMENT, "uniform scale");
    mf_grid open_grid = g;
    open_grid.nx = 1;
    EXPECT_STATUS(mf_surface_new_grid(&open_grid, &g2), MF_ERROR_INVALID_ARGUMENT, "dimensions");
    mf_grid no_values = g;
    no_values.values = NULL;
    EXPECT_STATUS(mf_surface_new_grid(&no_values, &g2), MF_ERROR_NULL_POINTER, "grid->values");
    values[0] = -1;
    EXPECT_STATUS(mf_surface_new_grid(&g, &g2), MF_ERROR_INVALID_ARGUMENT, "inside the grid");
    values[0] = 1;
    CHECK(g2 == (mf_surface *)0x1, "a failed mf_surface_new_grid wrote its out-parameter");
    mf_surface_free(grid);
  }

  /* The enclosure of the shell around the octahedron: a closed, non-empty mesh. */
  mf_enclosure *e = NULL;
  EXPECT_OK(mf_surface_enclosure(mesh, NULL, top, 0.0, &e));
  mf_mesh em;
  EXPECT_OK(mf_enclosure_mesh(e, &em));
  CHECK(em.triangle_count > 0 && em.vertex_count > 0 && em.normals == NULL, "enclosure mesh %zu triangles",
        em.triangle_count);
  double max_x = -1e300;
  for (size_t i = 0; i < em.vertex_count; ++i) max_x = em.positions[3 * i] > max_x ? em.positions[3 * i] : max_x;
  CHECK(max_x >= 2 + top, "the enclosure must reach beyond the shell (%g)", max_x);
  mf_mesh em_keep = em;
  EXPECT_STATUS(mf_enclosure_mesh(NULL, &em_keep), MF_ERROR_NULL_POINTER, "enclosure");
  EXPECT_STATUS(mf_enclosure_mesh(e, NULL), MF_ERROR_NULL_POINTER, "out_mesh");
  CHECK(same_bits(&em_keep, &em, sizeof em), "mf_enclosure_mesh wrote its out-parameter on failure");
  /* Its exit level: no vertex lies above it. A ray from inside the shell with it ends outside
     the enclosure: at a collision, or where it found the ray outside (f above the level). */
  double exit_level = 0;
  EXPECT_OK(mf_enclosure_exit_level(e, &exit_level));
  CHECK(exit_level >= top && exit_level < 4 * top, "exit level %g for a shell top of %g", exit_level, top);
  for (size_t i = 0; i < em.vertex_count; ++i) {
    mf_surface_point at;
    EXPECT_OK(mf_surface_eval(mesh, NULL, v3(em.positions[3 * i], em.positions[3 * i + 1], em.positions[3 * i + 2]), &at));
    CHECK(at.f <= exit_level, "enclosure vertex %zu has f = %g above the exit level %g", i, at.f, exit_level);
  }
  const mf_track_query outward = {v3(2, 0, 0), v3(1, 0, 0), INFINITY, 7, exit_level, 0, 0};
  mf_collision out_c;
  mf_transmittance out_t;
  EXPECT_OK(mf_track_free_flight(m, mesh, NULL, NULL, &outward, &out_c));
  EXPECT_OK(mf_track_transmittance(m, mesh, NULL, NULL, &outward, &out_t));
  CHECK(out_c.scattered || (isfinite(out_c.t) && out_c.t <= max_x - 2 + exit_level),
        "a flight to the exit ends by the enclosure (t = %g)", out_c.t);
  CHECK(out_t.transmittance == 0 || (isfinite(out_t.t) && out_t.t <= max_x - 2 + exit_level),
        "a transmittance to the exit ends by the enclosure (t = %g)", out_t.t);
  double level_keep = -7;
  EXPECT_STATUS(mf_enclosure_exit_level(NULL, &level_keep), MF_ERROR_NULL_POINTER, "enclosure");
  EXPECT_STATUS(mf_enclosure_exit_level(e, NULL), MF_ERROR_NULL_POINTER, "out_level");
  CHECK(level_keep == -7, "mf_enclosure_exit_level wrote its out-parameter on failure");
  mf_enclosure_free(e);
  mf_enclosure_free(NULL);
  EXPECT_STATUS(mf_surface_enclosure(sphere, NULL, NAN, 0.0, &e), MF_ERROR_INVALID_ARGUMENT, "level");

  mf_surface_free(liar);
  mf_surface_free(nan_bounds);
  mf_surface_free(sphere);
  mf_surface_free(callbacks);
  mf_surface_free(mesh);
  mf_surface_free(NULL);
  mf_medium_free(m);
}

/* A host field for test_fields: sigma GPSS_SIGMA below the plane x = 0 and twice that above
 * (mode 0), the medium's own sigma everywhere (mode 1), a callback failure (mode 2), a negative
 * sigma (mode 3), unknown bits in `set` (mode 4). */
typedef struct host_field {
  int mode;
  int calls;
} host_field;

static double field_sigma(const host_field *h, double x) { return (h->mode == 0 && x >= 0) ? 2 * GPSS_SIGMA : GPSS_SIGMA; }

static int32_t field_at(void *user_data, mf_vec3 p, const mf_surface_point *point, mf_local_params *out) {
  host_field *h = (host_field *)user_data;
  (void)point;
  h->calls++;
  if (h->mode == 2) return 7;
  memset(out, 0, sizeof *out);
  out->set = h->mode == 4 ? 0x100 : MF_LOCAL_SIGMA;
  out->sigma = h->mode == 3 ? -1.0 : field_sigma(h, p.x);
  return 0;
}

static int32_t field_bounds(void *user_data, mf_vec3 p, mf_vec3 d, double length, mf_param_bounds *out) {
  host_field *h = (host_field *)user_data;
  const double x0 = p.x, x1 = p.x + length * d.x;
  out->set = MF_LOCAL_SIGMA;
  out->sigma_lo = field_sigma(h, x0 < x1 ? x0 : x1);
  out->sigma_hi = field_sigma(h, x0 < x1 ? x1 : x0);
  out->alpha_lo = out->alpha_hi = 0;
  return 0;
}

/* Spatially varying media (mf_field): a field of the medium's own values tracks exactly as no
 * field; a stepped field reports its local sigma at collisions; the _local phase calls equal the
 * plain ones without local parameters and scale with reflectance_scale; bad fields and bad
 * local parameters get statuses and messages. */
static void test_fields(void) {
  mf_medium *m = gpss_conductor();
  mf_surface *sphere = NULL;
  EXPECT_OK(mf_surface_new_sphere(v3(0, 0, 0), 1.0, false, v3(0, 0, 1), &sphere));
  mf_field *field = NULL, *unset = (mf_field *)0x1;
  mf_field_callbacks cb = {field_at, field_bounds, 2 * GPSS_SIGMA};
  EXPECT_OK(mf_field_new_callbacks(&cb, &field));
  mf_field_callbacks no_at = {NULL, field_bounds, 0}, no_bounds = {field_at, NULL, 0}, bad_max = {field_at, field_bounds, -1};
  EXPECT_STATUS(mf_field_new_callbacks(&no_at, &unset), MF_ERROR_NULL_POINTER, "callbacks->at");
  EXPECT_STATUS(mf_field_new_callbacks(&no_bounds, &unset), MF_ERROR_NULL_POINTER, "callbacks->bounds");
  EXPECT_STATUS(mf_field_new_callbacks(&bad_max, &unset), MF_ERROR_INVALID_ARGUMENT, "sigma_max");
  EXPECT_STATUS(mf_field_new_callbacks(NULL, &unset), MF_ERROR_NULL_POINTER, "callbacks");
  CHECK(unset == (mf_field *)0x1, "a failed mf_field_new_callbacks wrote its out-parameter");

  /* The medium's own sigma through a field (sigma_max 0: sigma does not vary): the same
   * collisions, bit for bit. */
  mf_field *own = NULL;
  mf_field_callbacks own_cb = {field_at, field_bounds, 0};
  EXPECT_OK(mf_field_new_callbacks(&own_cb, &own));
  host_field same = {1, 0};
  for (uint64_t seed = 0; seed < 20; ++seed) {
    const mf_track_query q = {v3(-3, 0.1, 0.2), v3(1, 0, 0), INFINITY, seed, 0, 0, 0};
    mf_collision plain, through;
    EXPECT_OK(mf_track_free_flight(m, sphere, NULL, NULL, &q, &plain));
    EXPECT_OK(mf_track_free_flight(m, sphere, own, &same, &q, &through));
    CHECK(plain.scattered == through.scattered && plain.t == through.t, "seed %u: t %.17g vs %.17g", (unsigned)seed,
          plain.t, through.t);
    CHECK(plain.local.set == 0 && (!through.scattered || (through.local.set == MF_LOCAL_SIGMA && through.local.sigma == GPSS_SIGMA)),
          "collision local parameters (set %u, sigma %g)", through.local.set, through.local.sigma);
  }
  CHECK(same.calls > 0, "the field must be asked");

  /* A stepped field: collisions on the far side (x > 0) report the doubled sigma. */
  host_field stepped = {0, 0};
  int far_side = 0;
  for (uint64_t seed = 0; seed < 40; ++seed) {
    const mf_track_query q = {v3(3, 0.2, 0.1), v3(-1, 0, 0), INFINITY, seed, 0, 0, 0};
    mf_collision c;
    EXPECT_OK(mf_track_free_flight(m, sphere, field, &stepped, &q, &c));
    CHECK(c.stats.majorant_violations == 0, "violations with honest bounds");
    if (c.scattered && c.p.x > 0) {
      far_side++;
      CHECK(c.local.sigma == 2 * GPSS_SIGMA, "local sigma %g at x = %g", c.local.sigma, c.p.x);
    }
    mf_transmittance t;
    EXPECT_OK(mf_track_transmittance(m, sphere, field, &stepped, &q, &t));
    CHECK(t.transmittance >= 0 && t.transmittance <= 1, "transmittance %g", t.transmittance);
  }
  CHECK(far_side > 20, "collisions on the stepped side: %d", far_side);

  /* The _local phase calls: NULL local parameters give the plain calls; a reflectance scale of
   * one half halves the value and the weight, not the density. */
  const mf_frame fr = {v3(0, 0, 1), v3(1, 0, 0)};
  const mf_vec3 wi = normalize(v3(0.2, 0.1, 1)), wo = normalize(v3(-0.3, 0.2, 0.9));
  mf_phase_value plain, local, half;
  EXPECT_OK(mf_phase_eval_pdf(m, &fr, wi, wo, &plain));
  EXPECT_OK(mf_phase_eval_pdf_local(m, NULL, &fr, wi, wo, &local));
  CHECK(same_bits(&plain, &local, sizeof plain), "eval_pdf_local(NULL) must equal eval_pdf");
  mf_local_params scale;
  memset(&scale, 0, sizeof scale);
  scale.set = MF_LOCAL_REFLECTANCE_SCALE;
  scale.reflectance_scale = (mf_rgb){0.5, 0.5, 0.5};
  EXPECT_OK(mf_phase_eval_pdf_local(m, &scale, &fr, wi, wo, &half));
  CHECK_ABS(half.value.r, 0.5 * plain.value.r, 1e-15);
  CHECK(half.pdf == plain.pdf, "the density does not depend on the reflectance");
  const double u[MF_PHASE_SAMPLE_DIMENSIONS] = {0.3, 0.6, 0.2, 0.5, 0.5};
  mf_phase_sample_result s0, s1, s2;
  EXPECT_OK(mf_phase_sample(m, &fr, wi, u, &s0));
  EXPECT_OK(mf_phase_sample_local(m, NULL, &fr, wi, u, &s1));
  EXPECT_OK(mf_phase_sample_local(m, &scale, &fr, wi, u, &s2));
  CHECK(s0.valid == s1.valid && s0.pdf == s1.pdf && same_bits(&s0.wo, &s1.wo, sizeof s0.wo) && same_bits(&s0.weight, &s1.weight, sizeof s0.weight),
        "sample_local(NULL) must equal sample");
  CHECK(s2.valid && same_bits(&s2.wo, &s0.wo, sizeof s0.wo) && fabs(s2.weight.g - 0.5 * s0.weight.g) < 1e-15,
        "a halved reflectance halves the weight (%g vs %g)", s2.weight.g, s0.weight.g);
  /* A local sigma and roughness change the medium the phase function sees. */
  mf_local_params rough;
  memset(&rough, 0, sizeof rough);
  rough.set = MF_LOCAL_ALPHA;
  rough.alpha = v3(0.9, 0.9, 0.9);
  EXPECT_OK(mf_phase_eval_pdf_local(m, &rough, &fr, wi, wo, &local));
  CHECK(local.pdf != plain.pdf, "a local roughness must change the phase function");

  /* Bad local parameters and bad fields: statuses and messages, outputs untouched. */
  mf_local_params bad = scale;
  bad.reflectance_scale = (mf_rgb){3, 3, 3};
  memset(&half, 0xA5, sizeof half);
  local = half;
  EXPECT_STATUS(mf_phase_eval_pdf_local(m, &bad, &fr, wi, wo, &half), MF_ERROR_INVALID_ARGUMENT, "outside [0, 1]");
  bad = rough;
  bad.alpha.x = NAN;
  EXPECT_STATUS(mf_phase_eval_pdf_local(m, &bad, &fr, wi, wo, &half), MF_ERROR_INVALID_ARGUMENT, "alpha");
  bad.set = 0x40;
  EXPECT_STATUS(mf_phase_sample_local(m, &bad, &fr, wi, u, &s2), MF_ERROR_INVALID_ARGUMENT, "unknown bits");
  memset(&bad, 0, sizeof bad);
  bad.set = MF_LOCAL_ANISOTROPY;
  bad.anisotropy[0] = 1, bad.anisotropy[1] = -1, bad.anisotropy[2] = 1;
  EXPECT_STATUS(mf_phase_eval_pdf_local(m, &bad, &fr, wi, wo, &half), MF_ERROR_INVALID_ARGUMENT, "positive definite");
  CHECK(same_bits(&half, &local, sizeof half), "a failed _local call wrote its out-parameter");
  const mf_track_query q = {v3(-3, 0.1, 0.2), v3(1, 0, 0), INFINITY, 1, 0, 0, 0};
  mf_collision c;
  host_field failing = {2, 0}, negative = {3, 0}, unknown = {4, 0};
  EXPECT_STATUS(mf_track_free_flight(m, sphere, field, &failing, &q, &c), MF_ERROR_CALLBACK, "returned 7");
  EXPECT_STATUS(mf_track_free_flight(m, sphere, field, &negative, &q, &c), MF_ERROR_INVALID_VALUE, "sigma");
  EXPECT_STATUS(mf_track_free_flight(m, sphere, field, &unknown, &q, &c), MF_ERROR_INVALID_ARGUMENT, "unknown bits");
  CHECK(failing.calls == 1 && negative.calls == 1, "a bad field answer must be reported at once");

  mf_field_free(field);
  mf_field_free(own);
  mf_field_free(NULL);
  mf_surface_free(sphere);
  mf_medium_free(m);
}

/* A host field for test_gpis_fields, sharing the trace's user_data with plane_sdf (which counts
 * in the first member): sigma 0.5 below x = 0 and 0.8 above with a reflectance scale of one half
 * (mode 0), nothing set (mode 1: the GPIS's own parameters), a callback failure (mode 2), a sigma
 * above the field's sigma_max (mode 3), a non-positive-definite anisotropy (mode 4). */
typedef struct gpis_host {
  int sdf_calls; /* first: plane_sdf increments *(int *)user_data */
  int mode;
  int field_calls;
} gpis_host;

static int32_t gpis_field_at(void *user_data, mf_vec3 p, const mf_surface_point *point, mf_local_params *out) {
  gpis_host *h = (gpis_host *)user_data;
  h->field_calls++;
  CHECK(fabs(point->f - p.z) < 1e-12 && point->normal.z == 1.0, "the field sees the mean: f %g at z %g", point->f, p.z);
  memset(out, 0, sizeof *out);
  switch (h->mode) {
    case 0:
      out->set = MF_LOCAL_SIGMA | MF_LOCAL_REFLECTANCE_SCALE;
      out->sigma = p.x < 0 ? 0.5 : 0.8;
      out->reflectance_scale = (mf_rgb){0.5, 0.5, 0.5};
      return 0;
    case 1:
      return 0;
    case 2:
      return 9;
    case 3:
      out->set = MF_LOCAL_SIGMA;
      out->sigma = 2.0;
      return 0;
    default:
      out->set = MF_LOCAL_SIGMA | MF_LOCAL_ANISOTROPY;
      out->sigma = 0.5;
      out->anisotropy[0] = 1, out->anisotropy[1] = 1, out->anisotropy[2] = 1, out->anisotropy[3] = 2;
      return 0;
  }
}

static int32_t gpis_field_bounds(void *user_data, mf_vec3 p, mf_vec3 d, double length, mf_param_bounds *out) {
  (void)user_data, (void)p, (void)d, (void)length;
  out->set = MF_LOCAL_SIGMA;
  out->sigma_lo = 0.5, out->sigma_hi = 0.8, out->alpha_lo = out->alpha_hi = 0;
  return 0;
}

/* mf_gpis_* with a field: a field that sets nothing traces exactly as no field; a stepped field
 * widens the envelope to shell_extent * sigma_max, reports its parameters at the crossings, and
 * its reflectance scale halves the scattering weight; bad fields get statuses and messages. */
static void test_gpis_fields(void) {
  mf_gpis *g = build_gpis("renewal_plus");
  mf_field *field = NULL;
  const mf_field_callbacks cb = {gpis_field_at, gpis_field_bounds, 0.8};
  EXPECT_OK(mf_field_new_callbacks(&cb, &field));
  double envelope = 0, own_envelope = 0;
  EXPECT_OK(mf_gpis_envelope(g, field, &envelope));
  EXPECT_OK(mf_gpis_envelope(g, NULL, &own_envelope));
  CHECK_REL(envelope, 6.0 * 0.8, 1e-15);
  CHECK_REL(own_envelope, 6.0, 1e-15);

  /* sigma_max 0: sigma does not vary (the GPIS's own 1 holds everywhere). */
  mf_field *own_field = NULL;
  const mf_field_callbacks own_cb = {gpis_field_at, gpis_field_bounds, 0};
  EXPECT_OK(mf_field_new_callbacks(&own_cb, &own_field));
  EXPECT_OK(mf_gpis_envelope(g, own_field, &own_envelope));
  CHECK_REL(own_envelope, 6.0, 1e-15);
  const mf_gpis_start free_start = {MF_GPIS_START_FREE, {0, 0, 0}};
  const mf_vec3 d = normalize(v3(0.3, 0.1, -1));
  gpis_host own = {0, 1, 0};
  for (uint64_t seed = 0; seed < 20; ++seed) {
    mf_gpis_hit plain, through;
    EXPECT_OK(mf_gpis_trace(g, plane_sdf, NULL, &own, v3(0, 0, 3), d, INFINITY, &free_start, seed, &plain));
    EXPECT_OK(mf_gpis_trace(g, plane_sdf, own_field, &own, v3(0, 0, 3), d, INFINITY, &free_start, seed, &through));
    CHECK(plain.hit && through.hit && plain.t == through.t && same_bits(&plain.gradient, &through.gradient, sizeof plain.gradient),
          "seed %u: a field of the GPIS's own parameters changed the realization (t %.17g vs %.17g)", (unsigned)seed, plain.t, through.t);
    CHECK(through.local.set == 0 && plain.local.set == 0, "nothing set: local.set %u", through.local.set);
  }
  CHECK(own.field_calls > 0, "the field must be asked");

  gpis_host stepped = {0, 0, 0};
  int left = 0, right = 0;
  for (uint64_t seed = 0; seed < 40; ++seed) {
    mf_gpis_hit h;
    const mf_vec3 origin = v3(seed % 2 ? 2.0 : -2.0, 0, envelope);
    EXPECT_OK(mf_gpis_trace(g, plane_sdf, field, &stepped, origin, v3(0, 0, -1), INFINITY, &free_start, seed, &h));
    CHECK(h.hit && h.local.set == (MF_LOCAL_SIGMA | MF_LOCAL_REFLECTANCE_SCALE), "stepped: hit %d, set %u", (int)h.hit, h.local.set);
    CHECK(h.local.sigma == (h.point.x < 0 ? 0.5 : 0.8), "local sigma %g at x = %g", h.local.sigma, h.point.x);
    left += h.point.x < 0, right += h.point.x >= 0;
    /* The crossing's reflectance scale halves the weight; the direction does not change. */
    phase_sample_t full, half;
    EXPECT_OK(mf_gpis_scatter(g, NULL, h.normal, h.normal, &full));
    EXPECT_OK(mf_gpis_scatter(g, &h.local, h.normal, h.normal, &half));
    CHECK(full.valid && half.valid && same_bits(&full.wo, &half.wo, sizeof full.wo) && fabs(half.weight.r - 0.5 * full.weight.r) < 1e-15,
          "reflectance scale: %g vs %g", half.weight.r, full.weight.r);
  }
  CHECK(left == 20 && right == 20, "crossings on both sides: %d, %d", left, right);

  /* Bad fields: the call fails at once with a status and a message, the output untouched. */
  const struct {
    int mode;
    mf_status status;
    const char *needle;
  } bad[] = {{2, MF_ERROR_CALLBACK, "returned 9"}, {3, MF_ERROR_INVALID_ARGUMENT, "sigma_max"}, {4, MF_ERROR_INVALID_ARGUMENT, "positive definite"}};
  for (size_t i = 0; i < sizeof bad / sizeof bad[0]; ++i) {
    gpis_host host = {0, bad[i].mode, 0};
    mf_gpis_hit h, before;
    memset(&h, 0xA5, sizeof h);
    before = h;
    EXPECT_STATUS(mf_gpis_trace(g, plane_sdf, field, &host, v3(0, 0, 3), d, INFINITY, &free_start, 1, &h), bad[i].status, bad[i].needle);
    CHECK(same_bits(&before, &h, sizeof h), "a failed field trace wrote its out-parameter");
    CHECK(host.field_calls == 1, "mode %d: a bad field answer must end the trace at once (%d calls)", bad[i].mode, host.field_calls);
  }
  mf_local_params too_bright;
  memset(&too_bright, 0, sizeof too_bright);
  too_bright.set = MF_LOCAL_REFLECTANCE_SCALE;
  too_bright.reflectance_scale = (mf_rgb){3, 3, 3};
  phase_sample_t s;
  EXPECT_STATUS(mf_gpis_scatter(g, &too_bright, v3(0, 0, 1), v3(0, 0, 1), &s), MF_ERROR_INVALID_ARGUMENT, "outside [0, 1]");
  too_bright.set = 0x40;
  EXPECT_STATUS(mf_gpis_scatter(g, &too_bright, v3(0, 0, 1), v3(0, 0, 1), &s), MF_ERROR_INVALID_ARGUMENT, "unknown bits");
  mf_field_free(field);
  mf_field_free(own_field);
  mf_gpis_free(g);
}


/* ------------------------------------------------------------------------------ mf_ndf */

static mf_ndf *build_ndf(const named_float *floats, const char *const *strings) {
  mf_params *p = NULL;
  mf_ndf *n = NULL;
  EXPECT_OK(mf_params_new(&p));
  for (; floats && floats->name; ++floats) EXPECT_OK(mf_params_set_float(p, floats->name, floats->value));
  for (; strings && strings[0]; strings += 2) EXPECT_OK(mf_params_set_string(p, strings[0], strings[1]));
  EXPECT_OK(mf_ndf_new(p, &n));
  mf_params_free(p);
  CHECK(n != NULL, "ndf not built: %s", last_error());
  return n;
}

/* Expects mf_ndf_new to fail with `want` and a message naming `needle`. */
static void expect_ndf_error(const named_float *floats, const char *const *strings, mf_status want, const char *needle) {
  mf_params *p = NULL;
  mf_ndf *n = (mf_ndf *)&g_rng; /* must stay untouched */
  EXPECT_OK(mf_params_new(&p));
  for (; floats && floats->name; ++floats) EXPECT_OK(mf_params_set_float(p, floats->name, floats->value));
  for (; strings && strings[0]; strings += 2) EXPECT_OK(mf_params_set_string(p, strings[0], strings[1]));
  EXPECT_STATUS(mf_ndf_new(p, &n), want, needle);
  CHECK(n == (mf_ndf *)&g_rng, "out_ndf written on failure");
  mf_params_free(p);
}

static void test_ndf(void) {
  /* GTR by name through mf_ndf_new: D and Lambda are finite and positive above the horizon
   * (their values: tests/ndf.rs, e.g. gtr_at_gamma_2_is_ggx_and_the_berry_limit_is_continuous;
   * FFI == core bit for bit: tests/ffi_abi.rs ndf_calls_equal_the_core_bit_for_bit). */
  const named_float f2[] = {{"alpha", 0.3}, {"gamma", 2.0}, {NULL, 0}};
  const char *const gtr[] = {"distribution", "gtr", NULL};
  mf_ndf *n = build_ndf(f2, gtr);
  for (int i = 0; i < 20; ++i) {
    mf_vec3 w = spherical(0.2 + 0.06 * i, 0.3 * i);
    double d = -1, lambda = -1;
    EXPECT_OK(mf_ndf_eval(n, &FRAME_Z, w, &d));
    EXPECT_OK(mf_ndf_lambda(n, &FRAME_Z, w, &lambda));
    CHECK(isfinite(d) && d > 0 && isfinite(lambda) && lambda > 0, "D %g, Lambda %g", d, lambda);
  }
  double horizon = 0;
  EXPECT_OK(mf_ndf_lambda(n, &FRAME_Z, v3(1, 0, 0), &horizon));
  CHECK(isinf(horizon) && horizon > 0, "Λ on the horizon: %g", horizon);
  mf_ndf_free(n);

  /* A stretched heavy-tailed GTR (seeds/001 Eq. 31): samples are visible unit normals whose
     reported density is mf_ndf_pdf_visible's; a tilted frame gives the same local answers. */
  const named_float f[] = {{"alpha", 0.3}, {"gamma", 1.5}, {"stretch", 0.5}, {NULL, 0}};
  n = build_ndf(f, gtr);
  basis b = basis_of(FRAME_TILTED);
  for (int i = 0; i < 200; ++i) {
    mf_vec3 wi_local = spherical(0.01 + 1.5 * uniform01(), 6.28 * uniform01());
    double u[MF_NDF_SAMPLE_DIMENSIONS] = {uniform01(), uniform01(), uniform01()};
    mf_ndf_sample s, t;
    EXPECT_OK(mf_ndf_sample_visible(n, &FRAME_Z, wi_local, u, &s));
    CHECK(s.valid, "no visible normal from above");
    CHECK_ABS(dot(s.m, s.m), 1.0, 1e-12);
    CHECK(dot(s.m, wi_local) > 0, "sampled normal faces away from wi");
    double pdf = 0;
    EXPECT_OK(mf_ndf_pdf_visible(n, &FRAME_Z, wi_local, s.m, &pdf));
    CHECK_REL(s.pdf, pdf, 1e-12);
    EXPECT_OK(mf_ndf_sample_visible(n, &FRAME_TILTED, to_world(b, wi_local), u, &t));
    mf_vec3 back = to_local(b, t.m);
    CHECK_ABS(back.x, s.m.x, 1e-9);
    CHECK_ABS(back.z, s.m.z, 1e-9);
  }
  /* Straight from below nothing of a height field is visible. */
  double u0[MF_NDF_SAMPLE_DIMENSIONS] = {0.5, 0.5, 0.5};
  mf_ndf_sample none;
  EXPECT_OK(mf_ndf_sample_visible(n, &FRAME_Z, v3(0, 0, -1), u0, &none));
  CHECK(!none.valid && none.pdf == 0.0, "visible normal from straight below");

  /* Bad arguments: a status, a message naming the argument, outputs untouched. */
  double x = 42;
  EXPECT_STATUS(mf_ndf_eval(NULL, &FRAME_Z, v3(0, 0, 1), &x), MF_ERROR_NULL_POINTER, "ndf");
  EXPECT_STATUS(mf_ndf_eval(n, NULL, v3(0, 0, 1), &x), MF_ERROR_NULL_POINTER, "frame");
  EXPECT_STATUS(mf_ndf_eval(n, &FRAME_Z, v3(0, 0, NAN), &x), MF_ERROR_INVALID_ARGUMENT, "m");
  EXPECT_STATUS(mf_ndf_lambda(n, &FRAME_Z, v3(0, 0, 2), &x), MF_ERROR_INVALID_ARGUMENT, "w");
  EXPECT_STATUS(mf_ndf_lambda(n, &FRAME_Z, v3(0, 0, 1), NULL), MF_ERROR_NULL_POINTER, "out_lambda");
  EXPECT_STATUS(mf_ndf_pdf_visible(n, &FRAME_Z, v3(0, 0, 1), v3(0, 0, 0), &x), MF_ERROR_INVALID_ARGUMENT, "m");
  CHECK(x == 42, "output written on failure");
  double bad_u[MF_NDF_SAMPLE_DIMENSIONS] = {0.5, 0.5, 1.0};
  mf_ndf_sample keep = {{7, 7, 7}, 7, true};
  EXPECT_STATUS(mf_ndf_sample_visible(n, &FRAME_Z, v3(0, 0, 1), bad_u, &keep), MF_ERROR_INVALID_ARGUMENT, "u[2]");
  EXPECT_STATUS(mf_ndf_sample_visible(n, &FRAME_Z, v3(0, 0, 1), NULL, &keep), MF_ERROR_NULL_POINTER, "u");
  CHECK(keep.pdf == 7 && keep.valid, "sample written on failure");
  mf_ndf_free(n);
  mf_ndf_free(NULL);

  /* Parameter errors name the parameter. */
  EXPECT_STATUS(mf_ndf_new(NULL, &n), MF_ERROR_NULL_POINTER, "params");
  const named_float no_gamma[] = {{"alpha", 0.3}, {NULL, 0}};
  expect_ndf_error(no_gamma, gtr, MF_ERROR_MISSING_PARAMETER, "gamma");
  const named_float big_gamma[] = {{"alpha", 0.3}, {"gamma", 4.5}, {NULL, 0}};
  expect_ndf_error(big_gamma, gtr, MF_ERROR_INVALID_VALUE, "gamma");
  const char *const ggx[] = {"distribution", "ggx", NULL};
  const named_float gamma_on_ggx[] = {{"alpha", 0.3}, {"gamma", 1.5}, {NULL, 0}};
  expect_ndf_error(gamma_on_ggx, ggx, MF_ERROR_UNKNOWN_PARAMETER, "gamma");
  const char *const bad_lambda[] = {"distribution", "gtr", "lambda", "smith", NULL};
  expect_ndf_error(f2, bad_lambda, MF_ERROR_INVALID_VALUE, "lambda");
  const char *const gpss[] = {"distribution", "gpss", NULL};
  expect_ndf_error(no_gamma, gpss, MF_ERROR_INVALID_VALUE, "distribution");
  const named_float partial[] = {{"alpha", 0.3}, {"transform_xx", 1}, {"transform_xy", 2}, {"transform_yx", 0}, {NULL, 0}};
  expect_ndf_error(partial, ggx, MF_ERROR_MISSING_PARAMETER, "transform_yy");
  const named_float singular[] = {{"alpha", 0.3}, {"transform_xx", 1}, {"transform_xy", 2}, {"transform_yx", 2}, {"transform_yy", 4}, {NULL, 0}};
  expect_ndf_error(singular, ggx, MF_ERROR_INVALID_VALUE, "transform_xx");
  const named_float both[] = {{"alpha", 0.3}, {"stretch", 0.2}, {"transform_xx", 1}, {"transform_xy", 0}, {"transform_yx", 0}, {"transform_yy", 1}, {NULL, 0}};
  expect_ndf_error(both, ggx, MF_ERROR_MISSING_PARAMETER, "stretch");
  const named_float stretch_one[] = {{"alpha", 0.3}, {"stretch", 1.0}, {NULL, 0}};
  expect_ndf_error(stretch_one, ggx, MF_ERROR_INVALID_VALUE, "stretch");
  const named_float sigma[] = {{"alpha", 0.3}, {"sigma", 0.1}, {NULL, 0}};
  expect_ndf_error(sigma, ggx, MF_ERROR_UNKNOWN_PARAMETER, "sigma");

  /* The medium takes the same names. */
  const named_float mf[] = {{"sigma", 0.1}, {"alpha_u", 0.2}, {"alpha_v", 0.5}, {"gamma", 1.2}, {"transform_xx", 1},
                            {"transform_xy", 2}, {"transform_yx", 0}, {"transform_yy", 1}, {NULL, 0}};
  const char *const gtr_dimov[] = {"distribution", "gtr", "lambda", "dimov", NULL};
  mf_medium *m = build(mf, gtr_dimov, NULL, NULL, NULL, NULL);
  double st = 0;
  EXPECT_OK(mf_medium_sigma_t(m, &FRAME_Z, 0.0, v3(0, 0.6, -0.8), &st));
  CHECK(st > 0 && isfinite(st), "sigma_t of a GTR medium: %g", st);
  mf_medium_free(m);
}

int main(void) {
  test_last_error_message(); /* first: checks the fresh-thread state */
  test_version_and_status();
  test_params_errors();
  test_medium_new_errors();
  test_medium_variants();
  test_query_ranges();
  test_phase();
  test_reference_values();
  test_batches();
  test_bad_query_arguments();
  test_gpis();
  test_surfaces_and_tracking();
  test_opaque_core();
  test_fields();
  test_gpis_fields();
  test_ndf();
  if (g_failures) {
    fprintf(stderr, "abi_test: %d of %d checks FAILED\n", g_failures, g_checks);
    return 1;
  }
  printf("abi_test: all %d checks passed\n", g_checks);
  return 0;
}
