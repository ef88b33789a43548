//! What every method sees and gives back: frames, scored candidates and the
//! [`PlaceRecognizer`] interface the evaluation and the CLI drive.

use image::GrayImage;
use raypath_geometry::{PointCloud, Scan2};

use crate::Result;

/// One observation handed to a place-recognition method, in input order.
#[derive(Clone, Copy, Debug)]
pub enum Frame<'a> {
    /// A planar laser scan in the sensor frame (REP-103, metres).
    Planar(&'a Scan2),
    /// A 3-D point cloud in the sensor frame; the intensity channel is used where present.
    Cloud(&'a PointCloud),
    /// An 8-bit grayscale image (a camera frame, or a lidar intensity/range image).
    Image(&'a GrayImage),
}

impl Frame<'_> {
    /// The kind of frame in words, for error messages.
    pub fn kind(&self) -> &'static str {
        match self {
            Frame::Planar(_) => "planar scan",
            Frame::Cloud(_) => "point cloud",
            Frame::Image(_) => "image",
        }
    }
}

/// A database frame proposed for a query, with its similarity (higher = more similar).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Candidate {
    /// Index of the database frame (0-based, in insertion order).
    pub frame: usize,
    /// Similarity score: higher means more similar. Scales differ between methods.
    pub score: f64,
}

/// A place-recognition method: describes frames, scores a description against the database,
/// and inserts descriptions into the database.
///
/// Online (loop-closure) use, frame `t` after frame `t − 1`:
/// `let d = m.describe(&frame)?; let c = m.query(&d, t.saturating_sub(window)); m.insert(d);`
/// — the database is updated *after* the query, as IBuILD's vocabulary (Khan 2017, §4.4.3).
///
/// Kidnapped-robot use (Khan 2017, §4.5.3): insert every frame, then
/// [`query_stored`](PlaceRecognizer::query_stored) each against the whole database.
pub trait PlaceRecognizer {
    /// What the database keeps per frame.
    type Description;

    /// Short name of the method (`ibuild`, `dbow`, `scan-context`, …).
    fn name(&self) -> &'static str;

    /// Describes one frame. Takes `&mut self` because some methods look at consecutive
    /// frames (IBuILD tracks features from the previous frame).
    fn describe(&mut self, frame: &Frame<'_>) -> Result<Self::Description>;

    /// Scores the database frames `0..before` against a description that is not in the
    /// database (yet). Returns candidates in any order; frames it does not propose are absent.
    fn query(&self, description: &Self::Description, before: usize) -> Vec<Candidate>;

    /// Scores the database frames `0..before` against the stored frame `index`.
    fn query_stored(&self, index: usize, before: usize) -> Vec<Candidate>;

    /// Appends a description as frame [`len`](PlaceRecognizer::len).
    fn insert(&mut self, description: Self::Description);

    /// Number of frames in the database.
    fn len(&self) -> usize;

    /// A new sequence of frames starts (a query sequence after the database,
    /// [`crate::run_cross`]): methods that look at consecutive frames forget the previous one.
    /// Default: nothing to forget.
    fn start_sequence(&mut self) {}

    /// True when the database is empty.
    fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// A frame that owns its data (what loaders hand to the runners); [`OwnedFrame::as_frame`]
/// borrows it as a [`Frame`].
#[derive(Clone, Debug)]
pub enum OwnedFrame {
    /// A planar laser scan.
    Planar(Scan2),
    /// A 3-D point cloud.
    Cloud(PointCloud),
    /// An 8-bit grayscale image.
    Image(GrayImage),
}

impl OwnedFrame {
    /// The frame as a borrowed [`Frame`].
    pub fn as_frame(&self) -> Frame<'_> {
        match self {
            OwnedFrame::Planar(s) => Frame::Planar(s),
            OwnedFrame::Cloud(c) => Frame::Cloud(c),
            OwnedFrame::Image(i) => Frame::Image(i),
        }
    }
}
