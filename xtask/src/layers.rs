//! `cargo xtask check-layers`: the crate layers of `docs/architecture.md` hold in the code.
//!
//! The layer of every workspace crate is read from the architecture page's crate table
//! (`| \`crate\` | layer | … |`), its dependencies from `cargo metadata`. A crate may depend on
//! crates of its own layer or below — never above; normal and build dependencies count,
//! dev-dependencies (tests, benchmarks, examples) do not. Every workspace crate must be in the
//! table, so the page cannot fall behind the workspace.

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
    let found = violations(&layers, &deps);
    for (name, uses) in &deps {
        let rank = layers.get(name).map_or("?", |&r| LAYERS[r]);
        println!("{name:<28} {rank:<12} {}", uses.join(", "));
    }
    if found.is_empty() {
        println!(
            "layers hold: {} crates, none depends on a higher layer",
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

    /// The workspace itself passes (what CI runs as `cargo xtask check-layers`).
    #[test]
    fn the_workspace_layers_hold() {
        run(&Path::new(env!("CARGO_MANIFEST_DIR")).join("..")).unwrap();
    }
}
