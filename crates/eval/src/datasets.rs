//! `cargo xtask datasets`: which data sets of `datasets/manifest.json` are under
//! `RAYPATH_DATA`, which are missing, and where to get them.

use anyhow::{Context, Result};
use serde::Deserialize;

use crate::eval::{data_dir, workspace_root};
use crate::table::Table;

#[derive(Deserialize)]
struct Manifest {
    datasets: Vec<Dataset>,
}

#[derive(Deserialize)]
struct Dataset {
    id: String,
    name: String,
    source: String,
    license: String,
    size: String,
    layout: String,
    check: Vec<String>,
    #[serde(default)]
    check_mode: Option<String>,
    place: String,
}

/// Prints the status of every data set.
pub fn run(json: bool) -> Result<()> {
    let path = workspace_root().join("datasets/manifest.json");
    let text =
        std::fs::read_to_string(&path).with_context(|| format!("reading {}", path.display()))?;
    let manifest: Manifest =
        serde_json::from_str(&text).with_context(|| format!("parsing {}", path.display()))?;
    let data = data_dir();

    let mut rows = Vec::new();
    for set in &manifest.datasets {
        let present = set.check.iter().filter(|p| data.join(p).exists()).count();
        let any = set.check_mode.as_deref() == Some("any");
        let status = match (present, any) {
            (0, _) => "missing",
            (_, true) => "found",
            (n, false) if n == set.check.len() => "found",
            _ => "partial",
        };
        rows.push((set, status, present));
    }

    if json {
        let out: Vec<_> = rows
            .iter()
            .map(|(set, status, present)| {
                serde_json::json!({
                    "id": set.id, "name": set.name, "status": status,
                    "present": present, "checked": set.check.len(),
                    "source": set.source, "license": set.license, "size": set.size,
                    "layout": set.layout, "place": set.place,
                })
            })
            .collect();
        println!(
            "{}",
            serde_json::to_string_pretty(&serde_json::json!({
                "data_dir": data.display().to_string(),
                "datasets": out,
            }))?
        );
        return Ok(());
    }

    println!("RAYPATH_DATA = {}\n", data.display());
    let mut table = Table::new(["data set", "status", "layout"]);
    for (set, status, present) in &rows {
        let status = if *status == "partial" {
            format!("partial ({present}/{})", set.check.len())
        } else {
            (*status).to_owned()
        };
        table.row([set.id.clone(), status, set.layout.clone()]);
    }
    print!("{}", table.to_markdown()?);
    let missing: Vec<_> = rows.iter().filter(|(_, s, _)| *s != "found").collect();
    if !missing.is_empty() {
        println!("\nWhere to get what is missing:\n");
        for (set, _, _) in missing {
            println!(
                "- {} — {}\n  source: {}\n  license: {}; size: {}\n  place: {}\n",
                set.id, set.name, set.source, set.license, set.size, set.place
            );
        }
    }
    Ok(())
}
