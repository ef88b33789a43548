//! Scoring against the SLAM benchmark's own relation files (Kümmerle et al. 2009): each
//! relation names two scans by their CARMEN ipc time stamps and gives their reference relative
//! pose, checked by hand by the benchmark's authors. This is the protocol of the published
//! figures (Cartographer, Hess et al. 2016, Table I; graph mapping and GMapping in Kümmerle et
//! al. 2009).

use raypath_geometry::Pose2;
use raypath_io::relations::Relation;
use raypath_reflectivity::benchmark::relation_error;

use super::{ErrorSummary, summarize};

/// Largest difference between a relation's time stamp and a scan's ipc time stamp for the two
/// to be the same scan, seconds. The files print six decimals; scans of the benchmark logs are
/// at least 10 ms apart.
pub const STAMP_TOLERANCE_SECS: f64 = 1e-4;

/// A relation file's relations found in a log: `(i, j, a_from_b)` with scan indices.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MatchedRelations {
    /// Relations whose two scans were found, in file order.
    pub relations: Vec<(usize, usize, Pose2)>,
    /// Relations with a time stamp that no scan has (reported, never silently dropped).
    pub unmatched: usize,
}

/// Finds the scans of `relations` among the log's scans by their ipc time stamps
/// (`ipc_stamps[k]` of scan `k`; `None` where a scan has none) within
/// [`STAMP_TOLERANCE_SECS`].
pub fn match_relation_file(ipc_stamps: &[Option<f64>], relations: &[Relation]) -> MatchedRelations {
    let mut sorted: Vec<(f64, usize)> = ipc_stamps
        .iter()
        .enumerate()
        .filter_map(|(k, s)| s.filter(|s| s.is_finite()).map(|s| (s, k)))
        .collect();
    sorted.sort_by(|a, b| a.0.total_cmp(&b.0));
    let find = |t: f64| -> Option<usize> {
        let at = sorted.partition_point(|(s, _)| *s < t);
        [at.checked_sub(1), Some(at)]
            .into_iter()
            .flatten()
            .filter_map(|k| sorted.get(k))
            .filter(|(s, _)| (s - t).abs() <= STAMP_TOLERANCE_SECS)
            .min_by(|a, b| (a.0 - t).abs().total_cmp(&(b.0 - t).abs()))
            .map(|&(_, k)| k)
    };
    let mut out = MatchedRelations::default();
    for r in relations {
        match (find(r.stamp_a_secs), find(r.stamp_b_secs)) {
            (Some(i), Some(j)) => out.relations.push((i, j, r.a_from_b)),
            _ => out.unmatched += 1,
        }
    }
    out
}

/// Relation errors of `estimate` (`world_from_sensor` per scan) against matched file relations:
/// for relation `(i, j, δ)`, the translation and angle of `δ⁻¹ (x_i⁻¹ x_j)` (Kümmerle et al.
/// 2009, eq. 3 split into its parts), as [`super::relation_errors`] does for derived relations.
pub fn file_relation_errors(estimate: &[Pose2], matched: &MatchedRelations) -> ErrorSummary {
    explicit_relation_errors(estimate, &matched.relations)
}

/// Relation errors of `estimate` against relations that carry their own relative pose
/// `(i, j, i_from_j)` (a relation file's, or [`super::refine_relations`]'); relations naming a
/// scan the estimate does not have are skipped.
pub fn explicit_relation_errors(
    estimate: &[Pose2],
    relations: &[(usize, usize, Pose2)],
) -> ErrorSummary {
    let (mut t, mut r) = (Vec::new(), Vec::new());
    for &(i, j, a_from_b) in relations {
        let (Some(a), Some(b)) = (estimate.get(i), estimate.get(j)) else {
            continue;
        };
        let (dt, dr) = relation_error(&Pose2::identity(), &a_from_b, a, b);
        t.push(dt);
        r.push(dr);
    }
    summarize(t, r)
}

/// Relations `(i, j)` of a reference trajectory in the benchmark's file format, named by the
/// scans' ipc time stamps; pairs where a stamp or a reference pose is missing are left out.
/// With [`raypath_io::relations::write_relations`], any reference (a corrected log, a
/// ground-truth bag) becomes a relation file the benchmark's tools read.
pub fn relations_from_reference(
    ipc_stamps: &[Option<f64>],
    reference: &[Option<Pose2>],
    pairs: &[(usize, usize)],
) -> Vec<Relation> {
    pairs
        .iter()
        .filter_map(|&(i, j)| {
            let (a, b) = ((*reference.get(i)?)?, (*reference.get(j)?)?);
            Some(Relation {
                stamp_a_secs: (*ipc_stamps.get(i)?)?,
                stamp_b_secs: (*ipc_stamps.get(j)?)?,
                a_from_b: a.inverse() * b,
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::benchmark::{consecutive_relations, relation_errors};

    fn trajectory(n: usize, wobble: f64) -> Vec<Pose2> {
        (0..n)
            .map(|k| {
                let s = k as f64;
                Pose2::new(
                    0.3 * s,
                    (0.2 * s).sin(),
                    0.05 * s + wobble * (1.7 * s).cos(),
                )
            })
            .collect()
    }

    /// A reference turned into a relation file scores an estimate exactly as the derived
    /// relations do; a stamp that no scan has is counted as unmatched.
    #[test]
    fn file_relations_equal_derived_relations() {
        let n = 40;
        let reference: Vec<Option<Pose2>> = trajectory(n, 0.0).into_iter().map(Some).collect();
        let estimate = trajectory(n, 0.01);
        let stamps: Vec<Option<f64>> = (0..n).map(|k| Some(1e9 + 0.25 * k as f64)).collect();
        let pairs = consecutive_relations(&(0..n).collect::<Vec<_>>());
        let mut file = relations_from_reference(&stamps, &reference, &pairs);
        // Six printed decimals move a stamp by at most half a microsecond.
        for r in &mut file {
            r.stamp_a_secs += 4e-7;
        }
        file.push(Relation {
            stamp_a_secs: 5.0,
            ..file[0]
        });
        let matched = match_relation_file(&stamps, &file);
        assert_eq!(matched.unmatched, 1);
        assert_eq!(matched.relations.len(), n - 1);
        let from_file = file_relation_errors(&estimate, &matched);
        let derived = relation_errors(&reference, &estimate, &pairs);
        assert_eq!(from_file.relations, derived.relations);
        assert!((from_file.trans_error_m - derived.trans_error_m).abs() < 1e-12);
        assert!((from_file.rot_error_deg - derived.rot_error_deg).abs() < 1e-9);
        assert!(derived.trans_error_m > 1e-4, "the wobble is measured");
        let exact = file_relation_errors(&trajectory(n, 0.0), &matched);
        assert!(exact.trans_error_m < 1e-12 && exact.rot_error_deg < 1e-9);
    }

    #[test]
    fn stamps_match_the_nearest_scan_within_tolerance() {
        let stamps = [Some(1.0), None, Some(1.0002), Some(1.01), Some(f64::NAN)];
        let rel = |a: f64, b: f64| Relation {
            stamp_a_secs: a,
            stamp_b_secs: b,
            a_from_b: Pose2::identity(),
        };
        let m = match_relation_file(
            &stamps,
            &[rel(1.00003, 1.01), rel(1.00015, 1.0002), rel(1.005, 1.0)],
        );
        assert_eq!(
            m.relations.iter().map(|r| (r.0, r.1)).collect::<Vec<_>>(),
            [(0, 3), (2, 2)]
        );
        assert_eq!(m.unmatched, 1);
        assert!(
            file_relation_errors(&[], &MatchedRelations::default())
                .trans_error_m
                .is_nan()
        );
    }
}
