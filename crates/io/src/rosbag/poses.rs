//! The poses of a sensor at a time: odometry (or tf) for the robot, tf for the mounting,
//! reference poses.

use std::collections::HashMap;
use std::path::Path;

use raypath_geometry::Pose3;

use super::select::{FirstPass, ODOMETRY, OdomTrack, POSE_STAMPED};
use super::tf::{TfTree, Track};
use crate::error::Result;
use crate::sequence::Topics;

/// Conventional names of the robot's body frame, tried in this order when there is no
/// odometry topic.
const ROBOT_FRAMES: [&str; 2] = ["base_link", "base_footprint"];

/// The poses of a sensor at one time.
#[derive(Clone, Copy, Debug)]
pub struct SensorPoses {
    /// `world_from_robot` (odometry), when the bag has odometry or a tf path to the robot.
    pub world_from_robot: Option<Pose3>,
    /// `robot_from_sensor` from tf (identity when tf does not connect them).
    pub robot_from_sensor: Pose3,
    /// Reference `world_from_sensor`, when a reference topic covers the time.
    pub reference: Option<Pose3>,
}

/// Computes [`SensorPoses`] from what the first pass read.
pub struct Poses {
    fixed: Option<String>,
    odom: Option<OdomTrack>,
    tf: TfTree,
    reference: Option<Track>,
    static_cache: HashMap<String, Pose3>,
    /// Notes about fallbacks (printed once).
    pub notes: Vec<String>,
}

impl Poses {
    /// Chooses the odometry and reference topics and the fixed frame (`topics.frame`, else the
    /// odometry's frame, else the tf root above the sensor).
    pub fn new(path: &Path, pass: &mut FirstPass, topics: &Topics) -> Result<Self> {
        let odom_topic = pass.choose(
            path,
            ODOMETRY,
            topics.odom.as_deref(),
            "--odom-topic",
            false,
        )?;
        let ref_topic = pass.choose(
            path,
            POSE_STAMPED,
            topics.reference.as_deref(),
            "--reference-topic",
            false,
        )?;
        let odom = odom_topic.and_then(|t| pass.odom.remove(&t));
        let reference = ref_topic
            .and_then(|t| pass.poses.remove(&t))
            .map(|(_, t)| t);
        let fixed = topics
            .frame
            .clone()
            .or_else(|| odom.as_ref().map(|o| o.frame_id.clone()));
        Ok(Self {
            fixed,
            odom,
            tf: std::mem::take(&mut pass.tf),
            reference,
            static_cache: HashMap::new(),
            notes: Vec::new(),
        })
    }

    /// True when the bag has odometry or tf transforms.
    pub fn has_motion(&self) -> bool {
        self.odom.is_some() || !self.tf.is_empty()
    }

    fn note(&mut self, note: String) {
        if !self.notes.contains(&note) {
            log::warn!("{note}");
            self.notes.push(note);
        }
    }

    fn robot_frame<'a>(&'a self, sensor: &'a str) -> &'a str {
        if let Some(o) = &self.odom {
            return &o.child_frame_id;
        }
        ROBOT_FRAMES
            .into_iter()
            .find(|f| self.tf.contains(f) && self.tf.connected(f, sensor))
            .unwrap_or(sensor)
    }

    /// The poses of the sensor with frame `sensor` at `t` seconds; an error (the reason) when
    /// odometry or tf do not cover `t`.
    pub fn at(&mut self, sensor: &str, t: f64) -> std::result::Result<SensorPoses, String> {
        let robot = self.robot_frame(sensor).to_string();
        let world_from_robot = match &self.odom {
            Some(o) => {
                let pose = o.track.at(t).map_err(|e| format!("odometry: {e}"))?;
                match &self.fixed {
                    Some(fixed) if *fixed != o.frame_id => {
                        Some(self.tf.lookup(fixed, &o.frame_id, t)? * pose)
                    }
                    _ => Some(pose),
                }
            }
            None => {
                let fixed = match &self.fixed {
                    Some(f) => Some(f.clone()),
                    None => self.tf.root_of(&robot).map(str::to_string),
                };
                match fixed {
                    Some(fixed) if self.tf.connected(&fixed, &robot) => {
                        Some(self.tf.lookup(&fixed, &robot, t)?)
                    }
                    Some(fixed) if self.fixed.is_some() => {
                        return Err(format!(
                            "tf has no path from --frame {fixed:?} to {robot:?}"
                        ));
                    }
                    _ => None,
                }
            }
        };
        let robot_from_sensor = self.robot_from_sensor(&robot, sensor, t)?;
        let reference = self
            .reference
            .as_ref()
            .and_then(|r| r.at(t).ok())
            .map(|p| p * robot_from_sensor);
        Ok(SensorPoses {
            world_from_robot,
            robot_from_sensor,
            reference,
        })
    }

    fn robot_from_sensor(
        &mut self,
        robot: &str,
        sensor: &str,
        t: f64,
    ) -> std::result::Result<Pose3, String> {
        if robot == sensor {
            return Ok(Pose3::identity());
        }
        if let Some(p) = self.static_cache.get(sensor) {
            return Ok(*p);
        }
        if !self.tf.connected(robot, sensor) {
            self.note(format!(
                "tf does not connect the robot frame {robot:?} and the sensor frame \
                 {sensor:?}: the sensor is taken to sit at the robot's origin"
            ));
            return Ok(Pose3::identity());
        }
        let pose = self.tf.lookup(robot, sensor, t)?;
        if self.tf.is_static_between(robot, sensor) {
            self.static_cache.insert(sensor.to_string(), pose);
        }
        Ok(pose)
    }
}
