//! Normals, the SHOT local reference frame and the interpolated histograms (Tombari et al.,
//! ECCV 2010; texture part after CSHOT, ICIP 2011). See the parent module for the decisions.

use std::f64::consts::{FRAC_PI_2, TAU};

use kiddo::SquaredEuclidean;
use kiddo::float::kdtree::KdTree;
use nalgebra::{Matrix3, Point3, SymmetricEigen, Vector3};
use rayon::prelude::*;
use raypath_geometry::PointCloud;

use super::{SHOT_SHAPE_LEN, ShotConfig, ShotDescriptors};
use crate::{PlaceError, Result};

const AZIMUTH: usize = 8;
const COS_BINS: usize = 11;

/// Radius search over a cloud; exact duplicate points share one tree entry.
struct PointIndex<'a> {
    points: &'a [Point3<f32>],
    tree: KdTree<f32, u64, 3, 32, u32>,
    /// Point indices grouped by position; tree item `g` owns `members[starts[g]..starts[g+1]]`.
    members: Vec<u32>,
    starts: Vec<usize>,
}

impl<'a> PointIndex<'a> {
    fn new(points: &'a [Point3<f32>]) -> Self {
        let mut order: Vec<u32> = (0..points.len() as u32)
            .filter(|&i| points[i as usize].coords.iter().all(|c| c.is_finite()))
            .collect();
        let key = |i: &u32| points[*i as usize].coords.map(f32::to_bits);
        order.sort_unstable_by_key(|i| (key(i).x, key(i).y, key(i).z, *i));
        let mut tree = KdTree::with_capacity(order.len().max(1));
        let mut starts = Vec::new();
        for (k, i) in order.iter().enumerate() {
            if k == 0 || points[order[k - 1] as usize] != points[*i as usize] {
                let p = &points[*i as usize];
                tree.add(&[p.x, p.y, p.z], starts.len() as u64);
                starts.push(k);
            }
        }
        starts.push(order.len());
        Self {
            points,
            tree,
            members: order,
            starts,
        }
    }

    /// Indices of the points within `radius` of `p` (any order), appended to `out`.
    fn within(&self, p: &Point3<f64>, radius: f64, out: &mut Vec<u32>) {
        let q = [p.x as f32, p.y as f32, p.z as f32];
        for nn in self
            .tree
            .within_unsorted::<SquaredEuclidean>(&q, (radius * radius) as f32)
        {
            let g = nn.item as usize;
            out.extend_from_slice(&self.members[self.starts[g]..self.starts[g + 1]]);
        }
    }

    fn point(&self, i: u32) -> Vector3<f64> {
        self.points[i as usize].coords.cast::<f64>()
    }
}

/// PCA normal from the neighbours of `p` (smallest-eigenvalue eigenvector), oriented towards
/// `viewpoint`; `None` with fewer than 3 neighbours.
fn normal(
    index: &PointIndex,
    p: &Vector3<f64>,
    neighbours: &[u32],
    viewpoint: &Vector3<f64>,
) -> Option<Vector3<f64>> {
    if neighbours.len() < 3 {
        return None;
    }
    let mean = neighbours
        .iter()
        .map(|&i| index.point(i))
        .sum::<Vector3<f64>>()
        / neighbours.len() as f64;
    let mut cov = Matrix3::zeros();
    for &i in neighbours {
        let d = index.point(i) - mean;
        cov += d * d.transpose();
    }
    let eig = SymmetricEigen::new(cov);
    let k = eig.eigenvalues.imin();
    let n: Vector3<f64> = eig.eigenvectors.column(k).into_owned();
    Some(if n.dot(&(viewpoint - p)) < 0.0 { -n } else { n })
}

/// The SHOT local reference frame `[x, y, z]` at `p` from its support (Tombari et al. 2010).
fn local_frame(
    index: &PointIndex,
    p: &Vector3<f64>,
    support: &[u32],
    radius: f64,
) -> Option<Matrix3<f64>> {
    let mut m = Matrix3::zeros();
    let mut wsum = 0.0;
    for &i in support {
        let q = index.point(i) - p;
        let w = radius - q.norm();
        if w > 0.0 {
            m += w * q * q.transpose();
            wsum += w;
        }
    }
    if wsum <= 0.0 {
        return None;
    }
    let eig = SymmetricEigen::new(m / wsum);
    let mut order = [0usize, 1, 2];
    order.sort_by(|&a, &b| eig.eigenvalues[b].total_cmp(&eig.eigenvalues[a]));
    let axis = |k: usize| -> Vector3<f64> { eig.eigenvectors.column(order[k]).into_owned() };
    let disambiguate = |v: Vector3<f64>| {
        let (mut pos, mut neg, mut wdot) = (0usize, 0usize, 0f64);
        for &i in support {
            let q = index.point(i) - p;
            let d = q.dot(&v);
            if d >= 0.0 {
                pos += 1
            } else {
                neg += 1
            }
            wdot += (radius - q.norm()).max(0.0) * d;
        }
        let flip = neg > pos || (neg == pos && wdot < 0.0);
        if flip { -v } else { v }
    };
    let x = disambiguate(axis(0));
    let z = disambiguate(axis(2));
    let y = z.cross(&x);
    Some(Matrix3::from_rows(&[
        x.transpose(),
        y.transpose(),
        z.transpose(),
    ]))
}

/// Linear interpolation of coordinate `u` (in bin-centre units) over `n` bins, clamped at
/// the ends (`circular`: wraps around) → `(bin, weight)` pairs.
fn spread(u: f64, n: usize, circular: bool) -> [(usize, f64); 2] {
    if circular {
        let u = u.rem_euclid(n as f64);
        let b = (u.floor() as usize).min(n - 1);
        let f = u - b as f64;
        return [(b, 1.0 - f), ((b + 1) % n, f)];
    }
    let u = u.clamp(0.0, (n - 1) as f64);
    let b = (u.floor() as usize).min(n.saturating_sub(2));
    let f = u - b as f64;
    [(b, 1.0 - f), ((b + 1).min(n - 1), f)]
}

/// Everything one keypoint needs, shared by all keypoints.
struct Context<'a> {
    index: PointIndex<'a>,
    normals: Vec<Option<Vector3<f64>>>,
    intensity: Option<(&'a [f32], f64)>,
    radius: f64,
    bins: usize,
    min_support: usize,
}

/// The descriptor of the keypoint `k` with support `support` into `out`; false if skipped.
fn describe_one(ctx: &Context, k: u32, support: &[u32], out: &mut [f32]) -> bool {
    let p = ctx.index.point(k);
    let usable = support
        .iter()
        .filter(|&&i| i != k && ctx.normals[i as usize].is_some())
        .count();
    if usable < ctx.min_support {
        return false;
    }
    let Some(lrf) = local_frame(&ctx.index, &p, support, ctx.radius) else {
        return false;
    };
    let z = lrf.row(2).transpose();
    out.iter_mut().for_each(|v| *v = 0.0);
    let (shape, texture) = out.split_at_mut(SHOT_SHAPE_LEN);
    for &i in support {
        let Some(n) = ctx.normals[i as usize] else {
            continue;
        };
        let q = ctx.index.point(i) - p;
        let d = q.norm();
        if i == k || d <= 0.0 || d > ctx.radius {
            continue;
        }
        let l = lrf * q;
        let azimuth = spread(
            l.y.atan2(l.x).rem_euclid(TAU) / (TAU / AZIMUTH as f64) - 0.5,
            AZIMUTH,
            true,
        );
        let elevation = spread(
            (l.z.atan2(l.x.hypot(l.y)) + FRAC_PI_2) / FRAC_PI_2 - 0.5,
            2,
            false,
        );
        let radial = spread(d / (ctx.radius / 2.0) - 0.5, 2, false);
        let cos = n.dot(&z).clamp(-1.0, 1.0);
        let cos_bins = spread((cos + 1.0) / 2.0 * COS_BINS as f64 - 0.5, COS_BINS, false);
        let tex_bins = ctx.intensity.map(|(v, s)| {
            let di = ((f64::from(v[i as usize]) - f64::from(v[k as usize])) / s).clamp(-1.0, 1.0);
            spread((di + 1.0) / 2.0 * ctx.bins as f64 - 0.5, ctx.bins, false)
        });
        for (r, wr) in radial {
            for (e, we) in elevation {
                for (a, wa) in azimuth {
                    let w = wr * we * wa;
                    let volume = (r * 2 + e) * AZIMUTH + a;
                    for (b, wb) in cos_bins {
                        shape[volume * COS_BINS + b] += (w * wb) as f32;
                    }
                    for &(b, wb) in tex_bins.iter().flatten() {
                        texture[volume * ctx.bins + b] += (w * wb) as f32;
                    }
                }
            }
        }
    }
    let parts = if ctx.intensity.is_some() { 2.0f32 } else { 1.0 };
    for part in [shape, texture] {
        let norm = part.iter().map(|v| v * v).sum::<f32>().sqrt();
        if norm > 0.0 {
            let scale = 1.0 / (norm * parts.sqrt());
            part.iter_mut().for_each(|v| *v *= scale);
        }
    }
    true
}

/// The intensity normaliser: `config.intensity_scale` or the 99th percentile of `|I|`.
fn intensity_scale(values: &[f32], config: &ShotConfig) -> f64 {
    if let Some(s) = config.intensity_scale {
        return s;
    }
    let mut abs: Vec<f32> = values
        .iter()
        .filter(|v| v.is_finite())
        .map(|v| v.abs())
        .collect();
    if abs.is_empty() {
        return 1.0;
    }
    let k = ((abs.len() - 1) as f64 * 0.99).round() as usize;
    let (_, v, _) = abs.select_nth_unstable_by(k, f32::total_cmp);
    if *v > 0.0 { f64::from(*v) } else { 1.0 }
}

/// SHOT descriptors of the points `keypoints` of `cloud` (no down-sampling), normals oriented
/// towards `viewpoint`. Keypoints with too small a support are skipped (absent from the
/// result); out-of-range or non-finite keypoints are an error. With
/// [`ShotConfig::with_intensity`] the cloud must carry intensities.
pub fn shot_at_keypoints(
    cloud: &PointCloud,
    keypoints: &[usize],
    viewpoint: &Point3<f64>,
    config: &ShotConfig,
) -> Result<ShotDescriptors> {
    config.validate()?;
    if u32::try_from(cloud.points.len()).is_err() {
        return Err(PlaceError::BadInput(
            "cloud has more than 2^32 points".into(),
        ));
    }
    let intensity = match (&cloud.intensity, config.with_intensity) {
        (Some(v), true) if v.len() == cloud.points.len() => {
            Some((v.as_slice(), intensity_scale(v, config)))
        }
        (_, true) => {
            return Err(PlaceError::BadInput(
                "SHOT with intensity needs a cloud with one intensity per point".into(),
            ));
        }
        _ => None,
    };
    for &k in keypoints {
        let ok = cloud
            .points
            .get(k)
            .is_some_and(|p| p.coords.iter().all(|c| c.is_finite()));
        if !ok || intensity.is_some_and(|(v, _)| !v[k].is_finite()) {
            return Err(PlaceError::BadInput(format!(
                "keypoint {k} is missing or not finite"
            )));
        }
    }
    let index = PointIndex::new(&cloud.points);
    let radius = config.support_radius();
    let supports: Vec<Vec<u32>> = keypoints
        .par_iter()
        .map(|&k| {
            let mut s = Vec::new();
            index.within(&Point3::from(index.point(k as u32)), radius, &mut s);
            s.sort_unstable();
            s
        })
        .collect();
    let mut needed: Vec<u32> = supports.iter().flatten().copied().collect();
    needed.sort_unstable();
    needed.dedup();
    let normal_radius = config.normal_radius_factor * config.voxel_size;
    let vp = viewpoint.coords;
    let computed: Vec<Option<Vector3<f64>>> = needed
        .par_iter()
        .map_init(Vec::new, |buf, &i| {
            buf.clear();
            let p = index.point(i);
            index.within(&Point3::from(p), normal_radius, buf);
            normal(&index, &p, buf, &vp)
        })
        .collect();
    let mut normals = vec![None; cloud.points.len()];
    for (&i, n) in needed.iter().zip(computed) {
        normals[i as usize] = n;
    }
    let ctx = Context {
        index,
        normals,
        intensity,
        radius,
        bins: config.intensity_bins,
        min_support: config.min_support,
    };
    let dim = config.descriptor_len();
    let described: Vec<Option<Vec<f32>>> = keypoints
        .par_iter()
        .zip(&supports)
        .map(|(&k, s)| {
            let mut out = vec![0f32; dim];
            describe_one(&ctx, k as u32, s, &mut out).then_some(out)
        })
        .collect();
    let mut result = ShotDescriptors {
        dim,
        values: Vec::new(),
        keypoints: Vec::new(),
    };
    for (&k, d) in keypoints.iter().zip(described) {
        if let Some(d) = d {
            result.values.extend_from_slice(&d);
            result.keypoints.push(k);
        }
    }
    Ok(result)
}
