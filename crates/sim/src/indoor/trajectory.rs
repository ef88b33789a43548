//! The robot's motion: planned paths turned into a smooth, time-stamped trajectory of a
//! differential-drive robot.
//!
//! A path (straight pieces from the planner) is driven with circular fillets at its corners
//! (radius up to [`RobotConfig::fillet_radius_m`], shrunk until the arc keeps
//! [`RobotConfig::radius_m`] + 5 cm from every obstacle); corners sharper than 100° (or
//! without room for a fillet) are driven as stop, turn in place, go. Along each stop-to-stop
//! section the speed is the largest profile with `v ≤ max_speed`, `v·κ ≤ max_turn_rate` and
//! `|dv/dt| ≤ max_accel` (forward and backward pass over 1 cm samples); turns in place use a
//! trapezoidal turn-rate profile with `max_turn_rate` and `max_turn_accel`. Headings are kept
//! unwrapped (continuous) in the trajectory.

use std::f64::consts::PI;

use nalgebra::{Point2, Vector2};
use raypath_geometry::{Pose2, wrap_angle};
use serde::Serialize;

use crate::scene2::Scene2;

/// Motion limits and behaviour of the simulated robot.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct RobotConfig {
    /// Cruise speed in m/s.
    pub max_speed_mps: f64,
    /// Largest acceleration and deceleration in m/s².
    pub max_accel_mps2: f64,
    /// Largest turn rate in rad/s.
    pub max_turn_rate_radps: f64,
    /// Largest angular acceleration in rad/s².
    pub max_turn_accel_radps2: f64,
    /// Radius of the robot's footprint in metres.
    pub radius_m: f64,
    /// Smallest clearance of planned paths in metres (grid cells and straight pieces).
    pub planning_clearance_m: f64,
    /// Paths keep this far from obstacles where they can (A* cost), metres.
    pub preferred_clearance_m: f64,
    /// Largest corner fillet radius in metres.
    pub fillet_radius_m: f64,
    /// Probability of looking around (turning in place by 90°–270°) at a room goal.
    pub look_around_probability: f64,
    /// Pause at a goal, seconds `[min, max]`.
    pub dwell_s: [f64; 2],
}

impl Default for RobotConfig {
    fn default() -> Self {
        Self {
            max_speed_mps: 0.45,
            max_accel_mps2: 0.3,
            max_turn_rate_radps: 0.6,
            max_turn_accel_radps2: 1.2,
            radius_m: 0.25,
            planning_clearance_m: 0.35,
            preferred_clearance_m: 1.0,
            fillet_radius_m: 1.0,
            look_around_probability: 0.5,
            dwell_s: [0.0, 1.5],
        }
    }
}

/// The robot's state at one instant.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct State {
    /// Time in seconds since the start.
    pub t: f64,
    /// Position x in metres.
    pub x: f64,
    /// Position y in metres.
    pub y: f64,
    /// Heading in radians, unwrapped (continuous over the trajectory).
    pub theta: f64,
    /// Forward speed in m/s.
    pub v: f64,
    /// Turn rate in rad/s.
    pub omega: f64,
}

impl State {
    /// The pose (heading wrapped to (−π, π]).
    pub fn pose(&self) -> Pose2 {
        Pose2::new(self.x, self.y, wrap_angle(self.theta))
    }

    /// The position.
    pub fn position(&self) -> Point2<f64> {
        Point2::new(self.x, self.y)
    }
}

/// A trajectory: states at increasing times (keyframes every ≤ 1 cm or ≤ 20 ms).
#[derive(Clone, Debug, Default)]
pub struct Trajectory {
    /// The keyframes, by time.
    pub states: Vec<State>,
}

impl Trajectory {
    /// A robot standing at `start`.
    pub fn starting_at(start: Pose2) -> Self {
        Self {
            states: vec![State {
                t: 0.0,
                x: start.x(),
                y: start.y(),
                theta: start.theta(),
                v: 0.0,
                omega: 0.0,
            }],
        }
    }

    /// The last state.
    pub fn last(&self) -> State {
        self.states.last().copied().unwrap_or(State {
            t: 0.0,
            x: 0.0,
            y: 0.0,
            theta: 0.0,
            v: 0.0,
            omega: 0.0,
        })
    }

    /// Duration in seconds.
    pub fn duration(&self) -> f64 {
        self.last().t
    }

    /// Path length in metres.
    pub fn length_m(&self) -> f64 {
        self.states
            .windows(2)
            .map(|w| (w[1].position() - w[0].position()).norm())
            .sum()
    }

    /// The state at time `t` (linear interpolation; clamped to the ends).
    pub fn at(&self, t: f64) -> State {
        let k = self.states.partition_point(|s| s.t <= t);
        match (
            k.checked_sub(1).and_then(|i| self.states.get(i)),
            self.states.get(k),
        ) {
            (Some(a), Some(b)) if b.t > a.t => {
                let u = (t - a.t) / (b.t - a.t);
                let lerp = |p: f64, q: f64| p + u * (q - p);
                State {
                    t,
                    x: lerp(a.x, b.x),
                    y: lerp(a.y, b.y),
                    theta: lerp(a.theta, b.theta),
                    v: lerp(a.v, b.v),
                    omega: lerp(a.omega, b.omega),
                }
            }
            (Some(a), _) => State { t, ..*a },
            (None, Some(b)) => State { t, ..*b },
            (None, None) => State { t, ..self.last() },
        }
    }

    /// Stands still for `seconds`.
    pub fn dwell(&mut self, seconds: f64) {
        if seconds > 0.0 {
            let s = self.last();
            self.states.push(State {
                t: s.t + seconds,
                v: 0.0,
                omega: 0.0,
                ..s
            });
        }
    }

    /// Turns in place by `delta_rad` (any sign and size) with a trapezoidal turn rate.
    pub fn turn(&mut self, delta_rad: f64, robot: &RobotConfig) {
        let total = delta_rad.abs();
        if total < 1e-9 {
            return;
        }
        let sign = delta_rad.signum();
        let (w, a) = (robot.max_turn_rate_radps, robot.max_turn_accel_radps2);
        let (peak, t_acc, t_const) = if total >= w * w / a {
            (w, w / a, (total - w * w / a) / w)
        } else {
            let peak = (total * a).sqrt();
            (peak, peak / a, 0.0)
        };
        let duration = 2.0 * t_acc + t_const;
        let start = self.last();
        let angle_at = |t: f64| -> (f64, f64) {
            if t < t_acc {
                (0.5 * a * t * t, a * t)
            } else if t < t_acc + t_const {
                (0.5 * a * t_acc * t_acc + peak * (t - t_acc), peak)
            } else {
                let r = (duration - t).max(0.0);
                (total - 0.5 * a * r * r, a * r)
            }
        };
        let steps = (duration / 0.02).ceil().max(1.0) as usize;
        for k in 1..=steps {
            let t = duration * k as f64 / steps as f64;
            let (angle, rate) = angle_at(t);
            self.states.push(State {
                t: start.t + t,
                theta: start.theta + sign * angle,
                v: 0.0,
                omega: if k == steps { 0.0 } else { sign * rate },
                ..start
            });
        }
    }

    /// Turns in place to face `heading_rad` (the short way).
    pub fn turn_to(&mut self, heading_rad: f64, robot: &RobotConfig) {
        let delta = wrap_angle(heading_rad - self.last().theta);
        self.turn(delta, robot);
    }

    /// Drives along `waypoints` (the first is the current position) and stops at the last.
    pub fn drive(&mut self, waypoints: &[Point2<f64>], scene: &Scene2, robot: &RobotConfig) {
        let pts: Vec<Point2<f64>> = waypoints.iter().copied().fold(Vec::new(), |mut acc, p| {
            if acc
                .last()
                .is_none_or(|q: &Point2<f64>| (p - q).norm() > 1e-6)
            {
                acc.push(p);
            }
            acc
        });
        if pts.len() < 2 {
            return;
        }
        let dirs: Vec<Vector2<f64>> = pts.windows(2).map(|w| (w[1] - w[0]).normalize()).collect();
        let lens: Vec<f64> = pts.windows(2).map(|w| (w[1] - w[0]).norm()).collect();
        let heading = |d: &Vector2<f64>| d.y.atan2(d.x);
        self.turn_to(heading(&dirs[0]), robot);
        // Fillet radius per interior corner (None: stop and turn).
        let corners: Vec<Option<f64>> = (1..pts.len() - 1)
            .map(|i| {
                fillet(
                    scene,
                    &pts[i],
                    &dirs[i - 1],
                    &dirs[i],
                    lens[i - 1],
                    lens[i],
                    robot,
                )
            })
            .collect();
        let mut section = Section::default();
        let mut from = pts[0];
        for i in 0..dirs.len() {
            let d = dirs[i];
            // Tangent distance of the fillet at the end of this piece.
            let end_cut = corners.get(i).copied().flatten().map_or(0.0, |r| {
                r * (turn_angle(&d, dirs.get(i + 1).unwrap_or(&d)).abs() / 2.0).tan()
            });
            let end = pts[i + 1] - d * end_cut;
            section.line(from, end, heading(&d));
            match corners.get(i) {
                Some(Some(r)) => {
                    let next = dirs[i + 1];
                    let phi = turn_angle(&d, &next);
                    section.arc(end, heading(&d), phi, *r);
                    from = pts[i + 1] + next * end_cut;
                }
                Some(None) => {
                    self.run(&section, robot);
                    section = Section::default();
                    self.turn(turn_angle(&d, &dirs[i + 1]), robot);
                    from = pts[i + 1];
                }
                None => {}
            }
        }
        self.run(&section, robot);
    }

    /// Appends a section driven from rest to rest.
    fn run(&mut self, section: &Section, robot: &RobotConfig) {
        let n = section.samples.len();
        if n < 2 {
            return;
        }
        let limit = |k: f64| {
            if k.abs() < 1e-12 {
                robot.max_speed_mps
            } else {
                robot.max_speed_mps.min(robot.max_turn_rate_radps / k.abs())
            }
        };
        let raw: Vec<f64> = section.samples.iter().map(|s| limit(s.curvature)).collect();
        let mut v: Vec<f64> = (0..n)
            .map(|j| {
                raw[j]
                    .min(raw[j.saturating_sub(1)])
                    .min(raw[(j + 1).min(n - 1)])
            })
            .collect();
        v[0] = 0.0;
        v[n - 1] = 0.0;
        let a = robot.max_accel_mps2;
        for j in 0..n - 1 {
            let ds = section.samples[j + 1].s - section.samples[j].s;
            v[j + 1] = v[j + 1].min((v[j] * v[j] + 2.0 * a * ds).sqrt());
        }
        for j in (0..n - 1).rev() {
            let ds = section.samples[j + 1].s - section.samples[j].s;
            v[j] = v[j].min((v[j + 1] * v[j + 1] + 2.0 * a * ds).sqrt());
        }
        let start = self.last();
        let theta0 = start.theta;
        // Headings continue the unwrapped heading of the robot.
        let offset = theta0 - section.samples[0].heading;
        let mut t = start.t;
        for j in 1..n {
            let (p, q) = (&section.samples[j - 1], &section.samples[j]);
            let ds = q.s - p.s;
            let mean = 0.5 * (v[j - 1] + v[j]);
            if ds <= 0.0 || mean <= 0.0 {
                continue;
            }
            t += ds / mean;
            self.states.push(State {
                t,
                x: q.x,
                y: q.y,
                theta: q.heading + offset,
                v: v[j],
                omega: v[j] * q.curvature,
            });
        }
    }
}

/// The signed turn from direction `a` to `b`, in (−π, π].
fn turn_angle(a: &Vector2<f64>, b: &Vector2<f64>) -> f64 {
    wrap_angle(b.y.atan2(b.x) - a.y.atan2(a.x))
}

/// The fillet radius at corner `p` (incoming direction `din`, outgoing `dout`), or `None`
/// when the robot should stop and turn.
fn fillet(
    scene: &Scene2,
    p: &Point2<f64>,
    din: &Vector2<f64>,
    dout: &Vector2<f64>,
    len_in: f64,
    len_out: f64,
    robot: &RobotConfig,
) -> Option<f64> {
    let phi = turn_angle(din, dout);
    if phi.abs() < 1e-6 {
        return Some(0.0);
    }
    if phi.abs() > 100f64.to_radians() {
        return None;
    }
    let half_tan = (phi.abs() / 2.0).tan();
    let mut r = robot
        .fillet_radius_m
        .min(0.5 * len_in.min(len_out) / half_tan);
    while r >= 0.1 {
        let start = p - din * (r * half_tan);
        let normal = Vector2::new(-din.y, din.x) * phi.signum();
        let center = start + normal * r;
        let a0 = (start - center).y.atan2((start - center).x);
        let ok = (0..=16).all(|k| {
            let a = a0 + phi * k as f64 / 16.0;
            let q = center + Vector2::new(a.cos(), a.sin()) * r;
            scene.distance(&q) >= robot.radius_m + 0.05
        });
        if ok {
            return Some(r);
        }
        r *= 0.5;
    }
    None
}

/// A geometric sample of a section: arc length, position, heading, curvature.
#[derive(Clone, Copy, Debug)]
struct Sample {
    s: f64,
    x: f64,
    y: f64,
    heading: f64,
    curvature: f64,
}

/// A stop-to-stop drive: samples every ≤ 1 cm; headings unwrapped along the section.
#[derive(Default)]
struct Section {
    samples: Vec<Sample>,
}

impl Section {
    fn push(&mut self, x: f64, y: f64, heading: f64, curvature: f64) {
        let (s, h) = match self.samples.last() {
            Some(last) => (
                last.s + ((x - last.x).powi(2) + (y - last.y).powi(2)).sqrt(),
                last.heading + wrap_angle(heading - last.heading),
            ),
            None => (0.0, heading),
        };
        self.samples.push(Sample {
            s,
            x,
            y,
            heading: h,
            curvature,
        });
    }

    fn line(&mut self, a: Point2<f64>, b: Point2<f64>, heading: f64) {
        let len = (b - a).norm();
        let steps = (len / 0.01).ceil() as usize;
        if self.samples.is_empty() {
            self.push(a.x, a.y, heading, 0.0);
        }
        for k in 1..=steps {
            let p = a + (b - a) * (k as f64 / steps as f64);
            self.push(p.x, p.y, heading, 0.0);
        }
    }

    /// An arc from `start` (heading `heading`) turning by `phi` with radius `r`.
    fn arc(&mut self, start: Point2<f64>, heading: f64, phi: f64, r: f64) {
        if r <= 0.0 || phi.abs() < 1e-9 {
            return;
        }
        let normal = Vector2::new(-heading.sin(), heading.cos()) * phi.signum();
        let center = start + normal * r;
        let a0 = (start - center).y.atan2((start - center).x);
        let steps = ((phi.abs() * r) / 0.01).ceil().max(1.0) as usize;
        let kappa = phi.signum() / r;
        for k in 1..=steps {
            let u = phi * k as f64 / steps as f64;
            let a = a0 + u;
            self.push(
                center.x + r * a.cos(),
                center.y + r * a.sin(),
                heading + u,
                kappa,
            );
        }
    }
}

/// Uniform angle of a look-around turn: ±(90°…270°).
pub(crate) fn look_around_angle(u: f64, sign: bool) -> f64 {
    let a = PI / 2.0 + u * PI;
    if sign { a } else { -a }
}
