//! A written map and what it holds: the files of [`write_map_files`] and the [`MapReport`]
//! that `raypath map --json` prints (and `raypath slam` under `"map"`).

use std::path::{Path, PathBuf};

use serde::Serialize;

use super::{MapFile, MapKind, MapPicture, RosMapOptions, StoredStats};
use super::{picture_values, write_png, write_ros_map};
use crate::{MappingSummary, SensorModelError};

/// The files of one map (see [`write_map_files`]).
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct MapFiles {
    /// ROS `map_server` picture.
    pub pgm: PathBuf,
    /// ROS `map_server` metadata.
    pub yaml: PathBuf,
    /// The same picture as PNG.
    pub png: PathBuf,
    /// The binary map ([`MapFile`]).
    pub rpmap: PathBuf,
}

fn with_suffix(prefix: &Path, suffix: &str) -> PathBuf {
    let mut name = prefix.as_os_str().to_owned();
    name.push(suffix);
    PathBuf::from(name)
}

/// Writes `PREFIX.pgm` + `PREFIX.yaml`, `PREFIX.png` (the ML map value `picture` of every
/// cell; a 3-D map is shown as its vertical column sums) and `PREFIX.rpmap` (`file`). The
/// suffixes are appended, so a prefix with a dot keeps it.
pub fn write_map_files(
    prefix: &Path,
    file: &MapFile,
    picture: MapPicture,
) -> Result<MapFiles, SensorModelError> {
    let projected;
    let planar = match &file.stats {
        StoredStats::Planar(stats) => stats,
        StoredStats::Spatial(stats) => {
            projected = stats.project_z();
            &projected
        }
    };
    let values = picture_values(planar, picture);
    // `write_ros_map` replaces the extension; give it a name whose "extension" is ours.
    let (pgm, yaml) = write_ros_map(
        &with_suffix(prefix, ".pgm"),
        planar.grid(),
        &values,
        &RosMapOptions::default(),
    )?;
    let png = with_suffix(prefix, ".png");
    write_png(&png, planar.grid(), &values)?;
    let rpmap = with_suffix(prefix, ".rpmap");
    file.write_file(&rpmap)?;
    Ok(MapFiles {
        pgm,
        yaml,
        png,
        rpmap,
    })
}

/// The extent of a map's grid, metres (two or three coordinates).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Extent {
    /// The lower corner.
    pub min: Vec<f64>,
    /// The upper corner.
    pub max: Vec<f64>,
}

/// What a built map holds and where it was written: the JSON object of `raypath map --json`.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct MapReport {
    /// The sensor model ([`MapKind::name`]).
    pub model: &'static str,
    /// The full-posterior variant.
    pub posterior: bool,
    /// 2 or 3.
    pub dimensions: usize,
    /// Cell edge, metres.
    pub resolution: f64,
    /// Cells per axis.
    pub grid: Vec<usize>,
    /// Cells in all.
    pub cells: usize,
    /// Cells some ray crossed or ended in.
    pub observed_cells: usize,
    /// Rays offered to the map.
    pub rays: u64,
    /// Returns that got a hit.
    pub hits: u64,
    /// No-returns traced to `r_max`.
    pub no_returns_traced: u64,
    /// No-returns skipped.
    pub no_returns_skipped: u64,
    /// Returns ending outside the grid.
    pub endpoints_outside: u64,
    /// Readings below `r_min`, ignored.
    pub sub_ignored: u64,
    /// Cell crossings recorded.
    pub crossings: u64,
    /// The grid's extent.
    pub extent: Extent,
    /// Time spent inserting rays, seconds.
    pub mapping_seconds: f64,
    /// Time in all, seconds.
    pub seconds: f64,
    /// Rays per second of mapping (0 when no time was measured).
    pub rays_per_second: f64,
    /// The files written.
    pub files: MapFiles,
}

impl MapReport {
    /// The report of `file`, built with cells of `resolution` metres in `mapping_seconds`
    /// (`seconds` in all) and written to `files`.
    pub fn new(
        file: &MapFile,
        resolution: f64,
        mapping_seconds: f64,
        seconds: f64,
        files: MapFiles,
    ) -> Self {
        let (dimensions, grid, cells, observed, summary, min, max): (
            usize,
            Vec<usize>,
            usize,
            usize,
            MappingSummary,
            Vec<f64>,
            Vec<f64>,
        ) = match &file.stats {
            StoredStats::Planar(s) => {
                let b = s.grid().bounds();
                (
                    2,
                    s.grid().dims().to_vec(),
                    s.cells().len(),
                    s.cells().iter().filter(|c| !c.is_empty()).count(),
                    *s.summary(),
                    vec![b.min.x, b.min.y],
                    vec![b.max.x, b.max.y],
                )
            }
            StoredStats::Spatial(s) => {
                let b = s.grid().bounds();
                (
                    3,
                    s.grid().dims().to_vec(),
                    s.cells().len(),
                    s.cells().iter().filter(|c| !c.is_empty()).count(),
                    *s.summary(),
                    vec![b.min.x, b.min.y, b.min.z],
                    vec![b.max.x, b.max.y, b.max.z],
                )
            }
        };
        let rays_per_second = if mapping_seconds > 0.0 {
            summary.rays as f64 / mapping_seconds
        } else {
            0.0
        };
        Self {
            model: file.kind.name(),
            posterior: file.posterior,
            dimensions,
            resolution,
            grid,
            cells,
            observed_cells: observed,
            rays: summary.rays,
            hits: summary.hits,
            no_returns_traced: summary.no_returns_traced,
            no_returns_skipped: summary.no_returns_skipped,
            endpoints_outside: summary.endpoints_outside,
            sub_ignored: summary.sub_ignored,
            crossings: summary.crossings,
            extent: Extent { min, max },
            mapping_seconds,
            seconds,
            rays_per_second,
            files,
        }
    }
}

impl MapKind {
    /// The model's name on the command line: `decay-rate`, `reflection`, `log-odds`,
    /// `likelihood-field`, or `statistics`.
    pub fn name(self) -> &'static str {
        match self {
            MapKind::Statistics => "statistics",
            MapKind::DecayRate => "decay-rate",
            MapKind::Reflection => "reflection",
            MapKind::LogOdds => "log-odds",
            MapKind::LikelihoodField => "likelihood-field",
        }
    }
}
