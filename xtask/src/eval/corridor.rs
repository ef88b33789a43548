//! The 1-D corridor simulation of Schaefer ch. 8 (Sec. 8.5.1): belief at the true pose for
//! MLM, FMP with uniform prior and FMP with conjugate prior; a section of `eval mcl`.
//!
//! (Being written for issue 4.)

use anyhow::Result;

use super::EvalContext;

/// The corridor section of the `mcl` report: markdown and JSON.
pub fn section(_ctx: &EvalContext) -> Result<(String, serde_json::Value)> {
    Ok(("Not written yet.\n".to_owned(), serde_json::json!({})))
}
