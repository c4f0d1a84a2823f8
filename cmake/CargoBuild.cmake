# cmake -P script run by the build (see the top-level CMakeLists.txt): builds the crate's library
# targets with cargo, shows cargo's output live, and records what rustc reports as the native libs
# of the staticlib.
#
# Inputs (-D): CARGO, MANIFEST, PACKAGE (the workspace member), TARGET_DIR, PROFILE, SONAME,
# EXTRA_FLAGS (;-list), NATIVE_LIBS_FILE, ARTIFACTS (|-separated files cargo must have produced)
# and OUTPUTS (where each artifact is published, under the library's public name).
foreach(var CARGO MANIFEST PACKAGE TARGET_DIR PROFILE SONAME NATIVE_LIBS_FILE ARTIFACTS OUTPUTS)
  if(NOT DEFINED ${var})
    message(FATAL_ERROR "CargoBuild.cmake: ${var} is not set")
  endif()
endforeach()

# `cargo rustc --lib`: one rustc run makes the rlib, the staticlib and the cdylib. The extra rustc
# arguments reach only that final run: a SONAME for the .so and the native-libs report.
execute_process(
  COMMAND "${CARGO}" rustc -p "${PACKAGE}" --lib --profile "${PROFILE}" --manifest-path "${MANIFEST}"
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
