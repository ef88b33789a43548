//! `raypath.place_recognition`: IBuILD, DBoW2-style and Scan Context databases with one
//! interface (`add`, `query`, `add_and_query`), over planar scans, point clouds or images.

use std::path::PathBuf;
use std::sync::Arc;

use numpy::{PyArray2, PyArrayDescrMethods, PyArrayMethods, PyUntypedArrayMethods};
use pyo3::prelude::*;
use raypath_place_recognition::{
    BinaryVocabulary, Candidate, Dbow as DbowDatabase, DbowConfig, Ibuild as IbuildDatabase,
    IbuildConfig, IbuildScore, OwnedFrame, PlaceError, PlaceRecognizer, ScanContext as Database,
    ScanContextConfig, VocabularyConfig, detect_and_describe, frame_image, sort_candidates,
};

use crate::arrays::point_cloud;
use crate::errors::{format_error, input_error, value_error};
use crate::io::{Cloud, Scan};

/// One frame from Python: a `raypath.Scan` (planar scan), a `raypath.Cloud` or an `(N, 3)` /
/// `(N, 4)` float array (point cloud, sensor frame), or an `(H, W)` uint8 array (image).
fn frame(obj: &Bound<'_, PyAny>) -> PyResult<OwnedFrame> {
    if let Ok(scan) = obj.downcast::<Scan>() {
        return Ok(OwnedFrame::Planar(scan.get().frame.scan.clone()));
    }
    if let Ok(cloud) = obj.downcast::<Cloud>() {
        return Ok(OwnedFrame::Cloud(cloud.get().cloud.clone()));
    }
    if let Ok(image) = obj.downcast::<PyArray2<u8>>() {
        let (h, w) = (image.shape()[0], image.shape()[1]);
        let pixels: Vec<u8> = image.readonly().as_array().iter().copied().collect();
        return image::GrayImage::from_raw(w as u32, h as u32, pixels)
            .map(OwnedFrame::Image)
            .ok_or_else(|| {
                value_error(
                    "frame",
                    format!("an image of {h} × {w} pixels is too large"),
                )
            });
    }
    if let Ok(array) = obj.downcast::<numpy::PyUntypedArray>() {
        let py = obj.py();
        let dtype = array.dtype();
        if !(dtype.is_equiv_to(&numpy::dtype::<f64>(py))
            || dtype.is_equiv_to(&numpy::dtype::<f32>(py)))
        {
            return Err(value_error(
                "frame",
                format!(
                    "expected a raypath.Scan, a raypath.Cloud, an (N, 3) or (N, 4) float32/float64 \
                     array or an (H, W) uint8 image, got a {dtype} array of shape {:?}",
                    array.shape()
                ),
            ));
        }
    }
    // Points (an array or anything NumPy reads as one): their own messages.
    point_cloud(obj, "frame").map(OwnedFrame::Cloud)
}

/// What every recognizer binding does with its database; the classes below only build
/// their database (`recognizer!` gives each class these methods).
fn add<R: PlaceRecognizer + Send>(
    py: Python<'_>,
    db: &mut R,
    obj: &Bound<'_, PyAny>,
) -> PyResult<usize> {
    let f = frame(obj)?;
    py.allow_threads(|| {
        let d = db.describe(&f.as_frame())?;
        db.insert(d);
        Ok(db.len() - 1)
    })
    .map_err(|e: PlaceError| input_error(e))
}

fn query<R: PlaceRecognizer + Send>(
    py: Python<'_>,
    db: &mut R,
    obj: &Bound<'_, PyAny>,
    k: Option<usize>,
    before: Option<usize>,
    insert: bool,
) -> PyResult<Vec<(usize, f64)>> {
    let f = frame(obj)?;
    let mut found: Vec<Candidate> = py
        .allow_threads(|| {
            let d = db.describe(&f.as_frame())?;
            let found = db.query(&d, before.unwrap_or(db.len()).min(db.len()));
            if insert {
                db.insert(d);
            }
            Ok(found)
        })
        .map_err(|e: PlaceError| input_error(e))?;
    sort_candidates(&mut found);
    if let Some(k) = k {
        found.truncate(k);
    }
    Ok(found.into_iter().map(|c| (c.frame, c.score)).collect())
}

/// The methods shared by the three classes: `add`, `query`, `add_and_query`, `len`.
macro_rules! recognizer {
    ($class:ident, $name:literal, { $($own:tt)* }) => {
        #[pymethods]
        impl $class {
            $($own)*

            /// Describes a frame and adds it to the database; returns its index. A frame is
            /// a `raypath.Scan`, a `raypath.Cloud`, an `(N, 3)`/`(N, 4)` float array (points in
            /// the sensor frame) or an `(H, W)` uint8 image.
            fn add(&mut self, py: Python<'_>, frame: &Bound<'_, PyAny>) -> PyResult<usize> {
                add(py, &mut self.db, frame)
            }

            /// Scores a frame against the database frames `0 .. before` (default all): a
            /// list of `(index, score)`, best first (higher = more similar), at most `k`.
            /// The frame is not added.
            #[pyo3(signature = (frame, k = None, before = None))]
            fn query(
                &mut self,
                py: Python<'_>,
                frame: &Bound<'_, PyAny>,
                k: Option<usize>,
                before: Option<usize>,
            ) -> PyResult<Vec<(usize, f64)>> {
                query(py, &mut self.db, frame, k, before, false)
            }

            /// One online loop-closure step (as `raypath loop-closure`): describes the
            /// frame once, scores it against the frames at least `exclusion_frames` before
            /// it, then adds it. Returns the candidates as `query` does.
            #[pyo3(signature = (frame, exclusion_frames = 50, k = None))]
            fn add_and_query(
                &mut self,
                py: Python<'_>,
                frame: &Bound<'_, PyAny>,
                exclusion_frames: usize,
                k: Option<usize>,
            ) -> PyResult<Vec<(usize, f64)>> {
                let before = self.db.len().saturating_sub(exclusion_frames);
                query(py, &mut self.db, frame, k, Some(before), true)
            }

            fn __len__(&self) -> usize {
                self.db.len()
            }

            fn __repr__(&self) -> String {
                format!(concat!($name, "({} frames)"), self.db.len())
            }
        }
    };
}

/// Scan Context place recognition (Kim & Kim 2018) of 3-D scans: scores are `1 − d` of the
/// yaw-invariant column distance (higher = more similar).
///
/// `num_sectors`: sectors over 360°. `max_range`: farther points are ignored, metres.
/// `num_candidates`: ring-key nearest neighbours scored fully (None = every scan).
#[pyclass(module = "raypath.place_recognition", name = "ScanContext")]
pub struct ScanContext {
    db: Database,
}

recognizer!(ScanContext, "ScanContext", {
    #[new]
    #[pyo3(signature = (num_sectors = 60, max_range = 80.0, num_candidates = Some(10)))]
    fn new(num_sectors: usize, max_range: f64, num_candidates: Option<usize>) -> PyResult<Self> {
        let config = ScanContextConfig {
            num_sectors,
            max_range,
            num_candidates,
            ..ScanContextConfig::default()
        };
        let db = Database::new(config).map_err(|e| value_error("ScanContext", e))?;
        Ok(Self { db })
    }
});

/// IBuILD (Khan 2017, §4.4): an incremental binary bag of words — features tracked between
/// consecutive frames become words of a vocabulary that grows online; frames are scored by
/// their shared words. Planar scans and clouds are rasterized to images first.
///
/// Describing a frame tracks features from the previously described frame, so feed frames in
/// order, each once (`add_and_query` for online loop closure; `query` alone also advances
/// the tracking). `delta`: matching threshold in bits (of 512). `window`: β, the temporal
/// window of loop-closure use. `score`: `"printed"` (§4.4.3) or `"symmetric"`. `upscale`:
/// integer enlargement of every image (small camera images).
#[pyclass(module = "raypath.place_recognition", name = "Ibuild")]
pub struct Ibuild {
    db: IbuildDatabase,
}

recognizer!(Ibuild, "Ibuild", {
    #[new]
    #[pyo3(signature = (delta = None, window = 10, score = "printed", upscale = 1))]
    fn new(delta: Option<u32>, window: usize, score: &str, upscale: u32) -> PyResult<Self> {
        let score = match score {
            "printed" => IbuildScore::Printed,
            "symmetric" => IbuildScore::Symmetric,
            other => {
                return Err(value_error(
                    "score",
                    format!("expected \"printed\" or \"symmetric\", got {other:?}"),
                ));
            }
        };
        let defaults = IbuildConfig::default();
        let config = IbuildConfig {
            delta: delta.unwrap_or(defaults.delta),
            beta: window.max(1),
            score,
            image: raypath_place_recognition::ImageConfig {
                upscale,
                ..defaults.image
            },
            ..defaults
        };
        let db = IbuildDatabase::new(config).map_err(|e| value_error("Ibuild", e))?;
        Ok(Self { db })
    }
});

/// DBoW2-style place recognition (Gálvez-López & Tardós 2012): ORB-like binary features
/// quantized by a vocabulary tree trained offline, tf-idf bag-of-words scores.
///
/// `vocabulary`: a vocabulary file (`raypath loop-closure --method dbow --save-vocabulary`,
/// or `Dbow.save_vocabulary`); `Dbow.train(frames)` trains one instead. `upscale`: integer
/// enlargement of every image.
#[pyclass(module = "raypath.place_recognition", name = "Dbow")]
pub struct Dbow {
    db: DbowDatabase,
    vocabulary: Arc<BinaryVocabulary>,
}

fn dbow_config(upscale: u32) -> DbowConfig {
    let defaults = DbowConfig::default();
    DbowConfig {
        image: raypath_place_recognition::ImageConfig {
            upscale,
            ..defaults.image
        },
        ..defaults
    }
}

recognizer!(Dbow, "Dbow", {
    #[new]
    #[pyo3(signature = (vocabulary, upscale = 1))]
    fn new(py: Python<'_>, vocabulary: PathBuf, upscale: u32) -> PyResult<Self> {
        let file = std::fs::File::open(&vocabulary).map_err(|e| {
            if e.kind() == std::io::ErrorKind::NotFound {
                pyo3::exceptions::PyFileNotFoundError::new_err(format!(
                    "{}: {e}",
                    vocabulary.display()
                ))
            } else {
                format_error(&vocabulary, e)
            }
        })?;
        let words = py
            .allow_threads(|| BinaryVocabulary::from_reader(std::io::BufReader::new(file)))
            .map_err(|e| format_error(&vocabulary, e))?;
        let vocabulary = Arc::new(words);
        Ok(Self {
            db: DbowDatabase::new(Arc::clone(&vocabulary), dbow_config(upscale)),
            vocabulary,
        })
    }

    /// Trains a vocabulary on `frames` (a sequence of frames, as `add` takes them) with seed
    /// `seed`, as `raypath loop-closure --method dbow` does without `--vocabulary`, and
    /// returns an empty database over it.
    #[staticmethod]
    #[pyo3(signature = (frames, upscale = 1, seed = 0))]
    fn train(py: Python<'_>, frames: &Bound<'_, PyAny>, upscale: u32, seed: u64) -> PyResult<Self> {
        let config = dbow_config(upscale);
        let owned: Vec<OwnedFrame> = frames
            .try_iter()?
            .map(|f| frame(&f?))
            .collect::<PyResult<_>>()?;
        if owned.is_empty() {
            return Err(value_error("frames", "expected at least one frame"));
        }
        let words = py
            .allow_threads(|| {
                let mut images = Vec::with_capacity(owned.len());
                for (i, f) in owned.iter().enumerate() {
                    let image = frame_image(&f.as_frame(), &config.image)?;
                    let (_, descriptors) = detect_and_describe(&image, &config.features)
                        .map_err(|e| PlaceError::BadInput(format!("frame {i}: {e}")))?;
                    images.push(descriptors);
                }
                BinaryVocabulary::train(&images, &VocabularyConfig::default(), seed)
            })
            .map_err(input_error)?;
        let vocabulary = Arc::new(words);
        Ok(Self {
            db: DbowDatabase::new(Arc::clone(&vocabulary), config),
            vocabulary,
        })
    }

    /// Writes the vocabulary (readable by `Dbow(path)` and `raypath loop-closure
    /// --vocabulary`).
    fn save_vocabulary(&self, path: PathBuf) -> PyResult<()> {
        let write = || -> std::io::Result<()> {
            let file = std::fs::File::create(&path)?;
            self.vocabulary.to_writer(std::io::BufWriter::new(file))
        };
        write().map_err(|e| input_error(format!("{}: {e}", path.display())))
    }
});
