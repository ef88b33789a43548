//! raypath's evaluations: every measurement behind the results pages in `docs/results/`.
//!
//! Each evaluation reads real data (`RAYPATH_DATA`) or generated stand-ins, runs the library
//! crates the way a user would, and compares what it measures with the thesis' tables and the
//! peers run beside ours. The crate is run through the developer tool:
//!
//! ```text
//! cargo xtask eval list                    the evaluations (the registry, in the order `all` runs them)
//! cargo xtask eval <name>|all [--quick]    run, print the tables, write the page and the JSON
//! cargo xtask eval <name> --shard i/n      run every n-th unit into target/eval/shards/<name>/
//! cargo xtask eval merge <name>            the report from the shards, as a single run writes it
//! cargo xtask datasets [generate]          what RAYPATH_DATA holds; write the simulated sets
//! cargo xtask readme                       rewrite the README's headline table from the pages
//! ```
//!
//! # How an evaluation is built
//!
//! The registry (the `eval` module, one table: name, one-line description, how it runs) lists
//! every evaluation. An evaluation is either one function `run(&EvalContext) ->
//! Result<EvalReport>` or, for the long ones, written in stages (`eval::stages`): units (a log,
//! a sequence, a session) measured one at a time, then one report function over their JSON
//! results — so `--shard i/n` can run the units on several machines and `merge` writes the same
//! report. [`EvalContext`] says where the data and the outputs are and whether the run is
//! quick (smaller workloads, seconds to minutes; the pages say so) or full.
//!
//! # What a run writes
//!
//! An [`EvalReport`] is a title, a markdown body (tables beside the thesis figures, notes on what
//! is real and what is simulated), machine-readable results and an optional one-line headline.
//! The runner prints the page and writes, under the workspace root (or `RAYPATH_EVAL_OUT` when
//! set, for tests and cluster runs that must not write into the checkout):
//!
//! * `docs/results/<name>.md`: a header (command, date, machine, data directory, run time), the
//!   headline and the body; figures beside it in `docs/results/<name>/`;
//! * `target/eval/<name>.json`: `name`, `title`, `command`, `quick`, `date_utc`, `machine`,
//!   `data_dir`, `seconds` and the evaluation's own `results`.
//!
//! A full run with a headline also rewrites the README's headline table ([`readme`]).
//!
//! # Printing
//!
//! Unlike the library crates it measures, this crate prints: progress bars and the tables of
//! a run go to the terminal (`check-layers` counts it with the applications for that rule).
//! The `memory` evaluation measures each workload in a process of its own by running the
//! calling program again as `<program> memory-probe <workload> [--quick]`, which the program
//! routes to [`memory_probe`] (`cargo xtask` does).

mod datasets;
mod eval;
mod generate;
pub mod readme;
mod render;
mod stats;
pub mod table;

pub use datasets::run as list_datasets;
pub use eval::memory::probe as memory_probe;
pub use eval::stages::Shard;
pub use eval::{EvalContext, EvalReport, data_dir, merge, names, run, run_shard, workspace_root};
pub use generate::run as generate_datasets;
