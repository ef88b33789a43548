//! `raypath map`: build a sensor-model map from a log or sequence.
//!
//! ```text
//! raypath map <log-or-sequence> --model decay-rate|reflection|log-odds [--posterior]
//!             --resolution R --out PREFIX [--json]
//!             [--max-range M] [--min-range M] [--ray-step N] [--skip-no-returns] [--sparse]
//!             [--laser front|rear|any] [--scan-topic T] [--cloud-topic T] [--odom-topic T]
//!             [--reference-topic T] [--frame F] [--record OUT.mcap]
//! ```
//!
//! The input is read through the sources of `raypath_io::sequence`:
//! * planar scans → a 2-D map: a CARMEN log (plain, gzip or bzip2; `--laser` picks the
//!   laser, front by default) whose laser poses are trusted as ground truth (a corrected
//!   log), or a rosbag2 bag's `sensor_msgs/msg/LaserScan` topic at its reference poses
//!   (`--reference-topic`), else at its odometry poses;
//! * 3-D sweeps → a 3-D map at their reference poses (else the odometry, with a warning): a
//!   KITTI-layout sequence directory (`velodyne/*.bin` + `poses.txt` + `calib.txt`, or the
//!   benchmark layout `sequences/NN` + `poses/NN.txt`; camera-0 poses are turned into
//!   velodyne poses with `Tr`), an NCLT session directory (`velodyne_sync/*.bin` +
//!   `groundtruth_<date>.csv`, the ground truth interpolated at the scan times; points and
//!   poses in REP-103 axes; the small body-to-velodyne offset is ignored), or a bag's
//!   `sensor_msgs/msg/PointCloud2` topic.
//!
//! A bag (its directory with `metadata.yaml`, or its `.mcap` file) gives a 2-D map from its
//! LaserScan topic, or a 3-D map from its PointCloud2 topic when it has no LaserScan topic or
//! `--cloud-topic` is given.
//!
//! The grid covers the sensor positions and all returns within the maximum range, plus one
//! cell. Outputs: `PREFIX.pgm` + `PREFIX.yaml` (ROS `map_server`; a 3-D map is shown as its
//! vertical column sums), `PREFIX.png` (same picture) and `PREFIX.rpmap` (the binary map of
//! `raypath_sensor_models::export`, read by `raypath localize`; it records the model and the
//! posterior flag). Pictures show the ML map value (reflection probability, decay-rate hit
//! probability over one cell, or log-odds occupancy).
//!
//! `--record OUT.mcap` writes a Foxglove recording (see `record`): 2-D — every scan at its
//! pose (`/tf`, `/scan`), the robot's trajectory and the map's picture values as a `FLOAT32`
//! Grid `/map` (NaN = unknown); 3-D — every sweep at its pose (`/tf`, `/points` thinned by
//! `record::sweep_points`), the trajectory, the column-sum picture as `/map` and the
//! centres of the occupied voxels (value above one half) as the PointCloud `/map_points` (at
//! most `map::record::MAX_VOXELS`).

mod input;
pub(crate) mod record;

use std::path::PathBuf;
use std::time::Instant;

use raypath_sensor_models::export::{
    MapFile, MapFiles, MapKind, MapPicture, MapReport, StoredStats, write_map_files,
};
use raypath_sensor_models::{DenseStats2, DenseStats3, MappingConfig, SparseStats3};

use super::Failure;
use super::record::{RecordArgs, Recording};
use super::source_args::SourceArgs;
use input::{Input, Sweep3};

/// The sensor model a map is built for.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Model {
    /// The decay-rate model (Schaefer 2020, ch. 7): λ = H / R.
    DecayRate,
    /// The reflection model: μ = H / (H + M).
    Reflection,
    /// Log-odds occupancy (OctoMap defaults).
    LogOdds,
}

impl Model {
    pub(crate) fn kind(self) -> MapKind {
        match self {
            Model::DecayRate => MapKind::DecayRate,
            Model::Reflection => MapKind::Reflection,
            Model::LogOdds => MapKind::LogOdds,
        }
    }

    pub(crate) fn picture(self) -> MapPicture {
        match self {
            Model::DecayRate => MapPicture::DecayRate,
            Model::Reflection => MapPicture::Reflection,
            Model::LogOdds => MapPicture::Occupancy,
        }
    }
}

/// Arguments of `raypath map`.
#[derive(clap::Args)]
pub struct Args {
    /// A CARMEN log with corrected poses (2-D), a KITTI sequence directory or an NCLT
    /// session directory (3-D), or a rosbag2 bag (directory with metadata.yaml, or .mcap
    /// file): LaserScan (2-D) or PointCloud2 (3-D).
    pub input: PathBuf,
    /// The sensor model the map is for.
    #[arg(long, value_enum)]
    pub model: Model,
    /// The full-posterior variant (Beta / Gamma map posteriors, Schaefer ch. 8); not for
    /// log-odds.
    #[arg(long)]
    pub posterior: bool,
    /// Cell edge in metres.
    #[arg(long)]
    pub resolution: f64,
    /// Output prefix: writes PREFIX.pgm, PREFIX.yaml, PREFIX.png and PREFIX.rpmap.
    #[arg(long)]
    pub out: PathBuf,
    /// Maximum range r_max in metres: returns at or beyond it (and no-returns) are traced
    /// to it as pure misses (default 80 m).
    #[arg(long, default_value_t = 80.0)]
    pub max_range: f64,
    /// Minimum range r_min in metres: returns below it are ignored.
    #[arg(long, default_value_t = 0.0)]
    pub min_range: f64,
    /// Use every N-th ray (beam or point) only.
    #[arg(long, default_value_t = 1)]
    pub ray_step: usize,
    /// Do not trace no-returns (by default they add misses and path length up to r_max).
    #[arg(long)]
    pub skip_no_returns: bool,
    /// 3-D: build in the blocked sparse grid (less memory while mapping; the stored map is
    /// dense).
    #[arg(long)]
    pub sparse: bool,
    /// How to read the input.
    #[command(flatten)]
    pub source: SourceArgs,
    /// A Foxglove recording of the run.
    #[command(flatten)]
    pub record: RecordArgs,
}

/// Largest dense map `raypath map` allocates (cells); 16 bytes per cell.
const MAX_CELLS: usize = 200_000_000;

/// Runs `raypath map`.
pub fn run(args: &Args) -> Result<(), Failure> {
    let mut recording = Recording::open(&args.record)?;
    let report = build(args, recording.as_mut())?;
    if super::console::json() {
        let mut doc = super::to_json(&report)?;
        super::record::finish(recording, Some(&mut doc))?;
        println!("{doc}");
    } else {
        print(&report);
        super::record::finish(recording, None)?;
    }
    Ok(())
}

fn build(args: &Args, recording: Option<&mut Recording>) -> Result<MapReport, Failure> {
    let started = Instant::now();
    let config = check_args(args)?;
    let input =
        Input::read(&args.input, &args.source, args.ray_step, &config).map_err(Failure::input)?;
    super::console::stage("reading", started);
    let mapping_started = Instant::now();
    let spinner = super::console::spinner("mapping");
    let stats = match &input {
        Input::Planar { scans, bounds, .. } => {
            let grid = raypath_geometry::Grid2::covering(bounds, args.resolution)
                .map_err(|e| grid_failure(args, e))?;
            check_size(args, grid.num_cells())?;
            let mut stats = DenseStats2::planar(grid);
            let step = args.ray_step;
            stats.insert_par(scans, &config, |(pose, scan), sink| {
                for ray in scan.rays(*pose).step_by(step) {
                    sink(&ray);
                }
            });
            StoredStats::Planar(stats)
        }
        Input::Spatial { sweeps, bounds, .. } => {
            let grid = raypath_geometry::Grid3::covering(bounds, args.resolution)
                .map_err(|e| grid_failure(args, e))?;
            check_size(args, grid.num_cells())?;
            let rays_of = |sweep: &Sweep3, sink: &mut dyn FnMut(&raypath_geometry::Ray3)| {
                sweep.for_each_ray(sink);
            };
            let stats = if args.sparse {
                let mut sparse = SparseStats3::new(grid);
                sparse.insert_par(sweeps, &config, rays_of);
                sparse.to_dense()
            } else {
                let mut dense = DenseStats3::spatial(grid);
                dense.insert_par(sweeps, &config, rays_of);
                dense
            };
            StoredStats::Spatial(stats)
        }
    };
    spinner.finish_and_clear();
    super::console::stage("mapping", mapping_started);
    let mapping_secs = mapping_started.elapsed().as_secs_f64();
    let file = MapFile {
        kind: args.model.kind(),
        posterior: args.posterior,
        mapping: config,
        stats,
    };
    let written = write_outputs(args, &file)?;
    if let Some(recording) = recording {
        record::record(recording, &input, &file, args.model.picture())?;
    }
    Ok(MapReport::new(
        &file,
        args.resolution,
        mapping_secs,
        started.elapsed().as_secs_f64(),
        written,
    ))
}

fn check_args(args: &Args) -> Result<MappingConfig, Failure> {
    let bad = |message: String| Failure {
        message,
        bad_input: true,
    };
    if args.posterior && args.model == Model::LogOdds {
        return Err(bad(
            "--posterior is not defined for --model log-odds: only the decay-rate (Gamma) and \
             reflection (Beta) models have full map posteriors"
                .into(),
        ));
    }
    if !(args.resolution.is_finite() && args.resolution > 0.0) {
        return Err(bad(format!(
            "--resolution must be a positive number of metres, got {}",
            args.resolution
        )));
    }
    if args.ray_step == 0 {
        return Err(bad("--ray-step must be at least 1".into()));
    }
    let mut config = MappingConfig::with_range(args.min_range, args.max_range)
        .map_err(|e| bad(format!("--min-range/--max-range: {e}")))?;
    config.include_no_returns = !args.skip_no_returns;
    Ok(config)
}

fn grid_failure(args: &Args, error: impl std::fmt::Display) -> Failure {
    Failure::input(format!(
        "{}: cannot build a grid of {} m cells over the data: {error}",
        args.input.display(),
        args.resolution
    ))
}

fn check_size(args: &Args, cells: usize) -> Result<(), Failure> {
    if cells > MAX_CELLS {
        return Err(Failure::input(format!(
            "{}: the map would have {cells} cells of {} m (at most {MAX_CELLS}); use a \
                 coarser --resolution or a smaller --max-range",
            args.input.display(),
            args.resolution
        )));
    }
    Ok(())
}

fn write_outputs(args: &Args, file: &MapFile) -> Result<MapFiles, Failure> {
    if let Some(dir) = args.out.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).map_err(|e| {
            Failure::internal(format!(
                "{}: cannot create the directory: {e}",
                dir.display()
            ))
        })?;
    }
    write_map_files(&args.out, file, args.model.picture()).map_err(Failure::internal)
}

/// The human view of the report.
fn print(report: &MapReport) {
    let grid: Vec<String> = report.grid.iter().map(usize::to_string).collect();
    let coords = |v: &[f64]| {
        v.iter()
            .map(|x| format!("{x:.2}"))
            .collect::<Vec<_>>()
            .join(", ")
    };
    println!(
        "{} map{} ({}-D), {} m cells: {} = {} cells, {} observed",
        report.model,
        if report.posterior {
            " (full posterior)"
        } else {
            ""
        },
        report.dimensions,
        report.resolution,
        grid.join(" × "),
        report.cells,
        report.observed_cells
    );
    println!(
        "extent: [{}] to [{}] m",
        coords(&report.extent.min),
        coords(&report.extent.max)
    );
    println!(
        "rays: {} ({} hits, {} no-returns traced, {} returns ending outside the grid, {} below r_min)",
        report.rays,
        report.hits,
        report.no_returns_traced,
        report.endpoints_outside,
        report.sub_ignored
    );
    println!(
        "time: {:.2} s mapping ({:.0} rays/s), {:.2} s in all",
        report.mapping_seconds, report.rays_per_second, report.seconds
    );
    let f = &report.files;
    for p in [&f.pgm, &f.yaml, &f.png, &f.rpmap] {
        println!("wrote {}", p.display());
    }
}
