//! The named data sets `cargo xtask datasets generate` writes under `datasets/generated/`.
//!
//! Each entry generates one set in a real format with the seed [`DEFAULT_SEED`]; `quick`
//! selects the smaller configuration that `cargo xtask eval all --quick` uses.

use std::path::Path;

use crate::{
    GeneratedSet, Progress, Result, corridor, indoor, polygons, semi_kitti, synpeb, urban,
};

/// The seed of the embedded default data sets.
pub const DEFAULT_SEED: u64 = 2020;

/// The signature of a set generator: `(quick, seed, out_dir, progress)`.
pub type GenerateFn = fn(bool, u64, &Path, Progress) -> Result<GeneratedSet>;

/// A named generator.
pub struct SetSpec {
    /// Directory name under `datasets/generated/`.
    pub name: &'static str,
    /// What it stands in for, in a few words.
    pub about: &'static str,
    /// Real data the generator builds on (relative to `RAYPATH_DATA`), if any.
    pub requires: Option<&'static str>,
    /// Writes the set (`quick` = the smaller configuration) into the given directory.
    pub generate: GenerateFn,
}

/// Picks the full or the quick configuration.
fn pick<C>(quick: bool, full: fn() -> C, small: fn() -> C) -> C {
    if quick { small() } else { full() }
}

/// All named sets, in generation order.
pub const SETS: &[SetSpec] = &[
    SetSpec {
        name: "polygons",
        about: "random polygons scanned by a 360-ray sensor (Schaefer ch. 10 protocol): CARMEN ROBOTLASER1 log + ground-truth polygons",
        requires: None,
        generate: |quick, seed, out, progress| {
            let config = pick(
                quick,
                polygons::PolygonsConfig::default,
                polygons::PolygonsConfig::quick,
            );
            polygons::generate(&config, seed, out, progress)
        },
    },
    SetSpec {
        name: "indoor",
        about: "2-D indoor worlds: corrected and raw CARMEN logs with odometry drift and intensities",
        requires: None,
        generate: |quick, seed, out, progress| {
            let config = pick(
                quick,
                indoor::IndoorConfig::default,
                indoor::IndoorConfig::quick,
            );
            indoor::generate(&config, seed, out, progress)
        },
    },
    SetSpec {
        name: "corridor",
        about: "the 1-D corridor of Schaefer ch. 8: ground-truth maps, mapping statistics and observations of seeded runs",
        requires: None,
        generate: |quick, seed, out, progress| {
            let config = pick(
                quick,
                corridor::CorridorConfig::default,
                corridor::CorridorConfig::quick,
            );
            corridor::generate(&config, seed, out, progress)
        },
    },
    SetSpec {
        name: "synpeb",
        about: "SynPEB-style rooms: organized 500 × 500 PCD scans with plane labels, train/test per noise level",
        requires: None,
        generate: |quick, seed, out, progress| {
            let config = pick(
                quick,
                synpeb::SynpebConfig::default,
                synpeb::SynpebConfig::quick,
            );
            synpeb::generate(&config, seed, out, progress)
        },
    },
    SetSpec {
        name: "urban-kitti",
        about: "procedural streets scanned by an HDL-64E: KITTI odometry layout with poles",
        requires: None,
        generate: |quick, seed, out, progress| {
            let config = pick(
                quick,
                urban::UrbanKittiConfig::default,
                urban::UrbanKittiConfig::quick,
            );
            urban::generate_kitti(&config, seed, out, progress)
        },
    },
    SetSpec {
        name: "urban-nclt",
        about: "sessions of a changing street world scanned by an HDL-32E: NCLT layout with poles",
        requires: None,
        generate: |quick, seed, out, progress| {
            let config = pick(
                quick,
                urban::UrbanNcltConfig::default,
                urban::UrbanNcltConfig::quick,
            );
            urban::generate_nclt(&config, seed, out, progress)
        },
    },
    SetSpec {
        name: "semi-kitti",
        about: "streets built around the real KITTI 07 trajectory and pole map, HDL-64E scans in KITTI layout",
        requires: Some("kitti-poles/07"),
        generate: |quick, seed, out, progress| {
            let config = pick(
                quick,
                semi_kitti::SemiKittiSetConfig::default,
                semi_kitti::SemiKittiSetConfig::quick,
            );
            semi_kitti::generate(&config, seed, out, progress)
        },
    },
];

/// The set with this name.
pub fn find(name: &str) -> Option<&'static SetSpec> {
    SETS.iter().find(|s| s.name == name)
}
