//! Finding data sets: the `RAYPATH_DATA` directory.
//!
//! raypath's tests, examples and evaluations read data from the directory named by the
//! environment variable `RAYPATH_DATA`. When it is unset, the `datasets/` folder of the
//! raypath workspace is used: the nearest ancestor of the current directory that holds
//! `datasets/manifest.json`, or `datasets/` in the current directory.

use std::path::{Path, PathBuf};

/// The data directory: `RAYPATH_DATA`, else the workspace's `datasets/` folder.
pub fn data_dir() -> PathBuf {
    if let Some(dir) = std::env::var_os("RAYPATH_DATA")
        && !dir.is_empty()
    {
        return PathBuf::from(dir);
    }
    let cwd = std::env::current_dir().unwrap_or_else(|_| PathBuf::from("."));
    cwd.ancestors()
        .map(|dir| dir.join("datasets"))
        .find(|datasets| datasets.join("manifest.json").is_file())
        .unwrap_or_else(|| PathBuf::from("datasets"))
}

/// The path of `relative` under the data directory, when it exists.
pub fn find(relative: impl AsRef<Path>) -> Option<PathBuf> {
    let path = data_dir().join(relative);
    path.exists().then_some(path)
}

/// For tests and examples that need real data: the path of `relative` under the data
/// directory, or `None` after printing a "skipping" message that names the missing path, so a
/// test can `return` early when the data set is not installed. When the environment sets
/// `RAYPATH_REQUIRE_DATA=1` (CI does whenever it has the data), a missing path panics
/// instead, so no real-data test can pass by skipping.
///
/// ```
/// let Some(log) = raypath_io::data::require("carmen/corrected/intel-corrected.log.gz") else {
///     return; // not installed: the message says what is missing
/// };
/// assert!(log.exists());
/// ```
pub fn require(relative: impl AsRef<Path>) -> Option<PathBuf> {
    let found = find(relative.as_ref());
    if found.is_none() && std::env::var("RAYPATH_REQUIRE_DATA").is_ok_and(|v| v == "1") {
        panic!(
            "RAYPATH_REQUIRE_DATA=1 but {} is missing",
            data_dir().join(relative).display()
        );
    }
    if found.is_none() {
        skip(format_args!(
            "{} not found (set RAYPATH_DATA to the data directory)",
            data_dir().join(relative).display()
        ));
    }
    found
}

/// Reports a test (or part of one) that cannot run here: prints `skipping: {reason}` and,
/// when the environment variable `RAYPATH_SKIP_LOG` names a file, appends the reason to it
/// as one line, so a run can count what it skipped (CI prints the count and the reasons).
/// [`require`] and [`require_python`] report through it; tests that need an external
/// program call it directly.
pub fn skip(reason: impl std::fmt::Display) {
    eprintln!("skipping: {reason}");
    if let Some(log) = std::env::var_os("RAYPATH_SKIP_LOG").filter(|v| !v.is_empty()) {
        use std::io::Write;
        let appended = std::fs::OpenOptions::new()
            .create(true)
            .append(true)
            .open(&log)
            .and_then(|mut file| writeln!(file, "{reason}"));
        if let Err(e) = appended {
            eprintln!("warning: cannot append to RAYPATH_SKIP_LOG: {e}");
        }
    }
}

/// For tests that check our files with Python tools: true when `python3` imports every module
/// of `imports` (for example `"rosbags, mcap"`). Otherwise prints a "skipping" message naming
/// the reason and returns false, or, when the environment sets `RAYPATH_REQUIRE_PYTHON=1` (CI
/// does), panics so the missing tool cannot pass unseen.
pub fn require_python(imports: &str) -> bool {
    require_python_in("python3", imports)
}

/// [`require_python`] for another interpreter, for example a virtual environment's
/// `…/bin/python` holding a tool whose pinned dependencies clash with the other tools'.
pub fn require_python_in(python: &str, imports: &str) -> bool {
    let probe = std::process::Command::new(python)
        .args(["-c", &format!("import {imports}")])
        .output();
    let reason = match probe {
        Ok(out) if out.status.success() => return true,
        Ok(out) => format!(
            "{python} cannot import {imports}: {}",
            String::from_utf8_lossy(&out.stderr).trim()
        ),
        Err(e) => format!("{python} not runnable: {e}"),
    };
    if std::env::var("RAYPATH_REQUIRE_PYTHON").is_ok_and(|v| v == "1") {
        panic!("RAYPATH_REQUIRE_PYTHON=1 but {reason}");
    }
    skip(reason);
    false
}
