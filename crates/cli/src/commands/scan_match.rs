//! `raypath scan-match`: Hector-style multi-resolution scan matching with occupancy, reflectivity or combined residuals.
//!
//! Work in progress: lands with its issue.

use super::Failure;

/// Arguments (placeholder until the subcommand lands).
#[derive(clap::Args)]
pub struct Args {
    /// Inputs.
    pub inputs: Vec<String>,
    /// Print one JSON document on standard output.
    #[arg(long)]
    pub json: bool,
}

/// Runs the subcommand.
pub fn run(args: &Args) -> Result<(), Failure> {
    Err(Failure {
        message: "not implemented yet".into(),
        bad_input: false,
        json: args.json,
    })
}
