// SPDX-License-Identifier: MIT
// The one namespace of everything inside libkissm: kissm::v<major>_<minor>::detail. The inline namespace is
// versioned so that two kissm versions linked statically into one program never share a symbol
// (tests/abi/check_static_symbols.cmake checks it). The C boundary checks at compile time that these
// numbers are the ones of kissm.h (src/capi/errors.cpp), so that the core itself needs no C header.
#pragma once

#define KISSM_DETAIL_VERSION_MAJOR 0
#define KISSM_DETAIL_VERSION_MINOR 1

#define KISSM_DETAIL_PASTE4(a, b, c, d) a##b##c##d
#define KISSM_DETAIL_VERSIONED(major, minor) KISSM_DETAIL_PASTE4(v, major, _, minor)
#define KISSM_DETAIL_INLINE_NAMESPACE KISSM_DETAIL_VERSIONED(KISSM_DETAIL_VERSION_MAJOR, KISSM_DETAIL_VERSION_MINOR)

// Opens and closes kissm::v<major>_<minor>::detail (clang-format knows them as statement macros).
#define KISSM_DETAIL_BEGIN                                                                                             \
  namespace kissm {                                                                                                    \
  inline namespace KISSM_DETAIL_INLINE_NAMESPACE {                                                                     \
  namespace detail {
#define KISSM_DETAIL_END                                                                                               \
  }                                                                                                                    \
  }                                                                                                                    \
  }
