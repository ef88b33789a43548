//! `cargo xtask datasets generate`: write the simulated data sets under `datasets/generated/`.
//!
//! Each set is written into a temporary directory beside its final place and renamed when
//! complete, so an interrupted run never leaves half a set. Beside the data, every set gets
//! `SHA256SUMS` (checkable with `sha256sum -c`) and `set.json` (seed, mode, files, statistics).

use std::io::Read;
use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result, bail};
use indicatif::{ProgressBar, ProgressStyle};
use raypath_sim::datasets::{DEFAULT_SEED, SETS, SetSpec};
use sha2::{Digest, Sha256};

use crate::eval::workspace_root;

/// Where generated sets live.
pub fn generated_root() -> PathBuf {
    workspace_root().join("datasets/generated")
}

/// Generates the selected sets (all, or `only`).
pub fn run(quick: bool, only: Option<&str>, seed: Option<u64>) -> Result<()> {
    let selected: Vec<&SetSpec> = match only {
        Some(name) => match raypath_sim::datasets::find(name) {
            Some(set) => vec![set],
            None => {
                let names: Vec<_> = SETS.iter().map(|s| s.name).collect();
                bail!(
                    "no generated set named {name:?}; choose one of {}",
                    names.join(", ")
                );
            }
        },
        None => SETS.iter().collect(),
    };
    let seed = seed.unwrap_or(DEFAULT_SEED);
    let started = Instant::now();
    for set in selected {
        if let Some(missing) = missing_input(set) {
            eprintln!(
                "{:>16}: skipped, needs {missing} (set RAYPATH_DATA)",
                set.name
            );
            continue;
        }
        generate(set, quick, seed)?;
    }
    eprintln!(
        "generated in {:.1} s under {}",
        started.elapsed().as_secs_f64(),
        generated_root().display()
    );
    Ok(())
}

/// The directory of `name`, generating it first when it is missing or was generated in a
/// smaller mode than asked for (a full set also serves `--quick`).
pub fn ensure(name: &str, quick: bool) -> Result<PathBuf> {
    let dir = generated_root().join(name);
    if let Some(info) = read_set_info(&dir)
        && (info.quick == quick || !info.quick)
    {
        return Ok(dir);
    }
    let Some(set) = raypath_sim::datasets::find(name) else {
        bail!("no generated set named {name:?}");
    };
    if let Some(missing) = missing_input(set) {
        bail!("the {name} set needs {missing} (set RAYPATH_DATA)");
    }
    generate(set, quick, DEFAULT_SEED)?;
    Ok(dir)
}

/// The raw log and the corrected log of the generated `indoor` world `world`
/// (`<world>.clf` and `<world>-corrected.log`, plain or compressed), generating the set
/// first when needed; `None` when the set has no such world.
pub fn indoor_logs(world: &str, quick: bool) -> Result<Option<(PathBuf, PathBuf)>> {
    let dir = ensure("indoor", quick)?;
    let find = |stem: String| {
        ["", ".gz", ".bz2"]
            .iter()
            .map(|ext| dir.join(format!("{stem}{ext}")))
            .find(|p| p.exists())
    };
    Ok(find(format!("{world}.clf")).zip(find(format!("{world}-corrected.log"))))
}

/// The real input a set needs and the data directory lacks, if any.
fn missing_input(set: &SetSpec) -> Option<String> {
    let required = set.requires?;
    raypath_io::data::find(required).is_none().then(|| {
        raypath_io::data::data_dir()
            .join(required)
            .display()
            .to_string()
    })
}

/// How long generating a set took: beside `set.json`, not in it, so that the same seed gives
/// the same bytes in every file the set lists and in `set.json` itself.
pub const TIMING_FILE: &str = "timing.json";
/// The bookkeeping files of a set, not listed in it.
const BOOKKEEPING: [&str; 3] = ["SHA256SUMS", "set.json", TIMING_FILE];
/// Statistics keys that are measured times, not properties of the data.
const TIMING_KEYS: [&str; 2] = ["elapsed_s", "rays_per_s"];

/// Removes the timing keys from `stats` and returns them with the whole run's seconds.
fn take_timing(stats: &mut serde_json::Value, total_s: f64) -> serde_json::Value {
    let mut timing = serde_json::Map::new();
    if let Some(object) = stats.as_object_mut() {
        for key in TIMING_KEYS {
            if let Some(value) = object.remove(key) {
                timing.insert(key.to_owned(), value);
            }
        }
    }
    timing.insert("total_s".to_owned(), serde_json::json!(total_s));
    serde_json::Value::Object(timing)
}

struct SetInfo {
    quick: bool,
}

fn read_set_info(dir: &Path) -> Option<SetInfo> {
    let text = std::fs::read_to_string(dir.join("set.json")).ok()?;
    let json: serde_json::Value = serde_json::from_str(&text).ok()?;
    Some(SetInfo {
        quick: json.get("quick")?.as_bool()?,
    })
}

fn generate(set: &SetSpec, quick: bool, seed: u64) -> Result<()> {
    generate_into(&generated_root(), set, quick, seed)
}

/// Generates `set` into `root/<name>` (through a partial directory renamed at the end).
fn generate_into(root: &Path, set: &SetSpec, quick: bool, seed: u64) -> Result<()> {
    let root = root.to_path_buf();
    std::fs::create_dir_all(&root).with_context(|| format!("creating {}", root.display()))?;
    let final_dir = root.join(set.name);
    let work_dir = root.join(format!(".{}.partial", set.name));
    if work_dir.exists() {
        std::fs::remove_dir_all(&work_dir)?;
    }

    let bar = ProgressBar::new(0);
    bar.set_style(
        ProgressStyle::with_template(
            "{msg:>16} [{bar:30}] {pos}/{len} {elapsed_precise} (eta {eta})",
        )
        .unwrap_or_else(|_| ProgressStyle::default_bar())
        .progress_chars("=> "),
    );
    bar.set_message(set.name.to_owned());
    let progress = |done: u64, total: u64| {
        bar.set_length(total);
        bar.set_position(done);
    };
    let started = Instant::now();
    let generated = (set.generate)(quick, seed, &work_dir, &progress)
        .with_context(|| format!("generating {}", set.name))?;
    bar.finish_and_clear();

    let mut files = list_files(&work_dir)?;
    files.sort();
    let mut sums = String::new();
    let mut entries = Vec::new();
    let mut total_bytes = 0u64;
    for relative in &files {
        let (digest, bytes) = sha256_file(&work_dir.join(relative))?;
        sums.push_str(&format!("{digest}  {}\n", relative.display()));
        total_bytes += bytes;
        entries.push(serde_json::json!({"path": relative.display().to_string(), "bytes": bytes, "sha256": digest}));
    }
    std::fs::write(work_dir.join("SHA256SUMS"), &sums)?;
    let mut stats = generated.stats;
    let timing = take_timing(&mut stats, started.elapsed().as_secs_f64());
    std::fs::write(
        work_dir.join(TIMING_FILE),
        serde_json::to_string_pretty(&timing)?,
    )?;
    let info = serde_json::json!({
        "name": set.name,
        "about": set.about,
        "description": generated.description,
        "seed": seed,
        "quick": quick,
        "generated_by": format!("raypath-sim {}", env!("CARGO_PKG_VERSION")),
        "files": entries,
        "bytes": total_bytes,
        "stats": stats,
    });
    std::fs::write(
        work_dir.join("set.json"),
        serde_json::to_string_pretty(&info)?,
    )?;

    if final_dir.exists() {
        std::fs::remove_dir_all(&final_dir)
            .with_context(|| format!("removing the old {}", final_dir.display()))?;
    }
    std::fs::rename(&work_dir, &final_dir)
        .with_context(|| format!("moving the set to {}", final_dir.display()))?;
    eprintln!(
        "{:>16}: {} files, {:.1} MB in {:.1} s ({}, seed {seed})",
        set.name,
        files.len(),
        total_bytes as f64 / 1e6,
        started.elapsed().as_secs_f64(),
        if quick { "quick" } else { "full" },
    );
    Ok(())
}

/// Files below `dir`, relative to it (the bookkeeping files excluded).
fn list_files(dir: &Path) -> Result<Vec<PathBuf>> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(current) = stack.pop() {
        for entry in
            std::fs::read_dir(&current).with_context(|| format!("listing {}", current.display()))?
        {
            let path = entry?.path();
            if path.is_dir() {
                stack.push(path);
            } else if let Ok(relative) = path.strip_prefix(dir) {
                if !BOOKKEEPING.iter().any(|b| relative == Path::new(b)) {
                    out.push(relative.to_path_buf());
                }
            }
        }
    }
    Ok(out)
}

fn sha256_file(path: &Path) -> Result<(String, u64)> {
    let mut file =
        std::fs::File::open(path).with_context(|| format!("opening {}", path.display()))?;
    let mut hasher = Sha256::new();
    let mut buffer = vec![0u8; 1 << 16];
    let mut total = 0u64;
    loop {
        let n = file.read(&mut buffer)?;
        if n == 0 {
            break;
        }
        hasher.update(&buffer[..n]);
        total += n as u64;
    }
    let digest = hasher.finalize();
    Ok((digest.iter().map(|b| format!("{b:02x}")).collect(), total))
}

#[cfg(test)]
#[allow(clippy::unwrap_used)] // test code: a panic is the failure report
mod tests {
    use super::*;

    /// Same seed, same bytes: a set generated twice is identical file for file, `set.json`
    /// and `SHA256SUMS` included.
    #[test]
    fn same_seed_same_bytes() {
        let set = raypath_sim::datasets::find("polygons").unwrap();
        let dirs = [tempfile::tempdir().unwrap(), tempfile::tempdir().unwrap()];
        for dir in &dirs {
            generate_into(dir.path(), set, true, 7).unwrap();
        }
        let [a, b] = [&dirs[0], &dirs[1]].map(|d| d.path().join("polygons"));
        let mut files = list_files(&a).unwrap();
        files.extend(["set.json", "SHA256SUMS"].map(PathBuf::from));
        assert!(files.len() > 2);
        for file in files {
            let (x, y) = (
                std::fs::read(a.join(&file)).unwrap(),
                std::fs::read(b.join(&file)).unwrap(),
            );
            assert!(x == y, "{} differs between two runs", file.display());
        }
    }

    #[test]
    fn timings_leave_the_set_description() {
        let mut stats = serde_json::json!({"scans": 3, "elapsed_s": 1.5, "rays_per_s": 2e6});
        let timing = take_timing(&mut stats, 2.0);
        assert_eq!(stats, serde_json::json!({"scans": 3}));
        assert_eq!(
            timing,
            serde_json::json!({"elapsed_s": 1.5, "rays_per_s": 2e6, "total_s": 2.0})
        );
    }
}
