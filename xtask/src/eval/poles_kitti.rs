//! `cargo xtask eval poles-kitti`: Pole extraction and localization on semi-synthetic KITTI drives (Table 12.2)
//!
//! Work in progress: lands with its issue.

use anyhow::Result;

use super::{EvalContext, EvalReport};

/// Runs the evaluation.
pub fn run(_ctx: &EvalContext) -> Result<EvalReport> {
    Ok(EvalReport {
        name: "poles-kitti",
        title: "Pole extraction and localization on semi-synthetic KITTI drives (Table 12.2)"
            .into(),
        markdown: "Not implemented yet.\n".into(),
        json: serde_json::json!({ "status": "not implemented" }),
    })
}
