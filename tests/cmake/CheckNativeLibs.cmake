# cmake -DFILE=<cargo-native-static-libs.txt> -DEXPECTED="<-l...>" -P CheckNativeLibs.cmake
#
# The imported target and the installed package link the native libs that rustc reported at
# configure time for an empty staticlib (cmake/NativeStaticLibs.cmake). This checks that the
# crate's own staticlib, as built by cargo, reports exactly the same list (a dependency that
# links a system library would make them differ).
if(NOT EXISTS "${FILE}")
  message(FATAL_ERROR "${FILE} does not exist: the cargo step did not record rustc's native-static-libs")
endif()
file(READ "${FILE}" actual)
string(STRIP "${actual}" actual)
string(STRIP "${EXPECTED}" EXPECTED)
if(NOT actual STREQUAL EXPECTED)
  message(FATAL_ERROR "native libs of the crate's staticlib: '${actual}'\nconfigured (and installed) list: '${EXPECTED}'\nre-run cmake")
endif()
message(STATUS "native-static-libs: ${actual}")
