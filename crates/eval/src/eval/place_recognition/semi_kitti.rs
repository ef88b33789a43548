//! Section 3: semi-synthetic KITTI — simulated HDL-64E scans with intensity along the **real**
//! trajectories of `kitti-poles/00, 02, 05, 06` (real poses and times, real pole layout;
//! simulated street scenery, scans and intensities). The second pass (from the first frame that
//! revisits an earlier place) is seen by a "night" camera stand-in and scanned in a changed
//! world (half of the parked cars gone, winter foliage). Intensity vs range images vs the
//! camera stand-in (HOG, GIST, IBuILD), Scan Context and DBoW2-style, kidnapped and online.
//!
//! In stages: one unit per sequence ([`run_sequence`]), the section ([`page::section`]) from
//! their results.

mod page;
mod rows;

use std::ops::Range;
use std::sync::Arc;

use anyhow::{Context, Result};
use rayon::prelude::*;
use raypath_geometry::{PointCloud, Pose3};
use raypath_place_recognition::{BinaryVocabulary, EquirectConfig, GroundTruth, equirectangular};
use raypath_sim::datasets::DEFAULT_SEED;
use raypath_sim::scene3::Scene3;
use raypath_sim::semi_kitti::SemiKittiDrive;
use serde::{Deserialize, Serialize};
use serde_json::Value;

use super::camera::{Lighting, camera_image};
use super::runner::{Input, MethodResult, Views};
use super::{FIGURES, methods, truth};
use crate::eval::EvalContext;

pub use page::section;

/// Seed of the camera stand-in and of the second-pass scans.
const SEED: u64 = 2017;
/// Frames simulated at once (in parallel) before they are fed to the methods.
const CHUNK: usize = 8;

/// What to simulate of one sequence.
struct Plan {
    sequence: &'static str,
    stride: usize,
    /// Input frame ranges to keep (`None`: the whole drive).
    ranges: Option<Vec<Range<usize>>>,
}

fn plans(quick: bool) -> Vec<Plan> {
    if quick {
        // Sequence 00: the first pass 390–949 and its revisit 3400–3859 (every 10th frame).
        return vec![Plan {
            sequence: "00",
            stride: 10,
            ranges: Some(vec![390..950, 3400..3860]),
        }];
    }
    let stride = std::env::var("PLACE_RECOGNITION_STRIDE")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(10);
    ["00", "02", "05", "06"]
        .into_iter()
        .map(|sequence| Plan {
            sequence,
            stride,
            ranges: None,
        })
        .collect()
}

/// The returns of an organized simulated cloud (finite points, with intensity).
fn returns_only(cloud: &PointCloud) -> PointCloud {
    let keep: Vec<usize> = (0..cloud.len())
        .filter(|&i| cloud.points[i].iter().all(|v| v.is_finite()))
        .collect();
    let mut out = PointCloud::from_points(keep.iter().map(|&i| cloud.points[i]).collect());
    out.intensity = cloud
        .intensity
        .as_ref()
        .map(|v| keep.iter().filter_map(|&i| v.get(i).copied()).collect());
    out
}

/// The changed world of the second pass: every other parked car removed (by index), crowns at
/// the winter leaf factor 0.6. Returns the scene and the number of cars removed.
fn changed_scene(drive: &SemiKittiDrive) -> Result<(Scene3, usize)> {
    let mut world = drive.world().clone();
    let before = world.cars.len();
    world.cars = world
        .cars
        .iter()
        .enumerate()
        .filter(|(i, _)| i % 2 == 0)
        .map(|(_, c)| *c)
        .collect();
    world.foliage = 0.6;
    Ok((world.build_scene()?, before - world.cars.len()))
}

/// Simulates the selected scan `index` of the drive and makes its views.
fn views(
    drive: &SemiKittiDrive,
    index: usize,
    second_pass: bool,
    changed: Option<&Scene3>,
    needs_cloud: bool,
    feature_inputs: &[Input],
) -> Result<Views> {
    let cloud = match (second_pass, changed) {
        (true, Some(scene)) => {
            let pose = drive.world_from_velo[index];
            returns_only(&drive.lidar().scan(scene, &pose, SEED, index as u64)?.cloud)
        }
        _ => drive.scan(index)?,
    };
    let images = equirectangular(&cloud, &EquirectConfig::default())?;
    let lighting = if second_pass {
        Lighting::Night
    } else {
        Lighting::Day
    };
    let mut views = Views {
        camera: Some(camera_image(
            &images.intensity,
            lighting,
            SEED,
            index as u64,
        )),
        cloud: needs_cloud.then_some(cloud),
        intensity: images.intensity,
        range: images.range,
        features: [None, None, None],
    };
    views.extract(feature_inputs)?;
    Ok(views)
}

/// One sequence of the section: its table rows, pictures and JSON (the cells as the page
/// prints them), or `None` in [`SequenceResult::rows`] when `kitti-poles/<sequence>` is absent.
#[derive(Serialize, Deserialize)]
pub struct SequenceResult {
    /// The sequence (`00` …).
    pub sequence: String,
    /// Its rows (`None`: absent).
    pub rows: Option<Box<SequenceRows>>,
}

/// The rows of one sequence.
#[derive(Serialize, Deserialize)]
pub struct SequenceRows {
    /// The row of the table of sequences.
    pub info: Vec<String>,
    /// Rows of the results table (one per method, the δ sweep left out).
    pub results: Vec<Vec<String>>,
    /// Rows of the δ-sweep table.
    pub sweep: Vec<Vec<String>>,
    /// Rows of the thesis-claim table (HOG, GIST, IBuILD), without the "comparable" cell.
    pub claims: Vec<Vec<String>>,
    /// The aim row (IBuILD against Scan Context).
    pub aim: Vec<String>,
    /// The same for the symmetric IBuILD (shown, not counted in the summary).
    pub symmetric_aim: Vec<String>,
    /// The PR pictures (markdown; the PNGs are written by the unit).
    pub pictures: String,
    /// The sequence's figures for the JSON.
    pub json: Value,
}

/// The sequences of this run (the units of the section).
pub fn sequences(quick: bool) -> Vec<&'static str> {
    plans(quick).into_iter().map(|p| p.sequence).collect()
}

/// The selected frames of a drive: the scans of the drive within the plan's ranges.
struct Selection {
    drive: SemiKittiDrive,
    /// Indices of the drive's scans used.
    selected: Vec<usize>,
    poses: Vec<Pose3>,
    times: Vec<f64>,
}

/// The drive of `plan` and its selected frames; `None` when the sequence is absent.
fn select(ctx: &EvalContext, plan: &Plan) -> Result<Option<Selection>> {
    let Some(mut config) = ctx.semi_kitti_config(plan.sequence, None)? else {
        return Ok(None);
    };
    config.stride = plan.stride;
    config.labels = false;
    if let Some(last) = plan
        .ranges
        .as_ref()
        .and_then(|r| r.iter().map(|r| r.end).max())
    {
        config.max_scans = Some(last.div_ceil(plan.stride));
    }
    let drive = SemiKittiDrive::new(&config, DEFAULT_SEED)?;
    let selected: Vec<usize> = (0..drive.len())
        .filter(|&i| {
            plan.ranges
                .as_ref()
                .is_none_or(|rs| rs.iter().any(|r| r.contains(&drive.frames[i])))
        })
        .collect();
    let poses = selected.iter().map(|&i| drive.world_from_velo[i]).collect();
    let times = selected.iter().map(|&i| drive.times_s[i]).collect();
    Ok(Some(Selection {
        drive,
        selected,
        poses,
        times,
    }))
}

/// Feeds the selected frames to every method online (from `second` on: the second pass, in
/// the `changed` world) and scores them against `truth`.
fn run_methods(
    ctx: &EvalContext,
    sequence: &str,
    s: &Selection,
    truth: &GroundTruth,
    (second, changed): (Option<usize>, Option<&Scene3>),
    vocabulary: Option<&Arc<BinaryVocabulary>>,
) -> Result<Vec<MethodResult>> {
    let mut runners = methods::semi_kitti(vocabulary)?;
    let needs_cloud = runners.iter().any(|r| r.input() == Input::Cloud);
    let feature_inputs: Vec<Input> = runners
        .iter()
        .filter(|r| r.uses_features())
        .map(|r| r.input())
        .collect();
    let limits = truth::online_limits(s.selected.len(), Some(&s.times));
    let bar = ctx.progress(s.selected.len() as u64, &format!("semi-kitti {sequence}"));
    for (c, chunk) in s.selected.chunks(CHUNK).enumerate() {
        let frames: Vec<Views> = chunk
            .par_iter()
            .enumerate()
            .map(|(k, &i)| {
                let pass2 = second.is_some_and(|s| c * CHUNK + k >= s);
                views(&s.drive, i, pass2, changed, needs_cloud, &feature_inputs)
            })
            .collect::<Result<_>>()?;
        for (k, frame) in frames.iter().enumerate() {
            let sample = frame.sample();
            let limit = limits[c * CHUNK + k];
            runners.par_iter_mut().for_each(|r| r.step(&sample, limit));
        }
        bar.inc(chunk.len() as u64);
    }
    bar.finish_and_clear();
    Ok(runners
        .par_iter_mut()
        .map(|r| r.evaluate(truth, true))
        .collect())
}

/// The unit of `sequence`: simulates its drive, runs every method, writes the PR pictures and
/// returns the rows.
pub fn run_sequence(
    ctx: &EvalContext,
    sequence: &str,
    vocabulary: Option<&Arc<BinaryVocabulary>>,
) -> Result<SequenceResult> {
    let plan = plans(ctx.quick)
        .into_iter()
        .find(|p| p.sequence == sequence)
        .with_context(|| format!("no semi-synthetic sequence {sequence:?} in this run"))?;
    let started = std::time::Instant::now();
    let Some(s) = select(ctx, &plan)? else {
        return Ok(SequenceResult {
            sequence: sequence.to_owned(),
            rows: None,
        });
    };
    let truth = truth::spatial(&s.poses, &s.times)?;
    let second = truth::first_revisit(&truth);
    let (changed, cars_removed) = match second {
        Some(_) => {
            let (scene, removed) = changed_scene(&s.drive)?;
            (Some(scene), removed)
        }
        None => (None, 0),
    };
    let pass2 = (second, changed.as_ref());
    let results = run_methods(ctx, sequence, &s, &truth, pass2, vocabulary)?;
    let seconds = started.elapsed().as_secs_f64();
    eprintln!(
        "place-recognition: semi-kitti {sequence} done in {seconds:.0} s ({} frames)",
        s.selected.len()
    );
    let facts = Facts {
        second,
        cars_removed,
        seconds,
    };
    let figures = ctx.figure_dir(FIGURES)?;
    let rows = rows::rows(&plan, &s, &truth, &facts, &results, &figures)?;
    Ok(SequenceResult {
        sequence: sequence.to_owned(),
        rows: Some(Box::new(rows)),
    })
}

/// What the sequence's info row and JSON say besides the selection and the ground truth.
struct Facts {
    /// The first frame of the second pass (index into the selection).
    second: Option<usize>,
    cars_removed: usize,
    /// Time of the unit so far.
    seconds: f64,
}
