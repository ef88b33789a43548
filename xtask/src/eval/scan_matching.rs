//! `cargo xtask eval scan-matching`: Intensity calibration and Hector-style scan matching (Khan ch. 3)
//!
//! Work in progress: lands with its issue.

use anyhow::Result;

use super::{EvalContext, EvalReport};

/// Runs the evaluation.
pub fn run(_ctx: &EvalContext) -> Result<EvalReport> {
    Ok(EvalReport {
        name: "scan-matching",
        title: "Intensity calibration and Hector-style scan matching (Khan ch. 3)".into(),
        markdown: "Not implemented yet.\n".into(),
        json: serde_json::json!({ "status": "not implemented" }),
    })
}
