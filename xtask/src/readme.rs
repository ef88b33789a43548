//! The README's crate map quotes each evaluation's headline between the markers
//! `<!-- headline:NAME -->` and `<!-- /headline -->`. A full `cargo xtask eval NAME` writes
//! the headline into `docs/results/NAME.md` (the line starting `**Headline.**`) and the same
//! text between the README's markers, so no figure there is typed by hand; a test checks that
//! every marked README text equals its results page.

use std::path::Path;

use anyhow::{Context, Result};

/// The line prefix of the headline on a results page of a full run.
pub const PREFIX: &str = "**Headline.** ";

fn markers(name: &str) -> (String, &'static str) {
    (format!("<!-- headline:{name} -->"), "<!-- /headline -->")
}

/// `readme` with the text between `name`'s markers replaced by `text`; `None` when the README
/// has no markers for `name`.
pub fn replace(readme: &str, name: &str, text: &str) -> Option<String> {
    let (open, close) = markers(name);
    let start = readme.find(&open)? + open.len();
    let end = start + readme[start..].find(close)?;
    Some(format!("{}{text}{}", &readme[..start], &readme[end..]))
}

/// Writes `text` between `name`'s markers in `root/README.md` (nothing when it has none).
pub fn update(root: &Path, name: &str, text: &str) -> Result<()> {
    let path = root.join("README.md");
    let readme =
        std::fs::read_to_string(&path).with_context(|| format!("reading {}", path.display()))?;
    if let Some(updated) = replace(&readme, name, text)
        && updated != readme
    {
        std::fs::write(&path, updated).with_context(|| format!("writing {}", path.display()))?;
        eprintln!("updated the {name} headline in {}", path.display());
    }
    Ok(())
}

#[cfg(test)]
#[allow(clippy::unwrap_used)] // test code: a panic is the failure report
mod tests {
    use super::*;

    /// Every `(name, text)` between markers in `readme`.
    fn marked(readme: &str) -> Vec<(String, String)> {
        let mut out = Vec::new();
        let mut rest = readme;
        while let Some(i) = rest.find("<!-- headline:") {
            let after = &rest[i + "<!-- headline:".len()..];
            let Some(name_end) = after.find(" -->") else {
                break;
            };
            let name = after[..name_end].to_owned();
            let body = &after[name_end + " -->".len()..];
            let Some(end) = body.find("<!-- /headline -->") else {
                break;
            };
            out.push((name, body[..end].to_owned()));
            rest = &body[end..];
        }
        out
    }

    /// The headline of a results page (`None` without one, or on a quick run's page).
    fn headline_of(results_md: &str) -> Option<&str> {
        results_md
            .lines()
            .find_map(|line| line.strip_prefix(PREFIX))
    }

    #[test]
    fn replace_and_find_marked_text() {
        let readme =
            "a <!-- headline:x -->old<!-- /headline --> b <!-- headline:y -->z<!-- /headline -->";
        let new = replace(readme, "x", "new 1.5 %").unwrap();
        assert_eq!(
            new,
            "a <!-- headline:x -->new 1.5 %<!-- /headline --> b <!-- headline:y -->z<!-- /headline -->"
        );
        assert_eq!(
            marked(&new),
            vec![("x".into(), "new 1.5 %".into()), ("y".into(), "z".into())]
        );
        assert!(replace(readme, "w", "t").is_none());
        assert_eq!(headline_of("# T\n\n**Headline.** 3 m\n"), Some("3 m"));
        assert_eq!(headline_of("**Headline (quick run).** 3 m"), None);
    }

    /// Every figure the README's crate map quotes is the headline of a full run's results page.
    #[test]
    fn readme_headlines_equal_the_results_pages() {
        let root = crate::eval::workspace_root();
        let readme = std::fs::read_to_string(root.join("README.md")).unwrap();
        for (name, text) in marked(&readme) {
            let page = root.join(format!("docs/results/{name}.md"));
            let md = std::fs::read_to_string(&page).unwrap();
            assert_eq!(
                headline_of(&md),
                Some(text.as_str()),
                "README headline of {name} differs from {} (run `cargo xtask eval {name}`)",
                page.display()
            );
        }
    }
}
