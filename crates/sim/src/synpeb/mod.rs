//! SynPEB-style plane-extraction scans (Schaefer 2020, ch. 11; the synthetic plane extraction
//! benchmark of the PPE paper): organized 500 × 500 scans of a room of about 6 × 7 × 3 m
//! filled with polyhedral objects, with a ground-truth plane label per pixel.
//!
//! ## World
//!
//! A room ([`build_room`]) with floor, ceiling and four walls and random objects: cuboids,
//! wedges (ramps), prisms with 3, 5 or 6 sides, stairs, tables (top and four legs), shelves
//! (sides, back panel, boards), wall-mounted cabinets, cuboids and prisms tumbled into a
//! random orientation resting on a vertex, cylinders and spheres, standing free or against a
//! wall, and small objects on tables and cuboids. The kinds are mixed in fixed proportions
//! (so rooms of one seed and another differ in layout, not in make-up), and objects do not
//! overlap (oriented footprints with a 5 cm gap). A few sensor stations per room are kept
//! clear of objects (0.5 m around); each scan is taken from a random station, moved by up to
//! 0.2 m, 0.5–1.5 m above the floor, looking at an object at least 2.5 m away. By default the
//! whole set is sampled in **one** room — the thesis speaks of "the virtual room from which
//! the SynPEB lidar scans are sampled" — from different sensor poses.
//!
//! ## Labels
//!
//! Every planar face of the scene is its own segment with a label ≥ 10 (`10` floor, `11`
//! ceiling, `12`–`15` walls, then the objects' faces in the order they were built). Coplanar
//! faces of *different* objects (two boxes side by side at the same height, a box top flush
//! with a table top) keep separate labels: SynPEB labels planar segments, not infinite planes,
//! and a plane extractor should not merge them across the gap. A face split into several
//! visible pieces by an occluder keeps one label. Curved surfaces are not planes: cylinder
//! sides get label 1, spheres label 2 (their facets are an approximation). Pixels without a
//! return get label 0. Cylinder caps are planes. Per scan, "planes" counts the distinct labels
//! ≥ 10 among the returns, as `synpebstat.m` of the PPE code does.
//!
//! ## Scanner
//!
//! The real sample (`planes/synpeb-sample-100x100.pcd`, a 100 × 100 crop of a SynPEB scan)
//! fixes the layout: its points lie exactly on a spherical grid whose rows have elevations
//! `30° − k · 60°/499` (k = 100 … 199) and whose columns have azimuths `−35° + j · 0.14°`
//! (j = 100 … 199). So a full scan spans 60° of elevation (+30° in row 0 down to −30° in row
//! 499, both included) and 69.86° of azimuth (column 0 at −35°, to the **right**, azimuth
//! growing with the column), looking along the sensor's +x axis; the sample is rows and
//! columns 100–199 of it. The sample's wall normals show a pitched sensor (its up axis is
//! tilted by ≈ 11°), so sensor poses get a random pitch (±15°) and a small roll (±3°).
//!
//! Noise: each beam is cast with Gaussian angular noise σ = 1 mdeg on elevation and azimuth and
//! reported along its nominal direction ([`Lidar3`]); the noise levels add Gaussian radial
//! noise σ ∈ {0, 0.5, 1, 2, 4} cm to the range of the same cast (one ray cast per scan, one
//! independent radial draw per level).
//!
//! ## Files
//!
//! `train/<σ>/pc_NN.pcd` (10 scans) and `test/<σ>/pc_NN.pcd` (30 scans) with `<σ>` the radial
//! noise in cm (`0.0`, `0.5`, `1.0`, `2.0`, `4.0`) and `NN` counting from `01`: organized PCD
//! (`WIDTH 500 HEIGHT 500`), `binary_compressed` like the real set, fields `x y z intensity`
//! in the sensor frame (metres), the label in `intensity`, NaN points for no-returns.

mod objects;
mod room;
mod stats;

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

use rayon::prelude::*;
use raypath_geometry::PointCloud;
use raypath_io::pcd::{self, DataEncoding, ReadOptions, WriteOptions};
use serde_json::json;

pub use objects::{FIRST_PLANE_LABEL, LABEL_CYLINDER, LABEL_SPHERE};
pub(crate) use objects::{Kind, Labeler, Shape, random_polygon};
pub(crate) use room::{Footprint, floor_pose};
pub use room::{SynpebRoom, build_room};
pub use stats::{MIN_PLANE_LABEL, ScanStats, crop, scan_stats};

use crate::dataset::{GeneratedSet, Progress};
use crate::error::{Result, SimError};
use crate::lidar3::Lidar3;

/// Planes per scan reported by the thesis (Table 11.1 caption).
pub const THESIS_PLANES_PER_SCAN: f64 = 42.6;

/// Where the real sample lies in a full scan: first row and column of the 100 × 100 crop.
pub const SAMPLE_CROP_ORIGIN: (usize, usize) = (100, 100);

/// The real sample, relative to the data directory.
pub const REAL_SAMPLE: &str = "planes/synpeb-sample-100x100.pcd";

/// Parameters of the SynPEB-style generator. `Default` is the full set of the thesis.
#[derive(Clone, Debug, PartialEq)]
pub struct SynpebConfig {
    /// Scans in `train/` (10).
    pub train_scans: usize,
    /// Scans in `test/` (30).
    pub test_scans: usize,
    /// Radial noise levels in centimetres, one folder each (`0.0 0.5 1.0 2.0 4.0`).
    pub noise_levels_cm: Vec<f64>,
    /// Rooms; scan `k` is taken in room `k mod rooms` (1: all scans in one room).
    pub rooms: usize,
    /// Objects standing on the floor per room (fewer when they do not fit).
    pub objects_per_room: usize,
    /// Probability that a table or large box carries a small object.
    pub stack_probability: f64,
    /// Nominal interior size (length x, width y, height z), metres.
    pub room_size_m: [f64; 3],
    /// Uniform jitter of each room dimension, ± metres.
    pub room_size_jitter_m: [f64; 3],
    /// Rows of the scanner (500).
    pub rows: usize,
    /// Columns of the scanner (500).
    pub cols: usize,
    /// Elevation of row 0 and of the last row, degrees (+30, −30).
    pub elevation_deg: [f64; 2],
    /// Azimuth of column 0 and of the last column, degrees (−35, +34.86).
    pub azimuth_deg: [f64; 2],
    /// Angular noise σ on elevation and azimuth, millidegrees (1).
    pub angular_noise_mdeg: f64,
    /// Sensor stations per room: spots kept free of objects (0.7 m around) from which the
    /// scans are taken, each scan at a random station moved by up to 0.2 m.
    pub sensor_stations: usize,
    /// Range of sensor heights above the floor, metres.
    pub sensor_height_m: [f64; 2],
    /// Largest sensor pitch, degrees (uniform in ±).
    pub sensor_pitch_max_deg: f64,
    /// Largest sensor roll, degrees (uniform in ±).
    pub sensor_roll_max_deg: f64,
}

impl Default for SynpebConfig {
    fn default() -> Self {
        Self {
            train_scans: 10,
            test_scans: 30,
            noise_levels_cm: vec![0.0, 0.5, 1.0, 2.0, 4.0],
            rooms: 1,
            objects_per_room: 42,
            stack_probability: 0.6,
            room_size_m: [7.0, 6.0, 3.0],
            room_size_jitter_m: [0.3, 0.3, 0.1],
            rows: 500,
            cols: 500,
            elevation_deg: [30.0, -30.0],
            azimuth_deg: [-35.0, -35.0 + 499.0 * 0.14],
            angular_noise_mdeg: 1.0,
            sensor_stations: 4,
            sensor_height_m: [0.5, 1.5],
            sensor_pitch_max_deg: 15.0,
            sensor_roll_max_deg: 3.0,
        }
    }
}

impl SynpebConfig {
    /// The quick set: only the 2.0 cm level (the one the thesis reports), 4 training and 10
    /// test scans.
    pub fn quick() -> Self {
        Self {
            train_scans: 4,
            test_scans: 10,
            noise_levels_cm: vec![2.0],
            ..Self::default()
        }
    }

    /// Checks the parameters.
    pub fn validate(&self) -> Result<()> {
        let invalid =
            |name: &'static str, reason: String| Err(SimError::InvalidParameter { name, reason });
        if self.train_scans + self.test_scans == 0 || self.train_scans.max(self.test_scans) > 99_999
        {
            return invalid(
                "train_scans/test_scans",
                "between 1 and 99 999 scans".into(),
            );
        }
        if self.noise_levels_cm.is_empty()
            || self
                .noise_levels_cm
                .iter()
                .any(|s| !(s.is_finite() && (0.0..=100.0).contains(s)))
        {
            return invalid(
                "noise_levels_cm",
                format!(
                    "{:?} (1 or more values in [0, 100] cm)",
                    self.noise_levels_cm
                ),
            );
        }
        let mut names: Vec<String> = self
            .noise_levels_cm
            .iter()
            .map(|s| level_name(*s))
            .collect();
        names.sort();
        names.dedup();
        if names.len() != self.noise_levels_cm.len() {
            return invalid("noise_levels_cm", "two levels share a folder name".into());
        }
        if self.rooms == 0 || self.rooms > 10_000 || self.objects_per_room > 1000 {
            return invalid(
                "rooms/objects_per_room",
                "1–10 000 rooms of at most 1000 objects".into(),
            );
        }
        if !(1..=100).contains(&self.sensor_stations) {
            return invalid(
                "sensor_stations",
                format!("{} (expected 1–100)", self.sensor_stations),
            );
        }
        if !(0.0..=1.0).contains(&self.stack_probability) {
            return invalid(
                "stack_probability",
                format!("{} is outside [0, 1]", self.stack_probability),
            );
        }
        for i in 0..3 {
            let (n, j) = (self.room_size_m[i], self.room_size_jitter_m[i]);
            if !(n.is_finite() && j.is_finite() && j >= 0.0 && n - j >= 2.0 && n + j <= 100.0) {
                return invalid(
                    "room_size_m",
                    format!("{n} ± {j} m (each dimension within 2–100 m)"),
                );
            }
        }
        let [h0, h1] = self.sensor_height_m;
        if !(h0.is_finite()
            && h1.is_finite()
            && 0.0 < h0
            && h0 <= h1
            && h1 < self.room_size_m[2] - self.room_size_jitter_m[2])
        {
            return invalid(
                "sensor_height_m",
                format!("[{h0}, {h1}] must lie inside the room"),
            );
        }
        for (name, v) in [
            ("sensor_pitch_max_deg", self.sensor_pitch_max_deg),
            ("sensor_roll_max_deg", self.sensor_roll_max_deg),
            ("angular_noise_mdeg", self.angular_noise_mdeg),
        ] {
            if !(v.is_finite() && (0.0..=90.0).contains(&v)) {
                return invalid(name, format!("{v} is outside [0, 90]"));
            }
        }
        scanner(self).map(|_| ())
    }
}

/// The folder name of a noise level: centimetres with one decimal (`2.0`).
fn level_name(sigma_cm: f64) -> String {
    format!("{sigma_cm:.1}")
}

/// The organized scanner of `config` (angular noise only; radial noise is added per level).
pub fn scanner(config: &SynpebConfig) -> Result<Lidar3> {
    let [e0, e1] = config.elevation_deg;
    let [a0, a1] = config.azimuth_deg;
    let mut lidar = Lidar3::organized(
        config.rows,
        config.cols,
        e0.to_radians(),
        e1.to_radians(),
        a0.to_radians(),
        a1.to_radians(),
    )?;
    lidar.name = format!("SynPEB {}×{}", config.rows, config.cols);
    lidar.angular_noise_sigma_rad = (config.angular_noise_mdeg * 1e-3).to_radians();
    lidar.validate()?;
    Ok(lidar)
}

/// One scan to write: split, number within the split, global index.
struct Job {
    split: &'static str,
    number: usize,
    index: u64,
}

/// Generates the set under `out_dir` (see the module documentation); deterministic in `seed`.
pub fn generate(
    config: &SynpebConfig,
    seed: u64,
    out_dir: &Path,
    progress: Progress,
) -> Result<GeneratedSet> {
    config.validate()?;
    let lidar = scanner(config)?;
    let rooms: Vec<SynpebRoom> = (0..config.rooms as u64)
        .map(|r| build_room(config, seed, r))
        .collect::<Result<_>>()?;
    let jobs: Vec<Job> = (0..config.train_scans)
        .map(|n| ("train", n))
        .chain((0..config.test_scans).map(|n| ("test", n)))
        .enumerate()
        .map(|(index, (split, n))| Job {
            split,
            number: n + 1,
            index: index as u64,
        })
        .collect();
    for split in ["train", "test"] {
        for sigma in &config.noise_levels_cm {
            let dir = out_dir.join(split).join(level_name(*sigma));
            std::fs::create_dir_all(&dir).map_err(|source| SimError::File {
                path: dir.clone(),
                source,
            })?;
        }
    }
    let levels = config.noise_levels_cm.len() as u64;
    let total = jobs.len() as u64 * levels;
    let done = AtomicU64::new(0);
    progress(0, total);
    let mut files = Vec::new();
    let mut per_scan = Vec::new();
    let mut crops = Vec::new();
    for job in &jobs {
        let room = rooms
            .get((job.index % rooms.len() as u64) as usize)
            .ok_or_else(|| SimError::InvalidScene {
                reason: "no room".into(),
            })?;
        let pose = room.sensor_pose(config, seed, job.index)?;
        let scan = lidar.scan(&room.scene, &pose, seed, job.index)?;
        per_scan.push(scan_stats(&scan.cloud));
        let (r0, c0) = SAMPLE_CROP_ORIGIN;
        crops.push(scan_stats(&crop(&scan.cloud, r0, c0, 100, 100)));
        let written: Vec<Result<PathBuf>> = config
            .noise_levels_cm
            .par_iter()
            .enumerate()
            .map(|(level, sigma_cm)| {
                let mut cloud = scan.with_range_noise(
                    sigma_cm / 100.0,
                    seed,
                    job.index * levels + level as u64,
                )?;
                labels_to_intensity(&mut cloud);
                let relative = Path::new(job.split)
                    .join(level_name(*sigma_cm))
                    .join(format!("pc_{:02}.pcd", job.number));
                let options = WriteOptions::new(DataEncoding::BinaryCompressed);
                pcd::write_pcd_with(&out_dir.join(&relative), &cloud, &options)?;
                progress(done.fetch_add(1, Ordering::Relaxed) + 1, total);
                Ok(relative)
            })
            .collect();
        for file in written {
            files.push(file?);
        }
    }
    files.sort();
    let stats = set_statistics(config, &rooms, &per_scan, &crops);
    Ok(GeneratedSet {
        name: "synpeb".into(),
        description: "SynPEB-style organized 500×500 room scans with ground-truth plane labels \
                      (PCD, binary_compressed, label in intensity), standing in for the SynPEB \
                      benchmark of Schaefer 2020 ch. 11"
            .into(),
        files,
        stats,
    })
}

/// Moves the label channel into `intensity` (SynPEB stores the segment id there).
fn labels_to_intensity(cloud: &mut PointCloud) {
    if let Some(labels) = cloud.label.take() {
        cloud.intensity = Some(labels.iter().map(|&l| l as f32).collect());
    }
}

/// Statistics of the real sample, when it is installed.
pub fn real_sample_stats() -> Option<Result<ScanStats>> {
    let path = raypath_io::data::find(REAL_SAMPLE)?;
    Some(
        pcd::read_pcd(&path, &ReadOptions::synpeb())
            .map(|read| scan_stats(&read.cloud))
            .map_err(SimError::from),
    )
}

fn set_statistics(
    config: &SynpebConfig,
    rooms: &[SynpebRoom],
    scans: &[ScanStats],
    crops: &[ScanStats],
) -> serde_json::Value {
    let column = |stats: &[ScanStats], f: fn(&ScanStats) -> f64| -> Vec<f64> {
        stats.iter().map(f).collect()
    };
    let aggregate = |stats: &[ScanStats]| {
        let mut medians = column(stats, |s| s.range_median_m);
        medians.sort_by(f64::total_cmp);
        json!({
            "planes_per_scan": stats::summary(&column(stats, |s| s.planes as f64)),
            "planes_per_scan_min_10_pixels": stats::summary(&column(stats, |s| s.planes_min_10_pixels as f64)),
            "plane_pixel_fraction": stats::summary(&column(stats, |s| s.plane_pixel_fraction)),
            "no_return_fraction": stats::summary(&column(stats, |s| s.no_return_fraction)),
            "range_m": {
                "min": stats::summary(&column(stats, |s| s.range_min_m))["min"],
                "median_of_scan_medians": medians.get(medians.len() / 2),
                "max": stats::summary(&column(stats, |s| s.range_max_m))["max"],
            },
        })
    };
    let real = match real_sample_stats() {
        Some(Ok(s)) => json!(s),
        Some(Err(e)) => json!({ "error": e.to_string() }),
        None => json!({ "missing": REAL_SAMPLE }),
    };
    json!({
        "scans": { "train": config.train_scans, "test": config.test_scans },
        "noise_levels_cm": config.noise_levels_cm,
        "angular_noise_mdeg": config.angular_noise_mdeg,
        "width": config.cols,
        "height": config.rows,
        "elevation_deg": config.elevation_deg,
        "azimuth_deg": config.azimuth_deg,
        "rooms": rooms.iter().map(|r| json!({
            "size_m": [r.size_m.x, r.size_m.y, r.size_m.z],
            "objects": r.objects,
            "planar_faces": r.planar_faces,
        })).collect::<Vec<_>>(),
        "planes_per_scan_per_scan": scans.iter().map(|s| s.planes).collect::<Vec<_>>(),
        "full_scans": aggregate(scans),
        "crop_100x100_at_row_col_100": aggregate(crops),
        "thesis_planes_per_scan": THESIS_PLANES_PER_SCAN,
        "real_sample_100x100": real,
    })
}
