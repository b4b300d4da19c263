# SPDX-License-Identifier: MIT
# abi_static_symbols: what libkissm.a can clash with when a program links it statically.
#
#   cmake -DNM=nm -DARCHIVE=libkissm.a -DSYMBOLS=tests/abi/kissm.symbols -DNAMESPACE=v0_1 -P check_static_symbols.cmake
#
# Every global symbol the archive defines must be one of:
#  - a C API function listed in kissm.symbols;
#  - a C++ symbol of kissm's inline versioned namespace kissm::<NAMESPACE> (v<major>_<minor> of the
#    project version: a host's own kissm::detail, or another kissm version's, then has other mangled
#    names), including template instantiations and typeinfo that mention kissm types;
#  - a weak (W/V/u) instantiation of a standard-library or Eigen template: the linker merges it with the
#    host's identical copy, which is how every C++ static library works.
# Anything else, in particular a strong symbol outside kissm_* and the versioned namespace (a C helper
# `voxelize`, a global variable, an unversioned kissm::detail function) could clash with a host's symbol.
cmake_minimum_required(VERSION 3.16)
foreach(var NM ARCHIVE SYMBOLS NAMESPACE)
  if(NOT DEFINED ${var})
    message(FATAL_ERROR "check_static_symbols.cmake: -D${var}=... is required")
  endif()
endforeach()

file(STRINGS "${SYMBOLS}" api REGEX "^kissm_")
string(LENGTH "${NAMESPACE}" ns_length)
set(versioned "5kissm${ns_length}${NAMESPACE}")  # the mangled prefix of kissm::<NAMESPACE>

execute_process(COMMAND "${NM}" -g --defined-only -P "${ARCHIVE}"
                OUTPUT_VARIABLE nm_out ERROR_VARIABLE nm_err RESULT_VARIABLE nm_rc)
if(NOT nm_rc EQUAL 0)
  message(FATAL_ERROR "${NM} -g --defined-only -P ${ARCHIVE} failed (${nm_rc}): ${nm_err}")
endif()
# Mangled names may contain brackets, which would stop CMake from splitting the list on ';'.
string(REPLACE "[" "(" nm_out "${nm_out}")
string(REPLACE "]" ")" nm_out "${nm_out}")
string(REPLACE "\n" ";" nm_lines "${nm_out}")

set(member "")
set(bad)
set(n_api 0)
set(n_versioned 0)
set(n_weak_other 0)
foreach(line IN LISTS nm_lines)
  if(line MATCHES "^(.*):$")  # "libkissm.a(file.o):"
    set(member "${CMAKE_MATCH_1}")
    continue()
  endif()
  if(NOT line MATCHES "^([^ ]+) ([A-Za-z]) ")
    continue()
  endif()
  set(name "${CMAKE_MATCH_1}")
  set(type "${CMAKE_MATCH_2}")
  if(name MATCHES "^kissm_")
    if(name IN_LIST api)
      math(EXPR n_api "${n_api} + 1")
    else()
      list(APPEND bad "${name} (${type}, ${member}): a C symbol named kissm_* that is not in the public API")
    endif()
    continue()
  endif()
  if(name MATCHES "5kissm")
    # Every kissm name inside the mangled name must be kissm::<NAMESPACE>.
    string(REPLACE "${versioned}" "" rest "${name}")
    if(rest MATCHES "5kissm")
      list(APPEND bad "${name} (${type}, ${member}): kissm C++ code outside the inline namespace kissm::${NAMESPACE}")
    else()
      math(EXPR n_versioned "${n_versioned} + 1")
    endif()
    continue()
  endif()
  if(type MATCHES "^[WVu]$")
    math(EXPR n_weak_other "${n_weak_other} + 1")
  else()
    list(APPEND bad "${name} (${type}, ${member}): a strong global symbol outside kissm_* and kissm::${NAMESPACE}")
  endif()
endforeach()

if(n_versioned EQUAL 0)
  list(APPEND bad "no symbol of kissm::${NAMESPACE} at all: is the inline namespace still v<major>_<minor> of the "
                  "project version (src/core)? docs/abi-policy.md, \"Static linking\"")
endif()
if(bad)
  list(JOIN bad "\n  " text)
  message(FATAL_ERROR "libkissm.a defines global symbols a host program could clash with:\n  ${text}\n"
                      "kissm's C++ code belongs in the inline namespace kissm::${NAMESPACE} (v<major>_<minor> of "
                      "the project version, renamed with every minor release) and C helpers in an anonymous "
                      "namespace or static: docs/abi-policy.md, \"Static linking\".")
endif()
message(STATUS "libkissm.a: ${n_api} C API functions, ${n_versioned} symbols of kissm::${NAMESPACE}, "
               "${n_weak_other} weak standard-library/Eigen instantiations; nothing else")
