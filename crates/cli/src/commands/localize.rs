//! `raypath localize`: Monte-Carlo localization on a log with a map
//!
//! (Being written for issue 4.)

use super::Failure;

/// Arguments of `raypath localize`.
#[derive(clap::Args)]
pub struct Args {
    /// Print one JSON document on standard output.
    #[arg(long)]
    pub json: bool,
}

/// Runs `raypath localize`.
pub fn run(args: &Args) -> Result<(), Failure> {
    Err(Failure {
        message: "raypath localize is not implemented yet".to_owned(),
        bad_input: false,
        json: args.json,
    })
}
