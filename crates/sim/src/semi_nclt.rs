//! Semi-synthetic NCLT: a campus built around the **real** NCLT pole layout and the **real**
//! path of the NCLT pole map (`ground-truth-poles.csv` and `pole-map-segment-positions.csv` in
//! `RAYPATH_DATA/nclt-poles/`), driven in sessions months apart with the changes of
//! [`sessions`](crate::urban::sessions) and scanned with a simulated HDL-32E — for long-term
//! pole localization as in Schaefer 2020, §12.4 (Table 12.1).
//!
//! **Real:** the pole positions (1205 poles derived from labelled NCLT scans) and the path (12 999
//! positions where the NCLT pole map's local maps were built, one continuous ≈ 6.5 km path,
//! NCLT frame: x, y metres). **Simulated:** everything else — the street scenery around the
//! path ([`world_along_path`]: flat ground, sidewalks, facades, parked cars; pole kinds and
//! sizes drawn per pole), the session changes, the scans, the odometry and the timing.
//!
//! **Frames and units.** The world frame is the NCLT frame of the input files, taken as
//! REP-103 (x, y in the ground plane, z up; the ground is flat at z = 0). Sensor poses are
//! `world_from_sensor` of the HDL-32E, 1.5 m above the ground, yawed along the path (chord over
//! ±1 m) with a small body roll/pitch (0.3° by default); points are in the sensor frame (x
//! forward, y left, z up), NaN for beams without return (organized 32 × `firings` clouds),
//! intensities in `[0, 1]`. Times are seconds since the UNIX epoch (15:00 UTC of the date).
//!
//! **Session plan.** Session `k` (0-based) drives the window `[k·shift, k·shift + W]` of the
//! path's arc length, `W = (scans − 1) · spacing`, `shift = window_shift · W` (0.25: a session
//! revisits the last three quarters of the previous one and adds a quarter; clamped to the end
//! of the path). Scans are `scan_spacing_m` (0.75 m) apart at 10 Hz stamps, i.e. a vehicle at
//! 7.5 m/s; NCLT's Segway drove about 1–1.5 m/s, so this is a Segway drive thinned to every
//! 5th–7th scan to keep the run time sane. The changes accumulate over the listed sessions
//! (removed poles stay removed), the foliage follows the month, parked cars are redrawn in
//! every session and the barrels of construction zones shift.
//!
//! **Odometry** as in [`nclt_set`](crate::urban::nclt_set): the true planar increments at
//! 10 sub-steps per scan corrupted with [`OdometryNoise`] and integrated from the identity;
//! per scan the integrated pose (`odom_from_sensor`, planar, z = 0) and the standard deviations
//! `[x, y, yaw]` of the increment from the previous scan (sum of the sub-step variances).
//!
//! **Streamed.** Nothing is written: [`SemiNcltSession::scan`] simulates scan `i` on demand;
//! it depends only on the seed, the session and `i`. Poles the path passes within 1 m of are
//! left out (a vehicle cannot drive through a pole) and counted in
//! [`SemiNclt::poles_on_path`].

mod path;

use std::path::Path;
use std::sync::Arc;

use nalgebra::{Point2, Vector2};
use rand::Rng;
use raypath_geometry::{PointCloud, Pose2, Pose3};
use raypath_io::point_csv::PointCsv;

pub use path::ArcPath;

use crate::error::{Result, SimError};
use crate::lidar3::Lidar3;
use crate::rng;
use crate::scene3::Scene3;
use crate::urban::along_path::{PathSample, Scenery, world_along_path};
use crate::urban::odometry::{self, OdometryNoise};
use crate::urban::output::{date_utime, parse_date};
use crate::urban::route::BodyMotion;
use crate::urban::sessions::{ChangeLog, SessionChanges, session_worlds_of};
use crate::urban::streets::{ConstructionZone, ParkingSlot};
use crate::urban::{Pole, World};

const DOMAIN_ZONES: u64 = 0x534e_434c_5a4f_4e45;
const DOMAIN_BODY: u64 = 0x534e_434c_424f_4459;
const DOMAIN_ODOMETRY: u64 = 0x534e_434c_4f44_4f4d;
const DOMAIN_LIDAR: u64 = 0x534e_434c_4c49_4441;

/// Spacing of the path samples the scenery is built around, metres.
const SAMPLE_SPACING_M: f64 = 2.0;
/// Odometry sub-steps per scan (as the 100 Hz odometry of 10 Hz scans in `nclt_set`).
const ODOMETRY_PER_SCAN: usize = 10;
/// Scan period of the stamps, seconds (10 Hz).
pub const SCAN_PERIOD_S: f64 = 0.1;
/// Standard deviation floor of a stated odometry increment (as `nclt_set`'s 1e-8 variance).
const MIN_ODOMETRY_STD: f64 = 1e-4;

/// Eight Table 12.1 sessions spanning the 15 months of NCLT (including the failing
/// 2013-02-23 and the last, 2013-04-05).
pub const DEFAULT_SESSIONS: [&str; 8] = [
    "2012-01-08",
    "2012-02-12",
    "2012-03-25",
    "2012-05-26",
    "2012-08-20",
    "2012-11-16",
    "2013-02-23",
    "2013-04-05",
];

/// The real layout and path, and how to simulate the sessions.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct SemiNcltConfig {
    /// The path, metres (consecutive positions; duplicates are dropped).
    pub path: Vec<Point2<f64>>,
    /// The pole positions, metres.
    pub poles: Vec<Point2<f64>>,
    /// Session dates `YYYY-MM-DD`, in order (the month sets the foliage).
    pub sessions: Vec<String>,
    /// Scans per session.
    pub scans_per_session: usize,
    /// Arc length between consecutive scans, metres.
    pub scan_spacing_m: f64,
    /// Start of session `k` at `k · window_shift · W` along the path (see the module docs).
    pub window_shift: f64,
    /// What changes between sessions.
    pub changes: SessionChanges,
    /// Noise of the odometry.
    pub odometry: OdometryNoise,
    /// Firings per revolution of the HDL-32E (2170 at 10 Hz).
    pub firings: usize,
    /// Body roll/pitch amplitude, degrees.
    pub body_motion_deg: f64,
    /// Construction zones (rows of barrels in a parking lane) per km of path.
    pub construction_zones_per_km: f64,
    /// The scenery (its `parked_car_probability` is ignored: every parking place becomes a
    /// slot, occupied per session by [`SessionChanges::parking_occupancy`]).
    pub scenery: Scenery,
}

impl SemiNcltConfig {
    /// The default plan on a given path and pole layout: [`DEFAULT_SESSIONS`], 500 scans
    /// 0.75 m apart per session, windows shifted by a quarter, sensor 1.5 m above the ground.
    pub fn new(path: Vec<Point2<f64>>, poles: Vec<Point2<f64>>) -> Self {
        Self {
            path,
            poles,
            sessions: DEFAULT_SESSIONS.map(String::from).to_vec(),
            scans_per_session: 500,
            scan_spacing_m: 0.75,
            window_shift: 0.25,
            changes: SessionChanges::default(),
            odometry: OdometryNoise::default(),
            firings: crate::lidar3::HDL32E_FIRINGS_10HZ,
            body_motion_deg: 0.3,
            construction_zones_per_km: 2.0,
            scenery: Scenery {
                sensor_height_m: 1.5,
                ..Scenery::default()
            },
        }
    }

    /// Reads the pole layout (`x,y[,…]` CSV) and the path (`x,y` CSV).
    pub fn from_files(poles: &Path, path: &Path) -> Result<Self> {
        let xy = |file: &Path| -> Result<Vec<Point2<f64>>> {
            Ok(PointCsv::read(file)?
                .rows()
                .filter_map(|r| Some(Point2::new(*r.first()?, *r.get(1)?)))
                .collect())
        };
        Ok(Self::new(xy(path)?, xy(poles)?))
    }

    /// Reads `nclt-poles/ground-truth-poles.csv` and `pole-map-segment-positions.csv` from the
    /// data directory (`RAYPATH_DATA`).
    pub fn from_data_dir() -> Result<Self> {
        let find = |name: &str| {
            let relative = Path::new("nclt-poles").join(name);
            raypath_io::data::find(&relative).ok_or_else(|| SimError::InvalidParameter {
                name: "RAYPATH_DATA",
                reason: format!(
                    "{} not found (set RAYPATH_DATA to the data directory)",
                    raypath_io::data::data_dir().join(relative).display()
                ),
            })
        };
        Self::from_files(
            &find("ground-truth-poles.csv")?,
            &find("pole-map-segment-positions.csv")?,
        )
    }

    /// Arc-length window `(start, end)` of session `k` on a path of `length_m`, metres.
    pub fn window_m(&self, k: usize, length_m: f64) -> (f64, f64) {
        let w = self.scans_per_session.saturating_sub(1) as f64 * self.scan_spacing_m;
        let start = (k as f64 * self.window_shift * w).min((length_m - w).max(0.0));
        (start, (start + w).min(length_m))
    }

    fn validate(&self) -> Result<()> {
        let invalid =
            |name: &'static str, reason: String| Err(SimError::InvalidParameter { name, reason });
        if self.sessions.is_empty() || self.scans_per_session == 0 {
            return invalid(
                "sessions/scans_per_session",
                "at least one session of one scan".into(),
            );
        }
        if !(self.scan_spacing_m.is_finite() && self.scan_spacing_m > 0.0) {
            return invalid(
                "scan_spacing_m",
                format!("{} is not positive", self.scan_spacing_m),
            );
        }
        if !(self.window_shift.is_finite() && self.window_shift >= 0.0) {
            return invalid("window_shift", format!("{} is not ≥ 0", self.window_shift));
        }
        if !(self.construction_zones_per_km.is_finite() && self.construction_zones_per_km >= 0.0) {
            return invalid(
                "construction_zones_per_km",
                format!("{} is not ≥ 0", self.construction_zones_per_km),
            );
        }
        if let Some(p) = self
            .poles
            .iter()
            .find(|p| !(p.x.is_finite() && p.y.is_finite()))
        {
            return invalid("poles", format!("pole at {p} is not finite"));
        }
        Ok(())
    }
}

/// The campus: the static world around the whole path and the worlds of the sessions.
pub struct SemiNclt {
    config: SemiNcltConfig,
    path: ArcPath,
    seed: u64,
    lidar: Lidar3,
    worlds: Vec<(World, ChangeLog)>,
    /// Indices of input poles left out because the path passes within 1 m of them.
    pub poles_on_path: Vec<usize>,
    /// Parking slots (every parking place of the scenery).
    pub parking_slots: usize,
    /// Construction zones.
    pub construction_zones: usize,
}

impl SemiNclt {
    /// Builds the campus. Deterministic by seed.
    pub fn new(config: SemiNcltConfig, seed: u64) -> Result<Self> {
        config.validate()?;
        let path = ArcPath::new(&config.path)?;
        let mut months = Vec::with_capacity(config.sessions.len());
        for date in &config.sessions {
            months.push(parse_date(date)?.1);
        }
        let n = (path.length_m() / SAMPLE_SPACING_M).ceil().max(1.0) as usize;
        let samples: Vec<PathSample> = (0..=n)
            .map(|i| {
                let s = path.length_m() * i as f64 / n as f64;
                PathSample {
                    position: path.at(s),
                    heading_rad: path.heading_rad(s),
                    ground_z: 0.0,
                }
            })
            .collect();
        let scenery = Scenery {
            parked_car_probability: 1.0,
            ..config.scenery.clone()
        };
        let (mut world, report) = world_along_path(&samples, &config.poles, &scenery, seed);
        let slots: Vec<ParkingSlot> = world
            .cars
            .drain(..)
            .map(|c| ParkingSlot {
                center: c.footprint.center,
                yaw_rad: c.footprint.yaw_rad,
                base_z: c.base_z,
            })
            .collect();
        let (parking, construction) = construction_zones(slots, &samples, &path, &config, seed);
        let worlds = session_worlds_of(
            &world,
            &parking,
            &construction,
            &months,
            &config.changes,
            seed,
        );
        let lidar = Lidar3::hdl32e().with_firings(config.firings)?;
        Ok(Self {
            parking_slots: parking.len(),
            construction_zones: construction.len(),
            poles_on_path: report.poles_on_trajectory,
            config,
            path,
            seed,
            lidar,
            worlds,
        })
    }

    /// The configuration.
    pub fn config(&self) -> &SemiNcltConfig {
        &self.config
    }

    /// The real path.
    pub fn path(&self) -> &ArcPath {
        &self.path
    }

    /// Number of sessions.
    pub fn len(&self) -> usize {
        self.worlds.len()
    }

    /// True without sessions (never: the configuration needs one).
    pub fn is_empty(&self) -> bool {
        self.worlds.is_empty()
    }

    /// The world of session `k` and what changed in it.
    pub fn world(&self, k: usize) -> Option<&(World, ChangeLog)> {
        self.worlds.get(k)
    }

    /// Session `k`: builds its scene (the world with that session's changes), poses and
    /// odometry; scans are simulated on demand by [`SemiNcltSession::scan`].
    pub fn session(&self, k: usize) -> Result<SemiNcltSession> {
        let (world, changes) = self
            .worlds
            .get(k)
            .ok_or_else(|| SimError::InvalidParameter {
                name: "session",
                reason: format!("no session {k} (of {})", self.worlds.len()),
            })?;
        let date = self.config.sessions.get(k).cloned().unwrap_or_default();
        let scans = self.config.scans_per_session;
        let (start_m, end_m) = self.config.window_m(k, self.path.length_m());
        let step_m = (end_m - start_m) / ((scans - 1).max(1) * ODOMETRY_PER_SCAN) as f64;
        let truth: Vec<Pose2> = (0..=(scans - 1) * ODOMETRY_PER_SCAN)
            .map(|j| {
                let s = start_m + j as f64 * step_m;
                let p = self.path.at(s);
                Pose2::new(p.x, p.y, self.path.heading_rad(s))
            })
            .collect();
        let odo = odometry::simulate(
            &truth,
            &self.config.odometry,
            &mut rng::stream(self.seed, DOMAIN_ODOMETRY, k as u64),
        );
        let body = BodyMotion::new(
            self.config.body_motion_deg,
            &mut rng::stream(self.seed, DOMAIN_BODY, k as u64),
        );
        let t0 = date_utime(&date, 15)? as f64 * 1e-6;
        let height = self.config.scenery.sensor_height_m;
        let mut stamps_secs = Vec::with_capacity(scans);
        let mut ground_truth = Vec::with_capacity(scans);
        let mut odometry = Vec::with_capacity(scans);
        let mut odometry_std = Vec::with_capacity(scans);
        for i in 0..scans {
            let t = i as f64 * SCAN_PERIOD_S;
            let j = i * ODOMETRY_PER_SCAN;
            let p = truth.get(j).copied().unwrap_or_else(Pose2::identity);
            let (roll, pitch) = body.roll_pitch(t);
            stamps_secs.push(t0 + t);
            ground_truth.push(Pose3::from_xyz_rpy(
                p.x(),
                p.y(),
                height,
                roll,
                pitch,
                p.theta(),
            ));
            let o = odo.poses.get(j).copied().unwrap_or_else(Pose2::identity);
            odometry.push(o.to_pose3());
            let var = odo
                .between(j.saturating_sub(ODOMETRY_PER_SCAN), j)
                .map_or([0.0; 3], |(_, v)| v);
            odometry_std.push(var.map(|v| v.max(0.0).sqrt().max(MIN_ODOMETRY_STD)));
        }
        let scene = Arc::new(world.build_scene()?);
        Ok(SemiNcltSession {
            date,
            index: k,
            window_m: (start_m, end_m),
            stamps_secs,
            ground_truth: Arc::new(ground_truth),
            odometry,
            odometry_std,
            poles: world.pole_list(),
            changes: changes.clone(),
            scanner: SessionScanner {
                scene,
                lidar: self.lidar.clone(),
                seed: rng::stream(self.seed, DOMAIN_LIDAR, k as u64).random(),
            },
        })
    }
}

/// One session: poses, odometry, the true poles and the scans on demand.
pub struct SemiNcltSession {
    /// Date `YYYY-MM-DD`.
    pub date: String,
    /// Index in the session plan.
    pub index: usize,
    /// Arc-length window of the real path driven, metres.
    pub window_m: (f64, f64),
    /// Scan times, seconds since the UNIX epoch (10 Hz).
    pub stamps_secs: Vec<f64>,
    /// True `world_from_sensor` per scan.
    pub ground_truth: Arc<Vec<Pose3>>,
    /// Odometry `odom_from_sensor` per scan (planar, from the identity).
    pub odometry: Vec<Pose3>,
    /// Standard deviations `[x m, y m, yaw rad]` of the odometry increment from the previous
    /// scan.
    pub odometry_std: Vec<[f64; 3]>,
    /// The true poles of this session (after its changes).
    pub poles: Vec<Pole>,
    /// What changed with respect to the previous session.
    pub changes: ChangeLog,
    /// The scan simulator.
    pub scanner: SessionScanner,
}

impl SemiNcltSession {
    /// Number of scans.
    pub fn len(&self) -> usize {
        self.stamps_secs.len()
    }

    /// True without scans.
    pub fn is_empty(&self) -> bool {
        self.stamps_secs.is_empty()
    }

    /// Simulates scan `index` (sensor frame; see the module docs).
    pub fn scan(&self, index: usize) -> Result<PointCloud> {
        let pose = self
            .ground_truth
            .get(index)
            .ok_or_else(|| SimError::InvalidParameter {
                name: "scan index",
                reason: format!(
                    "no scan {index} in session {} ({} scans)",
                    self.date,
                    self.len()
                ),
            })?;
        self.scanner.scan(pose, index)
    }

    /// A cheap, shareable scan function (owns the scene and the poses), for a scan source that
    /// outlives the session value.
    pub fn scan_fn(&self) -> impl Fn(usize) -> Result<PointCloud> + Send + Sync + 'static {
        let scanner = self.scanner.clone();
        let poses = Arc::clone(&self.ground_truth);
        move |index| {
            let pose = poses.get(index).ok_or_else(|| SimError::InvalidParameter {
                name: "scan index",
                reason: format!("no scan {index} ({} scans)", poses.len()),
            })?;
            scanner.scan(pose, index)
        }
    }
}

/// The scene of a session and the lidar that scans it.
#[derive(Clone)]
pub struct SessionScanner {
    scene: Arc<Scene3>,
    lidar: Lidar3,
    seed: u64,
}

impl SessionScanner {
    /// Triangles of the session's scene.
    pub fn num_triangles(&self) -> usize {
        self.scene.num_triangles()
    }

    /// Rays per scan.
    pub fn rays_per_scan(&self) -> usize {
        self.lidar.num_rays()
    }

    /// Scans from `world_from_sensor`; `index` selects the noise stream.
    pub fn scan(&self, world_from_sensor: &Pose3, index: usize) -> Result<PointCloud> {
        Ok(self
            .lidar
            .scan(&self.scene, world_from_sensor, self.seed, index as u64)?
            .cloud)
    }
}

/// Turns some parking places at least 4 m from the path into construction zones (rows of
/// barrels 10–20 m long, at least 30 m apart); returns the remaining slots and the zones.
fn construction_zones(
    slots: Vec<ParkingSlot>,
    samples: &[PathSample],
    path: &ArcPath,
    config: &SemiNcltConfig,
    seed: u64,
) -> (Vec<ParkingSlot>, Vec<ConstructionZone>) {
    let mut rng = rng::stream(seed, DOMAIN_ZONES, 0);
    let wanted = (config.construction_zones_per_km * path.length_m() / 1000.0).round() as usize;
    let nearest = |p: &Point2<f64>| {
        samples
            .iter()
            .map(|s| s.position)
            .min_by(|a, b| (a - p).norm().total_cmp(&(b - p).norm()))
    };
    let mut zones: Vec<ConstructionZone> = Vec::new();
    let mut attempts = 0;
    while zones.len() < wanted && attempts < 20 * wanted && !slots.is_empty() {
        attempts += 1;
        let slot = slots[rng.random_range(0..slots.len())];
        let Some(q) = nearest(&slot.center) else {
            break;
        };
        let away = slot.center - q;
        if away.norm() < 4.0 || zones.iter().any(|z| (z.start - slot.center).norm() < 30.0) {
            continue;
        }
        let direction = Vector2::new(slot.yaw_rad.cos(), slot.yaw_rad.sin());
        let normal = Vector2::new(-direction.y, direction.x);
        let towards_curb = if normal.dot(&away) >= 0.0 {
            normal
        } else {
            -normal
        };
        let length_m = rng.random_range(10.0..20.0);
        zones.push(ConstructionZone {
            start: slot.center - direction * (length_m / 2.0),
            direction,
            towards_curb,
            length_m,
            base_z: slot.base_z,
        });
    }
    let clear = |s: &ParkingSlot| {
        zones.iter().all(|z| {
            let t = (s.center - z.start)
                .dot(&z.direction)
                .clamp(0.0, z.length_m);
            (z.start + z.direction * t - s.center).norm() > 4.0
        })
    };
    let parking = slots.iter().copied().filter(clear).collect();
    (parking, zones)
}

#[cfg(test)]
mod tests;
