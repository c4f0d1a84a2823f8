# cmake -DHEADER=<macrofacet.h> -DSOURCES=<file;...> -P CheckHeaderCoverage.cmake
#
# Fails when a function declared in the header is never called in the test sources, so that a
# function added to the ABI cannot go untested. A "call" is the name followed by "(" outside
# comments.
foreach(var HEADER SOURCES)
  if(NOT DEFINED ${var})
    message(FATAL_ERROR "CheckHeaderCoverage.cmake: ${var} is not set")
  endif()
endforeach()

file(READ "${HEADER}" header)
# Declarations: "<return type> mf_name(" at the start of a line (documentation lines start with
# " *", so they do not match).
string(REGEX MATCHALL "\n[A-Za-z_][A-Za-z0-9_ ]*[ *]+(mf_[a-z0-9_]+)\\(" decls "${header}")
set(functions "")
foreach(d IN LISTS decls)
  string(REGEX REPLACE ".*[ *](mf_[a-z0-9_]+)\\($" "\\1" name "${d}")
  list(APPEND functions "${name}")
endforeach()
list(REMOVE_DUPLICATES functions)
list(LENGTH functions count)
if(count LESS 10)
  message(FATAL_ERROR "found only ${count} functions in ${HEADER}: the declaration pattern is out of date")
endif()

set(code "")
foreach(src IN LISTS SOURCES)
  file(READ "${src}" text)
  # Drop /* ... */ and // comments.
  string(REGEX REPLACE "/\\*([^*]|\\*+[^*/])*\\*+/" "" text "${text}")
  string(REGEX REPLACE "//[^\n]*" "" text "${text}")
  string(APPEND code "${text}\n")
endforeach()

set(missing "")
foreach(f IN LISTS functions)
  if(NOT code MATCHES "[^A-Za-z0-9_]${f}[ \t\n]*\\(")
    list(APPEND missing "${f}")
  endif()
endforeach()
if(missing)
  list(JOIN missing "\n  " text)
  message(FATAL_ERROR "functions declared in ${HEADER} but never called by the ABI test:\n  ${text}")
endif()
message(STATUS "all ${count} functions of the header are called: ${functions}")
