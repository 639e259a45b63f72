//! The README's Rust snippets are code that compiles: each is, line for line, the visible text of
//! a doctest in one of the workspace's crates (`cargo test --doc` compiles them all; the lines
//! that set up what a snippet takes for granted are hidden from the docs with `# `).

use quadray_test_support::layering::rust_files;
use std::path::{Path, PathBuf};

fn workspace() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// The ```` ```rust ```` blocks of a Markdown text.
fn markdown_rust_blocks(text: &str) -> Vec<String> {
    let mut blocks = Vec::new();
    let mut block: Option<String> = None;
    for line in text.lines() {
        match (&mut block, line.trim_end()) {
            (None, "```rust") => block = Some(String::new()),
            (Some(_), "```") => blocks.extend(block.take()),
            (Some(b), _) => b.extend([line, "\n"]),
            (None, _) => {}
        }
    }
    blocks
}

/// The visible text of each doctest in a Rust source file's `//!` and `///` comments: fences
/// that rustdoc compiles (no language, `rust`, `no_run`), hidden `# ` lines left out.
fn doctests(source: &str) -> Vec<String> {
    let mut tests = Vec::new();
    let mut test: Option<String> = None;
    for line in source.lines() {
        let trimmed = line.trim_start();
        let Some(doc) = trimmed
            .strip_prefix("//!")
            .or_else(|| trimmed.strip_prefix("///"))
        else {
            continue;
        };
        let doc = doc.strip_prefix(' ').unwrap_or(doc);
        match (&mut test, doc.trim_end()) {
            (None, "```" | "```rust" | "```no_run") => test = Some(String::new()),
            (Some(_), "```") => tests.extend(test.take()),
            (Some(_), hidden) if hidden == "#" || hidden.starts_with("# ") => {}
            (Some(t), _) => t.extend([doc, "\n"]),
            (None, _) => {}
        }
    }
    tests
}

#[test]
fn every_readme_snippet_is_a_compiled_doctest() {
    let root = workspace();
    let readme = std::fs::read_to_string(root.join("README.md")).unwrap();
    let snippets = markdown_rust_blocks(&readme);
    let mut sources = Vec::new();
    for krate in std::fs::read_dir(root.join("crates")).unwrap() {
        let src = krate.unwrap().path().join("src");
        if src.is_dir() {
            rust_files(&src, &mut sources);
        }
    }
    let doctests: Vec<String> = sources
        .iter()
        .flat_map(|path| doctests(&std::fs::read_to_string(path).unwrap()))
        .collect();
    assert!(
        snippets.len() >= 5,
        "README's Rust snippets: {}",
        snippets.len()
    );
    for snippet in &snippets {
        assert!(
            doctests.contains(snippet),
            "this README snippet is no doctest's visible text (put it in the docs of the crate it \
             uses, the lines it takes for granted hidden with `# `):\n{snippet}"
        );
    }
}
