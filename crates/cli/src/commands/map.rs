//! `raypath map`: build a sensor-model map from a log or sequence
//!
//! (Being written for issue 4.)

use super::Failure;

/// Arguments of `raypath map`.
#[derive(clap::Args)]
pub struct Args {
    /// Print one JSON document on standard output.
    #[arg(long)]
    pub json: bool,
}

/// Runs `raypath map`.
pub fn run(args: &Args) -> Result<(), Failure> {
    Err(Failure {
        message: "raypath map is not implemented yet".to_owned(),
        bad_input: false,
        json: args.json,
    })
}
