# mf_native_static_libs(<out-var>)
#
# The system libraries that a Rust staticlib must be linked with on this target, as rustc's
# `--print native-static-libs` reports them (e.g. "-lgcc_s -lutil -lrt -lpthread -lm -ldl -lc").
# They come from std (unwinder, threads, dlsym, maths), not from the crate: macrofacet's
# dependencies (glam, libm) link nothing native. So rustc is asked once, at configure time, about
# an empty staticlib, which takes a fraction of a second and needs no cargo build. The cargo build
# itself records the crate's own list (cmake/CargoBuild.cmake) and a test compares the two.
function(mf_native_static_libs out_var)
  set(dir "${CMAKE_BINARY_DIR}/native-static-libs-probe")
  file(MAKE_DIRECTORY "${dir}")
  file(WRITE "${dir}/probe.rs" "// an empty staticlib: only std\n")
  execute_process(
    COMMAND "${MF_RUSTC}" --crate-type staticlib --crate-name probe --edition 2021
            --print native-static-libs -o "${dir}/libprobe.a" "${dir}/probe.rs"
    RESULT_VARIABLE result
    OUTPUT_VARIABLE out
    ERROR_VARIABLE err)
  string(REGEX MATCH "native-static-libs: ([^\n]*)" match "${out}\n${err}")
  if(NOT result EQUAL 0 OR NOT match)
    message(FATAL_ERROR "macrofacet: could not ask rustc for the native libs of a staticlib:\n${out}\n${err}")
  endif()
  string(STRIP "${CMAKE_MATCH_1}" libs)
  separate_arguments(libs UNIX_COMMAND "${libs}")
  set(${out_var} "${libs}" PARENT_SCOPE)
endfunction()
