//! The global flags, and what the program says on standard error besides its errors:
//! progress bars, warnings and notes, and with `-v` the time each stage took. `--quiet` silences all of it (errors are
//! still printed); progress bars are drawn only when standard error is a terminal, so logs
//! and pipes stay clean.

use std::sync::atomic::{AtomicBool, AtomicU8, Ordering};
use std::time::Instant;

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressFinish, ProgressStyle};

/// 0 = `--quiet`, 1 = normal, 2 and more = `-v`.
static LEVEL: AtomicU8 = AtomicU8::new(1);
/// The global `--json`.
static JSON: AtomicBool = AtomicBool::new(false);

/// Sets the global flags (once, in `main`) and prints the libraries' warnings: the readers
/// return them as values and emit them through the `log` facade, printed here as
/// `warning: …` (silenced by `--quiet`).
pub fn set(quiet: bool, verbose: u8, json: bool) {
    let level = if quiet { 0 } else { 1 + verbose.min(2) };
    LEVEL.store(level, Ordering::Relaxed);
    JSON.store(json, Ordering::Relaxed);
    if log::set_logger(&LIBRARY_LOG).is_ok() {
        log::set_max_level(log::LevelFilter::Warn);
    }
}

/// The libraries' `log` records on standard error: warnings as [`warn`], errors as `error: …`.
struct LibraryLog;

static LIBRARY_LOG: LibraryLog = LibraryLog;

impl log::Log for LibraryLog {
    fn enabled(&self, metadata: &log::Metadata<'_>) -> bool {
        metadata.level() <= log::Level::Warn
    }

    fn log(&self, record: &log::Record<'_>) {
        match record.level() {
            log::Level::Error => eprintln!("error: {}", record.args()),
            log::Level::Warn => warn(record.args()),
            _ => {}
        }
    }

    fn flush(&self) {}
}

/// Whether `--json` was given: every subcommand then prints one JSON document on standard
/// output, and a failure `{"error": …}`.
pub fn json() -> bool {
    JSON.load(Ordering::Relaxed)
}

fn level() -> u8 {
    LEVEL.load(Ordering::Relaxed)
}

/// A progress bar over `len` steps labelled `what` on standard error; hidden under
/// `--quiet` and when standard error is not a terminal; cleared when dropped (also on an
/// early return with an error).
pub fn progress(len: usize, what: &str) -> ProgressBar {
    let target = if level() == 0 {
        ProgressDrawTarget::hidden()
    } else {
        ProgressDrawTarget::stderr()
    };
    let bar = ProgressBar::with_draw_target(Some(len as u64), target)
        .with_finish(ProgressFinish::AndClear);
    if let Ok(style) =
        ProgressStyle::with_template("{msg} [{bar:30}] {pos}/{len} ({per_sec}, {eta} left)")
    {
        bar.set_style(style.progress_chars("=> "));
    }
    bar.set_message(what.to_owned());
    bar
}

/// `warning: …` on standard error, unless `--quiet`.
pub fn warn(message: impl std::fmt::Display) {
    if level() > 0 {
        eprintln!("warning: {message}");
    }
}

/// `note: …` on standard error, unless `--quiet`.
pub fn note(message: impl std::fmt::Display) {
    if level() > 0 {
        eprintln!("note: {message}");
    }
}

/// With `-v`: `<stage>: <seconds> s` since `started` on standard error.
pub fn stage(stage: &str, started: Instant) {
    if level() >= 2 {
        eprintln!("{stage}: {:.3} s", started.elapsed().as_secs_f64());
    }
}

/// A spinner with the elapsed time for a long stage without a step count (a library call
/// that runs to the end); hidden like [`progress`]. Finish it with `finish_and_clear`.
pub fn spinner(what: &str) -> ProgressBar {
    let bar = progress(0, what);
    if let Ok(style) = ProgressStyle::with_template("{spinner} {msg} ({elapsed})") {
        bar.set_style(style);
    }
    bar.enable_steady_tick(std::time::Duration::from_millis(200));
    bar
}
