// SPDX-License-Identifier: MIT
//! Build script of `kissm-sys`.
//!
//! Linking, in order of precedence:
//!
//! 1. `KISSM_LIB_DIR=/path/to/lib` links an installed (or separately built) `libkissm` from that folder:
//!    the shared library by default, the static one (plus the C++ runtime) with `KISSM_STATIC=1`. No C++
//!    compiler or CMake is needed then. `KISSM_INCLUDE_DIR` may name the folder holding its `kissm.h`
//!    (only used by the `bindgen` feature; the repository's header otherwise).
//! 2. Otherwise the C++ core is built with CMake through the `cmake` crate, always as a `Release` static
//!    library whatever the Cargo profile, so that results are the same as the C library's and the CLI's,
//!    and linked statically together with the C++ runtime. The sources are `vendor/kissm/` when present
//!    (a packaged crate: `vendor.sh` copies them in before `cargo package`), else this repository
//!    (`../../..`). Eigen 3 comes from the system (libeigen3-dev) either way.
//!
//! Bindings: `src/bindings.rs` (committed) is used as is. With the `bindgen` feature the bindings are
//! regenerated from `kissm.h` into `OUT_DIR/bindings.rs` (needs libclang) with exactly the options that
//! produced the committed file, and used instead; `tests/bindings_drift.rs` compares the two.

use std::env;
use std::path::{Path, PathBuf};

fn main() {
    let manifest_dir = PathBuf::from(env::var_os("CARGO_MANIFEST_DIR").expect("CARGO_MANIFEST_DIR is set by cargo"));
    let vendored = manifest_dir.join("vendor/kissm");
    let source_root =
        if vendored.join("CMakeLists.txt").is_file() { vendored.clone() } else { manifest_dir.join("../../..") };
    let source_root = source_root.canonicalize().unwrap_or(source_root);
    if source_root.ends_with("vendor/kissm") && manifest_dir.join("../../../include/kissm.h").is_file() {
        println!(
            "cargo:warning=kissm-sys builds the copy in vendor/kissm, not the repository's sources; \
             remove it with kissm-sys/vendor.sh --clean"
        );
    }

    println!("cargo:rerun-if-changed=build.rs");
    // vendor/ appearing or disappearing switches the sources: watch it when present, else the crate folder
    // (whose entries change when vendor/ is created).
    let watched = if vendored.is_dir() { &vendored } else { &manifest_dir };
    println!("cargo:rerun-if-changed={}", watched.display());
    println!("cargo:rerun-if-env-changed=KISSM_LIB_DIR");
    println!("cargo:rerun-if-env-changed=KISSM_STATIC");
    println!("cargo:rerun-if-env-changed=KISSM_INCLUDE_DIR");
    println!("cargo:rerun-if-env-changed=DOCS_RS");

    let include_dir = match env::var_os("KISSM_INCLUDE_DIR") {
        Some(dir) if !dir.is_empty() => PathBuf::from(dir),
        _ => source_root.join("include"),
    };

    // docs.rs only documents (rustdoc links nothing), and its builders need not have CMake or Eigen.
    let docs_only = env::var_os("DOCS_RS").is_some();
    match env::var_os("KISSM_LIB_DIR") {
        _ if docs_only => {}
        Some(dir) if !dir.is_empty() => link_prebuilt(Path::new(&dir)),
        _ => build_with_cmake(&source_root),
    }
    // Dependents with `links`-aware build scripts see this as DEP_KISSM_INCLUDE.
    println!("cargo:include={}", include_dir.display());

    #[cfg(feature = "bindgen")]
    generate_bindings(&include_dir.join("kissm.h"));
}

fn env_flag(name: &str) -> bool {
    matches!(env::var(name).as_deref(), Ok("1") | Ok("true") | Ok("TRUE") | Ok("yes") | Ok("on") | Ok("ON"))
}

/// The C++ runtime that a static libkissm needs.
fn link_cxx_runtime() {
    let target = env::var("TARGET").unwrap_or_default();
    if target.contains("apple") || target.contains("freebsd") || target.contains("openbsd") {
        println!("cargo:rustc-link-lib=dylib=c++");
    } else if target.contains("msvc") {
        // MSVC links its C++ runtime by itself.
    } else {
        println!("cargo:rustc-link-lib=dylib=stdc++");
    }
    if !target.contains("windows") && !target.contains("apple") {
        println!("cargo:rustc-link-lib=dylib=pthread");
        println!("cargo:rustc-link-lib=dylib=m");
    }
}

fn link_prebuilt(dir: &Path) {
    println!("cargo:rustc-link-search=native={}", dir.display());
    if env_flag("KISSM_STATIC") {
        println!("cargo:rustc-link-lib=static=kissm");
        link_cxx_runtime();
    } else {
        println!("cargo:rustc-link-lib=dylib=kissm");
    }
}

fn build_with_cmake(source_root: &Path) {
    if !source_root.join("include/kissm.h").is_file() || !source_root.join("CMakeLists.txt").is_file() {
        panic!(
            "kissm-sys: the kissm sources were not found at {} (expected include/kissm.h and CMakeLists.txt). \
             Build inside the kissm repository or from a packaged crate (vendor/kissm), or set KISSM_LIB_DIR \
             to a folder holding an installed libkissm.",
            source_root.display()
        );
    }
    for path in ["CMakeLists.txt", "cmake", "include", "src", "third_party"] {
        println!("cargo:rerun-if-changed={}", source_root.join(path).display());
    }
    let out = cmake::Config::new(source_root)
        // Release whatever the Cargo profile: the results (and speed) must not depend on it.
        .profile("Release")
        .define("KISSM_BUILD_TESTS", "OFF")
        .define("KISSM_BUILD_CLI", "OFF")
        .define("KISSM_BUILD_SHARED", "OFF")
        .define("KISSM_BUILD_STATIC", "ON")
        // A newer compiler's new warning must not break a user's build.
        .define("KISSM_WERROR", "OFF")
        .define("KISSM_NATIVE", "OFF")
        .define("CMAKE_INSTALL_LIBDIR", "lib")
        .build();
    println!("cargo:rustc-link-search=native={}", out.join("lib").display());
    println!("cargo:rustc-link-lib=static=kissm");
    link_cxx_runtime();
    println!("cargo:root={}", out.display());
}

/// Regenerates the bindings. These options are the single definition of how `src/bindings.rs` is made
/// (`regen-bindings.sh` runs this same code and copies the output).
#[cfg(feature = "bindgen")]
fn generate_bindings(header: &Path) {
    println!("cargo:rerun-if-changed={}", header.display());
    let bindings = bindgen::Builder::default()
        .header(header.to_string_lossy())
        // The licence line first; bindgen's own header comment would come before it, and the bindgen version
        // it names is pinned in Cargo.lock anyway.
        .disable_header_comment()
        .raw_line("// SPDX-License-Identifier: MIT")
        .raw_line("// Generated by bindgen from include/kissm.h: do not edit. Regenerate with regen-bindings.sh.")
        .allowlist_function("^kissm_.*")
        .allowlist_type("^kissm_.*")
        .allowlist_var("^KISSM_.*")
        // Every #define is an int32_t in the C API (status codes are negative): one type for all.
        .default_macro_constant_type(bindgen::MacroTypeVariation::Signed)
        // Pinned so that the output does not change with the bindgen version's default target.
        .rust_target(bindgen::RustTarget::stable(77, 0).expect("a valid Rust target"))
        .use_core()
        .layout_tests(true)
        .derive_default(true)
        .derive_debug(true)
        .generate_comments(true)
        // The header documents with plain /* */ comments: keep them as rustdoc.
        .clang_arg("-fparse-all-comments")
        // Formatted by the prettyplease crate (pinned in Cargo.lock), not by whatever rustfmt and
        // rustfmt.toml the machine has, so that the output is the same everywhere.
        .formatter(bindgen::Formatter::Prettyplease)
        .generate()
        .expect("bindgen could not generate the kissm bindings (is libclang installed? set LIBCLANG_PATH)");
    let out = PathBuf::from(env::var_os("OUT_DIR").expect("OUT_DIR is set by cargo")).join("bindings.rs");
    bindings.write_to_file(&out).expect("could not write OUT_DIR/bindings.rs");
}
