//! `cargo xtask eval poles-nclt`: Pole-based localization over simulated NCLT-style sessions (Table 12.1)
//!
//! Work in progress: lands with its issue.

use anyhow::Result;

use super::{EvalContext, EvalReport};

/// Runs the evaluation.
pub fn run(_ctx: &EvalContext) -> Result<EvalReport> {
    Ok(EvalReport {
        name: "poles-nclt",
        title: "Pole-based localization over simulated NCLT-style sessions (Table 12.1)".into(),
        markdown: "Not implemented yet.\n".into(),
        json: serde_json::json!({ "status": "not implemented" }),
    })
}
