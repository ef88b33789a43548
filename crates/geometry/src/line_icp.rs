//! Point-to-line ICP between two planar scans (Chen & Medioni 1992, in 2-D): one scan's points
//! with their line normals are the target, Gauss–Newton on the Cauchy-weighted point-to-line
//! residuals of the other scan's points, and the information of the result from the
//! residuals' Jacobians. SLAM's polishing stage and place recognition's geometric check both
//! align scans with it.

use kiddo::{ImmutableKdTree, SquaredEuclidean};
use nalgebra::{Matrix2, Matrix3, Vector2, Vector3};

use crate::Pose2;

/// Fewest correspondences an alignment needs (and fewest points a target holds).
pub const MIN_CORRESPONDENCES: usize = 20;

/// How [`LineTarget::align`] iterates.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LineIcp<'a> {
    /// Correspondence gates, metres, one Gauss–Newton stage each (narrowing).
    pub gates_m: &'a [f64],
    /// Gauss–Newton iterations per gate at most.
    pub iterations: usize,
    /// Scale of the Cauchy weights of the point-to-line residuals, metres.
    pub kernel_m: f64,
}

/// A scan's points with their line normals (`None` where the neighbourhood is not line-like),
/// indexed for nearest-neighbour search.
pub struct LineTarget {
    points: Vec<[f64; 2]>,
    normals: Vec<Option<Vector2<f64>>>,
    tree: ImmutableKdTree<f64, 2>,
}

/// The outcome of [`LineTarget::align`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LineAlignment {
    /// The pose of the source scan in the target scan's frame.
    pub target_from_source: Pose2,
    /// `Σ w J Jᵀ / Σ w` of the last iteration: the information of one average correspondence
    /// (unit point-to-line σ), in the target frame's left-increment coordinates.
    pub mean_information: Matrix3<f64>,
    /// Correspondences of the last iteration.
    pub used: usize,
}

impl LineTarget {
    /// Indexes `points` (in beam order: a point's line is fitted to its neighbours along the
    /// scan, the two on each side within `normal_radius_m`); `None` when there are fewer than
    /// [`MIN_CORRESPONDENCES`].
    pub fn new(points: &[[f64; 2]], normal_radius_m: f64) -> Option<Self> {
        if points.len() < MIN_CORRESPONDENCES {
            return None;
        }
        let tree = ImmutableKdTree::new_from_slice(points);
        let r2 = normal_radius_m * normal_radius_m;
        let mut near = Vec::with_capacity(5);
        let normals = (0..points.len())
            .map(|k| {
                let p = points[k];
                near.clear();
                near.extend(
                    points[k.saturating_sub(2)..(k + 3).min(points.len())]
                        .iter()
                        .filter(|q| (q[0] - p[0]).powi(2) + (q[1] - p[1]).powi(2) <= r2)
                        .map(|q| Vector2::new(q[0], q[1])),
                );
                line_normal(&near)
            })
            .collect();
        Some(Self {
            points: points.to_vec(),
            normals,
            tree,
        })
    }

    /// The target's points.
    pub fn points(&self) -> &[[f64; 2]] {
        &self.points
    }

    /// Aligns `source` onto the target from `start` (`target_from_source`): Gauss–Newton with
    /// the correspondence gates of `icp`, narrowing; `None` when too few correspondences remain
    /// or the system is singular.
    pub fn align(
        &self,
        source: &[[f64; 2]],
        start: Pose2,
        icp: &LineIcp<'_>,
    ) -> Option<LineAlignment> {
        let mut pose = start;
        let mut last = None;
        for &gate in icp.gates_m {
            for _ in 0..icp.iterations {
                let (h, g, weight, used) = self.normal_equations(source, &pose, gate, icp.kernel_m);
                if used < MIN_CORRESPONDENCES || weight <= 0.0 {
                    return None;
                }
                let step = h.cholesky()?.solve(&(-g));
                // A left increment: q ↦ R(δθ) q + δt in the target frame.
                pose = Pose2::new(step.x, step.y, step.z) * pose;
                if !pose.is_finite() {
                    return None;
                }
                last = Some((h / weight, used));
                if step.xy().norm() < 1e-5 && step.z.abs() < 1e-6 {
                    break;
                }
            }
        }
        let (mean_information, used) = last?;
        Some(LineAlignment {
            target_from_source: pose,
            mean_information,
            used,
        })
    }

    /// The share of `source` points that lie within `radius_m` of a target point once moved
    /// by `target_from_source` (0 for no points).
    pub fn support(&self, source: &[[f64; 2]], target_from_source: &Pose2, radius_m: f64) -> f64 {
        if source.is_empty() {
            return 0.0;
        }
        let (c, s) = (
            target_from_source.theta().cos(),
            target_from_source.theta().sin(),
        );
        let r2 = radius_m * radius_m;
        let near = source
            .iter()
            .filter(|p| {
                let q = [
                    c * p[0] - s * p[1] + target_from_source.x(),
                    s * p[0] + c * p[1] + target_from_source.y(),
                ];
                self.tree.nearest_one::<SquaredEuclidean>(&q).distance <= r2
            })
            .count();
        near as f64 / source.len() as f64
    }

    /// The weighted normal equations of the point-to-line residuals at `pose`, the summed
    /// weight and the number of correspondences.
    fn normal_equations(
        &self,
        source: &[[f64; 2]],
        pose: &Pose2,
        gate: f64,
        kernel_m: f64,
    ) -> (Matrix3<f64>, Vector3<f64>, f64, usize) {
        let (mut h, mut g, mut weight, mut used) = (Matrix3::zeros(), Vector3::zeros(), 0.0, 0);
        let (c, s) = (pose.theta().cos(), pose.theta().sin());
        for p in source {
            let q = [
                c * p[0] - s * p[1] + pose.x(),
                s * p[0] + c * p[1] + pose.y(),
            ];
            let nn = self.tree.nearest_one::<SquaredEuclidean>(&q);
            if nn.distance > gate * gate {
                continue;
            }
            let k = nn.item as usize;
            let Some(n) = self.normals[k] else {
                continue;
            };
            let t = self.points[k];
            let e = n.x * (q[0] - t[0]) + n.y * (q[1] - t[1]);
            let jac = Vector3::new(n.x, n.y, n.y * q[0] - n.x * q[1]);
            let w = 1.0 / (1.0 + (e / kernel_m).powi(2));
            h += w * jac * jac.transpose();
            g += w * e * jac;
            weight += w;
            used += 1;
        }
        (h, g, weight, used)
    }
}

/// The unit normal of the line through `points` (the smaller principal axis of their
/// scatter), when they are at least three and line-like (the smaller eigenvalue below a tenth
/// of the larger).
pub fn line_normal(points: &[Vector2<f64>]) -> Option<Vector2<f64>> {
    if points.len() < 3 {
        return None;
    }
    let mean = points.iter().sum::<Vector2<f64>>() / points.len() as f64;
    let scatter: Matrix2<f64> = points
        .iter()
        .map(|p| (p - mean) * (p - mean).transpose())
        .sum();
    let eig = scatter.symmetric_eigen();
    let (small, large) = if eig.eigenvalues[0] <= eig.eigenvalues[1] {
        (0, 1)
    } else {
        (1, 0)
    };
    (eig.eigenvalues[small] <= 0.1 * eig.eigenvalues[large] && eig.eigenvalues[large] > 0.0)
        .then(|| eig.eigenvectors.column(small).into_owned())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Points every 2 cm along the walls of a 4 m × 3 m room corner with a box, in beam order.
    fn corner() -> Vec<[f64; 2]> {
        let mut points = Vec::new();
        let mut wall = |a: [f64; 2], b: [f64; 2]| {
            let n = ((b[0] - a[0]).hypot(b[1] - a[1]) / 0.02) as usize;
            for k in 0..n {
                let t = k as f64 / n as f64;
                points.push([a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])]);
            }
        };
        wall([4.0, -1.5], [4.0, 1.5]);
        wall([4.0, 1.5], [0.0, 1.5]);
        wall([2.0, -1.5], [2.5, -1.0]);
        wall([2.5, -1.0], [3.0, -1.5]);
        points
    }

    /// From 5 cm and 2° off, the alignment recovers a known relative pose; all points are
    /// then supported within 1 cm, and the corner constrains every direction.
    #[test]
    fn icp_recovers_a_known_offset() {
        let target_points = corner();
        let truth = Pose2::new(0.3, -0.2, 0.1);
        let source: Vec<[f64; 2]> = target_points
            .iter()
            .map(|p| {
                let q = truth.inverse() * nalgebra::Point2::new(p[0], p[1]);
                [q.x, q.y]
            })
            .collect();
        let target = LineTarget::new(&target_points, 0.1).unwrap();
        let icp = LineIcp {
            gates_m: &[0.3, 0.05],
            iterations: 20,
            kernel_m: 0.02,
        };
        let start = truth * Pose2::new(0.05, -0.03, 2f64.to_radians());
        let found = target.align(&source, start, &icp).unwrap();
        let d = truth.inverse() * found.target_from_source;
        assert!(
            d.translation().norm() < 1e-4 && d.theta().abs() < 1e-5,
            "{d:?}"
        );
        assert!(target.support(&source, &found.target_from_source, 0.01) > 0.99);
        assert!(found.mean_information.symmetric_eigenvalues().min() > 0.0);
        // Too few points: no target.
        assert!(LineTarget::new(&target_points[..MIN_CORRESPONDENCES - 1], 0.1).is_none());
    }
}
