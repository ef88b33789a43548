//! `raypath`: every raypath capability on your own files.
//!
//! ```text
//! raypath info <path> [--json] [--format <name>]
//! raypath convert <in> <out> [--to carmen|kitti|pcd|rosbag2] [--json]
//! raypath simulate <kind> --out DIR [--seed S] [--quick] [--scans N] [--json]
//! raypath simulate semi-kitti --poses poses.txt --times times.txt --poles poles.csv --out DIR
//! raypath register <source> <target> | <sequence> [--json]
//! raypath completions bash|zsh|fish|elvish|powershell
//! raypath man [--out DIR]
//! ```
//!
//! Every subcommand prints a human-readable report, or with `--json` one JSON document on
//! standard output for scripts. Long commands draw a progress bar on standard error when it
//! is a terminal; `--quiet` (`-q`) silences bars, warnings and notes, `-v` adds the time of
//! each stage. Errors go to standard error as `error: <file>:<place>: <reason>`
//! (and, with `--json`, as `{"error": "..."}` on standard output); the exit code is 2 for bad
//! input and 1 for other failures.

mod commands;

use std::process::ExitCode;

use clap::{CommandFactory, Parser, Subcommand};

#[derive(Parser)]
#[command(
    name = "raypath",
    version,
    about = "Lidar mapping, localization and place recognition on your own data"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
    /// Print one JSON document on standard output (a failure as `{"error": …}`).
    #[arg(long, global = true)]
    json: bool,
    /// No progress bars, warnings or notes on standard error (errors are still printed).
    #[arg(short, long, global = true, conflicts_with = "verbose")]
    quiet: bool,
    /// Also print how long each stage took on standard error.
    #[arg(short, long, global = true, action = clap::ArgAction::Count)]
    verbose: u8,
}

#[derive(Subcommand)]
enum Command {
    /// Detect a file's format and summarize it: scans, beams, points, poses, odometry,
    /// organized size, labels, bounding box, time span. A KITTI or NCLT directory is one input.
    Info(commands::info::Args),
    /// Convert between CARMEN logs, the KITTI layout, PCD files and rosbag2 (MCAP) bags.
    Convert(commands::convert::Args),
    /// Generate simulated data in real formats (CARMEN, PCD, KITTI, NCLT): polygons, indoor
    /// worlds, the 1-D corridor, SynPEB-style rooms, urban drives, semi-synthetic KITTI.
    Simulate(commands::simulate::Args),
    /// Build a map from a CARMEN log (corrected poses), a 3-D sequence or a rosbag2 bag:
    /// per-cell ray statistics and a decay-rate, reflection or log-odds model (PGM+YAML and
    /// binary map).
    Map(commands::map::Args),
    /// Score every sensor model on a corrected CARMEN log or a bag with reference poses:
    /// negative log-likelihood at the true poses and inverse KL over poses in a disc
    /// (Schaefer Table 7.3, Table 8.2/8.3 ratios).
    ScoreModel(commands::score_model::Args),
    /// Monte-Carlo localization of a log (CARMEN or rosbag2) in a map written by `raypath map`;
    /// with ground truth, the error summary.
    Localize(commands::localize::Args),
    /// Extract polylines from the scans of a CARMEN log or a bag: maximum-likelihood PLE / PLE+
    /// (Schaefer ch. 10) or the VVL, IEF, SAM baselines; vertices, RMSE, f, optional SVG.
    Polylines(commands::polylines::Args),
    /// Extract finite planes from an organized PCD scan or a bag's organized PointCloud2 (PPE,
    /// Schaefer ch. 11): labels per point and per plane its normal, distance, point count and
    /// RMSE.
    Planes(commands::planes::Args),
    /// Score a segmentation against ground-truth labels (Hoover et al., T = 0.8): f, k and
    /// the over-, under-segmented, missed and noise counts.
    SegcompEval(commands::segcomp_eval::Args),
    /// Build the Rtree variable-resolution occupancy grid (Khan ch. 2) from a scan graph, a
    /// sequence or a bag: nodes, leaves, bytes, times.
    Octree(commands::octree::Args),
    /// Pole extraction, pole maps and pole-based particle-filter localization (Schaefer ch. 12).
    Poles(commands::poles::Args),
    /// Fit a continuous DCT decay-rate map (Schaefer ch. 9) and a grid map with as many
    /// parameters from the same rays (a CARMEN log or a bag), and score both.
    DctMap(commands::dct_map::Args),
    /// Hector-style scan matching of a CARMEN log or a bag with occupancy, reflectivity or
    /// combined residuals (Khan ch. 3): trajectory, map, speed and errors.
    ScanMatch(commands::scan_match::Args),
    /// Fit the intensity look-up table I_ref(r, α) from reference-surface samples (Khan ch. 3).
    CalibrateIntensity(commands::calibrate_intensity::Args),
    /// Loop-closure detection (IBuILD, Khan ch. 4) or kidnapped-robot place recognition on a
    /// CARMEN log, KITTI sequence, NCLT session, rosbag2 bag or image folder; with ground
    /// truth, the precision–recall summary.
    LoopClosure(commands::loop_closure::Args),
    /// 2-D lidar SLAM of a raw CARMEN log or a bag: submap front-end, branch-and-bound loop
    /// closure, robust pose graph; trajectory, corrected log, map and, with a corrected log,
    /// the relation errors of Kümmerle et al. (2009).
    Slam(commands::slam::Args),
    /// 3-D scan registration: two scans by point-to-plane ICP, or a KITTI/NCLT/Ouster/bag
    /// sequence by KISS-ICP-style odometry, with errors against its reference poses.
    Register(commands::register::Args),
    /// Print a shell completion script (e.g. `raypath completions bash >
    /// ~/.local/share/bash-completion/completions/raypath`).
    Completions(commands::shell::CompletionsArgs),
    /// Print the man page, or with `--out DIR` write one page per subcommand.
    Man(commands::shell::ManArgs),
}

fn main() -> ExitCode {
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(error) => return parse_failure(&error),
    };
    commands::console::set(cli.quiet, cli.verbose, cli.json);
    let result = match &cli.command {
        Command::Info(args) => commands::info::run(args),
        Command::Convert(args) => commands::convert::run(args),
        Command::Simulate(args) => commands::simulate::run(args),
        Command::Map(args) => commands::map::run(args),
        Command::ScoreModel(args) => commands::score_model::run(args),
        Command::Localize(args) => commands::localize::run(args),
        Command::Polylines(args) => commands::polylines::run(args),
        Command::Planes(args) => commands::planes::run(args),
        Command::SegcompEval(args) => commands::segcomp_eval::run(args),
        Command::Octree(args) => commands::octree::run(args),
        Command::Poles(args) => commands::poles::run(args),
        Command::DctMap(args) => commands::dct_map::run(args),
        Command::ScanMatch(args) => commands::scan_match::run(args),
        Command::CalibrateIntensity(args) => commands::calibrate_intensity::run(args),
        Command::LoopClosure(args) => commands::loop_closure::run(args),
        Command::Slam(args) => commands::slam::run(args),
        Command::Register(args) => commands::register::run(args),
        Command::Completions(args) => commands::shell::completions(args, Cli::command()),
        Command::Man(args) => commands::shell::man(args, Cli::command()),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(failure) => failure.report(),
    }
}

/// A command line clap refuses: its message on standard error (and help or version on
/// standard output, exit 0, as clap does); for a refused command line with `--json`, also
/// `{"error": …}` on standard output, so scripts get the same shape as for any other bad
/// input. Exit code 2.
fn parse_failure(error: &clap::Error) -> ExitCode {
    use clap::error::ErrorKind;
    if matches!(
        error.kind(),
        ErrorKind::DisplayHelp
            | ErrorKind::DisplayVersion
            | ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand
    ) {
        let _ = error.print();
        return if error.kind() == ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand {
            ExitCode::from(2)
        } else {
            ExitCode::SUCCESS
        };
    }
    let _ = error.print();
    if std::env::args().skip(1).any(|a| a == "--json") {
        // The message up to the first blank line (before the usage hint), on one line.
        let rendered = error.render().to_string();
        let message: Vec<&str> = rendered
            .lines()
            .take_while(|l| !l.trim().is_empty())
            .map(str::trim)
            .collect();
        let message = message.join(" ");
        let message = message.trim_start_matches("error: ");
        commands::print_error_json(message);
    }
    ExitCode::from(2)
}
