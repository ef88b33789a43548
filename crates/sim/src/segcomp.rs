//! A SegComp-like stand-in: **simulated** Perceptron-style 512 × 512 range images of
//! polyhedral table-top scenes with ground-truth plane labels and angles, in place of the
//! Perceptron collection of the USF range segmentation comparison (Hoover et al. 1996, "An
//! experimental comparison of range image segmentation algorithms", IEEE TPAMI 18(7)) on
//! which Schaefer (2020, § 11.5, Table 11.1) evaluates PPE. The real images are not
//! redistributable; these are ours, comparable with them in kind, not in value.
//!
//! ## Scanner
//!
//! The projection is the reader's: every pixel `(row, col)` is cast along its beam
//! [`PerceptronGeometry::beam`] (`sc2cart` of the SegComp distribution, affine in the raw
//! range), and the distance of the hit becomes a raw 12-bit range count with
//! [`PerceptronBeam::range_of_distance`](raypath_io::segcomp::PerceptronBeam::range_of_distance),
//! rounded. The result is a [`RangeImage`] like the files hold, and [`RangeImage::to_cloud`] —
//! the conversion the reader applies to real files — puts the points back on the surfaces
//! (up to the 0.2 mm count). Units follow the reader: its geometry reads the file unit as
//! millimetres, so the whole 12-bit window spans 0.17–1.0 m and the scenes are table-top
//! sized (blocks of 2–24 cm, 0.25–0.95 m from the scanner).
//!
//! ## Scenes
//!
//! A table (plane z = 0) and a backdrop wall behind it, 0.55–0.65 m in front of the scanner;
//! the scanner 0.38–0.44 m above the table, pitched down by 42–50° and turned by up to ±8°,
//! so the table fills the lower part of the image and the wall the upper part, as on the
//! Perceptron images of blocks on a table. On the table stand 4–7 objects (the SynPEB
//! generator's shapes scaled down to blocks, [`crate::synpeb`]): boxes, wedges and 3-, 5-,
//! 6- or 8-sided prisms, each at a random yaw, not overlapping; a box carries a smaller
//! block, wedge or prism with probability 0.4 (stacked blocks).
//!
//! ## Noise: the Perceptron artifacts of § 11.5
//!
//! * **Incidence-dependent range noise**: Gaussian with σ = σ₀ / cos θ (θ the angle between
//!   beam and surface normal, the factor capped at 4), σ₀ = 1.0 mm — "rays that hit an object
//!   face at an obtuse angle are much more strongly affected by noise".
//! * **Mixed pixels** at edges: the beam has a footprint of 2 pixels; next to a change of
//!   surface the reading is the weighted mean of 3 × 3 sub-beams across it, so points near
//!   object edges are "scattered radially" between the surfaces.
//! * **Calibration error**: a systematic range error that pulls the centre column 1.5 mm
//!   towards the scanner and falls off linearly to the image sides, which bends every flat
//!   surface along the centre column — the "kinks due to systematic errors in the lidar
//!   calibration" of the tabletop.
//! * **Quantization** to 12-bit counts of 0.2 mm.
//!
//! The amplitudes are our assumptions (the thesis describes the artifacts, it does not
//! measure them); [`SegcompConfig`] holds them.
//!
//! ## Ground truth
//!
//! Labels follow the geometry, not the noisy readings (as the SegComp labelers did): every
//! planar face has its own label ≥ 10 (renumbered from 10 in raster order of first
//! appearance), faces with fewer than 100 visible pixels get label 1 (too small to label),
//! pixels outside the 12-bit window label 0. The angle pairs list the faces that meet along
//! a visible crease (at least 5 4-neighbour pixel pairs across which the true range is
//! continuous), with the exact angle between their normals (the real `.gt-ang` files hold
//! integer degrees).
//!
//! ## Determinism
//!
//! Image `i` of a split is a function of the seed, the split and `i` only (its own random
//! streams, [`crate::rng::stream`]): same seed, same counts and labels, whatever the number of
//! threads or images generated.

use std::collections::{BTreeMap, HashMap};
use std::f64::consts::PI;

use nalgebra::{Point2, Point3, Rotation2, Unit, Vector2, Vector3};
use rand::Rng;
use rand_distr::StandardNormal;
use rayon::prelude::*;
use raypath_geometry::{PointCloud, Pose3};
use raypath_io::segcomp::{
    AnglePair, GroundTruthAngles, GroundTruthSegmentation, PerceptronGeometry, RangeImage,
    RasterFormat,
};
use serde::Serialize;

use crate::error::{Result, SimError};
use crate::rng::{self, SimRng};
use crate::scene3::{Scene3, SurfaceId};
use crate::synpeb::{Footprint, Kind, Labeler, Shape, floor_pose, random_polygon};

/// Random-stream domains (index: image).
const DOMAIN_SCENE: [u64; 2] = [0x5345_4743_4f4d_0001, 0x5345_4743_4f4d_0002];
/// Random-stream domains of the range noise (index: image · 2¹⁶ + row).
const DOMAIN_NOISE: [u64; 2] = [0x5345_4743_4f4d_0011, 0x5345_4743_4f4d_0012];

/// Largest raw range count (12 bits).
pub const MAX_COUNT: u16 = 4095;
/// Label of visible faces too small to label.
pub const LABEL_TOO_SMALL: u32 = 1;
/// Label of pixels outside the 12-bit range window.
pub const LABEL_NO_DATA: u32 = 0;
/// Ground-truth planes per image of the real Perceptron test set (Table 11.1 caption).
pub const THESIS_PLANES_PER_IMAGE: f64 = 14.6;

/// Gap between objects on the table, metres.
const OBJECT_GAP_M: f64 = 0.01;
/// Placement attempts per object.
const ATTEMPTS: usize = 60;
/// Two faces are adjacent when at least this many 4-neighbour pixel pairs join them along a
/// crease.
const MIN_CREASE_PAIRS: usize = 5;
/// The true range is continuous across a crease: neighbours differ by less than this, metres.
const CREASE_JUMP_M: f64 = 0.004;

/// The training or the test images.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize)]
pub enum Split {
    /// `perc.train.N` (10 real images).
    Train,
    /// `perc.test.N` (30 real images).
    Test,
}

impl Split {
    /// `train` or `test`.
    pub fn name(self) -> &'static str {
        match self {
            Split::Train => "train",
            Split::Test => "test",
        }
    }

    fn index(self) -> usize {
        match self {
            Split::Train => 0,
            Split::Test => 1,
        }
    }
}

/// Parameters of the stand-in. `Default` is the full set (10 training and 30 test images, as
/// the real collection).
#[derive(Clone, Debug, PartialEq)]
pub struct SegcompConfig {
    /// Training images (10).
    pub train_images: usize,
    /// Test images (30).
    pub test_images: usize,
    /// Image rows (512).
    pub rows: usize,
    /// Image columns (512).
    pub cols: usize,
    /// The scanner geometry (the reader's default).
    pub geometry: PerceptronGeometry,
    /// Objects standing on the table, smallest and largest number (fewer when they do not fit).
    pub objects: [usize; 2],
    /// Probability that a box carries a smaller block.
    pub stack_probability: f64,
    /// Factor from the SynPEB furniture to table-top blocks.
    pub object_scale: f64,
    /// Scanner height above the table, metres (range).
    pub sensor_height_m: [f64; 2],
    /// Downward pitch of the scanner, degrees (range).
    pub sensor_pitch_deg: [f64; 2],
    /// Largest turn of the scanner about the vertical, degrees (uniform in ±).
    pub sensor_yaw_deg: f64,
    /// Horizontal distance of the backdrop wall from the scanner, metres (range).
    pub backdrop_distance_m: [f64; 2],
    /// Range noise σ₀ at normal incidence, millimetres.
    pub range_noise_mm: f64,
    /// Cap of the incidence factor 1 / cos θ of the noise.
    pub max_noise_factor: f64,
    /// Beam footprint (diameter) in pixels; 0 turns mixed pixels off.
    pub footprint_px: f64,
    /// Systematic range error at the centre column (towards the scanner), millimetres.
    pub calibration_kink_mm: f64,
    /// Visible faces with fewer pixels are not labelled as planes.
    pub min_region_pixels: usize,
}

impl Default for SegcompConfig {
    fn default() -> Self {
        Self {
            train_images: 10,
            test_images: 30,
            rows: 512,
            cols: 512,
            geometry: PerceptronGeometry::default(),
            objects: [4, 7],
            stack_probability: 0.4,
            object_scale: 0.2,
            sensor_height_m: [0.38, 0.44],
            sensor_pitch_deg: [42.0, 50.0],
            sensor_yaw_deg: 8.0,
            backdrop_distance_m: [0.55, 0.65],
            range_noise_mm: 1.0,
            max_noise_factor: 4.0,
            footprint_px: 2.0,
            calibration_kink_mm: 1.5,
            min_region_pixels: 100,
        }
    }
}

impl SegcompConfig {
    /// The noise-free variant: no range noise, no mixed pixels, no calibration error (only
    /// the quantization remains).
    pub fn noise_free(mut self) -> Self {
        self.range_noise_mm = 0.0;
        self.footprint_px = 0.0;
        self.calibration_kink_mm = 0.0;
        self
    }

    /// Images of `split`.
    pub fn images(&self, split: Split) -> usize {
        match split {
            Split::Train => self.train_images,
            Split::Test => self.test_images,
        }
    }

    /// Checks the parameters.
    pub fn validate(&self) -> Result<()> {
        let invalid =
            |name: &'static str, reason: String| Err(SimError::InvalidParameter { name, reason });
        if !(16..=4096).contains(&self.rows) || !(16..=4096).contains(&self.cols) {
            return invalid(
                "rows/cols",
                format!("{} × {} (each 16–4096)", self.rows, self.cols),
            );
        }
        if self.train_images.max(self.test_images) > 65_535 {
            return invalid("train_images/test_images", "at most 65 535 each".into());
        }
        if self.objects[0] > self.objects[1] || self.objects[1] > 50 {
            return invalid(
                "objects",
                format!("{:?} (0 ≤ min ≤ max ≤ 50)", self.objects),
            );
        }
        let ranges = [
            ("sensor_height_m", self.sensor_height_m, 0.05, 0.9),
            ("sensor_pitch_deg", self.sensor_pitch_deg, 20.0, 80.0),
            ("backdrop_distance_m", self.backdrop_distance_m, 0.2, 0.95),
        ];
        for (name, [lo, hi], min, max) in ranges {
            if !(lo.is_finite() && hi.is_finite() && min <= lo && lo <= hi && hi <= max) {
                return invalid(name, format!("[{lo}, {hi}] (within [{min}, {max}])"));
            }
        }
        let values = [
            ("stack_probability", self.stack_probability, 0.0, 1.0),
            ("object_scale", self.object_scale, 0.01, 1.0),
            ("sensor_yaw_deg", self.sensor_yaw_deg, 0.0, 45.0),
            ("range_noise_mm", self.range_noise_mm, 0.0, 100.0),
            ("max_noise_factor", self.max_noise_factor, 1.0, 100.0),
            ("footprint_px", self.footprint_px, 0.0, 8.0),
            (
                "calibration_kink_mm",
                self.calibration_kink_mm,
                -100.0,
                100.0,
            ),
        ];
        for (name, v, lo, hi) in values {
            if !(v.is_finite() && (lo..=hi).contains(&v)) {
                return invalid(name, format!("{v} is outside [{lo}, {hi}]"));
            }
        }
        Ok(())
    }
}

/// Figures of one generated image.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct ImageStats {
    /// Ground-truth planes (labels ≥ 10).
    pub planes: usize,
    /// Objects in the scene (standing and stacked).
    pub objects: usize,
    /// Visible faces too small to label (label 1).
    pub small_faces: usize,
    /// Pixels read as mixed pixels (sub-beams on more than one surface).
    pub mixed_pixels: usize,
    /// Pixels outside the 12-bit window (label 0).
    pub no_data_pixels: usize,
    /// RMS of the random range noise drawn, millimetres.
    pub noise_rms_mm: f64,
    /// Mean incidence angle on the plane pixels, degrees.
    pub mean_incidence_deg: f64,
    /// Smallest and largest true range of a labelled pixel, metres.
    pub range_m: [f64; 2],
}

/// One simulated image: what the three SegComp files of a scan hold, in memory.
#[derive(Clone, Debug, PartialEq)]
pub struct SegcompImage {
    /// `sim.<split>.<i>` (simulated; the real files are `perc.<split>.<i>`).
    pub name: String,
    /// The range image (raw 12-bit counts, as `perc.*.N` holds).
    pub range: RangeImage,
    /// The ground-truth labels (as `.gt-seg` holds).
    pub labels: GroundTruthSegmentation,
    /// The angles between adjacent ground-truth planes (as `.gt-ang` holds).
    pub angles: GroundTruthAngles,
    /// Figures of the image.
    pub stats: ImageStats,
}

impl SegcompImage {
    /// The organized cloud through the reader's conversion ([`RangeImage::to_cloud`]).
    pub fn cloud(&self, geometry: &PerceptronGeometry) -> PointCloud {
        self.range.to_cloud(geometry)
    }
}

/// What the central beam of a pixel hit.
#[derive(Clone, Copy)]
struct Hit {
    distance_m: f64,
    surface: Option<SurfaceId>,
    cos_incidence: f64,
    normal: Vector3<f64>,
}

/// A beam that hit nothing within the 12-bit window.
fn miss() -> Hit {
    Hit {
        distance_m: f64::NAN,
        surface: None,
        cos_incidence: 1.0,
        normal: Vector3::zeros(),
    }
}

/// A table-top scene and the scanner pose.
struct Setup {
    scene: Scene3,
    world_from_sensor: Pose3,
    objects: usize,
}

/// Generates image `index` of `split` (see the module documentation); deterministic in
/// `seed`, `split` and `index`.
pub fn generate_image(
    config: &SegcompConfig,
    seed: u64,
    split: Split,
    index: usize,
) -> Result<SegcompImage> {
    config.validate()?;
    let setup = build_setup(config, seed, split, index)?;
    let (rows, cols) = (config.rows, config.cols);
    let geometry = &config.geometry;
    let cast = |row: f64, col: f64| -> Hit {
        let beam = geometry.beam_at(row, col, rows, cols);
        let origin = setup.world_from_sensor.transform_point(&beam.origin);
        let direction = Unit::new_normalize(
            setup
                .world_from_sensor
                .transform_vector(&beam.direction.into_inner()),
        );
        let max = beam.distance_m(f64::from(MAX_COUNT) + 1.0);
        match setup.scene.cast(&origin, &direction, max) {
            Some(hit) => Hit {
                distance_m: hit.range_m,
                surface: Some(hit.surface),
                cos_incidence: -hit.normal.dot(&direction),
                normal: hit.normal.into_inner(),
            },
            None => miss(),
        }
    };
    // Central beams.
    let hits: Vec<Hit> = (0..rows)
        .into_par_iter()
        .flat_map_iter(|row| (0..cols).map(move |col| (row, col)))
        .map(|(row, col)| cast(row as f64, col as f64))
        .collect();
    // Readings: mixed pixels, noise, calibration error, quantization.
    let half = (cols as f64 - 1.0) / 2.0;
    let footprint = config.footprint_px;
    let noise_domain = DOMAIN_NOISE[split.index()];
    let per_row: Vec<(Vec<u16>, Vec<bool>, usize, f64)> = (0..rows)
        .into_par_iter()
        .map(|row| {
            let mut rng: SimRng =
                rng::stream(seed, noise_domain, ((index as u64) << 16) + row as u64);
            let mut counts = Vec::with_capacity(cols);
            let mut valid = Vec::with_capacity(cols);
            let (mut mixed, mut noise_sq) = (0usize, 0.0);
            for col in 0..cols {
                let hit = hits[row * cols + col];
                // One draw per pixel, so the stream does not depend on the scene.
                let z: f64 = rng.sample(StandardNormal);
                let beam = geometry.beam(row, col, rows, cols);
                let Some(surface) = hit.surface else {
                    counts.push(MAX_COUNT);
                    valid.push(false);
                    continue;
                };
                let on_edge = footprint > 0.0
                    && neighbours8(row, col, rows, cols)
                        .any(|(r, c)| hits[r * cols + c].surface != Some(surface));
                let mut distance = hit.distance_m;
                if on_edge {
                    let (d, several) = footprint_distance(&cast, row, col, footprint, &beam);
                    distance = d;
                    mixed += usize::from(several);
                }
                let factor = (1.0 / hit.cos_incidence.abs().max(1e-9)).min(config.max_noise_factor);
                let noise = 1e-3 * config.range_noise_mm * factor * z;
                noise_sq += noise * noise;
                let roof = 1.0 - ((col as f64 - half).abs() / half).min(1.0);
                let bias = -1e-3 * config.calibration_kink_mm * roof;
                let count = beam.range_of_distance(distance + noise + bias).round();
                if (0.0..=f64::from(MAX_COUNT)).contains(&count) {
                    counts.push(count as u16);
                    valid.push(true);
                } else {
                    counts.push(count.clamp(0.0, f64::from(MAX_COUNT)) as u16);
                    valid.push(false);
                }
            }
            (counts, valid, mixed, noise_sq)
        })
        .collect();
    let mut range = Vec::with_capacity(rows * cols);
    let mut valid = Vec::with_capacity(rows * cols);
    let (mut mixed_pixels, mut noise_sq) = (0, 0.0);
    for (c, v, m, n) in per_row {
        range.extend(c);
        valid.extend(v);
        mixed_pixels += m;
        noise_sq += n;
    }
    let truth = ground_truth(config, &setup.scene, &hits, &valid)?;
    let returns = valid.iter().filter(|&&v| v).count().max(1);
    let stats = ImageStats {
        planes: truth.planes,
        objects: setup.objects,
        small_faces: truth.small_faces,
        mixed_pixels,
        no_data_pixels: valid.iter().filter(|&&v| !v).count(),
        noise_rms_mm: 1e3 * (noise_sq / returns as f64).sqrt(),
        mean_incidence_deg: truth.mean_incidence_deg,
        range_m: truth.range_m,
    };
    let name = format!("sim.{}.{index}", split.name());
    let header = vec![
        format!("{rows} rows"),
        format!("{cols} columns"),
        format!("{name}: simulated SegComp-like Perceptron range image (raypath-sim), seed {seed}"),
        "not a SegComp image: a stand-in with the Perceptron projection".into(),
        format!(
            "range noise {} mm / cos(incidence), footprint {} px, calibration kink {} mm",
            config.range_noise_mm, config.footprint_px, config.calibration_kink_mm
        ),
        String::new(),
        String::new(),
        String::new(),
        String::new(),
        String::new(),
        String::new(),
    ];
    Ok(SegcompImage {
        name,
        range: RangeImage {
            rows,
            columns: cols,
            header,
            range,
        },
        labels: GroundTruthSegmentation {
            rows,
            columns: cols,
            labels: truth.labels,
            format: RasterFormat::RawWithHeader,
        },
        angles: GroundTruthAngles { pairs: truth.pairs },
        stats,
    })
}

/// Generates the first `count` images of `split` (images one after the other, rows in
/// parallel).
pub fn generate_split(
    config: &SegcompConfig,
    seed: u64,
    split: Split,
    count: usize,
) -> Result<Vec<SegcompImage>> {
    (0..count)
        .map(|i| generate_image(config, seed, split, i))
        .collect()
}

/// The 8-neighbours of a pixel inside the image.
fn neighbours8(
    row: usize,
    col: usize,
    rows: usize,
    cols: usize,
) -> impl Iterator<Item = (usize, usize)> {
    (-1i64..=1)
        .flat_map(|dr| (-1i64..=1).map(move |dc| (dr, dc)))
        .filter(|&(dr, dc)| dr != 0 || dc != 0)
        .filter_map(move |(dr, dc)| {
            let (r, c) = (row as i64 + dr, col as i64 + dc);
            (r >= 0 && c >= 0 && r < rows as i64 && c < cols as i64)
                .then_some((r as usize, c as usize))
        })
}

/// The reading of a beam with a footprint of `footprint` pixels: the weighted mean distance
/// of 3 × 3 sub-beams (weights 1-2-1 per axis) and whether they hit more than one surface.
fn footprint_distance(
    cast: &(impl Fn(f64, f64) -> Hit + Sync),
    row: usize,
    col: usize,
    footprint: f64,
    beam: &raypath_io::segcomp::PerceptronBeam,
) -> (f64, bool) {
    let step = footprint / 3.0;
    let (mut sum, mut weights) = (0.0, 0.0);
    let mut first: Option<Option<SurfaceId>> = None;
    let mut several = false;
    for (dr, wr) in [(-1.0, 1.0), (0.0, 2.0), (1.0, 1.0)] {
        for (dc, wc) in [(-1.0, 1.0), (0.0, 2.0), (1.0, 1.0)] {
            let hit = cast(row as f64 + dr * step, col as f64 + dc * step);
            let d = if hit.distance_m.is_finite() {
                hit.distance_m
            } else {
                beam.distance_m(f64::from(MAX_COUNT))
            };
            match first {
                None => first = Some(hit.surface),
                Some(s) => several |= s != hit.surface,
            }
            sum += wr * wc * d;
            weights += wr * wc;
        }
    }
    (sum / weights, several)
}

/// Labels, angle pairs and figures of the ground truth.
struct Truth {
    labels: Vec<u32>,
    pairs: Vec<AnglePair>,
    planes: usize,
    small_faces: usize,
    mean_incidence_deg: f64,
    range_m: [f64; 2],
}

fn ground_truth(
    config: &SegcompConfig,
    scene: &Scene3,
    hits: &[Hit],
    valid: &[bool],
) -> Result<Truth> {
    let (rows, cols) = (config.rows, config.cols);
    let raw: Vec<Option<u32>> = hits
        .iter()
        .zip(valid)
        .map(|(h, &v)| {
            h.surface
                .filter(|_| v)
                .and_then(|s| scene.surface(s))
                .map(|s| s.label)
        })
        .collect();
    let mut sizes: HashMap<u32, usize> = HashMap::new();
    for label in raw.iter().flatten() {
        *sizes.entry(*label).or_default() += 1;
    }
    // Renumber the faces large enough from 10, in raster order of first appearance.
    let mut renumber: HashMap<u32, u32> = HashMap::new();
    let mut normals: BTreeMap<u32, Vector3<f64>> = BTreeMap::new();
    let mut labels = Vec::with_capacity(raw.len());
    let mut small = std::collections::BTreeSet::new();
    let (mut incidence_sum, mut incidence_n) = (0.0, 0usize);
    let mut range_m = [f64::INFINITY, f64::NEG_INFINITY];
    for (i, label) in raw.iter().enumerate() {
        let out = match label {
            None => LABEL_NO_DATA,
            Some(l) if *l < crate::synpeb::FIRST_PLANE_LABEL => LABEL_TOO_SMALL,
            Some(l) if sizes[l] < config.min_region_pixels => {
                small.insert(*l);
                LABEL_TOO_SMALL
            }
            Some(l) => {
                let next = 10 + renumber.len() as u32;
                let id = *renumber.entry(*l).or_insert(next);
                normals.entry(id).or_insert(hits[i].normal);
                incidence_sum += hits[i].cos_incidence.abs().min(1.0).acos();
                incidence_n += 1;
                range_m[0] = range_m[0].min(hits[i].distance_m);
                range_m[1] = range_m[1].max(hits[i].distance_m);
                id
            }
        };
        labels.push(out);
    }
    // Faces meeting along a crease: 4-neighbours of two planes with a continuous true range.
    let mut creases: BTreeMap<(u32, u32), usize> = BTreeMap::new();
    for row in 0..rows {
        for col in 0..cols {
            let i = row * cols + col;
            for j in [
                (col + 1 < cols).then_some(i + 1),
                (row + 1 < rows).then_some(i + cols),
            ]
            .into_iter()
            .flatten()
            {
                let (a, b) = (labels[i], labels[j]);
                if a >= 10
                    && b >= 10
                    && a != b
                    && (hits[i].distance_m - hits[j].distance_m).abs() < CREASE_JUMP_M
                {
                    *creases.entry((a.min(b), a.max(b))).or_default() += 1;
                }
            }
        }
    }
    let pairs = creases
        .into_iter()
        .filter(|&(_, n)| n >= MIN_CREASE_PAIRS)
        .filter_map(|((a, b), _)| {
            let (na, nb) = (normals.get(&a)?, normals.get(&b)?);
            let cos = (na.dot(nb) / (na.norm() * nb.norm())).clamp(-1.0, 1.0);
            Some(AnglePair {
                label_a: a,
                label_b: b,
                angle_deg: cos.acos().to_degrees(),
            })
        })
        .collect();
    Ok(Truth {
        labels,
        pairs,
        planes: renumber.len(),
        small_faces: small.len(),
        mean_incidence_deg: if incidence_n == 0 {
            f64::NAN
        } else {
            (incidence_sum / incidence_n as f64).to_degrees()
        },
        range_m,
    })
}

/// The scene of image `index` of `split` and the scanner pose.
fn build_setup(config: &SegcompConfig, seed: u64, split: Split, index: usize) -> Result<Setup> {
    let mut rng = rng::stream(seed, DOMAIN_SCENE[split.index()], index as u64);
    let uniform = |rng: &mut SimRng, [lo, hi]: [f64; 2]| {
        if hi > lo {
            rng.random_range(lo..=hi)
        } else {
            lo
        }
    };
    let height = uniform(&mut rng, config.sensor_height_m);
    let pitch = uniform(&mut rng, config.sensor_pitch_deg).to_radians();
    let yaw = config.sensor_yaw_deg.to_radians() * rng.random_range(-1.0..=1.0);
    let backdrop = uniform(&mut rng, config.backdrop_distance_m);
    let world_from_sensor = Pose3::from_xyz_rpy(0.0, 0.0, height, 0.0, pitch, yaw);

    let mut labels = Labeler::new();
    let p = Point3::new;
    // The table (label 10 before renumbering) and the backdrop wall at x = backdrop.
    let table = labels.plane();
    labels.builder.add_polygon(
        &[
            p(-1.0, -2.0, 0.0),
            p(backdrop, -2.0, 0.0),
            p(backdrop, 2.0, 0.0),
            p(-1.0, 2.0, 0.0),
        ],
        table,
    );
    let wall = labels.plane();
    labels.builder.add_polygon(
        &[
            p(backdrop, -2.0, 0.0),
            p(backdrop, -2.0, 1.0),
            p(backdrop, 2.0, 1.0),
            p(backdrop, 2.0, 0.0),
        ],
        wall,
    );

    // Where the table is seen: between the bottom row's and the centre's ground distance and
    // the wall, within the horizontal field of view.
    let half_v = (config.geometry.vertical_fov_deg / 2.0).to_radians();
    let half_h = (config.geometry.horizontal_fov_deg / 2.0).to_radians();
    let near = height / (pitch + 0.8 * half_v).tan();
    let far = backdrop - 0.03;
    let n_objects = rng.random_range(config.objects[0]..=config.objects[1]);
    let mut taken: Vec<Footprint> = Vec::new();
    let mut supports: Vec<(Footprint, f64)> = Vec::new();
    let mut objects = 0;
    for _ in 0..n_objects {
        let shape = random_block(rng.random_range(0.0..1.0), &mut rng, false, config);
        let half = shape.half_footprint();
        for _ in 0..ATTEMPTS {
            let u = rng.random_range(near..far);
            let v = u * (0.85 * half_h).tan() * rng.random_range(-1.0..=1.0);
            let center = Point2::origin() + Rotation2::new(yaw) * Vector2::new(u, v);
            let candidate = Footprint {
                center,
                yaw: rng.random_range(-PI..PI),
                half,
            };
            let reach = candidate.radius_along(&Vector2::x());
            if center.x + reach > backdrop - OBJECT_GAP_M
                || taken.iter().any(|t| t.overlaps(&candidate, OBJECT_GAP_M))
            {
                continue;
            }
            shape.add_to(&mut labels, &floor_pose(&candidate, 0.0))?;
            if let Shape::Cuboid(s) = &shape {
                supports.push((
                    Footprint {
                        half: Vector2::new(s.x, s.y) / 2.0,
                        ..candidate
                    },
                    s.z,
                ));
            }
            taken.push(candidate);
            objects += 1;
            break;
        }
    }
    for (support, top) in supports {
        if !rng.random_bool(config.stack_probability) {
            continue;
        }
        let shape = random_block(rng.random_range(0.0..1.0), &mut rng, true, config);
        let room = support.half - shape.half_footprint();
        if room.x <= 0.0 || room.y <= 0.0 {
            continue;
        }
        let offset = Vector2::new(
            rng.random_range(-room.x..=room.x),
            rng.random_range(-room.y..=room.y),
        );
        let footprint = Footprint {
            center: support.center + Rotation2::new(support.yaw) * offset,
            yaw: support.yaw,
            half: shape.half_footprint(),
        };
        shape.add_to(&mut labels, &floor_pose(&footprint, top))?;
        objects += 1;
    }
    Ok(Setup {
        scene: labels.builder.build()?,
        world_from_sensor,
        objects,
    })
}

/// A block: a box (45 %), a wedge (20 %), a 3-, 5- or 6-sided prism (20 %) or an octagonal
/// prism (15 %) by `pick` ∈ [0, 1), sized like the SynPEB furniture times the scale.
fn random_block(pick: f64, rng: &mut SimRng, small: bool, config: &SegcompConfig) -> Shape {
    let shape = if pick < 0.45 {
        Shape::random(Kind::Cuboid, rng, small)
    } else if pick < 0.65 {
        Shape::random(Kind::Wedge, rng, small)
    } else if pick < 0.85 {
        Shape::random(Kind::Prism, rng, small)
    } else {
        let scale = if small { 0.4 } else { 0.8 };
        let radius = scale * rng.random_range(0.25..0.6);
        let height = scale * rng.random_range(0.2..0.8);
        Shape::Prism {
            base: random_polygon(rng, 8, radius),
            height,
        }
    };
    shape.scaled(config.object_scale)
}

/// Mean and range of the figures over images, for reports.
pub fn summary(images: &[&ImageStats]) -> serde_json::Value {
    let column = |f: fn(&ImageStats) -> f64| -> serde_json::Value {
        let v: Vec<f64> = images.iter().map(|s| f(s)).collect();
        if v.is_empty() {
            return serde_json::Value::Null;
        }
        let mean = v.iter().sum::<f64>() / v.len() as f64;
        let min = v.iter().copied().fold(f64::INFINITY, f64::min);
        let max = v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        serde_json::json!({"mean": mean, "min": min, "max": max})
    };
    serde_json::json!({
        "images": images.len(),
        "planes": column(|s| s.planes as f64),
        "objects": column(|s| s.objects as f64),
        "small_faces": column(|s| s.small_faces as f64),
        "mixed_pixels": column(|s| s.mixed_pixels as f64),
        "no_data_pixels": column(|s| s.no_data_pixels as f64),
        "noise_rms_mm": column(|s| s.noise_rms_mm),
        "mean_incidence_deg": column(|s| s.mean_incidence_deg),
        "range_min_m": column(|s| s.range_m[0]),
        "range_max_m": column(|s| s.range_m[1]),
    })
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    fn small() -> SegcompConfig {
        SegcompConfig {
            train_images: 1,
            test_images: 2,
            ..SegcompConfig::default()
        }
    }

    #[test]
    fn segcomp_same_seed_same_images_and_other_seeds_differ() {
        let config = small();
        let a = generate_image(&config, 7, Split::Test, 1).unwrap();
        let b = generate_image(&config, 7, Split::Test, 1).unwrap();
        assert_eq!(a, b);
        // An image does not depend on how many others are generated.
        let split = generate_split(&config, 7, Split::Test, 2).unwrap();
        assert_eq!(split[1], a);
        let c = generate_image(&config, 8, Split::Test, 1).unwrap();
        assert_ne!(a.range.range, c.range.range);
        let d = generate_image(&config, 7, Split::Train, 1).unwrap();
        assert_ne!(a.range.range, d.range.range);
    }

    #[test]
    fn segcomp_images_look_like_perceptron_images() {
        let config = small();
        for index in 0..2 {
            let image = generate_image(&config, 3, Split::Test, index).unwrap();
            let s = &image.stats;
            assert_eq!((image.range.rows, image.range.columns), (512, 512));
            assert_eq!(image.range.range.len(), 512 * 512);
            assert_eq!(image.labels.labels.len(), 512 * 512);
            assert!(image.range.range.iter().all(|&c| c <= MAX_COUNT));
            // Table, wall and several blocks: a SegComp-like number of planes.
            assert!((6..=30).contains(&s.planes), "{s:?}");
            assert!(s.objects >= 2, "{s:?}");
            // Labels ≥ 10 are numbered densely from 10.
            let mut planes: Vec<u32> = image
                .labels
                .labels
                .iter()
                .copied()
                .filter(|&l| l >= 10)
                .collect();
            planes.sort_unstable();
            planes.dedup();
            assert_eq!(planes, (10..10 + s.planes as u32).collect::<Vec<_>>());
            // Every pixel in the 12-bit window but a few.
            assert!(s.no_data_pixels < 512 * 512 / 200, "{s:?}");
            assert!(s.range_m[0] > 0.17 && s.range_m[1] < 1.0, "{s:?}");
            // Noise about 1–3 mm, mixed pixels along the edges.
            assert!(s.noise_rms_mm > 1.0 && s.noise_rms_mm < 3.0, "{s:?}");
            assert!(s.mixed_pixels > 500, "{s:?}");
            // Adjacent faces: table and wall (90°) at least, all angles in [0, 180].
            assert!(image.angles.pairs.len() >= 3, "{:?}", image.angles);
            assert!(
                image
                    .angles
                    .pairs
                    .iter()
                    .all(|p| (0.0..=180.0).contains(&p.angle_deg) && p.label_a < p.label_b)
            );
        }
    }

    #[test]
    fn segcomp_noise_free_points_lie_on_their_planes() {
        let config = small().noise_free();
        let image = generate_image(&config, 11, Split::Train, 0).unwrap();
        assert_eq!(image.stats.mixed_pixels, 0);
        let cloud = image.cloud(&config.geometry);
        // Per plane: the RMS distance to its least-squares plane stays at the 0.2 mm count.
        let mut by_label: BTreeMap<u32, Vec<Vector3<f64>>> = BTreeMap::new();
        for (p, &l) in cloud.points.iter().zip(&image.labels.labels) {
            if l >= 10 {
                by_label.entry(l).or_default().push(p.coords.cast::<f64>());
            }
        }
        assert_eq!(by_label.len(), image.stats.planes);
        for (label, points) in by_label {
            let n = points.len() as f64;
            let mean = points.iter().sum::<Vector3<f64>>() / n;
            let cov = points
                .iter()
                .map(|p| (p - mean) * (p - mean).transpose())
                .sum::<nalgebra::Matrix3<f64>>()
                / n;
            let smallest = cov.symmetric_eigenvalues().min();
            assert!(
                smallest.max(0.0).sqrt() < 2e-4,
                "label {label}: RMS {:.3} mm over {} points",
                1e3 * smallest.max(0.0).sqrt(),
                points.len()
            );
        }
        // The angles between the table and the wall, and between box faces, are right angles
        // or the slopes of wedges and prisms: in (0, 180).
        assert!(
            image
                .angles
                .pairs
                .iter()
                .any(|p| (p.angle_deg - 90.0).abs() < 1e-6)
        );
    }

    #[test]
    fn segcomp_config_is_checked() {
        assert!(SegcompConfig::default().validate().is_ok());
        let bad = SegcompConfig {
            objects: [5, 2],
            ..SegcompConfig::default()
        };
        assert!(bad.validate().is_err());
        let bad = SegcompConfig {
            range_noise_mm: f64::NAN,
            ..SegcompConfig::default()
        };
        assert!(generate_image(&bad, 1, Split::Train, 0).is_err());
    }
}
