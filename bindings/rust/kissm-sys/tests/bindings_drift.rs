// SPDX-License-Identifier: MIT
//! The committed `src/bindings.rs` must be exactly what bindgen makes of `include/kissm.h` with the
//! options in `build.rs`. Runs only with the `bindgen` feature (which needs libclang):
//!
//! ```text
//! cargo test -p kissm-sys --features bindgen --test bindings_drift
//! ```
//!
//! With `KISSM_BLESS=1` it rewrites `src/bindings.rs` instead of failing (what `regen-bindings.sh` does).
#![cfg(feature = "bindgen")]

#[test]
fn committed_bindings_match_the_header() {
    let generated = include_str!(concat!(env!("OUT_DIR"), "/bindings.rs"));
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/src/bindings.rs");
    if std::env::var_os("KISSM_BLESS").is_some_and(|v| v == "1") {
        std::fs::write(path, generated).expect("write src/bindings.rs");
        eprintln!("wrote {path}");
        return;
    }
    let committed = std::fs::read_to_string(path).expect("read src/bindings.rs");
    if committed == generated {
        return;
    }
    let (a, b): (Vec<&str>, Vec<&str>) = (committed.lines().collect(), generated.lines().collect());
    let first = a.iter().zip(&b).position(|(x, y)| x != y).unwrap_or(a.len().min(b.len()));
    panic!(
        "src/bindings.rs is out of date with include/kissm.h (first difference at line {}):\n  committed: {}\n  generated: {}\n\
         regenerate with bindings/rust/kissm-sys/regen-bindings.sh and commit the result",
        first + 1,
        a.get(first).unwrap_or(&"<end of file>"),
        b.get(first).unwrap_or(&"<end of file>"),
    );
}
