//! `cargo xtask`: raypath's evaluations and dataset checks.
//!
//! ```text
//! cargo xtask eval <name>|all [--quick]   run evaluations, print tables, write docs/results/
//! cargo xtask eval list                   list the evaluations
//! cargo xtask datasets                    what RAYPATH_DATA holds and what is missing
//! ```

mod datasets;
mod eval;
mod table;

use anyhow::Result;
use clap::{Parser, Subcommand};

#[derive(Parser)]
#[command(name = "cargo xtask", about = "raypath evaluations and dataset checks")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Run an evaluation (or `all`), print its table, write `docs/results/<name>.md` and
    /// `target/eval/<name>.json`.
    Eval {
        /// Evaluation name, `all`, or `list`.
        name: String,
        /// Smaller workloads (seconds instead of minutes); tables say so.
        #[arg(long)]
        quick: bool,
    },
    /// List the data sets found under RAYPATH_DATA and the ones missing, with where to get them.
    Datasets {
        /// Print machine-readable JSON instead of a table.
        #[arg(long)]
        json: bool,
    },
}

fn main() -> Result<()> {
    let cli = Cli::parse();
    match cli.command {
        Command::Eval { name, quick } => eval::run(&name, quick),
        Command::Datasets { json } => datasets::run(json),
    }
}
