//! # raypath-sim
//!
//! A lidar simulator and generated data sets that stand in for the benchmarks raypath cannot
//! download here (KITTI and NCLT scans, SegComp, the full SynPEB) and extend the real 2-D logs.
//! Every generator writes the **real formats** (CARMEN logs, KITTI and NCLT layouts, PCD), so
//! evaluations read simulated and real data through the same `raypath-io` readers.
//!
//! * **Exact ray casting** with parry2d/parry3d (f64) against scene geometry tagged with
//!   surfaces (ground-truth labels, reflectivity).
//! * **Deterministic by seed**: the same seed writes byte-identical files, whatever the number
//!   of threads ([`rng::stream`] gives every work item its own random stream).
//! * **Parallel** with rayon at the outer level (scans, rows of rays).

pub mod corridor;
mod dataset;
pub mod datasets;
mod error;
pub mod indoor;
pub mod lidar3;
mod out2d;
pub mod polygons;
pub mod rng;
pub mod scene2;
pub mod scene3;
pub mod semi_kitti;
pub mod synpeb;
pub mod urban;

pub use dataset::{GeneratedSet, Progress, no_progress};
pub use error::{Result, SimError};
