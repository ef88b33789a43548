//! Scoring a local map's detections per class set, and summing scorings.

use raypath_poles::{
    DetectionQuality, LabelledLocalMap, Pole, PoleClass, PoleParams, ReferencePole, ReferenceRule,
    ScoringRegion, class_quality,
};
use serde_json::{Value, json};

use super::diagnose::{FalsePositive, Miss, false_positives, misses};

/// Scoring radius around the scan positions, metres (as the semi-synthetic detection table).
pub(super) const RADIUS_M: f64 = 12.0;
/// Scoring margin inside the grid footprint, metres (hull 0.2 m + half the widest pole).
pub(super) const MARGIN_M: f64 = 1.0;
/// Matching radius, metres.
pub(super) const MATCH_M: f64 = 1.0;

/// The class sets reported: name and classes.
pub(super) const SETS: [(&str, &[PoleClass]); 5] = [
    ("pole", &[PoleClass::Pole]),
    ("trunk", &[PoleClass::Trunk]),
    ("traffic-sign", &[PoleClass::TrafficSign]),
    ("pole+trunk", &[PoleClass::Pole, PoleClass::Trunk]),
    (
        "all",
        &[PoleClass::Pole, PoleClass::Trunk, PoleClass::TrafficSign],
    ),
];

/// Summed counts of several scorings of one class set.
#[derive(Clone, Copy, Debug, Default, serde::Serialize)]
pub(super) struct Tally {
    pub detected: usize,
    pub truth: usize,
    pub matched: usize,
    pub error_sum_m: f64,
}

impl Tally {
    fn add(&mut self, q: &DetectionQuality) {
        self.detected += q.detected;
        self.truth += q.truth;
        self.matched += q.matched;
        self.error_sum_m += q.mean_centre_error_m * q.matched as f64;
    }

    /// Precision, recall and mean centre error of the sums.
    pub fn quality(&self) -> DetectionQuality {
        let mean = self.error_sum_m / self.matched.max(1) as f64;
        DetectionQuality::from_counts(self.detected, self.truth, &vec![mean; self.matched])
    }
}

/// The scoring of one or more local maps: a tally per class set, and extraction work.
#[derive(Clone, Debug, Default)]
pub(super) struct Scored {
    pub maps: usize,
    pub detections: usize,
    pub sets: [Tally; 5],
    pub rays: u64,
    pub secs: f64,
}

impl Scored {
    /// Adds another scoring.
    pub fn merge(&mut self, other: &Scored) {
        self.maps += other.maps;
        self.detections += other.detections;
        self.rays += other.rays;
        self.secs += other.secs;
        for (a, b) in self.sets.iter_mut().zip(&other.sets) {
            a.detected += b.detected;
            a.truth += b.truth;
            a.matched += b.matched;
            a.error_sum_m += b.error_sum_m;
        }
    }

    /// The counts and rates as JSON.
    pub fn json(&self) -> Value {
        let sets: serde_json::Map<String, Value> = SETS
            .iter()
            .zip(&self.sets)
            .map(|((name, _), t)| (name.to_string(), json!(t.quality())))
            .collect();
        json!({ "maps": self.maps, "detections": self.detections, "rays": self.rays,
                "secs": self.secs, "classes": sets })
    }
}

/// Scores `detected` against `references` inside `region`.
pub(super) fn score(
    detected: &[Pole],
    references: &[ReferencePole],
    region: &ScoringRegion,
) -> Scored {
    let det: Vec<Pole> = detected
        .iter()
        .filter(|p| region.contains(p.x, p.y))
        .copied()
        .collect();
    let refs: Vec<ReferencePole> = references
        .iter()
        .filter(|p| region.contains(p.x, p.y))
        .copied()
        .collect();
    let mut scored = Scored {
        maps: 1,
        detections: det.len(),
        ..Scored::default()
    };
    for (tally, (_, classes)) in scored.sets.iter_mut().zip(SETS) {
        tally.add(&class_quality(&det, &refs, classes, MATCH_M));
    }
    scored
}

/// One local map evaluated: all scans together, and each alone (pooled).
pub(super) struct Evaluated {
    pub full: Scored,
    pub single: Scored,
    pub misses: Vec<Miss>,
    pub false_positives: Vec<FalsePositive>,
    pub references: Vec<ReferencePole>,
    pub dropped: usize,
    /// The detections of the local map of all scans.
    pub poles: Vec<Pole>,
}

impl Evaluated {
    /// The scorings and diagnostics as JSON.
    pub fn json(&self) -> Value {
        json!({ "full": self.full.json(), "single": self.single.json(),
                "references": self.references, "dropped": self.dropped,
                "misses": self.misses, "false_positives": self.false_positives })
    }
}

/// Extracts and scores the local map of all scans and of every scan alone.
pub(super) fn evaluate(
    map: &LabelledLocalMap,
    params: &PoleParams,
    rule: &ReferenceRule,
) -> anyhow::Result<Evaluated> {
    let set = map.references(params, rule)?;
    let all = map.all();
    let (poles, stats) = map.extract(&all, params)?;
    let region = map.region(&all, params, RADIUS_M, MARGIN_M);
    let mut full = score(&poles, &set.poles, &region);
    full.rays = stats.rays;
    full.secs = stats.trace_secs + stats.score_secs;
    let misses = misses(map, &poles, &set.poles, &region, MATCH_M);
    let false_positives = false_positives(map, &poles, &set.poles, &region, MATCH_M);
    let mut single = Scored::default();
    for i in all {
        let (one_poles, stats) = map.extract(&[i], params)?;
        let region = map.region(&[i], params, RADIUS_M, MARGIN_M);
        let mut one = score(&one_poles, &set.poles, &region);
        one.rays = stats.rays;
        one.secs = stats.trace_secs + stats.score_secs;
        single.merge(&one);
    }
    Ok(Evaluated {
        full,
        single,
        misses,
        false_positives,
        references: set.poles,
        dropped: set.dropped,
        poles,
    })
}
