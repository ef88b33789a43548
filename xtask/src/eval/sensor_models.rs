//! `cargo xtask eval sensor-models`: sensor models scored at the true pose and by inverse KL (Schaefer Tables 7.3, 8.2, 8.3)
//!
//! (Being written for issue 4.)

use anyhow::Result;

use super::{EvalContext, EvalReport};

/// Runs the evaluation.
pub fn run(_ctx: &EvalContext) -> Result<EvalReport> {
    Ok(EvalReport {
        name: "sensor-models",
        title: "Sensor models: likelihood at the true pose and inverse KL".to_owned(),
        markdown: "Not written yet.\n".to_owned(),
        json: serde_json::json!({}),
    })
}
