//! Per-cell ray statistics `H_i`, `M_i`, `R_i` and how rays build them.

mod cell;
mod config;
mod dense;
pub(crate) mod insert;
mod parallel;
mod sparse;

pub use cell::CellStats;
pub use config::{MappingConfig, MappingSummary};
pub use dense::{DenseStats, DenseStats2, DenseStats3};
pub use sparse::{BLOCK_EDGE, SparseStats, SparseStats2, SparseStats3};
