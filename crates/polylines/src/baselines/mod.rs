//! The baselines of the thesis' comparison (§10.4), with PLE's interface: VVL, IEF, SAM.

mod split;
mod vvl;

pub use split::{ief, sam};
pub use vvl::vvl;
