//! `cargo xtask check-layers`: the crate layers of `docs/architecture.md` hold in the code.
//!
//! The layer of every workspace crate is read from the architecture page's crate table
//! (`| \`crate\` | layer | … |`), its dependencies from `cargo metadata`. A crate may depend on
//! crates of its own layer or below — never above; normal and build dependencies count,
//! dev-dependencies (tests, benchmarks, examples) do not. Every workspace crate must be in the
//! table, so the page cannot fall behind the workspace.
//!
//! The crate graph drawn on the page (lines `crate ──► dep, dep`, or `──► every library crate
//! below`) must list every crate with exactly its dependencies.
//!
//! Library crates (every workspace crate but the `raypath` program, xtask and the evaluations
//! it runs, `raypath-eval`) do not print: no `println!`, `eprintln!`, `print!`, `eprint!` or
//! `dbg!` in their `src/` outside comments, test modules (`#[cfg(test)] mod …`, `tests.rs`,
//! `tests/`) and [`PRINT_ALLOWED`]. Their warnings are values and go through the `log` facade;
//! the program and xtask print them.

use std::collections::BTreeMap;
use std::path::Path;
use std::process::Command;

use anyhow::{Context, Result, bail};

/// The layers from the bottom up.
const LAYERS: [&str; 6] = [
    "foundation",
    "models",
    "algorithms",
    "systems",
    "application",
    "tooling",
];

/// The crates that may print: the program, the developer tool and the evaluations it runs
/// (progress bars and the tables of a run).
const PRINTING_CRATES: [&str; 3] = ["raypath-cli", "xtask", "raypath-eval"];

/// The crates that face users and are no library other crates build on: the program, the
/// developer tool, the evaluations (a library only xtask calls) and the Python package (which
/// prints nothing).
const APPLICATIONS: [&str; 4] = ["raypath-cli", "xtask", "raypath-eval", "raypath-python"];

/// The printing macros a library crate may not call.
const PRINT_MACROS: [&str; 5] = ["println", "eprintln", "print", "eprint", "dbg"];

/// Library files that may print, relative to the workspace root, each with its reason.
pub const PRINT_ALLOWED: [(&str, &str); 1] = [(
    "crates/io/src/data.rs",
    "test support: `skip` reports a skipped test on the test's standard error",
)];

/// `line` with the contents of its string and character literals blanked (so braces and macro
/// names inside them do not count); a line comment is cut off.
fn code_of(line: &str) -> String {
    let mut out = String::with_capacity(line.len());
    let mut chars = line.chars().peekable();
    let mut in_string = false;
    while let Some(c) = chars.next() {
        if in_string {
            match c {
                '\\' => {
                    chars.next();
                }
                '"' => {
                    in_string = false;
                    out.push('"');
                }
                _ => out.push(' '),
            }
            continue;
        }
        match c {
            '"' => {
                in_string = true;
                out.push('"');
            }
            '/' if chars.peek() == Some(&'/') => break,
            '\'' => {
                // A character literal ('{', '\'') or a lifetime ('a): blank a literal's body.
                let rest: String = chars.clone().take(3).collect();
                let len = if rest.starts_with('\\') {
                    rest.chars().skip(2).position(|c| c == '\'').map(|p| p + 3)
                } else {
                    (rest.chars().nth(1) == Some('\'')).then_some(2)
                };
                out.push('\'');
                if let Some(len) = len {
                    for _ in 0..len {
                        chars.next();
                    }
                    out.push_str(&" ".repeat(len.saturating_sub(1)));
                    out.push('\'');
                }
            }
            _ => out.push(c),
        }
    }
    out
}

/// The printing macro calls in a Rust source file: `(line number, line)` for every call
/// outside comments, string literals and `#[cfg(test)]` items.
pub fn print_calls(source: &str) -> Vec<(usize, String)> {
    let mut out = Vec::new();
    let mut test_attribute = false;
    // Depth of braces inside a skipped `#[cfg(test)]` item (`None`: not in one).
    let mut skipping: Option<i64> = None;
    for (i, line) in source.lines().enumerate() {
        let code = code_of(line);
        let opens = code.matches('{').count() as i64;
        let closes = code.matches('}').count() as i64;
        if let Some(depth) = skipping.as_mut() {
            *depth += opens - closes;
            if *depth <= 0 {
                skipping = None;
            }
            continue;
        }
        let trimmed = code.trim();
        if trimmed.starts_with("#[cfg(test)]") {
            test_attribute = true;
            continue;
        }
        if test_attribute && !trimmed.starts_with("#[") && !trimmed.is_empty() {
            test_attribute = false;
            if opens > closes {
                skipping = Some(opens - closes);
            }
            continue;
        }
        let calls = PRINT_MACROS.iter().any(|name| {
            code.match_indices(&format!("{name}!")).any(|(at, _)| {
                !code[..at]
                    .chars()
                    .next_back()
                    .is_some_and(|c| c.is_alphanumeric() || c == '_')
            })
        });
        if calls {
            out.push((i + 1, line.trim().to_owned()));
        }
    }
    out
}

/// Every `.rs` file under `dir`, but test files (`tests.rs`, anything under a `tests/`).
fn library_sources(dir: &Path, out: &mut Vec<std::path::PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    let mut entries: Vec<_> = entries.flatten().map(|e| e.path()).collect();
    entries.sort();
    for path in entries {
        let name = path.file_name().map(|n| n.to_string_lossy().into_owned());
        if path.is_dir() {
            if name.as_deref() != Some("tests") {
                library_sources(&path, out);
            }
        } else if name
            .as_deref()
            .is_some_and(|n| n.ends_with(".rs") && n != "tests.rs")
        {
            out.push(path);
        }
    }
}

/// Every printing call in the `src/` of the library crates among `packages`
/// (`(name, crate directory)`), as `path:line: code` relative to `root`.
pub fn printing_violations(root: &Path, packages: &[(String, std::path::PathBuf)]) -> Vec<String> {
    let mut out = Vec::new();
    for (name, dir) in packages {
        if PRINTING_CRATES.contains(&name.as_str()) {
            continue;
        }
        let mut files = Vec::new();
        library_sources(&dir.join("src"), &mut files);
        for file in files {
            let relative = file.strip_prefix(root).unwrap_or(&file);
            let shown = relative.to_string_lossy().replace('\\', "/");
            if PRINT_ALLOWED.iter().any(|(path, _)| *path == shown) {
                continue;
            }
            let Ok(source) = std::fs::read_to_string(&file) else {
                continue;
            };
            for (line, code) in print_calls(&source) {
                out.push(format!(
                    "`{name}` prints (library crates return warnings as values or use `log`): \
                     {shown}:{line}: {code}"
                ));
            }
        }
    }
    out
}

/// `(name, crate directory)` of every workspace package in `cargo metadata` JSON.
pub fn package_dirs(metadata: &serde_json::Value) -> Vec<(String, std::path::PathBuf)> {
    metadata["packages"]
        .as_array()
        .into_iter()
        .flatten()
        .filter_map(|p| {
            let name = p["name"].as_str()?;
            let manifest = Path::new(p["manifest_path"].as_str()?);
            Some((name.to_owned(), manifest.parent()?.to_path_buf()))
        })
        .collect()
}

/// What the page's crate graph draws for a crate: its dependencies, or every library crate.
#[derive(Debug, PartialEq)]
pub enum Drawn {
    /// Exactly these workspace crates.
    Crates(Vec<String>),
    /// Every workspace crate but the [`APPLICATIONS`] (the program, the tool, the Python
    /// package).
    EveryLibrary,
}

/// `crate → what it depends on` from the lines of the page's crate graph: a line naming a
/// crate (`raypath-…` or `xtask`), optionally after its layer, then `──►` and the
/// dependencies separated by commas (none: no arrow).
pub fn graph_from_page(page: &str) -> BTreeMap<String, Drawn> {
    let mut out = BTreeMap::new();
    let mut in_block = false;
    for line in page.lines() {
        if line.trim_start().starts_with("```") {
            in_block = !in_block;
            continue;
        }
        if !in_block {
            continue;
        }
        let (left, right) = match line.split_once("──►") {
            Some((l, r)) => (l, Some(r)),
            None => (line, None),
        };
        let mut words = left.split_whitespace();
        let Some(name) = words.find(|w| w.starts_with("raypath-") || *w == "xtask") else {
            continue;
        };
        if words.next().is_some() {
            continue; // not a graph line (prose or a picture)
        }
        let drawn = match right.map(str::trim) {
            Some(r) if r.starts_with("every library crate") => Drawn::EveryLibrary,
            Some(r) => Drawn::Crates(
                r.split(',')
                    .map(|d| d.trim().to_owned())
                    .filter(|d| !d.is_empty())
                    .collect(),
            ),
            None => Drawn::Crates(Vec::new()),
        };
        out.insert(name.to_owned(), drawn);
    }
    out
}

/// Every difference between the drawn graph and the dependencies.
pub fn graph_violations(
    drawn: &BTreeMap<String, Drawn>,
    deps: &[(String, Vec<String>)],
) -> Vec<String> {
    let libraries: Vec<String> = deps
        .iter()
        .map(|(n, _)| n.clone())
        .filter(|n| !APPLICATIONS.contains(&n.as_str()))
        .collect();
    let mut out = Vec::new();
    for (name, uses) in deps {
        let mut actual = uses.clone();
        actual.sort();
        actual.dedup();
        let mut expected = match drawn.get(name) {
            None => {
                out.push(format!(
                    "`{name}` is not in the crate graph of docs/architecture.md"
                ));
                continue;
            }
            Some(Drawn::EveryLibrary) => libraries.clone(),
            Some(Drawn::Crates(list)) => list.clone(),
        };
        expected.sort();
        expected.dedup();
        if actual != expected {
            out.push(format!(
                "the crate graph of docs/architecture.md draws `{name}` ──► {}, but it depends on {}",
                expected.join(", "),
                if actual.is_empty() { "nothing".to_owned() } else { actual.join(", ") }
            ));
        }
    }
    for name in drawn.keys() {
        if !deps.iter().any(|(n, _)| n == name) {
            out.push(format!(
                "the crate graph of docs/architecture.md draws `{name}`, which is no workspace crate"
            ));
        }
    }
    out
}

/// `crate → layer rank` from the rows of the architecture page's crate table.
pub fn layers_from_page(page: &str) -> Result<BTreeMap<String, usize>> {
    let mut out = BTreeMap::new();
    for line in page.lines() {
        let cells: Vec<&str> = line.split('|').map(str::trim).collect();
        let [_, name, layer, ..] = cells.as_slice() else {
            continue;
        };
        let Some(name) = name.strip_prefix('`').and_then(|n| n.strip_suffix('`')) else {
            continue;
        };
        let Some(rank) = LAYERS.iter().position(|l| l == layer) else {
            continue;
        };
        out.insert(name.to_owned(), rank);
    }
    if out.is_empty() {
        bail!("no `| \\`crate\\` | layer |` rows found");
    }
    Ok(out)
}

/// `(crate, its workspace dependencies)` from `cargo metadata` JSON, normal and build
/// dependencies only.
pub fn dependencies(metadata: &serde_json::Value) -> Result<Vec<(String, Vec<String>)>> {
    let packages = metadata["packages"]
        .as_array()
        .context("cargo metadata: no `packages` array")?;
    let members: Vec<&str> = packages.iter().filter_map(|p| p["name"].as_str()).collect();
    let mut out = Vec::new();
    for p in packages {
        let name = p["name"]
            .as_str()
            .context("cargo metadata: package without a name")?;
        let deps = p["dependencies"]
            .as_array()
            .into_iter()
            .flatten()
            .filter(|d| d["kind"].as_str() != Some("dev"))
            .filter_map(|d| d["name"].as_str())
            .filter(|d| members.contains(d))
            .map(str::to_owned)
            .collect();
        out.push((name.to_owned(), deps));
    }
    Ok(out)
}

/// Every violation: a crate missing from the table, or a dependency on a higher layer.
pub fn violations(layers: &BTreeMap<String, usize>, deps: &[(String, Vec<String>)]) -> Vec<String> {
    let mut out = Vec::new();
    for (name, uses) in deps {
        let Some(&rank) = layers.get(name) else {
            out.push(format!(
                "`{name}` is not in the crate table of docs/architecture.md"
            ));
            continue;
        };
        for dep in uses {
            match layers.get(dep) {
                Some(&r) if r > rank => out.push(format!(
                    "`{name}` ({}) depends on `{dep}` ({}), a higher layer",
                    LAYERS[rank], LAYERS[r]
                )),
                Some(_) => {}
                None => out.push(format!(
                    "`{dep}` is not in the crate table of docs/architecture.md"
                )),
            }
        }
    }
    out.sort();
    out.dedup();
    out
}

/// Runs the check on the workspace at `root`; fails listing every violation.
pub fn run(root: &Path) -> Result<()> {
    let page_path = root.join("docs/architecture.md");
    let page = std::fs::read_to_string(&page_path)
        .with_context(|| format!("reading {}", page_path.display()))?;
    let layers = layers_from_page(&page).with_context(|| page_path.display().to_string())?;
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let output = Command::new(cargo)
        .args(["metadata", "--format-version", "1", "--no-deps"])
        .current_dir(root)
        .output()
        .context("running cargo metadata")?;
    if !output.status.success() {
        bail!(
            "cargo metadata failed: {}",
            String::from_utf8_lossy(&output.stderr)
        );
    }
    let metadata: serde_json::Value =
        serde_json::from_slice(&output.stdout).context("parsing cargo metadata")?;
    let deps = dependencies(&metadata)?;
    let root = std::fs::canonicalize(root).unwrap_or_else(|_| root.to_path_buf());
    let mut found = violations(&layers, &deps);
    found.extend(graph_violations(&graph_from_page(&page), &deps));
    found.extend(printing_violations(&root, &package_dirs(&metadata)));
    for (name, uses) in &deps {
        let rank = layers.get(name).map_or("?", |&r| LAYERS[r]);
        println!("{name:<28} {rank:<12} {}", uses.join(", "));
    }
    if found.is_empty() {
        println!(
            "layers hold: {} crates, none depends on a higher layer; no library crate prints",
            deps.len()
        );
        Ok(())
    } else {
        bail!("{} layer violation(s):\n{}", found.len(), found.join("\n"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const PAGE: &str = "| Crate | Layer | What |\n| --- | --- | --- |\n\
        | `geo` | foundation | x |\n| `algo` | algorithms | y |\n| `model` | models | z |\n";

    fn deps(list: &[(&str, &[&str])]) -> Vec<(String, Vec<String>)> {
        list.iter()
            .map(|(n, d)| (n.to_string(), d.iter().map(|s| s.to_string()).collect()))
            .collect()
    }

    #[test]
    fn reads_the_table_and_finds_upward_and_unlisted_dependencies() {
        let layers = layers_from_page(PAGE).unwrap();
        assert_eq!(layers.len(), 3);
        assert!(violations(&layers, &deps(&[("algo", &["model", "geo"])])).is_empty());
        let v = violations(&layers, &deps(&[("model", &["algo"]), ("new", &[])]));
        assert_eq!(v.len(), 2, "{v:?}");
        assert!(
            v.iter()
                .any(|m| m.contains("`model` (models) depends on `algo`"))
        );
        assert!(
            v.iter()
                .any(|m| m.contains("`new` is not in the crate table"))
        );
    }

    #[test]
    fn dev_dependencies_do_not_count() {
        let metadata = serde_json::json!({"packages": [
            {"name": "geo", "dependencies": [{"name": "algo", "kind": "dev"}]},
            {"name": "algo", "dependencies": [{"name": "geo", "kind": null}, {"name": "rand", "kind": null}]}
        ]});
        let d = dependencies(&metadata).unwrap();
        assert_eq!(d, deps(&[("geo", &[]), ("algo", &["geo"])]));
    }

    #[test]
    fn the_drawn_graph_must_match_the_dependencies() {
        let page = "text\n```text\ntooling  xtask ──► every library crate below\n\
                    models   algo ──► geo\n         geo\nnot a raypath-x line at all\n```\n";
        let drawn = graph_from_page(page);
        assert_eq!(drawn.len(), 1, "{drawn:?}"); // `algo` and `geo` are no `raypath-` names
        let page = page
            .replace("algo", "raypath-algo")
            .replace("  geo", "  raypath-geo");
        let page = page.replace("──► geo", "──► raypath-geo");
        let drawn = graph_from_page(&page);
        assert_eq!(drawn.len(), 3, "{drawn:?}");
        let good = deps(&[
            ("xtask", &["raypath-algo", "raypath-geo"]),
            ("raypath-algo", &["raypath-geo"]),
            ("raypath-geo", &[]),
        ]);
        assert!(graph_violations(&drawn, &good).is_empty());
        let bad = deps(&[
            ("xtask", &["raypath-algo"]),
            ("raypath-algo", &[]),
            ("raypath-geo", &[]),
            ("raypath-new", &[]),
        ]);
        let v = graph_violations(&drawn, &bad);
        assert_eq!(v.len(), 3, "{v:?}");
        assert!(v.iter().any(|m| {
            m.contains("draws `raypath-algo` ──► raypath-geo, but it depends on nothing")
        }));
        assert!(
            v.iter()
                .any(|m| m.contains("`raypath-new` is not in the crate graph"))
        );
    }

    #[test]
    fn finds_printing_calls_outside_comments_strings_and_tests() {
        let source = r#"//! println!("doc example");
/// eprintln!("doc");
fn a() {
    let s = "println!(\"in a string\")";
    eprintln!("warning: {s}");
    writeln!(out, "x").ok(); // println!("comment")
    std::print!("x");
    let v = dbg!(1 + 1);
    let c = '{';
}

#[cfg(test)]
mod tests {
    #[test]
    fn t() {
        println!("in a test {}", '}');
    }
}

fn b() { eprint!("after the tests"); }
"#;
        let found: Vec<usize> = print_calls(source).into_iter().map(|(l, _)| l).collect();
        assert_eq!(found, vec![5, 7, 8, 20]);
    }

    #[test]
    fn library_crates_may_not_print_but_the_program_may() {
        let dir = std::env::temp_dir().join(format!("xtask-layers-{}", std::process::id()));
        for (krate, file, text) in [
            ("lib", "src/lib.rs", "pub fn f() { println!(\"x\"); }\n"),
            ("lib", "src/m/tests.rs", "fn t() { println!(\"x\"); }\n"),
            ("lib", "src/tests/a.rs", "fn t() { println!(\"x\"); }\n"),
            ("cli", "src/main.rs", "fn main() { println!(\"x\"); }\n"),
        ] {
            let path = dir.join(krate).join(file);
            std::fs::create_dir_all(path.parent().unwrap()).unwrap();
            std::fs::write(path, text).unwrap();
        }
        let packages = vec![
            ("raypath-lib".to_owned(), dir.join("lib")),
            ("raypath-cli".to_owned(), dir.join("cli")),
        ];
        let found = printing_violations(&dir, &packages);
        std::fs::remove_dir_all(&dir).ok();
        assert_eq!(found.len(), 1, "{found:?}");
        assert!(found[0].contains("`raypath-lib` prints"), "{found:?}");
        assert!(found[0].contains("lib/src/lib.rs:1:"), "{found:?}");
    }

    /// The workspace itself passes (what CI runs as `cargo xtask check-layers`).
    #[test]
    fn the_workspace_layers_hold() {
        run(&Path::new(env!("CARGO_MANIFEST_DIR")).join("..")).unwrap();
    }
}
