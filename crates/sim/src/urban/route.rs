//! Vehicle trajectories along the streets: a random route through the intersections, the
//! right-hand lane as lines joined by circular arcs (turn radius about 8 m), a speed profile
//! with a cruise speed per street (8–12 m/s by default), lateral and longitudinal acceleration
//! limits, and a little body roll and pitch. Sampled at any rate as planar states and as
//! 3-D sensor poses (REP-103, `world_from_sensor`).

use std::f64::consts::TAU;

use nalgebra::{Point2, Vector2};
use rand::Rng;
use raypath_geometry::{Pose2, Pose3};

use super::streets::{StreetGrid, sample};
use crate::error::{Result, SimError};
use crate::rng::SimRng;

/// How the vehicle drives.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct DriveConfig {
    /// Cruise speed, drawn per street, m/s.
    pub speed_m_s: (f64, f64),
    /// Largest lateral acceleration in turns, m/s².
    pub lateral_accel_m_s2: f64,
    /// Largest acceleration and deceleration, m/s².
    pub longitudinal_accel_m_s2: f64,
    /// Radius of the turns at intersections, metres.
    pub turn_radius_m: f64,
    /// Height of the sensor above the road, metres.
    pub sensor_height_m: f64,
    /// Amplitude of the body roll and pitch oscillation, degrees.
    pub body_motion_deg: f64,
}

impl Default for DriveConfig {
    fn default() -> Self {
        Self {
            speed_m_s: (8.0, 12.0),
            lateral_accel_m_s2: 2.0,
            longitudinal_accel_m_s2: 1.5,
            turn_radius_m: 8.0,
            sensor_height_m: 1.73,
            body_motion_deg: 0.3,
        }
    }
}

impl DriveConfig {
    fn validate(&self) -> Result<()> {
        let (a, b) = self.speed_m_s;
        let ok = a.is_finite()
            && b.is_finite()
            && 0.5 <= a
            && a <= b
            && self.lateral_accel_m_s2 > 0.0
            && self.longitudinal_accel_m_s2 > 0.0
            && (2.0..=30.0).contains(&self.turn_radius_m)
            && self.sensor_height_m.is_finite()
            && self.body_motion_deg.abs() <= 5.0;
        if ok {
            Ok(())
        } else {
            Err(SimError::InvalidParameter {
                name: "drive",
                reason: format!(
                    "speeds 0.5 ≤ a ≤ b, positive accelerations, turn radius 2–30 m, body \
                     motion ≤ 5°: {self:?}"
                ),
            })
        }
    }
}

/// A piece of a path.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Piece {
    Line {
        from: Point2<f64>,
        to: Point2<f64>,
        /// Cruise speed on this line, m/s.
        speed: f64,
    },
    Arc {
        center: Point2<f64>,
        radius: f64,
        start_rad: f64,
        /// Signed sweep: positive counter-clockwise (left turn).
        sweep_rad: f64,
        speed: f64,
    },
}

impl Piece {
    fn length(&self) -> f64 {
        match self {
            Piece::Line { from, to, .. } => (to - from).norm(),
            Piece::Arc {
                radius, sweep_rad, ..
            } => radius * sweep_rad.abs(),
        }
    }

    /// Position, heading and signed curvature at arc length `s` from the start.
    fn at(&self, s: f64) -> (Point2<f64>, f64, f64) {
        match *self {
            Piece::Line { from, to, .. } => {
                let d = to - from;
                let len = d.norm().max(1e-12);
                (from + d * (s / len), d.y.atan2(d.x), 0.0)
            }
            Piece::Arc {
                center,
                radius,
                start_rad,
                sweep_rad,
                ..
            } => {
                let sign = sweep_rad.signum();
                let a = start_rad + sign * s / radius;
                let p = center + Vector2::new(a.cos(), a.sin()) * radius;
                (p, a + sign * std::f64::consts::FRAC_PI_2, sign / radius)
            }
        }
    }

    fn speed(&self) -> f64 {
        match self {
            Piece::Line { speed, .. } | Piece::Arc { speed, .. } => *speed,
        }
    }
}

/// A smooth planar path: lines and arcs, parameterized by arc length.
#[derive(Clone, Debug, PartialEq)]
pub struct LanePath {
    pieces: Vec<Piece>,
    /// Arc length at the start of each piece.
    starts: Vec<f64>,
    length: f64,
}

impl LanePath {
    /// Total length, metres.
    pub fn length(&self) -> f64 {
        self.length
    }

    fn piece_at(&self, s: f64) -> Option<(&Piece, f64)> {
        let i = self
            .starts
            .partition_point(|&start| start <= s)
            .saturating_sub(1);
        let piece = self.pieces.get(i)?;
        Some((
            piece,
            (s - self.starts.get(i).copied().unwrap_or(0.0)).clamp(0.0, piece.length()),
        ))
    }

    /// Position, heading (radians) and signed curvature (1/m) at arc length `s`.
    pub fn at(&self, s: f64) -> (Point2<f64>, f64, f64) {
        self.piece_at(s.clamp(0.0, self.length))
            .map_or((Point2::origin(), 0.0, 0.0), |(p, local)| p.at(local))
    }

    fn cruise_speed(&self, s: f64) -> f64 {
        self.piece_at(s.clamp(0.0, self.length))
            .map_or(1.0, |(p, _)| p.speed())
    }
}

/// A random route through the grid's intersections from `start`, without U-turns, preferring
/// streets not driven yet, at least `min_length_m` long. Returns the intersections visited.
pub fn random_route(
    grid: &StreetGrid,
    start: (usize, usize),
    min_length_m: f64,
    rng: &mut SimRng,
) -> Vec<(usize, usize)> {
    let (nx, ny) = (grid.xs.len(), grid.ys.len());
    let neighbours = |(i, j): (usize, usize)| {
        let mut v = Vec::with_capacity(4);
        if i + 1 < nx {
            v.push((i + 1, j));
        }
        if i > 0 {
            v.push((i - 1, j));
        }
        if j + 1 < ny {
            v.push((i, j + 1));
        }
        if j > 0 {
            v.push((i, j - 1));
        }
        v
    };
    let mut visited = std::collections::BTreeSet::new();
    let mut route = vec![start];
    let mut length = 0.0;
    while length < min_length_m && route.len() < 100_000 {
        let here = route[route.len() - 1];
        let previous = route.len().checked_sub(2).map(|k| route[k]);
        let options: Vec<((usize, usize), f64)> = neighbours(here)
            .into_iter()
            .filter(|n| Some(*n) != previous)
            .map(|n| {
                let edge = (here.min(n), here.max(n));
                (n, if visited.contains(&edge) { 1.0 } else { 4.0 })
            })
            .collect();
        let total: f64 = options.iter().map(|o| o.1).sum();
        let mut pick = rng.random::<f64>() * total;
        let mut next = options.first().map_or(here, |o| o.0);
        for (n, w) in &options {
            if pick < *w {
                next = *n;
                break;
            }
            pick -= w;
        }
        if next == here {
            break;
        }
        visited.insert((here.min(next), here.max(next)));
        length += (grid.node(next.0, next.1) - grid.node(here.0, here.1)).norm();
        route.push(next);
    }
    route
}

/// The right-hand lane along a route: the centre lines offset to the right so the vehicle
/// stays clear of the parking lanes (`(r_min − 2.2) / 2` from the centre for the narrowest
/// carriageway half width `r_min` on the route), corners rounded with `turn_radius_m`. The
/// path starts 30 % into the first street and ends 30 % before the last intersection.
pub fn lane_path(
    grid: &StreetGrid,
    route: &[(usize, usize)],
    config: &DriveConfig,
    rng: &mut SimRng,
) -> Result<LanePath> {
    config.validate()?;
    if route.len() < 2 {
        return Err(SimError::InvalidParameter {
            name: "route",
            reason: "a route needs at least two intersections".into(),
        });
    }
    let nodes: Vec<Point2<f64>> = route.iter().map(|&(i, j)| grid.node(i, j)).collect();
    let half_width = |a: (usize, usize), b: (usize, usize)| {
        if a.0 == b.0 {
            grid.half_widths_x.get(a.0).copied().unwrap_or(5.0)
        } else {
            grid.half_widths_y.get(a.1).copied().unwrap_or(5.0)
        }
    };
    let r_min = route
        .windows(2)
        .map(|w| half_width(w[0], w[1]))
        .fold(f64::INFINITY, f64::min);
    let offset = ((r_min - 2.2) / 2.0).max(0.5);
    // Lane lines: (point on line, unit direction, cruise speed), one per street driven.
    let lines: Vec<(Point2<f64>, Vector2<f64>, f64)> = nodes
        .windows(2)
        .map(|w| {
            let dir = (w[1] - w[0]).normalize();
            let right = Vector2::new(dir.y, -dir.x);
            (w[0] + right * offset, dir, sample(rng, config.speed_m_s))
        })
        .collect();
    let first_len = (nodes[1] - nodes[0]).norm();
    let last_len = (nodes[nodes.len() - 1] - nodes[nodes.len() - 2]).norm();
    let mut cursor = lines[0].0 + lines[0].1 * (0.3 * first_len);
    let mut pieces = Vec::new();
    for k in 1..lines.len() {
        let (a1, d1, v1) = lines[k - 1];
        let (a2, d2, _) = lines[k];
        let cross = d1.x * d2.y - d1.y * d2.x;
        let turn = cross.atan2(d1.dot(&d2));
        if turn.abs() < 1e-6 {
            continue;
        }
        // Intersection of the two lane lines.
        let t = ((a2 - a1).x * d2.y - (a2 - a1).y * d2.x) / cross;
        let corner = a1 + d1 * t;
        let tangent = config.turn_radius_m * (turn.abs() / 2.0).tan();
        let arc_start = corner - d1 * tangent;
        let arc_end = corner + d2 * tangent;
        pieces.push(Piece::Line {
            from: cursor,
            to: arc_start,
            speed: v1,
        });
        let left1 = Vector2::new(-d1.y, d1.x);
        let center = arc_start + left1 * (config.turn_radius_m * turn.signum());
        let start_rad = (arc_start - center).y.atan2((arc_start - center).x);
        pieces.push(Piece::Arc {
            center,
            radius: config.turn_radius_m,
            start_rad,
            sweep_rad: turn,
            speed: v1,
        });
        cursor = arc_end;
    }
    let (a, d, v) = lines[lines.len() - 1];
    let end_t = (nodes[nodes.len() - 1] - a).dot(&d) - 0.3 * last_len;
    pieces.push(Piece::Line {
        from: cursor,
        to: a + d * end_t.max((cursor - a).dot(&d) + 1.0),
        speed: v,
    });
    let mut starts = Vec::with_capacity(pieces.len());
    let mut length = 0.0;
    for p in &pieces {
        starts.push(length);
        length += p.length();
    }
    Ok(LanePath {
        pieces,
        starts,
        length,
    })
}

/// A planar vehicle state.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlanarState {
    /// Seconds since the start.
    pub time_s: f64,
    /// Position and heading.
    pub pose: Pose2,
    /// Speed, m/s.
    pub speed_m_s: f64,
}

/// Arc length and time along a path under the speed limits, tabulated every 0.25 m.
#[derive(Clone, Debug)]
pub struct SpeedProfile {
    step_m: f64,
    times: Vec<f64>,
    speeds: Vec<f64>,
}

impl SpeedProfile {
    /// The fastest profile under the cruise speeds and acceleration limits; the vehicle is
    /// at cruise speed at the start.
    pub fn new(path: &LanePath, config: &DriveConfig) -> Self {
        let step_m = 0.25;
        let n = (path.length() / step_m).ceil() as usize + 1;
        let mut v: Vec<f64> = (0..n)
            .map(|i| {
                let s = i as f64 * step_m;
                let (_, _, kappa) = path.at(s);
                let turn_limit = (config.lateral_accel_m_s2 / kappa.abs().max(1e-9)).sqrt();
                path.cruise_speed(s).min(turn_limit)
            })
            .collect();
        let a2 = 2.0 * config.longitudinal_accel_m_s2 * step_m;
        for i in (0..n.saturating_sub(1)).rev() {
            v[i] = v[i].min((v[i + 1] * v[i + 1] + a2).sqrt());
        }
        for i in 1..n {
            v[i] = v[i].min((v[i - 1] * v[i - 1] + a2).sqrt());
        }
        let mut times = vec![0.0; n];
        for i in 1..n {
            times[i] = times[i - 1] + 2.0 * step_m / (v[i - 1] + v[i]).max(1e-6);
        }
        Self {
            step_m,
            times,
            speeds: v,
        }
    }

    /// Time to drive the whole path, seconds.
    pub fn duration_s(&self) -> f64 {
        self.times.last().copied().unwrap_or(0.0)
    }

    /// Arc length and speed at time `t` (clamped to the path).
    pub fn at_time(&self, t: f64) -> (f64, f64) {
        let i = self.times.partition_point(|&x| x <= t);
        if i == 0 {
            return (0.0, self.speeds.first().copied().unwrap_or(0.0));
        }
        if i >= self.times.len() {
            let last = self.times.len().saturating_sub(1);
            return (
                last as f64 * self.step_m,
                self.speeds.get(last).copied().unwrap_or(0.0),
            );
        }
        let (t0, t1) = (self.times[i - 1], self.times[i]);
        let f = if t1 > t0 { (t - t0) / (t1 - t0) } else { 0.0 };
        let s = (i as f64 - 1.0 + f) * self.step_m;
        (s, self.speeds[i - 1] * (1.0 - f) + self.speeds[i] * f)
    }
}

/// Planar states every `period_s` seconds from the start, `count` of them.
pub fn sample_states(
    path: &LanePath,
    profile: &SpeedProfile,
    period_s: f64,
    count: usize,
) -> Vec<PlanarState> {
    (0..count)
        .map(|k| {
            let t = k as f64 * period_s;
            let (s, speed) = profile.at_time(t);
            let (p, heading, _) = path.at(s);
            PlanarState {
                time_s: t,
                pose: Pose2::new(p.x, p.y, heading),
                speed_m_s: speed,
            }
        })
        .collect()
}

/// Smooth body roll and pitch (two sinusoids each, random phases), radians, as a function of
/// time.
#[derive(Clone, Copy, Debug)]
pub struct BodyMotion {
    amplitude_rad: f64,
    freq_hz: [f64; 4],
    phase: [f64; 4],
}

impl BodyMotion {
    /// Random phases and frequencies (0.2–0.9 Hz) for an amplitude in degrees.
    pub fn new(amplitude_deg: f64, rng: &mut SimRng) -> Self {
        let mut freq_hz = [0.0; 4];
        let mut phase = [0.0; 4];
        for k in 0..4 {
            freq_hz[k] = rng.random_range(0.2..0.9);
            phase[k] = rng.random_range(0.0..TAU);
        }
        Self {
            amplitude_rad: amplitude_deg.to_radians(),
            freq_hz,
            phase,
        }
    }

    /// Roll and pitch at time `t`, radians.
    pub fn roll_pitch(&self, t: f64) -> (f64, f64) {
        let w = |k: usize| (TAU * self.freq_hz[k] * t + self.phase[k]).sin();
        let a = self.amplitude_rad * 0.6;
        (a * (w(0) + 0.5 * w(1)), a * (w(2) + 0.5 * w(3)))
    }
}

/// The sensor pose of a planar state: at `height_m` above the ground at `ground_z`, tilted by
/// the body motion.
pub fn sensor_pose(state: &PlanarState, ground_z: f64, height_m: f64, body: &BodyMotion) -> Pose3 {
    let (roll, pitch) = body.roll_pitch(state.time_s);
    Pose3::from_xyz_rpy(
        state.pose.x(),
        state.pose.y(),
        ground_z + height_m,
        roll,
        pitch,
        state.pose.theta(),
    )
}
