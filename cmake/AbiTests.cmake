# The C/C++ ABI tests of libmacrofacet (included from the top-level CMakeLists.txt).
#
#   abi_test_c            tests/c/abi_test.c against libmacrofacet.a (C11)
#   abi_test_c_shared     the same program against libmacrofacet.so
#   abi_test_c_asan       the same program with AddressSanitizer + UBSan, leak detection on
#   abi_test_cpp          tests/cpp/abi_test.cpp (C++17): RAII handles, 8 threads on one medium
#   header_only_c/_cpp    the header alone compiles as pedantic C11 and C++17, included twice
#   abi_test_covers_header  every function declared in the header is called by abi_test.c
#   header_fresh          include/macrofacet.h equals what cbindgen 0.29.4 generates now
#   header_scripts_fail_loudly  check_header.sh rejects a stale header, generate_header.sh a
#                         cbindgen of another version
#   native_static_libs    the libs rustc printed for the crate equal the configured ones
#   install_consumer      cmake --install into a temp prefix; find_package + pkg-config consumers
#   rust_ffi_abi          (MF_TEST_CARGO=ON) cargo test -p macrofacet-ffi --test ffi_abi: FFI == core, bit for bit

set(MF_C_WARNINGS -Wall -Wextra -Werror -pedantic)
set(MF_TESTS_DIR "${CMAKE_CURRENT_SOURCE_DIR}/tests")

function(mf_c_test name link)
  add_executable(${name} "${MF_TESTS_DIR}/c/abi_test.c")
  set_target_properties(${name} PROPERTIES C_STANDARD 11 C_STANDARD_REQUIRED ON C_EXTENSIONS OFF)
  target_compile_options(${name} PRIVATE ${MF_C_WARNINGS})
  target_link_libraries(${name} PRIVATE ${link} m)
endfunction()

mf_c_test(abi_test_c macrofacet::macrofacet_static)
add_test(NAME abi_test_c COMMAND abi_test_c)

mf_c_test(abi_test_c_shared macrofacet::macrofacet_shared)
add_test(NAME abi_test_c_shared COMMAND abi_test_c_shared)

# Sanitizers: the Rust code is not instrumented, but ASan replaces malloc/free for the whole
# process, so leaked handles (every *_new must meet its *_free) and bad accesses from C show up.
set(MF_SANITIZE -fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=undefined -g)
mf_c_test(abi_test_c_asan macrofacet::macrofacet_static)
target_compile_options(abi_test_c_asan PRIVATE ${MF_SANITIZE})
target_link_options(abi_test_c_asan PRIVATE ${MF_SANITIZE})
add_test(NAME abi_test_c_asan COMMAND abi_test_c_asan)
set_tests_properties(abi_test_c_asan PROPERTIES
  ENVIRONMENT "ASAN_OPTIONS=detect_leaks=1:abort_on_error=0:strict_string_checks=1;UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1")

find_package(Threads REQUIRED)
add_executable(abi_test_cpp "${MF_TESTS_DIR}/cpp/abi_test.cpp")
set_target_properties(abi_test_cpp PROPERTIES CXX_STANDARD 17 CXX_STANDARD_REQUIRED ON CXX_EXTENSIONS OFF)
target_compile_options(abi_test_cpp PRIVATE ${MF_C_WARNINGS})
target_link_libraries(abi_test_cpp PRIVATE macrofacet::macrofacet Threads::Threads)
add_test(NAME abi_test_cpp COMMAND abi_test_cpp)

# Header-only compile tests: the build fails if the header is not pedantic C11 / C++17 or is not
# protected against double inclusion; the programs also check a few things at run time.
add_executable(header_only_c "${MF_TESTS_DIR}/c/header_only.c")
set_target_properties(header_only_c PROPERTIES C_STANDARD 11 C_STANDARD_REQUIRED ON C_EXTENSIONS OFF)
target_compile_options(header_only_c PRIVATE ${MF_C_WARNINGS})
target_include_directories(header_only_c PRIVATE "${MF_INCLUDE_DIR}")
add_test(NAME header_only_c COMMAND header_only_c)
add_executable(header_only_cpp "${MF_TESTS_DIR}/cpp/header_only.cpp")
set_target_properties(header_only_cpp PROPERTIES CXX_STANDARD 17 CXX_STANDARD_REQUIRED ON CXX_EXTENSIONS OFF)
target_compile_options(header_only_cpp PRIVATE ${MF_C_WARNINGS})
target_include_directories(header_only_cpp PRIVATE "${MF_INCLUDE_DIR}")
add_test(NAME header_only_cpp COMMAND header_only_cpp)

add_test(NAME abi_test_covers_header
  COMMAND "${CMAKE_COMMAND}"
    "-DHEADER=${MF_INCLUDE_DIR}/macrofacet.h"
    "-DSOURCES=${MF_TESTS_DIR}/c/abi_test.c"
    -P "${MF_TESTS_DIR}/cmake/CheckHeaderCoverage.cmake")

add_test(NAME header_fresh COMMAND "${CMAKE_CURRENT_SOURCE_DIR}/scripts/check_header.sh")
set_tests_properties(header_fresh PROPERTIES
  ENVIRONMENT "PATH=${MF_CARGO_BIN_DIR}:$ENV{PATH}")

add_test(NAME header_scripts_fail_loudly
  COMMAND "${CMAKE_COMMAND}"
    "-DSOURCE_DIR=${CMAKE_CURRENT_SOURCE_DIR}"
    "-DWORK_DIR=${CMAKE_BINARY_DIR}/header-scripts-test"
    "-DCARGO_BIN_DIR=${MF_CARGO_BIN_DIR}"
    -P "${MF_TESTS_DIR}/cmake/CheckHeaderScripts.cmake")

add_test(NAME native_static_libs
  COMMAND "${CMAKE_COMMAND}"
    "-DFILE=${CMAKE_BINARY_DIR}/cargo-native-static-libs.txt"
    "-DEXPECTED=${MF_NATIVE_LIBS_STRING}"
    -P "${MF_TESTS_DIR}/cmake/CheckNativeLibs.cmake")

find_program(MF_PKG_CONFIG NAMES pkg-config pkgconf)
add_test(NAME install_consumer
  COMMAND "${CMAKE_COMMAND}"
    "-DBUILD_DIR=${CMAKE_BINARY_DIR}"
    "-DWORK_DIR=${CMAKE_BINARY_DIR}/consumer-test"
    "-DCONSUMER_DIR=${MF_TESTS_DIR}/consumer"
    "-DC_COMPILER=${CMAKE_C_COMPILER}"
    "-DCXX_COMPILER=${CMAKE_CXX_COMPILER}"
    "-DPKG_CONFIG=${MF_PKG_CONFIG}"
    "-DGENERATOR=${CMAKE_GENERATOR}"
    -P "${MF_TESTS_DIR}/cmake/ConsumerTest.cmake")
set_tests_properties(install_consumer PROPERTIES TIMEOUT 300)

# Its own target dir: `cargo test` and the `cargo rustc` of the library build would otherwise
# overwrite each other's artifacts and rebuild the crate every time.
if(MF_TEST_CARGO)
  add_test(NAME rust_ffi_abi
    COMMAND "${MF_CARGO}" test --profile "${MF_CARGO_PROFILE}" -p macrofacet-ffi --test ffi_abi
      --manifest-path "${CMAKE_CURRENT_SOURCE_DIR}/Cargo.toml" --target-dir "${CMAKE_BINARY_DIR}/cargo-test" ${MF_CARGO_FLAGS})
  set_tests_properties(rust_ffi_abi PROPERTIES TIMEOUT 600)
endif()

# The integration example of the README ("Use it in your renderer"): a plain-C path tracer that
# renders a thin-shell and a fuzzy sphere with the tracking API; built with the ABI tests' strict
# warnings and run small (it exits 1 on any library error or a non-finite/zero image).
add_executable(render_spheres "${CMAKE_CURRENT_SOURCE_DIR}/examples/c/render_spheres.c")
set_target_properties(render_spheres PROPERTIES C_STANDARD 11 C_STANDARD_REQUIRED ON C_EXTENSIONS OFF)
target_compile_options(render_spheres PRIVATE ${MF_C_WARNINGS})
target_link_libraries(render_spheres PRIVATE macrofacet::macrofacet_static m)
add_test(NAME example_render_spheres COMMAND render_spheres 64 32 8 "${CMAKE_CURRENT_BINARY_DIR}/render_spheres.ppm")
