//! `cargo xtask eval octomap`: Rtree variable-resolution grid beside OctoMap (Khan ch. 2)
//!
//! Work in progress: lands with its issue.

use anyhow::Result;

use super::{EvalContext, EvalReport};

/// Runs the evaluation.
pub fn run(_ctx: &EvalContext) -> Result<EvalReport> {
    Ok(EvalReport {
        name: "octomap",
        title: "Rtree variable-resolution grid beside OctoMap (Khan ch. 2)".into(),
        markdown: "Not implemented yet.\n".into(),
        json: serde_json::json!({ "status": "not implemented" }),
    })
}
