//! Planar frames from the `LaserScan` topic of a bag.

use std::collections::HashSet;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use raypath_geometry::Pose3;

use super::bag::BagFiles;
use super::msgs;
use super::poses::Poses;
use super::reader::{ChannelInfo, Classify, McapReader};
use super::select::{LASER_SCAN, ROLE_SCAN, first_pass, is_ros2, message_error, normalize_type};
use crate::error::{Error, Result};
use crate::sequence::{Origin, PlanarFrame, PlanarSource, Topics};

/// Skipped scans are listed one by one up to this many.
const MAX_SKIP_WARNINGS: usize = 5;

/// The scans of one `sensor_msgs/msg/LaserScan` topic of a bag with their poses, streamed in
/// file order (a second pass after odometry and tf were read).
pub struct BagScans {
    name: PathBuf,
    files: Vec<PathBuf>,
    next_file: usize,
    reader: Option<McapReader>,
    topic: Arc<str>,
    poses: Poses,
    known_warnings: HashSet<String>,
    warnings: Vec<String>,
    skipped: usize,
    failed: bool,
}

/// Reads the odometry, tf and reference poses of the bag at `path` and streams the scans of
/// its `LaserScan` topic (see [`crate::rosbag`] for how topics and frames are chosen).
pub fn open_planar(path: &Path, topics: &Topics) -> Result<Box<dyn PlanarSource>> {
    Ok(Box::new(BagScans::open(path, topics)?))
}

impl BagScans {
    /// Opens the bag (first pass over odometry, tf and reference poses).
    pub fn open(path: &Path, topics: &Topics) -> Result<Self> {
        let bag = BagFiles::resolve(path)?;
        let mut pass = first_pass(&bag, false)?;
        for w in &pass.warnings {
            eprintln!("warning: {w}");
        }
        let topic = pass
            .choose(
                path,
                LASER_SCAN,
                topics.scan.as_deref(),
                "--scan-topic",
                true,
            )?
            .ok_or_else(|| Error::UnknownFormat {
                path: path.to_path_buf(),
                reason: "no LaserScan topic".into(),
            })?;
        let mut poses = Poses::new(path, &mut pass, topics)?;
        if !poses.has_motion() {
            let note = "the bag has no odometry and no tf: the robot and laser poses are the \
                        identity";
            eprintln!("warning: {}: {note}", path.display());
            poses.notes.push(note.into());
        }
        Ok(Self {
            name: bag.path.clone(),
            files: bag.files,
            next_file: 0,
            reader: None,
            topic: Arc::from(topic.as_str()),
            poses,
            known_warnings: pass.warnings.iter().cloned().collect(),
            warnings: pass.warnings,
            skipped: 0,
            failed: false,
        })
    }

    /// The topic read.
    pub fn topic(&self) -> &str {
        &self.topic
    }

    /// The warnings printed so far (truncation, messages out of order, tf conflicts).
    pub fn warnings(&self) -> &[String] {
        &self.warnings
    }

    /// Scans skipped so far because odometry or tf did not cover their time.
    pub fn skipped(&self) -> usize {
        self.skipped
    }

    fn flush_warnings(&mut self) {
        if let Some(reader) = self.reader.as_mut() {
            for w in reader.take_warnings() {
                if self.known_warnings.insert(w.clone()) {
                    eprintln!("warning: {w}");
                    self.warnings.push(w);
                }
            }
        }
    }

    fn open_next(&mut self) -> Result<bool> {
        let Some(file) = self.files.get(self.next_file) else {
            return Ok(false);
        };
        let topic = self.topic.clone();
        let classify: Classify = Arc::new(move |c: &ChannelInfo| {
            (is_ros2(c) && c.topic == *topic && normalize_type(&c.schema_name) == LASER_SCAN)
                .then_some(ROLE_SCAN)
        });
        self.reader = Some(McapReader::open(file, self.next_file as u32, classify)?);
        self.next_file += 1;
        Ok(true)
    }

    fn next_frame(&mut self) -> Result<Option<PlanarFrame>> {
        loop {
            if self.reader.is_none() && !self.open_next()? {
                if self.skipped > MAX_SKIP_WARNINGS {
                    eprintln!(
                        "warning: {}: {} scans of {} skipped in all (odometry or tf do not \
                         cover their times)",
                        self.name.display(),
                        self.skipped,
                        self.topic
                    );
                }
                return Ok(None);
            }
            let Some(reader) = self.reader.as_mut() else {
                continue;
            };
            let Some(m) = reader.next_message()? else {
                self.flush_warnings();
                self.reader = None;
                continue;
            };
            let file = &self.files[self.next_file - 1];
            let (header, scan) = msgs::decode_scan(m.data)
                .map_err(|e| message_error(file, m.loc, &self.topic, m.log_time, e))?;
            let t = header.stamp.secs();
            let poses = match self.poses.at(header.frame_id, t) {
                Ok(p) => p,
                Err(reason) => {
                    self.skipped += 1;
                    if self.skipped <= MAX_SKIP_WARNINGS {
                        let w = format!(
                            "{}: {} at log time {:.9} s skipped: {reason}",
                            file.display(),
                            self.topic,
                            m.log_time as f64 * 1e-9
                        );
                        eprintln!("warning: {w}");
                        self.warnings.push(w);
                    }
                    continue;
                }
            };
            let world_from_robot = poses.world_from_robot.unwrap_or_else(Pose3::identity);
            return Ok(Some(PlanarFrame {
                stamp_secs: t,
                scan,
                world_from_robot: world_from_robot.to_planar(),
                world_from_laser: (world_from_robot * poses.robot_from_sensor).to_planar(),
                reference: poses.reference.map(|p| p.to_planar()),
                origin: Origin::LogTimeNs(m.log_time),
            }));
        }
    }
}

impl Iterator for BagScans {
    type Item = Result<PlanarFrame>;

    fn next(&mut self) -> Option<Self::Item> {
        if self.failed {
            return None;
        }
        match self.next_frame() {
            Ok(frame) => frame.map(Ok),
            Err(e) => {
                self.failed = true;
                Some(Err(e))
            }
        }
    }
}

impl PlanarSource for BagScans {
    fn name(&self) -> &Path {
        &self.name
    }
}
