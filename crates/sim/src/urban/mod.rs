//! Urban drives for pole-based localization (Schaefer 2020, ch. 12): procedural street worlds,
//! vehicle trajectories, odometry, sessions with changes, scanned with the HDL-64E (KITTI
//! style) or HDL-32E (NCLT style) and written in the real layouts.
//!
//! ## Worlds
//!
//! An irregular grid of streets ([`StreetConfig`]): carriageways 10–14 m wide (with parking
//! lanes), sidewalks 2–4 m wide raised by a 12 cm curb, buildings along every block side
//! (10–30 m long, 8–14 m deep, 6–24 m high with a style per block side, set back 0–3 m, some
//! with recessed glass ground floors or set-back top floors, gaps with fences), and the
//! pole-like landmarks the pole extractor looks for ([`PoleKind`]):
//!
//! | kind | radius | height | placement |
//! |---|---|---|---|
//! | street light | 0.08–0.15 m | 6–10 m, arm 1–2.5 m, lamp head | every 25–40 m, 0.5 m from the curb |
//! | sign post | 0.03–0.05 m | 2–3 m, plate 0.4–0.9 m | before intersections, ~12 per km |
//! | tree trunk | 0.1–0.4 m (0.1 + 0.3u²) | 2–4 m to the crown; crown 1.5–4 m radius | half of the street sides, every 8–14 m |
//! | bollard | 0.05–0.1 m | 0.8–1.2 m | groups of 3–6, 1.2–1.8 m apart |
//!
//! Poles keep at least 1 m between each other, so the free hull the extractor needs around a pole
//! (Schaefer 2020, §12.4.1) is there. Parked cars (3.8–5 m × 1.7–1.95 m × 1.4–1.75 m; body, cabin,
//! wheels) fill 30–75 % of the parking slots; construction zones hold rows of barrels (r 0.29 m,
//! 1.05 m high) in a parking lane.
//!
//! ## Drives and sessions
//!
//! Random routes through the intersections on the right-hand lane, turns of radius 8 m,
//! 8–12 m/s with acceleration limits, sampled at 10 Hz (scans) and 100 Hz (odometry);
//! [`odometry`] adds configurable noise. [`sessions`] derives later sessions of the same
//! world with accumulating changes (cars, removed/moved/added sign posts and bollards, cut
//! trees, shifted or removed barrels, foliage by month).
//!
//! ## Outputs
//!
//! [`generate_kitti`] writes the KITTI odometry layout ([`kitti_out`]), [`generate_nclt`] the
//! NCLT layout of several sessions ([`nclt_set`]); both write the pole ground truth as
//! `poles.csv` (`x,y,w,h,kind,id`, see [`output::POLES_HEADER`]). Surfaces carry SemanticKITTI
//! labels ([`kinds::label`]) with the pole id + 1 as instance on poles and what they carry.

pub mod along_path;
mod furniture;
pub mod kinds;
pub mod kitti_out;
mod kitti_set;
pub mod mesh;
pub mod nclt_set;
pub mod odometry;
pub mod output;
mod path_index;
mod roadside;
pub mod route;
pub mod sessions;
pub mod streets;
pub mod world;

pub use kinds::{Canopy, Pole, PoleKind};
pub use kitti_set::{UrbanKittiConfig, generate_kitti};
pub use nclt_set::{UrbanNcltConfig, generate_nclt};
pub use odometry::{Odometry, OdometryNoise};
pub use route::DriveConfig;
pub use sessions::{ChangeLog, SessionChanges};
pub use streets::{StreetConfig, UrbanLayout, generate_layout};
pub use world::World;
