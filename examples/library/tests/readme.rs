//! The README's library example is this crate: its `[dependencies]` are the README's toml
//! block and its `src/main.rs` the README's rust block, word for word, so that the
//! workspace's build compiles the example as a new user's crate would, seeing only the
//! crates the README lists (the doc test compiles the same code inside the engine, whose
//! own dependencies once hid three missing lines: `citygen`, `tempfile` and `glam`).
//!
//! A crate of its own made in a scratch folder would check the same, but it shares little
//! of the workspace's target folder: the workspace compiles its dependencies with the
//! features every member asks for together (serde's `alloc` for criterion, glam's
//! `bytemuck` for wgpu, …), so the engine and some forty crates would be compiled a second
//! time for it, minutes rather than seconds.

use std::path::Path;
use std::process::Command;

const SECTION: &str = "## Using the engine as a library";

/// The text of the README's section under `heading`, up to the next `## `.
fn section<'a>(readme: &'a str, heading: &str) -> &'a str {
    let start = readme
        .find(heading)
        .unwrap_or_else(|| panic!("the README has no section {heading:?}"));
    let body = &readme[start + heading.len()..];
    &body[..body.find("\n## ").unwrap_or(body.len())]
}

/// The first fenced block of `lang` in `text`.
fn first_block<'a>(text: &'a str, lang: &str) -> &'a str {
    let fence = format!("```{lang}\n");
    let start = text
        .find(&fence)
        .unwrap_or_else(|| panic!("the library section has no ```{lang} block"))
        + fence.len();
    let len = text[start..].find("```").expect("the block is closed");
    &text[start..start + len]
}

fn here() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

fn readme() -> String {
    std::fs::read_to_string(here().join("../../README.md"))
        .expect("the README beside the workspace")
}

#[test]
fn this_crate_is_the_readme_example_word_for_word() {
    let readme = readme();
    let library = section(&readme, SECTION);

    // The README's crate sits beside the repository (`../flaneur/…`); this one inside it.
    let listed = first_block(library, "toml").replace("../flaneur/", "../../");
    let manifest = std::fs::read_to_string(here().join("Cargo.toml")).unwrap();
    let dependencies = &manifest[manifest
        .find("[dependencies]\n")
        .expect("a [dependencies] table")..];
    assert_eq!(
        dependencies, listed,
        "examples/library/Cargo.toml's dependencies must be the README's toml block"
    );

    let code = first_block(library, "rust");
    let main = std::fs::read_to_string(here().join("src/main.rs")).unwrap();
    assert_eq!(
        main, code,
        "examples/library/src/main.rs must be the README's rust block"
    );
}

#[test]
fn the_example_runs_to_its_end() {
    let out = Command::new(env!("CARGO_BIN_EXE_library-example"))
        .output()
        .expect("the example runs");
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "the example failed ({}):\n{text}\n{}",
        out.status,
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(
        text.contains("pages read in all") && text.contains("levels, the coarsest"),
        "the example ran to its end:\n{text}"
    );
}

/// What a program that embeds the engine compiles: the engine and the generator, never a
/// command line parser, a progress bar or anyhow (citygen's binary alone needs them).
#[test]
fn the_example_compiles_no_command_line_crate() {
    let cargo = std::env::var_os("CARGO").unwrap_or_else(|| "cargo".into());
    let out = Command::new(cargo)
        .args(["tree", "--offline", "--edges", "normal", "--prefix", "none"])
        .args(["--package", "library-example"])
        .current_dir(here())
        .output()
        .expect("cargo tree runs");
    let tree = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "cargo tree: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(tree.lines().any(|l| l.starts_with("citygen ")), "{tree}");
    for cli_only in ["clap ", "indicatif ", "anyhow "] {
        assert!(
            !tree.lines().any(|line| line.starts_with(cli_only)),
            "the library example compiles {cli_only}through its dependencies:\n{tree}"
        );
    }
}
