//! Surface normals by PCA and angles of incidence (Khan 2017 §3.3.1: "the eigenvector of the
//! smallest eigenvalue of the neighbourhood covariance matrix", after Rusu).
//!
//! The angle of incidence is `α = arccos(|b̂ · n̂|)` ∈ [0, π/2], with `b̂` the unit beam
//! direction from the sensor to the point; the sign of the normal does not matter.

use nalgebra::{Matrix3, SymmetricEigen};

/// Accumulates 2-D second moments without storing the points.
#[derive(Clone, Copy, Debug, Default)]
struct Moments2 {
    n: f64,
    sx: f64,
    sy: f64,
    sxx: f64,
    sxy: f64,
    syy: f64,
}

impl Moments2 {
    fn add(&mut self, p: [f64; 2]) {
        self.n += 1.0;
        self.sx += p[0];
        self.sy += p[1];
        self.sxx += p[0] * p[0];
        self.sxy += p[0] * p[1];
        self.syy += p[1] * p[1];
    }

    /// Unit normal: the eigenvector of the smallest eigenvalue of the covariance.
    fn normal(&self) -> Option<[f64; 2]> {
        if self.n < 2.0 {
            return None;
        }
        let (mx, my) = (self.sx / self.n, self.sy / self.n);
        let cxx = self.sxx / self.n - mx * mx;
        let cxy = self.sxy / self.n - mx * my;
        let cyy = self.syy / self.n - my * my;
        // The larger eigenvalue's eigenvector is the line direction at angle φ with
        // tan 2φ = 2 cxy / (cxx − cyy); the normal is perpendicular to it.
        if cxx + cyy <= 0.0 {
            return None;
        }
        let phi = 0.5 * (2.0 * cxy).atan2(cxx - cyy);
        Some([-phi.sin(), phi.cos()])
    }
}

/// The unit normal of 2-D points by PCA (`None` for fewer than two distinct points).
pub fn pca_normal_2d(points: &[[f64; 2]]) -> Option<[f64; 2]> {
    let mut m = Moments2::default();
    for &p in points {
        m.add(p);
    }
    m.normal()
}

/// The unit normal of 3-D points by PCA: the eigenvector of the smallest eigenvalue of their
/// covariance (`None` for fewer than three points or a degenerate spread).
pub fn pca_normal_3d(points: &[[f64; 3]]) -> Option<[f64; 3]> {
    if points.len() < 3 {
        return None;
    }
    let n = points.len() as f64;
    let mut mean = [0.0; 3];
    for p in points {
        for (m, v) in mean.iter_mut().zip(p) {
            *m += v / n;
        }
    }
    let mut cov = Matrix3::zeros();
    for p in points {
        let d = nalgebra::Vector3::new(p[0] - mean[0], p[1] - mean[1], p[2] - mean[2]);
        cov += d * d.transpose() / n;
    }
    if cov.trace().is_nan() || cov.trace() <= 0.0 {
        return None;
    }
    let eig = SymmetricEigen::new(cov);
    let k = eig.eigenvalues.imin();
    let v = eig.eigenvectors.column(k);
    Some([v[0], v[1], v[2]])
}

/// The angle of incidence between a beam direction and a surface normal, radians in
/// [0, π/2] (neither needs to be unit length; `NaN` if either is zero).
pub fn incidence_angle<const D: usize>(beam: [f64; D], normal: [f64; D]) -> f64 {
    let dot: f64 = beam.iter().zip(&normal).map(|(a, b)| a * b).sum();
    let nb: f64 = beam.iter().map(|a| a * a).sum::<f64>().sqrt();
    let nn: f64 = normal.iter().map(|a| a * a).sum::<f64>().sqrt();
    (dot.abs() / (nb * nn)).clamp(0.0, 1.0).acos()
}

/// Angles of incidence of the end points of a 2-D scan (sensor at the origin; beam order;
/// `NaN` marks a missing point): PCA normal over the points within `half_window` beams and
/// `radius_m` of each point (at least three), then [`incidence_angle`]. `out` is refilled
/// (one value per point, `NaN` where no normal exists).
pub fn scan_incidence_angles(
    points: &[[f64; 2]],
    half_window: usize,
    radius_m: f64,
    out: &mut Vec<f64>,
) {
    out.clear();
    let r2 = radius_m * radius_m;
    for (i, p) in points.iter().enumerate() {
        if !p[0].is_finite() {
            out.push(f64::NAN);
            continue;
        }
        let lo = i.saturating_sub(half_window);
        let hi = (i + half_window + 1).min(points.len());
        let mut m = Moments2::default();
        for q in points.get(lo..hi).unwrap_or(&[]) {
            let (dx, dy) = (q[0] - p[0], q[1] - p[1]);
            if q[0].is_finite() && dx * dx + dy * dy <= r2 {
                m.add(*q);
            }
        }
        out.push(if m.n >= 3.0 {
            m.normal().map_or(f64::NAN, |n| incidence_angle(*p, n))
        } else {
            f64::NAN
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn normals_of_lines_and_planes() {
        let line: Vec<[f64; 2]> = (0..7)
            .map(|i| [1.0 + 0.1 * i as f64, 2.0 + 0.2 * i as f64])
            .collect();
        let n = pca_normal_2d(&line).unwrap();
        assert!((n[0] * 1.0 + n[1] * 2.0).abs() < 1e-9); // ⟂ to direction (1, 2)
        let plane: Vec<[f64; 3]> = (0..25)
            .map(|k| {
                let (u, v) = ((k % 5) as f64, (k / 5) as f64);
                [u, v, 0.5 * u - 0.25 * v + 3.0]
            })
            .collect();
        let n = pca_normal_3d(&plane).unwrap();
        let expect = [0.5, -0.25, -1.0];
        let norm = (0.25f64 + 0.0625 + 1.0).sqrt();
        let dot: f64 = n.iter().zip(expect).map(|(a, b)| a * b / norm).sum();
        assert!((dot.abs() - 1.0).abs() < 1e-9);
    }

    #[test]
    fn incidence_on_a_wall() {
        // Wall x = 2 seen from the origin: α = |beam angle|.
        let pts: Vec<[f64; 2]> = (-30..=30)
            .map(|i| {
                let a = (i as f64).to_radians();
                [2.0, 2.0 * a.tan()]
            })
            .collect();
        let mut out = Vec::new();
        scan_incidence_angles(&pts, 3, 0.5, &mut out);
        for (i, alpha) in out.iter().enumerate() {
            let expect = ((i as f64) - 30.0).abs().to_radians();
            assert!((alpha - expect).abs() < 1e-9, "{alpha} vs {expect}");
        }
    }
}
