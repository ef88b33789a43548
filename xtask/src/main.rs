//! `cargo xtask`: the developer tool. The command line of raypath's evaluations, data-set
//! checks and README table (all in `raypath-eval`, crates/eval), the fuzz run of the file
//! readers ([`fuzz`]) and the layer check ([`layers`]).
//!
//! ```text
//! cargo xtask eval <name>|all [--quick]   run evaluations, print tables, write docs/results/
//! cargo xtask eval list                   list the evaluations
//! cargo xtask eval <name> --shard i/n      run every n-th unit, write target/eval/shards/
//! cargo xtask eval merge <name>            the report from the shards
//! cargo xtask datasets                    what RAYPATH_DATA holds and what is missing
//! cargo xtask datasets generate [--quick] [--only NAME] [--seed S]
//!                                         write the simulated sets under datasets/generated/
//! cargo xtask fuzz [--cases N] [--reader NAME] [--seed S] [--case K] [--list]
//!                                         feed every raypath-io reader N mutated inputs
//!                                         (default 100000); fail on a panic, hang or an
//!                                         error that does not name the file and place
//! cargo xtask check-layers                no crate depends on a higher layer than its own
//!                                         (layers from docs/architecture.md)
//! cargo xtask readme                      rewrite README.md's headline table from the
//!                                         results pages
//! ```

mod fuzz;
mod layers;

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
        /// Evaluation name, `all`, `list`, or `merge` (then the evaluation to merge follows).
        name: String,
        /// With `merge`: the evaluation whose shards to join.
        merged: Option<String>,
        /// Smaller workloads (seconds instead of minutes); tables say so.
        #[arg(long)]
        quick: bool,
        /// Run shard i of n (every n-th unit: log, sequence, session …) and write its results
        /// to `target/eval/shards/<name>/`; `eval merge <name>` writes the report. For the
        /// evaluations written in stages (an error names them).
        #[arg(long, value_name = "I/N")]
        shard: Option<raypath_eval::Shard>,
    },
    /// List the data sets found under RAYPATH_DATA and the ones missing, with where to get them;
    /// `datasets generate` writes the simulated sets under datasets/generated/.
    Datasets {
        /// Print machine-readable JSON instead of a table.
        #[arg(long)]
        json: bool,
        #[command(subcommand)]
        action: Option<DatasetsAction>,
    },
    /// Fuzz every file reader of raypath-io: mutated seed inputs (bit flips, interesting
    /// values, truncation, chunk deletion and duplication, insertions), no panic, no hang,
    /// and `Ok` or an error naming the file and place. Prints a table of counts; fails on a
    /// panic, hang or bad error, saving its input to `target/fuzz/<reader>-<case>.bin`.
    Fuzz(fuzz::FuzzOptions),
    /// Check that no crate depends on a crate of a higher layer (layers from the crate table
    /// of docs/architecture.md, dependencies from `cargo metadata`); every crate must be listed.
    CheckLayers,
    /// Rewrite README.md's headline table from the `**Headline.**` lines of the results pages
    /// (what a full evaluation run does for its own page).
    Readme,
    /// One workload of `eval memory` in a process of its own (prints one JSON line).
    #[command(hide = true)]
    MemoryProbe {
        /// `<set>/thesis`, `<set>/equal`, `poles` or `ppe`.
        workload: String,
        /// The quick run's inputs.
        #[arg(long)]
        quick: bool,
    },
}

#[derive(Subcommand)]
enum DatasetsAction {
    /// Generate the simulated data sets (deterministic: same seed, identical files).
    Generate {
        /// The smaller configuration (under 5 minutes on 2 cores) that `eval all --quick` uses.
        #[arg(long)]
        quick: bool,
        /// Generate only this set.
        #[arg(long, value_name = "NAME")]
        only: Option<String>,
        /// Seed (default: the embedded default data's seed).
        #[arg(long)]
        seed: Option<u64>,
    },
}

/// The libraries' `log` records (their warnings) on standard error as `warning: …`: library
/// crates never print themselves.
struct LibraryLog;

static LIBRARY_LOG: LibraryLog = LibraryLog;

impl log::Log for LibraryLog {
    fn enabled(&self, metadata: &log::Metadata<'_>) -> bool {
        metadata.level() <= log::Level::Warn
    }

    fn log(&self, record: &log::Record<'_>) {
        let level = if record.level() == log::Level::Error {
            "error"
        } else {
            "warning"
        };
        eprintln!("{level}: {}", record.args());
    }

    fn flush(&self) {}
}

fn main() -> Result<()> {
    if log::set_logger(&LIBRARY_LOG).is_ok() {
        log::set_max_level(log::LevelFilter::Warn);
    }
    let cli = Cli::parse();
    match cli.command {
        Command::Eval {
            name,
            merged,
            quick,
            shard,
        } => match (name.as_str(), merged, shard) {
            ("merge", Some(target), None) => raypath_eval::merge(&target, quick),
            ("merge", None, _) => anyhow::bail!("eval merge <name>: name the evaluation"),
            (_, None, Some(shard)) => raypath_eval::run_shard(&name, quick, shard),
            (_, None, None) => raypath_eval::run(&name, quick),
            (_, Some(extra), _) => anyhow::bail!("eval {name}: unexpected argument {extra:?}"),
        },
        Command::Datasets { json, action } => match action {
            None => raypath_eval::list_datasets(json),
            Some(DatasetsAction::Generate { quick, only, seed }) => {
                raypath_eval::generate_datasets(quick, only.as_deref(), seed)
            }
        },
        Command::Fuzz(options) => fuzz::run(&options),
        Command::MemoryProbe { workload, quick } => raypath_eval::memory_probe(&workload, quick),
        Command::CheckLayers => {
            layers::run(&std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(".."))
        }
        Command::Readme => raypath_eval::readme::update(
            &std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(".."),
        ),
    }
}
