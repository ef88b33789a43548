//! # raypath-slam
//!
//! (front page written at the end of issue 16)

pub mod benchmark;
mod config;
pub mod correlative;
mod error;
mod frontend;
pub mod graph;
mod loops;
mod output;
mod pipeline;
mod submap;

pub use config::{LoopSearchConfig, Sigmas, SlamConfig, SubmapConfig};
pub use error::{Result, SlamError};
pub use loops::{LoopClosure, LoopSource, LoopStats};
pub use output::{ScanPose, SlamOutput, SlamStats};
pub use pipeline::Slam;
pub use submap::Submap;
