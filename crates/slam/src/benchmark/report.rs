//! The scores of one run against its reference, as `raypath slam --json` reports them (the
//! JSON keys are a contract).

use std::path::PathBuf;

use raypath_io::sequence::PlanarFrame;
use serde::Serialize;

use super::{
    Dropped, ErrorSummary, LoopPairing, MatchedRelations, RefineConfig, check_loops,
    consecutive_relations, explicit_relation_errors, file_relation_errors, random_relations,
    refine_relations, relation_errors, wrong_at_disputed_reference,
};
use crate::SlamOutput;
use crate::error::Result;

/// Loop closures between scans without a reference are checked against the nearest referenced
/// scan at most this many scans away, moved by the front-end's relative motion.
pub const NEIGHBOUR_GAP: usize = 50;

/// The consecutive relations refined by aligning their two scans ([`refine_relations`]).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ScanRefined {
    /// The run scored against the refined relations that were kept.
    pub summary: ErrorSummary,
    /// The relations not kept, by reason.
    pub dropped: Dropped,
    /// Mean correction of the reference's relations, metres.
    pub reference_moved_m: f64,
}

/// A run scored against a reference trajectory (a corrected log paired scan by scan).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ReferenceScore {
    /// Scans paired with the reference.
    pub paired_scans: usize,
    /// Relation errors over consecutive referenced scans.
    pub summary: ErrorSummary,
    /// The same over 1000 seeded random pairs of referenced scans.
    pub random_pairs: ErrorSummary,
    /// The same over the scan-refined consecutive relations.
    pub scan_refined: ScanRefined,
    /// Accepted loop closures that could be checked.
    pub loop_closures_checked: usize,
    /// Checked loop closures whose association error is above 0.3 m or 3°
    /// ([`LoopPairing::Overlap`]).
    pub wrong_loop_closures: usize,
    /// The same against the node nearest to where the loop placed the scan.
    pub wrong_loop_closures_nearest_node: usize,
    /// Wrong ones where the reference disagrees with its own scans.
    pub wrong_loop_closures_reference_disputed: usize,
}

/// Scores `out` against the reference poses of `frames` (the processed frames, paired with
/// the reference, e.g. by [`raypath_io::sequence::pair_reference`]; `paired_scans` is what
/// the pairing returned): relation errors over consecutive and random pairs (Kümmerle et al.
/// 2009), over the scan-refined consecutive relations, and the check of every loop closure.
pub fn score_reference(
    frames: &[PlanarFrame],
    paired_scans: usize,
    out: &SlamOutput,
) -> Result<ReferenceScore> {
    let truth: Vec<_> = frames.iter().map(|f| f.reference).collect();
    let referenced: Vec<usize> = (0..frames.len()).filter(|&i| truth[i].is_some()).collect();
    let summary = relation_errors(
        &truth,
        &out.world_from_sensor,
        &consecutive_relations(&referenced),
    );
    let random = relation_errors(
        &truth,
        &out.world_from_sensor,
        &random_relations(&referenced, 1000, 1),
    );
    let scans: Vec<_> = frames.iter().map(|f| &f.scan).collect();
    let (checked, wrong, checks) =
        check_loops(out, &scans, &truth, NEIGHBOUR_GAP, LoopPairing::Overlap);
    let (_, wrong_nearest, _) =
        check_loops(out, &scans, &truth, NEIGHBOUR_GAP, LoopPairing::Nearest);
    let refined = refine_relations(
        &scans,
        &truth,
        &consecutive_relations(&referenced),
        &RefineConfig::default(),
    )?;
    let (moved, _) = refined.correction_m();
    let disputed = wrong_at_disputed_reference(&checks, &scans, &truth);
    Ok(ReferenceScore {
        paired_scans,
        summary,
        random_pairs: random,
        scan_refined: ScanRefined {
            summary: explicit_relation_errors(&out.world_from_sensor, &refined.relations),
            dropped: refined.dropped,
            reference_moved_m: moved,
        },
        loop_closures_checked: checked,
        wrong_loop_closures: wrong,
        wrong_loop_closures_nearest_node: wrong_nearest,
        wrong_loop_closures_reference_disputed: disputed,
    })
}

/// A run scored against the benchmark's own relation file.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct RelationFileScore {
    /// The relation file.
    pub path: PathBuf,
    /// Relation errors over its relations found in the log.
    pub summary: ErrorSummary,
    /// Its relations naming a scan the log does not have.
    pub unmatched: usize,
}

impl RelationFileScore {
    /// The score of `out` over `matched` (from [`super::match_relation_file`]) of the file
    /// `path`.
    pub fn new(path: PathBuf, matched: &MatchedRelations, out: &SlamOutput) -> Self {
        Self {
            path,
            summary: file_relation_errors(&out.world_from_sensor, matched),
            unmatched: matched.unmatched,
        }
    }
}
