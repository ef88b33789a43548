//! Files shared by the urban outputs: the pole ground truth (`poles.csv`), SemanticKITTI-style
//! point labels, scan statistics and calendar helpers.

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use raypath_geometry::{PointCloud, Pose3};

use super::kinds::{Pole, PoleKind, label};
use crate::error::{Result, SimError};

/// Header of the pole ground truth: position (m), width = 2 × radius (m), height (m), kind
/// code ([`PoleKind`]) and the pole id (stable across sessions).
pub const POLES_HEADER: &str = "x,y,w,h,kind,id";

/// Writes `poles` as CSV ([`POLES_HEADER`], read by `raypath_io::point_csv`), positions
/// mapped by `out_from_world` (a rigid transform; only x and y are written). Four decimals
/// for lengths, as the real pole maps.
pub fn write_poles_csv(path: &Path, poles: &[Pole], out_from_world: &Pose3) -> Result<()> {
    let mut text = String::with_capacity(40 * (poles.len() + 1));
    text.push_str(POLES_HEADER);
    text.push('\n');
    let mut sorted: Vec<&Pole> = poles.iter().collect();
    sorted.sort_by_key(|p| p.id);
    for p in sorted {
        let q = out_from_world.transform_point(&nalgebra::Point3::new(p.x, p.y, p.base_z));
        let _ = writeln!(
            text,
            "{:.4},{:.4},{:.4},{:.3},{},{}",
            q.x + 0.0,
            q.y + 0.0,
            2.0 * p.radius_m,
            p.height_m,
            p.kind.code(),
            p.id
        );
    }
    write_bytes(path, text.as_bytes())
}

/// Writes `bytes` to `path`.
pub fn write_bytes(path: &Path, bytes: &[u8]) -> Result<()> {
    std::fs::write(path, bytes).map_err(|e| SimError::File {
        path: path.to_path_buf(),
        source: e,
    })
}

/// Creates a directory and its parents.
pub fn create_dir(path: &Path) -> Result<()> {
    std::fs::create_dir_all(path).map_err(|e| SimError::File {
        path: path.to_path_buf(),
        source: e,
    })
}

/// SemanticKITTI `.label` bytes: one little-endian `u32` per valid point of `cloud` (the same
/// points, in the same order, as the velodyne file written from it), class in the lower 16
/// bits and instance in the upper 16.
pub fn encode_labels(cloud: &PointCloud) -> Vec<u8> {
    let labels = cloud.label.as_deref().unwrap_or(&[]);
    let mut bytes = Vec::with_capacity(cloud.len() * 4);
    for (i, p) in cloud.points.iter().enumerate() {
        if p.iter().all(|v| v.is_finite()) {
            bytes.extend_from_slice(&labels.get(i).copied().unwrap_or(0).to_le_bytes());
        }
    }
    bytes
}

/// Running statistics of the scans of a set.
#[derive(Clone, Debug, Default)]
pub struct ScanStats {
    /// Number of scans.
    pub scans: u64,
    /// Rays cast.
    pub rays: u64,
    /// Points written (returns).
    pub points: u64,
    /// Fewest points in a scan.
    pub min_points: Option<u64>,
    /// Most points in a scan.
    pub max_points: u64,
    /// Returns per semantic class.
    pub classes: BTreeMap<u32, u64>,
}

impl ScanStats {
    /// Adds one scan.
    pub fn add(&mut self, cloud: &PointCloud) {
        let labels = cloud.label.as_deref().unwrap_or(&[]);
        let mut n = 0u64;
        for (i, p) in cloud.points.iter().enumerate() {
            if p.iter().all(|v| v.is_finite()) {
                n += 1;
                let class = label::class(labels.get(i).copied().unwrap_or(0));
                *self.classes.entry(class).or_default() += 1;
            }
        }
        self.scans += 1;
        self.rays += cloud.len() as u64;
        self.points += n;
        self.min_points = Some(self.min_points.map_or(n, |m| m.min(n)));
        self.max_points = self.max_points.max(n);
    }

    /// Merges another accumulator.
    pub fn merge(&mut self, other: &ScanStats) {
        self.scans += other.scans;
        self.rays += other.rays;
        self.points += other.points;
        self.min_points = match (self.min_points, other.min_points) {
            (Some(a), Some(b)) => Some(a.min(b)),
            (a, b) => a.or(b),
        };
        self.max_points = self.max_points.max(other.max_points);
        for (k, v) in &other.classes {
            *self.classes.entry(*k).or_default() += v;
        }
    }

    /// As JSON, with class names.
    pub fn to_json(&self) -> serde_json::Value {
        let classes: BTreeMap<String, u64> = self
            .classes
            .iter()
            .map(|(k, v)| (class_name(*k).to_owned(), *v))
            .collect();
        serde_json::json!({
            "scans": self.scans,
            "rays": self.rays,
            "points": self.points,
            "points_per_scan_mean": if self.scans > 0 { self.points as f64 / self.scans as f64 } else { 0.0 },
            "points_per_scan_min": self.min_points.unwrap_or(0),
            "points_per_scan_max": self.max_points,
            "return_fraction": if self.rays > 0 { self.points as f64 / self.rays as f64 } else { 0.0 },
            "points_per_class": classes,
        })
    }
}

/// Name of a semantic class.
pub fn class_name(class: u32) -> &'static str {
    match class {
        label::CAR => "car",
        label::ROAD => "road",
        label::SIDEWALK => "sidewalk",
        label::BUILDING => "building",
        label::FENCE => "fence",
        label::VEGETATION => "vegetation",
        label::TRUNK => "trunk",
        label::TERRAIN => "terrain",
        label::POLE => "pole",
        label::TRAFFIC_SIGN => "traffic_sign",
        label::OTHER_OBJECT => "other_object",
        _ => "unlabeled",
    }
}

/// Poles by kind, as JSON.
pub fn pole_counts_json(poles: &[Pole]) -> serde_json::Value {
    let mut map = serde_json::Map::new();
    for kind in PoleKind::ALL {
        let n = poles.iter().filter(|p| p.kind == kind).count();
        map.insert(kind.name().into(), n.into());
    }
    map.insert("total".into(), poles.len().into());
    serde_json::Value::Object(map)
}

/// Days since 1970-01-01 of a proleptic Gregorian date (Howard Hinnant's `days_from_civil`).
fn days_from_civil(year: i64, month: i64, day: i64) -> i64 {
    let y = if month <= 2 { year - 1 } else { year };
    let era = y.div_euclid(400);
    let yoe = y - era * 400;
    let mp = (month + 9) % 12;
    let doy = (153 * mp + 2) / 5 + day - 1;
    let doe = yoe * 365 + yoe / 4 - yoe / 100 + doy;
    era * 146_097 + doe - 719_468
}

/// Parses `YYYY-MM-DD` into (year, month, day), checking ranges.
pub fn parse_date(date: &str) -> Result<(i64, u32, u32)> {
    let bad = || SimError::InvalidParameter {
        name: "session date",
        reason: format!("{date:?} is not a YYYY-MM-DD date"),
    };
    let mut parts = date.split('-');
    let (Some(y), Some(m), Some(d), None) =
        (parts.next(), parts.next(), parts.next(), parts.next())
    else {
        return Err(bad());
    };
    if y.len() != 4 || m.len() != 2 || d.len() != 2 {
        return Err(bad());
    }
    let y: i64 = y.parse().map_err(|_| bad())?;
    let m: u32 = m.parse().map_err(|_| bad())?;
    let d: u32 = d.parse().map_err(|_| bad())?;
    if !(1970..=2100).contains(&y) || !(1..=12).contains(&m) || !(1..=31).contains(&d) {
        return Err(bad());
    }
    Ok((y, m, d))
}

/// Microseconds since the UNIX epoch at `hour`:00 UTC of a `YYYY-MM-DD` date.
pub fn date_utime(date: &str, hour: u32) -> Result<u64> {
    let (y, m, d) = parse_date(date)?;
    let days = days_from_civil(y, i64::from(m), i64::from(d));
    Ok(((days * 86_400 + i64::from(hour) * 3600) as u64) * 1_000_000)
}

/// Deletes the files ending in `.extension` directly inside `dir` (stale scans of an earlier
/// run into the same directory), if `dir` exists.
pub fn remove_stale(dir: &Path, extension: &str) -> Result<()> {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return Ok(());
    };
    for entry in entries.flatten() {
        let path = entry.path();
        if path.is_file() && path.extension().is_some_and(|e| e == extension) {
            std::fs::remove_file(&path).map_err(|e| SimError::File {
                path: path.clone(),
                source: e,
            })?;
        }
    }
    Ok(())
}

/// Files under `dir`, relative to it, sorted.
pub fn list_files(dir: &Path) -> Result<Vec<PathBuf>> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        let entries = std::fs::read_dir(&d).map_err(|e| SimError::File {
            path: d.clone(),
            source: e,
        })?;
        for entry in entries {
            let path = entry
                .map_err(|e| SimError::File {
                    path: d.clone(),
                    source: e,
                })?
                .path();
            if path.is_dir() {
                stack.push(path);
            } else if let Ok(rel) = path.strip_prefix(dir) {
                out.push(rel.to_path_buf());
            }
        }
    }
    out.sort();
    Ok(out)
}
