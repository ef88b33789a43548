//! `raypath loop-closure`: loop-closure detection (IBuILD, Khan 2017, §4.4) or place
//! recognition without temporal consistency (Khan 2017, §4.5) on a CARMEN log (the laser
//! `--laser`, front by default), a KITTI sequence or NCLT session directory (velodyne scans), a
//! rosbag2 bag (LaserScan or PointCloud2; its directory with `metadata.yaml` or its `.mcap`
//! file) — these read through `raypath_io::sequence` — or a folder of PNG/JPEG images (sorted
//! by file name, read by `raypath_io::images`), with the methods of
//! `raypath_place_recognition`: `ibuild` (default), `dbow`, `scan-context`, `hog`, `gist`,
//! `shot`, `polar`, `raw-pixels`. Methods that cannot describe the input's frames (Scan
//! Context and SHOT need point clouds, the polar descriptor planar scans) fail with exit code
//! 2. Images smaller than 128 px on their shorter side are enlarged for the feature stages of
//! `ibuild` and `dbow` (`--upscale`).
//!
//! `--geometric-check` (planar scans): each query's best candidates are re-scored by how well
//! the two scans align (`raypath_place_recognition::GeometricCheck`); scores are then shares
//! of supported points in [0.3, 1].
//!
//! `--database DIR`: the input folder's images are queries against the database folder's
//! images, ground truth by file name ± `--tolerance` frames, optional sequence matching
//! `--sequence D_S` (SeqSLAM) — see `cross`; the modes below do not apply.
//!
//! Modes:
//! - `online` (default): frame by frame, each frame queries the frames at least
//!   `--exclusion-frames` before it, then joins the database; the best candidate is accepted
//!   as a loop closure by the temporal-consistency test of Khan 2017, §4.4.3 (window
//!   `--window` β, threshold `--min-score`).
//! - `kidnapped`: every frame is inserted, then each queries the whole database (frames closer
//!   than `--exclusion-frames` to it, itself included, are dropped from its list); a loop is
//!   a best candidate with a score of at least `--min-score`, with no temporal test.
//!
//! `--ground-truth FILE` (a CARMEN corrected log — the input log itself when it is one —, a
//! bag with reference poses, a KITTI `poses.txt` or a TUM file `t x y z qx qy qz qw`) adds the precision–recall summary:
//! same place = less than `--radius` metres apart (default 2 m with overlapping fields of view
//! for planar scans, 5 m otherwise), pairs closer than `--exclusion-frames` frames or
//! `--exclusion-seconds` seconds are not evaluated. Pairing of poses and frames: see `truth`.
//!
//! DBoW needs a vocabulary trained offline (`--vocabulary FILE`, as written by
//! `--save-vocabulary`); without one it is trained on the input itself, with a warning: that
//! is not the offline protocol of Gálvez-López & Tardós (2012), whose vocabulary comes from
//! independent images, and flatters the method.
//!
//! `--json` prints exactly `{"method", "frames", "ms_per_query", "loops": [{"query", "match",
//! "score"}], "candidates": [{"query", "match", "score"}]}` plus `"summary":
//! {"recall_at_100_precision", "precision_at_100_recall", "max_f1"}` with ground truth.
//! `candidates` holds, for every query with any hypothesis, its best match (higher score =
//! more similar). Frame numbers are 0-based in input order (laser scans for CARMEN and bags,
//! sweeps for NCLT and bags, frame numbers for KITTI). `ms_per_query` is the mean time to describe, query and insert a
//! frame.
//!
//! `--record OUT.mcap` writes a Foxglove recording (see `record`) of the frames' poses — the
//! ground truth paired with them when `--ground-truth` is given, else the input's own
//! (reference, else logged or odometry) poses; an image folder without ground truth has none
//! —: `/tf` `map → base_link` at each posed frame's time (frame index as seconds when the
//! frames have no times), the poses as `/trajectory`, and the accepted loop closures as a
//! line list between the matched frames' positions on `/loops`.

mod cross;
mod input;
mod truth;

use std::path::PathBuf;

use nalgebra::Point3;
use raypath_geometry::Pose3;
use raypath_io::foxglove::{frame, topic};
use raypath_place_recognition::report::LoopClosureReport;
use raypath_place_recognition::{
    BinaryVocabulary, Candidate, Dbow, DbowConfig, Exclusion, FrameTiming, GeometricCheck,
    GeometricCheckConfig, GlobalDescriptorDb, GroundTruth, Ibuild, IbuildConfig, IbuildScore,
    ImageConfig, KidnappedRun, LoopClosure, LoopConfig, OwnedFrame, PlaceError, PlaceRecognizer,
    PlanarDescriptors, PolarContext, PrSummary, RawPixelConfig, RawPixels, SHAPE_DELTA,
    ScanContext, ScanShapeConfig, Shot3dBow, VocabularyConfig, detect_and_describe, detect_loops,
    frame_image, kidnapped_pr, online_pr, run_kidnapped, run_online,
};

use self::input::{Input, read_input};
use self::truth::{TruthParams, ground_truth};
use super::Failure;
use super::record::{RecordArgs, Recording, loop_lines};
use super::source_args::SourceArgs;

/// Place-recognition methods.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Method {
    /// IBuILD incremental binary bag of words (Khan 2017, §4.4).
    Ibuild,
    /// DBoW2-style bag of binary words over an offline vocabulary tree.
    Dbow,
    /// Scan Context (point clouds).
    ScanContext,
    /// HOG global descriptor, cosine similarity.
    Hog,
    /// GIST global descriptor, cosine similarity.
    Gist,
    /// SHOT 3-D bag of words (point clouds).
    Shot,
    /// Polar descriptor of planar scans.
    Polar,
    /// Raw pixels: downsampled, patch-normalised, mean absolute difference (SeqSLAM's
    /// single-image comparison).
    RawPixels,
}

/// Evaluation settings.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Mode {
    /// Loop closure: incremental database, temporal consistency.
    Online,
    /// Kidnapped robot: full similarity matrix, no temporal consistency.
    Kidnapped,
}

/// Arguments of `raypath loop-closure`.
#[derive(clap::Args)]
pub struct Args {
    /// A CARMEN log, a KITTI sequence or NCLT session directory, a rosbag2 bag (directory
    /// with metadata.yaml, or .mcap file) or a folder of PNG/JPEG images.
    pub input: PathBuf,
    /// The place-recognition method.
    #[arg(long, value_enum, default_value_t = Method::Ibuild)]
    pub method: Method,
    /// Online loop closure or kidnapped-robot place recognition.
    #[arg(long, value_enum, default_value_t = Mode::Online)]
    pub mode: Mode,
    /// Ground-truth poses: CARMEN (corrected) log, bag with reference poses, KITTI poses.txt
    /// or TUM file.
    #[arg(long, value_name = "POSES")]
    pub ground_truth: Option<PathBuf>,
    /// DBoW vocabulary file (without it, dbow trains one on the input, with a warning).
    #[arg(long, value_name = "FILE")]
    pub vocabulary: Option<PathBuf>,
    /// Write the DBoW vocabulary used (trained or read) to this file.
    #[arg(long, value_name = "FILE")]
    pub save_vocabulary: Option<PathBuf>,
    /// IBuILD matching threshold δ, bits (default 80).
    #[arg(long, value_name = "BITS")]
    pub delta: Option<u32>,
    /// IBuILD similarity: the thesis' normalised modified Jaccard index (`printed`) or our
    /// symmetric, unnormalised variant (`symmetric`).
    #[arg(long, value_enum, default_value_t = IbuildScoreArg::Printed)]
    pub ibuild_score: IbuildScoreArg,
    /// Frames at least this far apart are compared and evaluated.
    #[arg(long, default_value_t = 50, value_name = "N")]
    pub exclusion_frames: usize,
    /// Pairs closer in time than this are not evaluated, seconds (when frame times are known).
    #[arg(long, default_value_t = 30.0, value_name = "S")]
    pub exclusion_seconds: f64,
    /// Temporal-consistency window β, frames (Khan 2017, §4.6.1).
    #[arg(long, default_value_t = 10, value_name = "BETA")]
    pub window: usize,
    /// Accept only loops whose score is at least this.
    #[arg(
        long,
        default_value_t = 0.0,
        value_name = "S",
        allow_hyphen_values = true
    )]
    pub min_score: f64,
    /// Switch the temporal-consistency test off (online mode).
    #[arg(long)]
    pub no_temporal_consistency: bool,
    /// Ablation: accept an unconstrained loop only after this many consistent detections.
    #[arg(long, default_value_t = 1, value_name = "K")]
    pub consecutive: usize,
    /// Same place: less than this many metres apart (default 2 for planar scans, 5 otherwise).
    #[arg(long, value_name = "M")]
    pub radius: Option<f64>,
    /// Field of view of planar scans for the ground truth, degrees (default: the scan's span).
    #[arg(long, value_name = "DEG")]
    pub fov: Option<f64>,
    /// Use only the first N frames.
    #[arg(long, value_name = "N")]
    pub max_frames: Option<usize>,
    /// Kidnapped mode: keep this many best candidates per query (default all).
    #[arg(long, value_name = "K")]
    pub top_k: Option<usize>,
    /// Database folder of images: the input folder's images are the queries, scored against
    /// these (same file name = same place); see `cross`.
    #[arg(long, value_name = "DIR")]
    pub database: Option<PathBuf>,
    /// With --database: a query matches the database frames within N frames of the frame
    /// with its file name.
    #[arg(long, default_value_t = 2, value_name = "N")]
    pub tolerance: usize,
    /// With --database: sequence matching (SeqSLAM) over the last D_S queries on the
    /// method's scores.
    #[arg(long, value_name = "D_S")]
    pub sequence: Option<usize>,
    /// Enlarge images K times before the feature stages of ibuild and dbow (default: the
    /// smallest K that gives images a shorter side of at least 128 px; 1 for larger images).
    #[arg(long, value_name = "K")]
    pub upscale: Option<u32>,
    /// Planar scans: re-score each query's best candidates by how well the two scans align
    /// (point-to-line ICP from 8 headings; score = share of points both scans support).
    #[arg(long)]
    pub geometric_check: bool,
    /// Planar scans, `--method ibuild`: describe each scan by binary shape descriptors made on
    /// the scan instead of FAST/BRIEF on the rasterised scan (δ defaults to 35 then).
    #[arg(long)]
    pub scan_shapes: bool,
    /// How to read the input and the ground truth.
    #[command(flatten)]
    pub source: SourceArgs,
    /// A Foxglove recording of the run.
    #[command(flatten)]
    pub record: RecordArgs,
}

/// What a run produced.
struct Outcome {
    method: &'static str,
    /// Per query, candidates sorted by score (the exclusion window applied).
    candidates: Vec<Vec<Candidate>>,
    timings: Vec<FrameTiming>,
}

fn loop_config(args: &Args) -> LoopConfig {
    LoopConfig {
        min_score: args.min_score,
        temporal_window: args.window,
        temporal_consistency: args.mode == Mode::Online && !args.no_temporal_consistency,
        consecutive: args.consecutive,
    }
}

fn check_args(args: &Args) -> Result<(), Failure> {
    let bad = |m: &str| Err(Failure::input(m));
    if !args.min_score.is_finite() {
        return bad("--min-score: must be a finite number");
    }
    if !(args.exclusion_seconds.is_finite() && args.exclusion_seconds >= 0.0) {
        return bad("--exclusion-seconds: must be finite and non-negative");
    }
    if args.radius.is_some_and(|r| !(r.is_finite() && r > 0.0)) {
        return bad("--radius: must be positive");
    }
    if args.fov.is_some_and(|f| !(f.is_finite() && f > 0.0)) {
        return bad("--fov: must be positive");
    }
    if args.top_k == Some(0) || args.max_frames == Some(0) {
        return bad("--top-k and --max-frames must be at least 1");
    }
    if (args.vocabulary.is_some() || args.save_vocabulary.is_some()) && args.method != Method::Dbow
    {
        return bad("--vocabulary and --save-vocabulary apply to --method dbow only");
    }
    if args.delta.is_some() && args.method != Method::Ibuild {
        return bad("--delta applies to --method ibuild only");
    }
    if args.scan_shapes && args.method != Method::Ibuild {
        return bad("--scan-shapes applies to --method ibuild only");
    }
    if args.upscale == Some(0) {
        return bad("--upscale: must be at least 1");
    }
    if args.database.is_none() && args.sequence.is_some() {
        return bad("--sequence applies with --database only");
    }
    Ok(())
}

/// Runs `raypath loop-closure`.
pub fn run(args: &Args) -> Result<(), Failure> {
    check_args(args)?;
    if args.database.is_some() {
        return cross::run(args);
    }
    let mut recording = Recording::open(&args.record)?;
    let input = read_input(&args.input, &args.source, args.max_frames)?;
    if args.scan_shapes && !input.is_planar() {
        return Err(Failure::input(format!(
            "{}: --scan-shapes needs planar scans",
            args.input.display()
        )));
    }
    let truth = match &args.ground_truth {
        None => None,
        Some(path) => {
            let params = TruthParams {
                radius_m: args
                    .radius
                    .unwrap_or(if input.is_planar() { 2.0 } else { 5.0 }),
                fov_rad: args.fov.map(f64::to_radians),
                exclusion: Exclusion {
                    frames: args.exclusion_frames,
                    seconds: args.exclusion_seconds,
                },
            };
            Some((path, ground_truth(path, &args.source, &input, &params)?))
        }
    };
    let execute = Execute {
        args,
        input: &input,
    };
    let outcome = if args.geometric_check {
        dispatch(args, &input, WithCheck(execute))?
    } else {
        dispatch(args, &input, execute)?
    };
    let config = loop_config(args);
    let place = |e: PlaceError| Failure::input(format!("{}: {e}", args.input.display()));
    let loops = detect_loops(&config, &outcome.candidates).map_err(place)?;
    let summary = match &truth {
        None => None,
        Some((_, (gt, _))) => Some(evaluate(args, &config, &outcome, gt).map_err(place)?),
    };
    if let Some(recording) = &mut recording {
        let poses = match &truth {
            Some((_, (_, paired))) => Some(paired.as_slice()),
            None => input.poses.as_deref(),
        };
        record(recording, &input, poses.unwrap_or_default(), &loops)?;
    }
    if super::console::json() {
        let mut doc = super::to_json(&report(&input, &outcome, &loops, summary.as_ref()))?;
        super::record::finish(recording, Some(&mut doc))?;
        println!("{doc}");
    } else {
        let truth_info = truth
            .as_ref()
            .map(|(p, (gt, _))| (p.as_path(), gt, summary));
        print_text(args, &input, &outcome, &loops, truth_info);
        super::record::finish(recording, None)?;
    }
    Ok(())
}

/// `--record`: `/tf` at each frame with a pose (at its time, else its index in seconds), the
/// poses as `/trajectory`, and the loops between posed frames as segments on `/loops`.
fn record(
    recording: &mut Recording,
    input: &Input,
    poses: &[Option<Pose3>],
    loops: &[LoopClosure],
) -> Result<(), Failure> {
    let stamp = |i: usize| {
        input
            .times
            .as_ref()
            .and_then(|t| t.get(i).copied())
            .unwrap_or(i as f64)
    };
    let mut trajectory = Vec::with_capacity(poses.len());
    for (i, pose) in poses.iter().enumerate() {
        if let Some(pose) = pose.filter(Pose3::is_finite) {
            recording.robot_pose(stamp(i), &pose)?;
            trajectory.push(pose);
        }
    }
    let end = recording.end_stamp();
    recording.trajectory(topic::TRAJECTORY, end, &trajectory)?;
    let position = |i: usize| {
        poses
            .get(i)
            .copied()
            .flatten()
            .filter(Pose3::is_finite)
            .map(|p| Point3::from(p.translation()))
    };
    let pairs: Vec<(Point3<f64>, Point3<f64>)> = loops
        .iter()
        .filter_map(|l| Some((position(l.query)?, position(l.matched)?)))
        .collect();
    recording.scene(topic::LOOPS, end, frame::MAP, &loop_lines(&pairs))
}

fn evaluate(
    args: &Args,
    config: &LoopConfig,
    outcome: &Outcome,
    gt: &GroundTruth,
) -> Result<PrSummary, PlaceError> {
    let curve = match args.mode {
        Mode::Online => online_pr(&outcome.candidates, gt, config, 200)?,
        Mode::Kidnapped => kidnapped_pr(&outcome.candidates, gt)?,
    };
    Ok(curve.summary())
}

/// `--ibuild-score` values.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum IbuildScoreArg {
    /// Khan 2017, §4.4.3 as printed, normalised over the hypotheses.
    Printed,
    /// Ours: symmetric in the query's and the hypothesis' missing words, not normalised.
    Symmetric,
}

/// What to do with the recognizer `--method` names.
trait WithRecognizer {
    /// The result.
    type Output;
    /// Runs the recognizer.
    fn run<R: PlaceRecognizer + Sync>(self, recognizer: R) -> Result<Self::Output, Failure>;
}

/// The image configuration of the feature methods: `--upscale`, else enlarged to a shorter
/// side of at least 128 px (images only; other frames as they are).
fn feature_images(args: &Args, input: &Input) -> Result<ImageConfig, Failure> {
    let upscale = match args.upscale {
        Some(k) => k,
        None if matches!(input.source, input::Source::Images(_)) && !input.labels.is_empty() => {
            let place = |e: PlaceError| Failure::input(format!("{}: {e}", args.input.display()));
            let first = input.frame(0).map_err(place)?;
            match first {
                OwnedFrame::Image(image) => {
                    ImageConfig::upscale_for(image.width(), image.height(), 128)
                }
                _ => 1,
            }
        }
        None => 1,
    };
    Ok(ImageConfig {
        upscale,
        ..ImageConfig::default()
    })
}

/// Builds the recognizer `--method` names and hands it to `with`; `vocabulary_input` trains
/// DBoW's vocabulary when `--vocabulary` is absent.
fn dispatch<W: WithRecognizer>(
    args: &Args,
    vocabulary_input: &Input,
    with: W,
) -> Result<W::Output, Failure> {
    let place = |e: PlaceError| Failure::input(format!("{}: {e}", args.input.display()));
    match args.method {
        Method::Ibuild => {
            let (planar, default_delta) = if args.scan_shapes {
                let shape = ScanShapeConfig::default();
                (PlanarDescriptors::Shape(shape), SHAPE_DELTA)
            } else {
                (PlanarDescriptors::Image, IbuildConfig::default().delta)
            };
            let config = IbuildConfig {
                delta: args.delta.unwrap_or(default_delta),
                planar,
                beta: args.window.max(1),
                score: match args.ibuild_score {
                    IbuildScoreArg::Printed => IbuildScore::Printed,
                    IbuildScoreArg::Symmetric => IbuildScore::Symmetric,
                },
                image: feature_images(args, vocabulary_input)?,
                ..IbuildConfig::default()
            };
            with.run(Ibuild::new(config).map_err(place)?)
        }
        Method::Dbow => {
            let config = DbowConfig {
                image: feature_images(args, vocabulary_input)?,
                ..DbowConfig::default()
            };
            let vocabulary = dbow_vocabulary(args, vocabulary_input, &config)?;
            with.run(Dbow::new(vocabulary, config))
        }
        Method::ScanContext => with.run(ScanContext::new(Default::default()).map_err(place)?),
        Method::Hog => with.run(GlobalDescriptorDb::hog(
            Default::default(),
            Default::default(),
        )),
        Method::Gist => with
            .run(GlobalDescriptorDb::gist(Default::default(), Default::default()).map_err(place)?),
        Method::Shot => with.run(Shot3dBow::new(Default::default()).map_err(place)?),
        Method::Polar => with.run(PolarContext::new(Default::default()).map_err(place)?),
        Method::RawPixels => with.run(RawPixels::new(RawPixelConfig::default()).map_err(place)?),
    }
}

/// Runs the recognizer in the mode of `--mode` on the input.
struct Execute<'a> {
    args: &'a Args,
    input: &'a Input,
}

impl WithRecognizer for Execute<'_> {
    type Output = Outcome;
    fn run<R: PlaceRecognizer + Sync>(self, recognizer: R) -> Result<Outcome, Failure> {
        execute(recognizer, self.args, self.input)
    }
}

/// `--geometric-check`: the recognizer wrapped in a [`GeometricCheck`] before it runs.
struct WithCheck<'a>(Execute<'a>);

impl WithRecognizer for WithCheck<'_> {
    type Output = Outcome;
    fn run<R: PlaceRecognizer + Sync>(self, recognizer: R) -> Result<Outcome, Failure> {
        let args = self.0.args;
        let config = GeometricCheckConfig {
            exclude_recent: args.exclusion_frames,
            ..GeometricCheckConfig::default()
        };
        let checked = GeometricCheck::new(recognizer, config)
            .map_err(|e| Failure::input(format!("{}: {e}", args.input.display())))?;
        self.0.run(checked)
    }
}

/// Runs a recognizer in the chosen mode.
fn execute<R: PlaceRecognizer + Sync>(
    mut recognizer: R,
    args: &Args,
    input: &Input,
) -> Result<Outcome, Failure> {
    let place = |e: PlaceError| Failure::input(format!("{}: {e}", args.input.display()));
    let n = input.len();
    let bar = super::console::progress(n, "place recognition");
    let source = |i| {
        bar.inc(1);
        input.frame(i)
    };
    match args.mode {
        Mode::Online => {
            let run =
                run_online(&mut recognizer, n, source, args.exclusion_frames).map_err(place)?;
            Ok(Outcome {
                method: run.method,
                candidates: run.candidates,
                timings: run.timings,
            })
        }
        Mode::Kidnapped => {
            let top_k = args.top_k.map(|k| k + 2 * args.exclusion_frames);
            let run = run_kidnapped(&mut recognizer, n, source, top_k).map_err(place)?;
            Ok(kidnapped_outcome(run, args.exclusion_frames, args.top_k))
        }
    }
}

/// Drops the frames closer than `exclusion` to each query (itself included) and keeps `top_k`.
fn kidnapped_outcome(run: KidnappedRun, exclusion: usize, top_k: Option<usize>) -> Outcome {
    let candidates = run
        .candidates
        .into_iter()
        .enumerate()
        .map(|(i, list)| {
            let kept = list
                .into_iter()
                .filter(|c| c.frame.abs_diff(i) >= exclusion.max(1));
            kept.take(top_k.unwrap_or(usize::MAX)).collect()
        })
        .collect();
    Outcome {
        method: run.method,
        candidates,
        timings: run.timings,
    }
}

/// The DBoW vocabulary: read from `--vocabulary`, or trained on the input (with a warning).
fn dbow_vocabulary(
    args: &Args,
    input: &Input,
    config: &DbowConfig,
) -> Result<BinaryVocabulary, Failure> {
    let vocabulary = match &args.vocabulary {
        Some(path) => {
            let file = std::fs::File::open(path)
                .map_err(|e| Failure::input(format!("{}: {e}", path.display())))?;
            BinaryVocabulary::from_reader(std::io::BufReader::new(file))
                .map_err(|e| Failure::input(format!("{}: {e}", path.display())))?
        }
        None => {
            if args.database.is_some() {
                super::console::warn(
                    "no --vocabulary: training the DBoW vocabulary on the database images (the \
                     queries are not used); the offline protocol trains it on independent images",
                );
            } else {
                super::console::warn(
                    "no --vocabulary: training the DBoW vocabulary on the input itself; this is \
                     not the offline protocol (a vocabulary from independent images) and \
                     flatters DBoW",
                );
            }
            let place = |e: PlaceError| Failure::input(format!("{}: {e}", args.input.display()));
            let mut images = Vec::with_capacity(input.len());
            for i in 0..input.len() {
                let frame = input.frame(i).map_err(place)?;
                let image = frame_image(&frame.as_frame(), &config.image).map_err(place)?;
                let (_, descriptors) = detect_and_describe(&image, &config.features)
                    .map_err(|e| place(PlaceError::BadInput(format!("frame {i}: {e}"))))?;
                images.push(descriptors);
            }
            BinaryVocabulary::train(&images, &VocabularyConfig::default(), 0).map_err(place)?
        }
    };
    if let Some(path) = &args.save_vocabulary {
        let write = || -> std::io::Result<()> {
            let file = std::fs::File::create(path)?;
            vocabulary.to_writer(std::io::BufWriter::new(file))
        };
        write().map_err(|e| Failure::internal(format!("{}: {e}", path.display())))?;
    }
    Ok(vocabulary)
}

fn ms_per_query(outcome: &Outcome) -> f64 {
    FrameTiming::mean(&outcome.timings).total_s * 1e3
}

fn report(
    input: &Input,
    outcome: &Outcome,
    loops: &[LoopClosure],
    summary: Option<&PrSummary>,
) -> LoopClosureReport {
    LoopClosureReport::new(
        outcome.method,
        input.len(),
        ms_per_query(outcome),
        loops,
        &outcome.candidates,
        |i| input.labels.get(i).copied().unwrap_or(i),
        summary.copied(),
    )
}

fn print_text(
    args: &Args,
    input: &Input,
    outcome: &Outcome,
    loops: &[LoopClosure],
    truth: Option<(&std::path::Path, &GroundTruth, Option<PrSummary>)>,
) {
    let mean = FrameTiming::mean(&outcome.timings);
    let mode = match args.mode {
        Mode::Online => "online",
        Mode::Kidnapped => "kidnapped",
    };
    println!(
        "{}: {} {}, method {}, mode {mode}",
        args.input.display(),
        input.len(),
        input.kind(),
        outcome.method
    );
    println!(
        "{:.2} ms per frame (describe {:.2}, query {:.2}, insert {:.2})",
        mean.total_s * 1e3,
        mean.describe_s * 1e3,
        mean.query_s * 1e3,
        mean.insert_s * 1e3
    );
    let with_candidates = outcome.candidates.iter().filter(|c| !c.is_empty()).count();
    println!(
        "{with_candidates} frames with candidates, {} accepted loop closures",
        loops.len()
    );
    let label = |i: usize| input.labels.get(i).copied().unwrap_or(i);
    for l in loops.iter().take(20) {
        println!(
            "  {} -> {} (score {:.4})",
            label(l.query),
            label(l.matched),
            l.score
        );
    }
    if loops.len() > 20 {
        println!("  … {} more (--json lists all)", loops.len() - 20);
    }
    if let Some((path, gt, Some(s))) = truth {
        println!(
            "ground truth {}: {} true pairs; recall at 100% precision {:.4}, precision at 100% \
             recall {:.4}, max F1 {:.4}",
            path.display(),
            gt.true_pairs(),
            s.recall_at_100_precision,
            s.precision_at_100_recall,
            s.max_f1
        );
        if gt.true_pairs() == 0 {
            println!("warning: the ground truth has no evaluable revisit; the summary is empty");
        }
    }
}
