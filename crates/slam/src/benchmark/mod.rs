//! The SLAM benchmark metric of Kümmerle et al. (2009, "On measuring the accuracy of SLAM
//! algorithms"): errors of relative poses over *relations* — pairs of scans whose reference
//! relative pose is known — translational and rotational, mean ± standard deviation.
//!
//! The benchmark's own relation files are not distributed with the logs we read, so relations
//! are derived from a reference trajectory (the corrected log paired scan by scan with the raw
//! log, [`raypath_io::sequence::pair_reference`]):
//!
//! * **consecutive**: every pair of consecutive referenced scans (local accuracy, as in the
//!   benchmark's relations between nearby poses);
//! * **random pairs**: seeded uniform pairs of referenced scans anywhere in the log (global
//!   consistency, as in the benchmark's relations across loops).
//!
//! The relation set is written into every report so the numbers can be reproduced.
//!
//! Where the benchmark's relation files are at hand (`intel.relations` …, read by
//! [`raypath_io::relations`]), [`match_relation_file`] finds their scans by the logs' ipc time
//! stamps and [`file_relation_errors`] scores an estimate against them: the benchmark's own
//! protocol, like for like with the published figures.
//!
//! A corrected log carries the local errors of the mapping run that made it. Where the
//! benchmark's files are missing, [`refine_relations`] refines the derived relations by
//! aligning their two scans and keeps those whose alignment is unique and well constrained
//! (its docs give the checks); [`explicit_relation_errors`] scores against them.

use raypath_geometry::Pose2;
use raypath_reflectivity::benchmark::{Stats, relation_error, relation_error_lists};
use serde::{Deserialize, Serialize};

mod loop_check;
mod refine;
mod relation_file;
mod report;

pub use loop_check::{
    DISPUTE_GAP, LoopCheck, LoopPairing, REFUTE_SPAN, WRONG_LOOP_DEG, WRONG_LOOP_M, check_loops,
    reference_by_neighbour, reference_refuted_near, reference_support, wrong_at_disputed_reference,
};
pub use refine::{Dropped, RefineConfig, Refined, Refusal, refine, refine_relations};
pub use relation_file::{
    MatchedRelations, STAMP_TOLERANCE_SECS, explicit_relation_errors, file_relation_errors,
    match_relation_file, relations_from_reference,
};
pub use report::{NEIGHBOUR_GAP, ReferenceScore, RelationFileScore, ScanRefined, score_reference};

/// Mean and standard deviation of the relation errors: the JSON keys are a contract of
/// `raypath slam --ground-truth`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct ErrorSummary {
    /// Mean translational error, metres.
    pub trans_error_m: f64,
    /// Its standard deviation, metres.
    pub trans_error_std_m: f64,
    /// Mean absolute rotational error, degrees.
    pub rot_error_deg: f64,
    /// Its standard deviation, degrees.
    pub rot_error_std_deg: f64,
    /// Relations evaluated.
    pub relations: usize,
}

/// Relations `(i, j)` between consecutive entries of `referenced` (indices of scans with a
/// reference pose, increasing).
pub fn consecutive_relations(referenced: &[usize]) -> Vec<(usize, usize)> {
    referenced.windows(2).map(|w| (w[0], w[1])).collect()
}

/// `count` seeded pseudo-random relations between distinct entries of `referenced` (ChaCha8 on
/// `seed`; the same seed gives the same relations).
pub fn random_relations(referenced: &[usize], count: usize, seed: u64) -> Vec<(usize, usize)> {
    use rand::{Rng, SeedableRng};
    let n = referenced.len();
    if n < 2 {
        return Vec::new();
    }
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    (0..count)
        .map(|_| {
            let a = rng.random_range(0..n);
            let mut b = rng.random_range(0..n - 1);
            if b >= a {
                b += 1;
            }
            (referenced[a.min(b)], referenced[a.max(b)])
        })
        .collect()
}

/// Relation errors of `estimate` against `reference` (index-aligned; `None` where a scan has
/// no reference). The translational error of relation `(i, j)` is `‖t(δ_ref⁻¹ δ_est)‖` with
/// `δ = x_i⁻¹ x_j`, the rotational error the absolute angle of the same pose (Kümmerle et al.
/// 2009, eq. 3 split into its parts).
pub fn relation_errors(
    reference: &[Option<Pose2>],
    estimate: &[Pose2],
    relations: &[(usize, usize)],
) -> ErrorSummary {
    let (t, r) = relation_error_lists(
        |i| reference.get(i).and_then(Option::as_ref),
        estimate,
        relations,
    );
    summarize(t, r)
}

/// The summary of translational (m) and rotational (rad, signed) relation errors; NaN figures
/// when there are none.
fn summarize(translations: Vec<f64>, rotations_rad: Vec<f64>) -> ErrorSummary {
    let degrees = rotations_rad.into_iter().map(|dr| dr.abs().to_degrees());
    let (t, r) = (Stats::of(translations), Stats::of(degrees));
    let nan_if_empty = |v: f64| if t.count == 0 { f64::NAN } else { v };
    ErrorSummary {
        trans_error_m: nan_if_empty(t.mean),
        trans_error_std_m: nan_if_empty(t.std),
        rot_error_deg: nan_if_empty(r.mean),
        rot_error_std_deg: nan_if_empty(r.std),
        relations: t.count,
    }
}

/// The error of a measured relative pose `a⁻¹ b` against the reference poses of `a` and `b`:
/// translation (m) and absolute angle (rad); `None` when either reference is missing.
pub fn loop_error(
    reference_a: Option<Pose2>,
    reference_b: Option<Pose2>,
    measured_a_from_b: Pose2,
) -> Option<(f64, f64)> {
    let (a, b) = (reference_a?, reference_b?);
    let (t, r) = relation_error(&a, &b, &Pose2::identity(), &measured_a_from_b);
    Some((t, r.abs()))
}

/// A relation is **scan-supported** when its reference relative pose lays at least half of
/// the second scan's points (within [`SUPPORT_RANGE_M`]) within this distance of a point of
/// the first: 0.1 m (ours).
pub const SUPPORT_TOLERANCE_M: f64 = 0.1;
/// Points farther from the sensor than this are left out of the support check, metres.
pub const SUPPORT_RANGE_M: f64 = 10.0;

/// The relations whose reference the scans themselves support: for `(i, j)`, the points of
/// scan `j` placed by the reference `x_i⁻¹ x_j` into scan `i`'s frame, and the share of them
/// with a point of scan `i` within [`SUPPORT_TOLERANCE_M`]; supported when that share is at
/// least one half (a median nearest-neighbour distance within the tolerance).
///
/// A reference derived from a corrected log can be wrong at single scans (the corrected MIT
/// CSAIL log turns single scans by 10–20° against both neighbours, while the scans align
/// without the turn); Kümmerle et al. (2009) checked their relations by hand. The check uses
/// only the reference and the scans, never the estimate, so it cannot favour one. Relations
/// between scans that do not overlap are not supported either, so the supported set also
/// leaves out hard relations: report it beside the full set, never instead of it.
pub fn scan_supported(
    scans: &[&raypath_geometry::Scan2],
    reference: &[Option<Pose2>],
    relations: &[(usize, usize)],
) -> Vec<(usize, usize)> {
    relations
        .iter()
        .copied()
        .filter(|&pair| {
            reference_pair(scans, reference, pair)
                .and_then(|(si, sj, i_from_j)| support_share(si, sj, &i_from_j))
                .is_some_and(|s| s >= 0.5)
        })
        .collect()
}

/// The two scans of the relation `(i, j)` and their reference relative pose `i_from_j`;
/// `None` when a scan or a reference pose is missing.
fn reference_pair<'a>(
    scans: &[&'a raypath_geometry::Scan2],
    reference: &[Option<Pose2>],
    (i, j): (usize, usize),
) -> Option<(
    &'a raypath_geometry::Scan2,
    &'a raypath_geometry::Scan2,
    Pose2,
)> {
    let (xi, xj) = ((*reference.get(i)?)?, (*reference.get(j)?)?);
    Some((scans.get(i)?, scans.get(j)?, xi.inverse() * xj))
}

/// The share of scan `j`'s points (within [`SUPPORT_RANGE_M`] of its sensor) that the
/// relative pose `i_from_j` lays within [`SUPPORT_TOLERANCE_M`] of a point of scan `i`;
/// `None` when scan `j` has no such point.
pub fn support_share(
    scan_i: &raypath_geometry::Scan2,
    scan_j: &raypath_geometry::Scan2,
    i_from_j: &Pose2,
) -> Option<f64> {
    let index = PointIndex::new(near_points(scan_i, &Pose2::identity()));
    index.share(near_points(scan_j, i_from_j))
}

/// The points of `scan` within [`SUPPORT_RANGE_M`] of its sensor, placed by `pose`.
pub fn near_points<'a>(
    scan: &'a raypath_geometry::Scan2,
    pose: &'a Pose2,
) -> impl Iterator<Item = nalgebra::Point2<f64>> + 'a {
    scan.points(Pose2::identity())
        .filter(|p| p.coords.norm() <= SUPPORT_RANGE_M)
        .map(move |p| *pose * p)
}

/// Points hashed into [`SUPPORT_TOLERANCE_M`] cells, for "is there a point within the
/// tolerance" queries.
#[derive(Debug, Default)]
pub struct PointIndex {
    cells: std::collections::HashMap<(i64, i64), Vec<[f64; 2]>>,
}

impl PointIndex {
    /// Indexes `points`.
    pub fn new(points: impl IntoIterator<Item = nalgebra::Point2<f64>>) -> Self {
        let mut index = Self::default();
        for p in points {
            index
                .cells
                .entry(Self::key(&p))
                .or_default()
                .push([p.x, p.y]);
        }
        index
    }

    fn key(p: &nalgebra::Point2<f64>) -> (i64, i64) {
        let cell = SUPPORT_TOLERANCE_M;
        ((p.x / cell).floor() as i64, (p.y / cell).floor() as i64)
    }

    /// Whether an indexed point lies within [`SUPPORT_TOLERANCE_M`] of `q`.
    pub fn near(&self, q: &nalgebra::Point2<f64>) -> bool {
        let (kx, ky) = Self::key(q);
        (-1..=1).any(|dx| {
            (-1..=1).any(|dy| {
                self.cells
                    .get(&(kx + dx, ky + dy))
                    .is_some_and(|cell_points| {
                        cell_points
                            .iter()
                            .any(|c| (c[0] - q.x).hypot(c[1] - q.y) <= SUPPORT_TOLERANCE_M)
                    })
            })
        })
    }

    /// The share of `points` near an indexed point; `None` for no points.
    pub fn share(&self, points: impl IntoIterator<Item = nalgebra::Point2<f64>>) -> Option<f64> {
        let (mut close, mut total) = (0usize, 0usize);
        for q in points {
            total += 1;
            close += usize::from(self.near(&q));
        }
        (total > 0).then(|| close as f64 / total as f64)
    }
}

/// Self-consistency of a map without reference poses: of the confidently occupied cells of
/// each finished submap (log-odds > 2, finest level) that fall, at the optimised submap poses,
/// on confidently observed cells of another submap that shares no node with it, the fraction
/// that the other submap holds confidently **free** (log-odds < −2) with none of its own
/// confidently occupied cells within [`DISAGREEMENT_TOLERANCE_M`]. Walls seen through free
/// space of another visit are what a broken loop (or a missed one) leaves behind; a
/// consistent map scores close to 0. The tolerance keeps a wall drawn one or two cells
/// thicker or thinner by the other visit (5 cm cells) from counting. Returns
/// `(fraction, cells compared)`.
pub fn submap_disagreement(output: &crate::SlamOutput) -> (f64, usize) {
    let (mut conflicts, mut compared) = (0usize, 0usize);
    visit_disagreement(output, |_, conflict| {
        compared += 1;
        conflicts += usize::from(conflict);
    });
    let fraction = if compared == 0 {
        0.0
    } else {
        conflicts as f64 / compared as f64
    };
    (fraction, compared)
}

/// The world positions of the cells that [`submap_disagreement`] counts as disagreeing (a
/// cell once per pair of submaps), for a picture of where a map disagrees with itself.
pub fn disagreement_points(output: &crate::SlamOutput) -> Vec<nalgebra::Point2<f64>> {
    let mut points = Vec::new();
    visit_disagreement(output, |p, conflict| {
        if conflict {
            points.push(p);
        }
    });
    points
}

/// Calls `visit(world point, disagrees)` for every cell [`submap_disagreement`] compares.
fn visit_disagreement(
    output: &crate::SlamOutput,
    mut visit: impl FnMut(nalgebra::Point2<f64>, bool),
) {
    const CONFIDENT: f32 = 2.0;
    let submaps = &output.submaps;
    let pose = |s: &crate::Submap| output.nodes.get(s.anchor()).copied();
    for (a, sa) in submaps.iter().enumerate() {
        let (Some(world_from_a), Some(la)) = (pose(sa), sa.levels().first()) else {
            continue;
        };
        let (res, o) = (la.resolution_m(), la.origin());
        let near = (DISAGREEMENT_TOLERANCE_M / res).round() as usize;
        for (b, sb) in submaps.iter().enumerate() {
            let (Some(world_from_b), Some(lb)) = (pose(sb), sb.levels().first()) else {
                continue;
            };
            if a == b || sa.nodes().iter().any(|n| sb.nodes().contains(n)) {
                continue;
            }
            let b_from_a = world_from_b.inverse() * world_from_a;
            let reach = (la.width().max(la.height()) + lb.width().max(lb.height())) as f64 * res;
            let (ca, cb) = (sa.centre(), sb.centre());
            let ca_in_b = b_from_a * nalgebra::Point2::new(ca[0], ca[1]);
            if (ca_in_b.coords - nalgebra::Vector2::new(cb[0], cb[1])).norm() > reach / 2.0 {
                continue;
            }
            for j in 0..la.height() {
                for i in 0..la.width() {
                    if la.log_odds(i, j) <= CONFIDENT {
                        continue;
                    }
                    let p = nalgebra::Point2::new(
                        o[0] + (i as f64 + 0.5) * res,
                        o[1] + (j as f64 + 0.5) * res,
                    );
                    let q = b_from_a * p;
                    let Some((bi, bj)) = lb.cell_of(q.x, q.y) else {
                        continue;
                    };
                    let l = lb.log_odds(bi, bj);
                    if l.abs() > CONFIDENT {
                        let conflict =
                            l < -CONFIDENT && !occupied_near(lb, (bi, bj), near, CONFIDENT);
                        visit(world_from_a * p, conflict);
                    }
                }
            }
        }
    }
}

/// How far a wall of one submap may lie from the other submap's wall on the same spot before
/// [`submap_disagreement`] counts it: 0.15 m (three 5 cm cells; ours).
pub const DISAGREEMENT_TOLERANCE_M: f64 = 0.15;

/// Whether a cell within `near` cells (Chebyshev) of `cell` has log-odds above `confident`.
fn occupied_near(
    level: &raypath_reflectivity::GridLevel,
    (i, j): (usize, usize),
    near: usize,
    confident: f32,
) -> bool {
    let (w, h) = (level.width(), level.height());
    (j.saturating_sub(near)..=(j + near).min(h - 1)).any(|y| {
        (i.saturating_sub(near)..=(i + near).min(w - 1)).any(|x| level.log_odds(x, y) > confident)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_perfect_estimate_has_zero_error_and_a_shifted_one_its_shift() {
        let truth: Vec<Pose2> = (0..20)
            .map(|k| Pose2::new(k as f64 * 0.5, (k as f64 * 0.3).sin(), k as f64 * 0.1))
            .collect();
        let reference: Vec<Option<Pose2>> = truth.iter().map(|p| Some(*p)).collect();
        let idx: Vec<usize> = (0..20).collect();
        let rel = consecutive_relations(&idx);
        assert_eq!(rel.len(), 19);
        let s = relation_errors(&reference, &truth, &rel);
        assert!(s.trans_error_m < 1e-12 && s.rot_error_deg < 1e-9);
        // The whole trajectory moved rigidly: relative poses unchanged.
        let moved: Vec<Pose2> = truth
            .iter()
            .map(|p| Pose2::new(3.0, -2.0, 1.0) * *p)
            .collect();
        let s = relation_errors(&reference, &moved, &random_relations(&idx, 50, 7));
        assert!(s.trans_error_m < 1e-9 && s.relations == 50);
        // One scan displaced by 0.1 m: the two relations touching it are off by 0.1 m.
        let mut bad = truth.clone();
        bad[10] = bad[10] * Pose2::new(0.1, 0.0, 0.0);
        let s = relation_errors(&reference, &bad, &rel);
        assert!((s.trans_error_m - 0.2 / 19.0).abs() < 1e-9);
    }

    /// Exact 360-beam scans of a 7 m × 4.5 m room from `poses`.
    fn room_scans(poses: &[Pose2]) -> Vec<raypath_geometry::Scan2> {
        use nalgebra::Point2;
        use raypath_geometry::Scan2;
        use raypath_sim::scene2::{SceneBuilder2, Surface};
        let mut room = SceneBuilder2::new();
        let wall = room.add_surface(Surface {
            label: 10,
            reflectivity: 0.5,
        });
        let corners = [(-3.0, -2.0), (4.0, -2.0), (4.0, 2.5), (-3.0, 2.5)];
        room.add_polygon(&corners.map(|(x, y)| Point2::new(x, y)), wall);
        let room = room.build().unwrap();
        let step = std::f64::consts::PI / 180.0;
        poses
            .iter()
            .map(|p| Scan2 {
                angle_min_rad: -std::f64::consts::PI,
                angle_increment_rad: step,
                max_range_m: 30.0,
                ranges: (0..360)
                    .map(|k| {
                        let a = p.theta() - std::f64::consts::PI + k as f64 * step;
                        let origin = Point2::new(p.x(), p.y());
                        room.cast_angle(&origin, a, 30.0)
                            .map_or(30.0, |h| h.range_m)
                    })
                    .collect(),
                intensities: None,
            })
            .collect()
    }

    #[test]
    fn a_reference_that_misplaces_a_scan_is_not_supported() {
        use raypath_geometry::Scan2;
        // Two poses 0.3 m apart; the scans are exact.
        let poses = [Pose2::new(0.0, 0.0, 0.0), Pose2::new(0.3, 0.1, 0.05)];
        let scans = room_scans(&poses);
        let refs: Vec<&Scan2> = scans.iter().collect();
        let right = vec![Some(poses[0]), Some(poses[1])];
        assert_eq!(scan_supported(&refs, &right, &[(0, 1)]), vec![(0, 1)]);
        let turned = vec![Some(poses[0]), Some(poses[1] * Pose2::new(0.0, 0.0, 0.2))];
        assert!(scan_supported(&refs, &turned, &[(0, 1)]).is_empty());
        let missing = vec![Some(poses[0]), None];
        assert!(scan_supported(&refs, &missing, &[(0, 1)]).is_empty());
    }

    #[test]
    fn a_reference_pose_that_disagrees_with_the_rest_is_disputed() {
        use raypath_geometry::Scan2;
        // 80 scans along the room; the reference turns scan 40 by 0.2 rad.
        let poses: Vec<Pose2> = (0..80)
            .map(|k| Pose2::new(-2.0 + 0.06 * k as f64, 0.2, 0.01 * k as f64))
            .collect();
        let scans = room_scans(&poses);
        let refs: Vec<&Scan2> = scans.iter().collect();
        let mut reference: Vec<Option<Pose2>> = poses.iter().copied().map(Some).collect();
        let right = reference_support(&refs, &reference, 40, &poses[40]).unwrap();
        assert!(right > 0.95, "{right}");
        let turned = poses[40] * Pose2::new(0.0, 0.0, 0.2);
        reference[40] = Some(turned);
        let wrong = reference_support(&refs, &reference, 40, &turned).unwrap();
        assert!(wrong < 0.5, "{wrong}");
        let check = LoopCheck {
            closure: 0,
            near_scan: 0,
            scan: 40,
            measured: poses[0].inverse() * poses[40],
            reference_near: poses[0],
            reference_scan: turned,
            trans_m: 0.0,
            rot_rad: 0.2,
        };
        assert!(check.is_wrong() && check.reference_disputed(&refs, &reference));
        let undisputed = LoopCheck {
            reference_scan: poses[40],
            ..check
        };
        reference[40] = Some(poses[40]);
        assert!(!undisputed.reference_disputed(&refs, &reference));
    }

    /// A reference that turns a run of scans by 12° against their own alignment and turns
    /// back later is refuted near the run, not far from it, and never where it is exact.
    #[test]
    fn a_reference_excursion_is_refuted_by_the_scans() {
        use raypath_geometry::Scan2;
        // 16 scans spinning through the room, 0.1 m and 0.4 rad apart; every other one
        // referenced, as in a corrected log.
        let poses: Vec<Pose2> = (0..16)
            .map(|k| Pose2::new(-1.0 + 0.1 * k as f64, 0.1, 0.4 * k as f64))
            .collect();
        let scans = room_scans(&poses);
        let refs: Vec<&Scan2> = scans.iter().collect();
        let exact: Vec<Option<Pose2>> = poses
            .iter()
            .enumerate()
            .map(|(k, p)| (k % 2 == 0).then_some(*p))
            .collect();
        assert!((0..16).all(|k| !reference_refuted_near(&refs, &exact, k)));
        let mut excursion = exact.clone();
        for r in excursion.iter_mut().take(10).skip(6).flatten() {
            *r = *r * Pose2::new(0.0, 0.0, 0.21);
        }
        assert!(reference_refuted_near(&refs, &excursion, 7));
        assert!(reference_refuted_near(&refs, &excursion, 10));
        assert!(!reference_refuted_near(&refs, &excursion, 0));
    }

    #[test]
    fn random_relations_are_seeded_and_distinct() {
        let idx: Vec<usize> = (0..100).map(|k| 3 * k).collect();
        let a = random_relations(&idx, 200, 1);
        assert_eq!(a, random_relations(&idx, 200, 1));
        assert_ne!(a, random_relations(&idx, 200, 2));
        assert!(a.iter().all(|(i, j)| i < j && i % 3 == 0 && j % 3 == 0));
    }

    #[test]
    fn neighbours_lend_their_reference_moved_by_the_local_motion() {
        let local: Vec<Pose2> = (0..10).map(|k| Pose2::new(k as f64, 0.0, 0.0)).collect();
        let world = Pose2::new(5.0, 5.0, 1.0);
        let mut reference = vec![None; 10];
        reference[4] = Some(world * local[4]);
        let near = reference_by_neighbour(&reference, &local, 3);
        assert!(near[0].is_none() && near[8].is_none());
        for k in 1..=7 {
            let p = near[k].unwrap();
            let truth = world * local[k];
            assert!(
                (p.translation() - truth.translation()).norm() < 1e-12,
                "{k}"
            );
        }
        let err = loop_error(near[2], near[6], local[2].inverse() * local[6]).unwrap();
        assert!(err.0 < 1e-12 && err.1 < 1e-12);
    }
}
