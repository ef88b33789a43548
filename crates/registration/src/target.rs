//! The target of a registration: points with surface normals in a k-d tree.

use kiddo::SquaredEuclidean;
use nalgebra::{Point3, Vector3};
use raypath_geometry::PointCloud;

use crate::config::RegistrationConfig;
use crate::error::{RegistrationError, Result};
use crate::normals::{Tree, build_tree, estimate_normals};
use crate::preprocess::{crop, downsample};

/// Target points with unit normals, indexed for nearest-neighbour search.
///
/// Build it once with [`Target::from_cloud`] (or [`Target::new`] from points and normals) to
/// register several sources against the same cloud with [`align`](crate::align).
pub struct Target {
    points: Vec<Point3<f64>>,
    normals: Vec<Vector3<f64>>,
    tree: Tree,
}

impl std::fmt::Debug for Target {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Target")
            .field("points", &self.points.len())
            .finish_non_exhaustive()
    }
}

impl Target {
    /// A target from points and their unit normals (same length, finite, at least one).
    pub fn new(points: Vec<Point3<f64>>, normals: Vec<Vector3<f64>>) -> Result<Self> {
        if points.len() != normals.len() {
            return Err(RegistrationError::InvalidCloud {
                what: "target",
                reason: format!("{} points but {} normals", points.len(), normals.len()),
            });
        }
        if points.is_empty() {
            return Err(RegistrationError::EmptyCloud {
                what: "target",
                reason: "no points with normals".into(),
            });
        }
        for (index, (p, n)) in points.iter().zip(&normals).enumerate() {
            if !(p.iter().chain(n.iter()).all(|v| v.is_finite())) {
                return Err(RegistrationError::NonFinitePoint {
                    what: "target",
                    index,
                    x: p.x as f32,
                    y: p.y as f32,
                    z: p.z as f32,
                });
            }
        }
        let tree = build_tree(&points);
        Ok(Self {
            points,
            normals,
            tree,
        })
    }

    /// The target of a scan (sensor at its origin): range crop, voxel grid at
    /// `voxel_size_m × target_voxel_scale`, PCA normals; points without a normal are left out.
    pub fn from_cloud(cloud: &PointCloud, config: &RegistrationConfig) -> Result<Self> {
        config.validate()?;
        let cropped = crop(cloud, config, "target")?;
        let points = downsample(&cropped, config.target_voxel_m())?;
        let (points, normals) = with_normals(points, &Point3::origin(), config);
        Self::new(points, normals).map_err(|e| match e {
            RegistrationError::EmptyCloud { .. } => RegistrationError::EmptyCloud {
                what: "target",
                reason: "no down-sampled point has a planar neighbourhood (no normals)".into(),
            },
            other => other,
        })
    }

    /// Number of points.
    pub fn len(&self) -> usize {
        self.points.len()
    }

    /// True when there are no points (never, for a constructed target).
    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }

    /// The points.
    pub fn points(&self) -> &[Point3<f64>] {
        &self.points
    }

    /// The unit normals, one per point.
    pub fn normals(&self) -> &[Vector3<f64>] {
        &self.normals
    }

    /// The nearest target point of `p`: its index and squared distance.
    pub(crate) fn nearest(&self, p: &Point3<f64>) -> (usize, f64) {
        let nn = self.tree.nearest_one::<SquaredEuclidean>(&[p.x, p.y, p.z]);
        (nn.item as usize, nn.distance)
    }
}

/// The points of `points` that have a normal (seen from `viewpoint`), with their normals.
pub(crate) fn with_normals(
    points: Vec<Point3<f64>>,
    viewpoint: &Point3<f64>,
    config: &RegistrationConfig,
) -> (Vec<Point3<f64>>, Vec<Vector3<f64>>) {
    let tree = build_tree(&points);
    let normals = estimate_normals(&points, &tree, viewpoint, config);
    points
        .into_iter()
        .zip(normals)
        .filter_map(|(p, n)| n.map(|n| (p, n)))
        .unzip()
}
