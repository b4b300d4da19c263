// SPDX-License-Identifier: MIT
//! Raw FFI bindings to kissm, the global 3D point cloud registration library.
//!
//! This crate is the `-sys` half of the Rust binding: it declares the C API of `include/kissm.h`
//! exactly as bindgen translates it, and links the library. Use the safe `kissm` crate unless you need
//! the raw calls.
//!
//! - Every `#define` of the header is a `pub const KISSM_*: i32` (status codes, reasons, formats, ...).
//! - Structs are `#[repr(C)]`, checked at compile time against the layout libclang computed for the
//!   header (size, alignment and every field offset).
//! - The bindings are pregenerated (`src/bindings.rs`), so a default build needs no libclang. The
//!   `bindgen` feature regenerates them from the header at build time.
//!
//! Linking: by default `build.rs` builds the C++ core of the repository with CMake (Release, static) and
//! links it with the C++ runtime. Set `KISSM_LIB_DIR` to link an installed `libkissm` instead (shared, or
//! static with `KISSM_STATIC=1`).
#![no_std]
#![deny(missing_docs)]

/// The generated declarations, re-exported at the crate root. bindgen keeps the C names (kissm_config,
/// KISSM_OK, ...) and the header's comments, which do not document every item: the generated code is
/// exempt from `missing_docs` (this crate's own items are not). Clippy finds nothing in it. The header's
/// Doxygen markup (`@param[in]`, `[out]`) reads as broken intra-doc links to rustdoc: allowed here only.
#[allow(non_camel_case_types, non_snake_case, non_upper_case_globals, missing_docs, rustdoc::broken_intra_doc_links)]
mod generated {
    #[cfg(not(feature = "bindgen"))]
    include!("bindings.rs");

    #[cfg(feature = "bindgen")]
    include!(concat!(env!("OUT_DIR"), "/bindings.rs"));
}

pub use generated::*;
