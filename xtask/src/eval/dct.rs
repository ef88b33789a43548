//! `cargo xtask eval dct`: Continuous DCT decay-rate maps against grid maps (Tables 9.2-9.4)
//!
//! Work in progress: lands with its issue.

use anyhow::Result;

use super::{EvalContext, EvalReport};

/// Runs the evaluation.
pub fn run(_ctx: &EvalContext) -> Result<EvalReport> {
    Ok(EvalReport {
        name: "dct",
        title: "Continuous DCT decay-rate maps against grid maps (Tables 9.2-9.4)".into(),
        markdown: "Not implemented yet.\n".into(),
        json: serde_json::json!({ "status": "not implemented" }),
    })
}
