//! # raypath-sensor-models
//! (front page written below)

mod dimension;
pub mod edt;
mod error;
pub mod export;
mod models;
mod optical_depth;
mod reading;
mod scan;
pub mod scoring;
mod stats;

pub use dimension::{Crossing, Dimension, Planar, Spatial};
pub use error::SensorModelError;
pub use models::*;
pub use optical_depth::{OpticalDepthConfig, OpticalDepthTable, Tabulated};
pub use reading::{Reading, SensorRange};
pub use scan::{PreparedScan, ScanLikelihood};
pub use stats::{
    BLOCK_EDGE, CellStats, DenseStats, DenseStats2, DenseStats3, MappingConfig, MappingSummary,
    SparseStats, SparseStats2, SparseStats3,
};
