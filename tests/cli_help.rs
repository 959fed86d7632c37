//! Every `--help` of the `flaneur` command says everything: each argument and option
//! has a description, and each option that takes a value and may be left out says what
//! it is then: clap's "[default: …]", or its own words with "default" in them (an
//! `Option` the command resolves in code, or one that does nothing when absent).
//!
//! The commands are read from the binary's own help, `bench`'s experiments included,
//! so a command added later is checked as soon as it exists.

use std::process::Command;

/// Options that may be left out yet have no default to show, each with the reason.
/// Keyed by the command's path and the option's long name.
const NO_DEFAULT: &[(&str, &str, &str)] = &[
    (
        "lod",
        "--eye",
        "needed with --refine and unused without: there is no default eye",
    ),
    (
        "lod",
        "--look",
        "needed with --refine and unused without: there is no default point",
    ),
];

/// `flaneur ARGS… --help`, which must succeed.
fn help(path: &[&str]) -> String {
    let out = Command::new(env!("CARGO_BIN_EXE_flaneur"))
        .args(path)
        .arg("--help")
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "flaneur {} --help: {}",
        path.join(" "),
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout).unwrap()
}

/// The lines of the section `title` ("Commands:", "Arguments:", "Options:"): from its
/// heading to the next line that starts at the margin.
fn section<'h>(help: &'h str, title: &str) -> Vec<&'h str> {
    help.lines()
        .skip_while(|l| *l != title)
        .skip(1)
        .take_while(|l| l.is_empty() || l.starts_with(' '))
        .collect()
}

/// The subcommands a help lists, less `help`.
fn subcommands(help: &str) -> Vec<String> {
    section(help, "Commands:")
        .iter()
        .filter(|l| l.starts_with("  ") && !l[2..].starts_with(' '))
        .filter_map(|l| l.split_whitespace().next())
        .filter(|name| *name != "help")
        .map(String::from)
        .collect()
}

/// One argument or option of a help: its signature (`-o, --out <PNG>`, `<DB>`) and its
/// description, every line of it joined.
#[derive(Debug)]
struct Entry {
    signature: String,
    text: String,
}

impl Entry {
    /// The long name of an option (`--out`), or `None` for a positional argument.
    fn long(&self) -> Option<&str> {
        self.signature
            .split([',', ' '])
            .find(|w| w.starts_with("--"))
    }

    fn takes_value(&self) -> bool {
        self.long().is_some() && self.signature.contains('<')
    }
}

/// The entries of a help's section. An entry starts at a line indented at most six
/// spaces (clap's column for `-x, --long` and `    --long`); its description follows
/// the signature on that line after two spaces, or on the lines indented below it.
fn entries(help: &str, title: &str) -> Vec<Entry> {
    let mut out: Vec<Entry> = Vec::new();
    for line in section(help, title) {
        let indent = line.len() - line.trim_start().len();
        let trimmed = line.trim();
        if trimmed.is_empty() {
            continue;
        }
        if indent <= 6 && (trimmed.starts_with('-') || trimmed.starts_with(['<', '['])) {
            let (signature, text) = trimmed.split_once("  ").unwrap_or((trimmed, ""));
            out.push(Entry {
                signature: signature.to_string(),
                text: text.trim().to_string(),
            });
        } else if let Some(e) = out.last_mut() {
            e.text.push(' ');
            e.text.push_str(trimmed);
        }
    }
    out
}

/// What is wrong with one command's help, each problem a line naming the command and
/// the argument.
fn problems(path: &[&str], help: &str) -> Vec<String> {
    let command = path.join(" ");
    let usage = help
        .lines()
        .find(|l| l.starts_with("Usage:"))
        .unwrap_or_default();
    let mut found = Vec::new();
    for title in ["Arguments:", "Options:"] {
        for e in entries(help, title) {
            let text = e.text.trim();
            // A description, not only what clap adds.
            if text.is_empty() || text.starts_with('[') {
                found.push(format!("flaneur {command} {}: no description", e.signature));
                continue;
            }
            let Some(long) = e.long() else { continue };
            if !e.takes_value() {
                continue;
            }
            // A required option is in the usage line itself: it has no default.
            let required = usage
                .split_whitespace()
                .any(|w| w == long || w.starts_with(&format!("{long}=")));
            let excepted = NO_DEFAULT
                .iter()
                .any(|(c, o, _)| *c == command && *o == long);
            if !required && !excepted && !text.to_lowercase().contains("default") {
                found.push(format!(
                    "flaneur {command} {}: shows no default (\"[default: …]\", or say \
                     \"default …\" in its help)",
                    e.signature
                ));
            }
        }
    }
    found
}

/// Every command's help, and its subcommands', depth first: (path, help).
fn every_help() -> Vec<(Vec<String>, String)> {
    let mut out = Vec::new();
    let mut todo = vec![Vec::<String>::new()];
    while let Some(path) = todo.pop() {
        let args: Vec<&str> = path.iter().map(String::as_str).collect();
        let text = help(&args);
        for sub in subcommands(&text) {
            let mut p = path.clone();
            p.push(sub);
            todo.push(p);
        }
        out.push((path, text));
    }
    out
}

#[test]
fn every_help_describes_every_argument_and_shows_every_default() {
    let helps = every_help();
    // The walk found the commands and bench's experiments, not an empty list.
    let paths: Vec<String> = helps.iter().map(|(p, _)| p.join(" ")).collect();
    for expected in [
        "walk",
        "serve-stream",
        "bench",
        "bench stream-blocks",
        "merge",
    ] {
        assert!(
            paths.iter().any(|p| p == expected),
            "no {expected} in {paths:?}"
        );
    }
    assert!(paths.len() > 30, "{paths:?}");
    let mut found = Vec::new();
    for (path, text) in &helps {
        let args: Vec<&str> = path.iter().map(String::as_str).collect();
        found.extend(problems(&args, text));
    }
    // Every exception still names an option that exists and still needs it.
    for (command, option, why) in NO_DEFAULT {
        let (_, text) = helps
            .iter()
            .find(|(p, _)| p.join(" ") == *command)
            .unwrap_or_else(|| panic!("exception for a command that is gone: {command}"));
        let e = entries(text, "Options:")
            .into_iter()
            .find(|e| e.long() == Some(option))
            .unwrap_or_else(|| panic!("exception for an option that is gone: {command} {option}"));
        assert!(
            !e.text.to_lowercase().contains("default"),
            "{command} {option} shows a default now: drop its exception ({why})"
        );
    }
    assert!(found.is_empty(), "{}", found.join("\n"));
}

/// The checker itself: it finds what it must on a help of clap's shape, in both of
/// clap's layouts (description on the signature's line, or below it).
#[test]
fn the_checker_finds_a_missing_description_and_a_missing_default() {
    let help = "Usage: flaneur walk [OPTIONS] --must <X> <DB>\n\nArguments:\n  <DB>  \n\nOptions:\n      --json\n\n      --policy <POLICY>\n          Index cache policy\n\n      --far <FAR>\n          Frustum depth\n          \n          [default: 1000]\n\n      --must <X>\n          Needed\n\n  -q, --quiet  Print less\n      --k <K>  Prefetch [default: 0.8]\n";
    let found = problems(&["walk"], help);
    assert_eq!(found.len(), 3, "{found:#?}");
    assert!(found[0].contains("<DB>: no description"));
    assert!(found[1].contains("--json: no description"));
    assert!(found[2].contains("--policy <POLICY>: shows no default"));
}
