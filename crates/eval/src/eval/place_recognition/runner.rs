//! Drives any [`PlaceRecognizer`] over a stream of frames in both modes of Khan 2017, §4.5.3:
//! **online** (query `t` searches the frames outside the exclusion window, then is inserted;
//! describe + query + insert timed per frame) and, once the stream has ended, **kidnapped**
//! (every stored frame queried against the whole database). Type-erased behind [`Runner`] so
//! that one stream feeds several methods side by side (and no frame has to be kept).

use std::time::Instant;

use image::GrayImage;
use raypath_geometry::PointCloud;
use raypath_place_recognition::{
    Bits512, Candidate, FeatureConfig, Frame, GroundTruth, Keypoint, LoopConfig, PlaceRecognizer,
    PrCurve, PrSummary, detect_and_describe, kidnapped_pr, online_pr,
};
use serde_json::{Value, json};

/// Operating points of the online sweep (quantiles of the best-candidate scores).
const ONLINE_THRESHOLDS: usize = 200;

/// Which view of a frame a method reads.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Input {
    /// The planar scan.
    Planar,
    /// The 3-D point cloud.
    Cloud,
    /// The equirectangular intensity image.
    Intensity,
    /// The equirectangular range image.
    Range,
    /// The camera stand-in.
    Camera,
}

impl Input {
    fn index(self) -> usize {
        self as usize
    }

    /// The view in words, for tables.
    pub fn name(self) -> &'static str {
        match self {
            Input::Planar => "planar scan",
            Input::Cloud => "point cloud",
            Input::Intensity => "intensity image",
            Input::Range => "range image",
            Input::Camera => "camera stand-in",
        }
    }
}

/// Keypoints and binary descriptors of one image, extracted once and shared by IBuILD and the
/// DBoW2-style database (both use [`FeatureConfig::default`]).
#[derive(Clone, Debug, Default)]
pub struct Features {
    /// The keypoints.
    pub keypoints: Vec<Keypoint>,
    /// Their 512-bit descriptors.
    pub descriptors: Vec<Bits512>,
    /// Time to make the image (rasterising a planar scan) and extract them, seconds.
    pub seconds: f64,
}

impl Features {
    /// Extracts the features of an image; `started` is when making the image began.
    pub fn of(image: &GrayImage, started: Instant) -> anyhow::Result<Self> {
        let (keypoints, descriptors) = detect_and_describe(image, &FeatureConfig::default())?;
        Ok(Self {
            keypoints,
            descriptors,
            seconds: started.elapsed().as_secs_f64(),
        })
    }
}

/// One frame as the runners see it: its views and, per view, its features.
#[derive(Default)]
pub struct Sample<'a> {
    frames: [Option<Frame<'a>>; 5],
    features: [Option<&'a Features>; 5],
}

impl<'a> Sample<'a> {
    /// Adds a view.
    pub fn with(mut self, input: Input, frame: Frame<'a>) -> Self {
        self.frames[input.index()] = Some(frame);
        self
    }

    /// Adds the features of a view.
    pub fn with_features(mut self, input: Input, features: Option<&'a Features>) -> Self {
        self.features[input.index()] = features;
        self
    }

    /// The view, if present.
    pub fn frame(&self, input: Input) -> Option<Frame<'a>> {
        self.frames[input.index()]
    }

    /// The features of a view, if extracted.
    pub fn features(&self, input: Input) -> Option<&'a Features> {
        self.features[input.index()]
    }
}

/// The views of one 3-D frame.
pub struct Views {
    /// The cloud (sensor frame, with intensity); dropped once no method needs it.
    pub cloud: Option<PointCloud>,
    /// Equirectangular intensity image.
    pub intensity: GrayImage,
    /// Equirectangular range image.
    pub range: GrayImage,
    /// Camera stand-in (semi-synthetic drives only).
    pub camera: Option<GrayImage>,
    /// Features of the intensity, range and camera images (when a method needs them).
    pub features: [Option<Features>; 3],
}

impl Views {
    /// Extracts the features of the image views in `inputs`.
    pub fn extract(&mut self, inputs: &[Input]) -> anyhow::Result<()> {
        for (k, input) in [Input::Intensity, Input::Range, Input::Camera]
            .into_iter()
            .enumerate()
        {
            if !inputs.contains(&input) {
                continue;
            }
            let image = match input {
                Input::Intensity => Some(&self.intensity),
                Input::Range => Some(&self.range),
                _ => self.camera.as_ref(),
            };
            if let Some(image) = image {
                self.features[k] = Some(Features::of(image, Instant::now())?);
            }
        }
        Ok(())
    }

    /// The frame as the runners see it.
    pub fn sample(&self) -> Sample<'_> {
        let mut s = Sample::default()
            .with(Input::Intensity, Frame::Image(&self.intensity))
            .with(Input::Range, Frame::Image(&self.range))
            .with_features(Input::Intensity, self.features[0].as_ref())
            .with_features(Input::Range, self.features[1].as_ref())
            .with_features(Input::Camera, self.features[2].as_ref());
        if let Some(cloud) = &self.cloud {
            s = s.with(Input::Cloud, Frame::Cloud(cloud));
        }
        if let Some(camera) = &self.camera {
            s = s.with(Input::Camera, Frame::Image(camera));
        }
        s
    }
}

/// How a runner describes a sample: the description and the seconds spent before `describe`
/// (shared feature extraction charged to this method).
pub type DescribeFn<R> =
    fn(
        &mut R,
        &Sample<'_>,
        Input,
    ) -> raypath_place_recognition::Result<(<R as PlaceRecognizer>::Description, f64)>;

/// Describes the view itself (the method's own pipeline).
pub fn by_frame<R: PlaceRecognizer>(
    method: &mut R,
    sample: &Sample<'_>,
    input: Input,
) -> raypath_place_recognition::Result<(R::Description, f64)> {
    let frame = sample.frame(input).ok_or_else(|| {
        raypath_place_recognition::PlaceError::BadInput(format!("no {} view", input.name()))
    })?;
    Ok((method.describe(&frame)?, 0.0))
}

/// The shared features of a view, or an error.
pub fn features_of<'a>(
    sample: &Sample<'a>,
    input: Input,
) -> raypath_place_recognition::Result<&'a Features> {
    sample.features(input).ok_or_else(|| {
        raypath_place_recognition::PlaceError::BadInput(format!(
            "no features of the {} view",
            input.name()
        ))
    })
}

/// A method driven over a stream (object-safe wrapper of a [`PlaceRecognizer`]).
pub trait Runner: Send {
    /// The view it reads.
    fn input(&self) -> Input;
    /// True when it reads the shared features of its view.
    fn uses_features(&self) -> bool;
    /// Online step: describe, query `0..before`, insert. A failure disables the runner.
    fn step(&mut self, sample: &Sample<'_>, before: usize);
    /// Scores both modes against the ground truth (kidnapped only when `kidnapped`).
    fn evaluate(&mut self, truth: &GroundTruth, kidnapped: bool) -> MethodResult;
}

/// What one method achieved on one sequence.
#[derive(Clone, Debug)]
pub struct MethodResult {
    /// The method's label.
    pub label: String,
    /// The view it read.
    pub input: Input,
    /// Online precision–recall (loop closure with temporal consistency).
    pub online: Option<PrCurve>,
    /// Kidnapped precision–recall (full similarity matrix).
    pub kidnapped: Option<PrCurve>,
    /// Kidnapped: the best match of each frame, excluding itself.
    pub best_match: Vec<Option<usize>>,
    /// Mean online time per frame (describe + query + insert), milliseconds.
    pub ms_per_query: f64,
    /// Kidnapped: mean time of one query against the whole database, milliseconds.
    pub ms_per_kidnapped_query: f64,
    /// Why the method stopped, if it failed.
    pub error: Option<String>,
}

impl MethodResult {
    /// "label (input)", unique within a sequence.
    pub fn key(&self) -> String {
        format!("{} ({})", self.label, self.input.name())
    }

    /// Summary of the online curve (zeros when missing).
    pub fn online_summary(&self) -> Option<PrSummary> {
        self.online.as_ref().map(PrCurve::summary)
    }

    /// Summary of the kidnapped curve.
    pub fn kidnapped_summary(&self) -> Option<PrSummary> {
        self.kidnapped.as_ref().map(PrCurve::summary)
    }

    /// The numbers for the JSON (curves thinned to at most 100 points).
    pub fn json(&self) -> Value {
        json!({
            "method": self.label,
            "input": self.input.name(),
            "online": self.online_summary(),
            "kidnapped": self.kidnapped_summary(),
            "online_curve": self.online.as_ref().map(thin),
            "kidnapped_curve": self.kidnapped.as_ref().map(thin),
            "ms_per_query": finite(self.ms_per_query),
            "ms_per_kidnapped_query": finite(self.ms_per_kidnapped_query),
            "error": self.error,
        })
    }
}

fn finite(v: f64) -> Option<f64> {
    v.is_finite().then_some(v)
}

/// `[recall, precision]` pairs of a curve, at most 100.
fn thin(curve: &PrCurve) -> Vec<[f64; 2]> {
    let step = curve.points.len().div_ceil(100).max(1);
    curve
        .points
        .iter()
        .step_by(step)
        .chain(curve.points.last())
        .map(|p| [p.recall, p.precision])
        .collect()
}

/// A [`PlaceRecognizer`] with its online record.
pub struct Tracked<R: PlaceRecognizer> {
    method: R,
    describe: DescribeFn<R>,
    uses_features: bool,
    label: String,
    input: Input,
    online: Vec<Vec<Candidate>>,
    seconds: f64,
    error: Option<String>,
}

impl<R: PlaceRecognizer> Tracked<R> {
    /// Wraps a fresh method described by `describe` (`uses_features`: it reads the shared
    /// features).
    pub fn new(
        method: R,
        label: impl Into<String>,
        input: Input,
        describe: DescribeFn<R>,
        uses_features: bool,
    ) -> Self {
        Self {
            method,
            describe,
            uses_features,
            label: label.into(),
            input,
            online: Vec::new(),
            seconds: 0.0,
            error: None,
        }
    }
}

/// Boxes a method that describes its view itself as a [`Runner`].
pub fn boxed<R>(method: R, label: impl Into<String>, input: Input) -> Box<dyn Runner>
where
    R: PlaceRecognizer + Send + 'static,
{
    Box::new(Tracked::new(method, label, input, by_frame::<R>, false))
}

/// Boxes a method that reads the shared features of its view.
pub fn boxed_features<R>(
    method: R,
    label: impl Into<String>,
    input: Input,
    describe: DescribeFn<R>,
) -> Box<dyn Runner>
where
    R: PlaceRecognizer + Send + 'static,
{
    Box::new(Tracked::new(method, label, input, describe, true))
}

impl<R: PlaceRecognizer + Send> Runner for Tracked<R> {
    fn input(&self) -> Input {
        self.input
    }

    fn uses_features(&self) -> bool {
        self.uses_features
    }

    fn step(&mut self, sample: &Sample<'_>, before: usize) {
        if self.error.is_some() {
            return;
        }
        let t = Instant::now();
        match (self.describe)(&mut self.method, sample, self.input) {
            Ok((d, shared)) => {
                let candidates = self.method.query(&d, before.min(self.method.len()));
                self.method.insert(d);
                self.seconds += t.elapsed().as_secs_f64() + shared;
                self.online.push(candidates);
            }
            Err(e) => {
                self.error = Some(format!("frame {}: {e}", self.online.len()));
            }
        }
    }

    fn evaluate(&mut self, truth: &GroundTruth, kidnapped: bool) -> MethodResult {
        let n = self.online.len();
        let mut result = MethodResult {
            label: self.label.clone(),
            input: self.input,
            online: None,
            kidnapped: None,
            best_match: Vec::new(),
            ms_per_query: 1e3 * self.seconds / n.max(1) as f64,
            ms_per_kidnapped_query: f64::NAN,
            error: self.error.clone(),
        };
        if self.error.is_some() || n != truth.len() {
            if result.error.is_none() {
                result.error = Some(format!(
                    "{n} frames for {} in the ground truth",
                    truth.len()
                ));
            }
            return result;
        }
        match online_pr(
            &self.online,
            truth,
            &LoopConfig::default(),
            ONLINE_THRESHOLDS,
        ) {
            Ok(curve) => result.online = Some(curve),
            Err(e) => result.error = Some(format!("online PR: {e}")),
        }
        self.online = Vec::new();
        if kidnapped {
            let t = Instant::now();
            let all: Vec<Vec<Candidate>> = (0..n).map(|i| self.method.query_stored(i, n)).collect();
            result.ms_per_kidnapped_query = 1e3 * t.elapsed().as_secs_f64() / n.max(1) as f64;
            result.best_match = all
                .iter()
                .enumerate()
                .map(|(i, list)| {
                    list.iter()
                        .filter(|c| c.frame != i && c.score.is_finite())
                        .max_by(|a, b| a.score.total_cmp(&b.score).then(b.frame.cmp(&a.frame)))
                        .map(|c| c.frame)
                })
                .collect();
            match kidnapped_pr(&all, truth) {
                Ok(curve) => result.kidnapped = Some(curve),
                Err(e) => result.error = Some(format!("kidnapped PR: {e}")),
            }
        }
        result
    }
}
