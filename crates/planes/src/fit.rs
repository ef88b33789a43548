//! Exact maximum-likelihood plane fit along the rays (Schaefer 2020, Eq. 11.1–11.2).
//!
//! The residual of ray `q` (sensor at the origin, unit direction `v_q`, measured radius
//! `r_q`) with respect to the plane `{p : wᵀp = 1}` is `ε_q = r_q − 1/(wᵀv_q)`; the fit
//! minimizes `Σ ε_q²` with Levenberg–Marquardt on the three parameters `w`
//! (`∂r̂_q/∂w = −r̂_q² v_q`), started from the sufficient-statistics solution of
//! [`crate::PlaneStats`]. Planes a member ray does not hit from the front (`wᵀv ≤ 0`) are
//! rejected. Units: metres, errors in m².

use nalgebra::{Matrix3, Vector3};

use crate::stats::PlaneStats;

/// A fitted plane `{p : wᵀp = 1}` in the sensor frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlaneFit {
    /// Plane parameters (1/m); normal `w/‖w‖`, distance from the sensor `1/‖w‖`.
    pub w: Vector3<f64>,
    /// Sum of squared radial residuals of the members (m²).
    pub sse: f64,
    /// Number of rays.
    pub n: usize,
}

impl PlaneFit {
    /// Unit normal, pointing away from the sensor.
    pub fn normal(&self) -> Vector3<f64> {
        self.w.normalize()
    }

    /// Distance of the plane from the sensor in metres.
    pub fn distance_m(&self) -> f64 {
        1.0 / self.w.norm()
    }

    /// Root mean square radial residual in metres.
    pub fn rmse_m(&self) -> f64 {
        if self.n == 0 {
            0.0
        } else {
            (self.sse / self.n as f64).sqrt()
        }
    }

    /// Predicted radius along unit direction `v` (`None` when the ray misses the plane).
    pub fn predicted_range_m(&self, v: &Vector3<f64>) -> Option<f64> {
        let d = self.w.dot(v);
        (d > 0.0).then(|| 1.0 / d)
    }
}

/// Sum of squared radial residuals of endpoints `points` (sensor frame) for plane `w`
/// (`∞` when a ray misses the plane).
pub fn radial_sse(w: &Vector3<f64>, points: &[Vector3<f64>]) -> f64 {
    let mut sse = 0.0;
    for p in points {
        let r = p.norm();
        let d = w.dot(p) / r;
        if d <= 0.0 || r == 0.0 {
            return f64::INFINITY;
        }
        let e = r - 1.0 / d;
        sse += e * e;
    }
    sse
}

/// Fits a plane to endpoints `points` (sensor frame, metres) by minimizing the squared
/// radial residuals; `None` for fewer than three points or a degenerate configuration.
pub fn fit_plane(points: &[Vector3<f64>]) -> Option<PlaneFit> {
    if points
        .iter()
        .any(|p| !p.iter().all(|x| x.is_finite()) || p.norm_squared() == 0.0)
    {
        return None;
    }
    fit_members(points)
}

/// The exact radial fit of the members of an extracted plane (Eq. 11.1–11.2): the
/// sufficient-statistics solution of their [`PlaneStats`] (summed in the order of
/// `points`), refined by [`refit`]. `None` for a degenerate configuration. The points are
/// not checked (every extractor's rays are finite and non-zero).
pub(crate) fn fit_members(points: &[Vector3<f64>]) -> Option<PlaneFit> {
    let mut stats = PlaneStats::default();
    for p in points {
        stats.add(&PlaneStats::of_point(p));
    }
    let (w0, _) = stats.solve()?;
    refit(w0, points)
}

/// The final refit every extractor gives its planes (Eq. 11.1–11.2): [`refine`] from
/// `w0` with a relative step tolerance of 1e-6 and at most 20 iterations.
pub(crate) fn refit(w0: Vector3<f64>, points: &[Vector3<f64>]) -> Option<PlaneFit> {
    refine(w0, points, 1e-6, 20)
}

/// Levenberg–Marquardt refinement of `w0` on the exact radial residuals (`tol`: relative
/// step tolerance; `max_iter`: iterations).
pub fn refine(
    w0: Vector3<f64>,
    points: &[Vector3<f64>],
    tol: f64,
    max_iter: usize,
) -> Option<PlaneFit> {
    let mut w = w0;
    let mut sse = radial_sse(&w, points);
    if !sse.is_finite() {
        return None;
    }
    let mut lambda = 1e-3;
    for _ in 0..max_iter {
        let mut jtj = Matrix3::zeros();
        let mut jte = Vector3::zeros();
        for p in points {
            let r = p.norm();
            let v = p / r;
            let rhat = 1.0 / w.dot(&v);
            let e = r - rhat;
            // ε = r − r̂, ∂ε/∂w = r̂² v.
            let j = v * (rhat * rhat);
            jtj += j * j.transpose();
            jte += j * e;
        }
        let mut improved = false;
        for _ in 0..10 {
            let mut m = jtj;
            for i in 0..3 {
                m[(i, i)] *= 1.0 + lambda;
            }
            let Some(step) = m.cholesky().map(|c| c.solve(&jte)) else {
                lambda *= 10.0;
                continue;
            };
            let candidate = w - step;
            let candidate_sse = radial_sse(&candidate, points);
            if candidate_sse <= sse {
                let converged =
                    step.norm() <= tol * w.norm() || sse - candidate_sse <= tol * tol * sse;
                w = candidate;
                sse = candidate_sse;
                lambda = (lambda * 0.1).max(1e-12);
                improved = true;
                if converged {
                    return Some(PlaneFit {
                        w,
                        sse,
                        n: points.len(),
                    });
                }
                break;
            }
            lambda *= 10.0;
        }
        if !improved {
            break;
        }
    }
    Some(PlaneFit {
        w,
        sse,
        n: points.len(),
    })
}
