//! Surface normals by local PCA: the eigenvector of the smallest eigenvalue of the covariance
//! of a point's nearest neighbours (Hoppe et al. 1992; Rusu 2009), kept only where the
//! neighbourhood is a surface — not a blob (surface variation, Pauly et al. 2002) and not a
//! line (one ring of a far scan).

use std::num::NonZero;

use kiddo::{ImmutableKdTree, SquaredEuclidean};
use nalgebra::{Matrix3, Point3, SymmetricEigen, Vector3};
use rayon::prelude::*;

use crate::config::RegistrationConfig;

/// A k-d tree over points in `f64` (kiddo's immutable tree; item = index into the slice it
/// was built from).
pub(crate) type Tree = ImmutableKdTree<f64, 3>;

/// Builds the tree of `points`.
pub(crate) fn build_tree(points: &[Point3<f64>]) -> Tree {
    let coords: Vec<[f64; 3]> = points.iter().map(|p| [p.x, p.y, p.z]).collect();
    Tree::new_from_slice(&coords)
}

/// The unit normal at every point of `points` (`None` where the neighbourhood is not a
/// surface), oriented towards `viewpoint` (the sensor). `tree` indexes `points`.
pub(crate) fn estimate_normals(
    points: &[Point3<f64>],
    tree: &Tree,
    viewpoint: &Point3<f64>,
    config: &RegistrationConfig,
) -> Vec<Option<Vector3<f64>>> {
    let k = NonZero::new(config.normal_neighbours).unwrap_or(NonZero::<usize>::MIN);
    let radius_2 = config.normal_radius_m * config.normal_radius_m;
    points
        .par_iter()
        .map(|p| {
            // kiddo returns the neighbours in a small Vec: one allocation per target point
            // and frame, against a k-nearest search that costs far more.
            let neighbours =
                tree.nearest_n_within::<SquaredEuclidean>(&[p.x, p.y, p.z], radius_2, k, false);
            if neighbours.len() < 3 {
                return None;
            }
            let n = neighbours.len() as f64;
            let mean = neighbours
                .iter()
                .map(|nn| points[nn.item as usize].coords)
                .sum::<Vector3<f64>>()
                / n;
            let mut cov = Matrix3::zeros();
            for nn in &neighbours {
                let d = points[nn.item as usize].coords - mean;
                cov += d * d.transpose();
            }
            surface_normal(cov / n, config).map(|normal| {
                if normal.dot(&(viewpoint - p)) < 0.0 {
                    -normal
                } else {
                    normal
                }
            })
        })
        .collect()
}

/// Surface normals of a whole cloud seen from `viewpoint` (the sensor), with the neighbourhood
/// size, radius and surface tests of `config` (`normal_neighbours`, `normal_radius_m`,
/// `max_surface_variation`, `min_planarity`): one entry per point, `None` where the
/// neighbourhood is not a surface. For other uses of the normals than registration, for
/// example angles of incidence for intensity calibration.
pub fn surface_normals(
    points: &[Point3<f64>],
    viewpoint: &Point3<f64>,
    config: &RegistrationConfig,
) -> Vec<Option<Vector3<f64>>> {
    estimate_normals(points, &build_tree(points), viewpoint, config)
}

/// The normal of a neighbourhood with covariance `cov`, when it is a surface.
fn surface_normal(cov: Matrix3<f64>, config: &RegistrationConfig) -> Option<Vector3<f64>> {
    let eig = SymmetricEigen::new(cov);
    let mut order = [0usize, 1, 2];
    order.sort_by(|&a, &b| eig.eigenvalues[a].total_cmp(&eig.eigenvalues[b]));
    let [l0, l1, l2] = order.map(|i| eig.eigenvalues[i].max(0.0));
    let total = l0 + l1 + l2;
    if !(total.is_finite() && total > 0.0) {
        return None;
    }
    if l0 / total > config.max_surface_variation || l1 < config.min_planarity * l2 {
        return None;
    }
    let normal: Vector3<f64> = eig.eigenvectors.column(order[0]).into_owned();
    let norm = normal.norm();
    (norm > 0.0 && norm.is_finite()).then(|| normal / norm)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid(f: impl Fn(f64, f64) -> Point3<f64>) -> Vec<Point3<f64>> {
        let mut out = Vec::new();
        for i in 0..20 {
            for j in 0..20 {
                out.push(f(i as f64 * 0.3, j as f64 * 0.3));
            }
        }
        out
    }

    #[test]
    fn plane_normals_point_to_the_viewpoint() {
        // The plane z = 2 seen from below.
        let points = grid(|a, b| Point3::new(a, b, 2.0));
        let tree = build_tree(&points);
        let normals = estimate_normals(
            &points,
            &tree,
            &Point3::origin(),
            &RegistrationConfig::default(),
        );
        for n in &normals {
            let n = n.unwrap();
            assert!((n - Vector3::new(0.0, 0.0, -1.0)).norm() < 1e-9, "{n}");
        }
    }

    #[test]
    fn lines_and_blobs_have_no_normal() {
        let line: Vec<Point3<f64>> = (0..30)
            .map(|i| Point3::new(i as f64 * 0.2, 0.0, 0.0))
            .collect();
        let tree = build_tree(&line);
        let config = RegistrationConfig::default();
        let normals = estimate_normals(&line, &tree, &Point3::origin(), &config);
        assert!(normals.iter().all(Option::is_none));
        // A cube lattice: isotropic neighbourhoods.
        let mut cube = Vec::new();
        for i in 0..6 {
            for j in 0..6 {
                for k in 0..6 {
                    cube.push(Point3::new(i as f64, j as f64, k as f64) * 0.1);
                }
            }
        }
        let tree = build_tree(&cube);
        let config = RegistrationConfig {
            normal_neighbours: 27,
            ..RegistrationConfig::default()
        };
        let normals = estimate_normals(&cube, &tree, &Point3::new(5.0, 0.0, 0.0), &config);
        // The interior points (all 26 neighbours present) see an isotropic blob.
        let interior = cube
            .iter()
            .zip(&normals)
            .filter(|(p, _)| p.iter().all(|&c| c > 0.05 && c < 0.45));
        for (p, n) in interior {
            assert!(n.is_none(), "{p}: {n:?}");
        }
    }
}
