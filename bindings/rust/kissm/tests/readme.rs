// SPDX-License-Identifier: MIT
//! The README example is the crate documentation's doc test (`src/lib.rs`, run by `cargo test --doc` on
//! the shared test scene): the visible lines of that doc test must equal the `rust` block of this
//! crate's README.md, of the repository's README.md (its "Rust" section) and of bindings/rust/README.md,
//! so that a change to any README that the doc test does not carry fails here. Likewise the refinement
//! example (the doc test under "# Refinement") and the "## Refinement" blocks of this crate's README.md
//! and of bindings/rust/README.md, and the pose graph example (the doc test under "# Pose graphs") and the
//! "## Pose graphs" block of this crate's README.md. The repository's files are only absent outside a
//! source checkout (a packaged crate); those comparisons alone are skipped then.

mod common;

use std::path::{Path, PathBuf};

/// The lines of the first fenced block opening with exactly `open` after a line starting with `after`.
fn fenced_block(text: &str, after: &str, open: &str) -> Option<Vec<String>> {
    let mut lines = text.lines().skip_while(|l| !l.starts_with(after));
    lines.find(|l| l.trim_end() == open)?;
    let mut block = Vec::new();
    for line in lines {
        if line.trim_end() == "```" {
            return Some(block);
        }
        block.push(line.trim_end().to_string());
    }
    None
}

/// The doc test of the crate documentation's "# Example", without the hidden (`# `) lines rustdoc does
/// not show.
fn doc_test_lines() -> Vec<String> {
    section_doc_test_lines("# Example")
}

/// The doc test under the crate documentation's heading `heading`, without the hidden lines.
fn section_doc_test_lines(heading: &str) -> Vec<String> {
    let lib = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("src/lib.rs")).unwrap();
    let docs: String = lib
        .lines()
        .filter_map(|l| l.strip_prefix("//!"))
        .map(|l| l.strip_prefix(' ').unwrap_or(l))
        .fold(String::new(), |mut acc, l| {
            acc.push_str(l);
            acc.push('\n');
            acc
        });
    let block =
        fenced_block(&docs, heading, "```").unwrap_or_else(|| panic!("src/lib.rs has a doc test under {heading:?}"));
    block.into_iter().filter(|l| l != "#" && !l.starts_with("# ")).collect()
}

fn readme_lines(path: &Path, after: &str) -> Vec<String> {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("read {}: {e}", path.display()));
    fenced_block(&text, after, "```rust")
        .unwrap_or_else(|| panic!("{}: no ```rust block after {after:?}", path.display()))
}

fn assert_same(expected: &[String], got: &[String], what: &str) {
    if expected == got {
        return;
    }
    let first = expected.iter().zip(got).position(|(a, b)| a != b).unwrap_or(expected.len().min(got.len()));
    panic!(
        "{what} differs from the doc test of src/lib.rs (first difference at line {} of the block):\n  doc test: {}\n  README:   {}\n\
         change both (the doc test runs the example on the shared test scene)",
        first + 1,
        expected.get(first).map_or("<end of block>", String::as_str),
        got.get(first).map_or("<end of block>", String::as_str),
    );
}

#[test]
fn crate_readme_example_is_the_doc_test() {
    let doc = doc_test_lines();
    assert!(doc.iter().any(|l| l.contains("Matcher::new")), "the doc test is the README example: {doc:?}");
    let readme = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("README.md");
    assert_same(&doc, &readme_lines(&readme, "## Example"), "kissm/README.md's example");
    let refine = section_doc_test_lines("# Refinement");
    assert!(refine.iter().any(|l| l.contains(".refine(")), "the refinement doc test: {refine:?}");
    assert_same(&refine, &readme_lines(&readme, "## Refinement"), "kissm/README.md's refinement example");
    let pose_graph = section_doc_test_lines("# Pose graphs");
    assert!(pose_graph.iter().any(|l| l.contains(".optimize(")), "the pose graph doc test: {pose_graph:?}");
    assert_same(&pose_graph, &readme_lines(&readme, "## Pose graphs"), "kissm/README.md's pose graph example");
}

/// The repository's root, or `None` outside a source checkout (a packaged crate, which has no
/// repository README; the crate's own is checked above).
fn repository() -> Option<PathBuf> {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../..");
    root.join("include/kissm.h").is_file().then_some(root)
}

#[test]
fn repository_readme_example_is_the_doc_test() {
    let Some(root) = repository() else {
        common::skip("repository_readme_example_is_the_doc_test", "not in a source checkout (a packaged crate)");
        return;
    };
    assert_same(&doc_test_lines(), &readme_lines(&root.join("README.md"), "## Rust"), "README.md's Rust example");
    assert_same(
        &doc_test_lines(),
        &readme_lines(&root.join("bindings/rust/README.md"), "# kissm for Rust"),
        "bindings/rust/README.md's example",
    );
    assert_same(
        &section_doc_test_lines("# Refinement"),
        &readme_lines(&root.join("bindings/rust/README.md"), "## Refinement"),
        "bindings/rust/README.md's refinement example",
    );
}
