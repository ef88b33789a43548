//! Point-to-plane ICP: Gauss–Newton on the linearised point-to-plane error (Chen & Medioni
//! 1992; Low 2004) with robust weights (IRLS).
//!
//! For a source point `p` (moved by the current estimate to `p' = T p`), its nearest target
//! point `q` with unit normal `n`, the residual is `e = nᵀ (p' − q)`. A small motion
//! `x = (t, ω)` moves `p'` to `p' + ω × p' + t`, so `e(x) ≈ e + nᵀ t + (p' × n)ᵀ ω`: one row
//! `J = [nᵀ, (p' × n)ᵀ]` per correspondence (Low 2004, eq. (6)–(8)). Each iteration solves
//! `Σ w JᵀJ x = −Σ w Jᵀ e` with `w = w(e)` of the kernel and applies `T ← exp(x) T`.

use nalgebra::{Matrix6, Point3, Rotation3, UnitQuaternion, Vector3, Vector6};
use rayon::prelude::*;
use raypath_geometry::{PointCloud, Pose3};
use serde::{Deserialize, Serialize};

use crate::config::{Kernel, RegistrationConfig};
use crate::error::{RegistrationError, Result};
use crate::preprocess::{crop, downsample};
use crate::target::Target;

/// Source points per partial sum: the normal equations are summed in parallel over fixed
/// chunks and the partial sums added in chunk order, so the result does not depend on the
/// number of threads.
const CHUNK: usize = 512;

/// The result of a registration.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Registration {
    /// The estimate: maps source points into the target frame.
    pub target_from_source: Pose3,
    /// Gauss–Newton iterations run.
    pub iterations: usize,
    /// True when the last update was below both convergence thresholds (false when
    /// `max_iterations` ran out first).
    pub converged: bool,
    /// Share of the (thinned) source points that are inliers at the final pose — a
    /// correspondence within the gate whose point-to-plane residual is at most three final
    /// kernel scales (`3 × final_kernel_scale_m`) — in `[0, 1]`.
    pub fitness: f64,
    /// Root mean square point-to-plane residual of the inliers, metres.
    pub rmse_m: f64,
    /// Correspondences within the gate at the final pose (inliers and outliers).
    pub correspondences: usize,
    /// Number of down-sampled source points.
    pub source_points: usize,
}

/// The correspondence gate and kernel scale of one alignment.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Gate {
    /// Correspondences farther apart (point to point) are rejected, metres.
    pub max_distance_m: f64,
    /// The kernel scale κ, metres.
    pub kernel_scale_m: f64,
}

impl Gate {
    /// The gate and scale of `config`.
    pub fn of(config: &RegistrationConfig) -> Self {
        Self {
            max_distance_m: config.max_correspondence_distance_m,
            kernel_scale_m: config.kernel_scale_m,
        }
    }
}

/// Registers `source` to `target` (two scans, each in its sensor frame) starting from
/// `initial_guess` (`target_from_source`): both are range-cropped and voxel down-sampled
/// (target at `voxel_size_m × target_voxel_scale` with PCA normals, source at
/// `× source_voxel_scale`), then aligned by point-to-plane ICP.
///
/// Errors: an invalid config, a non-finite guess, an empty cloud (also after the crop), NaN
/// or inf in an unorganized cloud, or too few correspondences (no overlap at the guess).
pub fn register(
    source: &PointCloud,
    target: &PointCloud,
    initial_guess: &Pose3,
    config: &RegistrationConfig,
) -> Result<Registration> {
    config.validate()?;
    let source = source_points(source, config)?;
    let target = Target::from_cloud(target, config)?;
    align(&source, &target, initial_guess, &Gate::of(config), config)
}

/// The source points of a scan: range crop and voxel grid at
/// `voxel_size_m × source_voxel_scale` (KISS-ICP down-samples the `target_voxel_scale` grid
/// again; we do the same so both routes give one source).
pub fn source_points(cloud: &PointCloud, config: &RegistrationConfig) -> Result<Vec<Point3<f64>>> {
    config.validate()?;
    let cropped = crop(cloud, config, "source")?;
    let fine = downsample(&cropped, config.target_voxel_m())?;
    downsample(&crate::preprocess::to_cloud(&fine), config.source_voxel_m())
}

/// Aligns prepared source points to a prepared [`Target`] from `initial_guess`, with the
/// correspondence gate and kernel scale of `gate` and the iteration settings of `config`.
pub fn align(
    source: &[Point3<f64>],
    target: &Target,
    initial_guess: &Pose3,
    gate: &Gate,
    config: &RegistrationConfig,
) -> Result<Registration> {
    if !initial_guess.is_finite() {
        return Err(RegistrationError::NonFinitePose {
            what: "the initial guess",
        });
    }
    if source.is_empty() {
        return Err(RegistrationError::EmptyCloud {
            what: "source",
            reason: "no points".into(),
        });
    }
    let mut pose = *initial_guess;
    let mut converged = false;
    let mut iterations = 0;
    // Graduated robustness (Black & Rangarajan 1996; Yang et al. 2020): converge with the
    // wide kernel (large basin), then halve κ down to `final_kernel_scale_m` (precision).
    let mut kappa = gate.kernel_scale_m;
    let inlier_m = 3.0 * config.final_kernel_scale_m;
    while iterations < config.max_iterations {
        let stage = Gate {
            kernel_scale_m: kappa,
            ..*gate
        };
        let system = normal_equations(source, target, &pose, &stage, config.kernel, inlier_m);
        check_count(system.count, config, iterations, gate)?;
        iterations += 1;
        let step = solve(&system).ok_or(RegistrationError::Degenerate {
            iteration: iterations,
        })?;
        let translation = Vector3::new(step[0], step[1], step[2]);
        let rotation = Vector3::new(step[3], step[4], step[5]);
        let update = Pose3::from_parts(
            translation,
            UnitQuaternion::from_rotation_matrix(&Rotation3::new(rotation)),
        );
        pose = update * pose;
        let last_stage = kappa <= config.final_kernel_scale_m || config.kernel == Kernel::None;
        // Earlier stages only need to bring the estimate into the next one's basin: they stop
        // at ten times the thresholds.
        let loose = if last_stage { 1.0 } else { 10.0 };
        if translation.norm() < loose * config.convergence_translation_m
            && rotation.norm() < loose * config.convergence_rotation_rad
        {
            if last_stage {
                converged = true;
                break;
            }
            kappa = (kappa / 2.0).max(config.final_kernel_scale_m);
        }
    }
    let last = normal_equations(source, target, &pose, gate, config.kernel, inlier_m);
    check_count(last.count, config, iterations, gate)?;
    Ok(Registration {
        target_from_source: pose,
        iterations,
        converged,
        fitness: last.inliers as f64 / source.len() as f64,
        rmse_m: if last.inliers > 0 {
            (last.inlier_e2 / last.inliers as f64).sqrt()
        } else {
            f64::NAN
        },
        correspondences: last.count,
        source_points: source.len(),
    })
}

fn check_count(
    count: usize,
    config: &RegistrationConfig,
    iteration: usize,
    gate: &Gate,
) -> Result<()> {
    if count < config.min_correspondences {
        return Err(RegistrationError::TooFewCorrespondences {
            found: count,
            needed: config.min_correspondences,
            iteration,
            max_distance_m: gate.max_distance_m,
        });
    }
    Ok(())
}

/// The weighted normal equations `H x = −g`, the number of correspondences and the
/// residual statistics of the inliers.
#[derive(Clone, Copy, Debug)]
struct System {
    h: Matrix6<f64>,
    g: Vector6<f64>,
    count: usize,
    inliers: usize,
    inlier_e2: f64,
}

impl System {
    fn zero() -> Self {
        Self {
            h: Matrix6::zeros(),
            g: Vector6::zeros(),
            count: 0,
            inliers: 0,
            inlier_e2: 0.0,
        }
    }

    fn add(mut self, other: &Self) -> Self {
        self.h += other.h;
        self.g += other.g;
        self.count += other.count;
        self.inliers += other.inliers;
        self.inlier_e2 += other.inlier_e2;
        self
    }
}

/// Data association and linearisation at `pose`: parallel over fixed chunks of the source,
/// summed in chunk order. Residuals up to `inlier_m` count as inliers.
fn normal_equations(
    source: &[Point3<f64>],
    target: &Target,
    pose: &Pose3,
    gate: &Gate,
    kernel: Kernel,
    inlier_m: f64,
) -> System {
    let max_2 = gate.max_distance_m * gate.max_distance_m;
    let kappa = gate.kernel_scale_m;
    let partial: Vec<System> = source
        .par_chunks(CHUNK)
        .map(|chunk| {
            let mut s = System::zero();
            for p in chunk {
                let moved = pose.transform_point(p);
                let (j, d2) = target.nearest(&moved);
                if d2 > max_2 {
                    continue;
                }
                let q = target.points()[j];
                let n = target.normals()[j];
                // Low 2004, eq. (6)–(8): e = nᵀ(p' − q), J = [nᵀ, (p' × n)ᵀ].
                let e = n.dot(&(moved - q));
                let c = moved.coords.cross(&n);
                let jac = Vector6::new(n.x, n.y, n.z, c.x, c.y, c.z);
                let w = kernel.weight(e, kappa);
                s.h += w * jac * jac.transpose();
                s.g += (w * e) * jac;
                s.count += 1;
                if e.abs() <= inlier_m {
                    s.inliers += 1;
                    s.inlier_e2 += e * e;
                }
            }
            s
        })
        .collect();
    partial.iter().fold(System::zero(), |a, b| a.add(b))
}

/// The Gauss–Newton step: Cholesky, or the least-squares solution by SVD when the geometry
/// leaves a direction unconstrained (a single plane, a corridor): that direction stays at the
/// initial guess. `None` when no finite step exists.
fn solve(system: &System) -> Option<Vector6<f64>> {
    let rhs = -system.g;
    let step = match system.h.cholesky() {
        Some(chol) => chol.solve(&rhs),
        None => {
            let scale = system.h.diagonal().max().max(f64::MIN_POSITIVE);
            system.h.svd(true, true).solve(&rhs, scale * 1e-9).ok()?
        }
    };
    step.iter().all(|v| v.is_finite()).then_some(step)
}
