//! Scan-refined relations: reference relations refined by aligning their own two scans,
//! kept where that alignment is unique and well constrained ([`refine_relations`]).

use kiddo::{ImmutableKdTree, SquaredEuclidean};
use nalgebra::{Matrix2, Matrix3, Point2, Vector2, Vector3};
use raypath_geometry::line_normal;
use raypath_geometry::{Pose2, Scan2};

use super::{near_points, reference_pair};

/// Settings of [`refine_relations`]; the defaults are ours (its docs give them in words).
#[derive(Clone, Debug, PartialEq)]
pub struct RefineConfig {
    /// Correspondence gates of the successive ICP stages, metres, narrowing. Default 0.3,
    /// 0.15, 0.08.
    pub gates_m: Vec<f64>,
    /// Iterations per stage at most. Default 20.
    pub iterations: usize,
    /// Scale of the Cauchy weights on point-to-line residuals, metres. Default 0.02.
    pub kernel_m: f64,
    /// Offsets of the restarts from the reference: ± this translation (m) and angle (rad).
    /// Default 0.05 m, 1°.
    pub restart_offset: (f64, f64),
    /// Restarts agree when within this translation (m) and angle (rad). Default 5 mm, 0.1°.
    pub agreement: (f64, f64),
    /// Smallest share of the matched normals' scatter in its weaker direction. Default 0.05.
    pub min_constraint: f64,
    /// Largest correction of the reference: translation (m) and angle (rad). Default 0.2 m, 3°.
    pub max_correction: (f64, f64),
    /// Neighbours of a point within this radius fit its line, metres. Default 0.3.
    pub normal_radius_m: f64,
}

impl Default for RefineConfig {
    fn default() -> Self {
        Self {
            gates_m: vec![0.3, 0.15, 0.08],
            iterations: 20,
            kernel_m: 0.02,
            restart_offset: (0.05, 1f64.to_radians()),
            agreement: (0.005, 0.1f64.to_radians()),
            min_constraint: 0.05,
            max_correction: (0.2, 3f64.to_radians()),
            normal_radius_m: 0.3,
        }
    }
}

impl RefineConfig {
    /// Checks the settings: at least one gate, every value finite and positive (the minimum
    /// constraint may be zero) and the iterations at least one.
    pub fn validate(&self) -> crate::Result<()> {
        use crate::error::require_positive;
        if self.gates_m.is_empty() || self.iterations == 0 {
            return Err(crate::SlamError::InvalidParameter {
                name: "gates_m / iterations",
                reason: "at least one gate and one iteration".into(),
            });
        }
        for &gate in &self.gates_m {
            require_positive("gates_m", gate)?;
        }
        for (name, value) in [
            ("kernel_m", self.kernel_m),
            ("restart_offset.0", self.restart_offset.0),
            ("restart_offset.1", self.restart_offset.1),
            ("agreement.0", self.agreement.0),
            ("agreement.1", self.agreement.1),
            ("max_correction.0", self.max_correction.0),
            ("max_correction.1", self.max_correction.1),
            ("normal_radius_m", self.normal_radius_m),
        ] {
            require_positive(name, value)?;
        }
        if !(0.0..=0.5).contains(&self.min_constraint) {
            return Err(crate::SlamError::InvalidParameter {
                name: "min_constraint",
                reason: format!("must lie in [0, 0.5], got {}", self.min_constraint),
            });
        }
        Ok(())
    }
}

/// Why a relation was not refined.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct Dropped {
    /// A reference pose or a scan missing, or too few points to align.
    pub unaligned: usize,
    /// Restarts reached different relations.
    pub ambiguous: usize,
    /// The normals leave a direction free (a corridor).
    pub unconstrained: usize,
    /// Less than half of the second scan lies on the first at the refined relation.
    pub unsupported: usize,
    /// The refinement moved the reference farther than allowed.
    pub far_from_reference: usize,
}

/// The outcome of [`refine_relations`].
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Refined {
    /// The kept relations `(i, j, i_from_j)`, in input order: score them with
    /// [`super::explicit_relation_errors`].
    pub relations: Vec<(usize, usize, Pose2)>,
    /// Translation (m) by which each kept relation moved its reference.
    pub corrections_m: Vec<f64>,
    /// The relations left out, by reason.
    pub dropped: Dropped,
}

impl Refined {
    /// Mean and standard deviation of [`Self::corrections_m`], metres (zeros when none was
    /// kept): how far the reference sits from its scans.
    pub fn correction_m(&self) -> (f64, f64) {
        let c = &self.corrections_m;
        if c.is_empty() {
            return (0.0, 0.0);
        }
        let n = c.len() as f64;
        let mean = c.iter().sum::<f64>() / n;
        let var = c.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / n;
        (mean, var.sqrt())
    }
}

/// Refines the reference relations `pairs` of `scans` (reference poses `reference[k]` of scan
/// `k`) by aligning their two scans; an error only for invalid settings.
///
/// A corrected log is itself the output of a mapping run, so its relations carry its own local
/// errors, and an estimate scored against them is charged those too. Aligned from the
/// reference relation, the two scans of a consecutive pair of the corrected benchmark logs
/// move by centimetres (`cargo xtask eval slam` reports how far per log: the reference's own
/// disagreement with its scans). Kümmerle et al. (2009) built the benchmark's relations
/// from scan alignments that a person checked; here the check is automatic:
///
/// 1. **alignment**: point-to-line ICP (Chen & Medioni 1992, in 2-D) of scan `j` onto scan
///    `i`, started at the reference relation; correspondence gates narrowing from 0.3 to 0.08
///    m, Cauchy weights; line normals from the neighbours of each point of scan `i`;
/// 2. **unique**: restarts from the reference moved by ±5 cm and ±1° reach the same relation
///    (within 5 mm and 0.1°);
/// 3. **constrained**: the matched line normals span the plane (the smaller eigenvalue of
///    their scatter is at least 0.05 of the total) — in a corridor one direction stays free;
/// 4. **supported**: at the refined relation at least half of scan `j`'s points (within
///    [`super::SUPPORT_RANGE_M`]) lie within [`super::SUPPORT_TOLERANCE_M`] of a point of
///    scan `i`, as in [`super::scan_supported`];
/// 5. **near the reference**: the refinement moves the reference by at most 0.2 m and 3°;
///    farther, the reference or the alignment is wrong, and the check cannot tell which.
///
/// The alignment is not raypath-slam's matcher (no grid, no map, no odometry), and the checks
/// look at the reference and the two scans only, never at an estimate. Refined relations still
/// favour every method that aligns scans — as the benchmark's own relations do — so they are
/// reported beside the derived relations, never instead of them.
///
/// The settings and their defaults (ours) are in [`RefineConfig`].
pub fn refine_relations(
    scans: &[&Scan2],
    reference: &[Option<Pose2>],
    pairs: &[(usize, usize)],
    config: &RefineConfig,
) -> crate::Result<Refined> {
    use rayon::prelude::*;
    config.validate()?;
    let results: Vec<Result<(Pose2, f64), Refusal>> = pairs
        .par_iter()
        .map(|&pair| {
            let (si, sj, i_from_j) =
                reference_pair(scans, reference, pair).ok_or(Refusal::Unaligned)?;
            let refined = refine(si, sj, i_from_j, config)?;
            Ok((refined, (i_from_j.inverse() * refined).translation().norm()))
        })
        .collect();
    let mut out = Refined::default();
    for (&(i, j), result) in pairs.iter().zip(results) {
        match result {
            Ok((pose, moved)) => {
                out.corrections_m.push(moved);
                out.relations.push((i, j, pose));
            }
            Err(reason) => *reason.counter(&mut out.dropped) += 1,
        }
    }
    Ok(out)
}

/// Why [`refine`] refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Refusal {
    /// Too few points or correspondences.
    Unaligned,
    /// Restarts disagree.
    Ambiguous,
    /// A direction is free.
    Unconstrained,
    /// Too little overlap at the result.
    Unsupported,
    /// Too far from the initial relation.
    FarFromReference,
}

impl Refusal {
    fn counter(self, d: &mut Dropped) -> &mut usize {
        match self {
            Self::Unaligned => &mut d.unaligned,
            Self::Ambiguous => &mut d.ambiguous,
            Self::Unconstrained => &mut d.unconstrained,
            Self::Unsupported => &mut d.unsupported,
            Self::FarFromReference => &mut d.far_from_reference,
        }
    }
}

/// Aligns `scan_j` onto `scan_i` from `initial` (`i_from_j`) and applies the checks of
/// [`refine_relations`]: the refined `i_from_j`, or why not.
pub fn refine(
    scan_i: &Scan2,
    scan_j: &Scan2,
    initial: Pose2,
    config: &RefineConfig,
) -> Result<Pose2, Refusal> {
    if !initial.is_finite() {
        return Err(Refusal::Unaligned);
    }
    let target = Lines::new(near_points(scan_i, &Pose2::identity()).collect(), config);
    let source: Vec<Point2<f64>> = near_points(scan_j, &Pose2::identity()).collect();
    if target.points.len() < MIN_POINTS || source.len() < MIN_POINTS {
        return Err(Refusal::Unaligned);
    }
    let (pose, spread) = target.align(&source, initial, config)?;
    let (dt, dr) = config.restart_offset;
    for (sx, sy, sr) in [(1., 1., 1.), (-1., 1., -1.), (1., -1., -1.), (-1., -1., 1.)] {
        let start = initial * Pose2::new(sx * dt, sy * dt, sr * dr);
        let (other, _) = target
            .align(&source, start, config)
            .map_err(|_| Refusal::Ambiguous)?;
        let d = pose.inverse() * other;
        if d.translation().norm() > config.agreement.0 || d.theta().abs() > config.agreement.1 {
            return Err(Refusal::Ambiguous);
        }
    }
    if spread < config.min_constraint {
        return Err(Refusal::Unconstrained);
    }
    let index = super::PointIndex::new(target.points.iter().copied());
    if index
        .share(source.iter().map(|p| pose * *p))
        .is_none_or(|s| s < 0.5)
    {
        return Err(Refusal::Unsupported);
    }
    let c = initial.inverse() * pose;
    if c.translation().norm() > config.max_correction.0 || c.theta().abs() > config.max_correction.1
    {
        return Err(Refusal::FarFromReference);
    }
    Ok(pose)
}

/// Fewest points (and correspondences) an alignment needs.
const MIN_POINTS: usize = 20;

/// The first scan's points with their line normals, indexed for nearest-neighbour search.
struct Lines {
    points: Vec<Point2<f64>>,
    normals: Vec<Option<Vector2<f64>>>,
    tree: ImmutableKdTree<f64, 2>,
}

impl Lines {
    fn new(points: Vec<Point2<f64>>, config: &RefineConfig) -> Self {
        let coords: Vec<[f64; 2]> = points.iter().map(|p| [p.x, p.y]).collect();
        let tree = ImmutableKdTree::new_from_slice(&coords);
        let r2 = config.normal_radius_m * config.normal_radius_m;
        let normals = points
            .iter()
            .map(|p| {
                let near: Vec<Vector2<f64>> = tree
                    .within_unsorted::<SquaredEuclidean>(&[p.x, p.y], r2)
                    .iter()
                    .map(|n| points[n.item as usize].coords)
                    .collect();
                line_normal(&near)
            })
            .collect();
        Self {
            points,
            normals,
            tree,
        }
    }

    /// Gauss–Newton point-to-line ICP from `start`: the pose `i_from_j` and the smaller
    /// eigenvalue share of the last step's matched normals.
    fn align(
        &self,
        source: &[Point2<f64>],
        start: Pose2,
        config: &RefineConfig,
    ) -> Result<(Pose2, f64), Refusal> {
        let mut pose = start;
        let mut spread = 0.0;
        for &gate in &config.gates_m {
            for _ in 0..config.iterations {
                let (h, g, scatter, used) = self.normal_equations(source, pose, gate, config);
                if used < MIN_POINTS {
                    return Err(Refusal::Unaligned);
                }
                let step = h.cholesky().ok_or(Refusal::Unaligned)?.solve(&(-g));
                // A left increment: q ↦ R(δθ) q + δt in scan i's frame.
                pose = Pose2::new(step.x, step.y, step.z) * pose;
                if !pose.is_finite() {
                    return Err(Refusal::Unaligned);
                }
                spread = smaller_share(&scatter);
                if step.xy().norm() < 1e-6 && step.z.abs() < 1e-7 {
                    break;
                }
            }
        }
        Ok((pose, spread))
    }

    /// The weighted normal equations of the point-to-line residuals at `pose`, the matched
    /// normals' scatter and the number of correspondences.
    fn normal_equations(
        &self,
        source: &[Point2<f64>],
        pose: Pose2,
        gate: f64,
        config: &RefineConfig,
    ) -> (Matrix3<f64>, Vector3<f64>, Matrix2<f64>, usize) {
        let (mut h, mut g, mut scatter, mut used) =
            (Matrix3::zeros(), Vector3::zeros(), Matrix2::zeros(), 0);
        for p in source {
            let q = pose * *p;
            let nn = self.tree.nearest_one::<SquaredEuclidean>(&[q.x, q.y]);
            if nn.distance > gate * gate {
                continue;
            }
            let k = nn.item as usize;
            let Some(n) = self.normals[k] else {
                continue;
            };
            let e = n.dot(&(q - self.points[k]));
            let jac = Vector3::new(n.x, n.y, n.y * q.x - n.x * q.y);
            let w = 1.0 / (1.0 + (e / config.kernel_m).powi(2));
            h += w * jac * jac.transpose();
            g += w * e * jac;
            scatter += n * n.transpose();
            used += 1;
        }
        (h, g, scatter, used)
    }
}

/// The smaller eigenvalue of a 2 × 2 scatter as a share of its trace.
fn smaller_share(scatter: &Matrix2<f64>) -> f64 {
    let trace = scatter.trace();
    if trace <= 0.0 {
        return 0.0;
    }
    let eig = scatter.symmetric_eigenvalues();
    eig.min() / trace
}

#[cfg(test)]
mod tests;
