//! `raypath score-model`: score every sensor model on a corrected CARMEN log (Table 7.3)
//!
//! (Being written for issue 4.)

use super::Failure;

/// Arguments of `raypath score-model`.
#[derive(clap::Args)]
pub struct Args {
    /// Print one JSON document on standard output.
    #[arg(long)]
    pub json: bool,
}

/// Runs `raypath score-model`.
pub fn run(args: &Args) -> Result<(), Failure> {
    Err(Failure {
        message: "raypath score-model is not implemented yet".to_owned(),
        bad_input: false,
        json: args.json,
    })
}
