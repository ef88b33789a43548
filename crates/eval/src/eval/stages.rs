//! Evaluations in stages — list the units, measure each unit, report over all units — so
//! that the units can run apart and be merged:
//!
//! ```text
//! cargo xtask eval carmen-angles --shard 1/2     # units 1, 3, 5, … → target/eval/shards/
//! cargo xtask eval carmen-angles --shard 2/2     # units 2, 4, 6, …
//! cargo xtask eval merge carmen-angles           # the page a single run writes
//! ```
//!
//! A shard measures every n-th unit (unit k, counted from 0, belongs to shard `k mod n + 1`)
//! and writes its results to `target/eval/shards/<name>/<i>-of-<n>.json`; `merge` checks that
//! the shards of one `n` cover every unit exactly once, with the same `--quick` and data
//! directory, and writes the report from them with the code an unsharded run uses. The
//! report is a function of the unit results alone, so a merged report equals an unsharded
//! one (tested); only the run-time line differs (the merged page gives the shards' sum).
//! Shards on a cluster need the workspace and `RAYPATH_DATA` on a shared file system:
//! `docs/cluster/` has a Slurm job array and a Kubernetes Indexed Job.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result, bail, ensure};
use serde_json::{Value, json};

use super::{EvalContext, EvalReport};

/// The results of the units, in report order: (unit, result).
pub type UnitResults = [(String, Value)];

/// An evaluation split into stages.
pub struct Staged {
    /// The evaluation's name (as in `cargo xtask eval <name>`).
    pub name: &'static str,
    /// The units in report order (logs, sequences, sessions …): cheap, measures nothing.
    pub units: fn(&EvalContext) -> Result<Vec<String>>,
    /// Measures one unit; the result is JSON, so shards can be written and merged.
    pub run_unit: fn(&EvalContext, &str) -> Result<Value>,
    /// The report from every unit's result, in the order of `units`.
    pub report: fn(&EvalContext, &UnitResults) -> Result<EvalReport>,
}

/// Reads `value[key]` of a unit result as `T` (an error names the key).
pub fn field<T: serde::de::DeserializeOwned>(value: &Value, key: &str) -> Result<T> {
    serde_json::from_value(value[key].clone()).with_context(|| format!("reading {key:?}"))
}

/// `value[key]` of a unit result as a number; NaN where JSON holds none (`null`: a
/// non-finite figure written with `json!`).
pub fn number(value: &Value, key: &str) -> f64 {
    value[key].as_f64().unwrap_or(f64::NAN)
}

/// Shard `index` (1-based) of `count`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Shard {
    /// 1 ..= count.
    pub index: usize,
    /// Number of shards, at least 1.
    pub count: usize,
}

impl std::str::FromStr for Shard {
    type Err = String;

    fn from_str(text: &str) -> std::result::Result<Self, String> {
        let bad = || format!("{text:?}: expected i/n with 1 ≤ i ≤ n (e.g. 1/4)");
        let (i, n) = text.split_once('/').ok_or_else(bad)?;
        let (index, count) = (
            i.trim().parse::<usize>().map_err(|_| bad())?,
            n.trim().parse::<usize>().map_err(|_| bad())?,
        );
        if index == 0 || index > count {
            return Err(bad());
        }
        Ok(Self { index, count })
    }
}

impl Shard {
    /// Whether unit `k` (0-based, in report order) belongs to this shard.
    pub fn owns(&self, k: usize) -> bool {
        k % self.count + 1 == self.index
    }
}

/// An unsharded run: every unit, then the report.
pub fn run_all(staged: &Staged, ctx: &EvalContext) -> Result<EvalReport> {
    let units = (staged.units)(ctx)?;
    let bar = ctx.progress(units.len() as u64, staged.name);
    let mut results = Vec::with_capacity(units.len());
    for unit in units {
        bar.set_message(unit.clone());
        let result = (staged.run_unit)(ctx, &unit).with_context(|| format!("unit {unit}"))?;
        results.push((unit, result));
        bar.inc(1);
    }
    bar.finish_and_clear();
    (staged.report)(ctx, &results)
}

/// The directory of `name`'s shard files.
pub fn shard_dir(ctx: &EvalContext, name: &str) -> PathBuf {
    ctx.out_dir.join("target/eval/shards").join(name)
}

/// Runs the units of one shard and writes `<i>-of-<n>.json`; returns its path.
pub fn run_shard(staged: &Staged, ctx: &EvalContext, shard: Shard) -> Result<PathBuf> {
    let started = Instant::now();
    let units = (staged.units)(ctx)?;
    let mut results = Vec::new();
    for (k, unit) in units.iter().enumerate().filter(|(k, _)| shard.owns(*k)) {
        eprintln!("shard {}/{}: unit {k} {unit}", shard.index, shard.count);
        let result = (staged.run_unit)(ctx, unit).with_context(|| format!("unit {unit}"))?;
        results.push(json!({ "unit": unit, "index": k, "result": result }));
    }
    let document = json!({
        "name": staged.name,
        "quick": ctx.quick,
        "data_dir": ctx.data_dir.display().to_string(),
        "shard": [shard.index, shard.count],
        "units": units,
        "seconds": started.elapsed().as_secs_f64(),
        "results": results,
    });
    let dir = shard_dir(ctx, staged.name);
    std::fs::create_dir_all(&dir).with_context(|| format!("creating {}", dir.display()))?;
    let path = dir.join(format!("{}-of-{}.json", shard.index, shard.count));
    std::fs::write(&path, serde_json::to_string_pretty(&document)?)
        .with_context(|| format!("writing {}", path.display()))?;
    Ok(path)
}

/// Reads the shard files in `dir` and joins them: the unit results in report order and the
/// shards' summed run time. Errors name the file and what does not fit (another `n`, another
/// `--quick` or data directory, a unit missing or in two shards).
pub fn merge(
    staged: &Staged,
    ctx: &EvalContext,
    dir: &Path,
) -> Result<(Vec<(String, Value)>, f64)> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
        .with_context(|| format!("reading {} (run the shards first)", dir.display()))?
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|e| e == "json"))
        .collect();
    files.sort();
    ensure!(!files.is_empty(), "{}: no shard files", dir.display());
    let units = (staged.units)(ctx)?;
    let mut slots: Vec<Option<Value>> = vec![None; units.len()];
    let mut count = None;
    let mut seconds = 0.0;
    for path in &files {
        let text =
            std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
        let doc: Value = serde_json::from_str(&text)
            .with_context(|| format!("{}: not a shard file", path.display()))?;
        let place = path.display();
        ensure!(
            doc["name"] == staged.name,
            "{place}: a shard of {}",
            doc["name"]
        );
        ensure!(
            doc["quick"] == ctx.quick,
            "{place}: --quick differs from this run"
        );
        ensure!(
            doc["data_dir"] == ctx.data_dir.display().to_string(),
            "{place}: data directory {} differs from {}",
            doc["data_dir"],
            ctx.data_dir.display()
        );
        ensure!(
            doc["units"] == json!(units),
            "{place}: the unit list differs from this run's"
        );
        let n = doc["shard"][1].as_u64();
        if *count.get_or_insert(n) != n {
            bail!("{place}: shards of different counts in {}", dir.display());
        }
        seconds += doc["seconds"].as_f64().unwrap_or(0.0);
        for entry in doc["results"].as_array().into_iter().flatten() {
            let k = entry["index"].as_u64().map_or(usize::MAX, |k| k as usize);
            let slot = slots
                .get_mut(k)
                .with_context(|| format!("{place}: unit index {k} out of range"))?;
            ensure!(slot.is_none(), "{place}: unit {} in two shards", units[k]);
            *slot = Some(entry["result"].clone());
        }
    }
    let mut results = Vec::with_capacity(units.len());
    for (unit, slot) in units.into_iter().zip(slots) {
        let result =
            slot.with_context(|| format!("unit {unit}: in no shard of {}", dir.display()))?;
        results.push((unit, result));
    }
    Ok((results, seconds))
}

/// The unit results decoded as `T`, in report order; an error names the unit that does not
/// decode.
pub fn decode<T: serde::de::DeserializeOwned>(results: &UnitResults) -> Result<Vec<T>> {
    results
        .iter()
        .map(|(unit, value)| {
            serde_json::from_value(value.clone()).with_context(|| format!("result of {unit}"))
        })
        .collect()
}

/// Serde for `f64` fields that may be NaN or infinite, `#[serde(with = "stages::float")]`:
/// JSON has no such numbers (serde_json writes `null`, which does not read back as an `f64`),
/// so they are written as the strings `"NaN"`, `"inf"` and `"-inf"`. Finite values stay
/// numbers and round-trip exactly.
pub mod float {
    use serde::de::Error as _;
    use serde::{Deserialize, Deserializer, Serializer};

    /// Writes a finite value as a number, NaN and ±∞ as strings.
    pub fn serialize<S: Serializer>(value: &f64, serializer: S) -> Result<S::Ok, S::Error> {
        match *value {
            v if v.is_finite() => serializer.serialize_f64(v),
            v if v.is_nan() => serializer.serialize_str("NaN"),
            v if v > 0.0 => serializer.serialize_str("inf"),
            _ => serializer.serialize_str("-inf"),
        }
    }

    #[derive(Deserialize)]
    #[serde(untagged)]
    enum Written {
        Number(f64),
        Text(String),
    }

    /// Reads what [`serialize`] wrote.
    pub fn deserialize<'de, D: Deserializer<'de>>(deserializer: D) -> Result<f64, D::Error> {
        match Written::deserialize(deserializer)? {
            Written::Number(v) => Ok(v),
            Written::Text(text) => match text.as_str() {
                "NaN" => Ok(f64::NAN),
                "inf" => Ok(f64::INFINITY),
                "-inf" => Ok(f64::NEG_INFINITY),
                _ => Err(D::Error::custom(format!("{text:?} is not a number"))),
            },
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ctx(root: &Path) -> EvalContext {
        EvalContext::scratch(root)
    }

    fn units(_: &EvalContext) -> Result<Vec<String>> {
        Ok((0..5).map(|k| format!("u{k}")).collect())
    }

    fn run_unit(_: &EvalContext, unit: &str) -> Result<Value> {
        // Floats whose shortest decimal form needs all 17 digits: they survive the shard
        // files only with serde_json's exact float parsing (`float_roundtrip`).
        let k = unit[1..].parse::<u64>()?;
        Ok(json!({ "len": unit.len(), "square": k.pow(2), "third": (k as f64 + 0.1) / 3.0 }))
    }

    fn report(_: &EvalContext, results: &[(String, Value)]) -> Result<EvalReport> {
        let lines: Vec<String> = results.iter().map(|(u, r)| format!("{u}: {r}")).collect();
        Ok(EvalReport {
            name: "toy",
            title: "toy".into(),
            markdown: lines.join("\n"),
            json: json!(results.iter().map(|(_, r)| r.clone()).collect::<Vec<_>>()),
            headline: None,
        })
    }

    const TOY: Staged = Staged {
        name: "toy",
        units,
        run_unit,
        report,
    };

    #[test]
    fn shards_split_every_unit_once() {
        for n in 1..5 {
            for k in 0..20 {
                let owners = (1..=n).filter(|&i| Shard { index: i, count: n }.owns(k));
                assert_eq!(owners.count(), 1);
            }
        }
        assert_eq!("2/3".parse::<Shard>(), Ok(Shard { index: 2, count: 3 }));
        for bad in ["0/2", "3/2", "1", "a/b", "1/0"] {
            assert!(bad.parse::<Shard>().is_err(), "{bad}");
        }
    }

    #[test]
    fn merged_shards_give_the_unsharded_report() {
        let dir = tempfile::tempdir().unwrap();
        let ctx = ctx(dir.path());
        let whole = run_all(&TOY, &ctx).unwrap();
        for n in [1, 2, 3, 7] {
            let shards = shard_dir(&ctx, "toy");
            let _ = std::fs::remove_dir_all(&shards);
            for i in 1..=n {
                run_shard(&TOY, &ctx, Shard { index: i, count: n }).unwrap();
            }
            let (results, _) = merge(&TOY, &ctx, &shards).unwrap();
            let merged = report(&ctx, &results).unwrap();
            assert_eq!(merged.markdown, whole.markdown, "{n} shards");
            assert_eq!(merged.json, whole.json, "{n} shards");
        }
    }

    #[test]
    fn merge_refuses_missing_doubled_and_foreign_shards() {
        let dir = tempfile::tempdir().unwrap();
        let ctx = ctx(dir.path());
        let shards = shard_dir(&ctx, "toy");
        run_shard(&TOY, &ctx, Shard { index: 1, count: 2 }).unwrap();
        let missing = merge(&TOY, &ctx, &shards).unwrap_err();
        assert!(
            format!("{missing:#}").contains("in no shard"),
            "{missing:#}"
        );
        run_shard(&TOY, &ctx, Shard { index: 1, count: 3 }).unwrap();
        let mixed = merge(&TOY, &ctx, &shards).unwrap_err();
        assert!(
            format!("{mixed:#}").contains("different counts"),
            "{mixed:#}"
        );
        std::fs::remove_dir_all(&shards).unwrap();
        run_shard(&TOY, &ctx, Shard { index: 1, count: 1 }).unwrap();
        let other = EvalContext {
            quick: false,
            ..self::ctx(dir.path())
        };
        let quick = merge(&TOY, &other, &shards).unwrap_err();
        assert!(format!("{quick:#}").contains("--quick"), "{quick:#}");
    }

    #[test]
    fn non_finite_floats_survive_a_shard_file() {
        #[derive(Debug, serde::Serialize, serde::Deserialize)]
        struct Row {
            #[serde(with = "super::float")]
            x: f64,
        }
        for x in [
            f64::NAN,
            f64::INFINITY,
            f64::NEG_INFINITY,
            -0.0,
            0.1 + 0.2,
            1e300,
        ] {
            let text = serde_json::to_string(&Row { x }).unwrap();
            let back: Row = serde_json::from_str(&text).unwrap();
            let value: Row =
                serde_json::from_value(serde_json::to_value(Row { x }).unwrap()).unwrap();
            for y in [back.x, value.x] {
                assert!(
                    y.to_bits() == x.to_bits() || (x.is_nan() && y.is_nan()),
                    "{x} {text}"
                );
            }
        }
        assert!(serde_json::from_str::<Row>(r#"{"x": "many"}"#).is_err());
        let results = vec![("a".to_owned(), json!({"x": "inf"}))];
        let rows: Vec<Row> = decode(&results).unwrap();
        assert_eq!(rows[0].x, f64::INFINITY);
        let bad = vec![("b".to_owned(), json!({"y": 1}))];
        let error = decode::<Row>(&bad).unwrap_err();
        assert!(format!("{error:#}").contains("result of b"), "{error:#}");
    }
}
