//! What urban objects are: semantic labels and the size distributions of pole-like objects.
//!
//! Labels follow SemanticKITTI's class ids (Behley et al., ICCV 2019; `semantic-kitti.yaml`),
//! so simulated labels read like the real ones: the lower 16 bits of a point label are the
//! class, the upper 16 bits the instance (pole id + 1 for poles, 0 for stuff).

use rand::Rng;

use crate::rng::SimRng;

/// SemanticKITTI class ids used by the urban worlds.
pub mod label {
    /// No return / unlabelled.
    pub const UNLABELED: u32 = 0;
    /// Parked cars.
    pub const CAR: u32 = 10;
    /// Road surface.
    pub const ROAD: u32 = 40;
    /// Sidewalks and curbs.
    pub const SIDEWALK: u32 = 48;
    /// Building facades and roofs.
    pub const BUILDING: u32 = 50;
    /// Fences.
    pub const FENCE: u32 = 51;
    /// Tree canopies.
    pub const VEGETATION: u32 = 70;
    /// Tree trunks.
    pub const TRUNK: u32 = 71;
    /// Lawns and open ground.
    pub const TERRAIN: u32 = 72;
    /// Street-light masts, sign posts and bollards.
    pub const POLE: u32 = 80;
    /// Sign plates.
    pub const TRAFFIC_SIGN: u32 = 81;
    /// Construction barrels.
    pub const OTHER_OBJECT: u32 = 99;

    /// A point label: class in the lower 16 bits, instance in the upper 16.
    pub fn with_instance(class: u32, instance: u32) -> u32 {
        class | (instance << 16)
    }

    /// The class of a point label.
    pub fn class(label: u32) -> u32 {
        label & 0xffff
    }

    /// The instance of a point label (0 for stuff).
    pub fn instance(label: u32) -> u32 {
        label >> 16
    }
}

/// Kinds of pole-like landmarks, with the code written in the `kind` column of `poles.csv`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum PoleKind {
    /// Street light: mast radius 0.08–0.15 m, 6–10 m high, with an arm and a lamp head.
    StreetLight = 1,
    /// Sign post: radius 0.03–0.05 m, 2–3 m high, with a sign plate on top.
    SignPost = 2,
    /// Tree trunk: radius 0.1–0.4 m, 2–4 m to the crown base, with a canopy.
    TreeTrunk = 3,
    /// Bollard: radius 0.05–0.1 m, 0.8–1.2 m high (below the 1 m minimum pole height of the
    /// extractor for some of them, as in reality).
    Bollard = 4,
}

impl PoleKind {
    /// All kinds, by code.
    pub const ALL: [PoleKind; 4] = [
        PoleKind::StreetLight,
        PoleKind::SignPost,
        PoleKind::TreeTrunk,
        PoleKind::Bollard,
    ];

    /// The numeric code of the `kind` column.
    pub fn code(self) -> u32 {
        self as u32
    }

    /// A snake-case name for statistics.
    pub fn name(self) -> &'static str {
        match self {
            PoleKind::StreetLight => "street_light",
            PoleKind::SignPost => "sign_post",
            PoleKind::TreeTrunk => "tree_trunk",
            PoleKind::Bollard => "bollard",
        }
    }

    /// The kind with this code.
    pub fn from_code(code: u32) -> Option<Self> {
        Self::ALL.into_iter().find(|k| k.code() == code)
    }

    /// Semantic class of the pole's shaft.
    pub fn class(self) -> u32 {
        match self {
            PoleKind::TreeTrunk => label::TRUNK,
            _ => label::POLE,
        }
    }

    /// Samples (radius, height) in metres, uniform in the documented ranges. For trunks the
    /// height is the crown base (the visible trunk).
    pub fn sample_size(self, rng: &mut SimRng) -> (f64, f64) {
        let (r, h) = match self {
            PoleKind::StreetLight => ((0.08, 0.15), (6.0, 10.0)),
            PoleKind::SignPost => ((0.03, 0.05), (2.0, 3.0)),
            // Young street trees are more common than old ones: r = 0.1 + 0.3·u².
            PoleKind::TreeTrunk => {
                let u: f64 = rng.random();
                return (0.1 + 0.3 * u * u, rng.random_range(2.0..4.0));
            }
            PoleKind::Bollard => ((0.05, 0.10), (0.8, 1.2)),
        };
        (rng.random_range(r.0..r.1), rng.random_range(h.0..h.1))
    }
}

/// A pole-like landmark of the ground truth.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Pole {
    /// Stable id across sessions (the instance in point labels is `id + 1`).
    pub id: u32,
    /// What it is.
    pub kind: PoleKind,
    /// Position of the axis in the world frame, metres.
    pub x: f64,
    /// Position of the axis in the world frame, metres.
    pub y: f64,
    /// Height of the ground at the base, metres.
    pub base_z: f64,
    /// Shaft radius, metres.
    pub radius_m: f64,
    /// Shaft height above the base, metres (trunks: up to the crown base).
    pub height_m: f64,
}

/// A tree canopy: an ellipsoid-like polyhedron above a trunk.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Canopy {
    /// Horizontal semi-axis in metres (in full leaf).
    pub radius_m: f64,
    /// Vertical semi-axis in metres (in full leaf).
    pub half_height_m: f64,
}

impl Canopy {
    /// Samples a canopy for a trunk of radius `trunk_radius_m`: thicker trunks carry larger
    /// crowns (horizontal semi-axis 1.5–4 m, vertical 1.2–3 m).
    pub fn sample(trunk_radius_m: f64, rng: &mut SimRng) -> Self {
        let age = ((trunk_radius_m - 0.1) / 0.3).clamp(0.0, 1.0);
        let radius_m = 1.5 + 2.5 * (0.6 * age + 0.4 * rng.random::<f64>());
        Self {
            radius_m,
            half_height_m: (radius_m * rng.random_range(0.7..1.0)).clamp(1.2, 3.0),
        }
    }
}
