# SPDX-License-Identifier: MIT
# abi_exports: the dynamic symbol table of libkissm.so is exactly the committed list tests/abi/kissm.symbols,
# which is exactly the set of KISSM_API functions declared in include/kissm.h, and every export is a
# function. (The linker version script src/kissm.map and hidden visibility make it so.)
#
#   cmake -DNM=nm -DLIBRARY=libkissm.so -DSYMBOLS=tests/abi/kissm.symbols -DHEADER=include/kissm.h
#         [-DUPDATE=1] -P check_exports.cmake
#
# UPDATE=1 rewrites SYMBOLS from the library instead (tests/abi/update_baseline.sh does this); review the
# diff: a removed line is an ABI break.
cmake_minimum_required(VERSION 3.16)
foreach(var NM LIBRARY SYMBOLS HEADER)
  if(NOT DEFINED ${var})
    message(FATAL_ERROR "check_exports.cmake: -D${var}=... is required")
  endif()
endforeach()

# --- the library's dynamic symbol table ------------------------------------------------------------
execute_process(COMMAND "${NM}" -D --defined-only "${LIBRARY}"
                OUTPUT_VARIABLE nm_out ERROR_VARIABLE nm_err RESULT_VARIABLE nm_rc)
if(NOT nm_rc EQUAL 0)
  message(FATAL_ERROR "${NM} -D --defined-only ${LIBRARY} failed (${nm_rc}): ${nm_err}")
endif()
string(REPLACE "\n" ";" nm_lines "${nm_out}")
set(exported)            # names as nm prints them (with @VERSION when the version script names nodes)
set(exported_functions)  # the same without version suffixes and version node names
set(not_functions)
foreach(line IN LISTS nm_lines)
  # "<address> <type> <name>"; a version node definition (a named node in the version script) is type A.
  if(line MATCHES "^[0-9a-fA-F]* *([A-Za-z]) (.+)$")
    set(type "${CMAKE_MATCH_1}")
    set(name "${CMAKE_MATCH_2}")
    list(APPEND exported "${name}")
    if(type STREQUAL "A")
      continue()
    endif()
    string(REGEX REPLACE "@.*$" "" base "${name}")
    list(APPEND exported_functions "${base}")
    if(NOT type MATCHES "^[Ti]$")
      list(APPEND not_functions "${name} (${type})")
    endif()
  endif()
endforeach()
list(SORT exported)
list(SORT exported_functions)
list(REMOVE_DUPLICATES exported_functions)

if(UPDATE)
  list(JOIN exported "\n" text)
  file(WRITE "${SYMBOLS}" "${text}\n")
  list(LENGTH exported n)
  message(STATUS "wrote ${SYMBOLS} (${n} symbols)")
  return()
endif()

# --- the committed list --------------------------------------------------------------------------------
file(STRINGS "${SYMBOLS}" committed)
set(expected)
foreach(line IN LISTS committed)
  string(STRIP "${line}" line)
  if(line AND NOT line MATCHES "^#")
    list(APPEND expected "${line}")
  endif()
endforeach()
set(sorted ${expected})
list(SORT sorted)
if(NOT sorted STREQUAL expected)
  message(SEND_ERROR "${SYMBOLS} is not sorted")
endif()

# --- the header's KISSM_API functions ---------------------------------------------------------------
file(READ "${HEADER}" header)
# Drop /* ... */ comments (CMake regexes have no non-greedy match).
set(stripped "")
while(TRUE)
  string(FIND "${header}" "/*" open)
  if(open EQUAL -1)
    string(APPEND stripped "${header}")
    break()
  endif()
  string(SUBSTRING "${header}" 0 ${open} before)
  string(APPEND stripped "${before} ")
  math(EXPR open "${open} + 2")
  string(SUBSTRING "${header}" ${open} -1 header)
  string(FIND "${header}" "*/" close)
  if(close EQUAL -1)
    message(FATAL_ERROR "${HEADER}: unterminated comment")
  endif()
  math(EXPR close "${close} + 2")
  string(SUBSTRING "${header}" ${close} -1 header)
endwhile()
# A declaration runs from KISSM_API to its semicolon; the #define lines of KISSM_API itself have none
# before the next preprocessor line. (Semicolons become backticks first: a CMake list splits on ';'.)
string(REPLACE ";" "`" stripped "${stripped}")
string(REGEX MATCHALL "KISSM_API[^`#{}]*`" declarations "${stripped}")
set(declared)
foreach(declaration IN LISTS declarations)
  if(declaration MATCHES "(kissm_[A-Za-z0-9_]+)[ \t\r\n]*\\(")
    list(APPEND declared "${CMAKE_MATCH_1}")
  else()
    message(SEND_ERROR "cannot find the function name in: ${declaration}")
  endif()
endforeach()
list(SORT declared)
list(REMOVE_DUPLICATES declared)

# --- compare --------------------------------------------------------------------------------------------
# report_difference(<title> <name of A> <list variable A> <name of B> <list variable B>)
function(report_difference title a_name a_var b_name b_var)
  set(only_a ${${a_var}})
  set(only_b ${${b_var}})
  if(${b_var})
    list(REMOVE_ITEM only_a ${${b_var}})
  endif()
  if(${a_var})
    list(REMOVE_ITEM only_b ${${a_var}})
  endif()
  if(only_a OR only_b)
    list(JOIN only_a "\n    " la)
    list(JOIN only_b "\n    " lb)
    message(SEND_ERROR "${title}\n  only in ${a_name}:\n    ${la}\n  only in ${b_name}:\n    ${lb}")
  endif()
endfunction()

report_difference("libkissm.so's exports differ from the committed list. A removed or renamed export breaks every program linked against an earlier libkissm.so.0; an added function needs the list updated (tests/abi/update_baseline.sh)."
                  "${LIBRARY}" exported "${SYMBOLS}" expected)
report_difference("libkissm.so's exports differ from the KISSM_API functions of the header (check src/kissm.map and that every exported function is declared with KISSM_API)."
                  "${LIBRARY}" exported_functions "${HEADER}" declared)
if(not_functions)
  list(JOIN not_functions ", " nf)
  message(SEND_ERROR "libkissm.so exports symbols that are not functions: ${nf}")
endif()

list(LENGTH exported n_exported)
list(LENGTH declared n_declared)
message(STATUS "libkissm.so exports ${n_exported} symbols; ${HEADER} declares ${n_declared} KISSM_API functions")
