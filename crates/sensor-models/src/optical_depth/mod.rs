//! Fast 2-D ray likelihoods for localization: cumulative optical-depth tables.

mod table;
mod tabulated;

pub use table::{OpticalDepthConfig, OpticalDepthTable};
pub use tabulated::Tabulated;
