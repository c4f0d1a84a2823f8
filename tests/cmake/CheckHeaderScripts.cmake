# cmake -DSOURCE_DIR=<repo> -DWORK_DIR=<scratch> -DCARGO_BIN_DIR=<dir> -P CheckHeaderScripts.cmake
#
# The header scripts fail loudly when they should:
#  1. scripts/check_header.sh against a stale copy of the header exits non-zero and shows the diff.
#  2. scripts/generate_header.sh with a cbindgen of another version in PATH exits non-zero, says
#     which version it needs, and writes nothing.
file(REMOVE_RECURSE "${WORK_DIR}")
file(MAKE_DIRECTORY "${WORK_DIR}/fakebin")

# 1. stale header
file(READ "${SOURCE_DIR}/include/macrofacet.h" header)
file(WRITE "${WORK_DIR}/stale.h" "${header}/* a hand edit */\n")
execute_process(
  COMMAND "${CMAKE_COMMAND}" -E env "MF_CHECK_HEADER=${WORK_DIR}/stale.h" "PATH=$ENV{PATH}:${CARGO_BIN_DIR}"
          "${SOURCE_DIR}/scripts/check_header.sh"
  RESULT_VARIABLE result OUTPUT_VARIABLE out ERROR_VARIABLE out)
if(result EQUAL 0 OR NOT out MATCHES "is stale" OR NOT out MATCHES "\n-/\\* a hand edit \\*/")
  message(FATAL_ERROR "check_header.sh did not reject a stale header (exit ${result}):\n${out}")
endif()
message(STATUS "stale header rejected with the diff")

# 2. wrong cbindgen version
file(WRITE "${WORK_DIR}/fakebin/cbindgen" "#!/bin/sh\necho 'cbindgen 0.26.0'\n")
file(CHMOD "${WORK_DIR}/fakebin/cbindgen" PERMISSIONS OWNER_READ OWNER_WRITE OWNER_EXECUTE)
execute_process(
  COMMAND "${CMAKE_COMMAND}" -E env "PATH=${WORK_DIR}/fakebin:$ENV{PATH}"
          "${SOURCE_DIR}/scripts/generate_header.sh" "${WORK_DIR}/out.h"
  RESULT_VARIABLE result OUTPUT_VARIABLE out ERROR_VARIABLE out)
if(result EQUAL 0 OR NOT out MATCHES "need cbindgen 0\\.29\\.4, found 'cbindgen 0\\.26\\.0'" OR EXISTS "${WORK_DIR}/out.h")
  message(FATAL_ERROR "generate_header.sh accepted cbindgen 0.26.0 (exit ${result}):\n${out}")
endif()
message(STATUS "wrong cbindgen version rejected: ${out}")
