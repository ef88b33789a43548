//! `raypath planes`: maximum-likelihood finite planes (PPE; Schaefer 2020 ch. 11) from an
//! organized PCD scan, in the sensor frame (every ray starts at the origin).
//!
//! The scan is a PCD file, one sweep of a rosbag2 bag (its directory with `metadata.yaml`,
//! or its `.mcap` file; its `sensor_msgs/msg/PointCloud2` topic) or one frame of an Ouster
//! capture (`.pcap` with its metadata JSON; the organized first-return cloud): sweep
//! `--frame-index` (default 0), read through `raypath_io::sequence::SweepSequence`; the cloud
//! must be organized (height > 1, NaN = no return).
//!
//! `--method ppe|msac|peac` picks PPE (default), the iterative MSAC baseline or the
//! PEAC-style block-graph baseline (Feng et al. 2014); `--preset` applies to PPE (the
//! baselines use their SynPEB parameters).
//!
//! `--out FILE` writes one integer label per point in file order (`0` = no plane, planes
//! `1..=J`, largest first). Prints per plane its label, unit normal (pointing away from the
//! sensor), distance from the sensor (m), number of points and radial RMSE (m).
//!
//! `--json` prints `{"planes": [{"label", "normal": [x, y, z], "distance", "points",
//! "rmse"}, …]}` plus `scan`, `width`, `height`, `method`, `preset`, `rmse` (all planes,
//! per point) and `seconds` (extraction time).
//!
//! `--record OUT.mcap` writes a Foxglove recording (see `record`) at the sweep's time (a PCD
//! file: time 0): `/tf` `map → base_link` (the identity: the sensor at the origin), the scan
//! as the PointCloud `/points` in `base_link` with a `label` field (0 = no plane, planes
//! `1..=J`) and coloured by label (grey: no plane), and per plane an entity `plane <label>` on
//! `/planes`: the outline of its points' convex hull on the fitted plane, filled with
//! half-transparent triangles of the same colour.

use std::io::Write;
use std::path::PathBuf;
use std::time::Instant;

use raypath_geometry::{PointCloud, Pose3};
use raypath_io::foxglove::{Rgba, frame, topic};
use raypath_io::pcd::{ReadOptions, read_pcd};
use raypath_planes::report::{PlaneReport, PlanesReport};
use raypath_planes::{MsacParams, PeacParams, PpeParams, Segmentation, extract, msac, peac};

use super::Failure;
use super::record::{RecordArgs, Recording, label_color, plane_entity};
use super::source_args::{SourceArgs, is_bag};

/// `--method`: the plane extractor.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum MethodArg {
    /// PPE: probabilistic plane extraction (Schaefer 2020, ch. 11).
    Ppe,
    /// Baseline: iterative MSAC with its SynPEB parameters.
    Msac,
    /// Baseline: PEAC-style block graph (Feng et al. 2014) with its SynPEB parameters.
    Peac,
}

/// `--preset`: the PPE parameters (`raypath_planes::PpeParams::preset`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum PresetArg {
    /// SynPEB-style scans, σ = 2 cm (the same as synpeb-2.0).
    Synpeb,
    /// SynPEB noise level σ = 0 cm.
    #[value(name = "synpeb-0.0")]
    Synpeb00,
    /// SynPEB noise level σ = 0.5 cm.
    #[value(name = "synpeb-0.5")]
    Synpeb05,
    /// SynPEB noise level σ = 1 cm.
    #[value(name = "synpeb-1.0")]
    Synpeb10,
    /// SynPEB noise level σ = 2 cm.
    #[value(name = "synpeb-2.0")]
    Synpeb20,
    /// SynPEB noise level σ = 4 cm.
    #[value(name = "synpeb-4.0")]
    Synpeb40,
    /// The SegComp Perceptron scans (√e = d = 20 mm).
    Segcomp,
    /// Velodyne HDL-64E range images (tuned on KITTI).
    Kitti,
    /// The library defaults (e = 0.01 m², no neighbour filter).
    Default,
}

impl PresetArg {
    /// The preset's parameters.
    fn params(self) -> Option<PpeParams> {
        PpeParams::preset(&super::choice_name(&self))
    }
}

/// Arguments of `raypath planes`.
#[derive(clap::Args)]
pub struct Args {
    /// An organized PCD scan (width × height, NaN = no return), a rosbag2 bag (directory
    /// with metadata.yaml, or .mcap file) with organized PointCloud2, or an Ouster capture
    /// (.pcap with its metadata JSON beside it).
    pub scan: PathBuf,
    /// Bags and Ouster captures: the 0-based index of the sweep (frame) to use.
    #[arg(long, default_value_t = 0, value_name = "I")]
    pub frame_index: usize,
    /// Extraction method.
    #[arg(long, value_enum, default_value_t = MethodArg::Ppe, value_name = "NAME")]
    pub method: MethodArg,
    /// PPE parameter preset (the baselines use their SynPEB parameters).
    #[arg(long, value_enum, default_value_t = PresetArg::Synpeb, value_name = "NAME")]
    pub preset: PresetArg,
    /// Override the preset's stopping rule e (largest error increment per step, m²).
    #[arg(long, value_name = "M2")]
    pub max_increment: Option<f64>,
    /// Override the preset's neighbour-distance filter l_max (m).
    #[arg(long, value_name = "M")]
    pub l_max: Option<f64>,
    /// Write one label per point (0 = no plane) to this file.
    #[arg(long, value_name = "FILE")]
    pub out: Option<PathBuf>,
    /// How to read a bag.
    #[command(flatten)]
    pub source: SourceArgs,
    /// A Foxglove recording of the run.
    #[command(flatten)]
    pub record: RecordArgs,
}

/// The organized scan and its time: a PCD file (time 0), or sweep `--frame-index` of a bag
/// or an Ouster capture.
fn read_scan(args: &Args) -> Result<(PointCloud, f64), Failure> {
    let bad = |e: raypath_io::Error| Failure::input(e);
    if !is_bag(&args.scan) && !raypath_io::ouster::is_capture_name(&args.scan) {
        let options = ReadOptions {
            label_from: raypath_io::pcd::LabelSource::None,
        };
        return Ok((read_pcd(&args.scan, &options).map_err(bad)?.cloud, 0.0));
    }
    let sequence = args.source.open_sweeps(&args.scan).map_err(bad)?;
    if args.frame_index >= sequence.len() {
        return Err(Failure::input(format!(
            "{}: --frame-index {} but it has {} sweep(s)",
            sequence.name.display(),
            args.frame_index,
            sequence.len()
        )));
    }
    let cloud = sequence.sweep(args.frame_index).map_err(bad)?;
    if !cloud.is_organized() {
        return Err(Failure::input(format!(
            "{}: sweep {} is not organized ({} × {} points); plane extraction needs a \
                 range image (PointCloud2 with height > 1)",
            sequence.name.display(),
            args.frame_index,
            cloud.width,
            cloud.height
        )));
    }
    let stamp = sequence
        .stamps_secs
        .get(args.frame_index)
        .copied()
        .unwrap_or(0.0);
    Ok((cloud, stamp))
}

/// Points without a plane: grey.
const NO_PLANE: Rgba = [0.6, 0.6, 0.6, 1.0];

/// `--record`: the sensor at the origin, the cloud labelled and coloured by plane, and the
/// planes' outlines and fills.
fn record(
    recording: &mut Recording,
    stamp: f64,
    cloud: &PointCloud,
    seg: &Segmentation,
) -> Result<(), Failure> {
    recording.robot_pose(stamp, &Pose3::identity())?;
    let mut labelled = cloud.clone();
    let labels: Vec<u32> = (0..cloud.len())
        .map(|i| seg.labels.get(i).copied().flatten().map_or(0, |l| l + 1))
        .collect();
    let colors: Vec<Rgba> = labels
        .iter()
        .map(|&l| match l {
            0 => NO_PLANE,
            l => label_color(l as usize),
        })
        .collect();
    labelled.label = Some(labels);
    recording.points(
        topic::POINTS,
        stamp,
        frame::BASE_LINK,
        &labelled,
        Some(&colors),
    )?;
    let entities: Vec<_> = seg
        .planes
        .iter()
        .enumerate()
        .filter_map(|(i, plane)| {
            let points: Vec<_> = plane
                .index
                .iter()
                .filter(|&&k| k < cloud.len())
                .map(|&k| cloud.point_f64(k))
                .collect();
            plane_entity(i + 1, &points, &plane.fit.normal(), plane.fit.distance_m())
        })
        .collect();
    recording.scene(topic::PLANES, stamp, frame::BASE_LINK, &entities)
}

/// Runs the command.
pub fn run(args: &Args) -> Result<(), Failure> {
    let Some(mut params) = args.preset.params() else {
        // Unreachable: the test below resolves every preset.
        return Err(Failure {
            message: format!(
                "preset {}: not known to raypath_planes",
                super::choice_name(&args.preset)
            ),
            bad_input: false,
        });
    };
    if let Some(e) = args.max_increment {
        params.max_increment_m2 = e;
    }
    if let Some(l) = args.l_max {
        params.l_max_m = l;
    }
    params.validate().map_err(Failure::input)?;
    let mut recording = Recording::open(&args.record)?;
    let (cloud, stamp) = read_scan(args)?;
    let started = Instant::now();
    let result = match args.method {
        MethodArg::Msac | MethodArg::Peac => {
            let points: Vec<nalgebra::Vector3<f64>> = cloud
                .points
                .iter()
                .map(|p| p.coords.cast::<f64>())
                .collect();
            if args.method == MethodArg::Msac {
                msac(&points, cloud.width, cloud.height, &MsacParams::synpeb())
            } else {
                peac(&points, cloud.width, cloud.height, &PeacParams::synpeb())
            }
        }
        MethodArg::Ppe => extract(&cloud, &params),
    };
    let seg = result.map_err(|e| Failure::input(format!("{}: {e}", args.scan.display())))?;
    let seconds = started.elapsed().as_secs_f64();
    if let Some(out) = &args.out {
        let write = || -> std::io::Result<()> {
            let mut w = std::io::BufWriter::new(std::fs::File::create(out)?);
            for l in &seg.labels {
                writeln!(w, "{}", l.map_or(0, |l| l + 1))?;
            }
            w.flush()
        };
        write().map_err(|e| Failure::internal(format!("{}: {e}", out.display())))?;
    }
    if let Some(recording) = &mut recording {
        record(recording, stamp, &cloud, &seg)?;
    }
    if super::console::json() {
        let mut doc = super::to_json(&PlanesReport {
            scan: args.scan.display().to_string(),
            width: cloud.width,
            height: cloud.height,
            method: super::choice_name(&args.method),
            preset: super::choice_name(&args.preset),
            planes: PlaneReport::all(&seg),
            rmse: seg.rmse_m(),
            seconds,
        })?;
        super::record::finish(recording, Some(&mut doc))?;
        println!("{doc}");
    } else {
        println!(
            "{}: {} × {}, {} planes, RMSE {:.4} m, {:.3} s",
            args.scan.display(),
            cloud.width,
            cloud.height,
            seg.planes.len(),
            seg.rmse_m(),
            seconds
        );
        println!("label  normal                      distance_m  points  rmse_m");
        for (i, p) in seg.planes.iter().enumerate() {
            let n = p.fit.normal();
            println!(
                "{:>5}  [{:>7.4}, {:>7.4}, {:>7.4}]  {:>10.4}  {:>6}  {:.4}",
                i + 1,
                n.x,
                n.y,
                n.z,
                p.fit.distance_m(),
                p.index.len(),
                p.fit.rmse_m()
            );
        }
        super::record::finish(recording, None)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use clap::ValueEnum;

    use super::*;

    #[test]
    fn the_presets_are_those_of_raypath_planes() {
        let names: Vec<String> = PresetArg::value_variants()
            .iter()
            .map(|p| {
                assert!(p.params().is_some(), "{p:?}");
                super::super::choice_name(p)
            })
            .collect();
        assert_eq!(names, PpeParams::PRESETS);
    }
}
