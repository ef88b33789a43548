//! Parameters of IBuILD (Khan 2017, §4.4, §4.6.1).

use super::search::VocabularySearch;
use crate::{FeatureConfig, ImageConfig, PlaceError, Result, ScanShapeConfig};

/// Parameters of [`Ibuild`](super::Ibuild).
#[derive(Clone, Debug, PartialEq)]
pub struct IbuildConfig {
    /// Matching threshold δ in bits: descriptors and words match when `H < δ` (consecutive
    /// matching, merging and assignment alike). The thesis varies δ to trace its
    /// precision–recall points without printing the values (§4.6.1); default 80 of 512 bits
    /// (ours, the middle of a 30–120 sweep for BRISK).
    pub delta: u32,
    /// Temporal window β in frames: online users query the frames `< t − β` (§4.4.3); 10 as in
    /// §4.6.1. [`Ibuild`](super::Ibuild) itself takes `before` from the caller.
    pub beta: usize,
    /// How frames become images.
    pub image: ImageConfig,
    /// How planar scans are described: as images (the thesis' route, default) or by binary
    /// shape descriptors made on the scan.
    pub planar: PlanarDescriptors,
    /// Keypoints and descriptors.
    pub features: FeatureConfig,
    /// Require consecutive-frame matches to be mutual nearest neighbours (ours; default false,
    /// the thesis only thresholds the distance).
    pub mutual_matching: bool,
    /// Repeat the greedy merge pass of Fig. 4.8 until nothing merges (default false: the single
    /// pass as printed).
    pub merge_until_fixed_point: bool,
    /// Replace a matched vocabulary word by its centroid with the image's word (ablation; default
    /// false, the thesis does not update binary words).
    pub recentroid_matched: bool,
    /// Eq. (4.1) with ties going to 0 (a pair's centroid is then the AND) instead of 1 (the OR,
    /// as printed). Ablation, default false.
    pub strict_majority: bool,
    /// The similarity score of the candidates (default [`IbuildScore::Printed`], §4.4.3).
    pub score: IbuildScore,
    /// First-match search engine (identical answers; default [`VocabularySearch::Auto`]:
    /// multi-index hashing where it is expected to be faster than the scan; always the scan
    /// for [`PlanarDescriptors::Shape`], whose sparse bits defeat the hashing).
    pub search: VocabularySearch,
}

impl Default for IbuildConfig {
    fn default() -> Self {
        Self {
            delta: 80,
            beta: 10,
            image: ImageConfig::default(),
            planar: PlanarDescriptors::default(),
            features: FeatureConfig::default(),
            mutual_matching: false,
            merge_until_fixed_point: false,
            recentroid_matched: false,
            strict_majority: false,
            score: IbuildScore::Printed,
            search: VocabularySearch::default(),
        }
    }
}

/// How [`Ibuild`](super::Ibuild) describes a planar scan.
#[derive(Clone, Debug, Default, PartialEq)]
pub enum PlanarDescriptors {
    /// Rasterise the scan ([`ImageConfig`]) and describe the picture with FAST/BRIEF, as every
    /// other frame (default: the thesis describes images only, §4.4).
    #[default]
    Image,
    /// Binary shape descriptors made on the scan ([`crate::scan_shape_descriptors`]; ours).
    Shape(ScanShapeConfig),
}

/// Which similarity IBuILD reports for its hypotheses.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum IbuildScore {
    /// The modified Jaccard index as printed, normalised over the hypotheses
    /// (`Ŝ = S / Σ_L S`, §4.4.3). Its denominator counts the hypothesis' words missing from
    /// the query (`T`) but not the query's old words missing from the hypothesis, so an image
    /// whose words are a subset of the query's scores `S = 1`; and `Ŝ` depends on how many
    /// hypotheses a query has, so one threshold means different things for different queries.
    #[default]
    Printed,
    /// Ours: the same index made symmetric — the query's old words missing from the
    /// hypothesis enter the denominator like `T` (`Σ_{q∈Q} f_q⁻¹ |Q|`) — and not normalised,
    /// so scores are comparable across queries (a score threshold is then meaningful).
    Symmetric,
}

impl IbuildConfig {
    /// Checks δ ∈ 1..=512 and β ≥ 1.
    pub fn validate(&self) -> Result<()> {
        if !(1..=512).contains(&self.delta) {
            return Err(PlaceError::InvalidParameter {
                name: "delta",
                reason: format!("must be in 1..=512 bits, got {}", self.delta),
            });
        }
        if self.beta == 0 {
            return Err(PlaceError::InvalidParameter {
                name: "beta",
                reason: "must be at least 1 frame (β > 0, §4.4.3)".into(),
            });
        }
        if let PlanarDescriptors::Shape(shape) = &self.planar {
            shape.validate()?;
        }
        Ok(())
    }
}
