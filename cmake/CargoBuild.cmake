# cmake -P script run by the build (see the top-level CMakeLists.txt): builds the crate's library
# targets with cargo, shows cargo's output live, and records what rustc reports as the native libs
# of the staticlib.
#
# Inputs (-D): CARGO, MANIFEST, PACKAGE (the workspace member), TARGET_DIR, PROFILE, SONAME,
# EXTRA_FLAGS (;-list), NATIVE_LIBS_FILE, ARTIFACTS (|-separated files cargo must have produced)
# and OUTPUTS (where each artifact is published, under the library's public name); for a
# profile-guided build PGO_PROFDATA (llvm-profdata; empty: a plain build) and PGO_DIR.
foreach(var CARGO MANIFEST PACKAGE TARGET_DIR PROFILE SONAME NATIVE_LIBS_FILE ARTIFACTS OUTPUTS)
  if(NOT DEFINED ${var})
    message(FATAL_ERROR "CargoBuild.cmake: ${var} is not set")
  endif()
endforeach()

# The flags rustc gets for every crate: the caller's (CARGO_ENCODED_RUSTFLAGS, else RUSTFLAGS),
# then the profile-guided build's. Passed encoded (separated by 0x1f), so that a build directory
# whose path holds spaces stays one argument.
string(ASCII 31 separator)
if(DEFINED ENV{CARGO_ENCODED_RUSTFLAGS})
  string(REPLACE "${separator}" ";" rustflags "$ENV{CARGO_ENCODED_RUSTFLAGS}")
else()
  separate_arguments(rustflags UNIX_COMMAND "$ENV{RUSTFLAGS}")
endif()
set(env "")
if(PGO_PROFDATA)
  # The training run (crates/macrofacet-ffi/examples/pgo_training.rs, in a target dir of its own):
  # the library instrumented by LLVM drives the C ABI as a host's path tracer does; llvm-profdata
  # merges what it counted; the library below is built from that profile.
  file(REMOVE_RECURSE "${PGO_DIR}/raw")
  set(training ${rustflags} "-Cprofile-generate=${PGO_DIR}/raw")
  string(REPLACE ";" "${separator}" training "${training}")
  message(STATUS "macrofacet: the profile-guided build's training run")
  execute_process(
    COMMAND "${CMAKE_COMMAND}" -E env "CARGO_ENCODED_RUSTFLAGS=${training}"
            "${CARGO}" run -p "${PACKAGE}" --example pgo_training --profile "${PROFILE}" --manifest-path "${MANIFEST}"
            --target-dir "${TARGET_DIR}/pgo-training" ${EXTRA_FLAGS}
    RESULT_VARIABLE result)
  if(NOT result EQUAL 0)
    message(FATAL_ERROR "the profile-guided build's training run failed (exit status ${result})")
  endif()
  execute_process(COMMAND "${PGO_PROFDATA}" merge -o "${PGO_DIR}/merged.profdata" "${PGO_DIR}/raw" RESULT_VARIABLE result)
  if(NOT result EQUAL 0)
    message(FATAL_ERROR "llvm-profdata could not merge the training run's profile (exit status ${result})")
  endif()
  list(APPEND rustflags "-Cprofile-use=${PGO_DIR}/merged.profdata")
endif()
if(rustflags)
  string(REPLACE ";" "${separator}" encoded "${rustflags}")
  set(env "${CMAKE_COMMAND}" -E env "CARGO_ENCODED_RUSTFLAGS=${encoded}")
endif()

# `cargo rustc --lib`: one rustc run makes the rlib, the staticlib and the cdylib. The extra rustc
# arguments reach only that final run: a SONAME for the .so and the native-libs report.
execute_process(
  COMMAND ${env} "${CARGO}" rustc -p "${PACKAGE}" --lib --profile "${PROFILE}" --manifest-path "${MANIFEST}"
          --target-dir "${TARGET_DIR}" ${EXTRA_FLAGS}
          -- "-Clink-arg=-Wl,-soname,${SONAME}" --print native-static-libs
  RESULT_VARIABLE result
  OUTPUT_VARIABLE out
  ERROR_VARIABLE err
  ECHO_OUTPUT_VARIABLE
  ECHO_ERROR_VARIABLE)
if(NOT result EQUAL 0)
  message(FATAL_ERROR "cargo failed (exit status ${result})")
endif()

# rustc prints the list only when it actually re-links; keep the last one seen.
string(REGEX MATCH "native-static-libs: ([^\n]*)" match "${out}\n${err}")
if(match)
  string(STRIP "${CMAKE_MATCH_1}" libs)
  file(WRITE "${NATIVE_LIBS_FILE}" "${libs}\n")
endif()

string(REPLACE "|" ";" artifacts "${ARTIFACTS}")
string(REPLACE "|" ";" outputs "${OUTPUTS}")
foreach(artifact f IN ZIP_LISTS artifacts outputs)
  if(NOT EXISTS "${artifact}")
    message(FATAL_ERROR "cargo succeeded but did not produce ${artifact}")
  endif()
  get_filename_component(dir "${f}" DIRECTORY)
  file(MAKE_DIRECTORY "${dir}")
  file(COPY_FILE "${artifact}" "${f}" ONLY_IF_DIFFERENT)
  # cargo leaves an up-to-date library untouched; mark it current so that the build does not
  # re-run this step every time (the inputs may be newer after a no-op edit).
  file(TOUCH_NOCREATE "${f}")
endforeach()
