//! Point-to-line ICP between two scans (Chen & Medioni 1992, in 2-D), the polishing stage's
//! measurement: a scan's points with line normals as the target, Gauss–Newton on the
//! Cauchy-weighted point-to-line residuals of the other scan's points, and the information of
//! the result from the residuals' Jacobians.

use kiddo::{ImmutableKdTree, SquaredEuclidean};

use nalgebra::{Matrix2, Matrix3, Vector2, Vector3};
use raypath_geometry::Pose2;

use super::PolishConfig;

/// Fewest correspondences an alignment needs.
pub(crate) const MIN_CORRESPONDENCES: usize = 20;

/// A scan's points with their line normals (`None` where the neighbourhood is not line-like),
/// indexed for nearest-neighbour search.
pub(crate) struct LineTarget {
    points: Vec<[f64; 2]>,
    normals: Vec<Option<Vector2<f64>>>,
    tree: ImmutableKdTree<f64, 2>,
}

/// The outcome of [`LineTarget::align`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Alignment {
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

    /// Aligns `source` onto the target from `start` (`target_from_source`): Gauss–Newton with
    /// the correspondence gates of `config`, narrowing; `None` when too few correspondences
    /// remain or the system is singular.
    pub fn align(
        &self,
        source: &[[f64; 2]],
        start: Pose2,
        config: &PolishConfig,
    ) -> Option<Alignment> {
        let mut pose = start;
        let mut last = None;
        for &gate in &config.gates_m {
            for _ in 0..config.iterations {
                let (h, g, weight, used) = self.normal_equations(source, &pose, gate, config);
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
        Some(Alignment {
            target_from_source: pose,
            mean_information,
            used,
        })
    }

    /// The weighted normal equations of the point-to-line residuals at `pose`, the summed
    /// weight and the number of correspondences.
    fn normal_equations(
        &self,
        source: &[[f64; 2]],
        pose: &Pose2,
        gate: f64,
        config: &PolishConfig,
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
            let w = 1.0 / (1.0 + (e / config.kernel_m).powi(2));
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
pub(crate) fn line_normal(points: &[Vector2<f64>]) -> Option<Vector2<f64>> {
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
