//! The README's headline table: one row per evaluation whose full-run results page has a
//! headline (the line starting `**Headline.**` that a full `cargo xtask eval NAME` writes into
//! `docs/results/NAME.md`), with the headline and a link to the page. The table sits between
//! the README's markers `<!-- headlines -->` and `<!-- /headlines -->`; a full run rewrites it
//! from the results pages, so no figure there is typed by hand, and a test checks that the
//! README's table equals the one the pages give.

use std::path::Path;

use anyhow::{Context, Result};

/// The line prefix of the headline on a results page of a full run.
pub const PREFIX: &str = "**Headline.** ";

const OPEN: &str = "<!-- headlines -->";
const CLOSE: &str = "<!-- /headlines -->";

/// The headline of a results page (`None` without one, or on a quick run's page).
pub fn headline_of(results_md: &str) -> Option<&str> {
    results_md
        .lines()
        .find_map(|line| line.strip_prefix(PREFIX))
}

/// The headline table of `(evaluation, its results page)`, in the order given; evaluations
/// whose page has no full-run headline get no row.
pub fn table<'a>(pages: impl IntoIterator<Item = (&'a str, &'a str)>) -> String {
    let mut out = String::from("| Evaluation | Headline (last full run) |\n| --- | --- |\n");
    for (name, page) in pages {
        if let Some(headline) = headline_of(page) {
            out.push_str(&format!(
                "| [{name}](docs/results/{name}.md) | {} |\n",
                headline.replace('|', "\\|")
            ));
        }
    }
    out
}

/// The headline table of the results pages under `root/docs/results/` (missing pages give no
/// row), in the order `cargo xtask eval all` runs the evaluations.
pub fn table_of(root: &Path) -> String {
    let pages: Vec<(&str, String)> = crate::eval::names()
        .map(|name| {
            let path = root.join(format!("docs/results/{name}.md"));
            (name, std::fs::read_to_string(path).unwrap_or_default())
        })
        .collect();
    table(pages.iter().map(|(name, page)| (*name, page.as_str())))
}

/// `readme` with the text between the headline markers replaced by `table` (a line break
/// after the opening marker); `None` when the README has no markers.
pub fn replace(readme: &str, table: &str) -> Option<String> {
    let start = readme.find(OPEN)? + OPEN.len();
    let end = start + readme[start..].find(CLOSE)?;
    Some(format!("{}\n{table}{}", &readme[..start], &readme[end..]))
}

/// Rewrites the headline table of `root/README.md` from the results pages under `root`
/// (nothing when the README has no markers or the table is unchanged).
pub fn update(root: &Path) -> Result<()> {
    let path = root.join("README.md");
    let readme =
        std::fs::read_to_string(&path).with_context(|| format!("reading {}", path.display()))?;
    if let Some(updated) = replace(&readme, &table_of(root))
        && updated != readme
    {
        std::fs::write(&path, updated).with_context(|| format!("writing {}", path.display()))?;
        eprintln!("updated the headline table in {}", path.display());
    }
    Ok(())
}

#[cfg(test)]
#[allow(clippy::unwrap_used)] // test code: a panic is the failure report
mod tests {
    use super::*;

    /// The text between the README's headline markers (`None` without them).
    fn marked(readme: &str) -> Option<&str> {
        let start = readme.find(OPEN)? + OPEN.len();
        let end = start + readme[start..].find(CLOSE)?;
        Some(
            readme[start..end]
                .strip_prefix('\n')
                .unwrap_or(&readme[start..end]),
        )
    }

    #[test]
    fn the_table_has_a_row_per_full_run_headline() {
        let pages = [
            ("a", "# A\n\n**Headline.** 1.5 % | 2 m\n\nbody"),
            ("b", "# B\n\n**Headline (quick run).** 3 m\n"),
            ("c", "# C\n\nno headline\n"),
            ("d", "**Headline.** 4 s\n"),
        ];
        let t = table(pages);
        assert_eq!(
            t,
            "| Evaluation | Headline (last full run) |\n| --- | --- |\n\
             | [a](docs/results/a.md) | 1.5 % \\| 2 m |\n\
             | [d](docs/results/d.md) | 4 s |\n"
        );
        let readme = format!("x\n{OPEN}\nold\n{CLOSE}\ny");
        let new = replace(&readme, &t).unwrap();
        assert_eq!(new, format!("x\n{OPEN}\n{t}{CLOSE}\ny"));
        assert_eq!(marked(&new), Some(t.as_str()));
        assert_eq!(replace(&new, &t).as_deref(), Some(new.as_str()));
        assert!(replace("no markers", &t).is_none());
        assert_eq!(headline_of("# T\n\n**Headline.** 3 m\n"), Some("3 m"));
        assert_eq!(headline_of("**Headline (quick run).** 3 m"), None);
    }

    /// Every figure of the README's headline table is the headline of a full run's results
    /// page, and every full-run headline has its row.
    #[test]
    fn readme_headlines_equal_the_results_pages() {
        let root = crate::eval::workspace_root();
        let readme = std::fs::read_to_string(root.join("README.md")).unwrap();
        let marked = marked(&readme).expect("README.md has no `<!-- headlines -->` table");
        let expected = table_of(&root);
        assert!(
            expected.lines().count() > 2,
            "no results page under docs/results/ has a full-run headline"
        );
        assert_eq!(
            marked, expected,
            "the README's headline table differs from the results pages (a full run of \
             `cargo xtask eval NAME` rewrites it; a quick run's page has no headline)"
        );
    }
}
