//! Helpers shared by the end-to-end tests of the `raypath` program.
#![allow(dead_code, clippy::unwrap_used, clippy::expect_used)] // not every test uses all

use std::process::{Command, Output};

/// Runs the `raypath` binary with `args`.
pub fn raypath(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_raypath"))
        .args(args)
        .output()
        .expect("the raypath binary runs")
}

/// The JSON document a successful run printed (fails the test with its stderr otherwise).
pub fn json_of(out: &Output) -> serde_json::Value {
    assert!(
        out.status.success(),
        "raypath failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("one JSON document")
}
