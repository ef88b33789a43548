//! The result of an evaluation ([`EvalReport`]) and how a run writes it: the page
//! `docs/results/<name>.md` with its header (command, date, machine, data directory, run time)
//! and headline, and `target/eval/<name>.json`.

use anyhow::{Context, Result};

use super::EvalContext;

/// The result of one evaluation.
pub struct EvalReport {
    /// Short name (`io`, `geometry`, …): file names and `cargo xtask eval <name>`.
    pub name: &'static str,
    /// A one-line title.
    pub title: String,
    /// The markdown body: tables beside the thesis figures, notes on what is real and what is
    /// simulated.
    pub markdown: String,
    /// Machine-readable results.
    pub json: serde_json::Value,
    /// The run's figures in one line, real rows first (simulated ones named so): written at
    /// the top of the results page and, after a full run, into the README's headline table
    /// ([`crate::readme`]).
    pub headline: Option<String>,
}

/// `target/eval/<name>.json`: the run (what, when, where, how long) and the evaluation's own
/// results. The fields are in alphabetical order, the order the keys have always been written
/// in.
#[derive(serde::Serialize)]
struct ResultsFile<'a> {
    /// `cargo xtask eval <name>[ --quick]`.
    command: &'a str,
    /// The data directory.
    data_dir: String,
    /// `YYYY-MM-DD HH:MM`, UTC.
    date_utc: String,
    /// CPU model and cores available.
    machine: String,
    /// The evaluation's name.
    name: &'a str,
    /// Whether this was a quick run.
    quick: bool,
    /// [`EvalReport::json`].
    results: &'a serde_json::Value,
    /// Run time (for a merge: the shards' sum).
    seconds: f64,
    /// [`EvalReport::title`].
    title: &'a str,
}

/// Prints the report and writes its page and JSON (and, after a full run with a headline
/// written into the checkout, the README's headline table).
pub(crate) fn write_report(ctx: &EvalContext, report: &EvalReport, seconds: f64) -> Result<()> {
    let command = format!(
        "cargo xtask eval {}{}",
        report.name,
        if ctx.quick { " --quick" } else { "" }
    );
    let header = format!(
        "# {}\n\n<!-- Written by `{command}`; do not edit by hand. -->\n\n\
         - Command: `{command}`\n- Date (UTC): {}\n- Machine: {}\n- Data: `{}`\n- Run time: {seconds:.1} s\n\n",
        report.title,
        utc_date(),
        machine(),
        ctx.data_dir.display(),
    );
    let headline = match &report.headline {
        Some(text) if ctx.quick => format!("**Headline (quick run).** {text}\n\n"),
        Some(text) => format!("{}{text}\n\n", crate::readme::PREFIX),
        None => String::new(),
    };
    let markdown = format!("{header}{headline}{}", report.markdown.trim_end());
    println!("{markdown}\n");

    let docs = ctx.out_dir.join("docs/results");
    std::fs::create_dir_all(&docs)?;
    let md_path = docs.join(format!("{}.md", report.name));
    std::fs::write(&md_path, format!("{markdown}\n"))
        .with_context(|| format!("writing {}", md_path.display()))?;

    let json_dir = ctx.out_dir.join("target/eval");
    std::fs::create_dir_all(&json_dir)?;
    let json_path = json_dir.join(format!("{}.json", report.name));
    let json = ResultsFile {
        command: &command,
        data_dir: ctx.data_dir.display().to_string(),
        date_utc: utc_date(),
        machine: machine(),
        name: report.name,
        quick: ctx.quick,
        results: &report.json,
        seconds,
        title: &report.title,
    };
    std::fs::write(&json_path, serde_json::to_string_pretty(&json)?)
        .with_context(|| format!("writing {}", json_path.display()))?;
    eprintln!("wrote {} and {}", md_path.display(), json_path.display());
    if report.headline.is_some() && !ctx.quick && ctx.out_dir == ctx.workspace_root {
        crate::readme::update(&ctx.workspace_root)?;
    }
    Ok(())
}

/// CPU model and core count, for report headers.
pub fn machine() -> String {
    let cpu = std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|info| {
            info.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split(':').nth(1))
                .map(|m| m.trim().to_owned())
        })
        .unwrap_or_else(|| std::env::consts::ARCH.to_owned());
    let cores = std::thread::available_parallelism().map_or(1, usize::from);
    format!("{cpu}, {cores} cores available")
}

/// Today's date in UTC as `YYYY-MM-DD HH:MM`.
pub fn utc_date() -> String {
    let secs = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_secs());
    let days = (secs / 86_400) as i64;
    let (hour, minute) = ((secs % 86_400) / 3600, (secs % 3600) / 60);
    // Civil-from-days (Howard Hinnant's algorithm).
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let day = doy - (153 * mp + 2) / 5 + 1;
    let month = if mp < 10 { mp + 3 } else { mp - 9 };
    let year = yoe + era * 400 + i64::from(month <= 2);
    format!("{year:04}-{month:02}-{day:02} {hour:02}:{minute:02}")
}
