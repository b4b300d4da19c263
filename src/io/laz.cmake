# SPDX-License-Identifier: MIT
# KISSM_WITH_LAZ=ON: LAZ decompression by the `laz` crate (Apache-2.0) behind kissm's own C ABI
# (src/io/laz_rs), built here with cargo into a static library that libkissm links (src/io/README.md says why
# this implementation). Needs cargo (rustup or Debian's cargo) and crates.io, or a filled cargo cache.
# Defines the target kissm_laz_rs (an imported static library) when the option is ON.
if(NOT KISSM_WITH_LAZ)
  return()
endif()
find_program(KISSM_CARGO cargo HINTS $ENV{HOME}/.cargo/bin)
if(NOT KISSM_CARGO)
  message(FATAL_ERROR "KISSM_WITH_LAZ=ON needs cargo (the Rust toolchain) to build src/io/laz_rs")
endif()
set(KISSM_LAZ_RS_DIR ${CMAKE_CURRENT_LIST_DIR}/laz_rs)
set(KISSM_LAZ_RS_TARGET_DIR ${PROJECT_BINARY_DIR}/laz_rs)
set(KISSM_LAZ_RS_LIB ${KISSM_LAZ_RS_TARGET_DIR}/release/${CMAKE_STATIC_LIBRARY_PREFIX}kissm_laz${CMAKE_STATIC_LIBRARY_SUFFIX})
# --locked: the versions of src/io/laz_rs/Cargo.lock, nothing newer.
add_custom_command(OUTPUT ${KISSM_LAZ_RS_LIB}
  COMMAND ${CMAKE_COMMAND} -E env CARGO_TARGET_DIR=${KISSM_LAZ_RS_TARGET_DIR}
          ${KISSM_CARGO} build --release --locked --quiet --manifest-path ${KISSM_LAZ_RS_DIR}/Cargo.toml
  DEPENDS ${KISSM_LAZ_RS_DIR}/Cargo.toml ${KISSM_LAZ_RS_DIR}/Cargo.lock ${KISSM_LAZ_RS_DIR}/src/lib.rs
  COMMENT "Building the LAZ decompressor (src/io/laz_rs) with cargo"
  VERBATIM)
add_custom_target(kissm_laz_rs_build DEPENDS ${KISSM_LAZ_RS_LIB})
add_library(kissm_laz_rs STATIC IMPORTED GLOBAL)
# What a Rust static library needs from the system (rustc --print native-static-libs).
set_target_properties(kissm_laz_rs PROPERTIES IMPORTED_LOCATION ${KISSM_LAZ_RS_LIB}
                                              INTERFACE_LINK_LIBRARIES "Threads::Threads;${CMAKE_DL_LIBS};m;rt;util")
