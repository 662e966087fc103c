//! What the README and the docs promise, against the binary: the README's command table
//! against `--help`, every flag's help text, and the pages' links, free of issue numbers and
//! commit ids.

use std::collections::BTreeSet;
use std::path::PathBuf;

use crate::cli::repo;
use crate::common::vastocean;

/// The names under "Commands:" in a `--help` text (clap's own `help` left out).
fn help_commands(help: &str) -> Vec<String> {
    help.lines()
        .skip_while(|l| !l.starts_with("Commands:"))
        .skip(1)
        .take_while(|l| l.starts_with("  "))
        .filter_map(|l| l.split_whitespace().next())
        .filter(|c| *c != "help")
        .map(str::to_string)
        .collect()
}

/// Every command path the binary has: `render`, `sky generate`, ...
fn binary_commands() -> BTreeSet<String> {
    let (_, top, _) = vastocean(&["--help"]);
    let mut all = BTreeSet::new();
    for c in help_commands(&top) {
        let (_, sub, _) = vastocean(&[c.as_str(), "--help"]);
        let subs = help_commands(&sub);
        if subs.is_empty() {
            all.insert(c);
        } else {
            all.extend(subs.into_iter().map(|s| format!("{c} {s}")));
        }
    }
    all
}

/// The README's command table: for each `vastocean ...` span of its first column, the command
/// paths it names (`sky generate\|import` names two) and the flags it shows.
fn readme_commands() -> Vec<(Vec<String>, Vec<String>)> {
    let text = std::fs::read_to_string(repo().join("README.md")).unwrap();
    let table = text
        .split("\n## Commands\n")
        .nth(1)
        .expect("README has a Commands section");
    let mut out = Vec::new();
    for row in table.lines().filter(|l| l.starts_with("| `vastocean ")) {
        let first = row.split(" | ").next().unwrap();
        for span in first.split('`').skip(1).step_by(2) {
            let span = span.replace("\\|", "|");
            let mut words = span.split_whitespace().skip(1);
            let Some(cmd) = words.next() else { continue };
            let mut paths = vec![cmd.to_string()];
            let rest: Vec<&str> = words.collect();
            if let Some(sub) = rest
                .first()
                .filter(|w| w.chars().all(|c| c.is_ascii_lowercase() || c == '|'))
            {
                paths = sub.split('|').map(|s| format!("{cmd} {s}")).collect();
            }
            let flags = rest
                .iter()
                .flat_map(|w| w.split(['[', ']', '|']))
                .filter(|w| w.starts_with("--"))
                .map(str::to_string)
                .collect();
            out.push((paths, flags));
        }
    }
    out
}

#[test]
fn the_readme_command_table_matches_the_binary() {
    let binary = binary_commands();
    let table = readme_commands();
    let named: BTreeSet<String> = table.iter().flat_map(|(p, _)| p.clone()).collect();
    let least = if cfg!(feature = "embree") { 20 } else { 17 };
    assert!(binary.len() >= least, "{binary:?}");
    assert_eq!(
        binary.difference(&named).collect::<Vec<_>>(),
        Vec::<&String>::new(),
        "commands missing from the README's table"
    );
    // Commands that need Embree are absent from a build without it.
    let embree_only = ["crosscheck", "smoke", "bench bvh"];
    assert_eq!(
        named
            .difference(&binary)
            .filter(|c| cfg!(feature = "embree") || !embree_only.contains(&c.as_str()))
            .collect::<Vec<_>>(),
        Vec::<&String>::new(),
        "the README's table names commands the binary lacks"
    );
    for (paths, flags) in &table {
        for path in paths.iter().filter(|p| binary.contains(*p)) {
            let mut args: Vec<&str> = path.split(' ').collect();
            args.push("--help");
            let (_, help, _) = vastocean(&args);
            for flag in flags {
                assert!(
                    help.contains(&format!("{flag} ")) || help.contains(&format!("{flag}\n")),
                    "README shows `vastocean {path} {flag}`, which its --help lacks"
                );
            }
        }
    }
}

/// The README and docs/ pages: (path, text).
fn pages() -> Vec<(PathBuf, String)> {
    let mut files = vec![repo().join("README.md")];
    for e in std::fs::read_dir(repo().join("docs")).unwrap() {
        let p = e.unwrap().path();
        if p.extension().is_some_and(|x| x == "md") {
            files.push(p);
        }
    }
    files
        .into_iter()
        .map(|p| {
            let t = std::fs::read_to_string(&p).unwrap();
            (p, t)
        })
        .collect()
}

#[test]
fn every_relative_link_in_the_readme_and_docs_resolves() {
    let mut checked = 0;
    for (page, text) in pages() {
        for link in text.split("](").skip(1) {
            let target = link.split(')').next().unwrap();
            let file = target.split('#').next().unwrap();
            if file.is_empty() || file.contains("://") {
                continue;
            }
            let path = page.parent().unwrap().join(file);
            assert!(
                path.exists(),
                "{}: link to {target} is broken",
                page.display()
            );
            checked += 1;
        }
    }
    assert!(checked > 50, "{checked}");
}

#[test]
fn the_docs_hold_no_issue_numbers_or_commit_ids() {
    for (page, text) in pages() {
        for (n, line) in text.lines().enumerate() {
            let lower = line.to_lowercase();
            for word in lower.split(|c: char| !c.is_ascii_alphanumeric()) {
                let hex = word.len() >= 7
                    && word.chars().all(|c| c.is_ascii_hexdigit())
                    && word.chars().any(|c| c.is_ascii_digit())
                    && word.chars().any(|c| c.is_ascii_alphabetic());
                assert!(
                    !hex,
                    "{}:{}: `{word}` reads as a commit id",
                    page.display(),
                    n + 1
                );
            }
            let issue = lower
                .match_indices("issue ")
                .any(|(i, _)| lower[i + 6..].starts_with(|c: char| c.is_ascii_digit()));
            assert!(
                !issue,
                "{}:{}: an issue number: {line}",
                page.display(),
                n + 1
            );
            assert!(
                !lower.contains("this session"),
                "{}:{}: {line}",
                page.display(),
                n + 1
            );
        }
    }
}

#[test]
fn every_flag_of_every_command_has_help_text() {
    for path in binary_commands() {
        let mut args: Vec<&str> = path.split(' ').collect();
        args.push("--help");
        let (code, help, _) = vastocean(&args);
        assert_eq!(code, 0, "{path}");
        let lines: Vec<&str> = help.lines().collect();
        for (i, line) in lines.iter().enumerate() {
            let flag = line.trim_start();
            if !(line.starts_with("  ") && flag.starts_with('-')) {
                continue;
            }
            // The text follows on the same line after a gap, or (when some flag of the command
            // has a long text) on the lines below, indented further.
            let same_line = flag
                .split_once("  ")
                .is_some_and(|(_, t)| !t.trim().is_empty());
            let next = lines.get(i + 1).copied().unwrap_or("");
            let below = next.starts_with("          ") && !next.trim().is_empty();
            assert!(
                same_line || below,
                "vastocean {path}: `{flag}` has no help text"
            );
        }
    }
}
