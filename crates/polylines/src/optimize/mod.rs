//! PLE+: vertex optimization (Eq. 10.4) with the topology fixed.
//!
//! Each polyline is optimized on its own (as in the reference implementation) over the
//! returned beams that hit it before optimization. The cost is `Σ (r − r̂)²` over those
//! beams, where `r̂` is the distance to the first hit on the polyline; a beam that no longer
//! hits it is charged `d_rm²` (the PLE placeholder), so uncovering beams never pays.
//!
//! Parameters: the start and end vertex of an open polyline slide along the beam that
//! created them (their radius, 1 DOF each); all other vertices move in the plane (2 DOF) —
//! `2(J − I)` parameters in total. Nelder–Mead works on polar `(θ, ρ)` coordinates like the
//! reference implementation; Levenberg–Marquardt on Cartesian `(x, y)` with the analytic
//! derivative of the ray–segment distance.

mod lm;
mod nelder_mead;

use nalgebra::{Point2, Vector2};

use crate::rays::ScanRays;
use crate::{Optimizer, Polyline, PolylineConfig, Polylines};

/// Optimizes every polyline of `map` in place.
pub fn optimize(rays: &ScanRays, map: &mut Polylines, config: &PolylineConfig) {
    let mut slot_of = vec![u32::MAX; rays.len()];
    for line in &mut map.lines {
        if line.len() < 2 {
            continue;
        }
        let Some(problem) = Problem::new(rays, line, config.removed_residual_m, &mut slot_of)
        else {
            continue;
        };
        let optimized = match config.optimizer {
            Optimizer::NelderMead {
                tol_x,
                tol_f,
                iterations_per_dim,
            } => nelder_mead::run(&problem, tol_x, tol_f, iterations_per_dim, &slot_of),
            Optimizer::LevenbergMarquardt {
                max_iterations,
                rel_tolerance,
            } => lm::run(&problem, max_iterations, rel_tolerance, &slot_of),
        };
        if let Some(vertices) = optimized {
            line.vertices = vertices;
        }
        for &(k, _) in &problem.beams {
            slot_of[k] = u32::MAX;
        }
    }
}

/// One polyline's optimization problem.
pub(crate) struct Problem<'a> {
    rays: &'a ScanRays,
    /// Initial vertices.
    start: Vec<Point2<f64>>,
    closed: bool,
    /// Fixed directions of the two ends of an open polyline.
    end_dirs: [Vector2<f64>; 2],
    /// The scored beams `(k, r_k)`; `slot_of[k]` is the position in this list.
    beams: Vec<(usize, f64)>,
    d_rm2: f64,
}

impl<'a> Problem<'a> {
    fn new(
        rays: &'a ScanRays,
        line: &Polyline,
        removed_residual_m: f64,
        slot_of: &mut [u32],
    ) -> Option<Self> {
        let mut beams = Vec::new();
        for (p, q) in line.segments() {
            rays.for_each_ray_in_segment_arc(&p, &q, |k| {
                if let Some(r) = rays.radius(k)
                    && slot_of[k] == u32::MAX
                    && rays.hit(k, &p, &q).is_some()
                {
                    slot_of[k] = beams.len() as u32;
                    beams.push((k, r));
                }
            });
        }
        if beams.is_empty() {
            return None;
        }
        let n = line.len();
        let dir_of = |i: usize| {
            let v = line.vertices[i].coords;
            let beam = line.rays.get(i).map(|&k| rays.dir(k));
            match beam {
                Some(d) if d.norm() > 0.0 => d,
                _ => v.normalize(),
            }
        };
        Some(Self {
            rays,
            start: line.vertices.clone(),
            closed: line.closed,
            end_dirs: [dir_of(0), dir_of(n - 1)],
            beams,
            d_rm2: removed_residual_m * removed_residual_m,
        })
    }

    fn n(&self) -> usize {
        self.start.len()
    }

    /// True when vertex `i` is an end of an open polyline (1 DOF).
    fn is_end(&self, i: usize) -> bool {
        !self.closed && (i == 0 || i + 1 == self.n())
    }

    fn end_dir(&self, i: usize) -> Vector2<f64> {
        if i == 0 {
            self.end_dirs[0]
        } else {
            self.end_dirs[1]
        }
    }

    /// Number of parameters.
    fn dim(&self) -> usize {
        (0..self.n())
            .map(|i| if self.is_end(i) { 1 } else { 2 })
            .sum()
    }

    fn segment_count(&self) -> usize {
        if self.closed { self.n() } else { self.n() - 1 }
    }

    /// For every scored beam, the distance to its first hit and the segment hit, given the
    /// vertices. `best` must have one entry per beam.
    /// Returns how many (segment, beam) hits fall on returned beams outside the scored set.
    fn hits(&self, vertices: &[Point2<f64>], slot_of: &[u32], best: &mut [(f64, u32)]) -> usize {
        best.fill((f64::INFINITY, u32::MAX));
        let n = vertices.len();
        let mut foreign = 0;
        for s in 0..self.segment_count() {
            let (p, q) = (vertices[s], vertices[(s + 1) % n]);
            self.rays.for_each_ray_in_segment_arc(&p, &q, |k| {
                let slot = slot_of[k];
                if slot == u32::MAX {
                    if self.rays.radius(k).is_some() && self.rays.hit(k, &p, &q).is_some() {
                        foreign += 1;
                    }
                    return;
                }
                if let Some(t) = self.rays.hit(k, &p, &q) {
                    let b = &mut best[slot as usize];
                    if t < b.0 {
                        *b = (t, s as u32);
                    }
                }
            });
        }
        foreign
    }

    /// The cost `Σ (r − r̂)²` (`d_rm²` for a beam without a hit, and for every hit on a
    /// returned beam the polyline did not explain before: the topology stays fixed).
    fn cost(&self, vertices: &[Point2<f64>], slot_of: &[u32], best: &mut [(f64, u32)]) -> f64 {
        let foreign = self.hits(vertices, slot_of, best);
        foreign as f64 * self.d_rm2
            + self
                .beams
                .iter()
                .zip(best.iter())
                .map(|(&(_, r), &(t, _))| {
                    if t.is_finite() {
                        (r - t) * (r - t)
                    } else {
                        self.d_rm2
                    }
                })
                .sum::<f64>()
    }
}
