//! `cargo xtask fuzz`: a fuzz-style run of every file reader of `raypath-io` over mutated
//! inputs, for a fixed budget of cases per reader.
//!
//! For each reader ([`targets::all`]) the seed inputs are the small valid files of
//! [`raypath_io::samples`] (the readers' property tests start from the same ones); each case
//! mutates one of them ([`mutate`]: bit flips, interesting bytes and integers, truncation, chunk deletion and duplication, random and
//! token insertions, splices of two seeds) and feeds it to the reader through its in-memory
//! entry point (a file in a scratch directory for the two readers that only open paths). The
//! property: no panic, no hang, and either `Ok` or an error naming the file and a place in it.
//!
//! * A **panic** is caught with `catch_unwind` (a quiet panic hook records its message and
//!   place); panics on threads a reader starts (the rosbag workers) are caught by the hook and
//!   traced back to their case by running the suspect cases again one at a time.
//! * A **hang** is a case running longer than `--timeout-secs`: a watchdog thread reports it
//!   and ends the process.
//! * A **bad error** names another file, line 0, or a line or byte beyond the input (the
//!   line after the last is allowed for an unexpected end of file).
//! * A **crash** (abort, out of memory, stack overflow) cannot be caught in the process:
//!   every reader runs in a child process of its own (`--child-first`, internal), and when
//!   one dies the case range is halved in further children until one case is left. Children
//!   also keep the readers' warnings (printed to stderr, e.g. by the rosbag reader) out of
//!   the output.
//!
//! Every failure prints the reader, the case, the seed and the input, saved to
//! `target/fuzz/<reader>-<case>.bin`; `--reader R --seed S --case N` replays one case with the
//! panic message printed. The run fails (non-zero exit) on any failure.
//!
//! Cases are independent: case `n` of reader `r` draws from a generator seeded with
//! `(seed, r, n)`, so the same seed gives the same inputs on any number of threads. Cases run
//! on all cores (rayon). The default run (10⁵ cases for each of the 28 readers) takes about a
//! minute on 2 cores, half of it the rosbag reader, whose every open starts worker threads:
//! its seeds are three small bags (two messages per topic) and each case uses one of its three
//! entry points.

mod mutate;
mod targets;

use std::any::Any;
use std::cell::{Cell, RefCell};
use std::panic::AssertUnwindSafe;
use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::time::{Duration, Instant};

use anyhow::{Context, Result, bail};
use rayon::prelude::*;

use raypath_eval::table::Table;
use raypath_eval::workspace_root;
use targets::{Input, Target, Verdict};

/// Cases per reader unless `--cases` says otherwise.
pub const DEFAULT_CASES: u64 = 100_000;
/// The seed unless `--seed` says otherwise (fixed, so that one commit gets one verdict).
pub const DEFAULT_SEED: u64 = 20_201_126;
/// Failing inputs saved per reader at most.
const MAX_SAVED: usize = 20;

/// Options of `cargo xtask fuzz`.
#[derive(clap::Args, Debug)]
pub struct FuzzOptions {
    /// Cases per reader.
    #[arg(long, default_value_t = DEFAULT_CASES)]
    pub cases: u64,
    /// Only these readers (comma-separated names; `--list` shows them).
    #[arg(long, value_name = "NAME")]
    pub reader: Option<String>,
    /// Seed of the mutations (the same seed gives the same inputs).
    #[arg(long, default_value_t = DEFAULT_SEED)]
    pub seed: u64,
    /// Replay one case of one reader, printing its panic (if any) as usual.
    #[arg(long, value_name = "K")]
    pub case: Option<u64>,
    /// A case running longer than this many seconds is a hang.
    #[arg(long, default_value_t = 10)]
    pub timeout_secs: u64,
    /// List the readers, their seed counts and entry points.
    #[arg(long)]
    pub list: bool,
    /// Internal: the child process of one reader, from this case on.
    #[arg(long, hide = true)]
    pub child_first: Option<u64>,
}

/// Exit status of a child that found a hang (it has reported it).
const EXIT_HANG: i32 = 3;
/// Exit status of a child whose harness failed (it has printed why).
const EXIT_HARNESS: i32 = 2;
/// The line a child ends its output with: its counts as JSON.
const STATS_PREFIX: &str = "fuzz-stats ";
/// The line a child prints when its harness failed.
const ERROR_PREFIX: &str = "fuzz-error ";

/// The scratch directory of process `pid`: on a RAM disk when there is one (two readers go
/// through files, one a case).
fn scratch_dir(pid: u32) -> PathBuf {
    let shm = Path::new("/dev/shm");
    let base = if shm.is_dir() {
        shm.to_path_buf()
    } else {
        std::env::temp_dir()
    };
    base.join(format!("raypath-fuzz-{pid}"))
}

/// Runs the fuzz targets; an error when any case failed.
pub fn run(options: &FuzzOptions) -> Result<()> {
    let scratch = scratch_dir(std::process::id());
    std::fs::create_dir_all(&scratch).with_context(|| format!("creating {}", scratch.display()))?;
    let result = run_in(options, &scratch);
    let _ = std::fs::remove_dir_all(&scratch);
    if options.child_first.is_some()
        && let Err(e) = &result
    {
        // The parent reads stdout only.
        println!("{ERROR_PREFIX}{e:#}");
        std::process::exit(EXIT_HARNESS);
    }
    result
}

fn run_in(options: &FuzzOptions, scratch: &Path) -> Result<()> {
    let all = targets::all(scratch)?;
    if options.list {
        let mut table = Table::new(["reader", "seeds", "entry points"]);
        for t in &all {
            table.row([
                t.name.to_string(),
                t.seeds.len().to_string(),
                t.reads.to_string(),
            ]);
        }
        print!("{}", table.to_markdown()?);
        return Ok(());
    }
    let selected: Vec<&Target> = match &options.reader {
        None => all.iter().collect(),
        Some(names) => {
            let mut selected = Vec::new();
            for name in names.split(',').map(str::trim) {
                match all.iter().find(|t| t.name == name) {
                    Some(t) => selected.push(t),
                    None => {
                        let names: Vec<&str> = all.iter().map(|t| t.name).collect();
                        bail!("no reader named {name:?}; choose from {}", names.join(", "));
                    }
                }
            }
            selected
        }
    };
    if let Some(case) = options.case {
        let [target] = selected[..] else {
            bail!("--case needs exactly one --reader");
        };
        return replay(target, options.seed, case, scratch);
    }
    if let Some(first) = options.child_first {
        let [target] = selected[..] else {
            bail!("a child process runs exactly one reader");
        };
        return child(target, options, first, scratch);
    }
    parent(&selected, options)
}

/// Runs each reader in a child process (its stderr, where readers print warnings, is not
/// shown), prints the table, fails on any failure.
fn parent(selected: &[&Target], options: &FuzzOptions) -> Result<()> {
    let started = Instant::now();
    let mut table = Table::new([
        "reader",
        "seeds",
        "cases",
        "ok",
        "errors",
        "whole-file",
        "panics",
        "bad errors",
        "seconds",
        "slowest ms",
    ]);
    let mut totals = Stats::default();
    let mut failing = 0u64;
    let mut failed_readers = Vec::new();
    for target in selected {
        let t0 = Instant::now();
        let run = spawn_child(target.name, options, 0, options.cases, false)?;
        for line in &run.lines {
            println!("{line}");
        }
        let stats = match (&run.stats, run.code) {
            (Some(stats), _) => stats.clone(),
            (None, Some(EXIT_HANG)) => Stats {
                hangs: 1,
                seconds: t0.elapsed().as_secs_f64(),
                ..Stats::default()
            },
            (None, Some(EXIT_HARNESS)) => bail!("fuzzing {} failed (see above)", target.name),
            (None, _) => {
                // An abort (out of memory, stack overflow): find the case by bisection.
                println!(
                    "fuzz: the {} child process died ({}); looking for the case",
                    target.name, run.status
                );
                crashed(target, options)?;
                Stats {
                    crashes: 1,
                    seconds: t0.elapsed().as_secs_f64(),
                    ..Stats::default()
                }
            }
        };
        eprintln!(
            "fuzz: {:<16} {} cases in {:.1} s: {} ok, {} errors, {} panics, {} bad errors{}",
            target.name,
            stats.cases,
            stats.seconds,
            stats.ok,
            stats.errors,
            stats.panics,
            stats.bad,
            match (stats.hangs, stats.crashes) {
                (0, 0) => "",
                (_, 0) => ", HANG",
                _ => ", CRASH",
            }
        );
        let failures = stats.failures();
        if failures > 0 {
            failed_readers.push(target.name);
        }
        failing += failures;
        table.row(stats.cells(target.name, target.seeds.len()));
        totals.add(&stats);
    }
    totals.seconds = started.elapsed().as_secs_f64();
    table.row(totals.cells("total", selected.iter().map(|t| t.seeds.len()).sum()));
    println!(
        "\ncargo xtask fuzz: {} readers, {} cases each, seed {}, {} threads",
        selected.len(),
        options.cases,
        options.seed,
        rayon::current_num_threads()
    );
    print!("{}", table.to_markdown()?);
    if failing == 0 {
        println!(
            "no panics, hangs or bad errors in {} cases ({:.1} s)",
            totals.cases, totals.seconds
        );
        return Ok(());
    }
    bail!(
        "{failing} failing cases in {} (panics, hangs, crashes or bad errors); inputs under \
         target/fuzz/",
        failed_readers.join(", ")
    )
}

/// What a child process came to.
struct ChildRun {
    status: std::process::ExitStatus,
    code: Option<i32>,
    stats: Option<Stats>,
    /// Its output other than the counts.
    lines: Vec<String>,
    stderr: String,
}

/// Runs cases `first..first + cases` of `reader` in a child process.
fn spawn_child(
    reader: &str,
    options: &FuzzOptions,
    first: u64,
    cases: u64,
    keep_stderr: bool,
) -> Result<ChildRun> {
    let exe = std::env::current_exe().context("finding the xtask executable")?;
    let stderr = if keep_stderr {
        std::process::Stdio::piped()
    } else {
        std::process::Stdio::null()
    };
    let child = std::process::Command::new(exe)
        .args(["fuzz", "--reader", reader])
        .args(["--seed", &options.seed.to_string()])
        .args(["--cases", &cases.to_string()])
        .args(["--timeout-secs", &options.timeout_secs.to_string()])
        .args(["--child-first", &first.to_string()])
        .stdin(std::process::Stdio::null())
        .stderr(stderr)
        .stdout(std::process::Stdio::piped())
        .spawn()
        .context("starting a fuzz child process")?;
    let pid = child.id();
    let output = child
        .wait_with_output()
        .context("waiting for a fuzz child process")?;
    // A child that hung or died left its scratch directory behind.
    let _ = std::fs::remove_dir_all(scratch_dir(pid));
    let stdout = String::from_utf8_lossy(&output.stdout);
    let mut stats = None;
    let mut lines = Vec::new();
    for line in stdout.lines() {
        if let Some(json) = line.strip_prefix(STATS_PREFIX) {
            stats = Some(serde_json::from_str(json).context("reading a child's counts")?);
        } else {
            lines.push(line.to_string());
        }
    }
    Ok(ChildRun {
        status: output.status,
        code: output.status.code(),
        stats,
        lines,
        stderr: String::from_utf8_lossy(&output.stderr).into_owned(),
    })
}

/// A child died without reporting: halve the case range until one case kills a child,
/// then report that case.
fn crashed(target: &Target, options: &FuzzOptions) -> Result<()> {
    let (mut first, mut count) = (0u64, options.cases);
    while count > 1 {
        let half = count / 2;
        let run = spawn_child(target.name, options, first, half, false)?;
        if run.stats.is_none() && run.code != Some(EXIT_HANG) {
            count = half;
            continue;
        }
        let run = spawn_child(target.name, options, first + half, count - half, false)?;
        if run.stats.is_none() && run.code != Some(EXIT_HANG) {
            first += half;
            count -= half;
            continue;
        }
        println!(
            "fuzz: no single range of {} cases crashes alone",
            target.name
        );
        return Ok(());
    }
    // Once more to show what the process printed when it died.
    let run = spawn_child(target.name, options, first, 1, true)?;
    let seed_bytes: Vec<Vec<u8>> = target.seeds.iter().map(|s| s.bytes.clone()).collect();
    let mutated = generate(target, &seed_bytes, options.seed, first);
    let saved = save(target.name, first, &mutated.bytes);
    let tail: Vec<&str> = run.stderr.lines().rev().take(5).collect();
    println!(
        "\nFAIL reader {} case {first} (seed {}, from seed input {}): CRASH: the process died \
         ({}): {}\n  input: {} bytes, saved to {saved}\n  replay: cargo xtask fuzz --reader {} \
         --seed {} --case {first}",
        target.name,
        options.seed,
        mutated.seed,
        run.status,
        tail.into_iter().rev().collect::<Vec<_>>().join(" / "),
        mutated.bytes.len(),
        target.name,
        options.seed,
    );
    Ok(())
}

/// The child process of one reader: runs its cases, prints the failures and its counts.
fn child(target: &Target, options: &FuzzOptions, first: u64, scratch: &Path) -> Result<()> {
    install_quiet_hook();
    check_seeds(target, scratch)?;
    let (stats, failures) = fuzz(target, options, first, scratch);
    report(&failures, target, options.seed);
    println!("{STATS_PREFIX}{}", serde_json::to_string(&stats)?);
    Ok(())
}

/// Counts of one reader's run.
#[derive(Clone, Debug, Default, serde::Serialize, serde::Deserialize)]
struct Stats {
    cases: u64,
    ok: u64,
    errors: u64,
    whole_file: u64,
    panics: u64,
    bad: u64,
    hangs: u64,
    crashes: u64,
    seconds: f64,
    slowest_ms: f64,
}

impl Stats {
    fn add(&mut self, other: &Stats) {
        self.cases += other.cases;
        self.ok += other.ok;
        self.errors += other.errors;
        self.whole_file += other.whole_file;
        self.panics += other.panics;
        self.bad += other.bad;
        self.hangs += other.hangs;
        self.crashes += other.crashes;
        self.seconds += other.seconds;
        self.slowest_ms = self.slowest_ms.max(other.slowest_ms);
    }

    fn failures(&self) -> u64 {
        self.panics + self.bad + self.hangs + self.crashes
    }

    fn count(&mut self, outcome: &Outcome, elapsed: Duration) {
        self.cases += 1;
        self.slowest_ms = self.slowest_ms.max(elapsed.as_secs_f64() * 1e3);
        match outcome {
            Outcome::Verdict(Verdict::Ok) => self.ok += 1,
            Outcome::Verdict(Verdict::Err { whole_file, .. }) => {
                self.errors += 1;
                self.whole_file += u64::from(*whole_file);
            }
            Outcome::Verdict(Verdict::Bad(_)) => self.bad += 1,
            Outcome::Panic(_) => self.panics += 1,
        }
    }

    fn cells(&self, name: &str, seeds: usize) -> Vec<String> {
        let panics = match (self.hangs, self.crashes) {
            (0, 0) => self.panics.to_string(),
            (h, 0) => format!("{} + {h} hang", self.panics),
            (0, c) => format!("{} + {c} crash", self.panics),
            (h, c) => format!("{} + {h} hang + {c} crash", self.panics),
        };
        vec![
            name.to_string(),
            seeds.to_string(),
            self.cases.to_string(),
            self.ok.to_string(),
            self.errors.to_string(),
            self.whole_file.to_string(),
            panics,
            self.bad.to_string(),
            format!("{:.1}", self.seconds),
            format!("{:.1}", self.slowest_ms),
        ]
    }
}

/// What a case came to.
#[derive(Clone, Debug)]
enum Outcome {
    Verdict(Verdict),
    Panic(String),
}

impl Outcome {
    fn failed(&self) -> bool {
        matches!(self, Outcome::Panic(_) | Outcome::Verdict(Verdict::Bad(_)))
    }
}

/// A failing case.
struct Failure {
    reader: &'static str,
    case: u64,
    seed_input: usize,
    outcome: Outcome,
    bytes: Vec<u8>,
}

thread_local! {
    /// True while this thread runs a case.
    static IN_CASE: Cell<bool> = const { Cell::new(false) };
    /// The message and place of the last panic of this thread's case.
    static CASE_PANIC: RefCell<Option<String>> = const { RefCell::new(None) };
}

/// Panics outside a case (on threads a reader started), and the last one's message (the
/// case's own when suspect cases run again one at a time).
static STRAY_PANICS: AtomicU64 = AtomicU64::new(0);
static STRAY_MESSAGE: Mutex<Option<String>> = Mutex::new(None);

fn payload_text(payload: &dyn Any) -> String {
    if let Some(s) = payload.downcast_ref::<&str>() {
        (*s).to_string()
    } else if let Some(s) = payload.downcast_ref::<String>() {
        s.clone()
    } else {
        "(non-string panic payload)".to_string()
    }
}

/// A panic hook that records instead of printing: the message and place of a case's panic
/// in the thread's slot, any other panic as a stray one (printed, the first few times).
fn install_quiet_hook() {
    std::panic::set_hook(Box::new(|info| {
        let place = info.location().map_or_else(String::new, |l| {
            format!(" at {}:{}:{}", l.file(), l.line(), l.column())
        });
        let message = format!("{}{place}", payload_text(info.payload()));
        if IN_CASE.with(Cell::get) {
            CASE_PANIC.with(|p| *p.borrow_mut() = Some(message));
        } else {
            let thread = std::thread::current();
            let message = format!("thread {:?}: {message}", thread.name().unwrap_or("?"));
            let n = STRAY_PANICS.fetch_add(1, Ordering::SeqCst);
            if n < 3 {
                eprintln!("fuzz: panic outside a case: {message}");
            }
            if let Ok(mut last) = STRAY_MESSAGE.lock() {
                *last = Some(message);
            }
        }
    }));
}

/// The input of case `case` of `target`.
fn generate(target: &Target, seed_bytes: &[Vec<u8>], seed: u64, case: u64) -> mutate::Mutated {
    let mut rng = mutate::case_rng(seed, target.name, case);
    mutate::mutate(&mut rng, seed_bytes, &target.tokens)
}

/// Feeds `bytes` to the reader, catching panics.
fn execute(
    target: &Target,
    seed: usize,
    bytes: &[u8],
    variant: u64,
    dir: Option<&Path>,
) -> Outcome {
    let input = Input {
        seed,
        name: &target.seeds[seed].name,
        bytes,
        variant,
        dir,
    };
    IN_CASE.with(|c| c.set(true));
    CASE_PANIC.with(|p| p.borrow_mut().take());
    let result = std::panic::catch_unwind(AssertUnwindSafe(|| (target.read)(&input)));
    IN_CASE.with(|c| c.set(false));
    match result {
        Ok(verdict) => Outcome::Verdict(verdict),
        Err(payload) => Outcome::Panic(
            CASE_PANIC
                .with(|p| p.borrow_mut().take())
                .unwrap_or_else(|| payload_text(payload.as_ref())),
        ),
    }
}

/// Runs one input in its own scratch directory when the reader needs a file. A panic on a
/// reader's own thread during the case marks it as suspect (`true`).
fn run_one(
    target: &Target,
    seed: usize,
    bytes: &[u8],
    variant: u64,
    scratch: &Path,
    label: &str,
) -> (Outcome, bool) {
    let dir = target.needs_file.then(|| scratch.join(label));
    if let Some(dir) = &dir
        && let Err(e) = std::fs::create_dir_all(dir)
    {
        return (
            Outcome::Panic(format!(
                "fuzz harness: cannot create {}: {e}",
                dir.display()
            )),
            false,
        );
    }
    let stray = STRAY_PANICS.load(Ordering::SeqCst);
    let outcome = execute(target, seed, bytes, variant, dir.as_deref());
    let suspect = STRAY_PANICS.load(Ordering::SeqCst) != stray;
    if let Some(dir) = &dir {
        let _ = std::fs::remove_dir_all(dir);
    }
    (outcome, suspect)
}

/// The unmutated seeds must read cleanly: a seed that fails is a broken harness.
fn check_seeds(target: &Target, scratch: &Path) -> Result<()> {
    for (k, seed) in target.seeds.iter().enumerate() {
        let label = format!("{}-seed-{k}", target.name);
        let (outcome, suspect) = run_one(target, k, &seed.bytes, 0, scratch, &label);
        if !matches!(outcome, Outcome::Verdict(Verdict::Ok)) || suspect {
            bail!(
                "seed {k} ({}) of reader {} does not read cleanly: {outcome:?}",
                seed.name,
                target.name
            );
        }
    }
    Ok(())
}

/// One slot per worker thread: the case it runs (+1; 0 when idle) and since when.
struct Slot {
    case: AtomicU64,
    since_ms: AtomicU64,
}

/// Runs cases `first..first + options.cases` of `target` on all threads, with a watchdog
/// for hangs.
fn fuzz(
    target: &Target,
    options: &FuzzOptions,
    first: u64,
    scratch: &Path,
) -> (Stats, Vec<Failure>) {
    let seed_bytes: Vec<Vec<u8>> = target.seeds.iter().map(|s| s.bytes.clone()).collect();
    let started = Instant::now();
    let slots: Vec<Slot> = (0..=rayon::current_num_threads())
        .map(|_| Slot {
            case: AtomicU64::new(0),
            since_ms: AtomicU64::new(0),
        })
        .collect();
    let done = AtomicBool::new(false);
    let failures = Mutex::new(Vec::new());
    let suspects = Mutex::new(Vec::new());
    let timeout_ms = options.timeout_secs.max(1) * 1000;
    let mut stats = std::thread::scope(|scope| {
        scope.spawn(|| {
            while !done.load(Ordering::SeqCst) {
                std::thread::sleep(Duration::from_millis(100));
                let now = started.elapsed().as_millis() as u64;
                for slot in &slots {
                    let case = slot.case.load(Ordering::SeqCst);
                    if case != 0
                        && now.saturating_sub(slot.since_ms.load(Ordering::SeqCst)) > timeout_ms
                    {
                        hang(target, &seed_bytes, options, case - 1);
                    }
                }
            }
        });
        let stats = (0..usize::try_from(options.cases).unwrap_or(usize::MAX))
            .into_par_iter()
            .with_min_len(64)
            .fold(Stats::default, |mut stats, case| {
                let case = first + case as u64;
                let mutated = generate(target, &seed_bytes, options.seed, case);
                let slot = &slots[rayon::current_thread_index().unwrap_or(slots.len() - 1)];
                slot.since_ms
                    .store(started.elapsed().as_millis() as u64, Ordering::SeqCst);
                slot.case.store(case + 1, Ordering::SeqCst);
                let t0 = Instant::now();
                let (outcome, suspect) = run_one(
                    target,
                    mutated.seed,
                    &mutated.bytes,
                    mutated.variant,
                    scratch,
                    &format!("{}-{case}", target.name),
                );
                let elapsed = t0.elapsed();
                slot.case.store(0, Ordering::SeqCst);
                if suspect && let Ok(mut s) = suspects.lock() {
                    s.push(case);
                }
                if outcome.failed()
                    && let Ok(mut f) = failures.lock()
                {
                    f.push(Failure {
                        reader: target.name,
                        case,
                        seed_input: mutated.seed,
                        outcome: outcome.clone(),
                        bytes: mutated.bytes,
                    });
                }
                stats.count(&outcome, elapsed);
                stats
            })
            .reduce(Stats::default, |mut a, b| {
                a.add(&b);
                a
            });
        done.store(true, Ordering::SeqCst);
        stats
    });
    let mut failures = failures.into_inner().unwrap_or_default();
    // Panics on a reader's own threads: run each suspect case alone to see which it was.
    let mut suspects = suspects.into_inner().unwrap_or_default();
    suspects.sort_unstable();
    for case in suspects {
        let mutated = generate(target, &seed_bytes, options.seed, case);
        let label = format!("{}-{case}-again", target.name);
        let before = STRAY_PANICS.load(Ordering::SeqCst);
        let (outcome, _) = run_one(
            target,
            mutated.seed,
            &mutated.bytes,
            mutated.variant,
            scratch,
            &label,
        );
        if STRAY_PANICS.load(Ordering::SeqCst) != before && !outcome.failed() {
            let message = STRAY_MESSAGE
                .lock()
                .ok()
                .and_then(|m| m.clone())
                .unwrap_or_default();
            stats.panics += 1;
            match outcome {
                Outcome::Verdict(Verdict::Ok) => stats.ok -= 1,
                Outcome::Verdict(Verdict::Err { whole_file, .. }) => {
                    stats.errors -= 1;
                    stats.whole_file -= u64::from(whole_file);
                }
                _ => {}
            }
            failures.push(Failure {
                reader: target.name,
                case,
                seed_input: mutated.seed,
                outcome: Outcome::Panic(format!("on a reader thread: {message}")),
                bytes: mutated.bytes,
            });
        }
    }
    failures.sort_by_key(|f| f.case);
    stats.seconds = started.elapsed().as_secs_f64();
    (stats, failures)
}

/// Where failing inputs go.
fn fuzz_dir() -> PathBuf {
    workspace_root().join("target/fuzz")
}

/// Saves a failing input; its path for the report.
fn save(reader: &str, case: u64, bytes: &[u8]) -> String {
    let dir = fuzz_dir();
    let path = dir.join(format!("{reader}-{case}.bin"));
    match std::fs::create_dir_all(&dir).and_then(|()| std::fs::write(&path, bytes)) {
        Ok(()) => path
            .strip_prefix(workspace_root())
            .unwrap_or(&path)
            .display()
            .to_string(),
        Err(e) => format!("(not saved: {e})"),
    }
}

/// A case has run longer than the timeout: report it and end the process.
fn hang(target: &Target, seed_bytes: &[Vec<u8>], options: &FuzzOptions, case: u64) -> ! {
    let mutated = generate(target, seed_bytes, options.seed, case);
    let saved = save(target.name, case, &mutated.bytes);
    println!(
        "\nFAIL reader {} case {case} (seed {}, from seed input {}): HANG: it ran longer than {} s\n  \
         input: {} bytes, saved to {saved}\n  replay: cargo xtask fuzz --reader {} --seed {} \
         --case {case}",
        target.name,
        options.seed,
        mutated.seed,
        options.timeout_secs,
        mutated.bytes.len(),
        target.name,
        options.seed,
    );
    std::process::exit(EXIT_HANG);
}

/// Prints the failures and saves their inputs.
fn report(failures: &[Failure], target: &Target, seed: u64) {
    for f in failures.iter().take(MAX_SAVED) {
        let saved = save(f.reader, f.case, &f.bytes);
        let name = &target.seeds[f.seed_input].name;
        let what = match &f.outcome {
            Outcome::Panic(message) => format!("PANIC: {message}"),
            Outcome::Verdict(Verdict::Bad(message)) => format!("BAD ERROR: {message}"),
            other => format!("{other:?}"),
        };
        println!(
            "\nFAIL reader {} case {} (seed {seed}, from seed input {} {name}): {what}\n  \
             input: {} bytes, saved to {saved}\n  replay: cargo xtask fuzz --reader {} --seed \
             {seed} --case {}",
            f.reader,
            f.case,
            f.seed_input,
            f.bytes.len(),
            f.reader,
            f.case
        );
    }
    if failures.len() > MAX_SAVED {
        println!(
            "({}: {} more failures not shown or saved)",
            target.name,
            failures.len() - MAX_SAVED
        );
    }
}

/// Runs one case with the default panic hook (the message and backtrace print as usual;
/// panics on the reader's own threads count too).
fn replay(target: &Target, seed: u64, case: u64, scratch: &Path) -> Result<()> {
    let default_hook = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        if !IN_CASE.with(Cell::get) {
            STRAY_PANICS.fetch_add(1, Ordering::SeqCst);
        }
        default_hook(info);
    }));
    let seed_bytes: Vec<Vec<u8>> = target.seeds.iter().map(|s| s.bytes.clone()).collect();
    let mutated = generate(target, &seed_bytes, seed, case);
    let saved = save(target.name, case, &mutated.bytes);
    println!(
        "reader {} case {case} (seed {seed}): from seed input {} ({}), {} bytes, saved to {saved}",
        target.name,
        mutated.seed,
        target.seeds[mutated.seed].name,
        mutated.bytes.len()
    );
    let label = format!("{}-{case}", target.name);
    let (outcome, suspect) = run_one(
        target,
        mutated.seed,
        &mutated.bytes,
        mutated.variant,
        scratch,
        &label,
    );
    println!("outcome: {outcome:?}");
    if outcome.failed() || suspect {
        bail!("case {case} of {} fails", target.name);
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A short run of every reader in this process: no failure, and the same outcome when a
    /// case is run again.
    #[test]
    fn every_reader_survives_a_short_run() {
        let dir = tempfile::tempdir().unwrap_or_else(|e| panic!("{e}"));
        let targets = targets::all(dir.path()).unwrap_or_else(|e| panic!("{e:#}"));
        for target in &targets {
            check_seeds(target, dir.path()).unwrap_or_else(|e| panic!("{e:#}"));
            let seeds: Vec<Vec<u8>> = target.seeds.iter().map(|s| s.bytes.clone()).collect();
            for case in 0..60 {
                let m = generate(target, &seeds, DEFAULT_SEED, case);
                let (outcome, suspect) =
                    run_one(target, m.seed, &m.bytes, m.variant, dir.path(), "case");
                assert!(
                    !outcome.failed() && !suspect,
                    "{} case {case}: {outcome:?}",
                    target.name
                );
                let again = generate(target, &seeds, DEFAULT_SEED, case);
                assert_eq!(again.bytes, m.bytes);
            }
        }
    }
}
