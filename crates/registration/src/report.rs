//! Typed reports of a registration and of an odometry run: what `raypath register --json`
//! prints (the JSON keys are a contract).

use raypath_geometry::Pose3;
use serde::Serialize;

use crate::{OdometryStep, Registration};

/// A pose as translation, quaternion and roll/pitch/yaw.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct PoseReport {
    /// Translation, metres.
    pub translation_m: [f64; 3],
    /// Rotation quaternion `[x, y, z, w]`.
    pub rotation_xyzw: [f64; 4],
    /// Roll, pitch, yaw, degrees.
    pub rpy_deg: [f64; 3],
}

impl From<&Pose3> for PoseReport {
    fn from(pose: &Pose3) -> Self {
        let q = pose.rotation();
        let t = pose.translation();
        let (roll, pitch, yaw) = pose.rpy();
        Self {
            translation_m: [t.x, t.y, t.z],
            rotation_xyzw: [q.i, q.j, q.k, q.w],
            rpy_deg: [roll.to_degrees(), pitch.to_degrees(), yaw.to_degrees()],
        }
    }
}

/// How a registration ended, besides its iterations.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct FitReport {
    /// [`Registration::converged`].
    pub converged: bool,
    /// [`Registration::fitness`].
    pub fitness: f64,
    /// [`Registration::rmse_m`].
    pub rmse_m: f64,
    /// [`Registration::correspondences`].
    pub correspondences: usize,
    /// [`Registration::source_points`].
    pub source_points: usize,
}

impl From<&Registration> for FitReport {
    fn from(r: &Registration) -> Self {
        Self {
            converged: r.converged,
            fitness: r.fitness,
            rmse_m: r.rmse_m,
            correspondences: r.correspondences,
            source_points: r.source_points,
        }
    }
}

/// Two scans registered ([`crate::register`]).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct PairReport {
    /// Always `"pair"`.
    pub mode: &'static str,
    /// The source scan's name.
    pub source: String,
    /// The target scan's name.
    pub target: String,
    /// The estimate.
    pub target_from_source: PoseReport,
    /// Gauss–Newton iterations run.
    pub iterations: usize,
    /// How it ended.
    #[serde(flatten)]
    pub fit: FitReport,
    /// Time of the registration, seconds.
    pub seconds: f64,
}

impl PairReport {
    /// The report of `found`, registering `source` to `target` in `seconds`.
    pub fn new(source: String, target: String, found: &Registration, seconds: f64) -> Self {
        Self {
            mode: "pair",
            source,
            target,
            target_from_source: PoseReport::from(&found.target_from_source),
            iterations: found.iterations,
            fit: FitReport::from(found),
            seconds,
        }
    }
}

/// The error of an estimated relative pose against the reference's.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct StepError {
    /// Angle of `truth⁻¹ · estimate`, degrees.
    pub rotation_deg: f64,
    /// Length of its translation, metres.
    pub translation_m: f64,
    /// Length of the reference's translation, metres.
    pub distance_m: f64,
}

impl StepError {
    /// The error of `estimate` against `truth` (both relative poses).
    pub fn new(truth: &Pose3, estimate: &Pose3) -> Self {
        let d = truth.inverse() * *estimate;
        Self {
            rotation_deg: d.rotation().angle().to_degrees(),
            translation_m: d.translation().norm(),
            distance_m: truth.translation().norm(),
        }
    }
}

/// One scan of an odometry run ([`crate::Odometry::register_frame`]).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct StepReport {
    /// The scan's index.
    pub frame: usize,
    /// The scan's pose in the odometry frame.
    #[serde(flatten)]
    pub pose: PoseReport,
    /// Iterations of its registration (`None` for the first scan).
    pub iterations: Option<usize>,
    /// How its registration ended (absent for the first scan).
    #[serde(flatten)]
    pub fit: Option<FitReport>,
    /// [`OdometryStep::sigma_m`].
    pub sigma_m: f64,
    /// [`OdometryStep::map_points`].
    pub map_points: usize,
    /// Time of the step, seconds.
    pub seconds: f64,
    /// The error of the relative pose to the previous scan against the reference.
    pub error: Option<StepError>,
}

impl StepReport {
    /// The report of scan `frame`'s `step`, which took `seconds`.
    pub fn new(frame: usize, step: &OdometryStep, seconds: f64, error: Option<StepError>) -> Self {
        Self {
            frame,
            pose: PoseReport::from(&step.world_from_sensor),
            iterations: step.registration.as_ref().map(|r| r.iterations),
            fit: step.registration.as_ref().map(FitReport::from),
            sigma_m: step.sigma_m,
            map_points: step.map_points,
            seconds,
            error,
        }
    }
}

/// The relative-pose errors of an odometry run against its reference.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct SequenceSummary {
    /// Relative poses compared.
    pub pairs: usize,
    /// Mean rotation error, degrees.
    pub rotation_error_deg_mean: f64,
    /// Largest rotation error, degrees.
    pub rotation_error_deg_max: f64,
    /// Mean translation error, metres.
    pub translation_error_m_mean: f64,
    /// Largest translation error, metres.
    pub translation_error_m_max: f64,
    /// Summed translation error over summed reference distance, percent.
    pub translation_error_percent: f64,
    /// Median time of the registered steps, seconds.
    pub seconds_median: Option<f64>,
}

impl SequenceSummary {
    /// The summary over `steps` with an error (`None` when none has one). Non-finite errors
    /// are left out of the means.
    pub fn of(steps: &[StepReport]) -> Option<Self> {
        let errors: Vec<&StepError> = steps.iter().filter_map(|s| s.error.as_ref()).collect();
        if errors.is_empty() {
            return None;
        }
        let field = |get: fn(&StepError) -> f64| -> Vec<f64> {
            errors
                .iter()
                .map(|e| get(e))
                .filter(|v| v.is_finite())
                .collect()
        };
        let rot = field(|e| e.rotation_deg);
        let trans = field(|e| e.translation_m);
        let dist = field(|e| e.distance_m);
        let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
        let max = |v: &[f64]| v.iter().copied().fold(0.0, f64::max);
        let mut seconds: Vec<f64> = steps
            .iter()
            .filter(|s| s.iterations.is_some())
            .map(|s| s.seconds)
            .filter(|v| v.is_finite())
            .collect();
        seconds.sort_by(f64::total_cmp);
        Some(Self {
            pairs: errors.len(),
            rotation_error_deg_mean: mean(&rot),
            rotation_error_deg_max: max(&rot),
            translation_error_m_mean: mean(&trans),
            translation_error_m_max: max(&trans),
            translation_error_percent: 100.0 * trans.iter().sum::<f64>() / dist.iter().sum::<f64>(),
            seconds_median: seconds.get(seconds.len() / 2).copied(),
        })
    }
}

/// An odometry run over a sequence.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SequenceReport {
    /// Always `"sequence"`.
    pub mode: &'static str,
    /// The sequence's name.
    pub input: String,
    /// Scans registered.
    pub frames: usize,
    /// Every scan.
    pub steps: Vec<StepReport>,
    /// The errors against the reference, when it has one.
    pub summary: Option<SequenceSummary>,
    /// Where the poses were written.
    pub out: Option<String>,
}
