//! Loop closures checked against a reference trajectory: the association error of each
//! accepted loop closure, and whether the reference itself is in doubt where it is wrong.

use raypath_geometry::{Pose2, Scan2};

use super::{PointIndex, loop_error, near_points, support_share};

/// A loop closure is wrong when its association error exceeds this, metres …
pub const WRONG_LOOP_M: f64 = 0.3;
/// … or this, degrees.
pub const WRONG_LOOP_DEG: f64 = 3.0;

/// Which node of the matched submap a loop closure's scan is compared with by
/// [`check_loops`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LoopPairing {
    /// The node whose scan shares the most with the loop's scan at their **reference** poses
    /// (the share of the loop scan's points within [`super::SUPPORT_TOLERANCE_M`] of the node
    /// scan's, [`super::support_share`]); the nearest node where no scan shares any. The
    /// choice looks at the reference and the scans only, never at the estimate. Two scans that
    /// see the same walls are related by the reference as tightly as the corrected log was
    /// matched; two that barely overlap are related only through the corrected log's path
    /// between them.
    Overlap,
    /// The node nearest to where the loop closure placed its scan.
    Nearest,
}

/// Checks every accepted loop closure of `output` against `reference` (per scan; `None` where
/// a scan has none): the **association error** of a loop closure is the error of the relative
/// pose between its node and a node of the matched submap (`pairing`: the one whose scan
/// overlaps most with the loop's, or the nearest; the front-end's pose of that node in the
/// submap, composed with the loop's `submap_from_sensor`), against the reference. It says
/// whether the scan was placed at the right spot of the submap; the anchor-to-node relation
/// would also charge the loop for the submap's own bending over its length, which the
/// intra-submap constraints carry. Scans without a reference borrow one from the nearest
/// referenced scan within `max_gap` scans ([`reference_by_neighbour`]). `scans` are the
/// log's scans, by the same index. Returns `(checked, wrong, checks)` with one [`LoopCheck`]
/// per checked loop closure.
pub fn check_loops(
    output: &crate::SlamOutput,
    scans: &[&Scan2],
    reference: &[Option<Pose2>],
    max_gap: usize,
    pairing: LoopPairing,
) -> (usize, usize, Vec<LoopCheck>) {
    let local: Vec<Pose2> = output.scans.iter().map(|s| s.local).collect();
    let near = reference_by_neighbour(reference, &local, max_gap);
    let node_local = |n: usize| output.node_scan.get(n).and_then(|&k| local.get(k)).copied();
    let mut checks = Vec::new();
    for (closure, c) in output.loop_closures.iter().enumerate() {
        let (Some(submap), Some(anchor_local), Some(&scan)) = (
            output.submaps.get(c.submap),
            node_local(c.anchor),
            output.node_scan.get(c.node),
        ) else {
            continue;
        };
        let Some(reference_scan) = near.get(scan).copied().flatten() else {
            continue;
        };
        // The submap's nodes with their scan, pose in the submap and reference.
        let nodes: Vec<(usize, Pose2, Pose2)> = submap
            .nodes()
            .iter()
            .filter_map(|&k| {
                let k_scan = *output.node_scan.get(k)?;
                let reference_k = near.get(k_scan).copied().flatten()?;
                Some((k_scan, anchor_local.inverse() * node_local(k)?, reference_k))
            })
            .collect();
        let distance = |p: &Pose2| (p.translation() - c.submap_from_sensor.translation()).norm();
        let nearest = nodes
            .iter()
            .min_by(|a, b| distance(&a.1).total_cmp(&distance(&b.1)));
        let chosen = match pairing {
            LoopPairing::Nearest => nearest,
            LoopPairing::Overlap => {
                let overlap = |&&(k_scan, _, reference_k): &&(usize, Pose2, Pose2)| {
                    let (Some(a), Some(b)) = (scans.get(k_scan), scans.get(scan)) else {
                        return 0.0;
                    };
                    support_share(a, b, &(reference_k.inverse() * reference_scan)).unwrap_or(0.0)
                };
                nodes
                    .iter()
                    .map(|n| (overlap(&n), n))
                    .filter(|(share, _)| *share > 0.0)
                    .max_by(|a, b| a.0.total_cmp(&b.0))
                    .map(|(_, n)| n)
                    .or(nearest)
            }
        };
        let Some(&(k_scan, submap_from_k, reference_near)) = chosen else {
            continue;
        };
        let measured = submap_from_k.inverse() * c.submap_from_sensor;
        if let Some((trans_m, rot_rad)) =
            loop_error(Some(reference_near), Some(reference_scan), measured)
        {
            checks.push(LoopCheck {
                closure,
                near_scan: k_scan,
                scan,
                measured,
                reference_near,
                reference_scan,
                trans_m,
                rot_rad,
            });
        }
    }
    let wrong = checks.iter().filter(|c| c.is_wrong()).count();
    (checks.len(), wrong, checks)
}

/// One loop closure checked against the reference by [`check_loops`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LoopCheck {
    /// Index into [`crate::SlamOutput::loop_closures`].
    pub closure: usize,
    /// The scan of the submap node it was compared with ([`LoopPairing`]).
    pub near_scan: usize,
    /// The scan the loop closure placed.
    pub scan: usize,
    /// The loop closure's relative pose `near_scan ← scan`.
    pub measured: Pose2,
    /// The reference pose of `near_scan` (borrowed by neighbour where the scan has no
    /// reference of its own).
    pub reference_near: Pose2,
    /// The reference pose of `scan` (borrowed likewise).
    pub reference_scan: Pose2,
    /// Association error: translation, metres.
    pub trans_m: f64,
    /// Association error: absolute angle, radians.
    pub rot_rad: f64,
}

impl LoopCheck {
    /// Above [`WRONG_LOOP_M`] or [`WRONG_LOOP_DEG`].
    pub fn is_wrong(&self) -> bool {
        self.trans_m > WRONG_LOOP_M || self.rot_rad.to_degrees() > WRONG_LOOP_DEG
    }

    /// The reference's relative pose `near_scan ← scan`.
    pub fn reference(&self) -> Pose2 {
        self.reference_near.inverse() * self.reference_scan
    }

    /// Whether the reference itself is in doubt at this loop closure: one of its two scans,
    /// placed at its reference pose, has less than half of its points (within
    /// [`super::SUPPORT_RANGE_M`]) within [`super::SUPPORT_TOLERANCE_M`] of the points of the referenced
    /// scans more than [`DISPUTE_GAP`] scans away, placed at theirs ([`reference_support`]).
    /// A corrected log can be wrong at single scans; an association error measured against
    /// such a reference says nothing about the loop closure. Reported beside the wrong
    /// count, never instead of it.
    ///
    /// The reference is also in doubt where its own path near either scan is refuted by the
    /// scans ([`reference_refuted_near`]).
    pub fn reference_disputed(&self, scans: &[&Scan2], reference: &[Option<Pose2>]) -> bool {
        [
            (self.near_scan, self.reference_near),
            (self.scan, self.reference_scan),
        ]
        .into_iter()
        .any(|(i, pose)| {
            reference_support(scans, reference, i, &pose).is_some_and(|s| s < 0.5)
                || reference_refuted_near(scans, reference, i)
        })
    }
}

/// How many of `checks` are wrong at a disputed reference
/// ([`LoopCheck::reference_disputed`]).
pub fn wrong_at_disputed_reference(
    checks: &[LoopCheck],
    scans: &[&Scan2],
    reference: &[Option<Pose2>],
) -> usize {
    checks
        .iter()
        .filter(|c| c.is_wrong() && c.reference_disputed(scans, reference))
        .count()
}

/// Scans closer than this (by index) to the scan under test are left out of the map that
/// [`reference_support`] checks it against: 30, a few metres of travel in the logs we read.
pub const DISPUTE_GAP: usize = 30;

/// The share of scan `i`'s points (within [`super::SUPPORT_RANGE_M`]), placed at `pose`, within
/// [`super::SUPPORT_TOLERANCE_M`] of the points of every referenced scan more than [`DISPUTE_GAP`]
/// scans from `i`, placed at its reference pose; `None` without points.
/// See [`reference_refuted_near`] for the other ground of a dispute.
pub fn reference_support(
    scans: &[&Scan2],
    reference: &[Option<Pose2>],
    i: usize,
    pose: &Pose2,
) -> Option<f64> {
    let map = PointIndex::new(
        scans
            .iter()
            .zip(reference)
            .enumerate()
            .filter(|(m, _)| m.abs_diff(i) > DISPUTE_GAP)
            .filter_map(|(_, (scan, r))| Some(near_points(scan, r.as_ref()?).collect::<Vec<_>>()))
            .flatten(),
    );
    map.share(near_points(scans.get(i)?, pose))
}

/// For scans without a reference pose, a reference **by neighbour**: the nearest referenced
/// scan (by index, at most `max_gap` scans away) composed with the front-end's relative
/// motion to it (`local`: the front-end's poses, accurate over a few scans). Used to check
/// loop closures whose scans are not in the corrected log.
pub fn reference_by_neighbour(
    reference: &[Option<Pose2>],
    local: &[Pose2],
    max_gap: usize,
) -> Vec<Option<Pose2>> {
    let n = reference.len().min(local.len());
    (0..n)
        .map(|k| {
            if let Some(r) = reference[k] {
                return Some(r);
            }
            let lo = k.saturating_sub(max_gap);
            let hi = (k + max_gap).min(n - 1);
            let nearest = (lo..=hi)
                .filter(|&m| reference[m].is_some())
                .min_by_key(|&m| m.abs_diff(k))?;
            Some(reference[nearest]? * (local[nearest].inverse() * local[k]))
        })
        .collect()
}

/// Referenced scans on each side of a scan whose consecutive reference relations
/// [`reference_refuted_near`] checks: 3.
pub const REFUTE_SPAN: usize = 3;

/// Whether the reference's own path near scan `k` is refuted by its scans: among the
/// consecutive relations of the [`REFUTE_SPAN`] referenced scans before and after `k` (and `k`
/// itself when referenced), one whose reference lays less than half of its second scan on
/// the first (as [`super::scan_supported`]) while aligning the two scans from it
/// ([`super::refine`], corrections up to 1 m and 30°) reaches a relation that does, more than
/// [`WRONG_LOOP_M`] or [`WRONG_LOOP_DEG`] away. A corrected log that turns a run of scans
/// against the scans' own alignment and turns back later is such a place (the corrected MIT
/// CSAIL log does at scans 1887–1898); a loop closure checked there is measured against the
/// excursion. Looks at the reference and the scans only, never at an estimate.
pub fn reference_refuted_near(scans: &[&Scan2], reference: &[Option<Pose2>], k: usize) -> bool {
    let referenced = |range: &mut dyn Iterator<Item = usize>| -> Vec<usize> {
        range
            .filter(|&m| reference.get(m).is_some_and(Option::is_some))
            .take(REFUTE_SPAN)
            .collect()
    };
    let mut run = referenced(&mut (0..k).rev());
    run.reverse();
    run.extend(referenced(&mut (k..reference.len())));
    let wide = super::RefineConfig {
        max_correction: (1.0, 30f64.to_radians()),
        ..super::RefineConfig::default()
    };
    run.windows(2).any(|w| {
        let Some((si, sj, i_from_j)) = super::reference_pair(scans, reference, (w[0], w[1])) else {
            return false;
        };
        if support_share(si, sj, &i_from_j).is_none_or(|s| s >= 0.5) {
            return false;
        }
        super::refine(si, sj, i_from_j, &wide).is_ok_and(|aligned| {
            let (t, r) =
                super::relation_error(&Pose2::identity(), &i_from_j, &Pose2::identity(), &aligned);
            t > WRONG_LOOP_M || r.abs().to_degrees() > WRONG_LOOP_DEG
        })
    })
}
