//! # raypath-place-recognition
//!
//! Has the robot been here before? Appearance-based **place recognition** and **loop closure**
//! after Khan (2017, ch. 4): describe each observation (a planar scan, a 3-D cloud, an image),
//! keep the descriptions in a database, and score every new observation against it. Loop
//! closure is place recognition plus temporal consistency, run at 100 % precision because one
//! wrong loop edge corrupts a SLAM map (§4.1).
//!
//! ## Methods (all behind [`PlaceRecognizer`])
//!
//! | method | frames | idea | source |
//! | --- | --- | --- | --- |
//! | [`Ibuild`] | images, planar scans (as images, or by binary shape descriptors made on the scan: [`PlanarDescriptors::Shape`], ours), clouds (as images) | online incremental binary bag of words: features tracked over consecutive frames, merged into words, first-match assignment, modified Jaccard score, no training | Khan §4.4 |
//! | [`Dbow`] | same | DBoW2-style vocabulary tree of binary words trained offline, tf–idf, L1 score, inverse and direct index | Gálvez-López & Tardós 2012 |
//! | [`GlobalDescriptorDb`] (`hog`, `gist`) | same | one global HOG or GIST vector per image, cosine similarity | Khan §4.5.2 |
//! | [`Shot3dBow`] (`shot`, `shot-intensity`) | clouds | SHOT / intensity-textured SHOT on a voxel grid, words merged by averaging, tf–idf similarity eqs. (4.2)–(4.3) | Khan §4.5.2 |
//! | [`ScanContext`] | clouds | max height per ring × sector, ring key in a k-d tree, column-shift cosine distance | Kim & Kim, IROS 2018 (from the paper) |
//! | [`PolarContext`] | planar scans | the same idea for 2-D scans (end-point counts per ring × sector) | ours |
//! | [`RawPixels`] | same as the images | downsampled, patch-normalised pixels, mean absolute difference (SeqSLAM's single-image comparison) | Milford & Wyeth 2012 |
//! | [`GeometricCheck`] | planar scans | any method above, its best candidates re-scored by how well the two scans align (point-to-line ICP, share of supported points) | ours |
//!
//! Any method's scores of a query sequence against a database sequence ([`run_cross`], a
//! [`ScoreMatrix`]) can feed **sequence matching** ([`sequence_match`], SeqSLAM: difference
//! matrix, local contrast enhancement, straight-line search over `d_s` frames), scored by
//! [`cross_summary`] against a [`CrossTruth`] (same file name ± a frame tolerance).
//!
//! Planar scans can skip the picture: [`scan_shape_descriptors`] gives 512-bit descriptors of
//! the outline around keypoints along the scan (a polar occupancy grid in the frame of the
//! local normal), which IBuILD matches and merges like BRIEF bits
//! ([`IbuildConfig::planar`], ours).
//!
//! Images of lidar data come from [`frame_image`]: planar scans are rasterised
//! ([`rasterize_scan`]), clouds are projected to equirectangular **intensity** or **range**
//! images with incremental averaging per pixel ([`equirectangular`], App. A.1), and
//! [`rectilinear`] / [`cubic_front_back`] cut perspective views out of them (App. A.2). Binary
//! features are FAST-9 corners on a pyramid with a steered 512-bit BRIEF descriptor
//! ([`detect_and_describe`]; the thesis uses BRISK with p = 512).
//!
//! IBuILD's vocabulary search — 45 of its 50 ms per image in Table 4.3 — returns exactly the
//! thesis' linear first match ([`VocabularySearch::Linear`]) but can run in sub-linear time by
//! multi-index hashing (Norouzi et al., CVPR 2012; the thesis' future work, §4.7.1);
//! [`VocabularySearch::Auto`] picks the faster of the two for the vocabulary size and δ.
//!
//! ## Evaluation
//!
//! [`run_online`] (describe → query the frames outside the exclusion window → insert) and
//! [`run_kidnapped`] (every frame against the whole database: the similarity matrix of §4.5.3)
//! drive any method; [`LoopDetector`] accepts loop closures with the temporal-consistency test
//! of Fig. 4.11; [`GroundTruth`] marks true revisits from reference poses; [`kidnapped_pr`] and
//! [`online_pr`] give precision–recall curves and their key points ([`PrSummary`]: recall at
//! 100 % precision, precision at 100 % recall, max F1). `cargo xtask eval place-recognition`
//! runs all methods on the real CARMEN logs, the real KITTI frames and semi-synthetic KITTI
//! drives (docs/results/place-recognition.md); `raypath loop-closure` runs one method on your
//! own log, KITTI sequence or image folder.
//!
//! ## Decisions where the thesis is silent or inconsistent
//!
//! * IBuILD: δ is not printed (its PR curves sweep it); our default is 80 of 512 bits. The
//!   centroid of eq. (4.1) sends ties to 1 (for pairs: the bitwise OR), as printed; a strict
//!   majority is an ablation flag. Matched binary words are not re-centroided (flag). The first
//!   frame has no predecessor and keeps its own descriptors as words. The similarity is
//!   implemented as printed (inverse-frequency sums times |U| and |T|), normalised over the
//!   hypotheses, with no candidate when |L| ≤ 1. The very first loop closure is accepted when it
//!   passes the threshold (Fig. 4.11 only constrains later ones).
//! * Projections: the azimuth runs over a fixed full circle (a yaw rotation is a column shift)
//!   and the elevation over the sensor's span; the thesis' min/max-of-the-cloud rule is
//!   [`AngularSpan::FromCloud`]. The rectilinear view uses `η = atan2(c_x, c_z) + η_front`
//!   (the printed `arccos` loses the sign of `c_x`).
//! * GIST follows the body text's symbols: Ω scales, χ orientations per scale, φ blocks.
//! * SHOT keypoints (not named in the thesis): one per 1 m cell of the down-sampled cloud.
//!
//! ## Example
//!
//! ```
//! use raypath_geometry::Scan2;
//! use raypath_place_recognition::{
//!     Exclusion, GroundTruth, OwnedFrame, PolarConfig, PolarContext, kidnapped_pr, run_kidnapped,
//! };
//!
//! // A 360° scanner in a 10 m × 6 m room with a pillar, at six positions; the last three
//! // revisit the first three, turned by 90°.
//! let scan_at = |x: f64, y: f64, heading: f64| {
//!     let n = 360;
//!     let ranges = (0..n)
//!         .map(|i| {
//!             let a = heading + i as f64 * std::f64::consts::TAU / n as f64;
//!             let (c, s) = (a.cos(), a.sin());
//!             let wall_x = if c > 0.0 { (5.0 - x) / c } else { (-5.0 - x) / c };
//!             let wall_y = if s > 0.0 { (3.0 - y) / s } else { (-3.0 - y) / s };
//!             // A pillar of radius 0.3 m at (2, 1).
//!             let (px, py) = (2.0 - x, 1.0 - y);
//!             let along = px * c + py * s;
//!             let miss = (px * px + py * py - along * along).max(0.0);
//!             let pillar = if along > 0.0 && miss < 0.09 { along - (0.09 - miss).sqrt() } else { f64::INFINITY };
//!             wall_x.min(wall_y).min(pillar)
//!         })
//!         .collect();
//!     Scan2 {
//!         angle_min_rad: 0.0,
//!         angle_increment_rad: std::f64::consts::TAU / n as f64,
//!         max_range_m: 30.0,
//!         ranges,
//!         intensities: None,
//!     }
//! };
//! let poses = [(-3.0, 0.0), (0.0, 0.0), (3.0, -1.0)];
//! let mut scans = Vec::new();
//! for (k, &(x, y)) in poses.iter().chain(poses.iter()).enumerate() {
//!     let heading = if k < 3 { 0.0 } else { std::f64::consts::FRAC_PI_2 };
//!     scans.push(scan_at(x, y, heading));
//! }
//! let positions: Vec<[f64; 3]> = poses.iter().chain(poses.iter()).map(|&(x, y)| [x, y, 0.0]).collect();
//!
//! let mut polar = PolarContext::new(PolarConfig::default())?;
//! let run = run_kidnapped(&mut polar, scans.len(), |i| Ok(OwnedFrame::Planar(scans[i].clone())), None)?;
//! // Every revisit's best other match is the same place.
//! for (i, candidates) in run.candidates.iter().enumerate().skip(3) {
//!     let best = candidates.iter().find(|c| c.frame != i).expect("other frames");
//!     assert_eq!(best.frame, i - 3);
//! }
//! let truth = GroundTruth::from_positions(&positions, None, 1.0, Exclusion::none())?;
//! let summary = kidnapped_pr(&run.candidates, &truth)?.summary();
//! assert_eq!(summary.recall_at_100_precision, 1.0);
//! # Ok::<(), raypath_place_recognition::PlaceError>(())
//! ```

mod error;
mod frame;

// Binary descriptors and IBuILD (Khan 2017, §4.4).
mod binary;
mod ibuild;

// Image features and planar-scan images.
mod features;
mod raster;
mod shape;

// Baselines: DBoW2-style vocabulary tree, Scan Context, planar polar descriptor.
mod dbow;
mod polar;
mod scan_context;

// Lidar images and global descriptors (Khan 2017, §4.5).
mod gist;
mod hog;
mod images;
mod projection;

// 3-D local descriptors and the real-valued incremental bag of words (Khan 2017, §4.5.2).
mod local_bow;
mod shot;

// Precision–recall, online loop acceptance and the runners (Khan 2017, §4.5.3).
mod online;
mod pr;
pub mod report;
mod run;

// The geometric check of candidates on planar scans (ours).
mod verify;

// Query sequence against a database sequence (Nordland), the raw-pixel baseline and
// sequence matching (SeqSLAM, Milford & Wyeth 2012).
mod cross;
mod raw_pixels;
mod seqslam;

pub use binary::{BinaryDescriptor, Bits256, Bits512};
pub use error::{PlaceError, Result};
pub use frame::{Candidate, Frame, OwnedFrame, PlaceRecognizer};
pub use verify::{Checked, GeometricCheck, GeometricCheckConfig, ScanMatch};

// --- features (features work) ---
pub use features::{FeatureConfig, Keypoint, detect_and_describe};
pub use polar::{KEY_DIM as POLAR_KEY_DIM, PolarConfig, PolarContext, PolarDescription};
pub use raster::{RasterConfig, rasterize_scan};
pub use shape::{
    RINGS as SHAPE_RINGS, SECTORS as SHAPE_SECTORS, SHAPE_DELTA, ScanShapeConfig,
    scan_shape_descriptors,
};
// --- end features ---

// --- lidar images (lidar-images work) ---
mod global;
mod rectilinear;
pub use gist::{Gist, GistConfig, gist};
pub use global::{GlobalDescriptorDb, cosine_similarity};
pub use hog::{HogConfig, hog};
pub use images::{ImageConfig, LidarChannel, frame_image};
pub use projection::{
    AngularSpan, EquirectConfig, EquirectGeometry, IntensityScale, LidarImages, equirectangular,
};
pub use rectilinear::{RectilinearConfig, cubic_front_back, rectilinear};
// --- end lidar images ---

// --- ibuild (IBuILD work) ---
pub use ibuild::{
    Ibuild, IbuildConfig, IbuildDescription, IbuildScore, MultiIndexLayout, PlanarDescriptors,
    StageTimes, Vocabulary, VocabularySearch, WordIndex, match_consecutive, merge_descriptors,
};
// --- end ibuild ---

// --- dbow (DBoW work) ---
pub use dbow::{
    BinaryVocabulary, BowVector, Dbow, DbowConfig, DbowDescription, DirectIndex, VocabularyConfig,
};
// --- end dbow ---

// --- 3-D local (SHOT work) ---
pub use local_bow::{
    IncrementalBow, LocalWords, Shot3dBow, Shot3dBowConfig, merge_real_descriptors,
};
pub use scan_context::{SCAN_CONTEXT_RINGS, ScanContext, ScanContextConfig, ScanContextDescriptor};
pub use shot::{
    SHOT_SHAPE_LEN, ShotConfig, ShotDescriptors, describe_cloud, shot_at_keypoints,
    uniform_keypoints, voxel_downsample,
};
// --- end 3-D local ---

// --- evaluation (PR work) ---
pub use online::{LoopClosure, LoopConfig, LoopDetector, best_candidate, detect_loops};
pub use pr::{
    Confidence, CrossSummary, CrossTruth, Exclusion, GroundTruth, PrCurve, PrPoint, PrSummary,
    cross_pr, cross_summary, kidnapped_pr, online_pr, recall_at_k,
};
pub use run::{
    FrameTiming, KidnappedRun, OnlineRun, run_kidnapped, run_kidnapped_serial, run_online,
    sort_candidates,
};
// --- end evaluation ---

// --- query against database (Nordland work) ---
pub use cross::{CrossRun, ScoreMatrix, run_cross};
pub use raw_pixels::{RawPixelConfig, RawPixels, mean_abs_difference, patch_normalise, quantise};
pub use seqslam::{
    SequenceConfig, difference_row, enhance_row, enhanced_differences, sequence_match,
    sequence_match_timed, sequence_row,
};
// --- end query against database ---
