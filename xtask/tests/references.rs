//! The repository's docs, doc comments and results pages cite what a user can look up — thesis
//! chapters, sections, equations and tables — never the project's planning notes (their
//! section numbers, errata numbers or issue numbers), which are not part of the repository.

use std::path::{Path, PathBuf};

/// Phrases that point into the planning notes, each followed by a digit or a section sign.
const PATTERNS: [&str; 5] = ["spec §", "spec A", "errata ", "erratum ", "issue "];

fn files(dir: &Path, out: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for entry in entries.flatten() {
        let path = entry.path();
        let name = entry.file_name();
        let name = name.to_string_lossy();
        if path.is_dir() {
            if !matches!(name.as_ref(), "target" | "generated" | ".git") {
                files(&path, out);
            }
        } else if [".rs", ".md", ".toml", ".json", ".sh"]
            .iter()
            .any(|e| name.ends_with(e))
        {
            out.push(path);
        }
    }
}

/// Lines of `text` where a pattern is followed by a digit (or `#` and a digit).
fn offending(text: &str) -> Vec<(usize, String)> {
    let mut out = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let lower = line.to_lowercase();
        let hit = PATTERNS.iter().any(|p| {
            lower.match_indices(&p.to_lowercase()).any(|(at, m)| {
                let rest = lower[at + m.len()..].trim_start_matches('#');
                p.ends_with('§') || rest.starts_with(|c: char| c.is_ascii_digit())
            })
        });
        if hit {
            out.push((i + 1, line.trim().chars().take(120).collect()));
        }
    }
    out
}

#[test]
fn the_pattern_finds_planning_references_only() {
    assert_eq!(offending("see spec §4.8 and errata 8").len(), 1);
    assert_eq!(offending("(issue #12)\nspec A3\nerratum A4").len(), 2);
    assert!(offending("ModelSpec { DecayRate }; a known issue with glass; Eq. 8.22").is_empty());
}

#[test]
fn docs_cite_the_thesis_not_planning_notes() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let mut all = Vec::new();
    for dir in ["crates", "xtask", "docs", "datasets", ".ci"] {
        files(&root.join(dir), &mut all);
    }
    all.push(root.join("README.md"));
    let this = Path::new(file!()).file_name();
    let mut found = Vec::new();
    for path in all {
        if path.file_name() == this {
            continue;
        }
        let Ok(text) = std::fs::read_to_string(&path) else {
            continue;
        };
        for (line, excerpt) in offending(&text) {
            found.push(format!("{}:{line}: {excerpt}", path.display()));
        }
    }
    assert!(
        found.is_empty(),
        "references to planning notes (cite the thesis instead):\n{}",
        found.join("\n")
    );
}
