//! `cargo xtask eval mcl`: Monte-Carlo localization error per sensor model (Schaefer Table 7.2), the ch. 8 corridor, filter speed
//!
//! (Being written for issue 4.)

use anyhow::Result;

use super::{EvalContext, EvalReport};

/// Runs the evaluation.
pub fn run(ctx: &EvalContext) -> Result<EvalReport> {
    let (corridor_markdown, corridor_json) = super::corridor::section(ctx)?;
    Ok(EvalReport {
        name: "mcl",
        title: "Monte-Carlo localization per sensor model".to_owned(),
        markdown: format!("## The ch. 8 corridor\n\n{corridor_markdown}"),
        json: serde_json::json!({ "corridor": corridor_json }),
    })
}
