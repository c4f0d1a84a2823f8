# cmake -DBUILD_DIR=... -DWORK_DIR=... -DCONSUMER_DIR=... -DC_COMPILER=... -DCXX_COMPILER=...
#       -DPKG_CONFIG=... -DGENERATOR=... -P ConsumerTest.cmake
#
# Installs the current build into a fresh prefix and uses it from outside:
#  1. `cmake --install` into WORK_DIR/prefix; the expected files are there.
#  2. tests/consumer (find_package(macrofacet 0.1), macrofacet::macrofacet) configures, builds
#     and runs against that prefix (static, shared and C++ programs).
#  3. pkg-config: a C file compiled against the installed macrofacet.pc, linked dynamically
#     (Libs) and statically (Libs.private), and run.
foreach(var BUILD_DIR WORK_DIR CONSUMER_DIR C_COMPILER CXX_COMPILER GENERATOR)
  if(NOT DEFINED ${var})
    message(FATAL_ERROR "ConsumerTest.cmake: ${var} is not set")
  endif()
endforeach()

function(run)
  cmake_parse_arguments(R "" "WORKING_DIRECTORY" "COMMAND;ENV" ${ARGN})
  if(NOT R_WORKING_DIRECTORY)
    set(R_WORKING_DIRECTORY "${WORK_DIR}")
  endif()
  list(JOIN R_COMMAND " " shown)
  message(STATUS "$ ${shown}")
  execute_process(COMMAND ${CMAKE_COMMAND} -E env ${R_ENV} ${R_COMMAND}
    WORKING_DIRECTORY "${R_WORKING_DIRECTORY}"
    RESULT_VARIABLE result OUTPUT_VARIABLE out ERROR_VARIABLE out)
  message("${out}")
  if(NOT result EQUAL 0)
    message(FATAL_ERROR "command failed (${result}): ${shown}")
  endif()
endfunction()

file(REMOVE_RECURSE "${WORK_DIR}")
file(MAKE_DIRECTORY "${WORK_DIR}")
set(prefix "${WORK_DIR}/prefix")

# 1. install
run(COMMAND "${CMAKE_COMMAND}" --install "${BUILD_DIR}" --prefix "${prefix}")
file(GLOB_RECURSE config "${prefix}/*/macrofacetConfig.cmake")
file(GLOB_RECURSE pc "${prefix}/*/macrofacet.pc")
if(NOT config OR NOT pc)
  message(FATAL_ERROR "install: macrofacetConfig.cmake or macrofacet.pc missing under ${prefix}")
endif()
get_filename_component(libdir "${pc}" DIRECTORY)
get_filename_component(libdir "${libdir}" DIRECTORY)
foreach(f "${libdir}/libmacrofacet.a" "${libdir}/libmacrofacet.so" "${prefix}/include/macrofacet.h"
          "${libdir}/cmake/macrofacet/macrofacetConfigVersion.cmake")
  if(NOT EXISTS "${f}")
    message(FATAL_ERROR "install: ${f} missing")
  endif()
endforeach()

# 2. find_package consumer
run(COMMAND "${CMAKE_COMMAND}" -S "${CONSUMER_DIR}" -B "${WORK_DIR}/build" -G "${GENERATOR}"
  "-DCMAKE_PREFIX_PATH=${prefix}" "-DCMAKE_C_COMPILER=${C_COMPILER}" "-DCMAKE_CXX_COMPILER=${CXX_COMPILER}"
  -DCMAKE_BUILD_TYPE=Release)
run(COMMAND "${CMAKE_COMMAND}" --build "${WORK_DIR}/build")
foreach(app app app_shared app_cpp)
  run(COMMAND "${WORK_DIR}/build/${app}")
endforeach()
# The shared consumer must depend on libmacrofacet.so by its SONAME (not a build path) and find it
# through the RPATH CMake gives it.
find_program(READELF readelf)
if(READELF)
  execute_process(COMMAND "${READELF}" -d "${WORK_DIR}/build/app_shared" OUTPUT_VARIABLE dyn)
  if(NOT dyn MATCHES "NEEDED[^\n]*\\[libmacrofacet\\.so\\]")
    message(FATAL_ERROR "app_shared does not record NEEDED libmacrofacet.so:\n${dyn}")
  endif()
  execute_process(COMMAND "${READELF}" -d "${WORK_DIR}/build/app" OUTPUT_VARIABLE dyn)
  if(dyn MATCHES "libmacrofacet")
    message(FATAL_ERROR "app (static by default) depends on the shared library:\n${dyn}")
  endif()
endif()

# 3. pkg-config consumer
if(NOT PKG_CONFIG)
  message(FATAL_ERROR "pkg-config not found: cannot test macrofacet.pc")
endif()
set(pc_env "PKG_CONFIG_PATH=${libdir}/pkgconfig")
execute_process(COMMAND ${CMAKE_COMMAND} -E env ${pc_env} "${PKG_CONFIG}" --modversion macrofacet
  OUTPUT_VARIABLE version OUTPUT_STRIP_TRAILING_WHITESPACE RESULT_VARIABLE result)
if(NOT result EQUAL 0 OR NOT version STREQUAL "0.1.0")
  message(FATAL_ERROR "pkg-config --modversion macrofacet: '${version}' (${result})")
endif()
execute_process(COMMAND ${CMAKE_COMMAND} -E env ${pc_env} "${PKG_CONFIG}" --cflags --libs macrofacet
  OUTPUT_VARIABLE flags OUTPUT_STRIP_TRAILING_WHITESPACE)
execute_process(COMMAND ${CMAKE_COMMAND} -E env ${pc_env} "${PKG_CONFIG}" --static --libs macrofacet
  OUTPUT_VARIABLE static_libs OUTPUT_STRIP_TRAILING_WHITESPACE)
execute_process(COMMAND ${CMAKE_COMMAND} -E env ${pc_env} "${PKG_CONFIG}" --cflags macrofacet
  OUTPUT_VARIABLE cflags OUTPUT_STRIP_TRAILING_WHITESPACE)
separate_arguments(flags UNIX_COMMAND "${flags}")
separate_arguments(static_libs UNIX_COMMAND "${static_libs}")
separate_arguments(cflags UNIX_COMMAND "${cflags}")
message(STATUS "pkg-config: --cflags --libs: ${flags}; --static --libs: ${static_libs}")
# Dynamic: Libs only; run with the library directory on the loader path.
run(COMMAND "${C_COMPILER}" -std=c11 -Wall -Wextra -Werror "${CONSUMER_DIR}/main.c" ${flags} -lm -o "${WORK_DIR}/pc_dynamic")
run(COMMAND "${WORK_DIR}/pc_dynamic" ENV "LD_LIBRARY_PATH=${libdir}")
# Static: the archive itself plus Libs.private (the native libs of the Rust staticlib).
list(TRANSFORM static_libs REPLACE "^-lmacrofacet$" "-l:libmacrofacet.a")
run(COMMAND "${C_COMPILER}" -std=c11 -Wall -Wextra -Werror "${CONSUMER_DIR}/main.c" ${cflags} ${static_libs} -o "${WORK_DIR}/pc_static")
run(COMMAND "${WORK_DIR}/pc_static")
execute_process(COMMAND "${READELF}" -d "${WORK_DIR}/pc_static" OUTPUT_VARIABLE dyn)
if(dyn MATCHES "libmacrofacet")
  message(FATAL_ERROR "pc_static depends on the shared library:\n${dyn}")
endif()
message(STATUS "install + find_package + pkg-config consumers: OK")
