//! Pole extraction, pole maps and pole-based localization (Schaefer 2020, ch. 12).
//!
//! Docs: see below.

mod beta;
mod drive;
mod error;
mod extract;
mod filters;
mod hitmiss;
mod localize;
mod mapping;
mod params;
mod pipeline;
mod pole;
mod pole_map;
mod score;

pub use beta::{ReflectionPrior, ln_gamma, regularized_incomplete_beta};
pub use drive::{Drive, DriveFormat};
pub use error::{PoleError, Result};
pub use extract::{
    ExtractionStats, extract_poles, local_grid, non_maximum_suppression, occupancy,
    poles_from_counts,
};
pub use hitmiss::HitMissGrid;
pub use localize::{FilterParams, PoleFilter, PoleIndex};
pub use mapping::{Segment, SlidingWindowFilter, merge_poles, overlap_clusters, segments};
pub use params::PoleParams;
pub use pipeline::{
    DetectionQuality, ExtractionTotals, LocalMap, OdometryNoise, Preset, RunResult, SegmentParams,
    detection_quality, local_maps, localize_run, online_poles, reference_map,
};
pub use pole::Pole;
pub use pole_map::{
    POLE_MAP_HEADER, parse_pole_csv, read_pole_csv, write_pole_csv, write_pole_csv_to,
};
pub use score::{ScoreVolume, pole_scores};
