//! One module per subcommand, plus the shared failure type.

pub mod calibrate_intensity;
pub mod console;
pub mod convert;
pub mod dct_map;
pub mod info;
pub mod localize;
pub mod loop_closure;
pub mod map;
pub mod octree;
pub mod planes;
pub mod poles;
pub mod polylines;
pub mod record;
pub mod register;
pub mod scan_match;
pub mod score_model;
pub mod segcomp_eval;
pub mod shell;
pub mod simulate;
pub mod slam;
pub mod source_args;

use std::process::ExitCode;

/// The command-line spelling of a choice: the name clap accepts and `--help` lists, for
/// messages and JSON output.
pub fn choice_name<T: clap::ValueEnum>(value: &T) -> String {
    value
        .to_possible_value()
        .map(|v| v.get_name().to_owned())
        .unwrap_or_default()
}

/// Prints a command's typed report as one line of JSON (`--json`), its keys sorted (as the
/// JSON of every command is).
pub fn print_json(report: &impl serde::Serialize) -> Result<(), Failure> {
    println!("{}", to_json(report)?);
    Ok(())
}

/// A command's typed report as a JSON value (keys sorted), for commands that add to it
/// (`--record`).
pub fn to_json(report: &impl serde::Serialize) -> Result<serde_json::Value, Failure> {
    serde_json::to_value(report).map_err(Failure::internal)
}

/// The JSON of a failure.
#[derive(serde::Serialize)]
struct ErrorReport<'a> {
    error: &'a str,
}

/// Prints `{"error": message}` (the `--json` answer of a failure).
pub fn print_error_json(message: &str) {
    let doc = ErrorReport { error: message };
    println!("{}", serde_json::to_value(&doc).unwrap_or_default());
}

/// Why a subcommand failed, and how to report it.
pub struct Failure {
    /// The message (for input errors: `file:place: reason`).
    pub message: String,
    /// True for bad input (exit code 2), false for other failures (exit code 1).
    pub bad_input: bool,
}

impl Failure {
    /// A failure caused by the user's input (exit code 2).
    pub fn input(error: impl std::fmt::Display) -> Self {
        Self {
            message: error.to_string(),
            bad_input: true,
        }
    }

    /// Any other failure (exit code 1).
    pub fn internal(error: impl std::fmt::Display) -> Self {
        Self {
            message: error.to_string(),
            bad_input: false,
        }
    }

    /// Prints the failure (on standard error, and under `--json` as `{"error": …}` on
    /// standard output) and returns the exit code. The one error path of every subcommand.
    pub fn report(&self) -> ExitCode {
        eprintln!("error: {}", self.message);
        if console::json() {
            print_error_json(&self.message);
        }
        ExitCode::from(if self.bad_input { 2 } else { 1 })
    }
}
