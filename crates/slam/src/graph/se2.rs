//! The SE(2) edge error and its analytic Jacobians.
//!
//! For an edge from node `i` to node `j` with measurement `Z = from⁻¹·to` the error is
//! `e = t2v(Z⁻¹ · (X_i⁻¹ · X_j))` (Grisetti et al. 2010, "A tutorial on graph-based SLAM",
//! Sec. IV), with the angle wrapped to `(-π, π]`. Written out with `R(θ)` the 2-D rotation:
//!
//! ```text
//! e_xy = R_zᵀ · (R_iᵀ · (t_j − t_i) − t_z)
//! e_θ  = θ_j − θ_i − θ_z                      (wrapped)
//! ```
//!
//! The poses are updated by plain addition on `(x, y, θ)` (the global parametrisation of
//! g2o's 2-D types, Kümmerle et al. 2011), so the Jacobians are the derivatives with respect
//! to `(x, y, θ)` of each node:
//!
//! ```text
//! A = ∂e/∂x_i = [ −R_zᵀR_iᵀ   R_zᵀ · ∂R_iᵀ/∂θ_i · (t_j − t_i) ]
//!               [  0    0     −1                               ]
//! B = ∂e/∂x_j = [  R_zᵀR_iᵀ   0 ]
//!               [  0    0     1 ]
//! ```

use nalgebra::{Matrix3, Vector3};
use raypath_geometry::Pose2;

/// Cosine and sine of a pose's heading, read from its unit complex number (no trigonometry).
#[inline]
fn cos_sin(pose: &Pose2) -> (f64, f64) {
    let rotation = &pose.isometry.rotation;
    (rotation.re, rotation.im)
}

/// The angle of the unit complex number `(c, s)` wrapped to `(-π, π]`.
#[inline]
fn angle_of(c: f64, s: f64) -> f64 {
    use std::f64::consts::{PI, TAU};
    let angle = s.atan2(c);
    if angle <= -PI { angle + TAU } else { angle }
}

/// The error of an edge with measurement `z` between `xi` and `xj` (see the module docs).
#[inline]
pub(crate) fn edge_error(xi: &Pose2, xj: &Pose2, z: &Pose2) -> Vector3<f64> {
    error_and_jacobians(xi, xj, z, false).0
}

/// The error and, when `with_jacobians`, the Jacobians `A = ∂e/∂x_i` and `B = ∂e/∂x_j`
/// (zero matrices otherwise).
#[inline]
pub(crate) fn error_and_jacobians(
    xi: &Pose2,
    xj: &Pose2,
    z: &Pose2,
    with_jacobians: bool,
) -> (Vector3<f64>, Matrix3<f64>, Matrix3<f64>) {
    let (ci, si) = cos_sin(xi);
    let (cj, sj) = cos_sin(xj);
    let (cz, sz) = cos_sin(z);
    let dx = xj.x() - xi.x();
    let dy = xj.y() - xi.y();
    // R_iᵀ (t_j − t_i): the position of j in i's frame.
    let lx = ci * dx + si * dy;
    let ly = -si * dx + ci * dy;
    // Minus the measured translation, rotated into the measurement's frame by R_zᵀ.
    let (ux, uy) = (lx - z.x(), ly - z.y());
    let ex = cz * ux + sz * uy;
    let ey = -sz * ux + cz * uy;
    // θ_j − θ_i − θ_z as the angle of conj(z_i)·z_j·conj(z_z): wrapped by atan2.
    let (dc, ds) = (ci * cj + si * sj, ci * sj - si * cj);
    let eth = angle_of(dc * cz + ds * sz, ds * cz - dc * sz);
    let error = Vector3::new(ex, ey, eth);
    if !with_jacobians {
        return (error, Matrix3::zeros(), Matrix3::zeros());
    }
    // R_zᵀ R_iᵀ = R(θ_i + θ_z)ᵀ.
    let (c, s) = (ci * cz - si * sz, si * cz + ci * sz);
    // ∂R_iᵀ/∂θ_i · (t_j − t_i) = (−s_i dx + c_i dy, −c_i dx − s_i dy) = (ly, −lx).
    let (gx, gy) = (ly, -lx);
    let a02 = cz * gx + sz * gy;
    let a12 = -sz * gx + cz * gy;
    #[rustfmt::skip]
    let a = Matrix3::new(
        -c, -s, a02,
         s, -c, a12,
        0.0, 0.0, -1.0,
    );
    #[rustfmt::skip]
    let b = Matrix3::new(
        c,   s,  0.0,
        -s,  c,  0.0,
        0.0, 0.0, 1.0,
    );
    (error, a, b)
}
